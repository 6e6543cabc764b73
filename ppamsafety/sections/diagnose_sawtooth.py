"""Case study (a) of the discrepancy workflow: the static sawtooth with hidden hysteresis.

The plant of the static gravity-compensation validation (thesis §3.5.1.6,
figs. 3.1-3.2) carries the muscle-force hysteresis (3.35) at the thesis's
delta = 0.139 (§3.6.5), hidden from the diagnosis
(:func:`ppamsafety.diagnose.synthesize`, ``experiment="static-sawtooth"``:
set angles stepped in a sawtooth, static gravity compensation of the
nominal model as a feed-forward, 1 s of data after 3 s of rest, Table 3.2
noise, muscle forces recorded).  :func:`ppamsafety.diagnose.diagnose` sees
only the record.  What it has to do, as the thesis did by hand: localise
the error (the muscle forces and the torque balance are wrong, the valves
are not), name hysteresis, fit delta, and shrink the angle error.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from .._validation import check_range, check_seed
from ..diagnose import diagnose, static_record, synthesize
from ..hysteresis import DELTA_25_FIBRES
from ..markdown import markdown_table
from ..plots.diagnose import plot_sawtooth_diagnosis
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm)
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (measured 2026-11-23), the order a first report starts the sections in.
SECTION = SectionInfo(
    summary=("discrepancy diagnosis (a): the sawtooth with hysteresis hidden, localised in the "
             "muscle forces, delta fitted"),
    thesis="§3.5.1.6, figs. 3.1-3.2", typical_seconds=3.4, scope="hysteresis")

#: Hidden hysteresis scale delta of every muscle group [-] (thesis §3.6.5, 25-fibre muscles).
HIDDEN_DELTA = DELTA_25_FIBRES
#: The thesis's delta for the arm's muscles [-] (§3.6.5), and its RMS angle errors of the
#: gravity-compensation validation [deg] (§3.5.1.6, measured vs desired).
THESIS_DELTA = DELTA_25_FIBRES
THESIS_RMS_DEG = {"q1": 2.47, "q2": 2.06}
#: Record length of the quick mode [s] (the first 7 rest points: up and half way down).
QUICK_DURATION = 36.0
#: Seed of the synthetic record.
SEED = 7


@dataclass
class DiagnoseSawtoothFindings(Result):
    """Result of :func:`compute`.

    Attributes
    ----------
    quick : bool
        Short sawtooth (7 rest points instead of 21).
    hidden_delta : float
        The delta hidden in the plant [-].
    diagnosis : ppamsafety.diagnose.Diagnosis
        The diagnosis of the record.
    rest_points : pandas.DataFrame
        Per rest point: set, measured, model-before and model-after angles
        [deg], and the muscle-force residuals before/after [N].
    localisation : pandas.DataFrame
        Per subsystem channel: residual / noise RMS before and after.
    wall_time : float
        Seconds (synthesis + diagnosis).
    metrics : dict
        Headline numbers.
    thesis : bool
        Thesis values apply: the thesis arm.
    note : str
        The other-arm note ("" for the thesis arm).
    delta_source : str
        Where the hidden delta comes from, as the report says it.
    """

    quick: bool
    hidden_delta: float
    diagnosis: object
    rest_points: pd.DataFrame
    localisation: pd.DataFrame
    wall_time: float
    metrics: dict = field(default_factory=dict)
    thesis: bool = True
    note: str = ""
    delta_source: str = "§3.6.5"

    def to_pandas(self) -> pd.DataFrame:
        """The rest-point table."""
        return self.rest_points.copy()

    def figures(self) -> dict:
        """The section's figures, ``{file name: Figure}``."""
        return {"diagnose_sawtooth.png": plot_sawtooth_diagnosis(self.rest_points,
                                                                 self.metrics)}


