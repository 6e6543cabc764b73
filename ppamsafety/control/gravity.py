"""Static gravity compensation (thesis §3.5.1.5, eqs. (3.18)-(3.19)).

Delta p_gc makes the muscle torques (Delta-p approach with the mean
pressures p_m) balance the *identified* gravity torques K(q) theta_hat
(Table 3.1) through the identified torque functions (B.2).  The runner then
turns the desired pressures into valve set values with the inverse of the
static valve model (3.12), as the thesis does.

Where it is evaluated is a modelling choice the thesis leaves implicit.  The
options and what they do in simulation (measured with this toolkit, see the
controller-design section of the report):

* ``"desired"`` -- at the set angles q_d.  This is how §3.5.1.5 validates the
  compensation alone (set angles stepped in a sawtooth, fig. 3.1).  Default for
  :class:`GravityCompensation` and PID.  It keeps the antagonistic muscles'
  passive stiffness around q_d, but the feedforward jumps with every step of
  the reference, bypassing any limit on the feedback part.
* ``"measured"`` -- at the measured angles q.  Exact compensation at q also
  cancels the passive (constant-pressure) stiffness of the muscle pair,
  because the p_m (m_tau,1 + m_tau,2) part of (3.18) follows q; tracking
  degrades several-fold and high integral gains lose stability.
* ``"proxy"`` -- at the proxy's position (PSMC only): q_p = q + Nabla a/T in
  joint space, the inverse kinematics of r_p = r + Nabla a/T in task space.
  In normal tracking the proxy sits on q_d (so it behaves like
  ``"desired"``), after a large error it moves slowly with lambda (so the
  feedforward does too).  Default for PSMC: it is the only choice that
  reproduces both the tracking of Table 5.2 and the slow PSMC step responses
  of figs. 5.17-5.19 / Table 6.1.
"""

from __future__ import annotations

import numpy as np

from .._jit import leaf
from ..plant.pneumatics import gravity_compensation_dp
from .base import KIND_GC, Controller


GC_OFF, GC_MEASURED, GC_DESIRED, GC_PROXY = 0.0, 1.0, 2.0, 3.0
GC_MODES = {"off": GC_OFF, "measured": GC_MEASURED, "desired": GC_DESIRED, "proxy": GC_PROXY}


@leaf
def add_gravity_compensation(mode, Pm, qm, ref, qp1, qp2, dp, scratch):
    """Add Delta p_gc to ``dp`` in place (``scratch`` >= 12 floats).

    ``mode``: 0 off, 1 at the measured angles ``qm``, 2 at the desired
    angles ``ref[0:2]``, 3 at the proxy angles (qp1, qp2) [rad].
    """
    if mode > 0.5:
        if mode < 1.5:
            q1, q2 = qm[0], qm[1]
        elif mode < 2.5:
            q1, q2 = ref[0], ref[1]
        else:
            q1, q2 = qp1, qp2
        g1, g2 = gravity_compensation_dp(q1, q2, Pm, scratch[0:4], scratch[4:8], scratch[8:12])
        dp[0] += g1
        dp[1] += g2


def gc_mode(value, allowed=("off", "measured", "desired")) -> float:
    """Validate a gravity-compensation mode name and return its code."""
    if value not in allowed:
        raise ValueError(f"gravity_compensation = {value!r} is not one of {list(allowed)}")
    return GC_MODES[value]


@leaf
def gc_step(C, Pm, qm, ref, dp_out, scratch):
    """Delta p_gc only (no feedback); C = [mode]."""
    dp_out[0] = 0.0
    dp_out[1] = 0.0
    add_gravity_compensation(C[0], Pm, qm, ref, 0.0, 0.0, dp_out, scratch)


class GravityCompensation(Controller):
    """Static gravity compensation alone (no feedback).

    Parameters
    ----------
    at : {"desired", "measured"}
        Where (3.18)-(3.19) is evaluated (default: the set angles, as in the
        validation experiment of §3.5.1.6).
    """

    kind = KIND_GC
    name = "gravity compensation"

    def __init__(self, *, at: str = "desired"):
        super().__init__()
        if at not in ("desired", "measured"):
            raise ValueError(f"GravityCompensation.at = {at!r} is not 'desired' or 'measured'")
        self.at = at

    def pack(self) -> np.ndarray:
        """Parameter vector of the compiled step function (SI units)."""
        return np.array([gc_mode(self.at)])
