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


import numpy as np

from .._validation import check_range
from ..layouts import check_flag
from .base import Controller
from .dispatch import DECLARED
from .estimation import DEAD_ZONE_THESIS
from .kinds import KIND_ADMITTANCE
from .laws.admittance import ADMITTANCE_PARAMS, EstimateSource, PA_B, PA_FMIN, PA_SRC, _NJP
from .psmc import JointPSMC


#: Damping coefficient b of §5.4.3 [N s/m].
B_THESIS = 40.0


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
    PARAMS, STATE, INTERNALS, SCRATCH = DECLARED[KIND_ADMITTANCE]
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