@checked_compute
def compute(*, quick: bool = False, arm=None, delta: float = HIDDEN_DELTA,
            seed: int = SEED, head=None) -> DiagnoseSawtoothFindings:
    """Synthesize the sawtooth with hidden hysteresis and diagnose it.

    Parameters
    ----------
    quick : bool, keyword-only
        7 rest points (36 s) instead of the full 21-point sawtooth.
    arm : ppamsafety.params.ArmParameters, optional, keyword-only
        Nominal arm (default the thesis arm).
    delta : float, keyword-only
        Hidden hysteresis scale of every group [-], in (0, 1].
    seed : int, keyword-only
        Seed of the record's noise.
    head : HeadContactModel, optional, keyword-only
        Unused (no impact in this section); accepted like every section's.

    Returns
    -------
    DiagnoseSawtoothFindings

    Notes
    -----
    An arm with muscle hysteresis of its own is diagnosed against itself without it, its
    own delta hidden in the record (the largest of its groups).
    """
    thesis = compares_to_thesis(arm)
    arm = resolve_arm(arm)
    own = arm.effects.hysteresis_delta
    source = "§3.6.5" if thesis else "the value given to compute()"
    if own is not None:
        arm = arm.replace(effects=replace(arm.effects, hysteresis_delta=None))
        delta = max(own)
        source = "the arm's own, from its [effects]"
    elif not thesis and delta == HIDDEN_DELTA:
        source = ("ASSUMED: the arm declares no hysteresis, so the value fitted for the "
                  "thesis' 25-fibre muscles (§3.6.5) stands in")
    delta = check_range("delta", delta, 0.0, 1.0, lo_open=True)
    seed = check_seed("seed", seed)
    t0 = time.perf_counter()
    data = synthesize("static-sawtooth", {"hysteresis_delta": delta}, seed=seed, arm=arm,
                      duration=QUICK_DURATION if quick else None)
    dg = diagnose(data, arm=arm, seed=seed, bootstrap=20 if quick else 40)
    wall = time.perf_counter() - t0
    rec, _ = static_record(data)
    r = dg.replay
    qset = rec.means(data.frame[["q1_d", "q2_d"]].to_numpy())
    rows = {"rest point": np.arange(rec.m)}
    for j in range(2):
        rows[f"q{j + 1}_set_deg"] = np.degrees(qset[:, j])
        rows[f"q{j + 1}_measured_deg"] = np.degrees(r["measured"][:, j])
        rows[f"q{j + 1}_before_deg"] = np.degrees(r["before"][:, j])
        rows[f"q{j + 1}_after_deg"] = np.degrees(r["after"][:, j])
    f = dg.subsystems.get("forces")
    for k in range(4):
        rows[f"F{k + 1}_residual_before_N"] = f["residual_before"][:, k]
        rows[f"F{k + 1}_residual_after_N"] = f["residual_after"][:, k]
    rest = pd.DataFrame(rows)
    rr = dg.residual_rms
    loc = []
    for ch, sub in (("p1", "valves"), ("p2", "valves"), ("p3", "valves"), ("p4", "valves"),
                    ("tau1", "torque balance"), ("tau2", "torque balance")):
        b = rr[f"block_{ch}"]
        loc.append({"subsystem": sub, "channel": ch, "rho_before": b["before"],
                    "rho_after": b["after"]})
    for k in range(4):
        loc.append({"subsystem": "muscle forces", "channel": f"F{k + 1}",
                    "rho_before": float(f["rho_before"][k]), "rho_after": float(f["rho_after"][k])})
    loc = pd.DataFrame(loc)
    hyst = next((e for e in dg.effects if e.name == "hysteresis"), None)
    d = hyst.parameters["delta"] if hyst else None
    nan = float("nan")
    m = {"named": "+".join(dg.names) or "nothing", "hysteresis_named": hyst is not None,
         "delta_fit": d.value if d else nan, "delta_ci_low": d.ci_low if d else nan,
         "delta_ci_high": d.ci_high if d else nan,
         "delta_hidden": delta, "delta_thesis": THESIS_DELTA,
         "delta_forces": f["delta_forces"],
         "bootstrap_frequency": hyst.evidence.get("bootstrap_frequency") if hyst else 0.0,
         "unexplained": dg.unexplained, "rest_points": int(rec.m),
         "wall_time_s": wall}
    for j in (1, 2):
        m[f"rms_q{j}_before_deg"] = float(np.degrees(rr[f"q{j}"]["before"]))
        m[f"rms_q{j}_after_deg"] = float(np.degrees(rr[f"q{j}"]["after"]))
        m[f"rms_q{j}_vs_set_deg"] = float(np.sqrt(np.mean(
            (rest[f"q{j}_measured_deg"] - rest[f"q{j}_set_deg"]) ** 2)))
        m[f"thesis_rms_q{j}_deg"] = THESIS_RMS_DEG[f"q{j}"]
    for sub in ("valves", "torque balance", "muscle forces"):
        s = loc[loc.subsystem == sub]
        m[f"rho_before_{sub.replace(' ', '_')}"] = float(s.rho_before.max())
        m[f"rho_after_{sub.replace(' ', '_')}"] = float(s.rho_after.max())
    if not thesis:
        for k in ("delta_thesis", "thesis_rms_q1_deg", "thesis_rms_q2_deg"):
            m.pop(k)
    return DiagnoseSawtoothFindings(quick=quick, hidden_delta=delta, diagnosis=dg,
                                 rest_points=rest, localisation=loc, wall_time=wall, metrics=m,
                                 thesis=thesis, note="" if thesis else other_arm_note(arm),
                                 delta_source=source)


