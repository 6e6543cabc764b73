"""Discrepancy diagnosis: a two-effect closed-loop case, Table 5.2 against the library, a blind
battery (case studies (b) and (c) of docs/diagnose.md).

Part of ``ppamsafety report`` (section "diagnose_cases"); run alone with
``ppamsafety report --only diagnose_cases [--outdir DIR] [--quick] [--overwrite]``.

1. *Case (c), two effects in a closed-loop record.*  A 20 s record of the
   10 s circle under joint PSMC (Ki = 2 bar/(rad s), lambda = 0.4 s) is
   synthesised (:func:`ppamsafety.diagnose.synthesize`, Table 3.2 noise fed
   back through the controller) on a plant with Coulomb friction three times
   Table 3.5 (a worn bearing) and a valve dead time of 20 ms (two 10 ms
   fieldbus frames), and diagnosed blind
   (:func:`ppamsafety.diagnose.diagnose`).  Reported: what is named, the
   fitted parameters with their 95 % intervals against the hidden values,
   and the gap per channel before and after.
2. *Case (b), Table 5.2.*  The thesis publishes only summary statistics of
   its tracking errors; every library effect is fitted to them one at a
   time and the identifiability of the effects from such data is assessed
   (:mod:`ppamsafety.thesis_fits.summary_fit`).  The report runs a reduced
   design (three variants, two periods, 10 s windows)
   to stay within the report's time budget.
3. *A small blind battery* (:data:`BATTERY`): each library effect alone,
   nothing hidden, two together, one closed-loop record each; the confusion
   matrix of hidden against named effects.  The full battery (several seeds
   and experiments) is ``tests/test_diagnose_closed_loop.py`` (slow).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..diagnose import diagnose, synthesize
from ..thesis_fits.summary_fit import (TableDesign, fit_pair, fit_summary, CONFOUNDED_COS,
                                        PRINT_STD, RANK_TOL, REPRODUCIBILITY, axis)
from ..markdown import markdown_table
from ..plots.diagnose import plot_confusion, plot_gap
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm)
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (measured 2026-11-23), the order a first report starts the sections in.
SECTION = SectionInfo(
    summary=("discrepancy diagnosis: two hidden effects in a closed-loop record, Table 5.2 against"
             " every library effect (fit and identifiability), a blind closed-loop battery"),
    thesis="§5.3.5, Table 5.2", typical_seconds=23.5)

#: Case (c): hidden effects, experiment, controller, record length [s], seed.
CASE_C = {"effects": {"friction_coulomb_factor": 3.0, "valve_dead_time": 0.02},
          "reference": "circle10", "controller": "PSMC joint Ki=2 λ=0.4", "duration": 20.0,
          "seed": 7}
#: Blind battery: case -> (hidden effects, expected named set); magnitudes as
#: ``tests/test_diagnose_battery.py`` (its docstring gives the reasons).
BATTERY = {
    "nothing": ({}, ()),
    "payload 0.4 kg": ({"payload_mass": 0.4}, ("payload",)),
    "valve offset +0.05 bar": ({"valve_offset_delta": 5000.0}, ("valve_offset_gain",)),
    "valve lag x1.5": ({"valve_time_constant_factor": 1.5}, ("valve_lag",)),
    "Coulomb x3": ({"friction_coulomb_factor": 3.0}, ("joint_friction",)),
    "n = 1.0": ({"polytropic_n": 1.0}, ("polytropic_exponent",)),
    "dead time 20 ms": ({"valve_dead_time": 0.02}, ("valve_dead_time",)),
    "payload + lag": ({"payload_mass": 0.4, "valve_time_constant_factor": 1.5},
                      ("payload", "valve_lag")),
}
#: Battery records: experiment, controller, length [s], seed.
BATTERY_RECORD = {"reference": "circle10", "controller": "PSMC joint Ki=2 λ=0.4",
                  "duration": 8.0, "seed": 21}


def _report_design():
    return TableDesign(variants=("PID", "PSMC joint Ki=12 λ=0.4", "PSMC task λ=0.4"),
                       periods=(5.0, 10.0), warmup=3.0, window=10.0)


def _quick_design():
    return TableDesign(variants=("PID",), periods=(5.0,), warmup=1.0, window=5.0)


@dataclass
class DiagnoseCasesFindings(Result):
    """Result of :func:`compute`.

    Attributes
    ----------
    case_c : Diagnosis
        The two-effect closed-loop diagnosis.
    case_c_table : pandas.DataFrame
        Fitted parameters with intervals against the hidden values.
    case_c_gap : pandas.DataFrame
        Replay RMS error per channel before / after, with the noise.
    summary : SummaryFit
        Case (b).
    pair : PairFit or None
        Case (b): the two best effects fitted together.
    battery : pandas.DataFrame
        One row per battery case: hidden, expected, named, correct, seconds.
    confusion : pandas.DataFrame
        Counts of hidden case x named set.
    timings : dict
        Wall time of each part [s].
    metrics : dict
    note : str
        The other-arm note of the section ("" for the thesis arm).
    similar_pair : tuple or None
        Case (b): the two effects whose whitened sensitivity columns are the most alike, and
        their |cos| (``(name, name, cos)``); None without case (b).
    """

    case_c: object
    case_c_table: pd.DataFrame
    case_c_gap: pd.DataFrame
    summary: object
    pair: object
    battery: pd.DataFrame
    confusion: pd.DataFrame
    timings: dict = field(default_factory=dict)
    metrics: dict = field(default_factory=dict)
    note: str = ""
    similar_pair: tuple | None = None

    def to_pandas(self) -> pd.DataFrame:
        """Case (c)'s parameter table."""
        return self.case_c_table

    def figures(self) -> dict:
        """Figures ``{file name: Figure}``."""
        figs = {"diagnose_case_c_replay.png": self.case_c.plot(),
                "diagnose_case_c_gap.png": plot_gap(
                    self.case_c.residual_rms,
                    title="case (c): replay RMS error per channel / noise")}
        if self.summary is not None:
            figs["diagnose_table_5_2_profiles.png"] = self.summary.plot()
        figs["diagnose_confusion.png"] = plot_confusion(self.confusion)
        return figs


