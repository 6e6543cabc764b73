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

import numpy as np

from .._jit import leaf
from ..units import BAR
from .base import KIND_PID, Controller, pair
from .gravity import add_gravity_compensation, gc_mode

#: Table 5.1 (a): Kp [bar/rad], Ki [bar/(rad s)], Kd [bar s/rad] per joint.
TABLE_5_1_PID = {"kp": (2.0, 1.5), "ki": (2.0, 2.0), "kd": (0.1, 0.1)}


@leaf
def pid_step(C, S, Pm, dt, qm, qdm, ref, dp, internals, scratch):
    """One PID update (state S: integral (2), previous error (2))."""
    for j in range(2):
        e = ref[j] - qm[j]
        S[j] += dt * e
        if C[6] > 0.5:
            ed = (e - S[2 + j]) / dt
        else:
            ed = ref[2 + j] - qdm[j]
        S[2 + j] = e
        dp[j] = C[j] * e + C[2 + j] * S[j] + C[4 + j] * ed
        internals[j] = dp[j]
        internals[2 + j] = S[j]
    add_gravity_compensation(C[7], Pm, qm, ref, 0.0, 0.0, dp, scratch)


class PID(Controller):
    """PID with static gravity compensation.

    Parameters
    ----------
    kp, ki, kd : float or pair of float, keyword-only
        Gains per joint in Pa/rad, Pa/(rad s), Pa s/rad (default Table 5.1 (a)).
    derivative : {"velocity", "difference"}
        Derivative from the measured velocity or from the error difference.
    gravity_compensation : {"desired", "measured", "off"}
        Static gravity compensation (3.18)-(3.19) at the set angles (default),
        at the measured angles, or none (see :mod:`ppamsafety.control.gravity`).

    Internals logged: PID output (2) and integral state (2).
    """

    kind = KIND_PID
    name = "PID"

    def __init__(self, *, kp=None, ki=None, kd=None, derivative: str = "velocity",
                 gravity_compensation="desired"):
        super().__init__()
        g = TABLE_5_1_PID
        self.kp = pair("PID.kp", np.asarray(g["kp"]) * BAR if kp is None else kp, unit="Pa/rad")
        self.ki = pair("PID.ki", np.asarray(g["ki"]) * BAR if ki is None else ki,
                       unit="Pa/(rad s)")
        self.kd = pair("PID.kd", np.asarray(g["kd"]) * BAR if kd is None else kd,
                       unit="Pa s/rad")
        if derivative not in ("velocity", "difference"):
            raise ValueError(f"PID.derivative = {derivative!r} is not 'velocity' or 'difference'")
        self.derivative = derivative
        self.gravity_compensation = gravity_compensation
        self.gc = gc_mode(gravity_compensation)

    def pack(self) -> np.ndarray:
        """Parameter vector of the compiled step function (SI units)."""
        return np.array([*self.kp, *self.ki, *self.kd, float(self.derivative == "difference"),
                         self.gc])

    def describe(self) -> dict:
        """Parameters as a flat dict for result tables."""
        return {"controller": self.name, "Ki_bar_per_rad_s": self.ki[0] / BAR, "lambda_s": np.nan}
