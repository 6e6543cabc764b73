"""Trust in the diagnosis: does "high" mean what it says, on data it never saw?

Three things a user needs before trusting a name the discrepancy workflow
prints:

* **The calibration of "high"**: of all effects named with high confidence on
  the randomized scenario battery (:mod:`ppamsafety.diagnose.scenarios`:
  open loop, closed loop under every reference and controller family, the
  static sawtooth; 0-3 library effects with log-uniform magnitudes, sensor
  faults, out-of-library perturbations), how many were right -- measured on
  seeds never used to set the gates (``ARM_BATTERY.measure``, :mod:`ppamsafety.diagnose.scenarios`),
  with the battery's other targets.  The full battery (>= 1000 scenarios,
  ``python -m ppamsafety.diagnose.scenarios``, about 25 min on 2 cores) is too long
  for the report: its per-scenario rows are shipped
  (:data:`~ppamsafety.diagnose.scenarios.RESULTS_FILE`) and every number below
  is computed from them by the same code; the section also re-runs the first
  seeds live and says how many rows it reproduced exactly.
* **Arms that declare effects of their own**: the same scores on a battery whose arms
  declare effects in their ``[effects]`` (a payload, friction, valves, a polytropic
  exponent, hysteresis, a dead time, a torque bias), each record made with its arm and
  diagnosed against it, sometimes with a hidden change of a declared effect
  (``random_scenario(seed, declared=True)``), shipped in
  :data:`~ppamsafety.diagnose.scenarios.DECLARED_RESULTS_FILE` and measured on its own
  unseen seeds (:data:`~ppamsafety.diagnose.scenarios.DECLARED_MEASURE_SEEDS`).
* **The muscle test bench**: the same scores on the randomized battery of
  tensile-tester records (:mod:`ppamsafety.diagnose.bench.scenarios`: sawtooth
  and pressure-sweep protocols, the four muscle groups' force laws, force- and
  pressure-sensor faults, out-of-library perturbations), shipped in
  :data:`~ppamsafety.diagnose.scenarios.BENCH_RESULTS_FILE`; the scores table
  gives every measure over all records and per battery.
* **Detection limits of the standard records**: the smallest change of each
  library parameter that the default records of ``ppamsafety synthesize``
  (open loop and closed loop, 10 s; the full sawtooth) reveal at their
  noise, and the smallest at which it is also told apart from the effect that
  looks most like it (:mod:`ppamsafety.diagnose.arm.detection`).  "Nothing
  named" on such a record means "nothing above these".
* **Whether the limits hold**: named rate of the battery's hidden effects
  against their magnitude over their record's own limit.

For another arm than the thesis arm the shipped battery does not apply: the
section shows the live runs and the detection limits of that arm only.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import pandas as pd

from .._validation import check_int
from ..diagnose import (ARM_BATTERY, BENCH_RESULTS_FILE, DECLARED_MEASURE_SEEDS,
                        DECLARED_RESULTS_FILE, HIGH_PRECISION, HINT_P, P_DECLARED_CHANGE, POWER,
                        REPLAY_RHO, REPLAY_RHO_STATIC, by_effect, calibration_table,
                        declared_names, detection_curve, diagnose, failures, interval_widening,
                        load_results, run_battery, scores, single_effect_outcomes, synthesize)
from ..markdown import markdown_table
from ..plots.diagnose import plot_calibration, plot_detection_curve
from . import Section, SectionInfo, compares_to_thesis, other_arm_note, resolve_arm
from ..results import Result

#: This section in the report: what it shows, the thesis parts, its wall time [s] in a full
#: report on 2 cores with a cold kernel cache.
SECTION = SectionInfo(
    summary=("trust in the diagnosis: the calibration of 'high' and the battery's scores on "
             "unseen scenarios, detection limits of the standard records"),
    thesis="(new)", typical_seconds=45.0)

#: Live scenarios re-run by the report (full / quick): the first seeds of the measurement.
LIVE_RUNS, LIVE_RUNS_QUICK = 8, 1
#: ... and of the battery of arms with declared effects.
LIVE_DECLARED, LIVE_DECLARED_QUICK = 3, 1
#: The standard records whose detection limits are tabulated: experiment, options.
STANDARD_RECORDS = (("open-loop", {}, "open loop, Fourier excitation, 10 s, 1 kHz"),
                    ("closed-loop", {"reference": "circle10"},
                     "closed loop, circle 10 s, joint PSMC Ki=2 lambda=0.4, 1 kHz"),
                    ("static-sawtooth", {}, "static sawtooth of §3.5.1.6, 21 rest points"))
#: Seed of the standard records.
SEED = 3


@dataclass
class DiagnoseTrustFindings(Result):
    """Result of :func:`compute`.

    Attributes
    ----------
    scores : pandas.DataFrame
        The battery's measures against the targets (:func:`~ppamsafety.diagnose.scenarios.scores`),
        over every record kind, with the arm's and the bench's hits/count beside.
    calibration : pandas.DataFrame
        Claimed level -> precision (:func:`~ppamsafety.diagnose.scenarios.calibration_table`),
        per battery (``battery``: arm, declared -- arms with declared effects --, bench, all).
    outcomes : pandas.DataFrame
        What became of every single hidden effect, whatever its size (named right, "high",
        confounded, nothing, other), per battery.
    by_effect : pandas.DataFrame
        Per library effect: hidden, above its limit, named, "high".
    curve : pandas.DataFrame
        Named rate against magnitude / limit (:func:`~ppamsafety.diagnose.scenarios.detection_curve`).
    limits : pandas.DataFrame
        Detection limits of the standard records: ``record``, ``effect``, ``parameter``,
        ``unit``, ``limit``, ``limit_named``, ``closest``.
    live : pandas.DataFrame
        The live rows (:func:`~ppamsafety.diagnose.core.battery.run_battery`; with the thesis
        arm also those of the declared-effect battery, ``battery`` column).
    stored : bool
        The scores come from the shipped battery (the thesis arm); False: from the live
        rows only.
    metrics : dict
        Headline numbers.
    note : str
        The other-arm note ("" for the thesis arm).
    """

    scores: pd.DataFrame
    calibration: pd.DataFrame
    outcomes: pd.DataFrame
    by_effect: pd.DataFrame
    curve: pd.DataFrame
    limits: pd.DataFrame
    live: pd.DataFrame
    stored: bool
    metrics: dict = field(default_factory=dict)
    note: str = ""

    def to_pandas(self) -> pd.DataFrame:
        """The scores table."""
        return self.scores.copy()

    def figures(self) -> dict:
        """The section's figures, ``{file name: Figure}``."""
        return {"diagnose_trust_calibration.png": plot_calibration(
                    self.calibration, required=HIGH_PRECISION),
                "diagnose_trust_detection.png": plot_detection_curve(self.curve, power=POWER)}


