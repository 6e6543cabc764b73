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

from .._validation import check_choice
from ..layouts import check_flag
from .base import Controller
from .dispatch import DECLARED
from .kinds import KIND_GC
from .laws.gravity import GCMode, GC_PARAMS


def gc_mode(value, allowed=("off", "measured", "desired"), name: str = "gravity_compensation"
            ) -> GCMode:
    """Validate a gravity-compensation mode (member, name or code) and return the member.

    Parameters
    ----------
    value : GCMode, str or int
        The mode.
    allowed : sequence of str
        Names of the modes the caller supports.
    name : str
        Argument name for the error message.

    Returns
    -------
    GCMode
        The mode.

    Raises
    ------
    ValueError
        For a mode that is not one of ``allowed`` (naming ``name``).
    """
    allowed_codes = {int(GCMode[a.upper()]) for a in allowed}
    try:
        code = check_flag(GCMode, value, name)
    except ValueError:
        code = None
    if code not in allowed_codes:
        raise ValueError(f"{name} = {value!r} is not one of {list(allowed)}")
    return GCMode(code)


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
    PARAMS, STATE, INTERNALS, SCRATCH = DECLARED[KIND_GC]

    def __init__(self, *, at: str = "desired"):
        super().__init__()
        self.at = check_choice("GravityCompensation.at", at, ("desired", "measured"))

    @property
    def gc(self) -> GCMode:
        """Gravity-compensation mode code."""
        return gc_mode(self.at, name="GravityCompensation.at")

    def pack(self) -> np.ndarray:
        """Parameter row of the compiled step function (layout ``GC_PARAMS``)."""
        return GC_PARAMS.pack(gc=int(self.gc))
