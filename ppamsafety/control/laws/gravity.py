"""The compiled law of :mod:`ppamsafety.control.gravity`: its declared rows and step kernel."""

from __future__ import annotations

from enum import IntEnum

from ..._jit import leaf
from ...layouts import Field, Layout
from ...plant.pneumatics import gravity_compensation_dp
from ..reference import R_Q


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
])
_G_MT = GC_SCRATCH.offset("mt")

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
        Work memory (layout ``GC_SCRATCH``: m_tau of the four muscle groups),
        overwritten.
    """
    if mode != GCMode.OFF:
        if mode == GCMode.MEASURED:
            q1, q2 = qm[0], qm[1]
        elif mode == GCMode.DESIRED:
            q1, q2 = ref[R_Q], ref[R_Q + 1]
        else:
            q1, q2 = qp1, qp2
        g1, g2 = gravity_compensation_dp(q1, q2, Pm, scratch[_G_MT:_G_MT + 4])
        dp[0] += g1
        dp[1] += g2


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
