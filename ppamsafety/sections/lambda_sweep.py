"""A safety-versus-tracking sweep over lambda and Ki of joint-space PSMC.

The sweep users run all day: for each (lambda, Ki) the step response is
simulated and crashed into the head at the four instants, and the circle
(P = 10 s) is tracked, so the designer sees what safety costs in accuracy.
The cases are those of the shipped study ``lambda_ki``
(``ppamsafety/study_data/lambda_ki.toml``, the one ``ppamsafety sweep lambda_ki`` runs),
run by :func:`ppamsafety.sweep.run_sweep` on the sweep engine's case
(:func:`ppamsafety.sweep_cases.case_function`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import pandas as pd

from ..experiments.catalog import CIRCLE_WARMUP, DEFAULT_DURATIONS
from ..markdown import markdown_table
from ..plots.impact import plot_lambda_sweep
from ..study_files import load_study, shipped_study
from ..sweep import run_sweep
from ..params.head import MAXILLA_FRACTURE_N
from ..sweep_cases import add_verdicts, case_function
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm, resolve_head_model)
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (measured 2026-11-23), the order a first report starts the sections in.
SECTION = SectionInfo(
    summary="lambda x Ki safety-versus-tracking sweep",
    thesis="(new)", typical_seconds=3.4)

#: The shipped study whose cases this section runs.
STUDY = "lambda_ki"
#: The smoke test (``quick``): these lambdas [s] and Ki [bar/(rad s)] of the study, with
#: circles of :data:`QUICK_CIRCLE_S`.
QUICK_LAMBDAS = (0.1, 0.4, 1.5)
QUICK_KIS = (2.0, 12.0)
#: Length of the circles of the smoke test [s].
QUICK_CIRCLE_S = 10.0


def study_cases(*, quick: bool = False) -> list:
    """The cases this section runs: those of the shipped study :data:`STUDY`.

    Parameters
    ----------
    quick : bool, keyword-only
        Only :data:`QUICK_LAMBDAS` x :data:`QUICK_KIS`, circles of :data:`QUICK_CIRCLE_S`.

    Returns
    -------
    list of dict
        :func:`~ppamsafety.sweep_cases.safety_case` keyword arguments, in the study's order.
    """
    cases = list(load_study(shipped_study(STUDY)).cases)
    if not quick:
        return cases
    return [c if c["experiment"] == "step" else {**c, "duration": QUICK_CIRCLE_S}
            for c in cases if c["lam"] in QUICK_LAMBDAS and c["ki_bar"] in QUICK_KIS]


def _duration(case: dict) -> float:
    """A case's experiment length [s] (the catalogue's default when the case sets none)."""
    d = case.get("duration")
    return float(DEFAULT_DURATIONS[case["experiment"]] if d is None else d)


def _pivot(cases: list, table: pd.DataFrame) -> pd.DataFrame:
    """One row per (Ki, lambda): the worst step impact beside the circle's tracking error."""
    rows = {}
    for c, r in zip(cases, table.to_dict("records")):
        key = (float(c["ki_bar"]), float(c["lam"]))
        row = rows.setdefault(key, {"lam": key[1], "Ki_bar": key[0]})
        if c["experiment"] == "step":
            row.update(F_max=r["F_max"], HIC36=r["HIC36"], tcp_speed=r["tcp_speed"])
        else:
            row.update(circle_duration=_duration(c), circle_err_mean=r["track_mean"],
                       circle_err_max=r["track_max"])
    return pd.DataFrame(list(rows.values()),
                        columns=["lam", "Ki_bar", "circle_duration", "F_max", "HIC36",
                                 "tcp_speed", "circle_err_mean", "circle_err_max"])


@dataclass
class LambdaSweepFindings(Result):
    """Result of :func:`compute`: step-impact safety and circle tracking per (lambda, Ki).

    Attributes
    ----------
    lambdas : tuple of float
        PSMC lambda values [s].
    kis : tuple of float
        Integral gains [bar/(rad s)].
    circle_duration : float
        Length of each circle run [s].
    processes : int
        Worker processes of the sweep.
    table : pandas.DataFrame
        One row per case: ``lam``, ``Ki_bar``, ``circle_duration``, ``F_max``
        [N], ``HIC36``, ``tcp_speed`` [m/s], ``circle_err_mean``,
        ``circle_err_max`` [m], and the verdicts against the forehead criteria
        (:func:`ppamsafety.sweep_cases.add_verdicts`).
    metrics : dict
        Headline numbers.
    best_below_maxilla : pandas.Series or None
        The row of the best mean circle tracking among the cases whose F_max stays below the
        maxilla fracture force (:data:`~ppamsafety.params.head.MAXILLA_FRACTURE_N`); None if
        no case does.
    best_passing_iso : pandas.Series or None
        The row of the best mean circle tracking among the cases that pass the ISO/TS 15066
        transient limit of the head model's region; None if no case does.
    iso_limit : float
        That limit [N].
    head_name : str
        Name of the head model of the impacts.
    note : str
        The other-arm note ("" for the thesis arm and head).
    """

    lambdas: tuple
    kis: tuple
    circle_duration: float
    processes: int
    table: pd.DataFrame
    metrics: dict = field(default_factory=dict)
    best_below_maxilla: pd.Series | None = None
    best_passing_iso: pd.Series | None = None
    iso_limit: float = float("nan")
    head_name: str = "thesis-frontal"
    note: str = ""

    def to_pandas(self) -> pd.DataFrame:
        """The sweep table."""
        return self.table.copy()

    def figures(self) -> dict:
        """The section's figures, ``{file name: Figure}``."""
        return {"lambda_sweep.png": plot_lambda_sweep(self.table, tracking="circle_err_mean")}


