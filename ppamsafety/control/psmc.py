"""Proxy-based sliding mode control (thesis §5.2-5.3, Kikuuwe & Fujimoto 2006).

Discrete-time solution (5.26)-(5.29), per proxy with state a[k-1] and
Nabla a[k-1] = a[k-1] - a[k-2]::

    sigma = (x_d - x) + lambda (xd_d - xd)
    A     = Ki T^2 + Kp T + Kd
    f*    = A/(T + lambda) sigma + Ki a[k-1] + (lambda (Ki T + Kp) - Kd)/(T (T + lambda)) Nabla a[k-1]
    f     = F sat(f*/F)        (vector saturation (D.7))
    a[k]  = (a[k-1] (Kp T + Kd) + Kd Nabla a[k-1] + T^2 f)/A
    s[k]  = (T + lambda)/A (f* - f)                      (5.32)

* **Joint space** (§5.3.3, (5.37)-(5.41)): one scalar proxy per joint; x = q,
  f = Delta p_psmc limited to Delta p_lm; Delta p = Delta p_gc + Delta p_psmc.
* **Task space** (§5.3.2, (5.26)-(5.30), (5.33)-(5.34)): one planar proxy for
  the TCP; x = r = FK(q), xd = J q_dot; tau = J^T f is converted to Delta p
  with the controller's torque functions, on top of the gravity compensation.

Default gains: Table 5.1 (b), (c).  The proxy is "on its sliding surface"
when |f*| <= limit (then s = 0).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import leaf
from .._validation import check_range
from ..plant.geometry import inverse_kinematics_elbow_up, tcp_jacobian, tcp_position
from ..plant.torque import torque_kernel
from ..units import BAR
from .base import KIND_PSMC_JOINT, KIND_PSMC_TASK, Controller, pair
from .gravity import add_gravity_compensation, gc_mode
from .pid import TABLE_5_1_PID

#: Table 5.1 (c), joint space: lambda [s], Delta p_lm [bar]; gains as PID.
TABLE_5_1_JOINT = {"lambda": 0.4, "dp_lm": 0.2}
#: Table 5.1 (b), task space: lambda [s], Kp [N/m], Ki [N/(m s)], Kd [N s/m], F [N].
TABLE_5_1_TASK = {"lambda": 0.4, "kp": 200.0, "ki": 100.0, "kd": 10.0, "F": 15.0}


@leaf
def proxy_update(sigma, a, da, kp, ki, kd, lam, T):
    """Unsaturated proxy force f* of (5.27) for scalar inputs."""
    A = ki * T * T + kp * T + kd
    return A / (T + lam) * sigma + ki * a + (lam * (ki * T + kp) - kd) / (T * (T + lam)) * da


@leaf
def proxy_state(f, a, da, kp, ki, kd, T):
    """New integral state a[k] of (5.29)."""
    return (a * (kp * T + kd) + kd * da + T * T * f) / (ki * T * T + kp * T + kd)


@leaf
def psmc_joint_step(C, S, Pm, dt, qm, qdm, ref, dp, internals, scratch):
    """Joint-space PSMC; C = [Kp(2), Ki(2), Kd(2), lambda(2), dp_lm(2), use_gc].

    State S: a (2), Nabla a (2).  Internals: Delta p_psmc (2), s (2),
    on-surface flag (2), a (2).
    """
    for j in range(2):
        kp, ki, kd, lam, lim = C[j], C[2 + j], C[4 + j], C[6 + j], C[8 + j]
        sigma = (ref[j] - qm[j]) + lam * (ref[2 + j] - qdm[j])
        fs = proxy_update(sigma, S[j], S[2 + j], kp, ki, kd, lam, dt)
        f = min(max(fs, -lim), lim)
        a_new = proxy_state(f, S[j], S[2 + j], kp, ki, kd, dt)
        S[2 + j] = a_new - S[j]
        S[j] = a_new
        dp[j] = f
        internals[j] = f
        internals[2 + j] = (dt + lam) / (ki * dt * dt + kp * dt + kd) * (fs - f)
        internals[4 + j] = 1.0 if abs(fs) <= lim else 0.0
        internals[6 + j] = a_new
    # proxy angles q_p = q + Nabla a / T (a is the integral of q_p - q)
    add_gravity_compensation(C[10], Pm, qm, ref, qm[0] + S[2] / dt, qm[1] + S[3] / dt, dp,
                             scratch)


@leaf
def psmc_task_step(C, S, Pm, dt, qm, qdm, ref, dp, internals, scratch):
    """Task-space PSMC; C = [Kp, Ki, Kd, lambda, F, use_gc] (SI: N/m, N/(m s), N s/m, s, N).

    State S: a (2), Nabla a (2).  Internals: f (2), s (2), on-surface flag,
    |f*| , a (2).
    """
    kp, ki, kd, lam, F = C[0], C[1], C[2], C[3], C[4]
    x, y = tcp_position(qm[0], qm[1], Pm)
    j11, j12, j21, j22 = tcp_jacobian(qm[0], qm[1], Pm)
    xd = j11 * qdm[0] + j12 * qdm[1]
    yd = j21 * qdm[0] + j22 * qdm[1]
    sx = (ref[8] - x) + lam * (ref[10] - xd)
    sy = (ref[9] - y) + lam * (ref[11] - yd)
    fsx = proxy_update(sx, S[0], S[2], kp, ki, kd, lam, dt)
    fsy = proxy_update(sy, S[1], S[3], kp, ki, kd, lam, dt)
    norm = math.sqrt(fsx * fsx + fsy * fsy)
    scale = 1.0 if norm <= F else F / norm
    fx, fy = fsx * scale, fsy * scale
    ax = proxy_state(fx, S[0], S[2], kp, ki, kd, dt)
    ay = proxy_state(fy, S[1], S[3], kp, ki, kd, dt)
    S[2], S[3] = ax - S[0], ay - S[1]
    S[0], S[1] = ax, ay
    tau1 = j11 * fx + j21 * fy                     # tau = J^T f   (5.30)
    tau2 = j12 * fx + j22 * fy
    mt = scratch[0:4]
    torque_kernel(qm[0], qm[1], Pm, mt, scratch[4:8], scratch[8:12])
    dp[0] = tau1 / (mt[0] - mt[1])                 # (5.33)-(5.34) without the p_m/G part,
    dp[1] = tau2 / (mt[2] - mt[3])                 # which the gravity compensation adds
    c = (dt + lam) / (ki * dt * dt + kp * dt + kd)
    internals[0], internals[1] = fx, fy
    internals[2], internals[3] = c * (fsx - fx), c * (fsy - fy)
    internals[4] = 1.0 if norm <= F else 0.0
    internals[5] = norm
    internals[6], internals[7] = ax, ay
    # proxy position r_p = r + Nabla a / T, in joint space by inverse kinematics
    qp1, qp2, ok = inverse_kinematics_elbow_up(x + S[2] / dt, y + S[3] / dt, Pm)
    if not ok:
        qp1, qp2 = qm[0], qm[1]
    add_gravity_compensation(C[5], Pm, qm, ref, qp1, qp2, dp, scratch[12:24])


class JointPSMC(Controller):
    """Joint-space proxy-based sliding mode control (5.37)-(5.41).

    Parameters
    ----------
    lam : float or pair, keyword-only
        Sliding-surface time constant lambda [s] (Table 5.1: 0.4).  0 is
        allowed (then PSMC with a huge limit is a discrete PID).
    kp, ki, kd : float or pair
        Virtual-coupling gains [Pa/rad, Pa/(rad s), Pa s/rad] (default as PID).
    dp_limit : float or pair
        Delta p_lm [Pa] (Table 5.1: 0.2 bar).
    gravity_compensation : {"proxy", "desired", "measured", "off"}
        Where (3.18)-(3.19) is evaluated; default the proxy position (see
        :mod:`ppamsafety.control.gravity`).
    """

    kind = KIND_PSMC_JOINT
    name = "PSMC joint"

    def __init__(self, *, lam=TABLE_5_1_JOINT["lambda"], kp=None, ki=None, kd=None,
                 dp_limit=TABLE_5_1_JOINT["dp_lm"] * BAR, gravity_compensation="proxy"):
        super().__init__()
        g = TABLE_5_1_PID
        self.lam = pair("JointPSMC.lam", lam, unit="s")
        self.kp = pair("JointPSMC.kp", np.asarray(g["kp"]) * BAR if kp is None else kp,
                       unit="Pa/rad")
        self.ki = pair("JointPSMC.ki", np.asarray(g["ki"]) * BAR if ki is None else ki,
                       unit="Pa/(rad s)")
        self.kd = pair("JointPSMC.kd", np.asarray(g["kd"]) * BAR if kd is None else kd,
                       unit="Pa s/rad")
        self.dp_limit = pair("JointPSMC.dp_limit", dp_limit, lo=0.0, unit="Pa")
        if min(self.dp_limit) <= 0:
            raise ValueError("JointPSMC.dp_limit must be positive [Pa]")
        if min(self.kd) == 0 and min(self.lam) == 0 and min(self.kp) == 0:
            raise ValueError("JointPSMC: Kp, Kd and lambda cannot all be zero")
        self.gravity_compensation = gravity_compensation
        self.gc = gc_mode(gravity_compensation, ("off", "measured", "desired", "proxy"))

    def pack(self) -> np.ndarray:
        """Parameter vector of the compiled step function (SI units)."""
        return np.array([*self.kp, *self.ki, *self.kd, *self.lam, *self.dp_limit,
                         self.gc])

    def describe(self) -> dict:
        """Parameters as a flat dict for result tables."""
        return {"controller": self.name, "Ki_bar_per_rad_s": self.ki[0] / BAR,
                "lambda_s": self.lam[0]}


class TaskPSMC(Controller):
    """Task-space proxy-based sliding mode control of the TCP (§5.3.2).

    Parameters
    ----------
    lam : float, keyword-only
        lambda [s] (Table 5.1: 0.4).
    kp, ki, kd : float
        Virtual coupling [N/m, N/(m s), N s/m] (Table 5.1: 200, 100, 10).
    force_limit : float
        F [N] (Table 5.1: 15).
    gravity_compensation : {"proxy", "desired", "measured", "off"}
        Where (3.18)-(3.19) is evaluated; default the proxy position (see
        :mod:`ppamsafety.control.gravity`).
    """

    kind = KIND_PSMC_TASK
    name = "PSMC task"

    def __init__(self, *, lam=TABLE_5_1_TASK["lambda"], kp=TABLE_5_1_TASK["kp"],
                 ki=TABLE_5_1_TASK["ki"], kd=TABLE_5_1_TASK["kd"],
                 force_limit=TABLE_5_1_TASK["F"], gravity_compensation="proxy"):
        super().__init__()
        self.lam = check_range("TaskPSMC.lam", lam, 0.0, 100.0, unit="s")
        self.kp = check_range("TaskPSMC.kp", kp, 0.0, 1e7, unit="N/m")
        self.ki = check_range("TaskPSMC.ki", ki, 0.0, 1e7, unit="N/(m s)")
        self.kd = check_range("TaskPSMC.kd", kd, 0.0, 1e7, unit="N s/m")
        self.force_limit = check_range("TaskPSMC.force_limit", force_limit, 0.0, 1e7,
                                       lo_open=True, unit="N")
        self.gravity_compensation = gravity_compensation
        self.gc = gc_mode(gravity_compensation, ("off", "measured", "desired", "proxy"))

    def pack(self) -> np.ndarray:
        """Parameter vector of the compiled step function (SI units)."""
        return np.array([self.kp, self.ki, self.kd, self.lam, self.force_limit,
                         self.gc])

    def describe(self) -> dict:
        """Parameters as a flat dict for result tables."""
        return {"controller": self.name, "Ki_bar_per_rad_s": np.nan, "lambda_s": self.lam}
