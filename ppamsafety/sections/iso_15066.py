"""Clamping and ISO/TS 15066 power and force limiting for the head (thesis §6.3.5,
ISO/TS 15066:2016 Annex A).

What a safety assessor preparing an ISO/TS 15066 argument for this arm needs:

1. **Limits** (:mod:`ppamsafety.params.iso_ts_15066`): skull/forehead and face,
   quasi-static and transient forces, transfer energies E = F^2/(2K) and the
   largest permissible relative speeds v = F / sqrt(mu K), with the robot's
   effective mass from Annex A.4 (M/2) and from the arm's own apparent mass.
2. **Free transient contact** for every controller variant and a lambda grid per
   PSMC family: the closed-loop step and trajectory-switch experiments, the
   worst impact over the four instants of §6.3.3 against the ISO linear
   head regions (K, m_H = 4.4 kg) and the thesis Hunt-Crossley head; the
   smallest lambda that keeps the worst force below each limit (F_max falls
   with lambda, so the limit bounds lambda from *below*).
3. **Transient clamping**: the same worst states, head pinned against a wall
   (:func:`ppamsafety.impact.clamping.simulate_clamping`), clamped vs free.
4. **Quasi-static clamping**: (a) the exact static bound of the force the
   muscles can press at any configuration and direction of the working area
   (hardware pressures 0..p_max, and the Delta-p approach); (b) the closed loop:
   the step experiment with the head pinned where the tool passes at its
   largest speed -- a stiff spring-damper (:class:`~ppamsafety.experiments.interaction.Hand`)
   holds the tool there from that instant to the end of the run (about 9.8 s) while the controller keeps
   pushing toward its set point; the steady force (PID integral wind-up, PSMC
   bounded coupling).
5. **Linear spring vs Hunt-Crossley**: the standard's F = v sqrt(mu K) against the
   thesis head model at the same speeds.

Named assumptions are in :data:`ASSUMPTIONS` and rendered in the report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..control import PID, JointPSMC, TaskPSMC
from ..experiments import trajectories as tr
from ..experiments.trajectories import experiment_references
from ..experiments.case import ExperimentCase
from ..experiments.catalog import ControllerVariant, run_thesis_experiment, thesis_variants
from ..experiments.closed_loop import run_batch
from ..experiments.interaction import Hand
from ..impact.clamping import simulate_clamping, static_force_bound
from ..impact.head import head_model
from ..impact.instants import heuristic_instants, impact_states
from ..impact.model import effective_mass, simulate_impacts
from ..impact.pfl import (linear_peak_force, reduced_mass, region_limits,
                          robot_effective_mass_annex_a)
from ..impact.verdicts import annex_a_head, criteria_for, describe_head, evaluate
from ..impact.thesis_data import table_6_1
from ..impact.twobody import two_body_impact
from ..markdown import markdown_table
from ..params.iso_ts_15066 import FACE, SKULL_FOREHEAD, THESIS_ARM_MASS
from ..plant.geometry import jacobian
from ..plots import iso as f
from ..units import BAR, DEG
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm, resolve_head_model)
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (measured 2026-11-23), the order a first report starts the sections in.
SECTION = SectionInfo(
    summary=("clamping and ISO/TS 15066: head pinned against a wall (transient, quasi-static), "
             "Annex A limits, transfer energy, maximum speed and lambda per PSMC family"),
    thesis="§6.3.5, ISO/TS 15066:2016 Annex A", typical_seconds=4.9)

REGIONS = (SKULL_FOREHEAD, FACE)
EXPERIMENTS = ("step", "switch")
#: PSMC families of the lambda search: (label, factory(lam) -> controller).
FAMILIES = (("PSMC joint Ki=2", lambda lam: JointPSMC(lam=lam, ki=2.0 * BAR)),
            ("PSMC joint Ki=12", lambda lam: JointPSMC(lam=lam, ki=12.0 * BAR)),
            ("PSMC task", lambda lam: TaskPSMC(lam=lam)))
LAMBDAS_FULL = (0.1, 0.2, 0.3, 0.4, 0.6, 0.8, 1.5, 2.5)
LAMBDAS_QUICK = (0.4, 0.8, 1.5)
#: Quasi-static closed loop: stiffness of the tool-head and head-wall springs in series
#: (skull/forehead 150 N/mm each, ISO/TS 15066 Table A.3) [N/m] and a damping [N s/m].
CLAMP_SPRING = 1.0 / (2.0 / SKULL_FOREHEAD.spring_constant)
CLAMP_DAMPING = 300.0
#: Quasi-static run: up-step at 2 s, no down-step, 12 s; RK4 substeps per 1 ms period.
QS_DURATION, QS_T_UP, QS_SUBSTEPS = 12.0, 2.0, 5
#: Quick mode: 7 s (about 4.8 s of clamping).
QS_DURATION_QUICK = 7.0

ASSUMPTIONS = (
    "Limits are ISO/TS 15066:2016 Annex A values for skull/forehead (130 N, 150 N/mm) and face "
    "(65 N, 75 N/mm), head effective mass 4.4 kg; the force limits, pressures and 4.4 kg could "
    "not be confirmed against a stored copy of the TS (see ppamsafety.params.iso_ts_15066).",
    "Transient limit = 2 x quasi-static (the Table A.2 multiplier of the other regions, applied "
    "to the head too). Our reading of the TS is that it gives no transient allowance for the "
    "head; every verdict is also stated against the quasi-static force (factor 1).",
    "Robot effective mass: Annex A.4 m_R = M/2 + m_L with M = {mass}, m_L = 0; "
    "and the arm's own apparent mass 1/(u^T J H^-1 J^T u) along the impact direction.",
    "Free transient contact: the thesis impact model (flexible joints, horizontal plane, 50 ms) "
    "at the four instants of §6.3.3 (worst reported); ISO head = linear undamped spring K with "
    "a 4.4 kg free head.",
    "Transient clamping: the head's back touches a rigid frictionless wall perpendicular to the "
    "tool velocity (worst orientation); wall contact = skull spring 150 N/mm (ISO heads) or the "
    "{head}.",
    "Quasi-static clamping, closed loop: the tool is held where it passes at its largest speed in "
    "the {step} step by an isotropic spring-damper (75 N/mm = two 150 N/mm skull springs in "
    "series, 300 N s/m; head mass neglected) until the end of the 12 s run; the contact force is its magnitude "
    "(normal and tangential parts listed). Transient peaks of this run are not used (massless "
    "head, 1 ms zero-order hold of the force).",
    "Quasi-static bound: exact maximum of the static tool force over muscle pressures in "
    "[0, {p_max}] (or the Delta-p approach at the {mean_pressures}), gravity of the "
    "vertical plane included, over a 25 x 25 grid of the working area and 72 directions.",
)


def assumptions(arm=None, head=None) -> list:
    """The :data:`ASSUMPTIONS` for an arm and head: the robot mass, the largest muscle
    pressure, the mean pressures and the Hunt-Crossley head are the arm's and head's own.

    Parameters
    ----------
    arm : ArmParameters, optional
        The arm (default the thesis arm).
    head : HeadContactModel, optional
        The Hunt-Crossley head beside the ISO heads (default ``thesis-frontal``).

    Returns
    -------
    list of str
    """
    a = resolve_arm(arm)
    hc = resolve_head_model(head)
    if compares_to_thesis(a):
        mass = f"{THESIS_ARM_MASS:g} kg (thesis §6.3.5)"
        means = "calibrated mean pressures"
    else:
        mass = f"{_robot_mass(a):.3g} kg (the arm's link masses plus payload)"
        means = ("arm's mean pressures " + ", ".join(f"{p / BAR:.4g}" for p in
                                                     a.pneumatics.p_mean) + " bar")
    hd = ("thesis Hunt-Crossley fit (checked on the Hybrid III drop onto a rigid plate)"
          if hc == head_model() else f"Hunt-Crossley contact of head model `{hc.name}`")
    refs = experiment_references(a)
    step = (f"{np.degrees(refs.step_low):.4g}->{np.degrees(refs.step_high):.4g} deg"
            + ("" if refs.thesis else f" (q2_d {np.degrees(refs.step_q2):.4g} deg; {refs.origin})"))
    return [t.format(mass=mass, head=hd, p_max=f"{a.pneumatics.p_max / BAR:g} bar",
                     mean_pressures=means, step=step) for t in ASSUMPTIONS]


def _robot_mass(arm) -> float:
    """Annex A's total robot mass M of an arm that is not the thesis arm [kg]: its link masses
    plus payload."""
    return arm.links.m1 + arm.links.m2 + arm.effects.payload_mass


def _variants(lams):
    out = [ControllerVariant.of(PID())]
    for _, make in FAMILIES:
        out += [ControllerVariant.of(make(lam)) for lam in lams]
    return out


def _iso_head(region):
    """The Annex A body model of a region (the verdicts' own, :func:`annex_a_head`)."""
    return annex_a_head(region)


#: Label of the Hunt-Crossley head beside the ISO heads: the thesis head, or the report's.
HC_LABEL = "thesis HC"


def _free_impacts(arm, lams, hc=None, hc_label=HC_LABEL):
    """Worst heuristic-instant impacts per variant, experiment and head; the step runs."""
    variants = _variants(lams)
    heads = {"skull/forehead": _iso_head(SKULL_FOREHEAD), "face": _iso_head(FACE),
             hc_label: head_model("thesis-frontal") if hc is None else hc}
    rows, step_runs = [], {}
    for exp in EXPERIMENTS:
        runs = run_thesis_experiment(arm, exp, variants)
        for v, r in zip(variants, runs):
            if exp == "step":
                step_runs[v.label] = r
            st = impact_states(r, arm)
            idx = list(dict.fromkeys(heuristic_instants(st).values()))   # the four instants
            sub = st.iloc[idx]
            for hname, hm in heads.items():
                ev = simulate_impacts(arm, sub[["q1", "q2"]].to_numpy(),
                                      sub[["qd1", "qd2"]].to_numpy(),
                                      sub[["K1", "K2"]].to_numpy(), head=hm).summary
                j = int(np.argmax(ev["F_max"].to_numpy()))
                s = sub.iloc[j]
                rows.append({"experiment": exp, "label": v.label, "family": v.group,
                             "lambda": v.lambda_s, "head_model": hname,
                             "F_max": float(ev["F_max"].iloc[j]), "tcp_speed": float(s.tcp_speed),
                             "t0": float(s.t), "q1": s.q1, "q2": s.q2, "qd1": s.qd1,
                             "qd2": s.qd2, "K1": s.K1, "K2": s.K2})
    return pd.DataFrame(rows), step_runs


def _question(free, hc, hc_label=HC_LABEL):
    """Verdicts of every free impact against the ISO/TS 15066 criteria of its region.

    The forehead criteria for the forehead's Annex A body model and for the Hunt-Crossley
    head (the same question with two head models), the face criteria for the face's body
    model; the rows are :func:`ppamsafety.impact.verdicts.evaluate`'s, as in ``impact``,
    the sweeps and the envelopes.
    """
    heads = {"skull/forehead": (_iso_head(SKULL_FOREHEAD), SKULL_FOREHEAD),
             "face": (_iso_head(FACE), FACE), hc_label: (hc, SKULL_FOREHEAD)}
    rows = []
    for (exp, label, hname), g in free.groupby(["experiment", "label", "head_model"],
                                               sort=False):
        model, region = heads[hname]
        crit = [c for c in criteria_for(region) if c.name.startswith("iso_ts_15066")]
        r = g.iloc[0]
        t = evaluate({"F_max": r.F_max}, crit, head=model.name, region=region.name)
        for v in t.itertuples():
            rows.append({"experiment": exp, "label": label, "family": r.family,
                         "lambda": r["lambda"], "head_model": model.name, "region": v.region,
                         "criterion": v.criterion, "F_max": v.value, "limit": v.limit,
                         "margin": v.margin, "margin_pct": v.margin_pct, "passed": v.passed})
    return pd.DataFrame(rows)


def _worst_per_variant(free):
    """Row of the largest F_max over the experiments, per (label, head)."""
    idx = free.groupby(["label", "head_model"], sort=False)["F_max"].idxmax()
    return free.loc[idx].reset_index(drop=True)


def _lambda_min(lams, F, limit):
    """Smallest lambda [s] at which the grid curve F(lambda) first meets F <= limit.

    Scans the grid from the smallest lambda; the crossing is interpolated
    log-linearly between the last grid point above the limit and the first one
    below.  Returns ``(lambda_min, at_grid_min, admissible)``: NaN if no grid
    lambda meets the limit; ``at_grid_min`` True if the smallest grid lambda
    already does; ``admissible`` the grid lambdas that meet it (F(lambda) need
    not be monotonic: with Ki = 12 the force rises again at large lambda).
    """
    lams, F = np.asarray(lams, float), np.asarray(F, float)
    ok = F <= limit
    adm = " ".join(f"{x:g}" for x in lams[ok])
    if not ok.any():
        return math.nan, False, adm
    i = int(np.argmax(ok))
    if i == 0:
        return float(lams[0]), True, adm
    l0, l1, f0, f1 = math.log(lams[i - 1]), math.log(lams[i]), F[i - 1], F[i]
    return float(math.exp(l0 + (f0 - limit) / (f0 - f1) * (l1 - l0))), False, adm


def _clamping_transient(arm, worst, hc=None, hc_label=HC_LABEL):
    """Clamped vs free F_max at the worst free-impact state of each thesis variant."""
    rows = []
    thesis = {v.label for v in thesis_variants()}
    sub = worst[worst.label.isin(thesis)]
    hc = head_model("thesis-frontal") if hc is None else hc
    setups = {"skull/forehead": (_iso_head(SKULL_FOREHEAD), _iso_head(SKULL_FOREHEAD)),
              "face": (_iso_head(FACE), _iso_head(SKULL_FOREHEAD)),
              hc_label: (hc, hc)}
    hist = {}
    for hname, (hm, wall) in setups.items():
        s = sub[sub["head_model"] == hname]
        res = simulate_clamping(arm, s[["q1", "q2"]].to_numpy(), s[["qd1", "qd2"]].to_numpy(),
                                s[["K1", "K2"]].to_numpy(), head=hm, wall=wall)
        out = res.summary
        for j, (_, r) in enumerate(s.iterrows()):
            rows.append({"label": r.label, "family": r.family, "head_model": hname,
                         "experiment": r.experiment, "tcp_speed": r.tcp_speed,
                         "F_free": r.F_max, "F_clamped": float(out.F_max.iloc[j]),
                         "F_wall": float(out.F_wall_max.iloc[j]),
                         "clamp_ratio": float(out.F_max.iloc[j] / r.F_max),
                         "E_balance_error": float(out.E_balance_error.iloc[j])})
        hist[hname] = (res, list(s.label))
    return pd.DataFrame(rows), hist


def _static_bounds(arm, n_grid, n_dir):
    g = arm.geometry
    q1 = np.linspace(g.q1_min, g.q1_max, n_grid)
    q2 = np.linspace(g.q2_min, g.q2_max, n_grid)
    ang = np.linspace(0.0, 2 * math.pi, n_dir, endpoint=False)
    Q = np.array([(a, b) for a in q1 for b in q2])
    rows = []
    for mode in ("hardware", "delta_p"):
        best = np.full(len(Q), -np.inf)
        best_dir = np.zeros(len(Q))
        for th in ang:
            d = np.array([math.cos(th), math.sin(th)])
            F = static_force_bound(Q, d, arm, mode=mode)["F_u"].to_numpy()
            better = F > best
            best[better], best_dir[better] = F[better], th
        k = int(np.argmax(best))
        rows.append({"mode": mode, "F_max_N": float(best.max()), "F_median_N": float(np.median(best)),
                     "q1_deg": Q[k, 0] / DEG, "q2_deg": Q[k, 1] / DEG,
                     "direction_deg": best_dir[k] / DEG})
        if mode == "hardware":
            field_map = best.reshape(n_grid, n_grid)
    return pd.DataFrame(rows), (q1, q2, field_map)


def _quasi_static(arm, step_runs, duration):
    """Closed-loop clamping during the up-step: steady force per thesis variant.

    The clamping instant is taken from the free step runs (same reference as the
    clamped run until the down-step at 7 s, which the clamped run leaves out).
    """
    ref = tr.step(arm, t_up=QS_T_UP, t_down=duration, duration=duration)
    variants = thesis_variants()
    free = [step_runs[v.label] for v in variants]
    cases, info = [], []
    for v, r in zip(variants, free):
        t, sp = r.t, r.tcp_speed()
        window = (t > QS_T_UP) & (t < min(QS_T_UP + 5.0, ref.t[-1]))
        k0 = int(np.argmax(np.where(window, sp, -1.0)))
        tgt = np.array([r.signal("x")[k0], r.signal("y")[k0]])
        u = np.array([r.signal("xd")[k0], r.signal("yd")[k0]])
        u = u / np.linalg.norm(u)
        hand = Hand(np.tile(tgt, (len(ref.t), 1)), ref.t >= t[k0], stiffness=CLAMP_SPRING,
                    damping=CLAMP_DAMPING)
        cases.append(ExperimentCase(arm, v.controller, ref, hand=hand, name=f"clamped {v.label}"))
        info.append((v, k0, u, np.array([r.signal("q1")[k0], r.signal("q2")[k0]])))
    runs = run_batch(cases, substeps=QS_SUBSTEPS)
    rows, hist = [], {}
    n_end = 500                                   # last 0.5 s
    for (v, k0, u, q0), r in zip(info, runs):
        fx, fy = -r.signal("Fx_ext"), -r.signal("Fy_ext")    # force of the tool on the head
        fmag = np.hypot(fx, fy)
        fn = fx * u[0] + fy * u[1]
        ft = -fx * u[1] + fy * u[0]
        fdir = np.array([fx[-n_end:].mean(), fy[-n_end:].mean()])
        bound_dir = static_force_bound(np.array([r.signal("q1")[-1], r.signal("q2")[-1]]), fdir,
                                       arm)["F_u"].iloc[0]
        k2 = max(k0, len(r.t) - 1 - 2000)
        rows.append({"label": v.label, "family": v.group, "t_clamp": float(r.t[k0]),
                     "F_steady": float(fmag[-n_end:].mean()), "F_normal": float(fn[-n_end:].mean()),
                     "F_tangential": float(np.abs(ft[-n_end:]).mean()),
                     "F_2s_earlier": float(fmag[k2]), "t_hold": float(r.t[-1] - r.t[k0]), "bound_same_dir": float(bound_dir),
                     "dp1_end_bar": float(r.signal("dp1")[-1] / BAR),
                     "dp2_end_bar": float(r.signal("dp2")[-1] / BAR),
                     "tensile_fraction": float(np.mean(fn[k0:] < 0)), "diverged": bool(r.diverged)})
        hist[v.label] = (r.t[k0:] - r.t[k0], fmag[k0:])
    return pd.DataFrame(rows), hist


def _hc_vs_linear(arm, worst, m_r_annex, hc=None, hc_label=HC_LABEL):
    """The standard's linear-spring estimate against the Hunt-Crossley head at equal speeds."""
    v = np.linspace(0.05, 2.0, 40)
    mh = SKULL_FOREHEAD.effective_mass
    th = head_model("thesis-frontal") if hc is None else hc
    hc = two_body_impact(v, arm_mass=m_r_annex, head_mass=mh, stiffness=th.stiffness,
                         exponent=th.exponent, damping=th.damping)["F_max"]
    mu = reduced_mass(mh, m_r_annex)
    curve = pd.DataFrame({"speed": v, "F_linear_forehead": linear_peak_force(v, SKULL_FOREHEAD.spring_constant, mu),
                          "F_linear_face": linear_peak_force(v, FACE.spring_constant, mu),
                          "F_hunt_crossley": hc})
    # at the worst states of the thesis variants: engine vs formula with the own effective mass
    rows = []
    thesis = {x.label for x in thesis_variants()}
    for hname, region in (("skull/forehead", SKULL_FOREHEAD), ("face", FACE)):
        s = worst[(worst["head_model"] == hname) & worst.label.isin(thesis)]
        hcs = worst[(worst["head_model"] == hc_label) & worst.label.isin(thesis)].set_index("label")
        for _, r in s.iterrows():
            q = np.array([r.q1, r.q2])
            vt = jacobian(q, arm) @ np.array([r.qd1, r.qd2])
            m_own = float(effective_mass(q, vt, arm))
            mu_own = reduced_mass(region.effective_mass, m_own)
            rows.append({"label": r.label, "region": hname, "tcp_speed": r.tcp_speed,
                         "m_eff_own": m_own, "F_engine_linear": r.F_max,
                         "F_formula_own_mass": linear_peak_force(r.tcp_speed, region.spring_constant, mu_own),
                         "F_formula_annex_mass": linear_peak_force(r.tcp_speed, region.spring_constant,
                                                                   reduced_mass(region.effective_mass, m_r_annex)),
                         "F_engine_hunt_crossley": float(hcs.loc[r.label, "F_max"])})
    return curve, pd.DataFrame(rows)


@dataclass
class IsoFindings(Result):
    """Result of :func:`compute` (all forces in N, speeds in m/s, masses in kg).

    Attributes
    ----------
    limits : pandas.DataFrame
        Annex A numbers per region, transient factor and robot mass (:func:`region_limits`).
    free : pandas.DataFrame
        Worst free impact per (experiment, variant, head) with its state.
    lambda_table : pandas.DataFrame
        Per PSMC family, region and factor: the smallest admissible lambda [s]
        by the simulated force and by the speed criterion.
    clamp_transient : pandas.DataFrame
        Clamped vs free F_max per thesis variant and head.
    clamp_histories : dict
        Head name -> (ClampingResult, labels).
    static_bounds : pandas.DataFrame
        Largest static force over the working area and directions, per mode.
    static_map : tuple
        (q1 grid, q2 grid, max force over directions (n, n)) for the plot.
    quasi_static : pandas.DataFrame
        Closed-loop clamping per thesis variant.
    qs_histories : dict
        Label -> (time since clamping [s], contact force [N]).
    hc_curve : pandas.DataFrame
        F vs speed: linear forehead/face and Hunt-Crossley two-body.
    hc_states : pandas.DataFrame
        Engine and formula forces at the thesis variants' worst states.
    verdict : pandas.DataFrame
        The thesis's "safe side" claim checked per controller.
    question : pandas.DataFrame
        Every free impact's verdicts against the ISO/TS 15066 criteria of its region, with
        the head model (:func:`_question`).
    lambdas : tuple of float
        The lambda grid of the PSMC families [s].
    metrics : dict
        Headline numbers.
    thesis : bool
        Thesis values apply: the thesis arm and head.
    arm : ArmParameters or None
        The arm.
    head : HeadContactModel or None
        The Hunt-Crossley head beside the ISO heads.
    """

    limits: pd.DataFrame
    free: pd.DataFrame
    lambda_table: pd.DataFrame
    clamp_transient: pd.DataFrame
    clamp_histories: dict
    static_bounds: pd.DataFrame
    static_map: tuple
    quasi_static: pd.DataFrame
    qs_histories: dict
    hc_curve: pd.DataFrame
    hc_states: pd.DataFrame
    verdict: pd.DataFrame
    question: pd.DataFrame = field(default_factory=pd.DataFrame)
    lambdas: tuple = ()
    metrics: dict = field(default_factory=dict)
    thesis: bool = True
    arm: object = None
    head: object = None

    def to_pandas(self) -> pd.DataFrame:
        """The verdict table (one row per thesis controller variant)."""
        return self.verdict.copy()

    def figures(self) -> dict:
        """The section's figures, ``{file name: Figure}``."""
        return {"iso_clamping_transient.png": f.plot_clamping_vs_limits(self),
                "iso_quasi_static.png": f.plot_quasi_static(self),
                "iso_lambda.png": f.plot_lambda_limits(self),
                "iso_hc_vs_linear.png": f.plot_hc_vs_linear(self)}


@checked_compute
def compute(*, quick: bool = False, arm=None, head=None) -> IsoFindings:
    """Clamping and ISO/TS 15066 power and force limiting for the head.

    Parameters
    ----------
    quick : bool
        The thesis lambdas (0.4, 0.8, 1.5 s), a 9 x 9 x 24 static grid and a 7 s
        clamped run instead of 8 lambdas, 25 x 25 x 72 and 12 s.
    arm : ArmParameters, optional
        Default the thesis arm.  Annex A's robot mass is the thesis' "around 2.5 kg" for
        the thesis arm, the plant's link masses plus payload for another.
    head : HeadContactModel, optional
        The Hunt-Crossley head beside the ISO heads (default ``thesis-frontal``).

    Returns
    -------
    IsoFindings
    """
    if not isinstance(quick, bool):
        raise TypeError(f"quick must be a bool, got {quick!r}")
    thesis = compares_to_thesis(arm, head)
    arm = resolve_arm(arm)
    hc = resolve_head_model(head)
    hc_label = HC_LABEL if hc == head_model() else "head HC"
    lams = LAMBDAS_QUICK if quick else LAMBDAS_FULL
    mass = THESIS_ARM_MASS if compares_to_thesis(arm) else _robot_mass(arm)
    m_r = robot_effective_mass_annex_a(mass)
    free, step_runs = _free_impacts(arm, lams, hc, hc_label)
    worst = _worst_per_variant(free)
    # own effective mass at the PID worst state (the largest speed of all)
    lim_rows = []
    for region in REGIONS:
        for fac in (region.transient_factor, 1.0):
            lim_rows.append(region_limits(region, m_r, transient_factor=fac))
    limits = pd.DataFrame(lim_rows)
    # lambda search per family
    lrows = []
    for fam, _ in FAMILIES:
        for region in REGIONS:
            hn = region.name
            w = worst[(worst.family == fam) & (worst["head_model"] == hn)].sort_values("lambda")
            for fac in (region.transient_factor, 1.0):
                lim = fac * region.force_quasi_static
                lam_f, below, adm = _lambda_min(w["lambda"], w["F_max"], lim)
                vmax = region_limits(region, m_r, transient_factor=fac)["v_max"]
                lam_v, _, _ = _lambda_min(w["lambda"], w["tcp_speed"], vmax)
                wh = worst[(worst.family == fam) & (worst["head_model"] == hc_label)
                           ].sort_values("lambda")
                lam_h, below_h, adm_h = _lambda_min(wh["lambda"], wh["F_max"], lim)
                lrows.append({"family": fam, "region": hn, "factor": fac, "F_limit": lim,
                              "lambda_min_force": lam_f, "at_grid_min": below, "admissible_grid": adm,
                              "v_max_annex": vmax, "lambda_min_speed": lam_v,
                              "F_at_lambda_0.4": float(np.interp(0.4, w["lambda"], w["F_max"])),
                              "head_model": _iso_head(region).name,
                              "lambda_min_force_hc": lam_h, "at_grid_min_hc": below_h,
                              "admissible_grid_hc": adm_h,
                              "hc_head_model": hc.name,
                              "F_at_lambda_0.4_hc": float(np.interp(0.4, wh["lambda"],
                                                                    wh["F_max"]))})
    lambda_table = pd.DataFrame(lrows)
    clamp_tr, clamp_hist = _clamping_transient(arm, worst, hc, hc_label)
    static_tab, static_map = _static_bounds(arm, 9 if quick else 25, 24 if quick else 72)
    qs, qs_hist = _quasi_static(arm, step_runs, QS_DURATION_QUICK if quick else QS_DURATION)
    hc_curve, hc_states = _hc_vs_linear(arm, worst, m_r, hc, hc_label)
    # verdict per thesis variant
    vrows = []
    for label in [v.label for v in thesis_variants()]:
        ct = clamp_tr[clamp_tr.label == label].set_index("head_model")
        q = qs[qs.label == label].iloc[0]
        vrows.append({"label": label,
                      "F_clamped_forehead": ct.loc["skull/forehead", "F_clamped"],
                      "F_clamped_face": ct.loc["face", "F_clamped"],
                      ("F_clamped_thesis_HC" if hc_label == HC_LABEL else "F_clamped_head_HC"):
                          ct.loc[hc_label, "F_clamped"],
                      "F_quasi_static": q.F_steady,
                      "transient_ok_forehead_2x": bool(ct.loc["skull/forehead", "F_clamped"] <= SKULL_FOREHEAD.force_transient),
                      "transient_ok_face_2x": bool(ct.loc["face", "F_clamped"] <= FACE.force_transient),
                      "transient_ok_face_1x": bool(ct.loc["face", "F_clamped"] <= FACE.force_quasi_static),
                      "quasi_static_ok_forehead": bool(q.F_steady <= SKULL_FOREHEAD.force_quasi_static),
                      "quasi_static_ok_face": bool(q.F_steady <= FACE.force_quasi_static)})
    verdict = pd.DataFrame(vrows)
    # thesis Table 6.1 (free impact, worst of step and switch) beside our clamped HC force;
    # TABLE_6_1 lists the variants in the order of thesis_variants()
    t61 = table_6_1()
    if thesis and len(t61) == len(verdict):
        verdict.insert(4, "Fmax_thesis_free", np.maximum(t61["Fmax_step"].to_numpy(float),
                                                         t61["Fmax_switch"].to_numpy(float)))
        verdict.insert(5, "clamped_HC_over_thesis",
                       verdict["F_clamped_thesis_HC"] / verdict["Fmax_thesis_free"])
    # linear vs Hunt-Crossley at equal speeds (two-body, m_R = M/2, m_H = 4.4 kg)
    diff = hc_curve.F_hunt_crossley.to_numpy() - hc_curve.F_linear_forehead.to_numpy()
    cross = np.nonzero(np.diff(np.sign(diff)) != 0)[0]
    v_cross = (float(np.interp(0.0, [diff[cross[0]], diff[cross[0] + 1]],
                               [hc_curve.speed.iloc[cross[0]], hc_curve.speed.iloc[cross[0] + 1]]))
               if len(cross) else math.nan)
    vmax_f = float(limits.iloc[0]["v_max"])
    hw = static_tab.set_index("mode").loc["hardware"]
    psmc = verdict[verdict.label != "PID"]
    metrics = {
        **({} if thesis else {"robot_mass_kg": mass}),
        "m_R_annex_kg": m_r,
        "v_max_forehead_2x": float(limits.iloc[0]["v_max"]),
        "v_max_face_2x": float(limits.iloc[2]["v_max"]),
        "E_transfer_forehead_2x_J": float(limits.iloc[0]["E_transfer"]),
        "E_transfer_face_2x_J": float(limits.iloc[2]["E_transfer"]),
        "static_bound_max_N": float(hw["F_max_N"]),
        "quasi_static_max_N": float(qs.F_steady.max()),
        "quasi_static_PID_N": float(qs.set_index("label").loc["PID", "F_steady"]),
        "t_hold_s": float(qs.set_index("label").loc["PID", "t_hold"]),
        "quasi_static_PID_rising": bool(qs.set_index("label").loc["PID", "F_steady"]
                                        > 1.01 * qs.set_index("label").loc["PID", "F_2s_earlier"]),
        "quasi_static_PID_bound_N": float(qs.set_index("label").loc["PID", "bound_same_dir"]),
        "quasi_static_psmc_max_N": float(qs[qs.label != "PID"].F_steady.max()),
        "static_bound_median_N": float(hw["F_median_N"]),
        "clamped_PID_forehead_N": float(verdict.iloc[0]["F_clamped_forehead"]),
        "clamped_worst_psmc_face_N": float(psmc["F_clamped_face"].max()),
        "clamp_ratio_max": float(clamp_tr.clamp_ratio.max()),
        "clamp_ratio_min": float(clamp_tr.clamp_ratio.min()),
        "energy_error_max": float(clamp_tr.E_balance_error.max()),
        "psmc_transient_ok_face_2x": int(psmc["transient_ok_face_2x"].sum()),
        "psmc_variants": int(len(psmc)),
        "hc_linear_crossover_speed": v_cross,
        "hc_over_linear_forehead_at_vmax": float(
            np.interp(vmax_f, hc_curve.speed, hc_curve.F_hunt_crossley)
            / np.interp(vmax_f, hc_curve.speed, hc_curve.F_linear_forehead)),
    }
    return IsoFindings(limits=limits, free=free, lambda_table=lambda_table,
                    clamp_transient=clamp_tr, clamp_histories=clamp_hist,
                    static_bounds=static_tab, static_map=static_map, quasi_static=qs,
                    qs_histories=qs_hist, hc_curve=hc_curve, hc_states=hc_states,
                    verdict=verdict, question=_question(free, hc, hc_label),
                    lambdas=tuple(lams), metrics=metrics, thesis=thesis,
                    arm=arm, head=hc)


def _fmt_lam(lam, at_min, adm, lams):
    """The answer on the lambda grid: the bracket of grid values, then the interpolation."""
    if lam != lam:
        return "no lambda of the grid meets it"
    if at_min:
        return f"already the smallest grid lambda {lam:.3g} s meets it (grid values: {adm})"
    ok = [float(x) for x in str(adm).split()]
    below = [x for x in lams if x < ok[0]]
    return (f"the crossing lies between the grid values {below[-1]:g} s (fails) and {ok[0]:g} s "
            f"(passes), log-linear interpolation {lam:.3g} s (grid values that meet it: {adm})")


def _two_heads(study: IsoFindings) -> list:
    """The same question answered with both head models, and why they differ (Markdown)."""
    lt = study.lambda_table
    rows = lt[(lt.region == "skull/forehead")]
    if not len(rows) or "lambda_min_force_hc" not in rows.columns:
        return []
    iso = _iso_head(SKULL_FOREHEAD)
    hc = study.head if study.head is not None else head_model()
    lams = sorted(study.lambdas)
    out = ["**The same question with two head models.** Is a PSMC family safe against the "
           "forehead limits? The answer depends on the head model, so both are given (the "
           "same verdicts as `ppamsafety impact`, the sweeps and the envelopes, "
           "`iso_question.csv`): the Annex A body model "
           f"`{iso.name}` ({describe_head(iso)}), under which ISO/TS 15066 states its limits, "
           f"and the Hunt-Crossley head `{hc.name}` ({describe_head(hc)}).", ""]
    for _, r in rows.iterrows():
        which = ("transient contact" if r.factor > 1 else "quasi-static force, the TS reading "
                 "for the head")
        out.append(f"* {r.family}, {r.F_limit:g} N ({which}): with `{r.head_model}` "
                   f"{_fmt_lam(r.lambda_min_force, r.at_grid_min, r.admissible_grid, lams)}; "
                   f"with `{r.hc_head_model}` "
                   f"{_fmt_lam(r.lambda_min_force_hc, r.at_grid_min_hc, r.admissible_grid_hc, lams)}"
                   f".")
    out += ["", "The two answers differ because the contact law and the struck mass set the "
            "force at a given speed: at these speeds the Hunt-Crossley head (fitted to Table "
            "6.1) is softer than the 150 N/mm spring with 4.4 kg (the crossover speed is in the "
            "next paragraph). The transient forehead limit 2 x 130 N is not in the TS (it gives "
            "no transient value for the skull and face, see `ppamsafety.params.iso_ts_15066`); "
            "the quasi-static 130 N rows are the TS reading. The grid brackets each answer; a "
            "safety envelope brackets the crossing of one experiment to any tolerance with "
            "the same verdicts (e.g. `ppamsafety sweep studies/psmc_forehead_envelope.toml`; "
            "for the Annex A body model `safety_envelope(..., "
            "head=ppamsafety.impact.verdicts.annex_a_head())`).", ""]
    return out


def render(study: IsoFindings) -> Section:
    """The report section (formatting only).

    Parameters
    ----------
    study : IsoFindings
        Output of :func:`compute`.

    Returns
    -------
    Section
    """
    if not study.thesis:
        return _render_other(study)
    m = study.metrics
    v = study.verdict
    lim = study.limits.drop(columns=["m_H"])
    pid = v[v.label == "PID"].iloc[0]
    md = [
        "Thesis §6.3.5: \"the pneumatic manipulator is expected to be on the safe side [in "
        "clamping] with its total mass of around 2.5 kg\". Checked here against ISO/TS 15066:2016 "
        "Annex A for the head (a technical specification; its pressure limits come from one "
        "pain-onset study at the University of Mainz, its force limits from a literature review).",
        "",
        "**Assumptions**", "",
        *[f"{i + 1}. {a}" for i, a in enumerate(assumptions(study.arm, study.head))], "",
        "**ISO/TS 15066 limits, transfer energy and permissible relative speed** "
        f"(m_R = M/2 = {m['m_R_annex_kg']:g} kg; E = F^2/(2K), v_max = F/sqrt(mu K)):", "",
        markdown_table(lim, digits=4), "",
        "**Transient clamping** (worst free-impact state of each controller, head pinned "
        "against a wall; F in N):", "",
        markdown_table(study.clamp_transient.drop(columns=["family"]), digits=4), "",
        f"Clamped / free peak force: {m['clamp_ratio_min']:.4f} to {m['clamp_ratio_max']:.4f} "
        f"(largest energy-balance error {m['energy_error_max']:.1e}): the peak comes within "
        "1-3 ms, before the 4.4-5 kg head has moved far enough to load the wall, so pinning adds "
        "little at the peak; the wall force follows later.", "",
        "**Quasi-static clamping.** Static bound of the tool force over the working area and all "
        "directions:", "",
        markdown_table(study.static_bounds, digits=4), "",
        "Closed loop, head held from the instant of largest tool speed in the up-step (F in N, "
        f"steady = mean of the last 0.5 s, {m['t_hold_s']:.1f} s after clamping; `F_2s_earlier`: "
        "2 s before the end):", "",
        markdown_table(study.quasi_static.drop(columns=["family", "diverged"]), digits=4), "",
        "**Smallest admissible lambda per PSMC family** (worst free impact over step and "
        "switch, four instants; F_max falls with lambda, so the limit bounds lambda from below: "
        "the \"maximum lambda\" of a family is this bound on its aggressiveness "
        "1/lambda). `lambda_min_force` from the simulated forces, `lambda_min_speed` from the "
        "Annex A speed criterion with m_R = M/2; NaN: not reached on the grid "
        f"{list(study.lambdas)} s; `at_grid_min`: already met at the smallest lambda; "
        "`admissible_grid`: the grid lambdas that meet the force limit (F(lambda) need not be "
        "monotonic: check the list, not only the bound):", "",
        markdown_table(study.lambda_table, digits=4), "",
        *_two_heads(study),
        "**Linear spring (ISO) vs Hunt-Crossley (thesis head).** At equal speeds (two-body, "
        "m_R = M/2, m_H = 4.4 kg, figure below) the Hunt-Crossley head gives less force than "
        "the 150 N/mm spring at low speed and more at high speed (n = 1.5 stiffens with "
        f"penetration): they cross at {m['hc_linear_crossover_speed']:.2f} m/s; at the forehead "
        f"v_max = {m['v_max_forehead_2x']:.3f} m/s the Hunt-Crossley force is "
        f"{m['hc_over_linear_forehead_at_vmax']:.2f} x the linear one. At the worst states of "
        "the thesis variants (F in N; `F_formula_*` = v sqrt(mu K) with the arm's own "
        "effective mass or Annex A's M/2; `F_engine_hunt_crossley`: the thesis head, 5 kg, "
        "worst of the same four instants):", "",
        markdown_table(study.hc_states, digits=4), "",
        "The Annex A formula with the arm's own effective mass (about 1 kg) matches the "
        "flexible-joint engine within 1 %; Annex A's M/2 = 1.25 kg overestimates the force by "
        "about 10 %, on the safe side.", "",
        "**Verdict on the \"safe side\" claim** (`Fmax_thesis_free`: thesis Table 6.1, free "
        "head, worst of step and switch, with our clamped Hunt-Crossley force over it; "
        "transient limits 2 x F_qs: forehead "
        f"{SKULL_FOREHEAD.force_transient:g} N, face {FACE.force_transient:g} N; quasi-static "
        f"{SKULL_FOREHEAD.force_quasi_static:g} / {FACE.force_quasi_static:g} N):", "",
        markdown_table(v, digits=4), "",
        f"* Quasi-static: the static bound of the muscles (0..3 bar) is "
        f"{m['static_bound_max_N']:.0f} N at most in the working area (median over "
        f"configurations {m['static_bound_median_N']:.0f} N; largest near the stretched arm, "
        "where J^-T amplifies the torques), so the arm's strength alone does not keep it below "
        f"{FACE.force_quasi_static:g} N / {SKULL_FOREHEAD.force_quasi_static:g} N. What keeps the "
        "clamping force low is the controller: in the closed loop the PSMC variants settle at "
        f"{m['quasi_static_psmc_max_N']:.0f} N at most (bounded coupling), while PID's integral "
        f"winds up to {m['quasi_static_PID_N']:.0f} N after {m['t_hold_s']:.1f} s ({'still rising' if m['quasi_static_PID_rising'] else 'levelled off'}; its static "
        f"bound in that direction is {m['quasi_static_PID_bound_N']:.0f} N): "
        f"{'above' if m['quasi_static_PID_N'] > FACE.force_quasi_static else 'below'} the face "
        f"limit {FACE.force_quasi_static:g} N.",
        f"* Transient: PID's clamped peak on the forehead is {pid.F_clamped_forehead:.0f} N "
        f"(limit {SKULL_FOREHEAD.force_transient:g} N): PID is not on the safe side. "
        f"{m['psmc_transient_ok_face_2x']} of {m['psmc_variants']} PSMC variants stay below the "
        f"face transient limit; the worst PSMC clamped face force is "
        f"{m['clamped_worst_psmc_face_N']:.0f} N. The 2.5 kg mass alone does not make the arm "
        "safe in transient head contact: its speed (set by the controller and lambda) decides.",
        "",
        "![transient clamping](iso_clamping_transient.png)", "",
        "![quasi-static clamping](iso_quasi_static.png)", "",
        "![lambda limits](iso_lambda.png)", "",
        "![linear vs Hunt-Crossley](iso_hc_vs_linear.png)", "",
    ]
    arts = list(study.figures().items()) + [
        ("iso_limits.csv", study.limits), ("iso_clamping_transient.csv", study.clamp_transient),
        ("iso_quasi_static.csv", study.quasi_static), ("iso_lambda.csv", study.lambda_table),
        ("iso_free_impacts.csv", study.free), ("iso_hc_vs_linear.csv", study.hc_states),
        ("iso_verdict.csv", study.verdict), ("iso_question.csv", study.question)]
    return Section("Clamping and ISO/TS 15066 power and force limiting (head)", "\n".join(md),
                   arts, dict(m))


def _render_other(study: IsoFindings) -> Section:
    """The ISO/TS 15066 section for another arm or head: its own numbers, no thesis values."""
    m = study.metrics
    md = [
        other_arm_note(study.arm, study.head), "",
        "ISO/TS 15066:2016 Annex A for the head, for this arm (robot mass "
        f"{m['robot_mass_kg']:.3g} kg: link masses plus payload; m_R = M/2 = "
        f"{m['m_R_annex_kg']:.3g} kg) and head model `{study.head.name}` beside the ISO heads.", "",
        "**Assumptions**", "",
        *[f"{i + 1}. {a}" for i, a in enumerate(assumptions(study.arm, study.head))], "",
        "**Limits, transfer energy and permissible relative speed:**", "",
        markdown_table(study.limits.drop(columns=["m_H"]), digits=4), "",
        "**Transient clamping** (worst free-impact state of each controller; F in N):", "",
        markdown_table(study.clamp_transient.drop(columns=["family"]), digits=4), "",
        "**Quasi-static clamping.** Static bound of the tool force:", "",
        markdown_table(study.static_bounds, digits=4), "",
        "Closed loop, head held from the instant of largest tool speed in the up-step:", "",
        markdown_table(study.quasi_static.drop(columns=["family", "diverged"]), digits=4), "",
        "**Smallest admissible lambda per PSMC family** (NaN: not reached on the grid "
        f"{list(study.lambdas)} s):", "",
        markdown_table(study.lambda_table, digits=4), "",
        *_two_heads(study),
        "**Linear spring (ISO) vs Hunt-Crossley** at the worst states:", "",
        markdown_table(study.hc_states, digits=4), "",
        "**Verdict per controller** (transient limits 2 x F_qs: forehead "
        f"{SKULL_FOREHEAD.force_transient:g} N, face {FACE.force_transient:g} N; quasi-static "
        f"{SKULL_FOREHEAD.force_quasi_static:g} / {FACE.force_quasi_static:g} N):", "",
        markdown_table(study.verdict, digits=4), "",
        "![transient clamping](iso_clamping_transient.png)", "",
        "![quasi-static clamping](iso_quasi_static.png)", "",
        "![lambda limits](iso_lambda.png)", "",
        "![linear vs Hunt-Crossley](iso_hc_vs_linear.png)", "",
    ]
    arts = list(study.figures().items()) + [
        ("iso_limits.csv", study.limits), ("iso_clamping_transient.csv", study.clamp_transient),
        ("iso_quasi_static.csv", study.quasi_static), ("iso_lambda.csv", study.lambda_table),
        ("iso_free_impacts.csv", study.free), ("iso_hc_vs_linear.csv", study.hc_states),
        ("iso_verdict.csv", study.verdict), ("iso_question.csv", study.question)]
    return Section("Clamping and ISO/TS 15066 power and force limiting (head)", "\n".join(md),
                   arts, dict(m))


__all__ = ["IsoFindings", "compute", "render", "ASSUMPTIONS", "assumptions"]
