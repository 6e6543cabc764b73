"""The whole person on the thesis arm: the validated head, the implied covering, every region and
contact point on Table 6.1's experiments, the covering envelope."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import pandas as pd

from ..results import Result
from ..envelope import safety_envelope
from ..experiments.catalog import run_thesis_experiment
from ..impact.bodies import body_from_head, hybrid3_drop
from ..impact import covering_fit as cf
from ..impact.layers import series_contact
from ..impact.summary import EXPERIMENTS, region_point_verdicts
from ..markdown import markdown_table
from ..params.contact import BARE, FOREHEAD, THESIS_COVERING, arm_contact_points
from ..params.iso_ts_15066 import SKULL_FOREHEAD
from ..plots.contacts import plot_region_margins
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm)

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores.
SECTION = SectionInfo(
    summary="the whole person: the head that passes its drop test, the covering Table 6.1 "
            "implies, every body region at every contact point, the covering envelope",
    thesis="§6.3, Table 6.1", typical_seconds=45.0, scope="thesis")

#: The controllers of the covering envelope: the three PSMC families at lambda = 0.4 s in the
#: step experiment (name, case).
ENVELOPE_CASES = (("PSMC joint Ki=2 λ=0.4", {"controller": "PSMC joint", "ki_bar": 2.0}),
                  ("PSMC joint Ki=12 λ=0.4", {"controller": "PSMC joint", "ki_bar": 12.0}),
                  ("PSMC task λ=0.4", {"controller": "PSMC task"}))
#: Covering thicknesses searched [m].
ENVELOPE_RANGE = (0.5e-3, 30e-3)
#: The quick report's share: the step experiment's impacts and the first family's envelope.
QUICK_EXPERIMENTS, QUICK_ENVELOPE_CASES = ("step",), ENVELOPE_CASES[:1]


@dataclass
class PersonFindings(Result):
    """Result of :func:`compute`.

    Attributes
    ----------
    drop : pandas.DataFrame
        The Hybrid III head drop (49 CFR 572.32) of the validated head and of thesis-frontal.
    covering : pandas.DataFrame
        Table 6.1's pairs with the validated head (5 kg) on bare metal, behind the shipped
        implied covering, and behind the covering fitted again (full mode).
    regions : pandas.DataFrame
        Every body region x contact point, bare and behind the implied covering
        (:func:`~ppamsafety.impact.summary.region_point_verdicts`).
    envelope : pandas.DataFrame
        The thinnest implied covering that keeps each PSMC family (lambda = 0.4 s, step)
        below the forehead's transient limit at every contact point.
    quick : bool
        The quick report's share: the fit was not run again, the regions were judged on the
        impacts of :data:`QUICK_EXPERIMENTS`, the envelope searched for
        :data:`QUICK_ENVELOPE_CASES`.
    metrics : dict
        Headline numbers.
    note : str
        For another arm than the thesis arm: what is not shown (Table 6.1 is the thesis arm's;
        no covering is fitted to it), else "".
    """

    drop: pd.DataFrame
    covering: pd.DataFrame
    regions: pd.DataFrame
    envelope: pd.DataFrame
    quick: bool
    metrics: dict = field(default_factory=dict)
    note: str = ""

    def to_pandas(self) -> pd.DataFrame:
        """The verdicts of every region and contact point (:attr:`regions`)."""
        return self.regions.copy()

    @property
    def margin_grid(self) -> pd.DataFrame:
        """One row per body region, one column per (contact point, covering): the governing
        criterion's margin to its limit [%], rounded to 1 %."""
        grid = self.regions.pivot_table(index="body_region", columns=["covering",
                                                                      "contact_point"],
                                        values="margin [%]", sort=False)
        grid.columns = [f"{cp}, {cv} [% margin]" for cv, cp in grid.columns]
        return grid.round(0).reset_index()

    def figures(self) -> dict:
        """``{"person_regions.png": Figure}``: :attr:`margin_grid` as a colour grid
        (:func:`ppamsafety.plots.contacts.plot_region_margins`)."""
        return {"person_regions.png": plot_region_margins(
            self.margin_grid, title="Every body region at every contact point, Table 6.1 "
                                    "experiments: margin of the governing criterion")}


