"""The compiled law of :mod:`ppamsafety.control.admittance`: its declared rows and step kernel."""

from __future__ import annotations

import enum

from ..._jit import leaf
from ...layouts import Field, Layout
from ...plant.geometry import inverse_kinematics_elbow_up, tcp_jacobian
from ..estimation import EI_FMO, EI_FRLS, dead_zone
from ..reference import NREF, R_Q, R_QD, R_QDD, R_X, R_XD, R_Y, R_YD
from .gravity import GC_SCRATCH
from .psmc import (JOINT_PSMC_INTERNALS, JOINT_PSMC_PARAMS, JOINT_PSMC_STATE, psmc_joint_step, IJ_F,
                   IJ_S)


class EstimateSource(enum.IntEnum):
    """Which force estimate drives the admittance."""

    RLS = 0
    OBSERVER = 1


_NJP, _NJS = JOINT_PSMC_PARAMS.size, JOINT_PSMC_STATE.size

ADMITTANCE_PARAMS = Layout("admittance PSMC parameters", list(JOINT_PSMC_PARAMS.fields) + [
    Field("b", 1, "N s/m", "admittance damping b (5.43), thesis 40"),
    Field("f_min", 1, "N", "dead zone F_min on ||f_est|| (§5.4.3), thesis 3"),
    Field("source", 1, "code", "EstimateSource: RLS (5.47) or observer (5.56)"),
])
PA_B, PA_FMIN, PA_SRC = ADMITTANCE_PARAMS.offsets("b", "f_min", "source")

ADMITTANCE_STATE = Layout("admittance PSMC state", list(JOINT_PSMC_STATE.fields) + [
    Field("dr", 2, "m", "admittance offset Delta r = 1/b int f_dz dt (5.43) (x, y)",
          columns=("drx", "dry")),
])
SA_DR = ADMITTANCE_STATE.offset("dr")

ADMITTANCE_INTERNALS = Layout("admittance PSMC internals", [
    Field("dp_psmc", 2, "Pa", "saturated proxy output of the inner joint PSMC"),
    Field("s", 2, "rad", "sliding variable s[k] of the inner joint PSMC (5.32)"),
    Field("r_adm", 2, "m", "admittance desired TCP position r_d (5.43)",
          columns=("x_adm", "y_adm")),
    Field("f_dz", 2, "N", "dead-zoned force estimate driving the admittance",
          columns=("Fx_dz", "Fy_dz")),
])
IA_F, IA_S, IA_R, IA_FDZ = ADMITTANCE_INTERNALS.offsets("dp_psmc", "s", "r_adm", "f_dz")

ADMITTANCE_SCRATCH = Layout("admittance PSMC scratch", [
    Field("ref", NREF, "-", "reference row handed to the inner PSMC"),
    Field("psmc_internals", JOINT_PSMC_INTERNALS.size, "-", "inner PSMC internals"),
    Field("gc", GC_SCRATCH.size, "-", "work memory of the gravity compensation"),
])
XA_REF, XA_INT, XA_GC = ADMITTANCE_SCRATCH.offsets("ref", "psmc_internals", "gc")
_NPI, _NGC = JOINT_PSMC_INTERNALS.size, GC_SCRATCH.size


@leaf
def admittance_step(C, S, Pm, dt, qm, qdm, ref, fest, dp, internals, scratch):
    """Admittance (5.43) + joint PSMC: one control sample.

    Parameters
    ----------
    C : numpy.ndarray
        Parameter row (``ADMITTANCE_PARAMS``).
    S : numpy.ndarray
        State (``ADMITTANCE_STATE``), updated in place.
    Pm : numpy.ndarray
        The controller's model row (geometry, gravity compensation).
    dt : float
        Control period [s].
    qm, qdm : numpy.ndarray, shape (2,)
        Measured angles [rad] and velocities [rad/s].
    ref : numpy.ndarray, shape (12,)
        Reference row (its TCP position is r_0 of (5.43)).
    fest : numpy.ndarray
        The estimator's internals row (``ESTIMATOR_INTERNALS``).
    dp : numpy.ndarray, shape (2,)
        Written: Delta p per joint [Pa].
    internals : numpy.ndarray
        Written: ``ADMITTANCE_INTERNALS``.
    scratch : numpy.ndarray
        Work memory (``ADMITTANCE_SCRATCH``).
    """
    b, fmin = C[PA_B], C[PA_FMIN]
    if int(C[PA_SRC]) == EstimateSource.RLS:
        fx, fy = fest[EI_FRLS], fest[EI_FRLS + 1]
    else:
        fx, fy = fest[EI_FMO], fest[EI_FMO + 1]
    fx, fy = dead_zone(fx, fy, fmin)
    vx, vy = fx / b, fy / b
    drx = S[SA_DR] + dt * vx
    dry = S[SA_DR + 1] + dt * vy
    xd, yd = ref[R_X] + drx, ref[R_Y] + dry
    q1d, q2d, ok = inverse_kinematics_elbow_up(xd, yd, Pm)
    if not ok:                                   # not reachable: keep the previous offset
        drx, dry, vx, vy = S[SA_DR], S[SA_DR + 1], 0.0, 0.0
        xd, yd = ref[R_X] + drx, ref[R_Y] + dry
        q1d, q2d, ok = inverse_kinematics_elbow_up(xd, yd, Pm)
        if not ok:
            q1d, q2d = ref[R_Q], ref[R_Q + 1]
    S[SA_DR], S[SA_DR + 1] = drx, dry
    j11, j12, j21, j22 = tcp_jacobian(q1d, q2d, Pm)
    vxt, vyt = ref[R_XD] + vx, ref[R_YD] + vy
    det = j11 * j22 - j12 * j21
    rr = scratch[XA_REF:XA_REF + NREF]
    for i in range(NREF):
        rr[i] = ref[i]
    rr[R_Q], rr[R_Q + 1] = q1d, q2d
    rr[R_QD] = (j22 * vxt - j12 * vyt) / det
    rr[R_QD + 1] = (j11 * vyt - j21 * vxt) / det
    rr[R_QDD], rr[R_QDD + 1] = 0.0, 0.0
    rr[R_X], rr[R_Y], rr[R_XD], rr[R_YD] = xd, yd, vxt, vyt
    pint = scratch[XA_INT:XA_INT + _NPI]
    psmc_joint_step(C[:_NJP], S[:_NJS], Pm, dt, qm, qdm, rr, dp, pint,
                    scratch[XA_GC:XA_GC + _NGC])
    internals[IA_F], internals[IA_F + 1] = pint[IJ_F], pint[IJ_F + 1]
    internals[IA_S], internals[IA_S + 1] = pint[IJ_S], pint[IJ_S + 1]
    internals[IA_R], internals[IA_R + 1] = xd, yd
    internals[IA_FDZ], internals[IA_FDZ + 1] = fx, fy
