"""Reconstructing the thesis' head contact model from the evidence.

The thesis used Hunt-Crossley parameters of Haddadin et al. (2007) but does
not print them.  Three pieces of evidence constrain (k, n, b):

(a) **Table 6.1** lists 20 (HIC, F_max) pairs computed with that one contact
    model and a 5 kg head.  For a given effective arm mass at the tool, each
    impact speed gives one (F_max, HIC) point, so the pairs lie near one
    curve HIC(F_max).  We fit k and b to them in log space with a two-body
    model (:mod:`ppamsafety.impact.twobody`) whose arm mass is the thesis arm's
    effective mass at the step-response impact (:func:`default_arm_mass`).
    The printed HIC values have two decimals, so each pair gets a log-space
    standard deviation max(0.15, 0.005/HIC) (rounding, plus 15 % for the
    configuration-dependent effective mass).
(b) **Hybrid III head drop** (49 CFR 572.32): a 4.54 kg head dropped 376 mm
    onto a rigid plate must peak at 225-275 g.
(c) **ISO/TS 15066** Annex A: effective spring constant of the skull/forehead
    150 N/mm (energy-equivalent linear spring).

The pairs alone do not identify the exponent n (fits with n from 1 to 2 are
equally good), so n is fixed at the Hertz value 1.5 for a sphere-like
contact.  (b) and (c) are *checks*: the fitted contact is much softer than a
bare Hybrid III head on steel, which is expected -- Haddadin's parameters
describe the head against the robot's link (whose surface and structure
comply in series with the head), not against a rigid plate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..results import Result
from .._validation import (as_float_array, check_finite_result, check_instance, check_positive,
                           check_range, check_range_array, check_real)
from ..params import ArmParameters, thesis_arm
from ..params.iso_ts_15066 import FACE, SKULL_FOREHEAD
from ..plant import geometry as geo
from ..plots.impact import plot_head_fit
from ..units import DEG, G0
from .head import resolve_head
from .model import effective_mass
from .thesis_data import table_6_1_pairs
from .twobody import two_body_impact

HYBRID3_HEAD_MASS = 4.54            # kg (49 CFR 572 Subpart E)
HYBRID3_DROP_HEIGHT = 0.376         # m  (49 CFR 572.32)
HYBRID3_PEAK_RANGE_G = (225.0, 275.0)
ISO_TS_15066_FOREHEAD = 150.0e3     # N/m (150 N/mm)
ISO_TS_15066_FOREHEAD_FORCE = 130.0  # N, quasi-static permissible force, skull/forehead


def _arm(arm):
    return check_instance("arm", arm, ArmParameters)


def _contact(stiffness, exponent, damping):
    """Validated Hunt-Crossley (k, n, b); same ranges as :class:`HeadContactModel`."""
    return (check_range("stiffness", stiffness, 0.0, 1e20, lo_open=True, unit="N/m^n"),
            check_range("exponent", exponent, 1.0, 3.0),
            check_range("damping", damping, 0.0, 1e20, unit="N s/m^(n+1)"))


def _step(dt):
    """Integration step of the two-body model: [1e-8, 1e-4] s (0.02-0.05 s records)."""
    return check_range("dt", dt, 1e-8, 1e-4, unit="s")


def _finite_results(r: dict, what: str) -> dict:
    for key in ("F_max", "HIC36", "HIC15"):
        check_finite_result(f"{key} of {what}", r[key],
                            "these contact parameters (the impact is too violent to integrate)")
    return r


def default_arm_mass(arm) -> float:
    """Effective mass of the thesis arm at the tool for the step-response impact [kg].

    At q = (50, -80) deg with the tool moving as joint 1 turns (the step moves
    q1), see :func:`ppamsafety.impact.model.effective_mass`.

    Parameters
    ----------
    arm : ArmParameters
        The arm (links, geometry); TypeError otherwise.
    """
    arm = _arm(arm)

    q = np.array([50 * DEG, -80 * DEG])
    return float(effective_mass(q, geo.jacobian(q, arm)[:, 0], arm))


def hybrid3_drop_peak_g(stiffness, exponent, damping, *, dt=1e-6) -> float:
    """Peak head acceleration [g] of the Hybrid III drop test with this contact.

    A 4.54 kg head falling 376 mm onto a rigid plate (49 CFR 572.32; infinite
    arm mass in the two-body model), 20 ms simulated; peak F_max / (m g0).

    Parameters
    ----------
    stiffness : float
        Contact stiffness k [N/m^n], > 0.
    exponent : float
        Contact exponent n [-], in [1, 3].
    damping : float
        Hunt-Crossley damping b [N s/m^(n+1)], >= 0 (the ranges of
        :class:`~ppamsafety.impact.head.HeadContactModel`).
    dt : float, keyword-only
        Integration step [s], in [1e-8, 1e-4] (default 1e-6).
    """
    stiffness, exponent, damping = _contact(stiffness, exponent, damping)
    dt = _step(dt)
    v = math.sqrt(2.0 * G0 * HYBRID3_DROP_HEIGHT)
    r = _finite_results(two_body_impact([v], arm_mass=np.inf, head_mass=HYBRID3_HEAD_MASS, stiffness=stiffness,
                        exponent=exponent, damping=damping, dt=dt, duration=0.02),
        "the drop test")
    return float(r["F_max"][0] / (HYBRID3_HEAD_MASS * G0))


def iso_effective_spring(stiffness, exponent, force) -> float:
    """Energy-equivalent linear spring F^2/(2E) of the elastic part at ``force`` [N/m].

    E is the elastic contact energy k delta^(n+1)/(n+1) at the penetration
    where k delta^n = F.

    Parameters
    ----------
    stiffness : float
        Contact stiffness k [N/m^n], > 0.
    exponent : float
        Contact exponent n [-], in [1, 3].
    force : float
        Contact force F [N], in (0, 1e6].
    """
    stiffness = check_range("stiffness", stiffness, 0.0, 1e20, lo_open=True, unit="N/m^n")
    exponent = check_range("exponent", exponent, 1.0, 3.0)
    force = check_range("force", force, 0.0, 1e6, lo_open=True, unit="N")
    # With k delta^n = F the elastic energy is E = F delta/(n + 1), so F^2/(2E) =
    # (n + 1) F/(2 delta); evaluated in logarithms so that extreme but valid k and F
    # cannot overflow or underflow in an intermediate power.
    log_delta = (math.log(force) - math.log(stiffness)) / exponent
    log_spring = math.log((exponent + 1.0) / 2.0) + math.log(force) - log_delta
    if not -700.0 < log_spring < 700.0:
        raise ValueError(f"iso_effective_spring: stiffness = {stiffness:g} N/m^n, exponent = "
                         f"{exponent:g}, force = {force:g} N give an effective spring of "
                         f"e^{log_spring:.0f} N/m, outside the floating-point range")
    return float(check_finite_result("iso_effective_spring", math.exp(log_spring),
                                     f"stiffness = {stiffness:g}, exponent = {exponent:g}"))


def hic_curve(stiffness, exponent, damping, *, arm_mass, head_mass=5.0, dt=1e-5,
              speeds=None) -> pd.DataFrame:
    """Model (F_max, HIC36) over a range of impact speeds (the 'one curve' of (a)).

    Parameters
    ----------
    stiffness, exponent, damping : float
        Hunt-Crossley k [N/m^n] > 0, n in [1, 3], b [N s/m^(n+1)] >= 0.
    arm_mass : float, keyword-only
        Effective arm mass at the tool [kg], > 0 (``math.inf``: rigid arm).
    head_mass : float
        Head mass [kg], in (0, 100].
    dt : float
        Integration step [s], in [1e-8, 1e-4].
    speeds : array_like, optional
        1-D impact speeds [m/s] in (0, 20]; default 40 speeds from 0.02 to 8 m/s.
    """
    stiffness, exponent, damping = _contact(stiffness, exponent, damping)
    ma = check_real("arm_mass", arm_mass, unit="kg")
    if ma != math.inf:
        ma = check_positive("arm_mass", ma, unit="kg")
    head_mass = check_range("head_mass", head_mass, 0.0, 100.0, lo_open=True, unit="kg")
    dt = _step(dt)
    if speeds is None:
        v = np.geomspace(0.02, 8.0, 40)
    else:
        v = as_float_array("speeds", speeds, ndim=1, min_len=1)
        check_range_array("speeds", v, 1e-6, 20.0, unit="m/s")
    r = _finite_results(two_body_impact(v, arm_mass=ma, head_mass=head_mass,
                                        stiffness=stiffness, exponent=exponent,
                                        damping=damping, dt=dt), "the impacts")
    return pd.DataFrame({"speed": v, "F_max": r["F_max"], "HIC36": r["HIC36"]})


@dataclass(frozen=True)
class HeadFit(Result):
    """Result of :func:`fit_thesis_head`.

    Attributes
    ----------
    stiffness, exponent, damping : float
        Fitted k [N/m^n], fixed n, fitted b [N s/m^(n+1)].
    arm_mass, head_mass : float
        Masses of the two-body model [kg].
    pairs : pandas.DataFrame
        Table 6.1 pairs with the model HIC at the same F_max and the residual
        in standard deviations.
    rms_sigma : float
        RMS residual of the pairs [standard deviations].
    drop_peak_g : float
        Predicted Hybrid III drop peak [g] (evidence (b)).
    iso_spring : float
        Energy-equivalent spring at 130 N [N/m] (evidence (c)).
    """

    stiffness: float
    exponent: float
    damping: float
    arm_mass: float
    head_mass: float
    pairs: pd.DataFrame
    rms_sigma: float
    drop_peak_g: float
    iso_spring: float

    def to_pandas(self) -> pd.DataFrame:
        """The Table 6.1 pairs (:attr:`pairs`) with the model HIC and the residuals."""
        return self.pairs

    def mean_residual(self) -> dict:
        """Mean residual of the pairs per experiment [standard deviations]:
        ``{"step": ..., "switch": ...}``."""
        p = self.pairs
        return {e: float(p[p.experiment == e].residual_sigma.mean())
                for e in p.experiment.unique()}

    def curve(self) -> pd.DataFrame:
        """The fitted model's (F_max, HIC36) curve over impact speeds (:func:`hic_curve`)."""
        return hic_curve(self.stiffness, self.exponent, self.damping, arm_mass=self.arm_mass,
                         head_mass=self.head_mass)

    def plot(self, **kwargs):
        """The Table 6.1 pairs against the fitted HIC(F_max) curve, a matplotlib Figure.

        Parameters
        ----------
        **kwargs
            Passed to :func:`ppamsafety.plots.impact.plot_head_fit` (``title``).
        """
        return plot_head_fit(self.pairs, self.curve(), **kwargs)


