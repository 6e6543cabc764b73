"""Scalar measures of closed-loop runs: tracking error, recovery, step response, chattering.

All functions take :class:`~ppamsafety.experiments.closed_loop.ExperimentResult`
objects (or plain arrays) and return numbers or DataFrames in SI units; none
of them plots.  Times are measured from the event (step, switch) that caused
the error.  A run that never meets a tolerance inside its window gets NaN
(see the docstrings for how callers should read it).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from .._validation import (as_float_array, check_finite, check_instance, check_int, check_range,
                           check_positive, check_vector)
from .catalog import STEP_TIMES, SWITCH_TIME
from .closed_loop import ExperimentResult


def _window(t, t_from, t_to):
    t_to = np.inf if t_to is None else t_to
    return (t >= t_from - 1e-12) & (t < t_to - 1e-12)


def _result(result, name: str = "result") -> ExperimentResult:
    return check_instance(name, result, ExperimentResult)


def _times(t_from, t_to):
    """Validated window bounds (``t_to`` None: to the end)."""
    t_from = check_finite("t_from", t_from, unit="s")
    if t_to is not None:
        t_to = check_finite("t_to", t_to, unit="s")
        if t_to <= t_from:
            raise ValueError(f"t_to = {t_to:g} s must be after t_from = {t_from:g} s")
    return t_from, t_to


def _series(t, err):
    """Validated time and error series of equal length (NaN allowed in ``err``)."""
    t = as_float_array("t", t, ndim=1, allow_nonfinite=True)   # NaN after a divergence
    err = as_float_array("err", err, ndim=1, allow_nonfinite=True)
    if t.size != err.size:
        raise ValueError(f"err has {err.size} samples, t has {t.size}")
    return t, err


def tracking_stats(result, *, t_from: float = 0.0, t_to: float | None = None) -> dict:
    """Mean, max and RMS of the task-space error ||r_d - r|| [m] over [t_from, t_to).

    Parameters
    ----------
    result : ExperimentResult
        The run.
    t_from, t_to : float
        Evaluation window [s] (``t_to`` None: to the end).

    Returns
    -------
    dict
        ``mean``, ``max``, ``rms`` [m] (NaN if the run diverged, never
        otherwise), ``diverged`` (bool) and ``divergence_reason`` (str).
    """
    result = _result(result)
    t_from, t_to = _times(t_from, t_to)
    m = _window(result.t, t_from, t_to)
    if not m.any():
        raise ValueError(f"tracking_stats: empty window [t_from, t_to) = [{t_from}, {t_to}) s")
    e = result.tracking_error()[m]
    if result.diverged or not np.all(np.isfinite(e)):
        return {"mean": np.nan, "max": np.nan, "rms": np.nan, "diverged": True,
                "divergence_reason": result.divergence_reason or "non-finite tracking error"}
    return {"mean": float(e.mean()), "max": float(e.max()), "rms": float(np.sqrt(np.mean(e ** 2))),
            "diverged": False, "divergence_reason": ""}


def time_to_within(t, err, t_event: float, tol: float, *, t_end: float | None = None) -> float:
    """Time after ``t_event`` until ``err`` first drops to ``tol`` or below [s].

    NaN if it does not happen before ``t_end`` (read: "longer than
    t_end - t_event").

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times [s].
    err : array_like, shape (n,)
        Error magnitude per sample (any unit; NaN counts as outside).
    t_event : float
        Time of the event [s].
    tol : float
        Tolerance, positive (same unit as ``err``).
    t_end : float, optional
        End of the window [s] (default: the end of the record).

    Returns
    -------
    float
        Time [s] or NaN.
    """
    t, err = _series(t, err)
    t_event, t_end = _times(t_event, t_end)
    check_positive("tol", tol)
    m = _window(t, t_event, t_end)
    tt, ee = t[m], err[m]
    ok = np.nonzero(ee <= tol)[0]
    return float(tt[ok[0]] - t_event) if ok.size else np.nan


def settling_time(t, err, t_event: float, tol: float, *, t_end: float | None = None) -> float:
    """Time after ``t_event`` from which ``err`` stays within ``tol`` until ``t_end`` [s].

    NaN if the error is outside the band at the end of the window (not
    settled).

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times [s].
    err : array_like, shape (n,)
        Error magnitude per sample (NaN counts as outside).
    t_event : float
        Time of the event [s].
    tol : float
        Tolerance, positive (same unit as ``err``).
    t_end : float, optional
        End of the window [s] (default: the end of the record).

    Returns
    -------
    float
        Time [s] or NaN.
    """
    t, err = _series(t, err)
    t_event, t_end = _times(t_event, t_end)
    check_positive("tol", tol)
    m = _window(t, t_event, t_end)
    tt, ee = t[m], err[m]
    if ee.size == 0 or not ee[-1] <= tol:
        return np.nan
    out = np.nonzero(~(ee <= tol))[0]
    return float(tt[out[-1] + 1] - t_event) if out.size else 0.0


def peak_speeds(result, *, t_from: float = 0.0, t_to: float | None = None) -> dict:
    """Peak TCP speed [m/s] and peak |qd1|, |qd2| [rad/s] (true values) in a window.

    Parameters
    ----------
    result : ExperimentResult
        The run.
    t_from, t_to : float
        Window [s] (``t_to`` None: to the end).

    Returns
    -------
    dict
        ``peak_tcp_speed``, ``peak_qd1``, ``peak_qd2``; NaN (never a
        silent one) only if the run diverged before the window.
    """
    result = _result(result)
    t_from, t_to = _times(t_from, t_to)
    m = _window(result.t, t_from, t_to)
    if not m.any():
        raise ValueError(f"peak_speeds: empty window [t_from, t_to) = [{t_from}, {t_to}) s")
    v = result.tcp_speed()[m]
    qd = np.abs(result.signals("qd1", "qd2")[m])
    if not np.isfinite(v).any():
        return {"peak_tcp_speed": np.nan, "peak_qd1": np.nan, "peak_qd2": np.nan}
    return {"peak_tcp_speed": float(np.nanmax(v)), "peak_qd1": float(np.nanmax(qd[:, 0])),
            "peak_qd2": float(np.nanmax(qd[:, 1]))}


def step_metrics(result, *, t_event: float, t_end: float, joint: int = 0,
                 tol: float = np.radians(1.0)) -> dict:
    """Response of one joint to a step of its reference at ``t_event``.

    Parameters
    ----------
    result : ExperimentResult
    t_event, t_end : float
        Step time and end of the window (next step or end of record) [s].
    joint : {0, 1}
        Stepped joint.
    tol : float
        Band around the new set angle [rad] for the reach / settling times.

    Returns
    -------
    dict
        ``step`` (signed size [rad]), ``overshoot`` [rad] (beyond the new set
        angle in the direction of the step, 0 if none), ``overshoot_pct``
        [% of the step], ``t_90`` (time to 90 % of the step [s]),
        ``t_reach`` (first time within ``tol`` [s]), ``t_settle`` (stays
        within ``tol`` until ``t_end`` [s]); NaN where not reached.
    """
    result = _result(result)
    t_event = check_finite("t_event", t_event, unit="s")
    t_end = check_finite("t_end", t_end, unit="s")
    if t_end <= t_event:
        raise ValueError(f"t_end = {t_end:g} s must be after t_event = {t_event:g} s")
    joint = check_int("joint", joint, 0, 1)
    tol = check_positive("tol", tol, unit="rad")
    t = result.t
    q = result.signal(f"q{joint + 1}")
    qd_ref = result.reference.signal(f"q{joint + 1}_d")
    k0 = int(np.searchsorted(t, t_event - 1e-12))
    if k0 < 1 or k0 >= t.size:
        raise ValueError(f"step_metrics: t_event = {t_event} s is outside the record")
    q_from, q_to = qd_ref[k0 - 1], qd_ref[k0]
    size = q_to - q_from
    if size == 0:
        raise ValueError("step_metrics: the reference does not step at t_event")
    m = _window(t, t_event, t_end)
    direction = np.sign(size)
    progress = (q[m] - q_from) * direction
    if not np.isfinite(progress).any():     # diverged before the window
        return {"step": float(size), "overshoot": np.nan, "overshoot_pct": np.nan,
                "t_90": np.nan, "t_reach": np.nan, "t_settle": np.nan}
    over = max(0.0, float(np.nanmax(progress) - abs(size)))
    reached90 = np.nonzero(progress >= 0.9 * abs(size))[0]
    err = np.abs(q - q_to)
    return {"step": float(size), "overshoot": over, "overshoot_pct": 100.0 * over / abs(size),
            "t_90": float(t[m][reached90[0]] - t_event) if reached90.size else np.nan,
            "t_reach": time_to_within(t, err, t_event, tol, t_end=t_end),
            "t_settle": settling_time(t, err, t_event, tol, t_end=t_end)}


def chattering_index(dp, dt: float, *, f_cut: float = 5.0) -> float:
    """RMS of the commanded Delta p above ``f_cut`` [Pa], both joints combined.

    The command is detrended (mean removed per joint), transformed with an
    FFT, all components below ``f_cut`` are removed and the RMS of what is
    left is taken, summed over the joints in quadrature.  The default 5 Hz
    lies well above the reference's content (circle harmonics at
    multiples of 1/P) and above the valves' bandwidth (1/(2 pi T) = 2.7 Hz
    for T = 60 ms), so what it measures is switching the valves cannot
    follow: chattering.

    Parameters
    ----------
    dp : array_like, shape (n, 2)
        Commanded Delta p per joint [Pa] at the control rate.
    dt : float
        Sample period [s], in [1e-6, 1].
    f_cut : float
        Cut-off frequency [Hz].
    """
    x = as_float_array("dp", dp, ndim=2, allow_nonfinite=True)
    if x.shape[0] < 4:
        raise ValueError(f"dp must have shape (n >= 4, joints), got {x.shape}")
    dt = check_range("dt", dt, 1e-6, 1.0, unit="s")      # a control period
    f_cut = check_positive("f_cut", f_cut, unit="Hz")
    if not np.all(np.isfinite(x)):
        return np.nan
    n = x.shape[0]
    F = np.fft.rfft(x - x.mean(axis=0), axis=0)
    F[np.fft.rfftfreq(n, dt) < f_cut] = 0.0
    hp = np.fft.irfft(F, n=n, axis=0)
    return _combined_rms(hp)


def command_increment_rms(dp) -> float:
    """RMS of the sample-to-sample change of the commanded Delta p [Pa], joints combined.

    Parameters
    ----------
    dp : array_like, shape (n, joints)
        Commanded Delta p per joint [Pa], n >= 2, finite (check ``diverged``
        first: a diverged run's command is NaN after the divergence).

    Returns
    -------
    float
    """
    x = as_float_array("dp", dp, ndim=2)
    if x.shape[0] < 2:
        raise ValueError(f"dp must have shape (n >= 2, joints), got {x.shape}")
    return _combined_rms(np.diff(x, axis=0))


def _combined_rms(y) -> float:
    """sqrt(sum over columns of mean(y^2)) of finite ``y``, without overflow in the squares.

    Computed directly (so ordinary values are unchanged to the last bit); only if the
    squares overflow is it recomputed on ``y`` scaled by its largest magnitude.
    """
    with np.errstate(over="ignore"):
        v = float(np.sqrt(np.sum(np.mean(y ** 2, axis=0))))
    if math.isfinite(v):
        return v
    scale = float(np.max(np.abs(y)))
    z = y / scale
    return scale * float(np.sqrt(np.sum(np.mean(z ** 2, axis=0))))


def response_table(results, *, experiment: str, tol_angle: float = np.radians(1.0),
                   tol_tcp: float = 0.005, step_times=STEP_TIMES,
                   switch_time: float = SWITCH_TIME) -> pd.DataFrame:
    """One row of response measures per run of a step or switch experiment.

    Step (``experiment="step"``): peaks over t >= first step; overshoot,
    90 % time, reach and settling times (band ``tol_angle`` around the new
    q1 set angle) of the *upward* q1 step, evaluated until the downward step.
    Switch: peaks over t >= switch; reach and settling times of the TCP error
    into ``tol_tcp`` after the switch.

    Parameters
    ----------
    results : sequence of ExperimentResult
        Runs of the experiment.
    experiment : {"step", "switch"}
        Which experiment the runs are.
    tol_angle : float
        Band around the new q1 set angle [rad] (step), positive.
    tol_tcp : float
        Band of the TCP error [m] (switch), positive.
    step_times : pair of float
        Up- and down-step times [s] (default :data:`~.catalog.STEP_TIMES`).
    switch_time : float
        Switch time [s].

    Returns
    -------
    pandas.DataFrame
        Columns ``variant``, ``peak_tcp_speed_m_s``, ``peak_qd1_rad_s``,
        ``peak_qd2_rad_s``, and for the step ``overshoot_deg``,
        ``overshoot_pct``, ``t90_s``; for both ``t_reach_s``,
        ``t_settle_s`` (NaN: not within the band in the window), and
        ``diverged``, ``divergence_reason`` (a diverged run's NaN measures
        come with ``diverged=True`` and the reason).
    """
    if experiment not in ("step", "switch"):
        raise ValueError(f"response_table: experiment = {experiment!r} is not 'step' or 'switch'")
    tol_angle = check_positive("tol_angle", tol_angle, unit="rad")
    tol_tcp = check_positive("tol_tcp", tol_tcp, unit="m")
    step_times = check_vector("step_times", step_times, 2, 0.0, unit="s")
    switch_time = check_finite("switch_time", switch_time, unit="s")
    if isinstance(results, ExperimentResult) or not hasattr(results, "__iter__"):
        raise TypeError(f"results must be a sequence of ExperimentResult, got "
                        f"{type(results).__name__}")
    results = [_result(r, f"results[{i}]") for i, r in enumerate(results)]
    rows = []
    for r in results:
        label = r.meta.get("label", r.name)
        t_ev = step_times[0] if experiment == "step" else switch_time
        pk = peak_speeds(r, t_from=t_ev)
        row = {"variant": label, "peak_tcp_speed_m_s": pk["peak_tcp_speed"],
               "peak_qd1_rad_s": pk["peak_qd1"], "peak_qd2_rad_s": pk["peak_qd2"]}
        if experiment == "step":
            sm = step_metrics(r, t_event=step_times[0], t_end=step_times[1], joint=0,
                              tol=tol_angle)
            row.update({"overshoot_deg": np.degrees(sm["overshoot"]),
                        "overshoot_pct": sm["overshoot_pct"], "t90_s": sm["t_90"],
                        "t_reach_s": sm["t_reach"], "t_settle_s": sm["t_settle"]})
        else:
            e = r.tracking_error()
            row.update({"t_reach_s": time_to_within(r.t, e, switch_time, tol_tcp),
                        "t_settle_s": settling_time(r.t, e, switch_time, tol_tcp)})
        row.update({"diverged": bool(r.diverged), "divergence_reason": r.divergence_reason})
        rows.append(row)
    return pd.DataFrame(rows)


__all__ = ["tracking_stats", "time_to_within", "settling_time", "peak_speeds", "step_metrics",
           "chattering_index", "command_increment_rms", "response_table"]
