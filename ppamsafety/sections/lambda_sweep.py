"""A safety-versus-tracking sweep over lambda and Ki of joint-space PSMC.

The sweep users run all day: for each (lambda, Ki) the step response is
simulated and crashed into the head at the four instants, and the circle
(P = 10 s) is tracked, so the designer sees what safety costs in accuracy.
Runs through :func:`ppamsafety.sweep.run_sweep` (progress bar, resumable,
several processes).
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass, field

import pandas as pd

from ..experiments.catalog import CIRCLE_WARMUP
from ..markdown import markdown_table
from ..plots.impact import plot_lambda_sweep
from ..sweep import run_sweep
from ..params.head import MAXILLA_FRACTURE_N
from ..sweep_cases import add_verdicts, safety_case
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm, resolve_head_model)
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (measured 2026-11-23), the order a first report starts the sections in.
SECTION = SectionInfo(
    summary="lambda x Ki safety-versus-tracking sweep",
    thesis="(new)", typical_seconds=3.4)


def lambda_case(lam: float, ki_bar: float, circle_duration: float, *, arm=None,
                head=None) -> dict:
    """Worst step impact and circle tracking error of one joint PSMC tuning (sweep case).

    Two cases of :func:`ppamsafety.sweep_cases.safety_case` (the sweep engine's case, so
    that ``ppamsafety sweep studies/lambda_ki.toml`` gives the same numbers): the step
    response crashed into the head at the four heuristic instants, and the circle
    (P = 10 s), whose tracking error is taken after the warm-up.

    Parameters
    ----------
    lam : float
        PSMC lambda [s].
    ki_bar : float
        Integral gain [bar/(rad s)].
    circle_duration : float
        Length of the circle run (P = 10 s) [s].
    arm : ArmParameters, optional, keyword-only
        The arm (default the thesis arm; bound with :func:`functools.partial`).
    head : HeadContactModel, optional, keyword-only
        The head (default ``thesis-frontal``).

    Returns
    -------
    dict
        ``F_max`` [N], ``HIC36``, ``tcp_speed`` [m/s] of the worst step
        impact, ``circle_err_mean`` and ``circle_err_max`` [m].
    """
    kw = {"controller": "PSMC joint", "lam": lam, "ki_bar": ki_bar, "arm": arm,
          "head": "thesis-frontal" if head is None else head}
    step = safety_case("step", **kw)
    circle = safety_case("circle10", duration=circle_duration, **kw)
    return {"F_max": step["F_max"], "HIC36": step["HIC36"], "tcp_speed": step["tcp_speed"],
            "circle_err_mean": circle["track_mean"], "circle_err_max": circle["track_max"]}


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
        3 x 2 cases with 10 s circles instead of 7 x 3 with 45 s.
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
    case = lambda_case if arm is None and head is None else functools.partial(
        lambda_case, arm=resolve_arm(arm), head=resolve_head_model(head))
    head_name = resolve_head_model(head).name
    lams = (0.1, 0.4, 1.5) if quick else (0.05, 0.1, 0.2, 0.4, 0.8, 1.5, 2.5)
    kis = (2.0, 12.0) if quick else (2.0, 6.0, 12.0)
    dur = 10.0 if quick else 45.0
    cases = [{"lam": lam, "ki_bar": ki, "circle_duration": dur} for ki in kis for lam in lams]
    procs = processes or min(2, os.cpu_count() or 1)
    df = run_sweep(case, cases, name="lambda-sweep", processes=procs, progress=False,
                   on_error="raise").table
    df = add_verdicts(df.rename(columns={"ki_bar": "Ki_bar"}), head=resolve_head_model(head))
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
(P = 10 s, {dur - min(CIRCLE_WARMUP, dur / 2):.0f} s evaluated). {len(df)} cases via `ppamsafety.sweep.run_sweep`
on {procs} processes.

{markdown_table(show, digits=4)}

{'' if best is None else f"Below the {MAXILLA_FRACTURE_N:.0f} N maxilla line, the best tracking is lambda = {best.lam:g} s with Ki = {best.Ki_bar:g} bar/(rad s): mean error {1e3 * best.circle_err_mean:.2f} mm, F_max {best.F_max:.0f} N."}
{'No case stays below' if best_iso is None else f"Below the ISO/TS 15066 forehead transient limit {lim_iso:g} N (2 x 130 N, not in the TS for the head), the best tracking is lambda = {best_iso.lam:g} s with Ki = {best_iso.Ki_bar:g} bar/(rad s): mean error {1e3 * best_iso.circle_err_mean:.2f} mm, F_max {best_iso.F_max:.0f} N (margin {best_iso.iso_ts_15066_margin:.0f} N)."}{f' the ISO/TS 15066 forehead transient limit {lim_iso:g} N.' if best_iso is None else ''} Every case's verdicts against the forehead criteria (margins, governing criterion, head model `{study.head_name}`) are columns of `lambda_sweep.csv`.

![lambda sweep](lambda_sweep.png)
"""
    arts = [("lambda_sweep.csv", df), *study.figures().items()]
    return Section("Safety against tracking: a lambda x Ki sweep", md, arts, dict(study.metrics))
