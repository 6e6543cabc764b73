"""The bench case study: friction of real 3D-printed pneumatic cylinders.

The shipped bench data (``ppamsafety.data.datasets``, Zillen 2021, CC0): three
seals -- O-ring257, X-ring257 (25.7 mm bore), Kidney_lc (kidney-shaped bore) --
each a campaign of records at 4 or 7 pressures, imported from the raw files
with one profile and diagnosed per seal as a campaign
(:func:`ppamsafety.diagnose.diagnose`).  For each seal and pressure: the
force-stroke loops and the residual before (nominal law F = p A) and after,
the named effects with their confidence, the confounded sensor/area groups,
and the friction law against pressure.  The noise the residual is judged
against is the repeatability (stroke-to-stroke scatter at the same state of
the motion), with the sensor noise beside it.

A calibration of the confidence on synthetic campaigns
(:mod:`ppamsafety.diagnose.bench.calibration`, seeds never used to tune the
thresholds) goes with it: the precision of "high".
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .._validation import check_int
from ..data.campaign import load_campaign
from ..data.datasets import ZILLEN2021_SEALS, zillen2021_manifest
from ..data.measured import MeasuredDataWarning
from ..diagnose import (CAMPAIGN_MEASURE, HIGH_PRECISION, campaign_calibration_table, diagnose,
                        largest_regions, run_campaign_calibration)
from ..markdown import markdown_table
from ..plots.bench import seal_parameters_figure
from . import Section, SectionInfo, checked_compute
from ..results import Result

SECTION = SectionInfo(
    summary=("bench case study: friction of three real 3D-printed cylinders (campaigns over "
             "pressure), loops before/after, named effects, laws vs pressure; confidence "
             "calibration"),
    thesis="(new)", typical_seconds=35.0, scope="bench")

#: Synthetic campaigns of the calibration in the report: none by default (the report's time
#: budget; the full measurement, >= 200 campaigns, is ``tests/test_bench_calibration.py``
#: under ``slow`` and its table is in ``docs/diagnose.md``); ``compute(calibration_runs=N)``
#: adds it.
CALIBRATION_RUNS, CALIBRATION_RUNS_QUICK = 0, 0
#: The seals the quick report diagnoses (the full report: every shipped seal): one campaign,
#: a third of the section's time.
QUICK_SEALS = ZILLEN2021_SEALS[:1]


@dataclass
class BenchCaseFindings(Result):
    """Result of :func:`compute`.

    Attributes
    ----------
    diagnoses : dict
        Seal -> BenchDiagnosis.
    effects : pandas.DataFrame
        One row per seal and named effect / confounded group.
    records : pandas.DataFrame
        One row per seal and record: pressure, noise levels, residual before and after.
    laws : pandas.DataFrame
        Per seal and pressure: Coulomb level and presliding step with standard errors.
    calibration : pandas.DataFrame
        Claimed level -> count, right, precision.
    calibration_runs : pandas.DataFrame
        One row per synthetic campaign.
    metrics : dict
        Headline numbers.
    largest_where : dict
        Seal -> the three significant regions of the remaining residual with the largest
        |z| (rows of the diagnosis' ``where`` table), for a seal whose residual is unexplained.
    """

    diagnoses: dict
    effects: pd.DataFrame
    records: pd.DataFrame
    laws: pd.DataFrame
    calibration: pd.DataFrame
    calibration_runs: pd.DataFrame
    metrics: dict = field(default_factory=dict)
    largest_where: dict = field(default_factory=dict)

    def to_pandas(self) -> pd.DataFrame:
        """The per-record table."""
        return self.records.copy()

    def figures(self) -> dict:
        """``{file name: Figure}``: loops and residuals per seal, laws against pressure."""
        figs = {"bench_laws.png": seal_parameters_figure(self.laws)}
        for seal, dg in self.diagnoses.items():
            figs[f"bench_loops_{seal}.png"] = dg.plot()
            figs[f"bench_residual_{seal}.png"] = dg.plot_blocks()
        return figs


def _fmt_params(params: dict) -> str:
    out = []
    for k, v in params.items():
        val, unit = v.value, v.unit
        if unit == "N/Pa":
            val, unit = val * 1e5, "N/bar"
            ci = (v.ci_low * 1e5, v.ci_high * 1e5)
        elif unit == "N/Pa^2":
            val, unit = val * 1e10, "N/bar^2"
            ci = (v.ci_low * 1e10, v.ci_high * 1e10)
        elif unit == "m" and k == "x_d":
            out.append(f"x_d = {1e3 * val:.3g} mm")
            continue
        elif unit == "N/s":
            val, unit = val * 60, "N/min"
            ci = (v.ci_low * 60, v.ci_high * 60)
        else:
            ci = (v.ci_low, v.ci_high)
        if k == "K":
            out.append(f"K = {int(val)}")
        elif ci[0] == ci[0]:
            out.append(f"{k} = {val:.3g} [{ci[0]:.3g}, {ci[1]:.3g}] {unit}")
        else:
            out.append(f"{k} = {val:.3g} {unit}")
    return "; ".join(out)


@checked_compute
def compute(*, quick: bool = False, arm=None, calibration_runs: int | None = None,
            seals=None) -> BenchCaseFindings:
    """Diagnose the shipped seals as campaigns and calibrate the confidence.

    Parameters
    ----------
    quick : bool, keyword-only
        Fewer calibration campaigns (:data:`CALIBRATION_RUNS_QUICK`) and, unless ``seals``
        is given, only the seals of :data:`QUICK_SEALS`.
    arm : None, keyword-only
        Unused (the report passes no arm; the bench is not the arm).
    calibration_runs : int, optional, keyword-only
        Synthetic campaigns of the calibration (default
        :data:`CALIBRATION_RUNS`, quick :data:`CALIBRATION_RUNS_QUICK`), 0..1000.
    seals : sequence of str, keyword-only
        Subset of the shipped seals (default every one; quick :data:`QUICK_SEALS`).

    Returns
    -------
    BenchCaseFindings
    """
    n_cal = (CALIBRATION_RUNS_QUICK if quick else CALIBRATION_RUNS) if calibration_runs is None \
        else check_int("calibration_runs", calibration_runs, 0, 1000)
    if seals is None:
        seals = QUICK_SEALS if quick else ZILLEN2021_SEALS
    bad = [s for s in seals if s not in ZILLEN2021_SEALS]
    if bad or isinstance(seals, str):
        raise ValueError(f"seals = {seals!r}: allowed {list(ZILLEN2021_SEALS)}")
    t0 = time.perf_counter()
    dgs, eff, recs, laws = {}, [], [], []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeasuredDataWarning)
        for seal in seals:
            camp = load_campaign(zillen2021_manifest(seal))
            dg = diagnose(camp)
            dgs[seal] = dg
            for e in dg.effects:
                eff.append({"seal": seal, "effect": e.name, "status": "named",
                            "confidence": e.confidence_level,
                            "stability": e.confidence,
                            "held_out_gain": e.evidence["cv_gain"],
                            "parameters": _fmt_params(e.parameters)})
            for g in dg.confounded:
                first = g.members[0]
                eff.append({"seal": seal, "effect": " / ".join(g.members),
                            "status": "confounded", "confidence": "-",
                            "stability": g.evidence["stability_frequency"],
                            "held_out_gain": g.evidence["cv_gain"],
                            "parameters": f"as {first}: "
                                          + _fmt_params(g.interpretations[first])})
            r = dg.records.copy()
            r.insert(0, "seal", seal)
            r["pressure_bar"] = r["pressure_Pa"] / 1e5
            recs.append(r)
            lw = dg.settings["laws"]
            for i, p in enumerate(r["pressure_Pa"]):
                row = {"seal": seal, "pressure_bar": p / 1e5}
                for key, col in (("friction_level", "friction"), ("presliding_step",
                                                                  "presliding")):
                    if key in lw:
                        row[f"{col}_N"] = lw[key]["value_N"][i]
                        row[f"{col}_se_N"] = lw[key]["std_error_N"][i]
                    else:
                        row[f"{col}_N"] = row[f"{col}_se_N"] = np.nan
                laws.append(row)
    t1 = time.perf_counter()
    seeds = list(CAMPAIGN_MEASURE)[:n_cal]
    names, runs = run_campaign_calibration(seeds)   # no seeds: the two tables, empty
    cal = campaign_calibration_table(names)
    records = pd.concat(recs, ignore_index=True)
    m = {"seals": len(dgs), "diagnosis_seconds": t1 - t0,
         "calibration_seconds": time.perf_counter() - t1, "calibration_campaigns": len(seeds)}
    if seeds:
        m.update({"high_count": int(cal.loc["high", "count"]),
                  "high_precision": float(cal.loc["high", "precision"]),
                  "high_precision_required": HIGH_PRECISION})
    for seal, dg in dgs.items():
        lev = {e.name: e.confidence_level for e in dg.effects}
        m[f"{seal}_friction_high"] = lev.get("coulomb") == "high" or lev.get(
            "coulomb_pressure") == "high"
        m[f"{seal}_pressure_law"] = "+".join(n for n in ("coulomb_pressure",
                                                           "coulomb_pressure2") if n in lev)
        m[f"{seal}_rho_before"] = dg.residual_rms["block_force"]["before"]
        m[f"{seal}_rho_after"] = dg.residual_rms["block_force"]["after"]
        m[f"{seal}_rms_before_N"] = dg.residual_rms["force"]["before"]
        m[f"{seal}_rms_after_N"] = dg.residual_rms["force"]["after"]
        m[f"{seal}_repeatability_N"] = dg.residual_rms["force"]["noise"]
        m[f"{seal}_sensor_noise_N"] = dg.residual_rms["force"]["sensor_noise"]
        m[f"{seal}_unexplained"] = dg.unexplained
    return BenchCaseFindings(diagnoses=dgs, effects=pd.DataFrame(eff), records=records,
                             laws=pd.DataFrame(laws), calibration=cal.reset_index(),
                             calibration_runs=runs, metrics=m,
                             largest_where={seal: largest_regions(dg.where) for seal, dg in dgs.items()
                                            if dg.unexplained})


def render(study: BenchCaseFindings) -> Section:
    """Markdown section and artifacts of the bench case study.

    Parameters
    ----------
    study : BenchCaseFindings
        Output of :func:`compute`.
    """
    m = study.metrics
    left = [s for s in ZILLEN2021_SEALS if s not in study.diagnoses]
    md = [
        *([f"Diagnosed here: {', '.join(study.diagnoses)}; left out: {', '.join(left)} (the "
           "quick report diagnoses one seal, the full report every shipped seal).", ""]
          if left else []),
        "Real bench data: friction tests of 3D-printed pneumatic cylinders (E. Zillen, "
        "H. Vallery, G. Smit, TU Delft 2021, CC0; `ppamsafety/data/datasets/zillen2021`, the "
        "raw files byte for byte).  Each seal is one campaign: about 10 triangle cycles of "
        "42 mm at each pressure, imported from the raw columns with one profile "
        "(`docs/measured_data.md`) and diagnosed together (`ppamsafety diagnose "
        "<seal>.toml`): shared friction parameters over the pressures, chosen by held-out "
        "gain over alternate cycles with a cluster-robust test, confidence from stability "
        "reruns (`docs/diagnose.md`, \"Bench campaigns of a cylinder\").",
        "",
        "**Noise.** The residual is judged against the *repeatability*: the scatter of F - p A "
        "about its own mean at the same rod position and direction within a record, what no "
        "model of the motion's state can remove.  The *sensor noise* (force and pressure "
        "sensors, per sample) is 3-7 x smaller; against it nothing would ever be explained.  "
        "`rho_left_out`: the campaign's model refitted without that record predicts it "
        "(leave-one-record-out, the test of the pressure law).",
        "",
        markdown_table(study.records[["seal", "label", "samples", "strokes", "sigma_sensor_N",
                                      "sigma_repeat_N", "rms_before_N", "rms_after_N",
                                      "rho_after", "rho_left_out"]]),
        "",
        "Named effects (confidence: high/low; stability = share of the reruns on half the "
        "cycles and without each record that select it; held-out gain in repeatability "
        "variances per sample), and the groups the campaign cannot separate (confounded: "
        "never named; the separating experiment is in `diagnosis.json`):",
        "",
        markdown_table(study.effects),
        "",
    ]
    for seal, dg in study.diagnoses.items():
        rr = dg.residual_rms
        md.append(f"* **{seal}**: residual {rr['force']['before']:.3g} N -> "
                  f"{rr['force']['after']:.3g} N RMS (repeatability {rr['force']['noise']:.3g} "
                  f"N, sensor noise {rr['force']['sensor_noise']:.3g} N; "
                  f"{rr['block_force']['after']:.2f} x the repeatability): "
                  + ("explained." if not dg.unexplained else
                     "**unexplained** structure remains; largest where: "
                     + "; ".join(f"{r.region} {r.group} (mean {r.mean:+.2f}, rms {r.rms:.2f})"
                                 for r in study.largest_where[seal].itertuples()) + "."))
    md += ["", "Friction law against pressure (Coulomb level c(p) and presliding step h(p), "
           "95 % intervals, cluster-robust by stroke):", "",
           markdown_table(study.laws), "", "![laws](bench_laws.png)", ""]
    for seal in study.diagnoses:
        md += [f"![{seal} loops](bench_loops_{seal}.png)", "",
               f"![{seal} residual](bench_residual_{seal}.png)", ""]
    cal = study.calibration
    if m["calibration_campaigns"]:
        md += [f"**Calibration of the confidence** on {m['calibration_campaigns']} synthetic "
               "campaigns (`diagnose.bench.calibration`, seeds from 1000 on; the thresholds "
               "were tuned on seeds 0-99): random friction physics, sensor faults and "
               "out-of-library structure (stroke scatter, ripple, a time-based transient after "
               "the reversals, per-record offsets).  Required: \"high\" right >= "
               f"{100 * HIGH_PRECISION:.0f} %.", "", markdown_table(cal), ""]
    else:
        md += ["The confidence levels are calibrated on synthetic campaigns "
               "(`ppamsafety.diagnose.bench.calibration`; table and command in "
               "`docs/diagnose.md`); `compute(calibration_runs=N)` adds N of them here.", ""]
    arts = list(study.figures().items()) + [
        ("bench_records.csv", study.records), ("bench_effects.csv", study.effects),
        ("bench_laws.csv", study.laws), ("bench_calibration.csv", cal),
        ("bench_calibration_runs.csv", study.calibration_runs)]
    return Section("Bench case study: friction of real 3D-printed pneumatic cylinders",
                   "\n".join(md), arts, dict(m))


__all__ = ["BenchCaseFindings", "compute", "render", "CALIBRATION_RUNS", "QUICK_SEALS"]
