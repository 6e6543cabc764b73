"""The compiled law of :mod:`ppamsafety.control.psmc`: its declared rows and step kernel."""

from __future__ import annotations

import math

from ..._jit import leaf
from ...layouts import Field, Layout
from ...plant.geometry import inverse_kinematics_elbow_up, tcp_jacobian, tcp_position
from ...plant.torque import torque_functions_cs
from ..reference import R_Q, R_QD, R_X, R_XD, R_Y, R_YD
from .gravity import GC_SCRATCH, add_gravity_compensation


_GC_FIELD = Field("gc", 1, "code", "GCMode: gravity compensation (default at the proxy)")

JOINT_PSMC_PARAMS = Layout("joint PSMC parameters", [
    Field("kp", 2, "Pa/rad", "virtual-coupling proportional gains"),
    Field("ki", 2, "Pa/(rad s)", "virtual-coupling integral gains"),
    Field("kd", 2, "Pa s/rad", "virtual-coupling derivative gains"),
    Field("lam", 2, "s", "sliding-surface time constants lambda (Table 5.1 (c))"),
    Field("dp_limit", 2, "Pa", "output limits Delta p_lm (Table 5.1 (c))"),
    _GC_FIELD,
])
PJ_KP, PJ_KI, PJ_KD, PJ_LAM, PJ_LIM, PJ_GC = JOINT_PSMC_PARAMS.offsets(
    "kp", "ki", "kd", "lam", "dp_limit", "gc")

JOINT_PSMC_STATE = Layout("joint PSMC state", [
    Field("a", 2, "rad s", "proxy integral state a[k-1] (5.29)"),
    Field("da", 2, "rad s", "Nabla a[k-1] = a[k-1] - a[k-2]"),
])
SJ_A, SJ_DA = JOINT_PSMC_STATE.offsets("a", "da")

JOINT_PSMC_INTERNALS = Layout("joint PSMC internals", [
    Field("dp_psmc", 2, "Pa", "saturated proxy output f = Delta p_psmc"),
    Field("s", 2, "rad", "sliding variable s[k] (5.32)"),
    Field("on_surface", 2, "-", "1 if |f*| <= Delta p_lm (proxy on its sliding surface)"),
    Field("a", 2, "rad s", "new proxy integral state a[k]"),
])
IJ_F, IJ_S, IJ_ON, IJ_A = JOINT_PSMC_INTERNALS.offsets("dp_psmc", "s", "on_surface", "a")

TASK_PSMC_PARAMS = Layout("task PSMC parameters", [
    Field("kp", 1, "N/m", "virtual-coupling stiffness (Table 5.1 (b))"),
    Field("ki", 1, "N/(m s)", "virtual-coupling integral gain"),
    Field("kd", 1, "N s/m", "virtual-coupling damping"),
    Field("lam", 1, "s", "sliding-surface time constant lambda"),
    Field("force_limit", 1, "N", "force limit F of the vector saturation (D.7)"),
    _GC_FIELD,
])
PT_KP, PT_KI, PT_KD, PT_LAM, PT_F, PT_GC = TASK_PSMC_PARAMS.offsets(
    "kp", "ki", "kd", "lam", "force_limit", "gc")

TASK_PSMC_STATE = Layout("task PSMC state", [
    Field("a", 2, "m s", "proxy integral state a[k-1] (x, y)", columns=("ax", "ay")),
    Field("da", 2, "m s", "Nabla a[k-1] (x, y)", columns=("dax", "day")),
])
ST_A, ST_DA = TASK_PSMC_STATE.offsets("a", "da")

TASK_PSMC_INTERNALS = Layout("task PSMC internals", [
    Field("f", 2, "N", "saturated proxy force f (x, y)", columns=("fx", "fy")),
    Field("s", 2, "m", "sliding variable s[k] (x, y) (5.32)", columns=("sx", "sy")),
    Field("on_surface", 1, "-", "1 if |f*| <= F (proxy on its sliding surface)"),
    Field("f_star_norm", 1, "N", "|f*|, norm of the unsaturated force"),
    Field("a", 2, "m s", "new proxy integral state a[k] (x, y)", columns=("ax", "ay")),
])
IT_F, IT_S, IT_ON, IT_NORM, IT_A = TASK_PSMC_INTERNALS.offsets(
    "f", "s", "on_surface", "f_star_norm", "a")

TASK_PSMC_SCRATCH = Layout("task PSMC scratch", [
    Field("mt", 4, "m^3", "m_tau of the four muscle groups at q (B.2)"),
    Field("gc", GC_SCRATCH.size, "-", "work memory of the gravity compensation"),
])
XT_MT, XT_GC = TASK_PSMC_SCRATCH.offsets("mt", "gc")
_NGC = GC_SCRATCH.size