def render(study: DiagnoseSawtoothFindings) -> Section:
    """Markdown section and artifacts of the case study.

    Parameters
    ----------
    study : DiagnoseSawtoothFindings
        Output of :func:`compute`.
    """
    m = study.metrics
    summary = _summary_other(m) if not study.thesis else pd.DataFrame([
        {"quantity": "delta (fit, 95 % CI)", "ours": f"{m['delta_fit']:.4f} "
         f"[{m['delta_ci_low']:.4f}, {m['delta_ci_high']:.4f}]", "hidden": f"{m['delta_hidden']:.3f}",
         "thesis": f"{m['delta_thesis']:.3f}",
         "ratio ours/thesis": f"{m['delta_fit'] / m['delta_thesis']:.3f}"},
        {"quantity": "delta from the forces alone", "ours": f"{m['delta_forces']:.4f}",
         "hidden": f"{m['delta_hidden']:.3f}", "thesis": f"{m['delta_thesis']:.3f}",
         "ratio ours/thesis": f"{m['delta_forces'] / m['delta_thesis']:.3f}"},
        {"quantity": "RMS q1 measured - set [deg]", "ours": f"{m['rms_q1_vs_set_deg']:.2f}",
         "hidden": "", "thesis": f"{m['thesis_rms_q1_deg']:.2f}",
         "ratio ours/thesis": f"{m['rms_q1_vs_set_deg'] / m['thesis_rms_q1_deg']:.2f}"},
        {"quantity": "RMS q2 measured - set [deg]", "ours": f"{m['rms_q2_vs_set_deg']:.2f}",
         "hidden": "", "thesis": f"{m['thesis_rms_q2_deg']:.2f}",
         "ratio ours/thesis": f"{m['rms_q2_vs_set_deg'] / m['thesis_rms_q2_deg']:.2f}"},
    ])
    md = ([study.note, ""] if study.note else []) + [
        "The static gravity-compensation sawtooth of §3.5.1.6 (figs. 3.1-3.2), synthesized "
        f"with the muscle-force hysteresis (3.35) hidden in the plant at delta = "
        f"{m['delta_hidden']:.3f} "
        f"({study.delta_source}), "
        f"{m['rest_points']} rest points, Table 3.2 noise, "
        "muscle forces recorded; the diagnosis sees only the record "
        f"(`ppamsafety synthesize --experiment static-sawtooth --effect "
        f"hysteresis_delta={study.hidden_delta:g}{'' if study.thesis else ' --arm FILE'}`, "
        f"`ppamsafety diagnose{'' if study.thesis else ' --arm FILE'}`).",
        "",
        "Localisation (residual / noise RMS per subsystem channel, before and after the "
        "named effect; the valves are fine, the muscle forces and the torque balance are not):",
        "",
        markdown_table(study.localisation),
        "",
        f"Named: **{m['named']}** (bootstrap selection frequency "
        f"{m['bootstrap_frequency']:.2f}); unexplained: {'yes' if m['unexplained'] else 'no'}.",
        "",
        markdown_table(summary),
        "",
        f"Angle error of the model (model rest angles vs measured, RMS over the rest points): "
        f"q1 {m['rms_q1_before_deg']:.3f} -> {m['rms_q1_after_deg']:.3f} deg, "
        f"q2 {m['rms_q2_before_deg']:.3f} -> {m['rms_q2_after_deg']:.3f} deg.  The measured-"
        "vs-set error also holds the gravity model's own error (Table 3.1 against the plant), "
        "so it is not all hysteresis.",
        "",
        "![sawtooth diagnosis](diagnose_sawtooth.png)",
    ]
    arts = list(study.figures().items()) + [("diagnose_sawtooth.csv", study.rest_points),
                                         ("diagnose_sawtooth_localisation.csv",
                                          study.localisation)]
    return Section("Discrepancy workflow, case (a): hidden hysteresis in the static sawtooth "
                   "(§3.5.1.6)", "\n".join(md), arts, dict(m))


def _summary_other(m: dict) -> pd.DataFrame:
    """The fitted and hidden delta and the angle errors, without thesis values."""
    return pd.DataFrame([
        {"quantity": "delta (fit, 95 % CI)", "ours": f"{m['delta_fit']:.4f} "
         f"[{m['delta_ci_low']:.4f}, {m['delta_ci_high']:.4f}]", "hidden": f"{m['delta_hidden']:.3f}"},
        {"quantity": "delta from the forces alone", "ours": f"{m['delta_forces']:.4f}",
         "hidden": f"{m['delta_hidden']:.3f}"},
        {"quantity": "RMS q1 measured - set [deg]", "ours": f"{m['rms_q1_vs_set_deg']:.2f}",
         "hidden": ""},
        {"quantity": "RMS q2 measured - set [deg]", "ours": f"{m['rms_q2_vs_set_deg']:.2f}",
         "hidden": ""}])


__all__ = ["DiagnoseSawtoothFindings", "compute", "render", "HIDDEN_DELTA", "THESIS_DELTA",
           "THESIS_RMS_DEG"]