def _hidden_values(arm, effects: dict) -> dict:
    """Hidden parameter values in the diagnosis vocabulary (for the comparison table)."""
    out = {}
    nom_c = np.array(arm.plant_base.coulomb)
    nom_b = np.array(arm.plant_base.viscous)
    if "friction_coulomb_factor" in effects or "friction_viscous_factor" in effects:
        c = nom_c * effects.get("friction_coulomb_factor", 1.0)
        b = nom_b * effects.get("friction_viscous_factor", 1.0)
        out["joint_friction"] = {"c1": c[0], "c2": c[1], "b1": b[0], "b2": b[1]}
    if "valve_dead_time" in effects:
        out["valve_dead_time"] = {"d": effects["valve_dead_time"]}
    if "payload_mass" in effects:
        out["payload"] = {"M": effects["payload_mass"]}
    if "valve_time_constant_factor" in effects:
        T = [v.time_constant * effects["valve_time_constant_factor"] for v in arm.valves.valves]
        out["valve_lag"] = {f"T_{i + 1}": T[i] for i in range(4)}
    return out


def parameter_comparison(dg, hidden: dict) -> pd.DataFrame:
    """Fitted parameters of the named effects against the hidden values.

    Parameters
    ----------
    dg : Diagnosis
        The diagnosis.
    hidden : dict
        effect -> {parameter: hidden value} (SI units).

    Returns
    -------
    pandas.DataFrame
        effect, parameter, unit, hidden, fitted, ci_low, ci_high, covered
        (the hidden value inside the 95 % interval), nominal.
    """
    rows = []
    for e in dg.effects:
        for pn, p in e.parameters.items():
            h = hidden.get(e.name, {}).get(pn, np.nan)
            rows.append({"effect": e.name, "parameter": pn, "unit": p.unit, "hidden": h,
                         "fitted": p.value, "ci_low": p.ci_low, "ci_high": p.ci_high,
                         "covered": bool(p.ci_low <= h <= p.ci_high)
                         if np.isfinite(h) else False,
                         "nominal": p.nominal})
    return pd.DataFrame(rows, columns=["effect", "parameter", "unit", "hidden", "fitted",
                                       "ci_low", "ci_high", "covered", "nominal"])


