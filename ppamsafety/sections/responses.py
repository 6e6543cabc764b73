"""Step and trajectory-switch responses of the thesis controllers (figs. 5.15-5.19).

The ten variants of Table 6.1 (:func:`ppamsafety.experiments.catalog.thesis_variants`)
run the step (q1_d 30 -> 70 -> 30 deg at 2 s and 7 s, q2_d = -80 deg) and the
trajectory switch (3.333 s circle -> 10 s circle at 7.5 s) with realistic
sensors.  These are also the records the impact study evaluates.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..experiments import catalog
from ..experiments.metrics import response_table
from ..experiments.trajectories import experiment_references
from ..markdown import markdown_table
from ..plots.control import plot_lambda_recovery, plot_step_comparison, plot_switch
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm)
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (measured 2026-11-23), the order a first report starts the sections in.
SECTION = SectionInfo(
    summary="step and trajectory-switch responses",
    thesis="figs. 5.15-5.19", typical_seconds=3.1)

TOL_ANGLE = np.radians(1.0)   #: band around the new q1 set angle for reach/settling [rad]
TOL_TCP = 0.005               #: band around the new circle after the switch [m]
#: Variants shown in the three-controller comparison figures (figs. 5.15, 5.17, 5.18).
MAIN_VARIANTS = ("PID", "PSMC joint Ki=2 λ=0.4", "PSMC task λ=0.4")


def _with_family(table: pd.DataFrame, results) -> pd.DataFrame:
    t = table.copy()
    t.insert(1, "family", [r.meta["family"] for r in results])
    t.insert(2, "lambda_s", [r.meta["lambda_s"] for r in results])
    return t


#: Variant whose ringing after the switch is analysed (§5.3.5, fig. 5.19).
OSCILLATING_VARIANT = "PSMC joint Ki=12 λ=0.4"


@dataclass
class ResponsesFindings(Result):
    """Result of :func:`compute`: step and switch runs of the thesis variants.

    Attributes
    ----------
    step, switch : list of ExperimentResult
        Runs in Table 6.1 order.
    step_table, switch_table : pandas.DataFrame
        :func:`~ppamsafety.experiments.metrics.response_table` outputs with
        ``family`` and ``lambda_s`` columns (SI units).
    oscillation_hz : float
        Dominant frequency of the TCP error of :data:`OSCILLATING_VARIANT`
        1-5 s after the switch [Hz] (NaN if that variant was not run).
    metrics : dict
        Headline numbers.
    thesis : bool
        Thesis statements apply: the thesis arm.
    arm : ArmParameters or None
        The arm.
    """

    step: list
    switch: list
    step_table: pd.DataFrame
    switch_table: pd.DataFrame
    oscillation_hz: float = np.nan
    metrics: dict = field(default_factory=dict)
    thesis: bool = True
    arm: object = None

    def to_pandas(self) -> pd.DataFrame:
        """Step and switch response tables, stacked with an ``experiment`` column."""
        return pd.concat([self.step_table.assign(experiment="step"),
                          self.switch_table.assign(experiment="switch")], ignore_index=True)

    def figures(self) -> dict:
        """The section's figures, ``{file name: Figure}``."""
        return _figures(self)


def _oscillation_frequency(switch) -> float:
    """Dominant frequency [Hz] of the TCP error of the Ki = 12 variant 1-5 s after the switch."""
    by = {r.meta.get("label"): r for r in switch}
    if OSCILLATING_VARIANT not in by:
        return np.nan
    r12 = by[OSCILLATING_VARIANT]
    m = (r12.t >= catalog.SWITCH_TIME + 1.0) & (r12.t < catalog.SWITCH_TIME + 5.0)
    e = r12.tracking_error()[m]
    spec = np.abs(np.fft.rfft(e - e.mean()))
    freqs = np.fft.rfftfreq(e.size, r12.reference.dt)
    return float(freqs[1:][np.argmax(spec[1:])])