@checked_compute
def compute(*, quick: bool = False, arm=None) -> PersonFindings:
    """The drop test, the implied covering, every region and point, the covering envelope.

    Parameters
    ----------
    quick : bool
        Do not fit the covering again (use the shipped one); judge the regions on the
        impacts of :data:`QUICK_EXPERIMENTS` and search the envelope of
        :data:`QUICK_ENVELOPE_CASES` only.
    arm : ArmParameters, optional
        The arm (the thesis arm: Table 6.1 is its).

    Returns
    -------
    PersonFindings
    """
    cpu0 = time.process_time()
    thesis = compares_to_thesis(arm)
    arm = resolve_arm(arm)
    drops = [("head (forehead), validated", hybrid3_drop(FOREHEAD)),
             ("thesis-frontal", hybrid3_drop(body_from_head("thesis-frontal")))]
    drop = pd.DataFrame([{
        "head model": n, "mass [kg]": d.body.mass, "impact speed [m/s]": d.speed,
        "peak [g]": d.peak_g, "peak CFC 1000 [g]": d.peak_g_cfc, "restitution": d.restitution,
        "after_pulse_share": d.unimodal, "passed": d.passed} for n, d in drops])
    head5 = FOREHEAD.replace(mass=cf.THESIS_HEAD_MASS)
    tool = arm_contact_points(arm)[0]
    cov_rows = []
    coverings = (("bare metal", BARE), (THESIS_COVERING.name, THESIS_COVERING)) if thesis else ()
    for name, cov in coverings:
        rms, _ = cf.table_6_1_residuals(series_contact(cov, head5, point=tool), arm=arm)
        lay = cov.layers[0] if cov.layers else None
        cov_rows.append({"covering": name,
                         "thickness [mm]": 1e3 * cov.thickness,
                         "modulus [MPa]": lay.modulus / 1e6 if lay else float("nan"),
                         "hysteresis [s/m]": lay.hysteresis if lay else float("nan"),
                         "rms_sigma": rms, "reproduced": bool(rms <= 1.0)})
    if thesis and not quick:
        fit = cf.fit_covering(arm)
        cov_rows.append({"covering": "fitted again (fit_covering)",
                         "thickness [mm]": 1e3 * fit.covering.thickness,
                         "modulus [MPa]": fit.modulus / 1e6,
                         "hysteresis [s/m]": fit.hysteresis, "rms_sigma": fit.rms_sigma,
                         "reproduced": fit.reproduced})
    exps = QUICK_EXPERIMENTS if quick else EXPERIMENTS
    runs = {e: run_thesis_experiment(arm, e) for e in exps}
    regions = pd.concat([region_point_verdicts(arm, runs=runs, experiments=exps),
                         region_point_verdicts(arm, covering=THESIS_COVERING, runs=runs,
                                               experiments=exps)], ignore_index=True)
    env_rows = []
    for label, case in (QUICK_ENVELOPE_CASES if quick else ENVELOPE_CASES):
        env = safety_envelope("covering_thickness", ENVELOPE_RANGE, limit="iso_ts_15066",
                              case={**case, "experiment": "step", "lam": 0.4,
                                    "contact": "all"}, arm=arm, tolerance=0.02)
        env_rows.append({"controller": label, "limit": "iso_ts_15066 (skull/forehead)",
                         "F_limit [N]": SKULL_FOREHEAD.force_transient,
                         "thinnest safe [mm]": (1e3 * env.safe_value
                                                if env.safe_value is not None else float("nan")),
                         "thickest unsafe [mm]": (1e3 * env.unsafe_value if env.unsafe_value
                                                  is not None else float("nan")),
                         "margin [N]": env.margin if env.margin is not None else float("nan"),
                         "monotone": bool(env.monotone)})
    envelope = pd.DataFrame(env_rows)
    bare = regions[regions.covering == BARE.name]
    metrics = {"drop_peak_g": float(drops[0][1].peak_g_cfc),
               "drop_passed": bool(drops[0][1].passed),
               "thesis_frontal_drop_g": float(drops[1][1].peak_g_cfc),
               **({"covering_rms_sigma": float(cov_rows[1]["rms_sigma"]),
                   "bare_rms_sigma": float(cov_rows[0]["rms_sigma"])} if thesis else {}),
               "pairs_failing_bare": int((~bare.passed).sum()), "pairs": len(bare),
               "cpu_seconds": time.process_time() - cpu0}
    note = "" if thesis else (other_arm_note(arm) + " Table 6.1 and the covering it implies "
                              "belong to the thesis arm: the covering is not fitted again.")
    return PersonFindings(drop, pd.DataFrame(cov_rows), regions, envelope, quick, metrics, note)


