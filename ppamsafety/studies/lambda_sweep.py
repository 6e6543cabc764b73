"""A safety-versus-tracking sweep over lambda and Ki of joint-space PSMC.

The sweep users run all day: for each (lambda, Ki) the step response is
simulated and crashed into the head at the four instants, and the circle
(P = 10 s) is tracked, so the designer sees what safety costs in accuracy.
Runs through :func:`ppamsafety.sweep.run_sweep` (progress bar, resumable,
several processes).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..control import JointPSMC
from ..experiments.catalog import CIRCLE_WARMUP, run_thesis_experiment
from ..impact.instants import evaluate_experiment
from ..params import thesis_arm
from ..report.impact_figures import plot_lambda_sweep, save
from ..report.tables import markdown_table
from ..sweep import run_sweep
from ..units import BAR
from . import StudyResult


def lambda_case(lam: float, ki_bar: float, circle_duration: float) -> dict:
    """Worst step impact and circle tracking error of one joint PSMC tuning (sweep case)."""
    arm = thesis_arm()
    c = JointPSMC(lam=lam, ki=ki_bar * BAR)
    step = run_thesis_experiment(arm, "step", [("c", c)])[0]
    ev = evaluate_experiment(step, arm).summary
    circ = run_thesis_experiment(arm, "circle10", [("c", JointPSMC(lam=lam, ki=ki_bar * BAR))],
                                 duration=circle_duration)[0]
    k0 = int(round(min(CIRCLE_WARMUP, circle_duration / 2) / 1e-3))
    err = circ.tracking_error()[k0:]
    return {"F_max": float(ev.F_max.max()), "HIC36": float(ev.HIC36.max()),
            "tcp_speed": float(ev.tcp_speed.max()), "circle_err_mean": float(np.nanmean(err)),
            "circle_err_max": float(np.nanmax(err))}


def run(outdir, *, quick: bool = False, processes: int | None = None) -> StudyResult:
    """Sweep lambda x Ki of joint PSMC: step-impact safety against circle tracking."""
    out = Path(outdir)
    lams = (0.1, 0.4, 1.5) if quick else (0.05, 0.1, 0.2, 0.4, 0.8, 1.5, 2.5)
    kis = (2.0, 12.0) if quick else (2.0, 6.0, 12.0)
    dur = 10.0 if quick else 45.0
    cases = [{"lam": lam, "ki_bar": ki, "circle_duration": dur} for ki in kis for lam in lams]
    procs = processes or min(2, os.cpu_count() or 1)
    df = run_sweep(lambda_case, cases, name="lambda-sweep", processes=procs, progress=False,
                   on_error="raise")
    df = df.rename(columns={"ki_bar": "Ki_bar"})
    df.to_csv(out / "lambda_sweep.csv", index=False)
    arts = [str(out / "lambda_sweep.csv"),
            save(plot_lambda_sweep(df, tracking="circle_err_mean"), out / "lambda_sweep.png")]
    show = df.drop(columns=["circle_duration"])
    safe = df[df.F_max < 660.0]
    best = safe.loc[safe.circle_err_mean.idxmin()] if len(safe) else None
    md = f"""Joint-space PSMC (Table 5.1 gains otherwise) for lambda in {list(lams)} s and Ki in {list(kis)}
bar/(rad s): worst step-response impact (four instants, head `thesis-frontal`) and circle tracking
(P = 10 s, {dur - min(CIRCLE_WARMUP, dur / 2):.0f} s evaluated). {len(df)} cases via `ppamsafety.sweep.run_sweep`
on {procs} processes.

{markdown_table(show, digits=4)}

{'' if best is None else f"Below the 660 N maxilla line, the best tracking is lambda = {best.lam:g} s with Ki = {best.Ki_bar:g} bar/(rad s): mean error {1e3 * best.circle_err_mean:.2f} mm, F_max {best.F_max:.0f} N."}

![lambda sweep](lambda_sweep.png)
"""
    return StudyResult("Safety against tracking: a lambda x Ki sweep", md, arts,
                       {"cases": len(df)})
