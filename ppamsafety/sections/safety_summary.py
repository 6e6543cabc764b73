"""The report's first screen: the safety verdict of the arm per controller family and experiment."""

from __future__ import annotations

from dataclasses import dataclass, fields

import pandas as pd

from ..impact.summary import SafetySummary, safety_summary
from ..markdown import markdown_table
from . import Section, SectionInfo, checked_compute, resolve_arm

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores.
SECTION = SectionInfo(
    summary="safety summary: per controller family and experiment, the governing body region, "
            "contact point and criterion, the margin, and what it depends on",
    thesis="(new)", typical_seconds=25.0)

#: Instant stride of the scan in quick mode (every 20th control period).
QUICK_EVERY = 20


@dataclass
class SafetySummaryFindings(SafetySummary):
    """What the section shows: the :class:`~ppamsafety.impact.summary.SafetySummary` of the
    report's arm (the same fields).

    Attributes
    ----------
    table : pandas.DataFrame
        One row per (experiment, controller family): the governing verdict and what it
        depends on.
    cases : pandas.DataFrame
        One row per (experiment, variant).
    verdicts : pandas.DataFrame
        Every criterion at every case's worst impact.
    head : str
        The report's head model.
    covering : Covering
        The covering of the what-if.
    arm_name : str
        The arm.
    every : int
        Instant stride of the scan (1: every control period).
    metrics : dict
        Headline numbers.
    worst_scan : WorstContact or None
        The scan of the run with the smallest margin.
    arm : ArmParameters or None
        The arm (its figure).
    """


@checked_compute
def compute(*, quick: bool = False, arm=None, head=None) -> SafetySummaryFindings:
    """The governing verdicts (:func:`ppamsafety.impact.summary.safety_summary`).

    Parameters
    ----------
    quick : bool
        Every 20th instant instead of every one.
    arm : ArmParameters, optional
        The arm (default the thesis arm).
    head : HeadContactModel, optional
        The report's head model (default ``thesis-frontal``): the head regions' answer is
        also given with it.

    Returns
    -------
    SafetySummaryFindings
    """
    s = safety_summary(resolve_arm(arm), head=head, every=QUICK_EVERY if quick else 1)
    return SafetySummaryFindings(**{f.name: getattr(s, f.name) for f in fields(s)})


def _unit(u):
    return f" {u}" if u else ""


def _screen(s: SafetySummary):
    """The one-screen table: one row per experiment and family."""
    t = s.table
    rows = []
    for r in t.to_dict("records"):
        u = _unit(r["unit"])
        rows.append({
            "experiment": r["experiment"], "controller family": r["family"],
            "worst variant": r["variant"], "body region": r["body_region"],
            "contact point": r["contact_point"], "governing criterion": r["criterion"],
            "worst case": f"{r['value']:.4g}{u} vs {r['limit']:.4g}{u}",
            "margin to the limit": f"{r['margin [%]']:+.0f} %",
            "variants passing": f"{r['variants_passing']} of {r['variants']}",
            "best variant (margin)": f"{r['best_variant']} ({r['best_margin [%]']:+.0f} %)",
            "head model": ("verdict changes" if r["depends_on_head"] else "same verdict")
            if r["head_alternatives"] else "not a head region",
            "covering": "verdict changes" if r["depends_on_covering"] else "same verdict"})
    return pd.DataFrame(rows)


def render(s: SafetySummaryFindings) -> Section:
    """The report's first section (formatting only).

    Parameters
    ----------
    s : SafetySummaryFindings
        Output of :func:`compute`.

    Returns
    -------
    Section
    """
    o = s.overall
    u = _unit(o["unit"])
    npass, ncases = s.metrics["cases_passing"], s.metrics["cases"]
    scan = "every instant" if s.every == 1 else f"every {s.every}th instant (quick mode)"
    dep_head = s.table[s.table["depends_on_head"]]
    dep_cov = s.table[s.table["depends_on_covering"]]
    heads = s.table[s.table["head_alternatives"] != ""]
    head_text = ("; ".join(f"{r.experiment} {r.family}: {r.head_alternatives} "
                           f"against {r.limit:.4g}{_unit(r.unit)}" for r in dep_head.itertuples())
                 if len(dep_head) else "no row's verdict changes")
    cov_text = ("; ".join(f"{r.experiment} {r.family}: {r.covered_value:.4g}{_unit(r.unit)} "
                          f"against {r.limit:.4g}{_unit(r.unit)}" for r in dep_cov.itertuples())
                if len(dep_cov) else "no row's verdict changes")
    md = f"""**Verdict for the arm `{s.arm_name or 'unnamed arm'}`: {npass} of {ncases} runs (controller variant x
experiment) pass every criterion.** The worst case is the {o['experiment']}
experiment with {o['variant']}: its {o['contact_point']} hits the {o['body_region']}
({o['body_model']}) with {o['value']:.4g}{u} against the {o['criterion']} limit of {o['limit']:.4g}{u}
(margin {o['margin [%]']:+.0f} %).

{markdown_table(_screen(s), digits=3)}

How it is found: for every controller variant, the worst impact over the arm's four contact
points (bare), the 12 body regions of ISO/TS 15066 Annex A (the skull and forehead as the head
that passes the Hybrid III drop, the others as their Annex A two-body models) and {scan} of
the record, ranked by the force over each region's smallest force limit, then judged on every
criterion of its region; a family's row is its worst variant, the governing criterion the one
with the smallest margin ({s.metrics['candidates']} candidates, {s.metrics['simulated']} simulated
exactly). Every verdict is in `safety_summary_verdicts.csv`, every variant in
`safety_summary_cases.csv`.

![the worst run: each contact point's worst region](safety_summary_worst.png)

*Where the answer depends on the model.* The governing impact of each row simulated again with
the other models of a head region's body (the Annex A spring, the head model `{s.head}`):
{head_text}{'' if len(heads) else ' (no row is governed by a head region)'}. With the covering
`{s.covering.name}` on the contact point: {cov_text}.
"""
    arts = [*s.figures().items(), ("safety_summary.csv", s.to_pandas()), ("safety_summary_cases.csv", s.cases),
            ("safety_summary_verdicts.csv", s.verdicts)]
    return Section("Safety summary", md, arts, dict(s.metrics))


__all__ = ["compute", "render", "SECTION", "SafetySummaryFindings"]
