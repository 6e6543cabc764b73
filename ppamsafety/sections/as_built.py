"""The as-built arm: the library fitted jointly to the thesis' own printed measurements
(Tables 5.2, 6.1, fig. 3.1, §5.3.5).

Part of ``ppamsafety report`` (section "as_built"); run alone with
``ppamsafety report --only as_built [--outdir DIR] [--quick] [--overwrite]``.

The thesis prints Table 5.2 (tracking means and maxima), Table 6.1 (HIC and F_max of the step
and the switch), the RMS errors of the gravity-compensation sawtooth of fig. 3.1 and
statements about the step and switch responses (§5.3.5).  The computation,
:func:`ppamsafety.thesis_fits.as_built.fit_as_built`, fits a vector of effect magnitudes
(valve time constant and dead time, Coulomb friction, muscle hysteresis, payload, encoder
offsets, velocity noise) to all of them at once, after an identifiability analysis of the
joint sensitivity matrix, and returns the as-built plant with intervals.  This section shows
the fitted plant, every thesis table beside the nominal and the as-built simulation, the gap
that remains and why, and the thesis' conclusions (a)-(g) on both plants.

The thesis' numbers are measurements of the thesis arm: for another arm the fit is not run
and the section says so.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..thesis_fits.as_built import (CANDIDATES, CONFOUNDED_COS, FIG_3_1_RMS_DEG, GTOL,
                                     PROBE, RANK_TOL, REPRODUCIBILITY, SOURCES, XTOL, Design,
                                     fit_as_built)
from ..experiments.conclusions import conclusions_table
from ..hysteresis import DELTA_25_FIBRES
from ..markdown import markdown_table
from . import Section, SectionInfo, compares_to_thesis, other_arm_note, resolve_arm
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (the converged fit: 27 plants, about 55 s of CPU shared by the cores; measured under a
#: load of 7-10 on the shared machine).
SECTION = SectionInfo(
    summary=("the as-built arm: effects and sensor faults fitted jointly to Tables 5.2 and 6.1, "
             "the fig. 3.1 RMS and the §5.3.5 statements; identifiability, the remaining gap, "
             "the conclusions re-tested"),
    thesis="Tables 5.2, 6.1, §3.5.1.6, §5.3.5", typical_seconds=60.0, scope="thesis")

#: Quick mode: three variants, short runs, two candidates, a budget of three points.
QUICK_VARIANTS = ("PID", "PSMC joint Ki=12 λ=0.4", "PSMC task λ=0.4")
QUICK_CANDIDATES = ("valve_time_constant_factor", "payload_mass")
QUICK_EVALUATIONS = 3


def quick_design() -> Design:
    """The quick-mode design: :data:`QUICK_VARIANTS`, 4 s windows, a 4-level sawtooth."""
    return Design(variants=QUICK_VARIANTS, warmup=1.0, windows=(4.0, 4.0, 4.0),
                  step_duration=9.0, switch_duration=10.0, sawtooth_levels=4)


@dataclass
class AsBuiltFindings(Result):
    """Result of :func:`compute`.

    Attributes
    ----------
    fit : AsBuiltFit or None
        The joint fit (None for another arm).
    quick : bool
    wall_time_s : float
    metrics : dict
    note : str
        The other-arm note ("" for the thesis arm).
    measurements_by_source : dict
        Number of the thesis' printed measurements per source (table or figure).
    interval_widening : float
        sqrt(s2): how much the intervals widen because the model does not fit to within the
        stated uncertainty [-].
    table_6_1_fitted : bool
        Table 6.1 values are among the fitted measurements.
    """

    fit: object
    quick: bool
    wall_time_s: float = 0.0
    metrics: dict = field(default_factory=dict)
    note: str = ""
    measurements_by_source: dict = field(default_factory=dict)
    interval_widening: float = float("nan")
    table_6_1_fitted: bool = False

    def to_pandas(self) -> pd.DataFrame:
        """The fitted effects (empty for another arm)."""
        return self.fit.to_pandas() if self.fit is not None else pd.DataFrame()

    def figures(self) -> dict:
        """Figures ``{file name: Figure}``."""
        return {} if self.fit is None else {"as_built.png": self.fit.plot()}


def compute(*, quick: bool = False, arm=None, head=None) -> AsBuiltFindings:
    """Fit the as-built arm to the thesis' printed measurements (module docstring).

    Parameters
    ----------
    quick : bool, keyword-only
        :func:`quick_design`, :data:`QUICK_CANDIDATES`, a budget of
        :data:`QUICK_EVALUATIONS` points (numbers not comparable).
    arm : ArmParameters, optional, keyword-only
        The nominal arm (default the thesis arm); for another arm nothing is fitted.
    head : HeadContactModel, optional, keyword-only
        Head of the Table 6.1 impacts (default ``thesis-frontal``); the thesis' Table 6.1 is
        for its own head, so another head is refused like another arm.

    Returns
    -------
    AsBuiltFindings
    """
    t0 = time.perf_counter()
    if not compares_to_thesis(arm, head):
        return AsBuiltFindings(fit=None, quick=quick, metrics={"fitted": False},
                            note=other_arm_note(resolve_arm(arm), head))
    arm = resolve_arm(arm)
    if quick:
        fit = fit_as_built(arm, candidates=QUICK_CANDIDATES, design=quick_design(),
                           max_evaluations=QUICK_EVALUATIONS)
    else:
        fit = fit_as_built(arm, candidates=CANDIDATES, design=Design())
    wall = time.perf_counter() - t0
    metrics = {**fit.metrics, "quick": quick, "wall_time_s": wall}
    return AsBuiltFindings(
        fit=fit, quick=quick, wall_time_s=wall, metrics=metrics,
        measurements_by_source=fit.measurements.groupby("source", sort=False).size().to_dict(),
        interval_widening=float(np.sqrt(fit.s2)),
        table_6_1_fitted=bool(fit.cells.source.str.startswith("Table 6.1").any()))


def _num(v, unit):
    if unit == "rad":
        return f"{np.degrees(v):.2f} deg"
    if unit == "s":
        return f"{1e3 * v:.1f} ms"
    return f"{v:.3g} {unit}".strip()


def _effects_display(eff: pd.DataFrame) -> pd.DataFrame:
    rows = []
    for r in eff.itertuples():
        rows.append({"candidate": r.candidate, "fitted": "yes" if r.fitted else "no",
                     "nominal": _num(r.nominal, r.unit),
                     "as-built": _num(r.value, r.unit),
                     "95 % interval": (f"{_num(r.interval_low, r.unit)} .. "
                                       f"{_num(r.interval_high, r.unit)}") if r.fitted else "",
                     "theta": f"{r.theta:.3f}",
                     "sensitivity": f"{r.column_norm:.3g}",
                     "why not fitted": r.why_not_fitted})
    return pd.DataFrame(rows)


def _table_5_2(cells: pd.DataFrame) -> pd.DataFrame:
    c = cells[cells.source.str.startswith("Table 5.2")]
    rows = []
    for (v, e), g in c.groupby(["variant", "experiment"], sort=False):
        row = {"variant": v, "P [s]": e.replace("circle", "")}
        for stat, lab in (("mean", "mean"), ("max", "max")):
            s = g[g.statistic == stat].iloc[0]
            row[f"{lab}: thesis / nominal / as-built [mm]"] = (
                f"{1e3 * s.thesis:.1f} / {1e3 * s.nominal:.1f} / {1e3 * s.as_built:.1f}")
        rows.append(row)
    return pd.DataFrame(rows)


def _table_6_1(cells: pd.DataFrame) -> pd.DataFrame:
    c = cells[cells.source.str.startswith("Table 6.1")]
    rows = []
    for (v, e), g in c.groupby(["variant", "experiment"], sort=False):
        h = g[g.statistic == "HIC36"].iloc[0]
        f = g[g.statistic == "F_max"].iloc[0]
        rows.append({"experiment": e, "variant": v,
                     "HIC: thesis / nominal / as-built": (f"{h.thesis:.2f} / {h.nominal:.3f} / "
                                                          f"{h.as_built:.3f}"),
                     "F_max [N]: thesis / nominal / as-built": (
                         f"{f.thesis:.0f} / {f.nominal:.0f} / {f.as_built:.0f}")})
    return pd.DataFrame(rows)


def _gap_text(fit) -> list:
    gap = fit.gap.set_index("source")
    L = []
    worst = gap.chi2_as_built.idxmax()
    L.append(f"* The largest remaining share of chi2 is **{worst}** "
             f"({gap.loc[worst, 'chi2_as_built']:.0f} of {gap.chi2_as_built.sum():.0f}); "
             f"there the simulation is at {gap.loc[worst, 'ratio_as_built']:.2f}x the thesis on "
             f"geometric average, with a spread of ln ratio of "
             f"{gap.loc[worst, 'ln_ratio_sd_as_built']:.2f} (the stated uncertainty of one "
             f"number is ~{REPRODUCIBILITY['tracking'] if worst.startswith('Table 5.2') else REPRODUCIBILITY['HIC' if 'HIC' in worst else 'F_max' if 'F_max' in worst else 'sawtooth_rms']:.2f}).")
    u = fit.unreachable_fraction
    L.append(f"* **{100 * u:.0f} %** of the remaining chi2 lies outside the span of *all* "
             f"{len(fit.candidates)} candidate sensitivity columns (linearised at the nominal "
             f"arm): no combination of the candidates, at any magnitude, removes it to first "
             f"order. "
             + ("The library lacks the effect (or the thesis' measurement differs from ours in "
                "definition)." if u > 0.5 else
                "Most of the gap lies in directions the candidates do reach: a larger or "
                "nonlinear magnitude, beyond the prior and the axis ranges, would be needed."))
    sp = [s for s in gap.index if gap.loc[s, "ln_ratio_sd_as_built"] > 0.5]
    if sp:
        L.append("* Scatter, not only level: in " + ", ".join(sp) + " the ln ratios of the "
                 "as-built plant spread by more than 0.5 (a factor 1.6) around their mean, so the "
                 "*pattern* across variants and periods differs, which one common factor cannot "
                 "fix. The worst numbers: " + "; ".join(
                     f"{s}: {gap.loc[s, 'worst_as_built'].split('|', 1)[1].replace('|', ', ')}"
                     for s in sp) + ".")
    return L


def _convergence_text(fit) -> str:
    """How the fit ended: the criterion that holds, or the budget, and the numbers behind it."""
    p = fit.path
    h = p.history
    m = fit.metrics
    steps = h[h.kind == "step"]
    text = (f"{int(steps.accepted.sum())} of {len(steps)} trial steps were accepted and the "
            f"Jacobian was measured {m['fit_jacobians']} times by finite differences "
            f"({m['fit_steps'] + m['fit_jacobians'] * len(fit.identifiability.selected)} "
            f"points). ")
    crit = (f"largest projected gradient x probe step {m['fit_gradient_max']:.3g} "
            f"(tolerance {GTOL:g}), largest Gauss-Newton step "
            f"{m['fit_gauss_newton_step_max']:.3g} (tolerance {XTOL:g})")
    if p.converged:
        why = {"gradient": "the gradient criterion holds",
               "step": "the step criterion holds",
               "trust region": (f"every step the freshly measured model proposed raised chi2 + "
                                f"prior, until its trust region was smaller than {XTOL:g} (a "
                                f"minimum at that resolution, not one the linear model "
                                f"predicts)")}[p.reason]
        return text + (f"**Converged** at the best point, with a Jacobian measured there: "
                       f"{why} ({crit}).")
    return text + (f"**Not converged**: the budget of {m['fit_budget']} points ran out "
                   f"({crit}, from a Broyden-updated Jacobian); the best point found, not a "
                   f"proven minimum.")


def _tug_text(pull: pd.DataFrame) -> list:
    cands = [c for c in pull.columns if c not in ("source", "strength")]
    out = []
    for c in cands:
        v = pull.set_index("source")[c]
        up = [s for s in v.index if v[s] > 0.3]
        down = [s for s in v.index if v[s] < -0.3]
        if up and down:
            out.append(f"* **{c}**: {', '.join(up)} {'want' if len(up) > 1 else 'wants'} "
                       f"it larger, {', '.join(down)} smaller.")
    return out or ["* No candidate is pulled strongly (|component| > 0.3) in opposite "
                   "directions by two sources."]


def render(study: AsBuiltFindings) -> Section:
    """Markdown of the section and its artifacts.

    Parameters
    ----------
    study : AsBuiltFindings
        Output of :func:`compute`.
    """
    title = "The as-built arm: the library fitted to the thesis' own measurements"
    if study.fit is None:
        return Section(title, study.note + "\n\nThe as-built fit uses the thesis' printed "
                       "measurements of its own arm and head; it is not run for this arm.",
                       [], dict(study.metrics))
    fit = study.fit
    d = fit.design
    idf = fit.identifiability
    m = fit.metrics
    L = []
    if study.quick:
        L += ["**Quick mode: three variants, short runs, two candidates, one step; the numbers "
              "are not comparable to the thesis.**", ""]
    n_by = study.measurements_by_source
    L.append(f"The thesis prints {len(fit.measurements)} numbers about its real arm that the "
             f"toolkit can simulate: " + ", ".join(f"{src} ({n_by[src]})" for src in SOURCES
                                                   if src in n_by)
             + ". Each is compared as ln(simulated / printed) over its standard uncertainty "
               "sqrt(rep^2 + (printed step / sqrt(12) / value)^2), with the reproducibility "
               "rep our stated assumption (the thesis gives no repeats): "
             + ", ".join(f"{k} {100 * v:g} %" for k, v in REPRODUCIBILITY.items())
             + " (reasons: `ppamsafety/thesis_fits/as_built.py`). The circles run "
               f"{d.warmup:g} s of warm-up and windows of "
               f"{', '.join(f'{w:g}' for w in d.windows)} s for P = "
               f"{', '.join(f'{p:g}' for p in d.periods)} s (whole periods of the periodic "
               "steady state, shorter than the thesis' 40 s); Table 5.2 and fig. 3.1 are "
               "computed from the *measured* angles (encoders, as the thesis measured), Table "
               "6.1 at the four heuristic instants (§6.3.3). The §5.3.5 statements carry no "
               "magnitude: they are constraints tested on each plant, not terms of chi2.")
    L.append("")
    # ------------------------------------------------------------- identifiability
    L.append("### Identifiability of the candidates")
    L.append("")
    L.append(f"Sensitivities: the nominal arm and each candidate at theta = "
             f"{fit.step:g} of its plausible range, "
             f"one batched run per experiment; J is the whitened change per unit theta "
             f"({len(fit.measurements)} numbers x {len(fit.candidates)} candidates).")
    L.append("")
    L.append(markdown_table(idf.to_pandas(), digits=3))
    L.append("")
    conf = ", ".join(f"{a} ~ {b} ({c:.2f})" for a, b, c in idf.confounded) or "none"
    wd = sorted(idf.weakest_direction.items(), key=lambda kv: -abs(kv[1]))[:3]
    L.append(f"Singular values (/ largest): {', '.join(f'{v:.3g}' for v in idf.singular_values)}"
             f"; numerical rank **{idf.rank}** of {len(idf.names)} (threshold {RANK_TOL:g}), "
             f"condition number {idf.condition:.3g}. Confounded pairs (|cos| >= "
             f"{CONFOUNDED_COS:g}): {conf}. The least determined direction is mostly "
             + ", ".join(f"{n} ({v:+.2f})" for n, v in wd)
             + f". Fitted (QR with column pivoting, pivot ratio >= {RANK_TOL:g}): "
               f"**{', '.join(idf.selected) or 'none'}**; the others stay at nominal.")
    L.append("")
    # ------------------------------------------------------------- the fit
    L.append("### The as-built plant")
    L.append("")
    L.append(f"Bounded Levenberg-Marquardt on the fitted candidates, prior theta ~ "
             f"N(0, {fit.prior_sd:g}^2) towards the nominal arm (an axis end is two sigma), inside the "
             f"axis ranges, run to convergence: with a Jacobian measured at the point by finite "
             f"differences (steps of {PROBE:g} in theta), every component of the projected "
             f"gradient of chi2 + prior times its step is at most {GTOL:g}, or the Gauss-Newton "
             f"step is at most {XTOL:g} in every theta, or every step the model proposes raises "
             f"chi2 + prior until its trust region is smaller than {XTOL:g} (below that the "
             f"statistics are rough); "
             f"{fit.path.evaluations} points evaluated after the sensitivities. 95 % intervals "
             f"from the "
             f"posterior covariance, scaled by the residual variance s2 = {fit.s2:.3g} "
             f"(chi2 / (m - k); the intervals widen by sqrt(s2) = {study.interval_widening:.2f} because "
             f"the model does not fit to within the stated uncertainty).")
    L.append("")
    L.append(markdown_table(_effects_display(fit.effects)))
    L.append("")
    eff = fit.effects.set_index("candidate")
    if "hysteresis_delta" in eff.index and eff.loc["hysteresis_delta", "fitted"]:
        h = eff.loc["hysteresis_delta"]
        inside = h.interval_low <= DELTA_25_FIBRES <= h.interval_high
        L.append(f"An independent check: the fitted muscle hysteresis δ = {h.value:.3f} "
                 f"(95 %: {h.interval_low:.3f} .. {h.interval_high:.3f}) "
                 f"{'contains' if inside else 'does not contain'} the value the thesis "
                 f"fitted to its tensile tests of the arm's 25-fibre muscles, "
                 f"{DELTA_25_FIBRES:g} (§3.6.5), which the fit was not given.")
        L.append("")
    L.append(f"chi2 over the {m['measurements']} numbers: nominal **{m['chi2_nominal']:.0f}** "
             f"({m['chi2_per_number_nominal']:.1f} per number), as-built "
             f"**{m['chi2_as_built']:.0f}** ({m['chi2_per_number_as_built']:.1f} per number).")
    L.append("")
    if len(fit.correlation) > 1:
        L.append("Correlation of the fitted thetas:")
        L.append("")
        L.append(markdown_table(fit.correlation.reset_index().rename(
            columns={"index": ""}), digits=2))
        L.append("")
    hist = fit.path.history.copy()
    hist["theta"] = [", ".join(f"{v:.3f}" for v in t) for t in hist.theta]
    L.append("Iterations (theta in the order " + ", ".join(idf.selected) + "):")
    L.append("")
    L.append(markdown_table(hist, digits=4))
    L.append("")
    L.append(_convergence_text(fit))
    L.append("")
    L.append("![as-built fit](as_built.png)")
    L.append("")
    # ------------------------------------------------------------- tables
    L.append("### Each thesis table beside the nominal and the as-built plant")
    L.append("")
    L.append("Table 5.2 (§5.3.4), mean and max of ||r_d - r|| from the measured angles:")
    L.append("")
    L.append(markdown_table(_table_5_2(fit.cells)))
    L.append("")
    if study.table_6_1_fitted:
        L.append("Table 6.1 (§6.3.3), worst of the four heuristic impact instants:")
        L.append("")
        L.append(markdown_table(_table_6_1(fit.cells)))
        L.append("")
    nom, built = fit.nominal.sawtooth_rms_deg, fit.as_built.sawtooth_rms_deg
    L.append(f"Fig. 3.1 (§3.5.1.6), RMS angle error of static gravity compensation over the "
             f"sawtooth, measured angles: thesis {FIG_3_1_RMS_DEG[0]:.2f}° / "
             f"{FIG_3_1_RMS_DEG[1]:.2f}° (q1 / q2), nominal {nom[0]:.2f}° / {nom[1]:.2f}°, "
             f"as-built {built[0]:.2f}° / {built[1]:.2f}°.")
    L.append("")
    if len(fit.statements):
        L.append("§5.3.5's step and switch statements (constraints, criteria of "
                 "`ppamsafety/experiments/conclusions.py`):")
        L.append("")
        L.append(markdown_table(fit.statements))
        L.append("")
    # ------------------------------------------------------------- gap
    L.append("### The gap that remains, and why")
    L.append("")
    L.append(markdown_table(fit.gap, digits=3))
    L.append("")
    L += _gap_text(fit)
    L.append("")
    if len(fit.pull):
        L.append("Tug of war: per source, the direction over the fitted candidates in which its "
                 "own chi2 falls fastest at the as-built point (unit vector; opposite signs on a "
                 "candidate mean two sources pull it opposite ways, and the fit settles where "
                 "they balance):")
        L.append("")
        L.append(markdown_table(fit.pull, digits=2))
        L.append("")
        L += _tug_text(fit.pull)
        L.append("")
    # ------------------------------------------------------------- conclusions
    if fit.conclusions is not None:
        L.append("### The thesis' conclusions on the nominal and the as-built plant")
        L.append("")
        cn = {c.key: c for c in fit.conclusions["nominal"]}
        cb = {c.key: c for c in fit.conclusions["as-built"]}
        ct = pd.DataFrame({"": [f"({k})" for k in cn],
                           "thesis claim": [c.claim for c in cn.values()],
                           "nominal plant": ["holds" if c.holds else "does not hold"
                                             for c in cn.values()],
                           "as-built plant": ["holds" if cb[k].holds else "does not hold"
                                              for k in cn]})
        L.append(markdown_table(ct))
        L.append("")
        changed = [f"({k})" for k in cn if cn[k].holds != cb[k].holds]
        L.append(("Verdicts that change on the as-built plant: " + ", ".join(changed) + "."
                  ) if changed else "No verdict changes on the as-built plant.")
        c = cb["c"]
        L.append(f"Conclusion (c), Ki = 12 cuts the PSMC error several-fold: "
                 f"**{'holds' if c.holds else 'does not hold'}** on the as-built plant "
                 f"({c.evidence}); on the nominal plant "
                 f"{'it holds' if cn['c'].holds else 'it does not hold'} ({cn['c'].evidence}).")
        L.append("")
        L.append("Evidence on the as-built plant:")
        L.append("")
        L.append(markdown_table(conclusions_table(fit.conclusions["as-built"])[
            ["", "verdict", "evidence"]]))
        L.append("")
    L.append(f"Compute: {study.wall_time_s:.1f} s ({m['evaluations']} plants, each simulated "
             f"in every experiment).")
    arts = list(study.figures().items()) + [
        ("as_built_effects.csv", fit.effects),
        ("as_built_identifiability.csv", idf.to_pandas()),
        ("as_built_cells.csv", fit.cells),
        ("as_built_gap.csv", fit.gap),
        ("as_built_pull.csv", fit.pull),
        ("as_built_path.csv", hist)]
    if len(fit.statements):
        arts.append(("as_built_statements.csv", fit.statements))
    if fit.conclusions is not None:
        arts.append(("as_built_conclusions.csv", ct))
    return Section(title, "\n".join(L), arts, dict(study.metrics))


__all__ = ["compute", "render", "AsBuiltFindings", "SECTION", "quick_design", "QUICK_VARIANTS",
           "QUICK_CANDIDATES", "QUICK_EVALUATIONS"]