def hic_at_force(F, curve: pd.DataFrame) -> np.ndarray:
    """HIC36 of a model's (F_max, HIC36) curve at the forces ``F`` [N] (log-log interpolation).

    Parameters
    ----------
    F : array_like
        Peak forces [N], > 0.
    curve : pandas.DataFrame
        Columns ``F_max`` [N] and ``HIC36`` over impact speeds (:func:`hic_curve`); points
        with a zero value (trial parameters may give some) are left out; fewer than two
        points give 1e-15 (an unusable model, far from every pair).
    """
    ok = (curve["F_max"] > 0) & (curve["HIC36"] > 0)
    if ok.sum() < 2:
        return np.full(np.shape(F), 1e-15)
    c = curve[ok]
    return np.exp(np.interp(np.log(F), np.log(c["F_max"].to_numpy()),
                            np.log(c["HIC36"].to_numpy())))


def pair_sigma(hic) -> np.ndarray:
    """Log-space standard deviation of Table 6.1 HIC values: max(0.15, 0.005/HIC) (module
    docstring: rounding of two printed decimals, plus 15 % for the configuration-dependent
    effective mass).

    Parameters
    ----------
    hic : array_like
        Printed HIC values (> 0).
    """
    return np.maximum(0.15, 0.005 / np.asarray(hic, dtype=float))


