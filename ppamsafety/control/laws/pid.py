"""The compiled law of :mod:`ppamsafety.control.pid`: its declared rows and step kernel."""

from __future__ import annotations

from enum import IntEnum

from ..._jit import leaf
from ...layouts import Field, Layout
from ..reference import R_Q, R_QD
from .gravity import add_gravity_compensation


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
    """One PID update (compiled; arguments are not checked).

    Parameters
    ----------
    C : numpy.ndarray
        Parameter row (layout ``PID_PARAMS``).
    S : numpy.ndarray
        State (layout ``PID_STATE``), updated in place.
    Pm : numpy.ndarray
        Controller's model row (layout ``PLANT``).
    dt : float
        Control period [s].
    qm, qdm : numpy.ndarray, shape (2,)
        Measured angles [rad] and velocities [rad/s].
    ref : numpy.ndarray, shape (12,)
        Reference row.
    dp : numpy.ndarray, shape (2,)
        Output Delta p [Pa], written.
    internals : numpy.ndarray
        Logged internals (layout ``PID_INTERNALS``), written.
    scratch : numpy.ndarray
        Work memory (``GC_SCRATCH``).
    """
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