@leaf
def proxy_update(sigma, a, da, kp, ki, kd, lam, T):
    """Unsaturated proxy force f* of (5.27) for scalar inputs (compiled, unchecked).

    Units below are for a joint-space proxy; for a task-space proxy read
    m for rad and N for Pa.

    Parameters
    ----------
    sigma : float
        Sliding variable (x_d - x) + lambda (xd_d - xd) [rad].
    a : float
        Proxy integral state a[k-1] [rad s].
    da : float
        Nabla a[k-1] = a[k-1] - a[k-2] [rad s].
    kp, ki, kd : float
        Virtual-coupling gains [Pa/rad, Pa/(rad s), Pa s/rad].
    lam : float
        Sliding-surface time constant lambda [s].
    T : float
        Control period [s], > 0.

    Returns
    -------
    float
        f* [Pa].
    """
    A = ki * T * T + kp * T + kd
    return A / (T + lam) * sigma + ki * a + (lam * (ki * T + kp) - kd) / (T * (T + lam)) * da


@leaf
def proxy_state(f, a, da, kp, ki, kd, T):
    """New integral state a[k] of (5.29) (compiled, unchecked).

    Units below are for a joint-space proxy; for a task-space proxy read
    m for rad and N for Pa.

    Parameters
    ----------
    f : float
        Saturated proxy output f[k] [Pa].
    a : float
        Proxy integral state a[k-1] [rad s].
    da : float
        Nabla a[k-1] = a[k-1] - a[k-2] [rad s].
    kp, ki, kd : float
        Virtual-coupling gains [Pa/rad, Pa/(rad s), Pa s/rad]; A = Ki T^2 +
        Kp T + Kd must not be zero (:func:`check_proxy_gains`).
    T : float
        Control period [s], > 0.

    Returns
    -------
    float
        a[k] [rad s].
    """
    return (a * (kp * T + kd) + kd * da + T * T * f) / (ki * T * T + kp * T + kd)


@leaf
def psmc_joint_step(C, S, Pm, dt, qm, qdm, ref, dp, internals, scratch):
    """One joint-space PSMC update (5.37)-(5.41) (compiled, unchecked).

    Parameters
    ----------
    C : numpy.ndarray
        Parameter row (layout ``JOINT_PSMC_PARAMS``: Kp [Pa/rad], Ki
        [Pa/(rad s)], Kd [Pa s/rad], lambda [s], Delta p_lm [Pa] per joint,
        :class:`~ppamsafety.control.gravity.GCMode` code).
    S : numpy.ndarray
        State (layout ``JOINT_PSMC_STATE``: a[k-1], Nabla a[k-1] [rad s] per
        joint), updated in place.
    Pm : numpy.ndarray
        The controller's model row (layout ``PLANT``), for the gravity
        compensation.
    dt : float
        Control period T [s].
    qm, qdm : numpy.ndarray, shape (2,)
        Measured joint angles [rad] and velocities [rad/s].
    ref : numpy.ndarray, shape (12,)
        Reference row (q_d [rad], qd_d [rad/s] in the ``R_Q``, ``R_QD``
        columns).
    dp : numpy.ndarray, shape (2,)
        Output Delta p = Delta p_psmc + Delta p_gc per joint [Pa], written.
    internals : numpy.ndarray
        Logged internals (layout ``JOINT_PSMC_INTERNALS``), written.
    scratch : numpy.ndarray, shape (GC_SCRATCH.size,)
        Work memory of the gravity compensation (layout ``GC_SCRATCH``).
    """
    for j in range(2):
        kp, ki, kd = C[PJ_KP + j], C[PJ_KI + j], C[PJ_KD + j]
        lam, lim = C[PJ_LAM + j], C[PJ_LIM + j]
        sigma = (ref[R_Q + j] - qm[j]) + lam * (ref[R_QD + j] - qdm[j])
        fs = proxy_update(sigma, S[SJ_A + j], S[SJ_DA + j], kp, ki, kd, lam, dt)
        f = min(max(fs, -lim), lim)
        a_new = proxy_state(f, S[SJ_A + j], S[SJ_DA + j], kp, ki, kd, dt)
        S[SJ_DA + j] = a_new - S[SJ_A + j]
        S[SJ_A + j] = a_new
        dp[j] = f
        internals[IJ_F + j] = f
        internals[IJ_S + j] = (dt + lam) / (ki * dt * dt + kp * dt + kd) * (fs - f)
        internals[IJ_ON + j] = 1.0 if abs(fs) <= lim else 0.0
        internals[IJ_A + j] = a_new
    # proxy angles q_p = q + Nabla a / T (a is the integral of q_p - q)
    add_gravity_compensation(int(C[PJ_GC]), Pm, qm, ref, qm[0] + S[SJ_DA] / dt,
                             qm[1] + S[SJ_DA + 1] / dt, dp, scratch)


