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

from enum import IntEnum

import numpy as np

from .._jit import leaf
from .._validation import check_choice
from ..layouts import Field, Layout, check_flag
from ..plant.pneumatics import gravity_compensation_dp
from .base import KIND_GC, R_Q, Controller


class GCMode(IntEnum):
    """Where the static gravity compensation is evaluated (see the module docstring)."""

    OFF = 0
    MEASURED = 1
    DESIRED = 2
    PROXY = 3


GC_OFF, GC_MEASURED, GC_DESIRED, GC_PROXY = (GCMode.OFF, GCMode.MEASURED, GCMode.DESIRED,
                                             GCMode.PROXY)
GC_MODES = {m.name.lower(): m for m in GCMode}

#: Work memory of :func:`add_gravity_compensation` (arguments of
#: :func:`ppamsafety.plant.pneumatics.gravity_compensation_dp`).
GC_SCRATCH = Layout("gravity compensation scratch", [
    Field("mt", 4, "m^3", "m_tau of the four muscle groups (B.2)"),
    Field("dmt", 4, "m^3/rad", "d m_tau / dq"),
    Field("vol", 4, "m^3", "group volumes"),
])
_G_MT, _G_DMT, _G_VOL = GC_SCRATCH.offsets("mt", "dmt", "vol")

#: Parameter row of :class:`GravityCompensation`.
GC_PARAMS = Layout("gravity compensation parameters", [
    Field("gc", 1, "code", "GCMode: where (3.18)-(3.19) is evaluated"),
])
P_GC_MODE = GC_PARAMS.offset("gc")


@leaf
def add_gravity_compensation(mode, Pm, qm, ref, qp1, qp2, dp, scratch):
    """Add Delta p_gc of (3.18)-(3.19) to ``dp`` in place (compiled, unchecked).

    Parameters
    ----------
    mode : int
        :class:`GCMode` code: off (``dp`` unchanged), at the measured angles
        ``qm``, at the desired angles of the reference row ``ref``, or at
        the proxy angles (``qp1``, ``qp2``).
    Pm : numpy.ndarray
        The controller's model row (layout ``PLANT`` of
        :mod:`ppamsafety.plant.layout`): identified gravity and torque
        functions (Table 3.1, (B.2)), mean pressures p_m.
    qm : numpy.ndarray, shape (2,)
        Measured joint angles [rad] (read for ``GCMode.MEASURED``).
    ref : numpy.ndarray, shape (12,)
        Reference row; its q_d columns (``R_Q``) [rad] are read for
        ``GCMode.DESIRED``.
    qp1, qp2 : float
        Proxy joint angles [rad] (read for ``GCMode.PROXY``; pass 0.0
        otherwise).
    dp : numpy.ndarray, shape (2,)
        Delta p per joint [Pa]; Delta p_gc is added to it.
    scratch : numpy.ndarray, shape (GC_SCRATCH.size,)
        Work memory (layout ``GC_SCRATCH``: m_tau, d m_tau/dq and volumes of
        the four muscle groups), overwritten.
    """
    if mode != GCMode.OFF:
        if mode == GCMode.MEASURED:
            q1, q2 = qm[0], qm[1]
        elif mode == GCMode.DESIRED:
            q1, q2 = ref[R_Q], ref[R_Q + 1]
        else:
            q1, q2 = qp1, qp2
        g1, g2 = gravity_compensation_dp(q1, q2, Pm, scratch[_G_MT:_G_MT + 4],
                                         scratch[_G_DMT:_G_DMT + 4], scratch[_G_VOL:_G_VOL + 4])
        dp[0] += g1
        dp[1] += g2


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


@leaf
def gc_step(C, Pm, qm, ref, dp_out, scratch):
    """Delta p_gc only, no feedback (compiled step of :class:`GravityCompensation`).

    Parameters
    ----------
    C : numpy.ndarray
        Parameter row (layout ``GC_PARAMS``: the :class:`GCMode` code).
    Pm : numpy.ndarray
        The controller's model row (layout ``PLANT``).
    qm : numpy.ndarray, shape (2,)
        Measured joint angles [rad].
    ref : numpy.ndarray, shape (12,)
        Reference row (q_d [rad] in the ``R_Q`` columns).
    dp_out : numpy.ndarray, shape (2,)
        Output Delta p_gc per joint [Pa], written.
    scratch : numpy.ndarray, shape (GC_SCRATCH.size,)
        Work memory (layout ``GC_SCRATCH``), overwritten.
    """
    dp_out[0] = 0.0
    dp_out[1] = 0.0
    add_gravity_compensation(int(C[P_GC_MODE]), Pm, qm, ref, 0.0, 0.0, dp_out, scratch)


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
    PARAMS = GC_PARAMS
    SCRATCH = GC_SCRATCH.size

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
