"""Worst head placement around the tool point, over every instant.

The thesis (§6.3.2, fig. 6.2) places the head along the TCP velocity at the
impact instant and evaluates four instants per experiment (§6.3.3).  This
section searches every head placement around the TCP (head at rest, as in the
thesis) and every instant of the 20 experiments of Table 6.1, with
:func:`ppamsafety.impact.directions.worst_direction`, and reports how much
worse the worst placement is than the thesis' choice.

Run alone:  ``ppamsafety report --only worst_direction [--outdir DIR] [--quick] [--overwrite]``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..experiments.catalog import run_thesis_experiment, thesis_variants
from ..impact.directions import two_body_predictor, worst_direction
from ..impact.thesis_data import join_table_6_1
from ..markdown import markdown_table
from ..params.head import MAXILLA_FRACTURE_N
from ..plots.impact import plot_direction_polar, plot_direction_ratios
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm, resolve_head_model)
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (measured 2026-11-23), the order a first report starts the sections in.
SECTION = SectionInfo(
    summary=("worst impact direction: every head placement around the tool at every instant, "
             "against the thesis's choice"),
    thesis="§6.3.2, §6.3.5 (new)", typical_seconds=6.9)

EXPERIMENTS = ("step", "switch")
#: Instants with a slower tool are not candidates [m/s] (as the safety study's scan).
MIN_SPEED = 1e-3
#: Variants of the quick mode (and of the polar figure in both modes).
QUICK_VARIANTS = ("PID", "PSMC joint Ki=2 λ=0.4")
#: (experiment, variant) pairs whose polar sweep at the worst instant is plotted.
POLAR_RUNS = (("step", "PID"), ("switch", "PID"), ("step", "PSMC joint Ki=2 λ=0.4"))


@dataclass
class WorstDirectionFindings(Result):
    """Result of :func:`compute`.

    Attributes
    ----------
    quick : bool
        Every 20th ms and the :data:`QUICK_VARIANTS` only.
    every : int
        Instant stride [ms].
    head : HeadContactModel
        Head model.
    table : pandas.DataFrame
        One row per (experiment, variant): the head along the TCP velocity (psi = 0, the
        thesis' placement) worst over every instant ``F_max_along_velocity`` [N],
        ``HIC36_along_velocity``; worst over
        every instant and placement ``F_max_worst`` [N], ``HIC36_worst``, their
        placement ``psi_*_deg`` (from the TCP velocity, counter-clockwise) and
        ``phi_*_deg`` (base frame) [deg], instants ``t0_*`` [s], ratios
        ``ratio_*`` (worst / along the velocity) and ``ratio_*_same_instant``
        (placement only, at the worst instant along the velocity); Table 6.1
        values ``Fmax_table_6_1`` [N], ``HIC_table_6_1`` (the thesis arm only); search
        counts.
    results : list of WorstDirection
        Per-experiment results (polar sweeps for :data:`POLAR_RUNS`).
    metrics : dict
        Headline numbers and wall times [s].
    thesis : bool
        Table 6.1 applies: the thesis arm and head.
    arm : ArmParameters or None
        The arm.
    side : str
        Where every worst placement lies relative to the TCP velocity: ``"counter-clockwise"``,
        ``"clockwise"`` or ``"either"``.
    """

    quick: bool
    every: int
    head: object
    table: pd.DataFrame
    results: list
    metrics: dict = field(default_factory=dict)
    thesis: bool = True
    arm: object = None
    side: str = "either"

    def to_pandas(self) -> pd.DataFrame:
        """The per-experiment table (a copy).

        Returns
        -------
        pandas.DataFrame
        """
        return self.table.copy()

    def figures(self) -> dict:
        """The section's figures, ``{file name: Figure}``.

        Returns
        -------
        dict
        """
        return _figures(self)


def _figures(study) -> dict:
    """Figures of the worst-direction study: polar sweeps and the worst/thesis ratios.

    Parameters
    ----------
    study : ppamsafety.sections.worst_direction.WorstDirectionFindings
        Output of :func:`ppamsafety.sections.worst_direction.compute`.

    Returns
    -------
    dict
        File name -> Figure.
    """
    sweeps = [r.sweep for r in study.results if r.sweep is not None]
    figs = {}
    if sweeps:
        figs["worst_direction_polar.png"] = plot_direction_polar(sweeps)
    figs["worst_direction_ratios.png"] = plot_direction_ratios(study.table)
    return figs


@checked_compute
def compute(*, quick: bool = False, arm=None, head=None) -> WorstDirectionFindings:
    """Worst head placement and instant for the experiments of Table 6.1.

    Parameters
    ----------
    quick : bool
        Every 20th ms and two variants (PID, joint PSMC Ki = 2, lambda = 0.4 s).
    arm : ArmParameters, optional
        The arm (default the thesis arm).
    head : HeadContactModel, optional
        Head model (default ``thesis-frontal``); Table 6.1 is joined only for the thesis
        arm and head.

    Returns
    -------
    WorstDirectionFindings
    """
    if not isinstance(quick, (bool, np.bool_)):
        raise TypeError(f"quick must be a bool, got {type(quick).__name__}")
    thesis = compares_to_thesis(arm, head)
    arm = resolve_arm(arm)
    head = resolve_head_model(head)
    every = 20 if quick else 1
    variants = thesis_variants()
    if quick:
        variants = [v for v in variants if v.label in QUICK_VARIANTS]
    t0 = time.perf_counter()
    runs = {exp: run_thesis_experiment(arm, exp, variants) for exp in EXPERIMENTS}
    t_runs = time.perf_counter() - t0
    t1 = time.perf_counter()
    pred = two_body_predictor(head)
    rows, results = [], []
    for exp in EXPERIMENTS:
        for r in runs[exp]:
            label = r.meta["label"]
            w = worst_direction(r, arm, every=every, head=head, min_speed=MIN_SPEED,
                                predictor=pred, sweep=(exp, label) in POLAR_RUNS)
            results.append(w)
            rows.append({"experiment": exp, "label": label, **w.summary,
                         **{k: v for k, v in w.counts.items()}, "rho": w.rho,
                         **r.meta["variant"].keys()})
    t_search = time.perf_counter() - t1
    df = pd.DataFrame(rows)
    if thesis:
        df = join_table_6_1(df, complete=not quick)
        df = df.rename(columns={"Fmax_thesis": "Fmax_table_6_1", "HIC_thesis": "HIC_table_6_1"})
    psmc = df[df["label"] != "PID"]
    i_f, i_h = int(df["ratio_F_max"].idxmax()), int(df["ratio_HIC36"].idxmax())
    metrics = {
        "experiments": len(df),
        "max_ratio_F_max": float(df["ratio_F_max"].max()),
        "max_ratio_F_max_at": f"{df.experiment[i_f]}: {df.label[i_f]}",
        "max_ratio_HIC36": float(df["ratio_HIC36"].max()),
        "max_ratio_HIC36_at": f"{df.experiment[i_h]}: {df.label[i_h]}",
        "median_ratio_F_max": float(df["ratio_F_max"].median()),
        "median_ratio_HIC36": float(df["ratio_HIC36"].median()),
        "min_ratio": float(min(df["ratio_F_max"].min(), df["ratio_HIC36"].min())),
        "max_F_max_worst": float(df["F_max_worst"].max()),
        "psmc_max_F_max_worst": float(psmc["F_max_worst"].max()) if len(psmc) else float("nan"),
        "psmc_below_maxilla": bool((psmc["F_max_worst"] < MAXILLA_FRACTURE_N).all()),
        "instants": int(df["instants"].sum()),
        "bound_pruned": int(df["bound_pruned"].sum()),
        "psi_F_max_range_deg": [float(df["psi_F_max_deg"].min()), float(df["psi_F_max_deg"].max())],
        "psi_HIC36_range_deg": [float(df["psi_HIC36_deg"].min()), float(df["psi_HIC36_deg"].max())],
        "engine_runs": int(df["engine_runs"].sum()),
        "rho_max": float(df["rho"].max()),
        "runs_wall_time_s": t_runs, "search_wall_time_s": t_search,
    }
    psis = np.concatenate([df["psi_F_max_deg"].to_numpy(), df["psi_HIC36_deg"].to_numpy()])
    side = ("counter-clockwise" if (psis > 0).all() else "clockwise" if (psis < 0).all()
            else "either")
    return WorstDirectionFindings(quick, every, head, df.reset_index(drop=True), results, metrics,
                                  thesis=thesis, arm=arm, side=side)


def render(study: WorstDirectionFindings) -> Section:
    """The report section (formatting only).

    Parameters
    ----------
    study : WorstDirectionFindings
        Output of :func:`compute`.

    Returns
    -------
    Section
    """
    t = study.table
    m = study.metrics
    cols = ["experiment", "label", "F_max_along_velocity", "F_max_worst", "ratio_F_max",
            "psi_F_max_deg", "t0_F_max_worst", "ratio_F_max_same_instant", "HIC36_along_velocity",
            "HIC36_worst",
            "ratio_HIC36", "psi_HIC36_deg", "ratio_HIC36_same_instant"]
    if study.thesis:
        show = t[cols + ["Fmax_table_6_1", "HIC_table_6_1"]].copy()
        show["Fmax_worst/table_6_1"] = show["F_max_worst"] / show["Fmax_table_6_1"]
        show["HIC_worst/table_6_1"] = show["HIC36_worst"] / show["HIC_table_6_1"]
    else:
        show = t[cols].copy()
    mode = "every 20th ms, two variants (quick mode)" if study.quick else "every ms"
    side = ("on either side" if study.side == "either" else f"always {study.side} of it")
    n = study.head.exponent
    aF, bF = n / (n + 1), 2 * n / (n + 1)
    aH, bH = (1 + 2.5 * n) / (n + 1), (2 + 5 * n) / (n + 1) - 1
    intro = "" if study.thesis else other_arm_note(study.arm, study.head) + "\n\n"
    t61 = (" Table 6.1 values are the thesis' own (four instants, its placement)." if study.thesis
           else "")
    md = intro + f"""The thesis places the head centre along the TCP velocity at the impact instant (§6.3.2,
fig. 6.2) "to obtain the highest possible HIC value". Here the head (`{study.head.name}`, at rest,
as in the thesis) is placed all around the tool point, psi in (-89, 89) deg from the TCP velocity
(counter-clockwise; the tool must move towards the head), and every instant ({mode}, tool faster
than {MIN_SPEED * 1e3:g} mm/s) is considered: {m["instants"]} instants, {m["engine_runs"]} engine
impacts in {m["search_wall_time_s"]:.1f} s (closed loops {m["runs_wall_time_s"]:.1f} s).

Search (`ppamsafety.impact.directions`): the two-body model with the effective mass
m_eff(u) = 1/(u^T J H^-1 J^T u) and normal speed v_tcp . u predicts F_max and HIC for every
placement (exact Hunt-Crossley scaling, tabulated once); instants are dropped when the rigorous bounds of
`impact.bounds` (valid for every placement) or the prediction plus a margin (checked: the largest
engine/prediction ratio over all simulated placements is {m["rho_max"]:.4f}) stay below the worst
simulated value; the best candidates are refined with the full flexible-joint engine and a bounded
Brent search over psi. The rigorous bounds alone exclude {m["bound_pruned"]} of the {m["instants"]}
instants (in every placement); the rest are excluded by the predictor, which is physics, not proof.

"along_velocity" columns: the head along the TCP velocity (the thesis' placement), worst over every
instant (not only the four instants of Table 6.1); "worst": worst placement and instant; "same instant":
worst placement at the worst instant along the velocity.{t61}

{markdown_table(show, digits=4)}

**How much worse:** the worst placement raises F_max by at most
{100 * (m["max_ratio_F_max"] - 1):.1f} % ({m["max_ratio_F_max_at"]}; median
{100 * (m["median_ratio_F_max"] - 1):.1f} %) and HIC36 by at most {100 * (m["max_ratio_HIC36"] - 1):.1f} %
({m["max_ratio_HIC36_at"]}; median {100 * (m["median_ratio_HIC36"] - 1):.1f} %). The worst
placement lies {m["psi_F_max_range_deg"][0]:.0f} to {m["psi_F_max_range_deg"][1]:.0f} deg (F_max) and
{m["psi_HIC36_range_deg"][0]:.0f} to {m["psi_HIC36_range_deg"][1]:.0f} deg (HIC36) from the TCP
velocity ({side}): there the effective mass m_eff(u) grows faster than the normal speed
|v| cos(psi) falls. HIC gains more than F_max because it weighs the mass more: without damping the
two-body model gives F_max ~ mu^{aF:.2f} v^{bF:.2f} but HIC ~ mu^{aH:.2f} v^{bH:.2f} (n = {n:g}). Where
"same instant" is below the ratio, the worst placement also moves the worst instant. The thesis'
choice is thus close to, but not, the worst case. Its conclusions do not change: the largest PSMC
F_max over every placement and instant is {m["psmc_max_F_max_worst"]:.0f} N
({'below' if m["psmc_below_maxilla"] else 'NOT below'} the {MAXILLA_FRACTURE_N:.0f} N maxilla tolerance).

![polar](worst_direction_polar.png)

![ratios](worst_direction_ratios.png)
"""
    arts = [("worst_direction.csv", t), *study.figures().items()]
    return Section("Worst head placement around the tool point", md, arts,
                   dict(study.metrics))


__all__ = ["compute", "render", "WorstDirectionFindings"]