def run_battery(battery: dict, *, reference: str, controller: str, duration: float,
                seed: int, arm=None) -> pd.DataFrame:
    """Diagnose one closed-loop record per battery case, blind.

    Parameters
    ----------
    battery : dict
        case -> (hidden effects dict, expected named names).
    reference : str
        Thesis experiment of the records.
    controller : str
        Thesis controller variant label.
    duration : float
        Record length [s].
    seed : int
        Seed of every record's noise.
    arm : ArmParameters, optional
        The nominal arm (default the thesis arm).

    Returns
    -------
    pandas.DataFrame
        case, expected, named, correct, unexplained, seconds.
    """
    if not isinstance(battery, dict) or not battery:
        raise ValueError(f"battery must be a non-empty dict, got {battery!r:.80}")
    rows = []
    for case, (eff, expected) in battery.items():
        t0 = time.perf_counter()
        dg = diagnose(synthesize("closed-loop", eff, seed=seed, duration=duration,
                                 reference=reference, controller=controller, arm=arm), arm=arm)
        named = tuple(sorted(dg.names))
        rows.append({"case": case, "expected": "+".join(sorted(expected)) or "nothing",
                     "named": "+".join(named) or "nothing",
                     "correct": set(named) == set(expected), "unexplained": dg.unexplained,
                     "seconds": time.perf_counter() - t0})
    return pd.DataFrame(rows)


def confusion_matrix(battery: pd.DataFrame) -> pd.DataFrame:
    """Counts of hidden case (rows) x named set (columns).

    Parameters
    ----------
    battery : pandas.DataFrame
        Output of :func:`run_battery`.
    """
    return pd.crosstab(battery["case"], battery["named"]).reindex(
        index=list(dict.fromkeys(battery["case"])), fill_value=0)


@checked_compute
def compute(*, quick: bool = False, arm=None, head=None) -> DiagnoseCasesFindings:
    """Run case (c), case (b) and the battery (module docstring).

    Parameters
    ----------
    quick : bool, keyword-only
        Short records, a two-effect Table 5.2 fit on one cell, three battery cases.
    arm : ArmParameters, optional, keyword-only
        The nominal arm (default the thesis arm).  Case (b) fits the thesis' Table 5.2
        (the thesis arm's measurements): for another arm it is left out.
    head : HeadContactModel, optional, keyword-only
        Unused (no impact in this section); accepted like every section's.

    Returns
    -------
    DiagnoseCasesFindings
    """
    thesis = compares_to_thesis(arm)
    arm = resolve_arm(arm)
    timings = {}
    t0 = time.perf_counter()
    c = dict(CASE_C)
    dur = 6.0 if quick else c["duration"]
    rec = synthesize("closed-loop", c["effects"], seed=c["seed"], duration=dur,
                     reference=c["reference"], controller=c["controller"], arm=arm)
    dg = diagnose(rec, arm=arm)
    table = parameter_comparison(dg, _hidden_values(arm, c["effects"]))
    gap = pd.DataFrame([{"channel": ch, "unit": r["unit"], "before": r["before"],
                         "after": r["after"], "noise": r["noise"],
                         "before_over_noise": r["before"] / r["noise"],
                         "after_over_noise": r["after"] / r["noise"]}
                        for ch, r in dg.residual_rms.items() if not ch.startswith("block_")])
    t1 = time.perf_counter()
    timings["case_c"] = t1 - t0
    if not thesis:
        fit = pair = None
    elif quick:
        fit = fit_summary(arm, effects=("valve_time_constant_factor", "friction_coulomb_factor"),
                          thetas=(0.0, 1.0), design=_quick_design(), fine=21)
    else:
        fit = fit_summary(arm, design=_report_design())
    if fit is not None:
        pair = fit_pair(fit, arm, fine=21 if quick else 41) if len(fit.stats) >= 2 else None
    t2 = time.perf_counter()
    timings["case_b"] = t2 - t1
    bat = {k: BATTERY[k] for k in (("nothing", "payload 0.4 kg") if quick else BATTERY)}
    br = dict(BATTERY_RECORD)
    battery = run_battery(bat, reference=br["reference"], controller=br["controller"],
                          duration=3.0 if quick else br["duration"], seed=br["seed"],
                          arm=None if thesis else arm)
    timings["battery"] = time.perf_counter() - t2
    timings["total"] = time.perf_counter() - t0
    named = set(dg.names)
    want = {"joint_friction", "valve_dead_time"}
    metrics = {
        "case_c_named": sorted(named), "case_c_both_named": want <= named,
        "case_c_exact": named == want, "case_c_unexplained": dg.unexplained,
        "case_c_covered": int(table["covered"].sum()), "case_c_parameters": len(table),
        "case_c_q_gap_ratio": float(max(gap.set_index("channel").loc[["q1", "q2"], "after"]
                                        / gap.set_index("channel").loc[["q1", "q2"], "before"])),
        "battery_correct": int(battery["correct"].sum()), "battery_cases": len(battery),
        "battery_record_s": 3.0 if quick else br["duration"],
        **({"table_5_2": fit.metrics} if fit is not None else {}),
        "wall_times_s": {k: round(v, 2) for k, v in timings.items()},
    }
    if pair is not None:
        metrics["table_5_2_pair"] = {"effects": list(pair.names),
                                     "values": list(pair.best_value),
                                     "chi2_per_stat": pair.chi2_per_stat}
    return DiagnoseCasesFindings(case_c=dg, case_c_table=table, case_c_gap=gap, summary=fit,
                              pair=pair, battery=battery, confusion=confusion_matrix(battery),
                              timings=timings, metrics=metrics,
                              note="" if thesis else other_arm_note(arm),
                              similar_pair=None if fit is None else _most_similar(fit.cosines))