def render(study: PersonFindings) -> Section:
    """The section (formatting only).

    Parameters
    ----------
    study : PersonFindings
        Output of :func:`compute`.

    Returns
    -------
    Section
    """
    d, c, m = study.drop, study.covering, study.metrics
    r = study.regions
    grid = study.margin_grid
    if len(c):
        covering_text = f"""**The covering Table 6.1 implies** (in front of the validated head with the thesis' 5 kg,
at the tool point): the 20 (HIC, F_max) pairs are reproduced (RMS residual at most 1 standard
deviation) only with a soft, lossy covering; on bare metal they are not:

{markdown_table(c, digits=3)}

The thesis arm's links are bare aluminium (§2.3.3.4): such a covering is what the thesis'
numbers need, not what the arm has."""
    else:
        covering_text = ""
    quick_exps = (f"the quick report: {', '.join(r.experiment.unique())} only; "
                  if study.quick else "")
    quick_env = "; the quick report: the first family only" if study.quick else ""
    md = ("" if not study.note else study.note + "\n\n") + f"""The head the other impact sections hit by default is the thesis' lumped contact (`thesis-frontal`,
fitted to Table 6.1). Here the person is modelled in layers: the robot's covering (or bare
metal) in series with the body's soft tissue and bone (docs/impact_models.md).

**The validated head** passes the Hybrid III head drop of 49 CFR 572.32 (4.54 kg from 376 mm onto
a rigid plate, 225-275 g required); thesis-frontal does not:

{markdown_table(d, digits=3)}

{covering_text}

**Every body region at every contact point** on the Table 6.1 experiments ({quick_exps}the four impact
instants of §6.3.3 per run, each of the 12 ISO/TS 15066 Annex A body regions -- the skull and
forehead as the validated head, the others as their Annex A two-body models --, judged on every
criterion of the region; the margin of the governing criterion of the worst run; bare metal and
behind the implied covering; {m['pairs_failing_bare']} of {m['pairs']} region x point pairs fail on
bare metal). Every row with its governing criterion, worst run and runs passing is in
`person_regions.csv`:

{markdown_table(grid, digits=3)}

**The covering envelope**: the thinnest implied covering (its material, thickness searched) that
keeps each PSMC family at λ = 0.4 s in the step experiment below the forehead's transient limit
at every contact point (the worst of the four, heuristic instants, tolerance 2 %{quick_env}):

{markdown_table(study.envelope, digits=3)}
"""
    arts = [*study.figures().items(), ("person_drop.csv", d), ("person_covering.csv", c),
            ("person_regions.csv", r), ("person_envelope.csv", study.envelope)]
    return Section("The whole person: validated head, implied covering, every region and "
                   "contact point", md, arts, dict(m))


__all__ = ["compute", "render", "PersonFindings"]
