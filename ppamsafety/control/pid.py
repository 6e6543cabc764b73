"""Discrete PID control with gravity compensation (thesis §5.3.1).

    Delta p = Delta p_gc + Kp e + Ki sum(e) T + Kd edot,    e = q_d - q

The integral is a backward-Euler sum (it includes the current error).  The
derivative term uses either the measured velocity (``derivative="velocity"``,
edot = qd_d - qd_meas, as on the thesis hardware with its inter-pulse timing
board) or the backward difference of the error (``derivative="difference"``,
edot = (e[k] - e[k-1])/T, with zero initial memory).  The latter is the
discrete PID that proxy-based sliding mode control reduces to for lambda = 0
and F -> infinity (§5.2.6.4, Kikuuwe & Fujimoto 2006).

Default gains: Table 5.1 (a), converted from bar to Pa.
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np

from .._jit import leaf
from ..layouts import Field, Layout, check_flag
from ..units import BAR
from .base import KIND_PID, R_Q, R_QD, Controller, pair
from .gravity import GC_SCRATCH, add_gravity_compensation, gc_mode

#: Table 5.1 (a): Kp [bar/rad], Ki [bar/(rad s)], Kd [bar s/rad] per joint.
TABLE_5_1_PID = {"kp": (2.0, 1.5), "ki": (2.0, 2.0), "kd": (0.1, 0.1)}


class PIDDerivative(IntEnum):
    """Source of the PID derivative term."""

    VELOCITY = 0        #: edot = qd_d - qd_meas
    DIFFERENCE = 1      #: edot = (e[k] - e[k-1]) / T


PID_PARAMS = Layout("PID parameters", [
    Field("kp", 2, "Pa/rad", "proportional gains (Table 5.1 (a))"),
    Field("ki", 2, "Pa/(rad s)", "integral gains"),
    Field("kd", 2, "Pa s/rad", "derivative gains"),
    Field("derivative", 1, "code", "PIDDerivative: derivative source"),
    Field("gc", 1, "code", "GCMode: gravity compensation"),
])
P_KP, P_KI, P_KD, P_DERIV, P_GC = PID_PARAMS.offsets("kp", "ki", "kd", "derivative", "gc")

PID_STATE = Layout("PID state", [
    Field("integral", 2, "rad s", "backward-Euler error integral sum(e) T"),
    Field("e_prev", 2, "rad", "previous error e[k-1] (difference derivative)"),
])
S_INT, S_EPREV = PID_STATE.offsets("integral", "e_prev")

PID_INTERNALS = Layout("PID internals", [
    Field("pid", 2, "Pa", "PID output Delta p before gravity compensation"),
    Field("integral", 2, "rad s", "error integral (state)"),
])
I_PID, I_INT = PID_INTERNALS.offsets("pid", "integral")


@leaf
def pid_step(C, S, Pm, dt, qm, qdm, ref, dp, internals, scratch):
    """One PID update (C: ``PID_PARAMS``, S: ``PID_STATE``, internals: ``PID_INTERNALS``)."""
    difference = int(C[P_DERIV]) == PIDDerivative.DIFFERENCE
    for j in range(2):
        e = ref[R_Q + j] - qm[j]
        S[S_INT + j] += dt * e
        if difference:
            ed = (e - S[S_EPREV + j]) / dt
        else:
            ed = ref[R_QD + j] - qdm[j]
        S[S_EPREV + j] = e
        dp[j] = C[P_KP + j] * e + C[P_KI + j] * S[S_INT + j] + C[P_KD + j] * ed
        internals[I_PID + j] = dp[j]
        internals[I_INT + j] = S[S_INT + j]
    add_gravity_compensation(int(C[P_GC]), Pm, qm, ref, 0.0, 0.0, dp, scratch)


class PID(Controller):
    """PID with static gravity compensation.

    Parameters
    ----------
    kp, ki, kd : float or pair of float, keyword-only
        Gains per joint in Pa/rad, Pa/(rad s), Pa s/rad (default Table 5.1 (a)).
    derivative : {"velocity", "difference"}
        Derivative from the measured velocity or from the error difference
        (:class:`PIDDerivative`).
    gravity_compensation : {"desired", "measured", "off"}
        Static gravity compensation (3.18)-(3.19) at the set angles (default),
        at the measured angles, or none (see :mod:`ppamsafety.control.gravity`).

    Internals logged: PID output (2) and integral state (2) (``PID_INTERNALS``).
    """

    kind = KIND_PID
    name = "PID"
    PARAMS = PID_PARAMS
    STATE = PID_STATE
    INTERNALS = PID_INTERNALS
    SCRATCH = GC_SCRATCH.size

    def __init__(self, *, kp=None, ki=None, kd=None, derivative: str = "velocity",
                 gravity_compensation="desired"):
        super().__init__()
        g = TABLE_5_1_PID
        self.kp = pair("PID.kp", np.asarray(g["kp"]) * BAR if kp is None else kp, unit="Pa/rad")
        self.ki = pair("PID.ki", np.asarray(g["ki"]) * BAR if ki is None else ki,
                       unit="Pa/(rad s)")
        self.kd = pair("PID.kd", np.asarray(g["kd"]) * BAR if kd is None else kd,
                       unit="Pa s/rad")
        code = check_flag(PIDDerivative, derivative, "PID.derivative")
        self.derivative = PIDDerivative(code).name.lower()
        self.gravity_compensation = gravity_compensation
        self.gc = gc_mode(gravity_compensation, name="PID.gravity_compensation")

    def pack(self) -> np.ndarray:
        """Parameter row of the compiled step function (layout ``PID_PARAMS``, SI units)."""
        return PID_PARAMS.pack(
            kp=self.kp, ki=self.ki, kd=self.kd, gc=int(self.gc),
            derivative=check_flag(PIDDerivative, self.derivative, "PID.derivative"))

    def describe(self) -> dict:
        """Parameters as a flat dict for result tables."""
        return {"controller": self.name, "Ki_bar_per_rad_s": self.ki[0] / BAR, "lambda_s": np.nan}