def _model_hic_at(F, k, n, b, arm_mass, head_mass):
    return hic_at_force(F, hic_curve(k, n, b, arm_mass=arm_mass, head_mass=head_mass))


def fit_thesis_head(arm, *, exponent: float = 1.5, arm_mass: float | None = None,
                    head_mass: float = 5.0) -> HeadFit:
    """Fit k and b of a Hunt-Crossley head contact to the Table 6.1 pairs.

    Parameters
    ----------
    arm : ArmParameters
        Used for the effective arm mass (unless ``arm_mass`` is given).
    exponent : float, keyword-only
        Fixed exponent n (default 1.5, Hertz).
    arm_mass : float, optional
        Effective arm mass at the tool [kg], in (0, 1000].
    head_mass : float
        Head mass [kg] (thesis: 5), in (0, 100].
    """
    from scipy.optimize import least_squares

    arm = _arm(arm)
    n = check_range("exponent", exponent, 1.0, 3.0)
    head_mass = check_range("head_mass", head_mass, 0.0, 100.0, lo_open=True, unit="kg")
    ma = default_arm_mass(arm) if arm_mass is None else check_range(
        "arm_mass", arm_mass, 0.0, 1e3, lo_open=True, unit="kg")
    pairs = table_6_1_pairs()
    H, F = pairs["HIC"].to_numpy(), pairs["F_max"].to_numpy()
    sigma = pair_sigma(H)

    def residual(p):
        k, b = math.exp(p[0]), math.exp(p[1])
        return np.log(_model_hic_at(F, k, n, b, ma, head_mass) / H) / sigma

    best = None
    for b_over_k in (0.1, 1.0, 4.0):
        k0 = 1e6 * 10 ** (2 * (n - 1))
        s = least_squares(residual, [math.log(k0), math.log(k0 * b_over_k)], x_scale=1.0)
        if best is None or s.cost < best.cost:
            best = s
    k, b = math.exp(best.x[0]), math.exp(best.x[1])
    res = residual(best.x)
    out = pairs.assign(HIC_model=_model_hic_at(F, k, n, b, ma, head_mass), sigma_log=sigma,
                       residual_sigma=res)
    return HeadFit(k, n, b, ma, head_mass, out, float(np.sqrt(np.mean(res ** 2))),
                   hybrid3_drop_peak_g(k, n, b),
                   iso_effective_spring(k, n, ISO_TS_15066_FOREHEAD_FORCE))