def _most_similar(cosines: pd.DataFrame) -> tuple:
    """The two effects of the largest |cos| between sensitivity columns, and that |cos|."""
    cos = cosines.to_numpy()
    iu = np.triu_indices_from(cos, 1)
    k = int(np.argmax(cos[iu]))
    return cosines.index[iu[0][k]], cosines.columns[iu[1][k]], cos[iu][k]


def _period_shape(cells: pd.DataFrame) -> dict:
    """variant -> (thesis, nominal, best) ratio of the mean error, fastest / slowest circle."""
    m = cells[cells.statistic == "mean"]
    out = {}
    for v, g in m.groupby("variant", sort=False):
        if g.period_s.nunique() < 2:
            continue
        f, sl = g.loc[g.period_s.idxmin()], g.loc[g.period_s.idxmax()]
        out[v] = (f.thesis_m / sl.thesis_m, f.nominal_m / sl.nominal_m, f.best_m / sl.best_m)
    return out


def _fmt_effects(eff: dict) -> str:
    return ", ".join(f"`{k}={v:g}`" for k, v in eff.items())


def render(study: DiagnoseCasesFindings) -> Section:
    """Markdown of the section and its artifacts.

    Parameters
    ----------
    study : DiagnoseCasesFindings
        Output of :func:`compute`.
    """
    dg, fit = study.case_c, study.summary
    figs = study.figures()
    L = [study.note, ""] if study.note else []
    L.append("The discrepancy workflow (`ppamsafety diagnose`, `docs/diagnose.md`) on "
             "closed-loop records, on the thesis's own summary statistics, and on a blind "
             "battery. Records are synthesised by `ppamsafety synthesize --experiment "
             "closed-loop` on a plant with hidden effects (the controller keeps the nominal "
             "model, the Table 3.2 measurement noise on q and qd is fed back through it) and "
             "diagnosed without being told what was hidden.")
    L.append("")
    L.append("### Case (c): two effects in a closed-loop record")
    L.append("")
    rec_len = dg.settings["samples"] * dg.settings["dt_s"]
    L.append(f"Hidden: {_fmt_effects(CASE_C['effects'])} (Coulomb friction 3x Table 3.5, "
             f"valve dead time 20 ms); {rec_len:g} s of `{CASE_C['reference']}` under "
             f"`{CASE_C['controller']}`, seed {CASE_C['seed']}. Named, in the order found: "
             f"**{', '.join(dg.names) or 'nothing'}**"
             + (f"; partial: {', '.join(e.name for e in dg.partial)}" if dg.partial else "")
             + f"; unexplained: {'yes (' + ', '.join(dg.unexplained_channels) + ')' if dg.unexplained else 'no'}.")
    L.append("")
    if len(study.case_c_table):
        L.append(markdown_table(study.case_c_table, digits=4))
        L.append("")
        L.append(f"{study.metrics['case_c_covered']} of {len(study.case_c_table)} hidden "
                 f"values lie inside their 95 % intervals. (Viscous friction was not changed: "
                 f"its hidden value is the nominal. A Coulomb coefficient fitted from noisy "
                 f"velocities is biased, see `tests/test_diagnose_battery.py`.)")
        L.append("")
    L.append("Gap per channel: RMS of the full simulation (replayed with the measured set "
             "values) minus the record, nominal model vs the model with the fitted effects, "
             "and the noise level estimated from the data:")
    L.append("")
    L.append(markdown_table(study.case_c_gap[["channel", "unit", "before", "after", "noise",
                                              "before_over_noise", "after_over_noise"]],
                            digits=4))
    L.append("")
    L.append("![case (c) measured vs before vs after](diagnose_case_c_replay.png)")
    L.append("")
    L.append("![case (c) gap per channel](diagnose_case_c_gap.png)")
    L.append("")
    # ---------------------------------------------------------------- case (b)
    if fit is not None:
        d = fit.design
        L.append("### Case (b): which library effect closes the Table 5.2 gap?")
        L.append("")
        L.append(f"Simulated Table 5.2 cells: variants {', '.join(d.variants)}; circle periods "
                 f"{', '.join(f'{p:g}' for p in d.periods)} s; {d.warmup:g} s warm-up and a "
                 f"{d.window:g} s window (the thesis: 40 s; shortened to keep the report fast); "
                 f"mean and max of ||r_d - r||: {fit.m} statistics. Each effect is put into the "
                 f"plant truth at theta = {', '.join(f'{t:g}' for t in fit.thetas)} of its "
                 f"plausible range (one batched closed-loop run), the statistics are interpolated "
                 f"in theta and chi2 = sum (ln(sim/thesis)/s)^2 is profiled, with s = "
                 f"sqrt({REPRODUCIBILITY:g}^2 + ({PRINT_STD * 1e3:.3f} mm / thesis)^2): the "
                 f"printed rounding and an assumed {100 * REPRODUCIBILITY:g} % run-to-run "
                 f"reproducibility (the thesis gives no repeats). Nominal plant: chi2/statistic = "
                 f"{fit.nominal_chi2 / fit.m:.1f}, geometric-mean ratio sim/thesis = "
                 f"{fit.metrics['nominal_ratio_geo_mean']:.2f}.")
        L.append("")
        tab = fit.table.copy()
        tab["range"] = [f"{axis(n).nominal:g} -> {axis(n).full:g}" for n in tab.effect]
        L.append(markdown_table(tab[["effect", "unit", "range", "best_value", "interval_low",
                                     "interval_high", "chi2_per_stat", "chi2_reduction",
                                     "ratio_geo_mean", "at_edge"]], digits=3))
        L.append("")
        best = fit.table.iloc[0]
        closes = best.chi2_per_stat <= 2.0
        L.append(f"Best single effect: **{best.effect}** at {best.best_value:.3g} {best.unit} "
                 f"(chi2/statistic {best.chi2_per_stat:.1f}, {100 * best.chi2_reduction:.0f} % "
                 f"below the nominal plant{', at the edge of its plausible range' if best.at_edge else ''}). "
                 + ("It closes the gap to within the stated uncertainty." if closes else
                    "**No single effect closes the gap**: the best fit still leaves the statistics "
                    f"{np.sqrt(best.chi2_per_stat):.1f} standard uncertainties off on average (RMS)."))
        L.append("")
        pr = study.pair
        if pr is not None:
            a, b = axis(pr.names[0]), axis(pr.names[1])
            L.append(f"The two best together ({pr.names[0]} and {pr.names[1]}, the interior of "
                     f"their theta grid simulated with both on, bilinear in the log statistics): "
                     f"best at {pr.names[0]} = {pr.best_value[0]:.3g} {a.unit}, "
                     f"{pr.names[1]} = {pr.best_value[1]:.3g} {b.unit}, "
                     f"chi2/statistic {pr.chi2_per_stat:.1f} (alone: "
                     f"{pr.chi2_single / fit.m:.1f}). "
                     + ("The pair closes the gap within the stated uncertainty."
                        if pr.chi2_per_stat <= 2.0 else
                        "Even the pair does not close the gap within the stated uncertainty."))
            L.append("")
        cells = fit.cells()
        cd = pd.DataFrame({
            "variant": cells.variant, "P [s]": cells.period_s, "statistic": cells.statistic,
            "thesis [mm]": 1e3 * cells.thesis_m,
            "nominal [mm] (ratio)": [f"{1e3 * a:.2f} ({r:.2f})" for a, r in
                                     zip(cells.nominal_m, cells.ratio_nominal)],
            f"{best.effect} = {best.best_value:.3g} [mm] (ratio)": [
                f"{1e3 * a:.2f} ({r:.2f})" for a, r in zip(cells.best_m, cells.ratio_best)]})
        L.append(f"Per cell (Table 5.2 value beside ours, ratio ours/thesis; "
                 f"{d.window:g} s window):")
        L.append("")
        L.append(markdown_table(cd, digits=2))
        L.append("")
        shape = _period_shape(cells)
        if shape:
            L.append("Shape, not only level: mean error on the fastest circle divided by the "
                     "mean error on the slowest one, per variant (thesis / nominal plant / best "
                     "single effect): " + "; ".join(
                         f"{v}: {t:.2f} / {n:.2f} / {b:.2f}" for v, (t, n, b) in shape.items())
                     + ". Where the thesis ratio is the smaller, part of the real error does not "
                       "grow with the speed of the circle (a static or slowly varying error), "
                       "which no single speed-dependent effect of the library reproduces.")
            L.append("")
        conf = ", ".join(f"{a} ~ {b} ({c:.2f})" for a, b, c in fit.confounded) or "none"
        pair = study.similar_pair
        L.append(f"Identifiability from these statistics: the whitened sensitivity matrix "
                 f"({fit.m} statistics x {fit.sensitivity.shape[1]} effects, per unit theta at the "
                 f"first grid step) has numerical rank **{fit.rank}** (singular values above "
                 f"{RANK_TOL:g} of the largest; all: {', '.join(f'{v:.3g}' for v in fit.singular_values)}) "
                 f"and condition number {fit.condition:.3g}. Pairs confounded (|cos| >= "
                 f"{CONFOUNDED_COS:g} between their sensitivity columns): {conf}; the most "
                 f"similar pair is {pair[0]} / {pair[1]} (|cos| = {pair[2]:.2f}). "
                 + (f"With rank {fit.rank} < {fit.sensitivity.shape[1]}, at most {fit.rank} "
                    f"combinations of effect magnitudes are determined by the table. "
                    if fit.rank < fit.sensitivity.shape[1] else "")
                 + "A summary table can rank effects by how well they reproduce it, but "
                   "several effects move every statistic the same way (all of them make the "
                   "tracking worse), so it cannot *name* a cause the way a record does "
                   "(case (c)).")
        L.append("")
        L.append("![Table 5.2 profiles](diagnose_table_5_2_profiles.png)")
        L.append("")
    # ---------------------------------------------------------------- battery
    br = BATTERY_RECORD
    L.append("### Blind battery (closed loop)")
    L.append("")
    bl = study.battery
    rlen = float(study.metrics.get("battery_record_s", br["duration"]))
    L.append(f"One {rlen:g} s record of `{br['reference']}` under "
             f"`{br['controller']}` per case (seed {br['seed']}); {study.metrics['battery_correct']} of "
             f"{study.metrics['battery_cases']} named exactly the hidden set. Magnitudes and reasons: "
             f"`tests/test_diagnose_battery.py`; the full battery (three seeds, two "
             f"experiments, two-effect cases) is the slow test "
             f"`tests/test_diagnose_closed_loop.py::test_closed_loop_battery_full`.")
    L.append("")
    L.append(markdown_table(bl[["case", "expected", "named", "correct", "unexplained",
                                "seconds"]], digits=2))
    L.append("")
    L.append("![confusion matrix](diagnose_confusion.png)")
    L.append("")
    tm = study.timings
    L.append(f"Compute: case (c) {tm['case_c']:.1f} s, case (b) {tm['case_b']:.1f} s, battery "
             f"{tm['battery']:.1f} s, total {tm['total']:.1f} s.")
    arts = list(figs.items()) + [
        ("diagnose_case_c_parameters.csv", study.case_c_table),
        ("diagnose_case_c_gap.csv", study.case_c_gap)]
    if fit is not None:
        arts += [("diagnose_table_5_2_fit.csv", fit.table),
                 ("diagnose_table_5_2_cells.csv", cells),
                 ("diagnose_table_5_2_cosines.csv", fit.cosines.reset_index().rename(
                     columns={"index": "effect"}))]
    arts += [("diagnose_battery.csv", study.battery)]
    return Section(title="Discrepancy diagnosis: closed-loop records, Table 5.2, blind battery",
                   markdown="\n".join(L), artifacts=arts, metrics=dict(study.metrics))


__all__ = ["compute", "render", "DiagnoseCasesFindings", "CASE_C", "BATTERY", "BATTERY_RECORD",
           "parameter_comparison", "run_battery", "confusion_matrix"]