def _figures(study) -> dict:
    """Figures of the step and switch study (figs. 5.15-5.19).

    Parameters
    ----------
    study : ppamsafety.sections.responses.ResponsesFindings
        Output of :func:`ppamsafety.sections.responses.compute`.

    Returns
    -------
    dict
        File name -> Figure.
    """
    figs = {}
    step, switch = study.step, study.switch
    by_label = catalog.results_by_label(step)
    main = [by_label[k] for k in MAIN_VARIANTS if k in by_label]
    ev = catalog.STEP_TIMES
    refs = experiment_references(resolve_arm(study.arm))
    lo, hi, q2 = (float(np.degrees(v)) for v in (refs.step_low, refs.step_high, refs.step_q2))
    figs["responses_step.png"] = plot_step_comparison(
        main, events=ev, title=f"Step response (cf. figs. 5.17, 5.18): q1_d {lo:.4g}° → "
        f"{hi:.4g}° → {lo:.4g}°, q2_d = {q2:.4g}°, realistic sensors")
    ki12 = [r for r in step if r.meta["family"] == "PSMC joint Ki=12"]
    figs["responses_step_ki12.png"] = plot_step_comparison(
        ki12, events=ev, title="Step response, joint PSMC with Ki = 12 bar/(rad s), "
        "λ = 0.4 / 0.8 / 1.5 s (cf. fig. 5.19)")
    figs["responses_step_lambda.png"] = plot_lambda_recovery(
        step, experiment="step", events=ev, title="Step: recovery for λ = 0.4, 0.8, 1.5 s "
        "(PID grey)")
    by_label = catalog.results_by_label(switch)
    main = [by_label[k] for k in MAIN_VARIANTS if k in by_label]
    figs["responses_switch.png"] = plot_switch(
        main, t_switch=catalog.SWITCH_TIME, circle_center=refs.circle_center,
        circle_radius=refs.circle_radius, t_range=(catalog.SWITCH_TIME - 2.5, switch[0].t[-1]),
        title="Trajectory switch (cf. fig. 5.15): 3.33 s circle → 10 s circle at "
              f"t = {catalog.SWITCH_TIME:g} s (half a turn ahead)")
    figs["responses_switch_lambda.png"] = plot_lambda_recovery(
        switch, experiment="switch", events=[catalog.SWITCH_TIME], tol=TOL_TCP,
        t_range=(catalog.SWITCH_TIME - 1.0, switch[0].t[-1]),
        title="Trajectory switch: recovery for λ = 0.4, 0.8, 1.5 s (cf. fig. 5.16; PID grey)")
    return figs


@checked_compute
def compute(*, quick: bool = False, arm=None, variants=None, sensors=None,
            head=None) -> ResponsesFindings:
    """Run step and switch for the thesis variants and tabulate their responses.

    Parameters
    ----------
    quick : bool
        Changes nothing: the ten step and switch runs take well under a
        second once compiled.
    arm : ppamsafety.params.ArmParameters, optional
        Arm (default: the thesis arm).
    variants : list of (str, controller), optional
        Controller variants (default: the ten of Table 6.1).
    sensors : SensorConfig, optional
        Sensor model (default: realistic sensors).
    head : HeadContactModel, optional
        Unused (no impact in this section); accepted like every section's.

    Returns
    -------
    ResponsesFindings
        Runs, response tables and metrics.
    """
    arm = resolve_arm(arm)
    out = {}
    for name in ("step", "switch"):
        res = catalog.run_thesis_experiment(arm, name, variants, sensors=sensors)
        out[name] = res
        out[f"{name}_table"] = _with_family(
            response_table(res, experiment=name, tol_angle=TOL_ANGLE, tol_tcp=TOL_TCP), res)
    st, sw = out["step_table"], out["switch_table"]
    metrics = {}
    if (st.family == "PID").any() and (st.family != "PID").any():
        pid = st[st.family == "PID"].iloc[0]
        ps = st[st.family != "PID"]
        metrics = {"step_pid_peak_tcp_speed": float(pid.peak_tcp_speed_m_s),
                   "step_max_psmc_peak_tcp_speed": float(ps.peak_tcp_speed_m_s.max()),
                   "step_pid_overshoot_pct": float(pid.overshoot_pct),
                   "step_max_psmc_overshoot_pct": float(ps.overshoot_pct.max()),
                   "switch_pid_peak_tcp_speed":
                       float(sw[sw.family == "PID"].peak_tcp_speed_m_s.iloc[0])}
    return ResponsesFindings(step=out["step"], switch=out["switch"], step_table=st,
                          switch_table=sw, oscillation_hz=_oscillation_frequency(out["switch"]),
                          metrics=metrics, thesis=compares_to_thesis(arm), arm=arm)