def standard_limits(*, arm=None, quick: bool = False) -> pd.DataFrame:
    """Detection limits of the standard records (nothing hidden, Table 3.2 noise).

    Parameters
    ----------
    arm : ArmParameters, optional, keyword-only
    quick : bool, keyword-only
        A shorter sawtooth (the first 7 rest points).

    Returns
    -------
    pandas.DataFrame
    """
    rows = []
    for exp, opts, label in STANDARD_RECORDS:
        kw = dict(opts)
        if exp == "static-sawtooth" and quick:
            kw["duration"] = 36.0
        dg = diagnose(synthesize(experiment=exp, seed=SEED, arm=arm, **kw), seed=SEED, arm=arm)
        for name, ps in dg.detection_limits.items():
            for p, d in ps.items():
                rows.append({"record": label, "effect": name, "parameter": p, "unit": d["unit"],
                             "limit": d["limit"], "limit_named": d["limit_named"],
                             "closest": d["closest"] or ""})
    return pd.DataFrame(rows)


def compute(*, quick: bool = False, arm=None, head=None,
            live_runs: int | None = None) -> DiagnoseTrustFindings:
    """Scores of the battery, the calibration of "high" and the detection limits.

    Parameters
    ----------
    quick : bool, keyword-only
        Fewer live scenarios and a shorter sawtooth.
    arm : ppamsafety.params.ArmParameters, optional, keyword-only
        Nominal arm (default the thesis arm).
    head : HeadContactModel, optional, keyword-only
        Unused (no impact in this section); accepted like every section's.
    live_runs : int, optional, keyword-only
        Scenarios re-run live (default :data:`LIVE_RUNS`, quick :data:`LIVE_RUNS_QUICK`).

    Returns
    -------
    DiagnoseTrustFindings
    """
    thesis = compares_to_thesis(arm)
    arm = resolve_arm(arm)
    n = (LIVE_RUNS_QUICK if quick else LIVE_RUNS) if live_runs is None else \
        check_int("live_runs", live_runs, 0, 1000)
    t0 = time.perf_counter()
    seeds = list(ARM_BATTERY.measure)[:n]
    live = run_battery(ARM_BATTERY, seeds, processes=1, arm=arm) if seeds else pd.DataFrame()
    live_declared = pd.DataFrame()
    if thesis:
        nd = (LIVE_DECLARED_QUICK if quick else LIVE_DECLARED) if live_runs is None else \
            min(n, LIVE_DECLARED)
        dseeds = list(DECLARED_MEASURE_SEEDS)[:nd]
        if dseeds:
            live_declared = run_battery(ARM_BATTERY, dseeds, processes=1, declared=True)
    t1 = time.perf_counter()
    limits = standard_limits(arm=arm, quick=quick)
    t2 = time.perf_counter()
    m = {"live_runs": len(seeds), "live_seconds": t1 - t0, "limits_seconds": t2 - t1,
         "replay_rho": REPLAY_RHO, "replay_rho_static": REPLAY_RHO_STATIC}
    bench = declared = pd.DataFrame()
    if thesis:
        # arms with declared effects of their own: their battery, measured on its own seeds
        declared = load_results(DECLARED_RESULTS_FILE)
        m["declared_scenarios"] = int(len(declared))
        m["declared_seeds"] = f"{int(declared.seed.min())}-{int(declared.seed.max())}"
        m["declared_live_runs"] = int(len(live_declared))
        m["declared_live_reproduced"] = _reproduced(live_declared, declared)
        m.update({f"declared_{k}": v for k, v in declared_names(declared).items()})
        results = load_results()
        m["stored_scenarios"] = int(len(results))
        m["stored_seeds"] = f"{int(results.seed.min())}-{int(results.seed.max())}"
        m["live_reproduced"] = _reproduced(live, results)
        # the muscle bench battery does not depend on the arm: shown with the thesis arm's
        bench = load_results(BENCH_RESULTS_FILE)
        m["bench_scenarios"] = int(len(bench))
        m["bench_seeds"] = f"{int(bench.seed.min())}-{int(bench.seed.max())}"
    else:
        results = live
    batteries = {k: v for k, v in (("arm", results), ("declared", declared),
                                   ("bench", bench)) if k == "arm" or len(v)}
    every = pd.concat(list(batteries.values()), ignore_index=True)
    fail = failures(every)
    m.update({"records_not_made": fail["record"],
              "diagnosis_failures": fail["diagnose"] + fail["battery"]})
    sc = scores(every)
    for name, df in batteries.items():
        part = scores(df)
        sc[name] = [f"{h}/{n}" for h, n in zip(part["hits"], part["count"])]
    cal = pd.concat([calibration_table(df).assign(battery=name)
                     for name, df in {**batteries, "all": every}.items()], ignore_index=True)
    cal = cal[["battery"] + [c for c in cal.columns if c != "battery"]]
    outcomes = pd.concat([single_effect_outcomes(df).rename_axis("effect").reset_index()
                          .assign(battery=name)
                          for name, df in batteries.items()], ignore_index=True)
    outcomes = outcomes[["battery"] + [c for c in outcomes.columns if c != "battery"]]
    high = cal[(cal.claimed == "high") & (cal.battery == "all")].iloc[0]
    m.update({"high_names": int(high["names"]), "high_right": int(high["right"]),
              "high_precision": float(high["precision"]),
              "high_wilson_low": float(high["wilson_low"]),
              "targets_met": int(sc["met"].fillna(False).astype(bool).sum()),
              "targets": int(sc["target"].notna().sum())})
    w = interval_widening(every)
    m.update({"interval_parameters": w["parameters"], "intervals_widened": w["widened"],
              "interval_widening_median": w["median"], "interval_widening_p90": w["p90"]})
    if len(live_declared):
        live = pd.concat([live.assign(battery="arm"), live_declared.assign(battery="declared")],
                         ignore_index=True)
    return DiagnoseTrustFindings(scores=sc, calibration=cal, outcomes=outcomes,
                              by_effect=by_effect(every),
                              curve=detection_curve(every), limits=limits, live=live,
                              stored=thesis, metrics=m,
                              note="" if thesis else other_arm_note(arm))


