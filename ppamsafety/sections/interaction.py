"""Physical interaction: force estimation, admittance control and the release hazard.

Thesis §5.4 (figs. 5.21, 5.22) and the hazard of §6.3 (pushed away, released).
Part of ``ppamsafety report`` (section "interaction"); run alone with
``ppamsafety report --only interaction [--outdir DIR] [--quick] [--overwrite]``.

Experiments (all at 1 kHz, the arm held at A = FK(50 deg, -80 deg)):

1. *Clean estimation*: perfect estimator model (``arm.plant_base``), ideal
   sensors, a force step f = (10, -5) N at the TCP at t = 1 s, joint PSMC.
   Steady-state errors of both estimators; the observer's step response
   against 1 - exp(-K_I t).
2. *Realistic estimation*: the same push with encoder quantisation and the
   timing-board velocity, for three estimator models: perfect, the identified
   Table 3.5 set (``arm.model``) and a set identified here from a simulated
   excitation (§3.5.2).  Phantom force before the push and steady-state error.
3. *Phantom force in free motion*: a plant with a 0.5 kg payload
   (``Effects(payload_mass=0.5)``) runs the step experiment without any
   external force; estimator models: ``arm.model`` vs identified from an
   excitation of the payload plant.
4. *Admittance*: ``AdmittancePSMC`` (b = 40 N s/m, F_min = 3 N) and a
   spring-damper hand pulling the TCP A -> B -> C, then letting go.
5. *Release*: PID and joint PSMC hold A; the hand pulls the TCP toward B for
   3 s and lets go; head impacts (thesis §6.3.3 heuristic instants) on the
   motion after the release.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from ..control import PID, JointPSMC, SensorConfig
from ..control.admittance import AdmittancePSMC
from ..control.estimation import K_I_THESIS, ForceEstimator
from ..experiments import ExperimentCase, run_batch
from ..experiments import trajectories as tr
from ..experiments.closed_loop import ExperimentResult
from ..experiments.interaction import Hand, piecewise_targets
from ..identify.consistent import identify_dynamic_consistent
from ..identify.dynamic import identify_dynamic
from ..identify.excitation import design_excitation, simulate_excitation
from ..impact.instants import evaluate_experiment
from ..markdown import markdown_table
from ..params.inertia import BaseParameters
from ..plant import geometry as geo
from ..plots.interaction import (plot_force_estimates, plot_interaction_path, plot_observer_step,
                                 plot_release)
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm, resolve_head_model)
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (measured 2026-11-23), the order a first report starts the sections in.
SECTION = SectionInfo(
    summary="force estimation (RLS, momentum observer), admittance control, the release hazard",
    thesis="§5.4, figs. 5.21-5.22, §6.3", typical_seconds=4.2)

#: Hold configuration A and waypoints B, C on the thesis arm [rad]; another arm's at the same
#: fractions of its joint ranges (:func:`~ppamsafety.experiments.trajectories.arm_pose`).
Q_A = np.radians([50.0, -80.0])
Q_B = np.radians([70.0, -60.0])
Q_C = np.radians([35.0, -100.0])
F_STEP = np.array([10.0, -5.0])        #: force step of experiments 1-2 [N]
T_STEP = 1.0                           #: its time [s]
PAYLOAD = 0.5                          #: payload of experiment 3 [kg]


def _hold(arm, duration, q=None, name="hold"):
    q = tr.arm_pose(arm, Q_A) if q is None else q
    return tr.joint_steps(arm, q_levels=[q], t_changes=[], duration=duration, name=name)


def identify_model(plant_arm, *, quick: bool = False):
    """Identify the rigid-body model of ``plant_arm`` from a simulated excitation (§3.5.2).

    Parameters
    ----------
    plant_arm : ArmParameters
        The simulated plant (its effects included).
    quick : bool
        Fewer design evaluations.

    Returns
    -------
    BaseParameters
        LS estimate with friction (smooth Coulomb law of the plant).  A negative friction
        estimate (an effect the rigid-body model lacks, such as muscle hysteresis, aliased
        into friction) is set to 0: the estimators need a dissipative model.  Where that
        aliasing also makes an inertia estimate (theta3, theta6) non-positive -- a strong
        hysteresis -- the physically consistent estimate of the same data is used
        (:func:`~ppamsafety.identify.consistent.identify_dynamic_consistent`).
    """
    d = design_excitation(plant_arm, n_random=4 if quick else 8, maxfev=4 if quick else 24,
                          seed=1)
    data = simulate_excitation(plant_arm, d.excitation, periods=2, with_qdd=False)
    res = identify_dynamic(data, plant_arm, friction=True,
                           sign_velocity=plant_arm.friction_velocity)
    t = res.theta
    if not (t[2] > 0.0 and t[5] > 0.0):
        res = identify_dynamic_consistent(data, plant_arm, friction=True,
                                          sign_velocity=plant_arm.friction_velocity)
        t = res.theta
    if np.all(t[6:10] >= 0.0):
        return res.to_base_parameters()
    return BaseParameters(*[float(v) for v in t[:6]],
                          coulomb=(max(float(t[6]), 0.0), max(float(t[7]), 0.0)),
                          viscous=(max(float(t[8]), 0.0), max(float(t[9]), 0.0)))


def _steady(res, name, k0, k1):
    return float(np.mean(res.signal(name)[k0:k1]))


@dataclass
class InteractionFindings(Result):
    """Result of :func:`compute`.

    Attributes
    ----------
    clean : ExperimentResult
        Experiment 1.
    realistic : dict of str -> ExperimentResult
        Experiment 2 per estimator model.
    phantom : dict of str -> ExperimentResult
        Experiment 3 per estimator model.
    admittance : ExperimentResult
        Experiment 4.
    release : dict of str -> ExperimentResult
        Experiment 5 per controller.
    estimation_table, phantom_table, release_table : pandas.DataFrame
    waypoints : numpy.ndarray, shape (3, 2)
        A, B, C [m].
    t_release : float
        Release time of experiment 5 [s].
    step_response : pandas.DataFrame
        Observer step response of experiment 1: t [s], estimate and
        closed_form (1 - exp(-K_I t)), both normalised by the step.
    metrics : dict
    note : str
        The other-arm note ("" for the thesis arm and head).
    """

    clean: ExperimentResult
    realistic: dict
    phantom: dict
    admittance: ExperimentResult
    release: dict
    estimation_table: pd.DataFrame
    phantom_table: pd.DataFrame
    release_table: pd.DataFrame
    waypoints: np.ndarray
    t_release: float
    step_response: pd.DataFrame
    metrics: dict = field(default_factory=dict)
    note: str = ""

    def to_pandas(self) -> pd.DataFrame:
        """The estimation table."""
        return self.estimation_table

    def figures(self) -> dict:
        """Figures ``{file name: Figure}``."""
        s = self.step_response
        return {
            "interaction_estimates_fig_5_21.png": plot_force_estimates(
                self.realistic["identified"],
                title="Force estimation, realistic sensors, identified model (cf. fig. 5.21)"),
            "interaction_observer_step.png": plot_observer_step(
                s["t"], s["estimate"], s["closed_form"], k_i=K_I_THESIS),
            "interaction_admittance_fig_5_22.png": plot_interaction_path(
                self.admittance, waypoints=self.waypoints),
            "interaction_release.png": plot_release(
                list(self.release.values()), t_release=self.t_release,
                labels=list(self.release.keys())),
        }


@checked_compute
def compute(*, quick: bool = False, arm=None, head=None) -> InteractionFindings:
    """Run the five interaction experiments (see the module docstring).

    Parameters
    ----------
    quick : bool, keyword-only
        Shorter runs and a cheaper excitation design.
    arm : ArmParameters, optional, keyword-only
        Default the thesis arm.  Its identified model (``arm.model``, Table 3.5 for the
        thesis arm) is one of the estimators' models.
    head : HeadContactModel, optional, keyword-only
        Head of the impacts after the release (default ``thesis-frontal``).
    """
    thesis = compares_to_thesis(arm, head)
    arm = resolve_arm(arm)
    head = resolve_head_model(head)
    table = "Table 3.5" if thesis else "arm.model"
    dt = 1e-3
    # -- 1 and 2: a force step, clean and realistic -----------------------------------
    dur = 3.0 if quick else 4.0
    ref = _hold(arm, dur)
    n = ref.n_steps
    k_step = int(round(T_STEP / dt))
    F = np.zeros((n, 2))
    F[k_step:] = F_STEP
    ident = identify_model(arm, quick=quick)
    models = {"perfect": arm.plant_base, table: None, "identified": ident}
    cases = [ExperimentCase(arm, JointPSMC(), ref, sensors=SensorConfig.ideal(),
                            external_force=F, estimator=ForceEstimator(model=arm.plant_base),
                            name="clean")]
    cases += [ExperimentCase(arm, JointPSMC(), ref, external_force=F,
                             estimator=ForceEstimator(model=m), name=f"realistic {k}")
              for k, m in models.items()]
    runs = run_batch(cases, dt=dt)
    clean, realistic = runs[0], dict(zip(models, runs[1:]))
    k0, k1 = n - 500, n                           # steady window: last 0.5 s
    b0, b1 = k_step - 500, k_step                 # before the push
    rows = []
    for label, res in [("clean (perfect model, ideal sensors)", clean)] + \
            [(f"realistic sensors, {k} model", r) for k, r in realistic.items()]:
        row = {"case": label}
        for est in ("rls", "mo"):
            fx, fy = _steady(res, f"Fx_{est}", k0, k1), _steady(res, f"Fy_{est}", k0, k1)
            px, py = _steady(res, f"Fx_{est}", b0, b1), _steady(res, f"Fy_{est}", b0, b1)
            row[f"phantom_{est}_N"] = float(np.hypot(px, py))
            row[f"ss_error_{est}_rel"] = float(np.hypot(fx - F_STEP[0], fy - F_STEP[1])
                                               / np.linalg.norm(F_STEP))
        rows.append(row)
    est_table = pd.DataFrame(rows)
    # observer step response (clean): projection on the applied force direction
    u = F_STEP / np.linalg.norm(F_STEP)
    kk = np.arange(k_step, k_step + 300)
    tt = (kk - k_step) * dt
    fmo = clean.signals("Fx_mo", "Fy_mo")[kk] @ u / np.linalg.norm(F_STEP)
    closed = 1.0 - np.exp(-K_I_THESIS * tt)
    step = pd.DataFrame({"t": tt, "estimate": fmo, "closed_form": closed})
    i63 = int(np.argmax(fmo >= 1.0 - np.exp(-1.0)))
    # -- 3: phantom force in free motion with a payload -----------------------------------
    plant = arm.replace(effects=replace(arm.effects, payload_mass=PAYLOAD))
    ident_p = identify_model(plant, quick=quick)
    sref = tr.step(arm, duration=6.0 if quick else 12.0)
    pm = {table: None, "identified (payload plant)": ident_p}
    pruns = run_batch([ExperimentCase(plant, JointPSMC(), sref, estimator=ForceEstimator(model=m),
                                      name=f"phantom {k}") for k, m in pm.items()], dt=dt)
    phantom = dict(zip(pm, pruns))
    prow = []
    for k, r in phantom.items():
        skip = 300                              # initial transient of the estimators
        row = {"estimator model": k}
        for est in ("rls", "mo"):
            f = np.hypot(r.signal(f"Fx_{est}"), r.signal(f"Fy_{est}"))[skip:]
            row[f"rms_{est}_N"] = float(np.sqrt(np.mean(f ** 2)))
            row[f"max_{est}_N"] = float(f.max())
            row[f"above_3N_{est}_pct"] = float(100 * np.mean(f > 3.0))
        prow.append(row)
    ph_table = pd.DataFrame(prow)
    # -- 4: admittance with a hand A -> B -> C ------------------------------------------
    wp = geo.forward_kinematics(np.array([tr.arm_pose(arm, q) for q in (Q_A, Q_B, Q_C)]), arm)
    adur = 10.0
    aref = _hold(arm, adur, name="admittance")
    ta = aref.t
    target = piecewise_targets(ta, [wp[0], wp[0], wp[1], wp[1], wp[2]],
                               [0.0, 0.5, 3.0, 4.0, 6.5])
    engaged = (ta >= 0.5) & (ta < 7.5)
    hand = Hand(target, engaged, stiffness=200.0, damping=20.0)
    adm = run_batch([ExperimentCase(arm, AdmittancePSMC(), aref, hand=hand,
                                    estimator=ForceEstimator(model=ident), name="admittance")],
                    dt=dt)[0]
    # -- 5: pushed away and released ------------------------------------------------------
    rdur, t_rel = 6.0, 3.5
    rref = _hold(arm, rdur, name="release")
    tr_ = rref.t
    rtarget = piecewise_targets(tr_, [wp[0], wp[0], wp[1]], [0.0, 0.5, 2.0])
    rhand = Hand(rtarget, (tr_ >= 0.5) & (tr_ < t_rel), stiffness=200.0, damping=20.0)
    ctrls = {"PID": PID(), "PSMC joint": JointPSMC()}
    rr = run_batch([ExperimentCase(arm, c, rref, hand=rhand, name=f"release {k}")
                    for k, c in ctrls.items()], dt=dt)
    release = dict(zip(ctrls, rr))
    krel = int(round(t_rel / dt))
    rrows = []
    for k, r in release.items():
        after = ExperimentResult(r.name, r.controller, r.reference, r.log[krel:], r.diverged,
                                 dict(r.meta))
        imp = evaluate_experiment(after, arm, head=head).summary
        d = np.hypot(r.signal("x") - r.signal("x_d"), r.signal("y") - r.signal("y_d"))
        rrows.append({"controller": k,
                      "displacement_at_release_mm": float(d[krel - 1] * 1e3),
                      "hand_force_at_release_N": float(np.hypot(r.signal("Fx_ext"),
                                                                r.signal("Fy_ext"))[krel - 1]),
                      "max_tcp_speed_after_m_s": float(r.tcp_speed()[krel:].max()),
                      "F_max_N": float(imp["F_max"].max()),
                      "HIC36": float(imp["HIC36"].max())})
    rel_table = pd.DataFrame(rrows)
    ad_end = np.array([adm.signal("x")[-1], adm.signal("y")[-1]])
    metrics = {
        "clean_ss_error_rls_rel": float(est_table.iloc[0]["ss_error_rls_rel"]),
        "clean_ss_error_mo_rel": float(est_table.iloc[0]["ss_error_mo_rel"]),
        "observer_t63_s": float(tt[i63]), "observer_1_over_KI_s": float(1.0 / K_I_THESIS),
        "observer_step_max_dev": float(np.max(np.abs(fmo - closed))),
        "phantom_table35_N": float(est_table.iloc[2]["phantom_mo_N"]),
        "phantom_identified_N": float(est_table.iloc[3]["phantom_mo_N"]),
        "payload_phantom_rms_table35_N": float(ph_table.iloc[0]["rms_mo_N"]),
        "payload_phantom_rms_identified_N": float(ph_table.iloc[1]["rms_mo_N"]),
        "admittance_end_to_C_mm": float(np.linalg.norm(ad_end - wp[2]) * 1e3),
        "release_F_max_PID_N": float(rel_table.iloc[0]["F_max_N"]),
        "release_F_max_PSMC_N": float(rel_table.iloc[1]["F_max_N"]),
        "release_HIC36_PID": float(rel_table.iloc[0]["HIC36"]),
        "release_HIC36_PSMC": float(rel_table.iloc[1]["HIC36"]),
    }
    return InteractionFindings(clean, realistic, phantom, adm, release, est_table, ph_table,
                            rel_table, wp, t_rel, step, metrics,
                            note="" if thesis else other_arm_note(arm, head))


def render(study: InteractionFindings) -> Section:
    """Markdown section and artifacts of the interaction study.

    Parameters
    ----------
    study : InteractionFindings
        Output of :func:`compute`.
    """
    m = study.metrics
    md = ([study.note, ""] if study.note else []) + [
        "Force estimation (§5.4.2): recursive least squares with forgetting mu = 0.99 on the "
        "filtered model (5.44)-(5.47) and the generalized-momentum observer with "
        "K_I = 10 pi rad/s (5.51)-(5.56), both in the compiled loop, from measured signals "
        "and the estimator's model.  A force step (10, -5) N at the TCP at t = 1 s, arm held "
        "by joint PSMC:",
        "",
        markdown_table(study.estimation_table),
        "",
        f"Observer step (clean case): 63 % reached after {m['observer_t63_s'] * 1e3:.1f} ms "
        f"(1/K_I = {m['observer_1_over_KI_s'] * 1e3:.1f} ms); largest deviation from "
        f"1 - exp(-K_I t) over 0.3 s: {m['observer_step_max_dev']:.2e} of the step.",
        "",
        f"Phantom force in free motion (step experiment, plant with a {PAYLOAD} kg payload, "
        "no external force):",
        "",
        markdown_table(study.phantom_table),
        "",
        f"Admittance (b = 40 N s/m, F_min = 3 N), hand A -> B -> C and release: the TCP ends "
        f"{m['admittance_end_to_C_mm']:.0f} mm from C.",
        "",
        "Pushed away from the set point and released (§6.3 hazard), worst head impact after "
        "the release (§6.3.3 heuristic instants):",
        "",
        markdown_table(study.release_table),
    ]
    arts = list(study.figures().items()) + [
        ("interaction_estimation.csv", study.estimation_table),
        ("interaction_phantom.csv", study.phantom_table),
        ("interaction_release.csv", study.release_table)]
    return Section("Physical interaction: force estimation and admittance (§5.4)",
                   "\n".join(md), arts, dict(m))


__all__ = ["InteractionFindings", "compute", "render", "identify_model"]
