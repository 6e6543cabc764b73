"""Design figures of thesis chapter 2: torque functions, stiffness, maximum load."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .. import design
from ..markdown import markdown_table
from ..plant import geometry as geo
from ..plant import pneumatics as pn
from ..plant.muscle import force_function, force_polynomial
from ..plant.ppam_theory import theoretical_muscles
from ..sweep_cases import impact_pose_deg
from ..units import BAR, DEG, MM
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm)
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (measured 2026-11-23), the order a first report starts the sections in.
SECTION = SectionInfo(
    summary="Table A.1, torque functions, stiffness, maximum load",
    thesis="ch. 2, App. A", typical_seconds=2.8)


def _table_a1(arm, thesis: bool = True) -> pd.DataFrame:
    g = arm.geometry
    q1 = np.linspace(g.q1_min, g.q1_max, 4001)
    q2 = np.linspace(g.q2_min, g.q2_max, 4001)
    da = geo.muscle_lengths(np.stack([q1, np.full_like(q1, -80 * DEG)], -1), arm)
    db = geo.muscle_lengths(np.stack([np.full_like(q2, 50 * DEG), q2], -1), arm)
    ours = np.concatenate([[da[:, 0].max(), da[:, 1].min(), db[:, 2].max(), db[:, 3].min()],
                           geo.connection_lengths(arm)]) / MM
    names = ["d1,max", "d2,min", "d3,max", "d4,min", "Lconn,1", "Lconn,2", "Lconn,3", "Lconn,4"]
    if not thesis:
        return pd.DataFrame({"quantity": names, "computed [mm]": ours.round(2)})
    thesis = np.array([345.0, 200.5, 322.3, 265.8, 117.0, 74.5, 94.3, 139.8])
    return pd.DataFrame({"quantity": names, "thesis Table A.1 [mm]": thesis,
                         "computed [mm]": ours.round(2), "difference [mm]": (ours - thesis).round(2)})


@dataclass
class DesignFindings(Result):
    """Result of :func:`compute`: the chapter-2 design maps and Table A.1.

    Attributes
    ----------
    quick : bool
        Coarse grids were used.
    torque_functions : ppamsafety.design.TorqueFunctions
        Torque functions of the four muscle groups (fig. 2.11).
    stiffness : ppamsafety.design.StiffnessMap
        Joint stiffness (2.18) over the working area.
    max_load, max_load_cad : ppamsafety.design.MaxLoadMap
        Maximum load with the plant links and with the CAD links (fig. 2.15).
    max_load_theory : ppamsafety.design.MaxLoadMap
        Maximum load with the CAD links and the theoretical force function
        f_t0 (:func:`ppamsafety.plant.ppam_theory.theoretical_muscles`), as at design time.
        ``max_load_cad`` and ``max_load_theory`` use the thesis arm's design-time data:
        None for another arm.
    table_a1 : pandas.DataFrame
        Table A.1 (muscle lengths) computed vs thesis [mm] (computed only for another
        arm).
    K_step : numpy.ndarray
        Joint stiffness at the step-response impact configuration [Nm/rad].
    p_mean : numpy.ndarray
        Calibrated mean pressures [Pa].
    edge : dict
        Force functions at the working-area edges: ``e1max``, ``e4max``
        (largest contractions of groups 1 and 4 [-]), ``f1_edge`` [N/bar] and
        ``f4_raw`` [N/bar, before clipping to 0] (force functions there).
    metrics : dict
        Headline numbers.
    thesis : bool
        Thesis values (Table A.1, the design-time maps) apply: the thesis arm.
    arm : ArmParameters or None
        The arm (ArmParameters).
    """

    quick: bool
    torque_functions: object
    stiffness: object
    max_load: object
    max_load_cad: object
    table_a1: pd.DataFrame
    K_step: np.ndarray
    p_mean: np.ndarray
    edge: dict
    max_load_theory: object = None
    metrics: dict = field(default_factory=dict)
    thesis: bool = True
    arm: object = None

    def to_pandas(self) -> pd.DataFrame:
        """Table A.1 (computed vs thesis muscle lengths [mm])."""
        return self.table_a1.copy()

    def figures(self) -> dict:
        """The section's figures, ``{file name: Figure}``."""
        return {"design_torque_functions.png": self.torque_functions.plot(),
                "design_stiffness_map.png": self.stiffness.plot(),
                "design_max_load.png": self.max_load.plot()}


