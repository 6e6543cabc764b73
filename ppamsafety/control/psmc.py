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

from .._validation import PRESSURE_MAX, check_range
from ..units import BAR
from .base import Controller, pair
from .dispatch import DECLARED
from .gravity import gc_mode
from .kinds import KIND_PSMC_JOINT, KIND_PSMC_TASK
from .laws.psmc import JOINT_PSMC_PARAMS, TASK_PSMC_PARAMS
from .pid import GAIN_MAX, TABLE_5_1_PID, check_position_feedback


#: Largest sliding-surface time constant lambda accepted [s] (Table 5.1: 0.4-1.5 s; a
#: lambda of minutes would make the proxy's recovery slower than any experiment).
LAMBDA_MAX = 100.0
#: Largest task-space virtual-coupling gain accepted [N/m, N/(m s), N s/m] (Table 5.1 (b):
#: 10-200).
TASK_GAIN_MAX = 1.0e7


def _limit_pair(name: str, value) -> tuple:
    """A per-joint pressure limit: each in (0, PRESSURE_MAX] Pa, or ``math.inf`` (no limit)."""
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool) \
            and math.isinf(value) and value > 0:
        return (math.inf, math.inf)
    seq = (isinstance(value, (list, tuple)) and len(value) == 2) or (
        isinstance(value, np.ndarray) and value.ndim == 1 and value.size == 2)
    if seq:                 # each entry checked on its own (a ragged list names its entry)
        return tuple(math.inf if (isinstance(v, (int, float, np.integer, np.floating))
                                  and not isinstance(v, bool) and math.isinf(v) and v > 0)
                     else pair(f"{name}[{j}]", v, lo=0.0, hi=PRESSURE_MAX, lo_open=True,
                               unit="Pa")[0]
                     for j, v in enumerate(value))
    return pair(name, value, lo=0.0, hi=PRESSURE_MAX, lo_open=True, unit="Pa")


def check_proxy_gains(owner: str, kp: float, ki: float, kd: float, lam: float,
                      suffix: str = "") -> None:
    """Refuse virtual-coupling gains for which the proxy update (5.27)-(5.29) fails.

    With non-negative gains, A = Ki T^2 + Kp T + Kd of (5.27)-(5.29) is zero
    for every control period T only if Kp = Ki = Kd = 0: (5.29) divides by
    A (and (5.32) by A), so the proxy state becomes NaN.  With Kp = Kd = 0
    and lambda = 0 the coupling is a pure integrator of the position error,
    which with the arm's inertia has no damping and oscillates with growing
    amplitude; refused too.

    Parameters
    ----------
    owner : str
        Controller name for the message.
    kp, ki, kd, lam : float
        Validated non-negative gains and lambda [s] of one proxy.
    suffix : str
        Index appended to the names in the message (``"[0]"`` for joint 1).

    Raises
    ------
    ValueError
        For the gain combinations above.
    """
    if kp == 0.0 and ki == 0.0 and kd == 0.0:
        raise ValueError(
            f"{owner}.kp{suffix} = {owner}.ki{suffix} = {owner}.kd{suffix} = 0: the proxy update "
            f"(5.27)-(5.29) divides by A = Ki T^2 + Kp T + Kd = 0; give Kp > 0")
    if kp == 0.0 and kd == 0.0 and lam == 0.0:
        raise ValueError(
            f"{owner}.kp{suffix} = {owner}.kd{suffix} = {owner}.lam{suffix} = 0: the coupling is "
            f"a pure integrator with no damping, the loop oscillates with growing amplitude; "
            f"give Kp > 0, Kd > 0 or lam > 0")


#: Table 5.1 (c), joint space: lambda [s], Delta p_lm [bar]; gains as PID.
TABLE_5_1_JOINT = {"lambda": 0.4, "dp_lm": 0.2}
#: Table 5.1 (b), task space: lambda [s], Kp [N/m], Ki [N/(m s)], Kd [N s/m], F [N].
TABLE_5_1_TASK = {"lambda": 0.4, "kp": 200.0, "ki": 100.0, "kd": 10.0, "F": 15.0}