def _reproduced(live: pd.DataFrame, stored: pd.DataFrame) -> str:
    """'k of n': live rows whose claims (named, high, confounded) equal the stored ones."""
    if live is None or not len(live):
        return "0 of 0"
    def err(x):
        return x if isinstance(x, str) else ""

    by_seed = {int(r.seed): r for r in stored.itertuples()}
    same = 0
    for r in live.itertuples():
        s = by_seed.get(int(r.seed))
        if s is None:
            continue
        if err(r.error) or err(s.error):    # a record the drawn plant cannot make: same error
            same += err(r.error) == err(s.error)
        elif tuple(r.named) == tuple(s.named) and tuple(r.high) == tuple(s.high) and tuple(
                map(tuple, r.confounded)) == tuple(map(tuple, s.confounded)):
            same += 1
    return f"{same} of {len(live)}"


def _met_text(scores: pd.DataFrame) -> pd.DataFrame:
    """The scores with ``met`` as yes / no, "no samples" where nothing was scored (a short
    battery) and empty where the measure has no target."""
    out = scores.copy()
    out["met"] = ["no samples" if n == 0 and pd.notna(t) else "" if m is None or pd.isna(m)
                  else "yes" if m else "no"
                  for m, n, t in zip(out["met"], out["count"], out["target"])]
    return out