def _display(table: pd.DataFrame, experiment: str) -> pd.DataFrame:
    """Rounded copy for the report, with 'not reached' for NaN times."""
    if experiment == "step":
        win = catalog.STEP_TIMES[1] - catalog.STEP_TIMES[0]
        cols = {"variant": "variant", "peak_tcp_speed_m_s": "peak TCP speed [m/s]",
                "peak_qd1_rad_s": "peak abs(q̇1) [rad/s]", "peak_qd2_rad_s": "peak abs(q̇2) [rad/s]",
                "overshoot_deg": "q1 overshoot [deg]", "overshoot_pct": "overshoot [% of step]",
                "t90_s": "t to 90 % [s]", "t_reach_s": f"t to within {np.degrees(TOL_ANGLE):g} deg [s]",
                "t_settle_s": f"settled within {np.degrees(TOL_ANGLE):g} deg [s]"}
    else:
        win = catalog.DEFAULT_DURATIONS["switch"] - catalog.SWITCH_TIME
        cols = {"variant": "variant", "peak_tcp_speed_m_s": "peak TCP speed [m/s]",
                "peak_qd1_rad_s": "peak abs(q̇1) [rad/s]", "peak_qd2_rad_s": "peak abs(q̇2) [rad/s]",
                "t_reach_s": f"t to within {TOL_TCP * 1e3:g} mm [s]",
                "t_settle_s": f"settled within {TOL_TCP * 1e3:g} mm [s]"}
    d = table[list(cols)].rename(columns=cols).copy()
    for c in d.columns[1:]:
        d[c] = [f"> {win:g}" if isinstance(v, float) and np.isnan(v) else
                (f"{v:.2f}" if "[s]" in c or "deg" in c or "%" in c else f"{v:.3f}")
                for v in d[c]]
    return d


def render(study: ResponsesFindings) -> Section:
    """The report section of the responses study (formatting only).

    Parameters
    ----------
    study : ResponsesFindings
        Output of :func:`compute` (with the ten thesis variants).

    Returns
    -------
    Section
        Markdown and artifacts (figures, ``responses_step.csv``,
        ``responses_switch.csv``).
    """
    st, sw, m = study.step_table, study.switch_table, study.metrics
    pid = st[st.family == "PID"].iloc[0]
    osc_label = OSCILLATING_VARIANT
    osc_f = study.oscillation_hz

    def _settle(label):
        v = sw.set_index("variant").t_settle_s[label]
        return (f"has not settled within {TOL_TCP * 1e3:g} mm by the end of the record"
                if np.isnan(v) else f"settles within {TOL_TCP * 1e3:g} mm only after {v:.2f} s")
    osc_settle = _settle(osc_label)
    v2 = sw.set_index("variant").t_settle_s["PSMC joint Ki=2 λ=0.4"]
    ki2_settle = "no settling" if np.isnan(v2) else f"{v2:.2f} s"
    thesis_txt = ("the \"slightly oscillatory\" response the thesis reports\nfor the high "
                  "integral gain (§5.3.5, fig. 5.19)." if study.thesis else
                  "the high integral gain's oscillatory response.")
    md = f"""{'' if study.thesis else other_arm_note(study.arm) + chr(10) + chr(10)}All ten controller variants of Table 6.1 (Table 5.1 gains; joint PSMC with
Ki = 2 and 12 bar/(rad s); λ = 0.4, 0.8, 1.5 s) with the realistic sensors (encoder
quantisation, inter-pulse-timing velocity). {'' if study.thesis else 'Experiment references: ' + experiment_references(study.arm).describe('all') + '. '}Peaks are taken over the record from the first
discontinuity on; overshoot, reach and settling times are for the upward q1 step
(window {catalog.STEP_TIMES[0]:g}-{catalog.STEP_TIMES[1]:g} s) and, for the switch, for the TCP error after
t = {catalog.SWITCH_TIME:g} s. "> x" means not within the band before the window ends. Data:
`responses_step.csv`, `responses_switch.csv`.

**Step** (figs. 5.17-5.19):

{markdown_table(_display(st, "step"))}

PID's peak TCP speed is {m["step_pid_peak_tcp_speed"] / m["step_max_psmc_peak_tcp_speed"]:.1f} times the largest
PSMC peak and it overshoots by {pid.overshoot_pct:.0f} % of the step; PSMC approaches the new set
angle at a rate set by λ (no PSMC variant overshoots more than {m["step_max_psmc_overshoot_pct"]:.1f} %).

![step](responses_step.png)

![step Ki=12](responses_step_ki12.png)

![step lambda](responses_step_lambda.png)

**Trajectory switch** (figs. 5.15-5.16). Both circles run from t = 0, so at the switch the
desired point jumps half a turn (20 cm) ahead:

{markdown_table(_display(sw, "switch"))}

After the switch the Ki = 12 variants ring: the TCP error of {osc_label} oscillates at
{osc_f:.1f} Hz (dominant frequency 1-5 s after the switch) and {osc_settle}, against
{ki2_settle} for Ki = 2 at the same λ -- {thesis_txt}

![switch](responses_switch.png)

![switch lambda](responses_switch_lambda.png)
"""
    arts = [*study.figures().items(), ("responses_step.csv", st), ("responses_switch.csv", sw)]
    return Section("Step and trajectory-switch responses (thesis figs. 5.15-5.19)", md, arts,
                   dict(study.metrics))
