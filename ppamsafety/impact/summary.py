"""The safety verdict of an arm on one screen: per controller family and experiment, what governs.

For an arm, its controller variants (the thesis' families, designed for the arm:
:func:`~ppamsafety.experiments.catalog.thesis_variants`) and the step and switch experiments
of Table 6.1, :func:`safety_summary` finds, for every experiment and variant, the worst impact
over the arm's contact points x the ISO/TS 15066 Annex A body regions x every instant
(:func:`~ppamsafety.impact.anywhere.worst_contact`), judges it against every criterion of
its region (:func:`~ppamsafety.impact.verdicts.criteria_for`: the TS forces, the fracture
forces and the HIC of a head region) and names the governing criterion (smallest relative
margin, :func:`~ppamsafety.impact.verdicts.evaluate`).  A controller family's row is the worst
of its variants.

**Body regions** (:func:`region_bodies`): one body per Annex A body region (force limits, K and
m_H are per region; the locations of a region differ only in their pressure), each hit as its
Annex A two-body model (:func:`~ppamsafety.impact.bodies.body_from_region`, its surface
radius that of :func:`~ppamsafety.impact.verdicts.annex_a_head`) -- except the skull and
forehead, hit as the head that passes the Hybrid III drop
(:data:`~ppamsafety.params.contact.FOREHEAD`).  Candidates are ranked by the force over the
region's smallest force limit (:func:`ranking_limit`), so the worst case found is the worst of
every force criterion exactly; the HIC criteria are judged at that case (the HIC of an arm's
impact is orders of magnitude below its limit where the force criteria fail).

**Where the answer depends on a model.**  The governing impact of each family row is simulated
again (same instant, contact point and pose) with the other models of the region's body -- the
region's Annex A spring, the report's head model -- and with a covering on the contact point;
the row says whether the governing criterion's verdict changes.  This is the same impact with
another model, not a new search over every instant.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..results import Result
from .._validation import check_instance, check_int
from ..experiments.catalog import run_thesis_experiment
from ..params import ArmParameters, thesis_arm
from ..params.contact import FOREHEAD, BodyContact, Covering, arm_contact_points
from ..params.contact import covering as named_covering
from ..params.iso_ts_15066 import LOCATIONS, body_region, resolve_region
from .anywhere import simulate_contacts, worst_contact
from .bodies import body_from_head, body_from_region
from .head import resolve_head
from .instants import heuristic_instants, impact_states
from .verdicts import (METRICS, annex_a_head, check_head_for_region, criteria_for, evaluate,
                       verdict_rows)

#: The experiments of Table 6.1.
EXPERIMENTS = ("step", "switch")
#: Instants with a slower contact point are not candidates [m/s] (as the safety scan).
MIN_SPEED = 1e-3
#: The covering the governing impacts are simulated again with (by name,
#: :func:`ppamsafety.params.contact.covering`).
WHAT_IF_COVERING = "thesis-implied"


def region_bodies(head_body: BodyContact = FOREHEAD) -> tuple:
    """One (Annex A body location, body contact) per Annex A body region (module docstring).

    Parameters
    ----------
    head_body : BodyContact
        The body of the skull and forehead (default the head that passes the Hybrid III drop).

    Returns
    -------
    tuple of (BodyRegion, BodyContact)
        The first location of each of the 12 regions of Table A.2, in the Annex's order; the
        body carries the location's name.
    """
    head_body = check_instance("head_body", head_body, BodyContact)
    seen, out = set(), []
    for number, region, *_ in LOCATIONS:
        if region in seen:
            continue
        seen.add(region)
        r = body_region(number)
        out.append((r, region_body(r, head_body=head_body)))
    return tuple(out)


def region_body(region, *, head_body: BodyContact = FOREHEAD, head=None) -> BodyContact:
    """The body a region is hit as (module docstring), named after the region.

    Parameters
    ----------
    region : BodyRegion, str, int or path-like
        The region (:func:`~ppamsafety.params.iso_ts_15066.resolve_region`).
    head_body : BodyContact
        The skull and forehead's body (default the head that passes the Hybrid III drop).
    head : HeadContactModel, str or path-like, optional
        A head model to hit a head region with instead (its one-layer body); refused for a
        region that is not a head region
        (:func:`~ppamsafety.impact.verdicts.check_head_for_region`).

    Returns
    -------
    BodyContact
        ``head`` for a head region when given; ``head_body`` for the skull and forehead;
        else the region's Annex A two-body model.
    """
    r = resolve_region(region)
    check_head_for_region(r, head)
    if head is not None:
        return body_from_head(head).replace(name=r.name)
    if r.name == "skull/forehead":
        return check_instance("head_body", head_body, BodyContact).replace(name=r.name)
    return body_from_region(r, radius=annex_a_head(r).radius)


def body_model_name(region, *, head=None) -> str:
    """The name of the body model :func:`region_body` strikes a region with.

    Parameters
    ----------
    region : BodyRegion, str, int or path-like
        The region.
    head : HeadContactModel, str or path-like, optional
        A head model chosen for a head region.

    Returns
    -------
    str
        The head model's name; ``"validated head"`` (the skull and forehead, the head that
        passes the Hybrid III drop); else the Annex A body model's name
        (:func:`~ppamsafety.impact.verdicts.annex_a_head`, e.g. ``iso15066-chest-40kg``).
    """
    r = resolve_region(region)
    check_head_for_region(r, head)
    if head is not None:
        return resolve_head(head).name
    return "validated head" if r.name == "skull/forehead" else annex_a_head(r).name


def ranking_limit(region):
    """The smallest force criterion of a region (:func:`~ppamsafety.impact.verdicts.criteria_for`).

    Parameters
    ----------
    region : BodyRegion, str, int or path-like
        The region.

    Returns
    -------
    Criterion
    """
    return min((c for c in criteria_for(region) if c.metric == "F_max"), key=lambda c: c.limit)


#: Columns of :attr:`SafetySummary.cases` and :attr:`SafetySummary.table`: the governing
#: verdict of one impact, units in the names.
CASE_COLUMNS = ("experiment", "family", "variant", "contact_point", "body_region", "body_model",
                "criterion", "value", "limit", "unit", "margin", "margin [%]", "passed",
                "all_passed", "t0 [s]", "point_speed [m/s]", "F_max [N]", "HIC36", "q1 [rad]",
                "q2 [rad]", "qd1 [rad/s]", "qd2 [rad/s]", "K1 [N m/rad]", "K2 [N m/rad]")


@dataclass
class SafetySummary(Result):
    """Result of :func:`safety_summary`.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per (experiment, controller family): the worst variant's governing verdict
        (:data:`CASE_COLUMNS`), ``variants`` and ``variants_passing`` (variants that pass every
        criterion), and the dependence columns: ``head_alternatives`` (text: the governing
        criterion's value with its unit with each other body model of the region, '' for a
        region without one), ``depends_on_head`` (the verdict changes with one of them),
        ``covered_value`` (the governing value with :attr:`covering` on the contact point) and
        ``depends_on_covering``.
    cases : pandas.DataFrame
        One row per (experiment, variant): :data:`CASE_COLUMNS`.
    verdicts : pandas.DataFrame
        Every criterion at every case's worst impact
        (:data:`~ppamsafety.impact.verdicts.VERDICT_COLUMNS` plus experiment and variant).
    head : str
        The report's head model (an alternative body of the head regions).
    covering : Covering
        The covering of the what-if.
    arm_name : str
        The arm.
    every : int
        Instant stride (1: every control period).
    metrics : dict
        Headline numbers: candidates, simulations, the process time [s].
    worst_scan : WorstContact or None
        The scan of the run with the smallest margin (every contact point's worst region).
    arm : ArmParameters or None
        The arm (its figure).
    """

    table: pd.DataFrame
    cases: pd.DataFrame
    verdicts: pd.DataFrame
    head: str
    covering: Covering
    arm_name: str
    every: int
    metrics: dict = field(default_factory=dict)
    worst_scan: object = None
    arm: object = None

    def to_pandas(self) -> pd.DataFrame:
        """The one-screen table (:attr:`table`)."""
        return self.table.copy()

    def figures(self) -> dict:
        """The arm at the worst instant of the worst run, each contact point with its worst
        region and margin (:meth:`~ppamsafety.impact.anywhere.WorstContact.plot`),
        ``{file name: Figure}``."""
        o = self.overall
        return {"safety_summary_worst.png": self.worst_scan.plot(
            self.arm, title=f"{o['experiment']}, {o['variant']}: worst region per contact point "
                            f"(margin to its smallest force limit)")}

    @property
    def overall(self) -> pd.Series:
        """The row of the smallest margin over every family and experiment."""
        return self.table.loc[self.table["margin [%]"].idxmin()]


def _governing(values, region, point, body_name):
    v = evaluate(values, criteria_for(region), head=body_name, contact_point=point,
                 region=region.name)
    return v, v.loc[v["margin_pct"].idxmin()]


def _again(arm, row, body, covering, criterion):
    """The governing criterion's value of one case's impact with another body or covering."""
    q = [row["q1 [rad]"], row["q2 [rad]"]]
    qd = [row["qd1 [rad/s]"], row["qd2 [rad/s]"]]
    K = [row["K1 [N m/rad]"], row["K2 [N m/rad]"]]
    s = simulate_contacts(arm, q, qd, K, point=row["contact_point"], body=body,
                          covering=covering).summary.iloc[0]
    return float(s[criterion.metric])


def _experiments(experiments) -> tuple:
    """The experiments checked: a non-empty sequence of :data:`EXPERIMENTS`."""
    if isinstance(experiments, str):
        raise TypeError(f"experiments must be a sequence of experiment names, got the str "
                        f"{experiments!r} (write ({experiments!r},))")
    out = tuple(experiments)
    bad = [e for e in out if e not in EXPERIMENTS]
    if bad or not out:
        raise ValueError(f"experiments = {out!r}: give one or more of {list(EXPERIMENTS)}")
    return out


def safety_summary(arm=None, *, head=None, covering=None, experiments=EXPERIMENTS,
                   every: int = 1, runs=None) -> SafetySummary:
    """The governing verdict per controller family and experiment (module docstring).

    Parameters
    ----------
    arm : ArmParameters, optional
        The arm (default the thesis arm).
    head : HeadContactModel, str or path-like, optional
        The report's head model (default ``thesis-frontal``): the head regions' answer is also
        given with it.
    covering : Covering or str, optional
        The covering of the what-if (default :data:`WHAT_IF_COVERING`).
    experiments : sequence of {"step", "switch"}
        The experiments.
    every : int
        Instant stride of the scan (1: every control period; the report's quick mode 20).
    runs : dict, optional
        Already computed ``{experiment: list of ExperimentResult}`` of the thesis variants on
        ``arm`` (:func:`~ppamsafety.experiments.catalog.run_thesis_experiment`), to reuse.

    Returns
    -------
    SafetySummary
    """
    cpu0 = time.process_time()
    arm = thesis_arm() if arm is None else check_instance("arm", arm, ArmParameters)
    hm = resolve_head(head)
    cov = named_covering(WHAT_IF_COVERING) if covering is None else (
        named_covering(covering) if isinstance(covering, str) else
        check_instance("covering", covering, Covering))
    every = check_int("every", every, 1, 10 ** 6)
    experiments = _experiments(experiments)
    pairs = region_bodies()
    regions = {b.name: r for r, b in pairs}
    bodies = [b for _, b in pairs]
    limits = {b.name: ranking_limit(r).limit for r, b in pairs}
    rows, verdicts, n_cand, n_sim = [], [], 0, 0
    worst_scan, worst_margin = None, float("inf")
    for exp in experiments:
        res_list = run_thesis_experiment(arm, exp) if runs is None else runs[exp]
        for res in res_list:
            w = worst_contact(res, arm, bodies=bodies, limits=limits, min_speed=MIN_SPEED,
                              every=every)
            n_cand += w.n_candidates
            n_sim += w.n_simulated
            # every point's worst, judged on every criterion of its region: the governing one
            best = None
            for _, o in w.worst.iterrows():
                reg = regions[o["body"]]
                v, gov = _governing({"F_max": o["F_max"], "HIC36": o["HIC36"]}, reg,
                                    o["point"], o["body"])
                if best is None or gov["margin_pct"] < best[2]["margin_pct"]:
                    best = (o, v, gov)
            o, v, gov = best
            if gov["margin_pct"] < worst_margin:
                worst_scan, worst_margin = w, gov["margin_pct"]
            label, fam = res.meta["label"], res.meta["family"]
            verdicts.append(v.assign(experiment=exp, variant=label))
            rows.append({"experiment": exp, "family": fam, "variant": label,
                         "contact_point": o["point"], "body_region": o["body"],
                         "body_model": ("validated head" if o["body"] == "skull/forehead"
                                        else "Annex A two-body"),
                         "criterion": gov["criterion"], "value": gov["value"],
                         "limit": gov["limit"], "unit": gov["unit"], "margin": gov["margin"],
                         "margin [%]": gov["margin_pct"], "passed": bool(gov["passed"]),
                         "all_passed": bool(v["passed"].all()), "t0 [s]": o["t0"],
                         "point_speed [m/s]": o["point_speed"], "F_max [N]": o["F_max"],
                         "HIC36": o["HIC36"], "q1 [rad]": o["q1"], "q2 [rad]": o["q2"],
                         "qd1 [rad/s]": o["qd1"], "qd2 [rad/s]": o["qd2"],
                         "K1 [N m/rad]": o["K1"], "K2 [N m/rad]": o["K2"]})
    cases = pd.DataFrame(rows, columns=list(CASE_COLUMNS))
    table = []
    for (exp, fam), g in cases.groupby(["experiment", "family"], sort=False):
        r = g.loc[g["margin [%]"].idxmin()].to_dict()
        reg = regions[r["body_region"]]
        crit = next(c for c in criteria_for(reg) if c.name == r["criterion"])
        alts = []
        if reg.head:
            if r["body_region"] == "skull/forehead":
                alts.append(("Annex A spring", body_from_region(
                    reg, radius=annex_a_head(reg).radius)))
            else:
                alts.append(("validated head", FOREHEAD.replace(name=reg.name)))
            alts.append((f"head model {hm.name}", body_from_head(hm)))
        body = dict((b.name, b) for b in bodies)[r["body_region"]]
        alt_vals = [(name, _again(arm, r, b, None, crit)) for name, b in alts]
        unit = f" {METRICS[crit.metric]}" if METRICS.get(crit.metric) else ""
        covered = _again(arm, r, body, cov, crit)
        b_row = g.loc[g["margin [%]"].idxmax()]
        r.update(variants=len(g), variants_passing=int(g["all_passed"].sum()),
                 best_variant=b_row["variant"], **{"best_margin [%]": b_row["margin [%]"]},
                 head_alternatives="; ".join(f"{n}: {val:.4g}{unit}" for n, val in alt_vals),
                 depends_on_head=any((val < crit.limit) != r["passed"] for _, val in alt_vals),
                 covered_value=covered,
                 depends_on_covering=bool((covered < crit.limit) != r["passed"]))
        table.append(r)
    table = pd.DataFrame(table)
    metrics = {"candidates": n_cand, "simulated": n_sim,
               "cpu_seconds": time.process_time() - cpu0,
               "worst_margin_pct": float(table["margin [%]"].min()),
               "cases_passing": int(cases["all_passed"].sum()), "cases": len(cases)}
    return SafetySummary(table, cases, pd.concat(verdicts, ignore_index=True), hm.name, cov,
                         arm.name, every, metrics, worst_scan, arm)


def region_point_verdicts(arm=None, *, covering=None, experiments=EXPERIMENTS,
                          runs=None) -> pd.DataFrame:
    """The verdict of every body region at every contact point over Table 6.1's impacts.

    Every experiment and controller variant is crashed, as Table 6.1 is, at its four
    heuristic impact instants (thesis §6.3.3:
    :func:`~ppamsafety.impact.instants.heuristic_instants`), at each of the arm's contact
    points, into each body region of :func:`region_bodies`; each impact is judged on every
    criterion of its region; per (region, contact point) the row of the worst impact (the
    smallest governing margin).

    Parameters
    ----------
    arm : ArmParameters, optional
        The arm (default the thesis arm).
    covering : Covering or str, optional
        The covering of every contact point (default bare metal).
    experiments : sequence of {"step", "switch"}
        The experiments.
    runs : dict, optional
        ``{experiment: list of ExperimentResult}`` to reuse.

    Returns
    -------
    pandas.DataFrame
        One row per (body region, contact point): ``body_region``, ``contact_point``,
        ``covering``, the worst impact's ``experiment``, ``variant``, governing ``criterion``,
        ``value``, ``limit``, ``unit``, ``margin``, ``margin [%]``, ``passed``, ``F_max [N]``,
        ``HIC36``, and ``passing`` / ``impacts`` (experiments x variants whose worst instant
        passes every criterion of the region).
    """
    arm = thesis_arm() if arm is None else check_instance("arm", arm, ArmParameters)
    cov = None if covering is None else (named_covering(covering) if isinstance(covering, str)
                                         else check_instance("covering", covering, Covering))
    experiments = _experiments(experiments)
    states = []
    for exp in experiments:
        for res in (run_thesis_experiment(arm, exp) if runs is None else runs[exp]):
            st = impact_states(res, arm)
            sub = st.iloc[list(heuristic_instants(st).values())]
            states.append((exp, res.meta["label"], sub))
    q = np.concatenate([s[["q1", "q2"]].to_numpy() for *_, s in states])
    qd = np.concatenate([s[["qd1", "qd2"]].to_numpy() for *_, s in states])
    K = np.concatenate([s[["K1", "K2"]].to_numpy() for *_, s in states])
    ends = np.cumsum([len(s) for *_, s in states])     # each run's instants, in order
    rows = []
    for reg, body in region_bodies():
        crit = criteria_for(reg)
        for p in arm_contact_points(arm):
            s = simulate_contacts(arm, q, qd, K, point=p, body=body, covering=cov).summary
            F, H = s["F_max"].to_numpy(), s["HIC36"].to_numpy()
            best, npass = None, 0
            for j, (exp, label, _) in enumerate(states):
                a = ends[j - 1] if j else 0
                fmax, hic = F[a + np.nanargmax(F[a:ends[j]])], np.nanmax(H[a:ends[j]])
                # the rows only: a table per impact costs more than its verdicts
                v = verdict_rows({"F_max": fmax, "HIC36": hic}, crit, contact_point=p.name,
                                 region=reg.name)
                gov = min(v, key=lambda row: row["margin_pct"])     # the first smallest
                npass += all(row["passed"] for row in v)
                if best is None or gov["margin_pct"] < best[2]["margin_pct"]:
                    best = (exp, label, gov, fmax, hic)
            exp, label, gov, fmax, hic = best
            rows.append({"body_region": reg.name, "contact_point": p.name,
                         "covering": (cov or p.covering).name, "experiment": exp,
                         "variant": label, "criterion": gov["criterion"], "value": gov["value"],
                         "limit": gov["limit"], "unit": gov["unit"], "margin": gov["margin"],
                         "margin [%]": gov["margin_pct"], "passed": bool(gov["passed"]),
                         "F_max [N]": fmax, "HIC36": hic, "passing": npass,
                         "impacts": len(states)})
    return pd.DataFrame(rows)


__all__ = ["safety_summary", "region_point_verdicts", "region_body", "body_model_name",
           "SafetySummary",
           "region_bodies", "ranking_limit", "EXPERIMENTS", "CASE_COLUMNS", "WHAT_IF_COVERING"]