@checked_compute
def compute(*, quick: bool = False, arm=None, head=None) -> DesignFindings:
    """Torque functions, stiffness and maximum-load maps, Table A.1.

    Parameters
    ----------
    quick : bool
        Coarse grids (41 x 41 instead of 121 x 121 for the stiffness map).
    arm : ppamsafety.params.ArmParameters, optional
        Arm (default: the thesis arm).
    head : HeadContactModel, optional
        Unused (no impact in this section); accepted like every section's.

    Returns
    -------
    DesignFindings
        Maps, tables and metrics.
    """
    arm = resolve_arm(arm)
    thesis = compares_to_thesis(arm)
    n = 41 if quick else 121
    tf = design.torque_function_curves(arm)
    sm = design.stiffness_map(arm, n1=n, n2=n)
    q_step = np.array(impact_pose_deg(arm)) * DEG
    K_step = pn.joint_stiffness(q_step, pn.static_pressures(q_step, arm), arm)
    ml = design.max_load_map(arm, n1=2 * n, n2=2 * n)
    if thesis:     # the thesis arm's design-time data: CAD links, theoretical force function
        ml_cad = design.max_load_map(arm, links=design.cad_links(), n1=2 * n, n2=2 * n)
        g0 = arm.muscles.groups[0]
        arm_theory = arm.replace(muscles=theoretical_muscles(slenderness=g0.slenderness,
                                                             l0=g0.l0))
        ml_theory = design.max_load_map(arm_theory, links=design.cad_links(), n1=2 * n,
                                        n2=2 * n)
    else:
        ml_cad = ml_theory = None
    d = ml.data
    g = arm.geometry
    inner = d[(d.q1_rad > g.q1_min + 5 * DEG) & (d.q1_rad < g.q1_max - 5 * DEG)
              & (d.q2_rad > g.q2_min + 5 * DEG) & (d.q2_rad < g.q2_max - 5 * DEG)]

    eps = geo.contractions(d[["q1_rad", "q2_rad"]].to_numpy(), arm)
    e1max, e4max = eps[:, 0].max(), eps[:, 3].max()
    f1_edge = float(force_function(1, e1max, arm)) * BAR
    f4_raw = float(force_polynomial(4, e4max, arm)) * BAR
    ta1 = _table_a1(arm, thesis)
    if thesis:
        metrics = {"table_A1_max_abs_diff_mm": float(ta1["difference [mm]"].abs().max()),
                   "K_step": K_step.tolist(), "max_load_min_kg": ml.minimum,
                   "max_load_min_cad_kg": ml_cad.minimum,
                   "max_load_interior_min_kg": float(inner.M_max_kg.min()),
                   "max_load_min_theory_cad_kg": ml_theory.minimum}
    else:
        metrics = {"K_step": K_step.tolist(), "max_load_min_kg": ml.minimum,
                   "max_load_interior_min_kg": float(inner.M_max_kg.min()
                                                     if len(inner) else ml.minimum)}
    return DesignFindings(quick=quick, torque_functions=tf, stiffness=sm, max_load=ml,
                       max_load_cad=ml_cad, table_a1=ta1, K_step=K_step,
                       p_mean=np.array(arm.pneumatics.p_mean),
                       edge={"e1max": e1max, "e4max": e4max, "f1_edge": f1_edge,
                             "f4_raw": f4_raw},
                       max_load_theory=ml_theory, metrics=metrics, thesis=thesis, arm=arm)


