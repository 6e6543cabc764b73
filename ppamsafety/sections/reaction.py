"""Collision detection and reaction in the closed loop (beyond thesis §6.3.5).

Part of ``ppamsafety report`` (section "reaction"); run alone with
``ppamsafety report --only reaction [--outdir DIR] [--quick] [--overwrite]``.

For each experiment (the thesis' step response, fig. 5.17, and, in full mode,
the trajectory switch, fig. 5.15) and controller (PID, joint PSMC
Ki = 2 bar/(rad s) lambda = 0.4 s, and in full mode task PSMC lambda = 0.4 s):

1. the collision-free run with the force estimators gives the impact instant
   t0 (largest TCP speed, §6.3.3), the head placement of §6.3.2 (touching the
   TCP at t0, centre along the TCP velocity, 5 kg, at rest, free; present from
   :data:`HEAD_LEAD` = 50 ms before t0) and the
   detection thresholds (:func:`~ppamsafety.impact.collision.calibrate_threshold`:
   the default margin 1.5 over the largest collision-free residual, and the
   tightest margin :data:`TIGHT_MARGIN` = 1.05);
2. the same run with the head, through the first impact and
   :data:`HORIZON` = 300 ms beyond, for every reaction, detection at the
   tight margin (an optimistic bound: no false alarm on this very task);
   the detection instant at margin 1.5 is read from the NONE run's residual
   (a reaction-free run is the same at any threshold);
3. the first ~10 ms against the frozen-stiffness impact engine at the same
   state (:func:`~ppamsafety.impact.model.simulate_impacts`);
4. the timing argument: contact duration and time to F_max against the
   detection delay, the valve time constants and the pressure change the
   valves can make before the first contact ends.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..control import PID, JointPSMC, TaskPSMC
from ..control.estimation import ForceEstimator
from ..experiments import ExperimentCase, run_batch
from ..experiments.catalog import thesis_reference
from ..experiments.trajectories import Reference
from ..impact.collision import (DETECTION_MARGIN, Reaction, calibrate_threshold,
                                head_touching, simulate_collision)
from ..impact.instants import heuristic_instants, impact_states
from ..impact.model import simulate_impacts
from ..markdown import markdown_table
from ..params.head import MAXILLA_FRACTURE_N
from ..plant.geometry import jacobian
from ..plant.pneumatics import joint_stiffness
from ..plant.torque import torque_functions
from ..plots.reaction import plot_collision, plot_reactions
from ..units import BAR
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm, resolve_head_model)
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (measured 2026-11-23), the order a first report starts the sections in.
SECTION = SectionInfo(
    summary=("detection and reaction: the head coupled to the full closed loop, momentum-observer "
             "detection, stop / retract / vent, the second impact"),
    thesis="§5.4.2, §6.3 (new)", typical_seconds=3.6)

#: Simulated time after the impact instant [s] (beyond the 50 ms of thesis §6.3.2).
HORIZON = 0.3
#: Tightest detection margin studied: just above the largest collision-free residual.
TIGHT_MARGIN = 1.05
#: Window of the comparison with the frozen-stiffness engine [s].
ENGINE_WINDOW = 0.01
#: The head steps into the path this long before the impact instant [s] (the switch's circles
#: passed its place earlier; thesis §6.3.2 simulates only from t0).
HEAD_LEAD = 0.05
#: Length of the collision-free runs per experiment [s] (the impact instants lie well inside).
FREE_DURATION = {"step": 3.0, "switch": 8.5}


def _controllers(quick: bool) -> dict:
    c = {"PID": PID(), "PSMC joint Ki=2 λ=0.4": JointPSMC(lam=0.4, ki=2.0 * BAR)}
    if not quick:
        c["PSMC task λ=0.4"] = TaskPSMC(lam=0.4)
    return c


@dataclass
class ReactionFindings(Result):
    """Result of :func:`compute`.

    Attributes
    ----------
    quick : bool
    table : pandas.DataFrame
        One row per (experiment, controller, reaction), tight margin: thresholds
        [N m], contact and detection times [s], detection delay [s], F_max [N],
        HIC36 and start of the first and second impacts, number of impacts,
        energy-balance error of the contact.
    timing : pandas.DataFrame
        Per (experiment, controller): first-contact duration, time to F_max,
        detection delay at both margins, fastest valve time constant, the
        fraction of a set-value change the valves follow before the first
        contact ends, the pressure change VENT achieved by then, and the
        spread of the first impact's F_max over the reactions.
    engine : pandas.DataFrame
        Per (experiment, controller): closed-loop vs frozen-stiffness engine
        over the first ``ENGINE_WINDOW``: F_max of both, relative difference,
        largest force difference / F_max, HIC36 of both, largest pressure
        change [Pa] in the window.
    runs : dict
        (experiment, controller, reaction name) -> CollisionResult.
    free : dict
        (experiment, controller) -> collision-free ExperimentResult.
    compute_seconds : float
    metrics : dict
    note : str
        The other-arm note ("" for the thesis arm and head).
    head_name : str
        Name of the head model.
    """

    quick: bool
    table: pd.DataFrame
    timing: pd.DataFrame
    engine: pd.DataFrame
    runs: dict
    free: dict
    compute_seconds: float
    metrics: dict = field(default_factory=dict)
    note: str = ""
    head_name: str = "thesis-frontal"

    def to_pandas(self) -> pd.DataFrame:
        """The results table (one row per run)."""
        return self.table

    def figures(self) -> dict:
        """Figures ``{file name: Figure}``: reactions per case and one detailed run per controller."""
        figs = {}
        for (exp, ctrl) in self.free:
            if exp != "step":
                continue
            tag = "pid" if ctrl == "PID" else ctrl.split()[1]
            rs = [self.runs[(exp, ctrl, r.name)] for r in Reaction]
            figs[f"reaction_{exp}_{tag}_reactions.png"] = plot_reactions(
                rs, title=f"{exp}, {ctrl}: reactions (margin {TIGHT_MARGIN})")
            figs[f"reaction_{exp}_{tag}_stop.png"] = plot_collision(
                self.runs[(exp, ctrl, "STOP")])
        return figs


def _row(exp, ctrl, margin, res):
    i1, i2 = res.impact(0), res.impact(1)
    later = res.impacts.iloc[1:] if len(res.impacts) > 1 else None
    return {"experiment": exp, "controller": ctrl, "margin": margin,
            "reaction": res.reaction.name,
            "r1_th_Nm": res.threshold[0], "r2_th_Nm": res.threshold[1],
            "t_contact_s": res.t_contact, "t_detect_s": res.t_detect,
            "detect_delay_ms": res.detection_delay * 1e3,
            "F_max_1_N": i1["F_max"], "HIC36_1": i1["HIC36"], "duration_1_ms": i1["duration"] * 1e3,
            "t_2_after_ms": (i2["t_start"] - res.t_contact) * 1e3,
            "F_max_2_N": i2["F_max"], "HIC36_2": i2["HIC36"],
            "F_max_later_N": float(later["F_max"].max()) if later is not None else 0.0,
            "impacts": len(res.impacts),
            "energy_error": res.energy["contact_balance_error"]}


@checked_compute
def compute(*, quick: bool = False, arm=None, head=None) -> ReactionFindings:
    """Run the collision-detection and reaction study (see the module docstring).

    Parameters
    ----------
    quick : bool, keyword-only
        Step experiment and two controllers only.
    arm : ArmParameters, optional, keyword-only
        Default the thesis arm.
    head : HeadContactModel, optional, keyword-only
        Head model (default ``thesis-frontal``).
    """
    t_start = time.perf_counter()
    note = "" if compares_to_thesis(arm, head) else other_arm_note(arm, head)
    arm = resolve_arm(arm)
    head = resolve_head_model(head)
    ctrls = _controllers(quick)
    exps = ("step",) if quick else ("step", "switch")
    rows, trows, erows, runs, free = [], [], [], {}, {}
    tv = np.array([v.time_constant for v in arm.valves.valves])
    for exp in exps:
        ref = thesis_reference(arm, exp, duration=FREE_DURATION[exp])
        cases = [ExperimentCase(arm, c, ref, estimator=ForceEstimator(), name=f"{exp}: {k}")
                 for k, c in ctrls.items()]
        for (name, ctrl), fr in zip(ctrls.items(), run_batch(cases)):
            free[(exp, name)] = fr
            st = impact_states(fr, arm)
            k0 = int(round(st["t"].iloc[heuristic_instants(st)["max TCP speed"]] / ref.dt))
            xh, u = head_touching(fr, k0, head)
            n = min(k0 + int(round(HORIZON / ref.dt)), ref.n_steps)
            cref = Reference(ref.name, ref.t[:n], ref.data[:n], ref.dt)
            case = ExperimentCase(arm, ctrl, cref, estimator=ForceEstimator(), name=f"{exp}: {name}")
            th = calibrate_threshold(fr, margin=TIGHT_MARGIN)
            for rea in Reaction:
                res = simulate_collision(case, head_position=xh, head=head, threshold=th,
                                         reaction=rea, head_appears=max(
                                             k0 * ref.dt - HEAD_LEAD, 0.0))
                runs[(exp, name, rea.name)] = res
                rows.append(_row(exp, name, TIGHT_MARGIN, res))
            # -- frozen-stiffness engine at the state of t0 ------------------------------
            none = runs[(exp, name, "NONE")]
            q = fr.signals("q1", "q2")[k0]
            qd = fr.signals("qd1", "qd2")[k0]
            p = fr.signals("p1", "p2", "p3", "p4")[k0]
            K = joint_stiffness(q, p, arm)
            eng = simulate_impacts(arm, q, qd, K, head=head, direction=u, dt=none.fine_dt,
                                   duration=0.05, history=True)
            Fe = eng.signal("F", 0)
            m = int(round(ENGINE_WINDOW / none.fine_dt))
            i0 = k0 * int(round(ref.dt / none.fine_dt))
            Fc = none.fine[i0:i0 + m + 1, 0]
            ne = min(Fc.size, Fe.size)
            fmax_e = float(eng.summary["F_max"].iloc[0])
            i1 = none.impact(0)
            pw = none.experiment.signals("p1", "p2", "p3", "p4")[k0:k0 + int(round(ENGINE_WINDOW / ref.dt)) + 1]
            erows.append({"experiment": exp, "controller": name,
                          "F_max_closed_loop_N": float(i1["F_max"]), "F_max_engine_N": fmax_e,
                          "F_max_rel_diff": float(i1["F_max"]) / fmax_e - 1.0,
                          "max_dF_over_Fmax": float(np.max(np.abs(Fc[:ne] - Fe[:ne])) / fmax_e),
                          "HIC36_closed_loop": float(i1["HIC36"]),
                          "HIC36_engine": float(eng.summary["HIC36"].iloc[0]),
                          "K1_Nm_rad": float(K[0]), "K2_Nm_rad": float(K[1]),
                          "max_dp_window_Pa": float(np.max(np.abs(pw - pw[0])))})
            # -- timing: why reaction cannot shape the first impact ----------------------
            r_t = runs[(exp, name, "VENT")]
            t_end = float(i1["t_end"])
            # detection at the default margin, from the reaction-free run's residual
            th15 = calibrate_threshold(fr, margin=DETECTION_MARGIN)
            over = np.nonzero(np.any(np.abs(none.experiment.signals("r1", "r2")) > th15,
                                     axis=1))[0]
            dets = {"tight": r_t.detection_delay,
                    "margin": over[0] * ref.dt - none.t_contact if over.size else math.nan}
            left = t_end - r_t.t_detect if np.isfinite(r_t.t_detect) else -math.inf
            frac = 1.0 - math.exp(-max(left, 0.0) / tv.min())
            kend = int(math.floor(t_end / ref.dt))
            pv = r_t.experiment.signals("p1", "p2", "p3", "p4")
            pn = none.experiment.signals("p1", "p2", "p3", "p4")
            kd = min(kend, pv.shape[0] - 1)
            # the actuators' whole torque range at q(t0) against the contact torque J^T n F_max
            mt = torque_functions(q, arm)
            span = arm.pneumatics.p_max * np.array([abs(mt[0]) + abs(mt[1]),
                                                    abs(mt[2]) + abs(mt[3])])
            tau_c = np.abs(jacobian(q, arm).T @ u) * float(i1["F_max"])
            f1 = [runs[(exp, name, rea.name)].impact(0)["F_max"] for rea in Reaction]
            trows.append({"experiment": exp, "controller": name,
                          "contact_1_ms": float(i1["duration"]) * 1e3,
                          "t_to_Fmax_ms": (float(i1["t_Fmax"]) - none.t_contact) * 1e3,
                          "detect_delay_ms": dets["margin"] * 1e3,
                          "detect_delay_tight_ms": dets["tight"] * 1e3,
                          "valve_T_min_ms": tv.min() * 1e3,
                          "valve_fraction_by_contact_end": frac,
                          "vent_dp_by_contact_end_Pa": float(np.max(np.abs(pv[kd] - pn[kd]))),
                          "contact_torque_Nm": float(tau_c.max()),
                          "actuator_span_Nm": float(span.max()),
                          "span_over_contact_torque": float(np.max(span / tau_c)),
                          "Fmax_1_spread_rel": float((max(f1) - min(f1)) / max(f1))})
    table = pd.DataFrame(rows)
    timing = pd.DataFrame(trows)
    engine = pd.DataFrame(erows)
    secs = time.perf_counter() - t_start
    stp = table[table.experiment == "step"]

    def _val(ctrl, rea, col):
        s = stp[(stp.controller == ctrl) & (stp.reaction == rea)][col]
        return float(s.iloc[0]) if len(s) else math.nan

    psmc = list(ctrls)[1]
    metrics = {
        "compute_seconds": secs,
        "step_PID_Fmax1_N": _val("PID", "NONE", "F_max_1_N"),
        "step_PID_Fmax_later_NONE_N": _val("PID", "NONE", "F_max_later_N"),
        "step_PID_Fmax_later_STOP_N": _val("PID", "STOP", "F_max_later_N"),
        "step_PID_detect_delay_tight_ms": _val("PID", "NONE", "detect_delay_ms"),
        "step_PSMC_Fmax1_N": _val(psmc, "NONE", "F_max_1_N"),
        "step_PSMC_Fmax_later_NONE_N": _val(psmc, "NONE", "F_max_later_N"),
        "step_PSMC_Fmax_later_STOP_N": _val(psmc, "STOP", "F_max_later_N"),
        "step_PSMC_detect_delay_tight_ms": _val(psmc, "NONE", "detect_delay_ms"),
        "step_PID_detected_at_margin_1_5": bool(np.isfinite(float(timing[
            (timing.experiment == "step") & (timing.controller == "PID")]
            ["detect_delay_ms"].iloc[0]))),
        "engine_Fmax_rel_diff_max": float(engine["F_max_rel_diff"].abs().max()),
        "engine_dF_over_Fmax_max": float(engine["max_dF_over_Fmax"].max()),
        "first_impact_Fmax_spread_max": float(timing["Fmax_1_spread_rel"].max()),
        "energy_error_max": float(table["energy_error"].abs().max()),
    }
    return ReactionFindings(quick, table, timing, engine, runs, free, secs, metrics, note=note,
                         head_name=head.name)


def render(study: ReactionFindings) -> Section:
    """Markdown section and artifacts of the reaction study.

    Parameters
    ----------
    study : ReactionFindings
        Output of :func:`compute`.
    """
    m = study.metrics
    cols = ["experiment", "controller", "margin", "reaction", "r1_th_Nm", "r2_th_Nm",
            "detect_delay_ms", "F_max_1_N", "HIC36_1", "duration_1_ms", "t_2_after_ms",
            "F_max_2_N", "HIC36_2", "F_max_later_N", "impacts"]
    head_txt = ("the 5 kg head (thesis-frontal Hunt-Crossley contact" if study.head_name ==
                "thesis-frontal" else f"the head `{study.head_name}` (Hunt-Crossley contact")
    md = ([study.note, ""] if study.note else []) + [
        "The thesis rates only the first 50 ms of an impact on a frozen flexible-joint arm "
        "(§6.3.2) and notes (§6.3.5) that detection and reaction can reduce contact forces "
        f"afterwards.  Here {head_txt}, free, at rest, "
        "touching the TCP at the instant of largest TCP speed along the TCP velocity, §6.3.2) "
        f"is coupled to the full closed loop (sensors, observer, controller, valves, "
        f"pressures, gravity) and simulated {HORIZON * 1e3:.0f} ms beyond the impact instant "
        "(20 us coupled RK4 steps near and in contact).  Detection: the generalized-momentum "
        "observer residual (5.54), K_I = 10 pi rad/s, exceeds margin x its largest value on "
        f"the same task without head; the reactions below use the tightest margin "
        f"{TIGHT_MARGIN} (optimistic: no false alarm on this very run), the timing table also "
        f"gives the detection at the default margin {DETECTION_MARGIN}.  Reactions act "
        "through the controller and the valves from the detection sample on: STOP (hold the "
        "measured position), RETRACT (back to the position 100 ms earlier), VENT (all set "
        "values 0 bar gauge), EQUALIZE (Delta p = 0).",
        "",
        markdown_table(study.table[cols], digits=3),
        "",
        f"Maxilla fracture tolerance {MAXILLA_FRACTURE_N:.0f} N (§6.3.3).  "
        "F_max_later: the largest force of all impacts after the first.",
        "",
        "Why reaction cannot shape the first impact (per case; the valve fraction is "
        "1 - exp(-(t_end - t_detect)/T_min), the share of a set-value change the fastest "
        "valve follows before the first contact ends):",
        "",
        markdown_table(study.timing, digits=3),
        "",
    ]
    for _, r in study.timing.iterrows():
        md.append(
            f"* {r.experiment}, {r.controller}: F_max {r.t_to_Fmax_ms:.1f} ms after the first "
            f"contact, detection after {r.detect_delay_tight_ms:.1f} ms (tight margin; "
            f"{r.detect_delay_ms:.1f} ms at margin 1.5, NaN: not detected), contact over after "
            f"{r.contact_1_ms:.1f} ms; by then the fastest valve (T = {r.valve_T_min_ms:.0f} ms) "
            f"follows {r.valve_fraction_by_contact_end:.0%} of a set-value change.  Even an "
            f"instantaneous swing over the muscles' whole pressure range would give "
            f"{r.actuator_span_Nm:.0f} N m against a contact torque of "
            f"{r.contact_torque_Nm:.0f} N m (J^T n F_max) -- the impact is decided by the link "
            f"inertia (§6.3.4); the first impact's F_max differs by "
            f"{r.Fmax_1_spread_rel:.1%} between the reactions.")
    md += [
        "",
        f"Cross-check of the first {ENGINE_WINDOW * 1e3:.0f} ms against the frozen-stiffness "
        "engine (§6.3.2) started from the same state (stiffness (2.18) from the pressures at "
        "t0):",
        "",
        markdown_table(study.engine, digits=4),
        "",
        f"Largest |F_max| difference to the engine: {m['engine_Fmax_rel_diff_max']:.2%}; "
        f"first-impact F_max spread over the reactions: {m['first_impact_Fmax_spread_max']:.2%}; "
        f"contact energy balance error: {m['energy_error_max']:.1e}.  "
        f"Compute time {study.compute_seconds:.1f} s.",
    ]
    arts = list(study.figures().items()) + [
        ("reaction_results.csv", study.table), ("reaction_timing.csv", study.timing),
        ("reaction_engine_check.csv", study.engine)]
    return Section("Collision detection and reaction in the closed loop (beyond §6.3.5)",
                   "\n".join(md), arts, dict(m))


__all__ = ["ReactionFindings", "compute", "render", "HORIZON", "TIGHT_MARGIN", "ENGINE_WINDOW"]