#: Largest RMS residual of the Table 6.1 pairs [standard deviations] for a head model to
#: count as reproducing the thesis' head (the thesis-frontal fit reaches about 0.6).
TABLE_6_1_MAX_RMS_SIGMA = 1.0
#: Relative tolerance of the ISO/TS 15066 check: the energy-equivalent spring at the
#: region's quasi-static force within 10 % of the region's effective spring constant.
ISO_SPRING_TOLERANCE = 0.10


def head_checks(head, *, arm=None) -> pd.DataFrame:
    """The checks a head contact model is judged by, computed, beside what it claims.

    * ``hybrid_iii_drop``: its contact (k, n, b) in the Hybrid III head drop (49 CFR
      572.32: 4.54 kg head, 376 mm onto a rigid plate) must peak at 225-275 g;
    * ``iso_ts_15066``: its energy-equivalent linear spring at the region's quasi-static
      force must be within 10 % of the ISO/TS 15066 Annex A effective spring constant of
      the skull/forehead (150 N/mm at 130 N) or of the face (75 N/mm at 65 N);
    * ``table_6_1``: with its own head mass and the thesis arm's effective mass at the
      step-response impact, its (F_max, HIC) curve must pass the 20 pairs of thesis
      Table 6.1 within an RMS residual of 1 standard deviation (the fit's weighting).

    Parameters
    ----------
    head : str, path-like or HeadContactModel
        A model (see :func:`ppamsafety.impact.head.resolve_head`).
    arm : ArmParameters, optional, keyword-only
        Arm of the Table 6.1 check's effective mass (default the thesis arm: Table 6.1
        was computed with it).

    Returns
    -------
    pandas.DataFrame
        One row per check: ``check``, ``value`` (what the model gives, with unit),
        ``target``, ``met`` (computed), ``claimed`` (the model's claim: True, False or
        None) and ``claim_holds`` (None without a claim).
    """
    hm = resolve_head(head)
    arm = thesis_arm() if arm is None else _arm(arm)
    k, n, b = hm.stiffness, hm.exponent, hm.damping
    rows = []
    g = hybrid3_drop_peak_g(k, n, b)
    lo, hi = HYBRID3_PEAK_RANGE_G
    rows.append({"check": "hybrid_iii_drop", "value": f"{g:.0f} g",
                 "target": f"{lo:.0f}-{hi:.0f} g (49 CFR 572.32)", "met": bool(lo <= g <= hi)})
    best = None
    for region in (SKULL_FOREHEAD, FACE):
        spring = iso_effective_spring(k, n, region.force_quasi_static)
        rel = spring / region.spring_constant - 1.0
        if best is None or abs(rel) < abs(best[2]):
            best = (region, spring, rel)
    region, spring, rel = best
    rows.append({"check": "iso_ts_15066",
                 "value": f"{spring / 1e3:.0f} N/mm at {region.force_quasi_static:g} N",
                 "target": f"{region.spring_constant / 1e3:g} N/mm ({region.name}, ISO/TS 15066 "
                           f"Annex A, +-{100 * ISO_SPRING_TOLERANCE:g} %)",
                 "met": bool(abs(rel) <= ISO_SPRING_TOLERANCE)})
    pairs = table_6_1_pairs()
    H, F = pairs["HIC"].to_numpy(), pairs["F_max"].to_numpy()
    sigma = pair_sigma(H)
    model = _model_hic_at(F, k, n, b, default_arm_mass(arm), hm.mass)
    rms = float(np.sqrt(np.mean((np.log(model / H) / sigma) ** 2)))
    rows.append({"check": "table_6_1", "value": f"RMS residual {rms:.2f} sd",
                 "target": f"<= {TABLE_6_1_MAX_RMS_SIGMA:g} sd (20 pairs of thesis Table 6.1)",
                 "met": bool(rms <= TABLE_6_1_MAX_RMS_SIGMA)})
    claims = {c[0]: c[1] for c in hm.checks}
    for r in rows:
        r["claimed"] = claims.get(r["check"])
        r["claim_holds"] = None if r["claimed"] is None else bool(r["claimed"] == r["met"])
    return pd.DataFrame(rows)