def render(study: DesignFindings) -> Section:
    """The report section of the design study (formatting only).

    Parameters
    ----------
    study : DesignFindings
        Output of :func:`compute`.

    Returns
    -------
    Section
        Markdown and artifacts (figures, ``design_table_A1.csv``).
    """
    if not study.thesis:
        return _render_other(study)
    sm, ml, ml_cad, ta1 = study.stiffness, study.max_load, study.max_load_cad, study.table_a1
    K_step, quick = study.K_step, study.quick
    lim, kr = ml.limits, sm.ranges
    m1_min, m2a, m2b = lim["M1_min"], lim["M2_min_muscle3"], lim["M2_min_muscle4"]
    e1max, e4max = study.edge["e1max"], study.edge["e4max"]
    f1_edge, f4_raw = study.edge["f1_edge"], study.edge["f4_raw"]
    qmin = np.array(ml.argmin) / DEG
    pm = study.p_mean / BAR
    inner_min = study.metrics["max_load_interior_min_kg"]
    ml_th = study.max_load_theory
    qth = np.array(ml_th.argmin) / DEG
    md = f"""Geometry of Table 2.1 with the identified muscle model of Table B.1 (all SI inside).

**Table A.1 reproduced** (acceptance: +-0.5 mm):

{markdown_table(ta1, digits=2)}

**Torque functions** (cf. fig. 2.11): ![torque functions](design_torque_functions.png)

**Joint stiffness** (2.18) including the closed-valve polytropic term, with static
gravity-compensation pressures and the calibrated mean pressures p_m = ({pm[0]:.3f}, {pm[1]:.3f}) bar.
At the step-response impact configuration q = (50, -80) deg: K = ({K_step[0]:.1f}, {K_step[1]:.1f}) Nm/rad
(thesis §6.3.3: 43 and 27 Nm/rad). Over the working area K1 ranges
{kr["K1_min"]:.1f}-{kr["K1_max"]:.1f} and K2
{kr["K2_min"]:.1f}-{kr["K2_max"]:.1f} Nm/rad. With the Delta-p approach
at these p_m the arm can hold itself statically in {100 * kr["holdable_fraction"]:.0f} % of the working
area (hatched: a pressure would leave [0, 3] bar).

![stiffness](design_stiffness_map.png)

**Maximum load** (fig. 2.15, App. A.4), carrying muscle at 3 bar, antagonist at 0:

| | minimum over the working area | where (q1, q2) [deg] |
|---|---|---|
| thesis fig. 2.15 | "just over 2 kg" | |
| this toolkit, plant links | {ml.minimum:.2f} kg | ({qmin[0]:.0f}, {qmin[1]:.0f}) |
| this toolkit, CAD links (m1 = 1.5, m2 = 1.05 kg) | {ml_cad.minimum:.2f} kg | |
| this toolkit, CAD links, theoretical f_t0 (2.3) instead of Table B.1 | {ml_th.minimum:.2f} kg | ({qth[0]:.0f}, {qth[1]:.0f}) |
| joint-1 limit (A.43) alone | {m1_min:.2f} kg | |
| joint-2 limit, muscle 3 carrying (A.44) | {m2a:.2f} kg | |
| joint-2 limit, muscle 4 carrying (A.45) | {m2b:.2f} kg | |
| 5 deg away from every edge | {inner_min:.2f} kg | |

The minimum differs from the thesis because the thesis computed fig. 2.15 at design time with the
*theoretical* PPAM force function f_t0(eps, l0/R = 6) of Daerden's model (eq. 2.2, fig. 2.2),
whereas the toolkit uses the force law identified afterwards on the built arm (3.9, Table B.1).
The identified fits fall to about zero force near 30 % contraction: f1({100 * e1max:.1f} %) =
{f1_edge:.1f} N/bar for group 1 at q1 = 105 deg, and f4({100 * e4max:.1f} %) = {f4_raw:.2f} N/bar
(clipped to 0) for group 4 at q2 = -130 deg, where the design puts those muscles. At those edges the arm cannot carry a load (at
q2 = -130 deg muscle 4 cannot even hold the forearm: negative maximum load). In the interior the
map agrees in magnitude with the thesis (median {lim["median"]:.1f} kg).
Recomputed with the theoretical f_t0 (Daerden's N -> inf model, `ppamsafety.plant.ppam_theory`,
fitted as (2.3)) and the CAD links, the minimum is {ml_th.minimum:.2f} kg, the thesis' "just over 2 kg".
{'' if not quick else '(quick mode: coarse grids)'}

![max load](design_max_load.png)
"""
    arts = [*study.figures().items(), ("design_table_A1.csv", ta1)]
    return Section("Design of the arm (thesis chapter 2)", md, arts, dict(study.metrics))


def _render_other(study: DesignFindings) -> Section:
    """The design section for an arm other than the thesis arm: its own numbers only."""
    sm, ml, ta1, K, quick = (study.stiffness, study.max_load, study.table_a1, study.K_step,
                             study.quick)
    lim, kr = ml.limits, sm.ranges
    qmin = np.array(ml.argmin) / DEG
    pm = study.p_mean / BAR
    q = impact_pose_deg(study.arm)
    md = f"""{other_arm_note(study.arm)}

**Muscle group lengths and connection lengths** (as Table A.1; connection lengths by the design
rule (A.35)-(A.38)):

{markdown_table(ta1, digits=2)}

**Torque functions** (cf. fig. 2.11): ![torque functions](design_torque_functions.png)

**Joint stiffness** (2.18) with static gravity-compensation pressures at the mean pressures
p_m = ({pm[0]:.3f}, {pm[1]:.3f}) bar. At q = ({q[0]:.0f}, {q[1]:.0f}) deg: K = ({K[0]:.1f}, {K[1]:.1f})
Nm/rad. Over the working area K1 ranges {kr["K1_min"]:.1f}-{kr["K1_max"]:.1f}
and K2 {kr["K2_min"]:.1f}-{kr["K2_max"]:.1f} Nm/rad; the arm can hold
itself statically in {100 * kr["holdable_fraction"]:.0f} % of the working area (hatched: a pressure
would leave [0, p_max]).

![stiffness](design_stiffness_map.png)

**Maximum load** (App. A.4), carrying muscle at p_max = {ml.p_max / BAR:g} bar, antagonist at 0:
minimum over the working area {ml.minimum:.2f} kg at ({qmin[0]:.0f}, {qmin[1]:.0f}) deg; joint-1 limit
(A.43) alone {lim["M1_min"]:.2f} kg; 5 deg away from every edge
{study.metrics["max_load_interior_min_kg"]:.2f} kg; median {lim["median"]:.1f} kg.
{'' if not quick else '(quick mode: coarse grids)'}

![max load](design_max_load.png)
"""
    arts = [*study.figures().items(), ("design_table_A1.csv", ta1)]
    return Section("Design of the arm (thesis chapter 2)", md, arts, dict(study.metrics))