@leaf
def psmc_task_step(C, S, Pm, dt, qm, qdm, ref, dp, internals, scratch):
    """One task-space PSMC update of the TCP (§5.3.2) (compiled, unchecked).

    Parameters
    ----------
    C : numpy.ndarray
        Parameter row (layout ``TASK_PSMC_PARAMS``: Kp [N/m], Ki [N/(m s)],
        Kd [N s/m], lambda [s], F [N],
        :class:`~ppamsafety.control.gravity.GCMode` code).
    S : numpy.ndarray
        State (layout ``TASK_PSMC_STATE``: a[k-1], Nabla a[k-1] (x, y)
        [m s]), updated in place.
    Pm : numpy.ndarray
        The controller's model row (layout ``PLANT``): kinematics, torque
        functions and gravity compensation.
    dt : float
        Control period T [s].
    qm, qdm : numpy.ndarray, shape (2,)
        Measured joint angles [rad] and velocities [rad/s].
    ref : numpy.ndarray, shape (12,)
        Reference row (r_d [m] and rd_d [m/s] in the ``R_X``, ``R_Y``,
        ``R_XD``, ``R_YD`` columns; q_d for ``GCMode.DESIRED``).
    dp : numpy.ndarray, shape (2,)
        Output Delta p per joint [Pa] ((5.33)-(5.34) plus Delta p_gc),
        written.
    internals : numpy.ndarray
        Logged internals (layout ``TASK_PSMC_INTERNALS``), written.
    scratch : numpy.ndarray, shape (TASK_PSMC_SCRATCH.size,)
        Work memory (layout ``TASK_PSMC_SCRATCH``), overwritten.
    """
    kp, ki, kd, lam, F = C[PT_KP], C[PT_KI], C[PT_KD], C[PT_LAM], C[PT_F]
    x, y = tcp_position(qm[0], qm[1], Pm)
    j11, j12, j21, j22 = tcp_jacobian(qm[0], qm[1], Pm)
    xd = j11 * qdm[0] + j12 * qdm[1]
    yd = j21 * qdm[0] + j22 * qdm[1]
    sx = (ref[R_X] - x) + lam * (ref[R_XD] - xd)
    sy = (ref[R_Y] - y) + lam * (ref[R_YD] - yd)
    fsx = proxy_update(sx, S[ST_A], S[ST_DA], kp, ki, kd, lam, dt)
    fsy = proxy_update(sy, S[ST_A + 1], S[ST_DA + 1], kp, ki, kd, lam, dt)
    norm = math.sqrt(fsx * fsx + fsy * fsy)
    scale = 1.0 if norm <= F else F / norm
    fx, fy = fsx * scale, fsy * scale
    ax = proxy_state(fx, S[ST_A], S[ST_DA], kp, ki, kd, dt)
    ay = proxy_state(fy, S[ST_A + 1], S[ST_DA + 1], kp, ki, kd, dt)
    S[ST_DA], S[ST_DA + 1] = ax - S[ST_A], ay - S[ST_A + 1]
    S[ST_A], S[ST_A + 1] = ax, ay
    tau1 = j11 * fx + j21 * fy                     # tau = J^T f   (5.30)
    tau2 = j12 * fx + j22 * fy
    mt = scratch[XT_MT:XT_MT + 4]
    torque_functions_cs(math.cos(qm[0]), math.sin(qm[0]), math.cos(qm[0] + qm[1]),
                        math.sin(qm[0] + qm[1]), Pm, mt)
    dp[0] = tau1 / (mt[0] - mt[1])                 # (5.33)-(5.34) without the p_m/G part,
    dp[1] = tau2 / (mt[2] - mt[3])                 # which the gravity compensation adds
    c = (dt + lam) / (ki * dt * dt + kp * dt + kd)
    internals[IT_F], internals[IT_F + 1] = fx, fy
    internals[IT_S], internals[IT_S + 1] = c * (fsx - fx), c * (fsy - fy)
    internals[IT_ON] = 1.0 if norm <= F else 0.0
    internals[IT_NORM] = norm
    internals[IT_A], internals[IT_A + 1] = ax, ay
    # proxy position r_p = r + Nabla a / T, in joint space by inverse kinematics
    qp1, qp2, ok = inverse_kinematics_elbow_up(x + S[ST_DA] / dt, y + S[ST_DA + 1] / dt, Pm)
    if not ok:
        qp1, qp2 = qm[0], qm[1]
    add_gravity_compensation(int(C[PT_GC]), Pm, qm, ref, qp1, qp2, dp,
                             scratch[XT_GC:XT_GC + _NGC])
