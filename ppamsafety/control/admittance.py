"""Damping-only admittance control around joint-space PSMC (thesis §5.4.1, §5.4.3).

The desired TCP position moves with the estimated external force (5.43)::

    r_d(t) = r_0(t) + 1/b int_0^t f_dz(t') dt',     f_dz = dead zone of f_est   (5.43)

with b = 40 N s/m and the dead zone F_min = 3 N of §5.4.3 (||f_est|| <= F_min
-> f_dz = 0, else f_dz = f_est unchanged).  r_0(t) is the reference's TCP
position (columns ``x_d``, ``y_d``; a hold reference for the thesis'
experiment).  Discretisation: forward Euler, Delta r[k] = Delta r[k-1] +
T f_dz[k]/b.  The joint reference of the inner joint-space PSMC (5.37)-(5.41)
is q_d = IK_elbow-up(r_d), qd_d = J(q_d)^-1 (rd_0 + f_dz/b); if r_d leaves
the reachable annulus the offset is not advanced that sample.  There is no
working-area clamp (the thesis' operator kept the arm inside it).

f_est comes from the loop's :class:`~ppamsafety.control.estimation.ForceEstimator`
(the runner gives every controller the estimator's internals row); ``source``
selects the RLS (5.47) or the observer (5.56) estimate.  The model of the
estimators is theirs (``ForceEstimator.model``, default ``arm.model``), the
PSMC's gravity compensation uses the controller view (Table 3.1).
"""

from __future__ import annotations

import enum

import numpy as np

from .._jit import leaf
from .._validation import check_range
from ..layouts import Field, Layout, check_flag
from ..plant.geometry import inverse_kinematics_elbow_up, tcp_jacobian
from .base import (KIND_ADMITTANCE, NREF, R_Q, R_QD, R_QDD, R_X, R_XD, R_Y, R_YD, Controller)
from .estimation import DEAD_ZONE_THESIS, EI_FMO, EI_FRLS, dead_zone
from .gravity import GC_SCRATCH
from .psmc import (JOINT_PSMC_INTERNALS, JOINT_PSMC_PARAMS, JOINT_PSMC_STATE, JointPSMC,
                   psmc_joint_step, IJ_F, IJ_S)

#: Damping coefficient b of §5.4.3 [N s/m].
B_THESIS = 40.0


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


class AdmittancePSMC(Controller):
    """Damping-only admittance (5.43) around joint-space PSMC (§5.4.3).

    Needs a force estimator in the loop: an
    :class:`~ppamsafety.experiments.ExperimentCase` with this controller gets
    a default :class:`~ppamsafety.control.estimation.ForceEstimator` when its
    ``estimator`` is None.

    Parameters
    ----------
    b : float, keyword-only
        Damping b [N s/m] of the desired admittance 1/b (thesis 40), > 0.
    f_min : float, keyword-only
        Dead zone F_min [N] on the estimated force (thesis 3), >= 0.
    source : {"observer", "rls"}, keyword-only
        Which estimate drives the admittance (thesis: both worked alike).
    psmc : JointPSMC, optional, keyword-only
        The inner position controller (default ``JointPSMC()``, Table 5.1 (c)).

    Raises
    ------
    ValueError
        For b, f_min out of range or an unknown source.
    TypeError
        For a ``psmc`` that is not a JointPSMC.
    """

    kind = KIND_ADMITTANCE
    name = "Admittance PSMC"
    PARAMS = ADMITTANCE_PARAMS
    STATE = ADMITTANCE_STATE
    INTERNALS = ADMITTANCE_INTERNALS
    SCRATCH = ADMITTANCE_SCRATCH.size
    needs_estimator = True

    def __init__(self, *, b: float = B_THESIS, f_min: float = DEAD_ZONE_THESIS,
                 source: str = "observer", psmc: JointPSMC | None = None):
        super().__init__()
        self.b = check_range("AdmittancePSMC.b", b, 0.0, 1e6, lo_open=True, unit="N s/m")
        self.f_min = check_range("AdmittancePSMC.f_min", f_min, 0.0, 1e4, unit="N")
        self.source_code = EstimateSource(check_flag(EstimateSource, source,
                                                     "AdmittancePSMC.source"))
        self.source = self.source_code.name.lower()
        if psmc is None:
            psmc = JointPSMC()
        if not isinstance(psmc, JointPSMC):
            raise TypeError(f"AdmittancePSMC.psmc must be a JointPSMC, got "
                            f"{type(psmc).__name__}")
        self.psmc = psmc

    def pack(self) -> np.ndarray:
        """Parameter row of the compiled step (SI units)."""
        row = np.empty(ADMITTANCE_PARAMS.size)
        row[:_NJP] = self.psmc.pack()
        row[PA_B], row[PA_FMIN], row[PA_SRC] = self.b, self.f_min, float(self.source_code)
        return row

    def describe(self) -> dict:
        """Parameters as a flat dict for result tables."""
        d = self.psmc.describe()
        d.update(controller=self.name, b_Ns_per_m=self.b, f_min_N=self.f_min,
                 source=self.source)
        return d
