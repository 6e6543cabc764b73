"""The thesis' qualitative conclusions of §5.3.5 as testable statements.

Each function takes tables computed elsewhere (tracking errors per variant
and period, step / switch response measures) and returns a
:class:`Conclusion`: the claim, the criterion it was tested with, whether it
holds, and the numbers behind the verdict.  The criteria and their
thresholds are fixed here, before looking at any result, and are reported
with the verdict:

(a) task-space PSMC tracks worst -- in every period, every task-space
    variant has a larger mean error than every other variant.
(b) joint PSMC ~ PID at equal gains -- mean error of joint PSMC with
    Ki = 2 within +-25 % of PID's for every lambda and period (the thesis'
    own ratios are 1.04-1.21).
(c) Ki = 12 cuts the PSMC error several-fold -- mean error with Ki = 2 at
    least 2x that with Ki = 12 at equal lambda, every period (thesis:
    3.4-5.0x).
(d) lambda hardly changes tracking -- within each PSMC family and period the
    largest mean error over lambda is at most 1.5x the smallest (the
    thesis' own table spreads up to 1.45x).
(e) lambda slows the recovery from large errors -- the time to come back
    within the tolerance band after the step and after the switch increases
    strictly with lambda in every PSMC family (not reaching the band within
    the window counts as slower than any time that did).
(f) PID responds violently to the step while PSMC is smooth -- PID's peak
    TCP speed in the step is at least 2x that of every PSMC variant, PID
    overshoots by more than 10 % of the step, every PSMC variant by less
    than 5 %.
(g) Ki = 12 pays with a slightly oscillatory step response (§5.3.5, fig. 5.19:
    "The price to pay is a slightly oscillatory step response") -- the joint
    PSMC with Ki = 12 overshoots the upward step more than with Ki = 2 at the
    same lambda, for lambda = 0.4 s (the lambda of Table 5.1), and by more than
    0.1 % of the step.  Not part of :func:`evaluate_conclusions` (a)-(f); the
    as-built arm (:mod:`ppamsafety.thesis_fits.as_built`) tests it.

Table formats (all SI): ``errors`` has one row per (variant, period) with
columns ``variant``, ``family``, ``lambda_s``, ``period_s``, ``mean_m``,
``max_m``; the step and switch tables are
:func:`~ppamsafety.experiments.metrics.response_table` outputs with
``family`` and ``lambda_s`` columns added.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

EQUAL_GAINS_TOL = 0.25
SEVERAL_FOLD = 2.0
LAMBDA_SPREAD = 1.5
VIOLENT_SPEED_RATIO = 2.0
PID_OVERSHOOT_MIN_PCT = 10.0
PSMC_OVERSHOOT_MAX_PCT = 5.0
PSMC_FAMILIES = ("PSMC joint Ki=2", "PSMC joint Ki=12", "PSMC task")


@dataclass
class Conclusion:
    """One qualitative conclusion of the thesis, tested.

    Attributes
    ----------
    key : str
        Letter (a)-(f).
    claim : str
        The thesis' statement.
    criterion : str
        How it was tested (thresholds included).
    holds : bool
        Verdict.
    evidence : str
        The numbers behind the verdict (Markdown sentence; mm, s, m/s).
    numbers : dict
        The same numbers, machine-readable (SI units).
    """

    key: str
    claim: str
    criterion: str
    holds: bool
    evidence: str
    numbers: dict = field(default_factory=dict)

    def as_row(self) -> dict:
        """The conclusion as a flat dict (one table row)."""
        return {"": f"({self.key})", "thesis claim": self.claim,
                "verdict": "holds" if self.holds else "does not hold",
                "criterion": self.criterion, "evidence": self.evidence}


def _need(df: pd.DataFrame, cols, what: str):
    missing = [c for c in cols if c not in df.columns]
    if missing:
        raise ValueError(f"{what} table lacks columns {missing}")


def _mm(x) -> str:
    return f"{1e3 * x:.2f} mm"


def task_space_worst(errors: pd.DataFrame) -> Conclusion:
    """(a) Task-space PSMC has the largest mean error in every period.

    Parameters
    ----------
    errors : pandas.DataFrame
        Tracking errors, one row per (variant, period) (module docstring);
        columns used: ``family``, ``period_s`` [s], ``mean_m`` [m], ``variant``.

    Returns
    -------
    Conclusion
        Verdict (a) with its criterion and evidence.

    Raises
    ------
    ValueError
        If a table lacks a column it needs.
    """
    _need(errors, ["family", "period_s", "mean_m", "variant"], "errors")
    parts, ok, nums = [], True, {}
    for P, g in errors.groupby("period_s"):
        task = g[g.family == "PSMC task"]
        other = g[g.family != "PSMC task"]
        best_task = task.mean_m.min()
        worst_other = other.loc[other.mean_m.idxmax()]
        holds = bool(best_task > worst_other.mean_m)
        ok &= holds
        nums[f"P{P:g}"] = {"best_task_mean_m": float(best_task),
                           "worst_other_mean_m": float(worst_other.mean_m),
                           "worst_other": worst_other.variant}
        parts.append(f"P = {P:g} s: best task {_mm(best_task)} vs worst other "
                     f"{_mm(worst_other.mean_m)} ({worst_other.variant})"
                     + ("" if holds else " **violated**"))
    return Conclusion("a", "task-space PSMC tracks worst",
                      "every task-space variant has a larger mean error than every other "
                      "variant, in every period", ok, "; ".join(parts) + ".", nums)


def joint_psmc_equals_pid(errors: pd.DataFrame, *, tol: float = EQUAL_GAINS_TOL) -> Conclusion:
    """(b) Joint PSMC with the PID gains (Ki = 2) tracks like PID.

    Parameters
    ----------
    errors : pandas.DataFrame
        Tracking errors, one row per (variant, period) (module docstring);
        columns used: ``family``, ``period_s`` [s], ``mean_m`` [m], ``lambda_s`` [s].
    tol : float, keyword-only
        Largest relative deviation of the mean-error ratio PSMC/PID from 1
        [-] (default :data:`EQUAL_GAINS_TOL` = 0.25).

    Returns
    -------
    Conclusion
        Verdict (b) with its criterion and evidence.

    Raises
    ------
    ValueError
        If a table lacks a column it needs.
    """
    _need(errors, ["family", "period_s", "mean_m", "lambda_s"], "errors")
    parts, ok, nums = [], True, {}
    pid_better = 0
    n = 0
    for P, g in errors.groupby("period_s"):
        pid = float(g[g.family == "PID"].mean_m.iloc[0])
        j = g[g.family == "PSMC joint Ki=2"]
        ratios = (j.mean_m / pid).to_numpy()
        pid_better += int(np.sum(ratios > 1.01))
        n += ratios.size
        bad = np.abs(ratios - 1) > tol
        ok &= not bad.any()
        nums[f"P{P:g}"] = {"ratios": ratios.tolist(), "lambdas": j.lambda_s.tolist()}
        parts.append(f"P = {P:g} s: PSMC/PID = "
                     + ", ".join(f"{r:.2f}" + (" **out**" if b else "")
                                 for r, b in zip(ratios, bad)))
    nums["pid_better_cells"] = pid_better
    ev = ("; ".join(parts) + f" (λ = 0.4, 0.8, 1.5 s). PID is better by more than 1 % in "
          f"{pid_better} of {n} cells (thesis: better in all).")
    return Conclusion("b", "joint PSMC ≈ PID at equal gains",
                      f"joint PSMC (Ki = 2) mean error within ±{100 * tol:.0f} % of PID's, "
                      "every λ and period", ok, ev, nums)


def high_integral_gain_helps(errors: pd.DataFrame, *, factor: float = SEVERAL_FOLD) -> Conclusion:
    """(c) Ki = 12 cuts the joint PSMC tracking error several-fold.

    Parameters
    ----------
    errors : pandas.DataFrame
        Tracking errors, one row per (variant, period) (module docstring);
        columns used: ``family``, ``period_s`` [s], ``mean_m`` [m], ``lambda_s`` [s].
    factor : float, keyword-only
        Smallest ratio mean error (Ki = 2) / mean error (Ki = 12) at equal
        lambda for the claim to hold [-] (default :data:`SEVERAL_FOLD` = 2).

    Returns
    -------
    Conclusion
        Verdict (c) with its criterion and evidence.

    Raises
    ------
    ValueError
        If a table lacks a column it needs.
    """
    _need(errors, ["family", "period_s", "mean_m", "lambda_s"], "errors")
    parts, ok, nums = [], True, {}
    for P, g in errors.groupby("period_s"):
        a = g[g.family == "PSMC joint Ki=2"].set_index("lambda_s").mean_m
        b = g[g.family == "PSMC joint Ki=12"].set_index("lambda_s").mean_m
        r = (a / b).dropna()
        bad = r < factor
        ok &= not bad.any()
        nums[f"P{P:g}"] = {float(k): float(v) for k, v in r.items()}
        parts.append(f"P = {P:g} s: " + ", ".join(f"{v:.1f}x" + (" **no**" if x else "")
                                                   for v, x in zip(r, bad)))
    return Conclusion("c", "Ki = 12 cuts the PSMC error several-fold",
                      f"mean error Ki = 2 / Ki = 12 ≥ {factor:g} at equal λ, every period", ok,
                      "; ".join(parts) + " (λ = 0.4, 0.8, 1.5 s).", nums)


def lambda_hardly_matters(errors: pd.DataFrame, *, spread: float = LAMBDA_SPREAD) -> Conclusion:
    """(d) lambda hardly changes the tracking error.

    Parameters
    ----------
    errors : pandas.DataFrame
        Tracking errors, one row per (variant, period) (module docstring);
        columns used: ``family``, ``period_s`` [s], ``mean_m`` [m].
    spread : float, keyword-only
        Largest ratio max/min of the mean error over lambda within a PSMC
        family and period [-] (default :data:`LAMBDA_SPREAD` = 1.5).

    Returns
    -------
    Conclusion
        Verdict (d) with its criterion and evidence.

    Raises
    ------
    ValueError
        If a table lacks a column it needs.
    """
    _need(errors, ["family", "period_s", "mean_m"], "errors")
    parts, ok, nums = [], True, {}
    for fam in PSMC_FAMILIES:
        sub = []
        for P, g in errors[errors.family == fam].groupby("period_s"):
            s = float(g.mean_m.max() / g.mean_m.min())
            ok &= s <= spread
            nums[f"{fam} P{P:g}"] = s
            sub.append(f"{s:.2f}" + (" **out**" if s > spread else ""))
        parts.append(f"{fam}: " + ", ".join(sub))
    return Conclusion("d", "λ hardly changes tracking",
                      f"max/min mean error over λ ≤ {spread:g} per family and period", ok,
                      "max/min over λ for P = 5, 10, 20 s -- " + "; ".join(parts) + ".", nums)


def _increasing(times) -> bool:
    t = np.where(np.isnan(times), np.inf, times)
    return bool(np.all(np.diff(t) > 0) and np.isfinite(t[:-1]).all())


def _fmt_t(x) -> str:
    return "not reached" if np.isnan(x) else f"{x:.2f} s"


def lambda_slows_recovery(step: pd.DataFrame, switch: pd.DataFrame, *,
                          tol_angle_deg: float = 1.0, tol_tcp_mm: float = 5.0) -> Conclusion:
    """(e) Larger lambda: slower recovery after the step and the switch.

    Parameters
    ----------
    step, switch : pandas.DataFrame
        Step and switch response tables
        (:func:`~ppamsafety.experiments.metrics.response_table` outputs with
        ``family`` and ``lambda_s`` [s] columns added); column ``t_reach_s``
        is the time to come back within the tolerance band [s] (NaN: not
        reached within the window).
    tol_angle_deg : float, keyword-only
        Tolerance band of the step on the q1 set angle [deg] with which
        ``step.t_reach_s`` was measured; only quoted in the criterion text
        (the times are not recomputed here).
    tol_tcp_mm : float, keyword-only
        Tolerance band of the switch on the distance to the new circle [mm]
        with which ``switch.t_reach_s`` was measured; only quoted in the
        criterion text.

    Returns
    -------
    Conclusion
        Verdict (e) with its criterion and evidence.

    Raises
    ------
    ValueError
        If a table lacks a column it needs.
    """
    for name, df in (("step", step), ("switch", switch)):
        _need(df, ["family", "lambda_s", "t_reach_s"], name)
    parts, ok, nums = [], True, {}
    for exp, df, tol in (("step", step, f"{tol_angle_deg:g} deg"),
                         ("switch", switch, f"{tol_tcp_mm:g} mm")):
        for fam in PSMC_FAMILIES:
            g = df[df.family == fam].sort_values("lambda_s")
            times = g.t_reach_s.to_numpy()
            inc = _increasing(times)
            ok &= inc
            nums[f"{exp} {fam}"] = dict(zip(g.lambda_s.tolist(), times.tolist()))
            parts.append(f"{exp}, {fam}: " + " < ".join(_fmt_t(x) for x in times)
                         + ("" if inc else " **not increasing**"))
    return Conclusion("e", "λ slows the recovery from large errors",
                      f"time to come within {tol_angle_deg:g} deg of the new q1 set angle (step up) "
                      f"and within {tol_tcp_mm:g} mm of the new circle (switch) increases strictly "
                      "with λ = 0.4, 0.8, 1.5 s in every PSMC family", ok, "; ".join(parts) + ".",
                      nums)


def pid_violent_psmc_smooth(step: pd.DataFrame, *, speed_ratio: float = VIOLENT_SPEED_RATIO,
                            pid_overshoot_pct: float = PID_OVERSHOOT_MIN_PCT,
                            psmc_overshoot_pct: float = PSMC_OVERSHOOT_MAX_PCT) -> Conclusion:
    """(f) PID's step response is violent, PSMC's smooth.

    Parameters
    ----------
    step : pandas.DataFrame
        Step response table (one row per variant, one with family ``"PID"``);
        columns used: ``family``, ``variant``, ``peak_tcp_speed_m_s`` [m/s],
        ``overshoot_pct`` [% of the step], ``peak_qd1_rad_s``,
        ``peak_qd2_rad_s`` [rad/s].
    speed_ratio : float, keyword-only
        Smallest ratio of PID's peak TCP speed to every PSMC variant's [-]
        (default :data:`VIOLENT_SPEED_RATIO` = 2).
    pid_overshoot_pct : float, keyword-only
        PID's overshoot must exceed this [% of the step] (default
        :data:`PID_OVERSHOOT_MIN_PCT` = 10).
    psmc_overshoot_pct : float, keyword-only
        Every PSMC variant's overshoot must stay below this [% of the step]
        (default :data:`PSMC_OVERSHOOT_MAX_PCT` = 5).

    Returns
    -------
    Conclusion
        Verdict (f) with its criterion and evidence.

    Raises
    ------
    ValueError
        If a table lacks a column it needs.
    """
    _need(step, ["family", "peak_tcp_speed_m_s", "overshoot_pct", "peak_qd1_rad_s",
                 "peak_qd2_rad_s"], "step")
    pid = step[step.family == "PID"].iloc[0]
    ps = step[step.family != "PID"]
    worst = ps.loc[ps.peak_tcp_speed_m_s.idxmax()]
    ratio = float(pid.peak_tcp_speed_m_s / worst.peak_tcp_speed_m_s)
    ok = bool(ratio >= speed_ratio and pid.overshoot_pct > pid_overshoot_pct
              and ps.overshoot_pct.max() < psmc_overshoot_pct)
    nums = {"pid_peak_tcp_speed": float(pid.peak_tcp_speed_m_s),
            "max_psmc_peak_tcp_speed": float(worst.peak_tcp_speed_m_s), "speed_ratio": ratio,
            "pid_overshoot_pct": float(pid.overshoot_pct),
            "max_psmc_overshoot_pct": float(ps.overshoot_pct.max()),
            "pid_peak_qd": [float(pid.peak_qd1_rad_s), float(pid.peak_qd2_rad_s)],
            "max_psmc_peak_qd": [float(ps.peak_qd1_rad_s.max()), float(ps.peak_qd2_rad_s.max())]}
    ev = (f"peak TCP speed PID {pid.peak_tcp_speed_m_s:.2f} m/s vs at most "
          f"{worst.peak_tcp_speed_m_s:.2f} m/s for PSMC ({worst.variant}), ratio {ratio:.1f}; "
          f"peak abs(q̇1), abs(q̇2) PID {pid.peak_qd1_rad_s:.2f}, {pid.peak_qd2_rad_s:.2f} rad/s vs PSMC "
          f"≤ {ps.peak_qd1_rad_s.max():.2f}, {ps.peak_qd2_rad_s.max():.2f} rad/s; overshoot PID "
          f"{pid.overshoot_pct:.0f} % of the step vs PSMC ≤ {ps.overshoot_pct.max():.1f} %.")
    return Conclusion("f", "PID responds violently to the step, PSMC smoothly",
                      f"PID peak TCP speed ≥ {speed_ratio:g}x every PSMC variant's, PID overshoot "
                      f"> {pid_overshoot_pct:g} %, every PSMC overshoot < {psmc_overshoot_pct:g} % "
                      "of the step", ok, ev, nums)


#: Smallest overshoot of the Ki = 12 step for "oscillatory" (g) [% of the step].
OSCILLATORY_MIN_PCT = 0.1


def ki12_step_oscillatory(step: pd.DataFrame, *, lambda_s: float = 0.4,
                          min_pct: float = OSCILLATORY_MIN_PCT) -> Conclusion:
    """(g) Ki = 12 pays with a slightly oscillatory step response (§5.3.5, fig. 5.19).

    Parameters
    ----------
    step : pandas.DataFrame
        Step response table with ``family``, ``lambda_s`` [s] and ``overshoot_pct``
        [% of the step] (module docstring); needs the joint PSMC Ki = 2 and Ki = 12 rows
        at ``lambda_s``.
    lambda_s : float, keyword-only
        The lambda at which Ki = 12 and Ki = 2 are compared [s] (default 0.4, Table 5.1).
    min_pct : float, keyword-only
        Ki = 12 must overshoot by more than this [% of the step] (default
        :data:`OSCILLATORY_MIN_PCT`).

    Returns
    -------
    Conclusion
        Verdict (g) with its criterion and evidence.

    Raises
    ------
    ValueError
        If the table lacks a column or the two rows.
    """
    _need(step, ["family", "lambda_s", "overshoot_pct"], "step")
    rows = {}
    for fam in ("PSMC joint Ki=2", "PSMC joint Ki=12"):
        g = step[(step.family == fam) & np.isclose(step.lambda_s.astype(float), lambda_s)]
        if len(g) != 1:
            raise ValueError(f"step table has no single {fam} row at lambda_s = {lambda_s:g} s")
        rows[fam] = float(g.overshoot_pct.iloc[0])
    o2, o12 = rows["PSMC joint Ki=2"], rows["PSMC joint Ki=12"]
    ok = bool(o12 > o2 and o12 > min_pct)
    return Conclusion("g", "Ki = 12 pays with a slightly oscillatory step response",
                      f"joint PSMC step overshoot with Ki = 12 above that with Ki = 2 at "
                      f"λ = {lambda_s:g} s, and above {min_pct:g} % of the step", ok,
                      f"overshoot at λ = {lambda_s:g} s: Ki = 12 {o12:.2f} %, Ki = 2 "
                      f"{o2:.2f} % of the step.", {"overshoot_ki12_pct": o12,
                                                   "overshoot_ki2_pct": o2})


def evaluate_conclusions(errors: pd.DataFrame, step: pd.DataFrame,
                         switch: pd.DataFrame) -> list:
    """All six conclusions (a)-(f), in order, with the default criteria.

    Parameters
    ----------
    errors : pandas.DataFrame
        Tracking errors, one row per (variant, period) (module docstring).
    step, switch : pandas.DataFrame
        Step and switch response tables (module docstring).

    Returns
    -------
    list of Conclusion
        The verdicts (a) to (f).
    """
    return [task_space_worst(errors), joint_psmc_equals_pid(errors),
            high_integral_gain_helps(errors), lambda_hardly_matters(errors),
            lambda_slows_recovery(step, switch), pid_violent_psmc_smooth(step)]


def conclusions_table(conclusions) -> pd.DataFrame:
    """Conclusions as a DataFrame (one row each) for the report.

    Parameters
    ----------
    conclusions : iterable of Conclusion
        The tested conclusions (e.g. from :func:`evaluate_conclusions`).

    Returns
    -------
    pandas.DataFrame
        One row per conclusion (columns of :meth:`Conclusion.as_row`).
    """
    return pd.DataFrame([c.as_row() for c in conclusions])


__all__ = ["Conclusion", "task_space_worst", "joint_psmc_equals_pid", "high_integral_gain_helps",
           "lambda_hardly_matters", "lambda_slows_recovery", "pid_violent_psmc_smooth",
           "ki12_step_oscillatory", "OSCILLATORY_MIN_PCT",
           "evaluate_conclusions", "conclusions_table"]
