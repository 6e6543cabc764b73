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

from ..layouts import check_flag
from ..units import BAR
from .base import Controller, pair
from .dispatch import DECLARED
from .gravity import gc_mode
from .kinds import KIND_PID
from .laws.pid import PIDDerivative, PID_PARAMS


#: Table 5.1 (a): Kp [bar/rad], Ki [bar/(rad s)], Kd [bar s/rad] per joint.
TABLE_5_1_PID = {"kp": (2.0, 1.5), "ki": (2.0, 2.0), "kd": (0.1, 0.1)}


#: Largest gain accepted by PID and joint PSMC [Pa/rad, Pa/(rad s), Pa s/rad]: 10^4 bar/rad,
#: about 5000 times the gains of Table 5.1 (larger gains only amplify sensor noise and
#: overflow the pressure command).
GAIN_MAX = 1.0e9


def check_position_feedback(owner: str, kp, ki, kd) -> None:
    """Refuse gains that leave a joint without position feedback.

    Parameters
    ----------
    owner : str
        Controller name for the message (``"PID"``, ``"JointPSMC"``).
    kp, ki, kd : pair of float
        Validated non-negative gains per joint.

    Raises
    ------
    ValueError
        If ``kp[j] == ki[j] == 0`` for a joint ``j`` (only the derivative
        term, or nothing, acts: no restoring action towards q_d).
    """
    for j in range(2):
        if kp[j] == 0.0 and ki[j] == 0.0:
            what = "no feedback at all" if kd[j] == 0.0 else "only damping (Kd)"
            raise ValueError(
                f"{owner}.kp[{j}] = 0 and {owner}.ki[{j}] = 0: joint {j + 1} has no position "
                f"feedback ({what}; Kd = {kd[j]:g}), so nothing pulls it towards q_d; give "
                f"Kp > 0 or Ki > 0 (Table 5.1: Kp = 2 bar/rad = 2e5 Pa/rad)")


class PID(Controller):
    """PID with static gravity compensation.

    Parameters
    ----------
    kp, ki, kd : float or pair of float, keyword-only
        Gains per joint in Pa/rad, Pa/(rad s), Pa s/rad (default Table 5.1
        (a)), each in [0, :data:`GAIN_MAX`].  Kp and Ki must not both be
        zero on a joint: that joint would have no position feedback (only
        damping), so gravity and friction would let it drift.
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
    PARAMS, STATE, INTERNALS, SCRATCH = DECLARED[KIND_PID]

    def __init__(self, *, kp=None, ki=None, kd=None, derivative: str = "velocity",
                 gravity_compensation="desired"):
        super().__init__()
        g = TABLE_5_1_PID
        self.kp = pair("PID.kp", np.asarray(g["kp"]) * BAR if kp is None else kp,
                       hi=GAIN_MAX, unit="Pa/rad")
        self.ki = pair("PID.ki", np.asarray(g["ki"]) * BAR if ki is None else ki,
                       hi=GAIN_MAX, unit="Pa/(rad s)")
        self.kd = pair("PID.kd", np.asarray(g["kd"]) * BAR if kd is None else kd,
                       hi=GAIN_MAX, unit="Pa s/rad")
        check_position_feedback("PID", self.kp, self.ki, self.kd)
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
        """Parameters as a flat dict for result tables.

        Returns
        -------
        dict
            ``controller``, ``Ki_bar_per_rad_s`` (joint 1), ``lambda_s`` (NaN).
        """
        return {"controller": self.name, "Ki_bar_per_rad_s": self.ki[0] / BAR, "lambda_s": np.nan}