class JointPSMC(Controller):
    """Joint-space proxy-based sliding mode control (5.37)-(5.41).

    Parameters
    ----------
    lam : float or pair, keyword-only
        Sliding-surface time constant lambda [s] (Table 5.1: 0.4), in
        [0, :data:`LAMBDA_MAX`].  0 is allowed (then PSMC with a huge limit
        is a discrete PID).
    kp, ki, kd : float or pair
        Virtual-coupling gains [Pa/rad, Pa/(rad s), Pa s/rad] (default as
        PID), each in [0, ``GAIN_MAX``] = [0, 1e9].  Refused per joint:
        Kp = Ki = 0 (no position feedback), Kp = Ki = Kd = 0 (the proxy
        update divides by zero, see :func:`check_proxy_gains`), Kp = Kd =
        lambda = 0 (undamped integrator).
    dp_limit : float or pair
        Delta p_lm [Pa] (Table 5.1: 0.2 bar), in (0, :data:`PRESSURE_MAX`] = (0, 100 bar],
        or ``math.inf``: no limit, which with lambda = 0 turns PSMC into a discrete PID
        (§5.2.6.4).  A finite limit beyond any pressure (1e300) is refused.
    gravity_compensation : {"proxy", "desired", "measured", "off"}
        Where (3.18)-(3.19) is evaluated; default the proxy position (see
        :mod:`ppamsafety.control.gravity`).
    """

    kind = KIND_PSMC_JOINT
    name = "PSMC joint"
    PARAMS, STATE, INTERNALS, SCRATCH = DECLARED[KIND_PSMC_JOINT]

    def __init__(self, *, lam=TABLE_5_1_JOINT["lambda"], kp=None, ki=None, kd=None,
                 dp_limit=TABLE_5_1_JOINT["dp_lm"] * BAR, gravity_compensation="proxy"):
        super().__init__()
        g = TABLE_5_1_PID
        self.lam = pair("JointPSMC.lam", lam, hi=LAMBDA_MAX, unit="s")
        self.kp = pair("JointPSMC.kp", np.asarray(g["kp"]) * BAR if kp is None else kp,
                       hi=GAIN_MAX, unit="Pa/rad")
        self.ki = pair("JointPSMC.ki", np.asarray(g["ki"]) * BAR if ki is None else ki,
                       hi=GAIN_MAX, unit="Pa/(rad s)")
        self.kd = pair("JointPSMC.kd", np.asarray(g["kd"]) * BAR if kd is None else kd,
                       hi=GAIN_MAX, unit="Pa s/rad")
        self.dp_limit = _limit_pair("JointPSMC.dp_limit", dp_limit)
        for j in range(2):
            check_proxy_gains("JointPSMC", self.kp[j], self.ki[j], self.kd[j], self.lam[j],
                              f"[{j}]")
        check_position_feedback("JointPSMC", self.kp, self.ki, self.kd)
        self.gravity_compensation = gravity_compensation
        self.gc = gc_mode(gravity_compensation, ("off", "measured", "desired", "proxy"),
                          name=f"{type(self).__name__}.gravity_compensation")

    def pack(self) -> np.ndarray:
        """Parameter row of the compiled step function (SI units)."""
        return JOINT_PSMC_PARAMS.pack(kp=self.kp, ki=self.ki, kd=self.kd, lam=self.lam,
                                      dp_limit=self.dp_limit, gc=int(self.gc))

    def describe(self) -> dict:
        """Parameters as a flat dict for result tables.

        Returns
        -------
        dict
            ``controller``, ``Ki_bar_per_rad_s`` and ``lambda_s`` of joint 1.
        """
        return {"controller": self.name, "Ki_bar_per_rad_s": self.ki[0] / BAR,
                "lambda_s": self.lam[0]}


class TaskPSMC(Controller):
    """Task-space proxy-based sliding mode control of the TCP (§5.3.2).

    Parameters
    ----------
    lam : float, keyword-only
        lambda [s] (Table 5.1: 0.4), in [0, 100].
    kp, ki, kd : float
        Virtual coupling [N/m, N/(m s), N s/m] (Table 5.1: 200, 100, 10),
        each in [0, 1e7]; the same combinations as for :class:`JointPSMC`
        are refused (Kp = Ki = 0, Kp = Ki = Kd = 0, Kp = Kd = lambda = 0).
    force_limit : float
        F [N] (Table 5.1: 15), in (0, 1e7].
    gravity_compensation : {"proxy", "desired", "measured", "off"}
        Where (3.18)-(3.19) is evaluated; default the proxy position (see
        :mod:`ppamsafety.control.gravity`).
    """

    kind = KIND_PSMC_TASK
    name = "PSMC task"
    PARAMS, STATE, INTERNALS, SCRATCH = DECLARED[KIND_PSMC_TASK]

    def __init__(self, *, lam=TABLE_5_1_TASK["lambda"], kp=TABLE_5_1_TASK["kp"],
                 ki=TABLE_5_1_TASK["ki"], kd=TABLE_5_1_TASK["kd"],
                 force_limit=TABLE_5_1_TASK["F"], gravity_compensation="proxy"):
        super().__init__()
        self.lam = check_range("TaskPSMC.lam", lam, 0.0, LAMBDA_MAX, unit="s")
        self.kp = check_range("TaskPSMC.kp", kp, 0.0, TASK_GAIN_MAX, unit="N/m")
        self.ki = check_range("TaskPSMC.ki", ki, 0.0, TASK_GAIN_MAX, unit="N/(m s)")
        self.kd = check_range("TaskPSMC.kd", kd, 0.0, TASK_GAIN_MAX, unit="N s/m")
        check_proxy_gains("TaskPSMC", self.kp, self.ki, self.kd, self.lam)
        if self.kp == 0.0 and self.ki == 0.0:
            raise ValueError("TaskPSMC.kp = 0 and TaskPSMC.ki = 0: the TCP has no position "
                             "feedback, nothing pulls it towards r_d; give Kp > 0 or Ki > 0 "
                             "(Table 5.1 (b): Kp = 200 N/m)")
        self.force_limit = check_range("TaskPSMC.force_limit", force_limit, 0.0, TASK_GAIN_MAX,
                                       lo_open=True, unit="N")
        self.gravity_compensation = gravity_compensation
        self.gc = gc_mode(gravity_compensation, ("off", "measured", "desired", "proxy"),
                          name=f"{type(self).__name__}.gravity_compensation")

    def pack(self) -> np.ndarray:
        """Parameter row of the compiled step function (SI units)."""
        return TASK_PSMC_PARAMS.pack(kp=self.kp, ki=self.ki, kd=self.kd, lam=self.lam,
                                     force_limit=self.force_limit, gc=int(self.gc))

    def describe(self) -> dict:
        """Parameters as a flat dict for result tables.

        Returns
        -------
        dict
            ``controller``, ``Ki_bar_per_rad_s`` (NaN), ``lambda_s``.
        """
        return {"controller": self.name, "Ki_bar_per_rad_s": np.nan, "lambda_s": self.lam}
