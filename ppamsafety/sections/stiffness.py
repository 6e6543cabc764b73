"""Influence of the joint stiffness on the impact force (thesis §6.3.4, fig. 6.3).

The PID step-response impact (instant of largest TCP speed) is repeated with
both joint stiffnesses set to k, for the two named motor-side conventions of
the impact model (:class:`~ppamsafety.impact.engine.JointModel`):

* **frozen equilibrium** -- the springs pull towards q(t0) and their far end
  never moves (pressures held: the PPAM's own physics at its own stiffness);
* **flexible joint** (Spong; De Luca and Book, the source the thesis cites for
  its stiffness range) -- a motor-side inertia B moving with the link at t0,
  for several B, and its exact limit k -> infinity, the **rigid** arm of
  inertia H + diag(B).

The sweep runs from 1 Nm/rad to beyond 1e6 Nm/rad, each point with an
integration step that resolves its spring (:func:`_step_for`), so every
answer is physically sane at every stiffness: the energy balance is reported
per point.  The motor-side inertia that reproduces fig. 6.3 is fitted from
the rise F_max(6000) - F_max(1) against B.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..control import PID
from ..experiments.catalog import run_thesis_experiment
from ..impact import engine as eng
from ..impact.instants import heuristic_instants, impact_states
from ..impact.model import (effective_mass, flexible_stiffness_limit, simulate_impacts,
                            stiffness_limit)
from ..impact.thesis_data import FIG_6_3
from ..impact.twobody import two_body_impact
from ..markdown import markdown_table
from ..plant import dynamics as dyn
from ..plant import geometry as geo
from ..plots.impact import plot_stiffness_conventions
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm, resolve_head_model)
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (measured 2026-11-23), the order a first report starts the sections in.
SECTION = SectionInfo(
    summary=("joint stiffness sweep: the motor-side conventions (frozen equilibrium, Spong "
             "flexible joint, rigid limit) against fig. 6.3"),
    thesis="§6.3.4, fig. 6.3", typical_seconds=1.4)

#: Mass of one PPAM [kg]: "the low mass of the PPAMs (around 150 g)", thesis §2.3.1.3.
PPAM_MASS = 0.150
#: Base integration step of the sweep [s] (the impact engine's default).
DT0 = 2e-5
#: Integrator of the sweep (:func:`~ppamsafety.impact.model.simulate_impacts`).
INTEGRATOR = "fixed"
#: Motor-side inertias of the flexible-joint sweep [kg m^2] besides the PPAM drive's (0)
#: and the PPAM muscles' upper bound (:func:`ppam_motor_inertia_bound`).
B_SWEEP = (0.01, 0.1, 1.0)
#: Motor-side inertias of the fit of fig. 6.3 [kg m^2] (full mode; quick: every third).
B_FIT = tuple(np.geomspace(1e-4, 1e2, 13))
#: Stiffnesses [Nm/rad] beyond the sweep's 1e6 that show the rigid limit (full mode).
K_RIGID_CHECK = (1e7,)


def ppam_motor_inertia_bound(q, arm) -> np.ndarray:
    """Upper bound of the motor-side inertia of the PPAM drive per joint [kg m^2].

    B_j <= sum over the muscle groups k of joint j of n_k m_PPAM r_k(q)^2: the
    whole mass of every muscle (n_k PPAMs of :data:`PPAM_MASS`, thesis
    §2.3.1.3 and Table B.1's n_m) moving at its attachment's speed r_k qd_j
    (lever arm r_k, (A.1)-(A.4)).  An overestimate twice over: a muscle's
    fixed end does not move, and its moving end is attached rigidly to the
    link (the compliance of a PPAM is its gas, not a part between the
    muscle's mass and the link), so that mass is link-side inertia and is
    already in H.  Behind the gas spring there is only the pressure supply,
    which has no inertia: the PPAM drive's motor-side inertia is 0.

    Parameters
    ----------
    q : array_like, shape (2,)
        Joint angles [rad].
    arm : ArmParameters
        Geometry (lever arms) and muscle groups.

    Returns
    -------
    numpy.ndarray, shape (2,)
        B_1, B_2 [kg m^2].
    """
    r = np.asarray(geo.lever_arms(np.asarray(q, dtype=float), arm), dtype=float)
    n = np.array([g.n_muscles for g in arm.muscles.groups], dtype=float)
    b = PPAM_MASS * n * r ** 2
    return np.array([b[0] + b[1], b[2] + b[3]])


def _step_for(limit_at_dt0: float, k: float) -> float:
    """Largest step DT0 / 2^m whose stiffness limit (scaling as 1/step^2) admits ``k``."""
    if not k > limit_at_dt0:
        return DT0
    m = math.ceil(math.log2(math.sqrt(k / limit_at_dt0) * 1.0001))
    return DT0 / 2.0 ** m


def _sweep(arm, q, qd, head, ks, joint_model, B=None, integrator=None) -> pd.DataFrame:
    """F_max etc. at every stiffness of ``ks`` for one convention, each at a resolving step."""
    ks = np.asarray(ks, dtype=float)
    if joint_model == "frozen-equilibrium":
        lim = float(stiffness_limit(q, arm, eng.FREE_STRIDE * DT0))
    elif joint_model == "flexible-joint":
        lim = float(flexible_stiffness_limit(q, B, arm, eng.FREE_STRIDE * DT0))
    else:
        lim = math.inf
    dts = np.array([_step_for(lim, k) for k in ks])
    cols = ["F_max", "HIC36", "E_balance_error", "contact_time"]
    vals = np.full((ks.size, len(cols)), np.nan)
    kw = {} if B is None else {"motor_inertia": B}
    for dt in np.unique(dts):
        sel = np.nonzero(dts == dt)[0]
        kk = ks[sel]
        r = simulate_impacts(arm, np.tile(q, (kk.size, 1)), np.tile(qd, (kk.size, 1)),
                             np.stack([kk, kk], 1), head=head, dt=float(dt),
                             joint_model=joint_model, integrator=integrator or INTEGRATOR,
                             **kw).summary
        vals[sel] = r[cols].to_numpy()
    out = pd.DataFrame(vals, columns=cols)
    out.insert(0, "dt", dts)
    out.insert(0, "k", ks)
    return out


@dataclass
class StiffnessFindings(Result):
    """Result of :func:`compute`: F_max of one impact against the joint stiffness.

    Attributes
    ----------
    quick : bool
        Fewer stiffnesses and motor-side inertias.
    instant : pandas.Series
        Impact state (row of :func:`~ppamsafety.impact.instants.impact_states`)
        at the PID step's instant of largest TCP speed.
    tool_speed : float
        Tool speed at that instant [m/s].
    sweep : pandas.DataFrame
        Long table: ``convention`` (``"frozen-equilibrium"``,
        ``"flexible-joint"``, ``"rigid"``), ``B`` [kg m^2] (both joints; inf for
        the frozen equilibrium, whose anchor is an infinite motor-side inertia at
        rest; the PPAM bound as its joint-1 value), ``B_label``, ``k`` [Nm/rad] (inf for rigid), ``dt`` [s],
        ``F_max`` [N], ``HIC36``, ``E_balance_error`` [-], ``contact_time``
        [s], ``dF vs k=1 [N]``, ``F/F_thesis`` (ratio to the level of fig. 6.3,
        Table 6.1's 1524 N).
    by_stiffness : pandas.DataFrame
        F_max [N] with k as rows and one column per convention / B (the
        last row, k = inf, the rigid limit), and the largest
        |E_balance_error| of the row.
    fit : pandas.DataFrame
        ``B`` [kg m^2], ``F_k1``, ``F_k6000`` [N], ``rise [N]``, ``rise [%]``
        of the flexible-joint model.
    B_ppam : numpy.ndarray
        Upper bound of the PPAM drive's motor-side inertia per joint
        (:func:`ppam_motor_inertia_bound`) [kg m^2].
    rigid : pandas.DataFrame
        Per B: ``F_rigid`` (rigid mode), ``F_two_body`` (two-body impact with
        the effective mass of H + diag(B)), ``F_flex_kmax`` (flexible joint at
        the largest k) [N] and their relative differences.
    m_eff, m_link2 : float
        Effective mass at the tool along the impact direction, and that of
        the forearm alone (joint 1 locked) [kg].
    f_two_body : float
        Two-body F_max with ``m_eff`` [N].
    contact : float
        Contact duration at the experiment's stiffness (frozen equilibrium) [s].
    periods : dict
        Joint stiffness [Nm/rad] (the sweep's largest, 1e6) or ``"experiment"`` (the larger
        of the experiment's own K1, K2 at the impact instant) -> shortest vibration period of
        the links on frozen springs [s].
    metrics : dict
        Headline numbers.
    thesis : bool
        Fig. 6.3's values apply: the thesis arm and head.
    arm : ArmParameters or None
        The arm.
    head : HeadContactModel or None
        The head model.
    """

    quick: bool
    instant: pd.Series
    tool_speed: float
    sweep: pd.DataFrame
    by_stiffness: pd.DataFrame
    fit: pd.DataFrame
    B_ppam: np.ndarray
    rigid: pd.DataFrame
    m_eff: float
    m_link2: float
    f_two_body: float
    contact: float
    periods: dict
    metrics: dict = field(default_factory=dict)
    thesis: bool = True
    arm: object = None
    head: object = None

    def to_pandas(self) -> pd.DataFrame:
        """The stiffness sweep (long table, one row per convention, B and k)."""
        return self.sweep.copy()

    def figures(self) -> dict:
        """The section's figures, ``{file name: Figure}``."""
        return {"stiffness_sweep.png": plot_stiffness_conventions(
            self.sweep, thesis=FIG_6_3 if self.thesis else None,
            reference=tuple(self.instant[["K1", "K2"]]))}


@checked_compute
def compute(*, quick: bool = False, arm=None, head=None) -> StiffnessFindings:
    """Sweep both joint stiffnesses for the step-response impact, for each motor-side convention.

    Parameters
    ----------
    quick : bool
        7 stiffnesses from 1 to 1e6 Nm/rad, 2 motor-side inertias besides the
        PPAM's, 5 in the fit, no points beyond 1e6 (full mode: 23
        stiffnesses and 1e7, 13 inertias in the fit).
    arm : ppamsafety.params.ArmParameters, optional
        Arm (default: the thesis arm).
    head : HeadContactModel, optional
        Head model (default ``thesis-frontal``).  Fig. 6.3's values (the ratio column,
        the fit of B to its bound) apply to the thesis arm and head only.

    Returns
    -------
    StiffnessFindings
        Sweep tables, fit of B, rigid limits, effective masses and metrics.
    """
    thesis = compares_to_thesis(arm, head)
    arm = resolve_arm(arm)
    head = resolve_head_model(head)
    res = run_thesis_experiment(arm, "step", [("PID", PID())])[0]
    st = impact_states(res, arm)
    row = st.iloc[heuristic_instants(st)["max TCP speed"]]
    q = row[["q1", "q2"]].to_numpy(float)
    qd = row[["qd1", "qd2"]].to_numpy(float)
    kmin, kmax = FIG_6_3["k_min"], FIG_6_3["k_max"]
    if quick:
        ks = np.array([kmin, 10.0, 100.0, 1000.0, kmax, 1e5, 1e6])
        b_sweep, b_fit, k_far = B_SWEEP[1:], B_FIT[::3], ()
    else:
        ks = np.unique(np.concatenate([np.geomspace(kmin, kmax, 16), np.geomspace(kmax, 1e6, 8)]))
        b_sweep, b_fit, k_far = B_SWEEP, B_FIT, K_RIGID_CHECK
    ks_all = np.concatenate([ks, k_far])
    B_ppam = ppam_motor_inertia_bound(q, arm)
    F_ref = FIG_6_3["F_level_N"]

    parts = []
    fr = _sweep(arm, q, qd, head, ks_all, "frozen-equilibrium")
    # the frozen anchor is a motor side of infinite inertia at rest: B = inf
    parts.append(fr.assign(convention="frozen-equilibrium", B=np.inf, B_label="frozen"))
    b_list = [(np.zeros(2), "B = 0 (PPAM)"), (B_ppam, "B = PPAM bound")] + \
        [(np.full(2, b), f"B = {b:g}") for b in b_sweep]
    rig_rows = []
    v = geo.jacobian(q, arm) @ qd
    speed = float(np.linalg.norm(v))
    u = v / speed
    for B, label in b_list:
        fl = _sweep(arm, q, qd, head, ks_all, "flexible-joint", B)
        parts.append(fl.assign(convention="flexible-joint", B=B[0], B_label=label))
        rg = _sweep(arm, q, qd, head, [math.inf], "rigid", B)
        parts.append(rg.assign(convention="rigid", B=B[0], B_label=label))
        m_r = float(effective_mass(q, u, arm, motor_inertia=B))
        f_tb = float(two_body_impact([speed], arm_mass=m_r, head_mass=head.mass,
                                     stiffness=head.stiffness, exponent=head.exponent,
                                     damping=head.damping)["F_max"][0])
        f_r, f_far = float(rg.F_max.iloc[0]), float(fl.F_max.iloc[-1])
        rig_rows.append({"B_label": label, "B1": B[0], "B2": B[1], "m_eff": m_r, "F_rigid": f_r,
                         "F_two_body": f_tb, "two-body/rigid - 1": f_tb / f_r - 1.0,
                         "k_max": float(ks_all[-1]), "F_flex_kmax": f_far,
                         "flex(k_max)/rigid - 1": f_far / f_r - 1.0})
    sweep = pd.concat(parts, ignore_index=True)
    f1 = sweep[sweep.k == kmin].set_index("B_label").F_max
    sweep["dF vs k=1 [N]"] = sweep.F_max - sweep.B_label.map(f1)
    sweep["F/F_thesis"] = sweep.F_max / F_ref
    sweep = sweep[["convention", "B_label", "B", "k", "dt", "F_max", "dF vs k=1 [N]",
                   "F/F_thesis", "HIC36", "E_balance_error", "contact_time"]]
    if not thesis:
        sweep = sweep.drop(columns=["F/F_thesis"])
    rigid = pd.DataFrame(rig_rows)

    # wide table: k rows, one F_max column per convention; rigid limit as k = inf
    wide = sweep.assign(col=np.where(sweep.convention == "frozen-equilibrium", "frozen",
                                     "flexible, " + sweep.B_label))
    table = wide.pivot_table(index="k", columns="col", values="F_max", sort=False)
    order = ["frozen"] + [f"flexible, {lab}" for _, lab in b_list]
    table = table[order]
    table["max |E error|"] = wide.assign(a=wide.E_balance_error.abs()).groupby("k").a.max()
    table = table.reset_index()

    # fit of B to fig. 6.3: the rise F_max(6000) - F_max(1) of the flexible-joint model
    fit_rows = []
    for b in b_fit:
        r = _sweep(arm, q, qd, head, [kmin, kmax], "flexible-joint", np.full(2, b))
        fit_rows.append({"B": b, "F_k1": r.F_max[0], "F_k6000": r.F_max[1],
                         "max |E error|": float(r.E_balance_error.abs().max())})
    fit = pd.DataFrame(fit_rows)
    fit["rise [N]"] = fit.F_k6000 - fit.F_k1
    fit["rise [%]"] = 100.0 * fit["rise [N]"] / fit.F_k1
    target = 100.0 * FIG_6_3["max_change_rel"]
    i_fit = int(np.argmin(np.abs(fit["rise [%]"] - target)))
    rise_sat = float(fit["rise [N]"].iloc[-1])
    above = np.nonzero(fit["rise [N]"].to_numpy() >= 0.9 * rise_sat)[0]
    j = int(above[0])
    if j > 0:            # log-linear interpolation of the 90 % point
        r0, r1 = fit["rise [N]"].iloc[j - 1], fit["rise [N]"].iloc[j]
        t = (0.9 * rise_sat - r0) / (r1 - r0)
        b90 = float(10 ** (np.log10(fit.B.iloc[j - 1]) + t * np.log10(fit.B.iloc[j] / fit.B.iloc[j - 1])))
    else:
        b90 = float(fit.B.iloc[0])

    own = simulate_impacts(arm, q, qd, row[["K1", "K2"]].to_numpy(float), head=head)
    m_eff = float(effective_mass(q, u, arm))
    f_two = float(two_body_impact([speed], arm_mass=m_eff, head_mass=head.mass,
                                  stiffness=head.stiffness, exponent=head.exponent,
                                  damping=head.damping)["F_max"][0])
    J = geo.jacobian(q, arm)
    H = dyn.inertia_matrix(q, arm)
    m_link2 = float(1.0 / (u @ np.outer(J[:, 1], J[:, 1]) @ u / H[1, 1]))
    contact = float(own.summary.contact_time.iloc[0])
    lam = float(min(np.linalg.eigvalsh(H)))
    # the experiment's own stiffness at the impact instant (the arm's pressures, (2.18))
    k_exp = float(max(row.K1, row.K2))
    periods = {kk: 2 * math.pi * math.sqrt(lam / kk) for kk in (kmax, 1e6)}
    periods["experiment"] = 2 * math.pi * math.sqrt(lam / k_exp)

    def at(conv, label, k):
        s = sweep[(sweep.convention == conv) & (sweep.B_label == label) & (sweep.k == k)]
        return float(s.F_max.iloc[0])

    dF_frozen = at("frozen-equilibrium", "frozen", kmax) - at("frozen-equilibrium", "frozen", kmin)
    dF_ppam = at("flexible-joint", "B = PPAM bound", kmax) - at("flexible-joint", "B = PPAM bound",
                                                                  kmin)
    metrics = {
        "F_k1_N": at("frozen-equilibrium", "frozen", kmin),
        "dF_frozen_6000_N": dF_frozen,
        "F_frozen_1e6_N": at("frozen-equilibrium", "frozen", 1e6),
        "F_frozen_kmax_N": float(fr.F_max.iloc[-1]),
        "dF_flexible_B0_6000_N": at("flexible-joint", "B = 0 (PPAM)", kmax)
        - at("flexible-joint", "B = 0 (PPAM)", kmin),
        "dF_flexible_Bppam_6000_N": dF_ppam,
        "rise_saturation_N": rise_sat,
        "B_90_kgm2": b90,
        "B_fit_kgm2": float(fit.B.iloc[i_fit]),
        "fit_residual_N": float(fit["rise [N]"].iloc[i_fit] - FIG_6_3["max_change_N"]),
        "fit_residual_pct_points": float(fit["rise [%]"].iloc[i_fit] - target),
        "B_ppam_1_kgm2": float(B_ppam[0]), "B_ppam_2_kgm2": float(B_ppam[1]),
        "max_abs_energy_error": float(sweep.E_balance_error.abs().max()),
        "max_rigid_two_body_rel": float(rigid["two-body/rigid - 1"].abs().max()),
        "max_flex_kmax_rigid_rel": float(rigid["flex(k_max)/rigid - 1"].abs().max()),
        "m_eff": m_eff, "F_two_body": f_two, "contact_ms": 1e3 * contact,
    }
    if not thesis:
        for k in ("B_fit_kgm2", "fit_residual_N", "fit_residual_pct_points"):
            metrics.pop(k)
    return StiffnessFindings(quick=quick, instant=row, tool_speed=speed, sweep=sweep, by_stiffness=table,
                          fit=fit, B_ppam=B_ppam, rigid=rigid, m_eff=m_eff, m_link2=m_link2,
                          f_two_body=f_two, contact=contact, periods=periods, metrics=metrics,
                          thesis=thesis, arm=arm, head=head)


def render(study: StiffnessFindings) -> Section:
    """The report section of the stiffness study (formatting only).

    Parameters
    ----------
    study : StiffnessFindings
        Output of :func:`compute`.

    Returns
    -------
    Section
        Markdown and artifacts (figure, ``stiffness_sweep.csv``,
        ``stiffness_table.csv``, ``stiffness_fit.csv``, ``stiffness_rigid.csv``).
    """
    if not study.thesis:
        return _render_other(study)
    row, m, per = study.instant, study.metrics, study.periods
    F_ref = FIG_6_3["F_level_N"]
    tab = study.by_stiffness.copy()
    tab["k"] = [("inf (rigid)" if not np.isfinite(k) else f"{k:.4g}") for k in tab.k]
    frozen_ratio = tab["frozen"] / F_ref
    tab.insert(2, "frozen / 1524 N", frozen_ratio)
    bp = study.B_ppam
    fit = study.fit.copy()
    md = f"""The PID step-response impact (instant of largest TCP speed, t0 = {row.t:.3f} s, tool speed
{study.tool_speed:.2f} m/s) repeated with both joint stiffnesses set to k (fig. 6.3), for the two
named conventions of what holds the springs' far ("motor") side during the impact
(`ppamsafety.impact.JointModel`, `simulate_impacts(..., joint_model=, motor_inertia=)`):

* **frozen equilibrium** (the default, and the PPAM's own physics): the pressures are held, so the
  antagonistic pair is a gas spring anchored at the link's equilibrium q(t0), which never moves;
* **flexible joint** (Spong; De Luca and Book, whom the thesis cites for its stiffness range): a
  motor-side inertia B, moving with the link at t0, behind each spring
  (H q'' + C q' + K (q - theta) = J^T f, B theta'' + K (theta - q) = 0, theta(t0) = q(t0),
  theta'(t0) = q'(t0)); its limit k -> inf is the **rigid arm** of inertia H + diag(B), also
  simulated exactly (`joint_model="rigid"`, the row k = inf).

**The motor side of a PPAM pair.** The compliance of a PPAM is its gas; the muscle's moving end is
bolted to the link, so the muscles' own mass is link-side inertia (already in H), and behind the gas
there is only the pressure supply, which has no inertia: the PPAM drive's motor-side inertia is 0.
Counting every muscle (n = 4, 3, 4, 3 PPAMs of {PPAM_MASS * 1e3:.0f} g, §2.3.1.3) as if it moved at its
attachment's speed gives the upper bound B = {bp[0]:.2e}, {bp[1]:.2e} kg m^2, 1.5 % of the forearm's
inertia. With B = 0 the spring can never be loaded: the joint is free, and F_max is that of the rigid
links at every k.

Every point is integrated with a step that resolves its spring (20 steps per period at the largest
step; column `dt` of `stiffness_sweep.csv`); the largest energy-balance error of the whole sweep is
{m['max_abs_energy_error']:.1e}.

F_max [N] against k (both joints; last column: largest |energy-balance error| of the row; the
thesis' level is Table 6.1's {F_ref:.0f} N, ratio in the third column):

{markdown_table(tab, digits=5)}

* **Frozen equilibrium:** F_max *falls* by {-m['dF_frozen_6000_N']:.1f} N from 1 to 6000 Nm/rad (the thesis:
  *rises* by less than 5 N), and keeps falling -- {m['F_frozen_1e6_N']:.0f} N at 1e6 Nm/rad and
  {m['F_frozen_kmax_N']:.0f} N at the largest k -- because the spring clamps the link to q(t0): the link's
  kinetic energy goes into a spring that stops it within q'/omega (smallest period
  {1e3 * per[1e6]:.2f} ms at 1e6 Nm/rad, against a contact of {1e3 * study.contact:.1f} ms). That is the
  correct limit of this convention (a link clamped in place), not a stiffer actuator: a stiff joint's
  motor moves with its link.
* **Flexible joint:** F_max *rises* with k, from the links' free impact (k -> 0) towards the rigid arm
  H + diag(B) (k -> inf), and never falls to 0. For B = 0 (the PPAM drive) it is the rigid links' value
  at every k (change {m['dF_flexible_B0_6000_N']:.2g} N); for the PPAM bound it rises by
  {m['dF_flexible_Bppam_6000_N']:.2f} N up to 6000 Nm/rad.
* **Which convention reproduces fig. 6.3:** the flexible joint, for every B: its rise from 1 to
  6000 Nm/rad is positive and below the thesis' 5 N (0.33 %) for every motor-side inertia; it grows with
  B and saturates at {m['rise_saturation_N']:.2f} N (the motor side a constant-speed source); it reaches
  90 % of that from B = {m['B_90_kgm2']:.2g} kg m^2 on. A least-squares fit of B to the printed bound (0.33 %)
  runs to the largest B of the grid ({m['B_fit_kgm2']:.3g} kg m^2) with residual
  {m['fit_residual_N']:+.2f} N ({m['fit_residual_pct_points']:+.3f} percentage points): the thesis' "less than
  5 N" is met, its 5 N is not reached by any B. The frozen equilibrium cannot reproduce it at any
  setting (wrong sign, {-m['dF_frozen_6000_N'] / FIG_6_3['max_change_N']:.0f}x the bound).

Fit of B (flexible joint, rise of F_max from 1 to 6000 Nm/rad):

{markdown_table(fit, digits=4)}

Rigid limit (per B): the rigid mode against a two-body impact with the effective mass of
H + diag(B) (a one-dimensional check; the arm's configuration change during the contact is the
difference) and the flexible joint at the largest k:

{markdown_table(study.rigid.drop(columns=["B2"]), digits=4)}

* **Why the change is small at PPAM stiffnesses:** the impact lasts {1e3 * study.contact:.1f} ms, far
  shorter than the arm's vibration on its joint springs (smallest period
  {1e3 * per["experiment"]:.0f} ms at the experiment's K = {row.K1:.4g}/{row.K2:.4g} Nm/rad at the impact
  instant), so the tool behaves like the links' effective mass at the tool,
  m_eff = 1/(u^T J H^-1 J^T u) = {study.m_eff:.3f} kg (forearm alone: {study.m_link2:.3f} kg); a two-body
  impact of that mass gives {study.f_two_body:.1f} N, against {m['F_k1_N']:.1f} N for the full model at
  k = 1 Nm/rad, and {m['F_k1_N'] / F_ref:.3f} of the thesis' {F_ref:.0f} N.

![stiffness sweep](stiffness_sweep.png)
"""
    arts = [("stiffness_sweep.csv", study.sweep), ("stiffness_table.csv", study.by_stiffness),
            ("stiffness_fit.csv", study.fit), ("stiffness_rigid.csv", study.rigid),
            *study.figures().items()]
    return Section("Joint stiffness, motor-side conventions and the rigid limit (thesis §6.3.4)",
                   md, arts, dict(m))


def _render_other(study: StiffnessFindings) -> Section:
    """The stiffness section for another arm or head: its own numbers, no fig. 6.3 values."""
    row, m, per = study.instant, study.metrics, study.periods
    tab = study.by_stiffness.copy()
    tab["k"] = [("inf (rigid)" if not np.isfinite(k) else f"{k:.4g}") for k in tab.k]
    bp = study.B_ppam
    md = f"""{other_arm_note(study.arm, study.head)}

The PID step-response impact (instant of largest TCP speed, t0 = {row.t:.3f} s, tool speed
{study.tool_speed:.2f} m/s) repeated with both joint stiffnesses set to k, for the frozen-equilibrium
convention (pressures held: the PPAM's own physics) and the flexible joint with motor-side inertia B
(`simulate_impacts(..., joint_model=, motor_inertia=)`; PPAM drive: B = 0, upper bound from the
muscles' masses B = {bp[0]:.2e}, {bp[1]:.2e} kg m^2); k = inf is the rigid arm. Largest
energy-balance error of the sweep: {m['max_abs_energy_error']:.1e}.

F_max [N] against k (last column: largest |energy-balance error| of the row):

{markdown_table(tab, digits=5)}

* Frozen equilibrium: F_max changes by {m['dF_frozen_6000_N']:+.1f} N from 1 to 6000 Nm/rad and is
  {m['F_frozen_1e6_N']:.0f} N at 1e6 Nm/rad (the spring clamps the link to q(t0)).
* Flexible joint: F_max rises towards the rigid arm; with the PPAM bound by
  {m['dF_flexible_Bppam_6000_N']:.2f} N up to 6000 Nm/rad; it saturates at {m['rise_saturation_N']:.2f} N
  for a large motor-side inertia (90 % from B = {m['B_90_kgm2']:.2g} kg m^2).
* The impact lasts {1e3 * study.contact:.1f} ms, against the arm's shortest vibration period on its
  joint springs of {1e3 * per["experiment"]:.0f} ms at the experiment's K = {row.K1:.4g}/{row.K2:.4g} Nm/rad
  at the impact instant: the tool behaves like the links' effective
  mass m_eff = {study.m_eff:.3f} kg (two-body impact {study.f_two_body:.1f} N, full model at k = 1 Nm/rad
  {m['F_k1_N']:.1f} N).

Rise of F_max from 1 to 6000 Nm/rad against B (flexible joint):

{markdown_table(study.fit, digits=4)}

![stiffness sweep](stiffness_sweep.png)
"""
    arts = [("stiffness_sweep.csv", study.sweep), ("stiffness_table.csv", study.by_stiffness),
            ("stiffness_fit.csv", study.fit), ("stiffness_rigid.csv", study.rigid),
            *study.figures().items()]
    return Section("Joint stiffness, motor-side conventions and the rigid limit (thesis §6.3.4)",
                   md, arts, dict(m))