@checked_compute
def compute(*, quick: bool = False, arm=None, processes: int | None = None,
            head=None) -> LambdaSweepFindings:
    """Sweep lambda x Ki of joint PSMC: step-impact safety against circle tracking.

    Parameters
    ----------
    quick : bool
        3 x 2 of the study's (lambda, Ki) with 10 s circles instead of all 7 x 3 with the
        study's 45 s (:func:`study_cases`).
    arm : ppamsafety.params.ArmParameters, optional
        Arm (default: the thesis arm); the workers receive it with the case function.
    processes : int, optional
        Worker processes (default: min(2, CPU count)).
    head : HeadContactModel, optional
        Head model (default ``thesis-frontal``).

    Returns
    -------
    LambdaSweepFindings
        The sweep table and metrics.
    """
    note = "" if compares_to_thesis(arm, head) else other_arm_note(arm, head)
    case = case_function(None if arm is None else resolve_arm(arm),
                         None if head is None else resolve_head_model(head))
    head_name = resolve_head_model(head).name
    cases = study_cases(quick=quick)
    lams = tuple(dict.fromkeys(float(c["lam"]) for c in cases))
    kis = tuple(dict.fromkeys(float(c["ki_bar"]) for c in cases))
    dur = max(_duration(c) for c in cases if c["experiment"] != "step")
    procs = processes or min(2, os.cpu_count() or 1)
    df = _pivot(cases, run_sweep(case, cases, name="lambda-sweep", processes=procs,
                                 progress=False, on_error="raise").table)
    df = add_verdicts(df, head=resolve_head_model(head))
    return LambdaSweepFindings(lambdas=lams, kis=kis, circle_duration=dur, processes=procs,
                               table=df, metrics={"cases": len(df)},
                               best_below_maxilla=_best_tracking(df[df.F_max <
                                                                    MAXILLA_FRACTURE_N]),
                               best_passing_iso=_best_tracking(
                                   df[df["iso_ts_15066_pass"].astype(bool)]),
                               iso_limit=float((df["F_max"] + df["iso_ts_15066_margin"]).iloc[0]),
                               head_name=head_name, note=note)


def _best_tracking(cases: pd.DataFrame):
    """The case of the smallest mean circle tracking error, or None without cases."""
    return cases.loc[cases.circle_err_mean.idxmin()] if len(cases) else None


def render(study: LambdaSweepFindings) -> Section:
    """The report section of the lambda sweep (formatting only).

    Parameters
    ----------
    study : LambdaSweepFindings
        Output of :func:`compute`.

    Returns
    -------
    Section
        Markdown and artifacts (figure, ``lambda_sweep.csv``).
    """
    df, lams, kis, dur, procs = (study.table, study.lambdas, study.kis, study.circle_duration,
                                 study.processes)
    show = df[[c for c in df.columns if c not in ("circle_duration", "head_model")
               and not c.endswith(("_margin", "_pass"))] + ["iso_ts_15066_margin"]]
    best, best_iso, lim_iso = study.best_below_maxilla, study.best_passing_iso, study.iso_limit
    md = (study.note + "\n\n" if study.note else "") + f"""Joint-space PSMC (Table 5.1 gains otherwise) for lambda in {list(lams)} s and Ki in {list(kis)}
bar/(rad s): worst step-response impact (four instants, head `{study.head_name}`) and circle tracking
(P = 10 s, {dur - min(CIRCLE_WARMUP, dur / 2):.0f} s evaluated). {len(df)} cases: those of the shipped study `{STUDY}`
(`ppamsafety sweep {STUDY}` runs the same), via `ppamsafety.sweep.run_sweep` on {procs} processes.

{markdown_table(show, digits=4)}

{'' if best is None else f"Below the {MAXILLA_FRACTURE_N:.0f} N maxilla line, the best tracking is lambda = {best.lam:g} s with Ki = {best.Ki_bar:g} bar/(rad s): mean error {1e3 * best.circle_err_mean:.2f} mm, F_max {best.F_max:.0f} N."}
{'No case stays below' if best_iso is None else f"Below the ISO/TS 15066 forehead transient limit {lim_iso:g} N (2 x 130 N, not in the TS for the head), the best tracking is lambda = {best_iso.lam:g} s with Ki = {best_iso.Ki_bar:g} bar/(rad s): mean error {1e3 * best_iso.circle_err_mean:.2f} mm, F_max {best_iso.F_max:.0f} N (margin {best_iso.iso_ts_15066_margin:.0f} N)."}{f' the ISO/TS 15066 forehead transient limit {lim_iso:g} N.' if best_iso is None else ''} Every case's verdicts against the forehead criteria (margins, governing criterion, head model `{study.head_name}`) are columns of `lambda_sweep.csv`.

![lambda sweep](lambda_sweep.png)
"""
    arts = [("lambda_sweep.csv", df), *study.figures().items()]
    return Section("Safety against tracking: a lambda x Ki sweep", md, arts, dict(study.metrics))