def _fmt(df: pd.DataFrame) -> pd.DataFrame:
    out = df.copy()
    for c in out.columns:
        if out[c].dtype.kind == "f":
            out[c] = out[c].map(lambda v: "" if pd.isna(v) else f"{v:.3g}")
    return out


def render(study: DiagnoseTrustFindings) -> Section:
    """Markdown section and artifacts.

    Parameters
    ----------
    study : DiagnoseTrustFindings
        Output of :func:`compute`.
    """
    m = study.metrics
    src = (f"the shipped batteries: {m['stored_scenarios']} arm scenarios of seeds "
           f"{m['stored_seeds']} (open loop, closed loop under every reference and controller "
           f"family, the static sawtooth), {m.get('declared_scenarios', 0)} scenarios of arms "
           f"that declare effects of their own (battery `declared`, seeds "
           f"{m.get('declared_seeds', '-')}: each arm declares 1-4 of a payload, friction, "
           f"valve offsets and gains, valve time constants, a polytropic exponent, muscle "
           f"hysteresis, a valve dead time, a joint torque bias; its records are made with it "
           f"and diagnosed against it, and {P_DECLARED_CHANGE:.0%} of them hide a change of a "
           f"declared effect on top, so a declared effect named is a wrong name) and "
           f"{m.get('bench_scenarios', 0)} muscle test-bench "
           f"scenarios of seeds {m.get('bench_seeds', '-')}, none used to set the gates "
           f"(regenerate with `python -m ppamsafety.diagnose.scenarios [--kind "
           f"declared|bench]`); the first {m['live_runs']} arm scenarios and "
           f"{m.get('declared_live_runs', 0)} of the declared battery were re-run live here "
           f"and {m['live_reproduced']} and {m.get('declared_live_reproduced', '0 of 0')} "
           f"reproduced exactly" if study.stored else
           f"{m['live_runs']} scenarios run live for this arm (the shipped battery is the "
           f"thesis arm's)")
    lim = study.limits.copy()
    lim = _fmt(lim)
    md = ([study.note, ""] if study.note else []) + [
        "A confidence the tool prints is a promise; this section measures it.  Scores of the "
        f"randomized scenario battery ({src}; {m['records_not_made']} drawn plants could not "
        "make their record -- no rest pose within the valves' pressure range, or a closed "
        "loop that diverged -- and are not scenarios; the diagnosis raised an error on "
        f"{m['diagnosis_failures']} valid records):",
        "",
        markdown_table(_fmt(_met_text(study.scores))),
        "",
    ] + ([
        "Arms with declared effects: a declared effect is the model under test, so only a "
        "change of it is a right name.  Of the "
        f"{m['declared_changes']} hidden changes of a declared effect (no out-of-library "
        f"perturbation), {m['declared_changes_above']} were above their detection limit "
        f"and {m['declared_changes_named']} of those were named; "
        f"{m['declared_high_right']} of the {m['declared_high']} \"high\" names of an "
        "effect the arm declares were such a change; a declared effect the record did not "
        f"change was named (at any level) {m['declared_unchanged_named']} times.",
        ""] if "declared_changes" in m else []) + [
        "\"Unexplained: no\" needs the fitted model at the noise twice: every block channel's "
        "residual at most `rho_max` (1.5) times its noise, and the replay of the fitted "
        "model (the arm with its declared effects, changed by the fit) within "
        f"{m['replay_rho']:g} times the sample noise on every channel of an open- or "
        f"closed-loop record ({m['replay_rho_static']:g} for the rest angles of a sawtooth): "
        "thresholds set on the tuning seeds from the replays of models the diagnosis got "
        "right (`docs/diagnose.md`).",
        "",
        "Intervals.  A fit's own 95 % interval covers at 95 % only if the model is right.  "
        "An effect of the library too small to name, left out of the model, biases the "
        "named ones; so the reported interval is the union of the fit's own and, for every "
        "candidate the record holds a hint of (its likelihood-ratio test against the final "
        f"model at p < {HINT_P:g}, far below the naming threshold), the interval of the fit "
        "with that candidate added (`ppamsafety.diagnose.core.omitted`; the fit's own is "
        "kept in `diagnosis.json` as `ci_low_noise`/`ci_high_noise`, and `widened_by` names "
        f"the candidates).  Over the battery, {m['intervals_widened']} of "
        f"{m['interval_parameters']} intervals of right names were widened; the median "
        f"width ratio (reported / fit's own) is {m['interval_widening_median']:.2f}, the "
        f"90th percentile {m['interval_widening_p90']:.1f}: wide where a named effect and a "
        "hinted one are nearly collinear on the record (a pressure-sensor error against a "
        "valve characteristic).",
        "",
        "Calibration of the claimed confidence (a name is right when the scenario hid it; a "
        "confounded group is not a claim and is scored apart):",
        "",
        markdown_table(_fmt(study.calibration)),
        "",
        "![calibration](diagnose_trust_calibration.png)",
        "",
        "What became of every single hidden effect without an out-of-library perturbation, "
        "whatever its size (the scores above count it only above its detection limit "
        "against its look-alikes): named right, of those \"high\", reported in a "
        "confounded group with the experiment that separates it, nothing named, or "
        "something else named:",
        "",
        markdown_table(study.outcomes),
        "",
        "Per effect (above the limit: the hidden magnitude is at least the record's naming "
        "limit):",
        "",
        markdown_table(study.by_effect),
        "",
        "Detection limits of the standard records (`ppamsafety synthesize` defaults, Table "
        "3.2 noise, nothing hidden): the smallest change of one parameter (from its nominal "
        f"value) named with {POWER:.0%} probability against the nominal model ("
        "`limit`), and the smallest at which it is also told apart from the library effect "
        "that looks most like it on that record (`limit_named`, `closest`).  Every "
        "diagnosis reports its own record's limits in `diagnosis.json` "
        "(`detection_limits`).",
        "",
        markdown_table(lim),
        "",
        "Do the limits hold?  Named rate of the hidden effects against their magnitude over "
        "their record's naming limit (scenarios without an out-of-library perturbation):",
        "",
        markdown_table(_fmt(study.curve)),
        "",
        "![detection](diagnose_trust_detection.png)",
    ]
    arts = list(study.figures().items()) + [
        ("diagnose_trust_scores.csv", study.scores),
        ("diagnose_trust_calibration.csv", study.calibration),
        ("diagnose_trust_outcomes.csv", study.outcomes),
        ("diagnose_trust_by_effect.csv", study.by_effect),
        ("diagnose_trust_detection.csv", study.curve),
        ("diagnose_trust_limits.csv", study.limits)]
    return Section("Trust in the diagnosis: calibrated confidence, detection limits",
                   "\n".join(md), arts, dict(m))


__all__ = ["DiagnoseTrustFindings", "compute", "render", "standard_limits", "LIVE_RUNS",
           "STANDARD_RECORDS"]
