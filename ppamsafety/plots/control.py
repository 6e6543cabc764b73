"""Plots of closed-loop experiments (thesis figs. 5.10-5.19, SMC chattering).

Every function takes result objects (``ExperimentResult``) or DataFrames that
were computed elsewhere and returns a matplotlib Figure; nothing here
simulates.  Colours identify the controller family (PID black, joint PSMC
Ki = 2 blue, joint PSMC Ki = 12 green, task PSMC red), line styles lambda
(0.4 s solid, 0.8 s dashed, 1.5 s dotted).  Angles are plotted in degrees,
angular velocities in rad/s, distances in mm.
"""

from __future__ import annotations

import numpy as np

from ..units import BAR, DEG
from .figure import new_figure

FAMILY_COLORS = {"PID": "black", "PSMC joint Ki=2": "tab:blue", "PSMC joint Ki=12": "tab:green",
                 "PSMC task": "tab:red", "SMC": "tab:purple"}
LAMBDA_STYLES = {0.4: "-", 0.8: "--", 1.5: ":"}
LAMBDA_COLORS = {0.4: "tab:blue", 0.8: "tab:orange", 1.5: "tab:green"}


def _label(result) -> str:
    return result.meta.get("label", result.name)


def _style(result, *, by="family") -> dict:
    """Line colour and style of a run from its ``meta`` (family, lambda)."""
    fam = result.meta.get("family", result.controller.get("controller", ""))
    lam = result.meta.get("lambda_s", np.nan)
    lam = None if lam is None or not np.isfinite(lam) else round(float(lam), 3)
    if by == "lambda" and lam is not None:
        return {"color": LAMBDA_COLORS.get(lam, "tab:gray"), "ls": "-"}
    return {"color": FAMILY_COLORS.get(fam, None), "ls": LAMBDA_STYLES.get(lam, "-")}


def _mark_events(ax, times):
    for t in times:
        ax.axvline(t, color="0.6", lw=0.8, ls=":", zorder=0)


def plot_experiment(result, *, title: str | None = None, t_range=None):
    """Joint angles vs reference, TCP error and joint velocities of one run.

    Parameters
    ----------
    result : ExperimentResult
    title : str, optional
        Figure title (default: the run's name and controller).
    t_range : (float, float), optional
        Time window [s] to show.
    """
    t = result.t
    fig, axes = new_figure(3, 1, figsize=(10.5, 7.5), sharex=True)
    a = axes[0]
    for j, c in enumerate(("tab:blue", "tab:orange")):
        a.plot(t, result.signal(f"q{j + 1}_d") / DEG, color=c, ls="--", lw=1,
               label=f"$q_{j + 1}$ desired")
        a.plot(t, result.signal(f"q{j + 1}") / DEG, color=c, lw=1.3, label=f"$q_{j + 1}$")
    a.set_ylabel("angle [deg]")
    a.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[1].plot(t, result.tracking_error() * 1e3, color="k", lw=1)
    axes[1].set_ylabel(r"$\|r_d - r\|$ [mm]")
    for j, c in enumerate(("tab:blue", "tab:orange")):
        axes[2].plot(t, result.signal(f"qd{j + 1}_meas"), color=c, lw=0.6, alpha=0.6,
                     label=fr"$\dot q_{j + 1}$ measured")
        axes[2].plot(t, result.signal(f"qd{j + 1}"), color=c, lw=1.2,
                     label=fr"$\dot q_{j + 1}$")
    axes[2].set_ylabel("angular velocity [rad/s]")
    axes[2].set_xlabel("t [s]")
    axes[2].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    for a in axes:
        a.grid(alpha=0.3)
    if t_range is not None:
        axes[0].set_xlim(*t_range)
    ctrl = result.controller.get("controller", "")
    fig.suptitle(title or f"{result.name} ({ctrl})" + ("  -- DIVERGED" if result.diverged else ""))
    fig.tight_layout()
    return fig


def plot_step_comparison(results, *, title: str, events=(), t_range=None):
    """Step responses: q1, q2 [deg] and qd1, qd2 [rad/s] of several runs (figs. 5.17-5.19).

    Parameters
    ----------
    results : sequence of ExperimentResult
        Runs of the same step reference (drawn dashed grey from the first).
    title : str
        Figure title.
    events : sequence of float
        Times [s] marked with vertical lines.
    t_range : (float, float), optional
        Time window [s] to show.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    results = list(results)
    if not results:
        raise ValueError("plot_step_comparison: no results")
    fig, axes = new_figure(2, 2, figsize=(11, 6.5), sharex=True)
    t = results[0].t
    for j in range(2):
        axes[0, j].plot(t, results[0].signal(f"q{j + 1}_d") / DEG, color="0.5", ls="--", lw=1.2,
                        label="desired")
    for r in results:
        st = _style(r)
        for j in range(2):
            axes[0, j].plot(r.t, r.signal(f"q{j + 1}") / DEG, lw=1.3, label=_label(r), **st)
            axes[1, j].plot(r.t, r.signal(f"qd{j + 1}"), lw=1.1, label=_label(r), **st)
    for j in range(2):
        axes[0, j].set_ylabel(f"$q_{j + 1}$ [deg]")
        axes[1, j].set_ylabel(fr"$\dot q_{j + 1}$ [rad/s]")
        axes[1, j].set_xlabel("t [s]")
    for a in axes.ravel():
        a.grid(alpha=0.3)
        _mark_events(a, events)
        if t_range is not None:
            a.set_xlim(*t_range)
    axes[0, 0].legend(fontsize=8, loc="best")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def plot_switch(results, *, title: str, t_switch: float, circle_center, circle_radius: float,
                t_range=None):
    """Response to the trajectory switch (figs. 5.15-5.16).

    Panels: TCP path from the switch on (target circle dashed), TCP error
    [mm], TCP speed [m/s] and q1 [deg] against time.

    Parameters
    ----------
    results : sequence of ExperimentResult
        Runs of the same switch reference.
    title : str
        Figure title.
    t_switch : float
        Switch time [s].
    circle_center : (float, float)
        Centre of the target circle [m].
    circle_radius : float
        Radius of the target circle [m].
    t_range : (float, float), optional
        Time window [s] of the time plots.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    results = list(results)
    if not results:
        raise ValueError("plot_switch: no results")
    fig, axes = new_figure(2, 2, figsize=(11, 7.5))
    a = axes[0, 0]
    ang = np.linspace(0, 2 * np.pi, 361)
    a.plot(circle_center[0] + circle_radius * np.cos(ang), circle_center[1]
           + circle_radius * np.sin(ang), color="0.5", ls="--", lw=1, label="desired circle")
    ref_xy = results[0].signals("x_d", "y_d")
    k_sw = int(np.searchsorted(results[0].t, t_switch))
    a.plot(*ref_xy[k_sw - 1], "o", color="0.3", ms=5, label="desired, before switch")
    a.plot(*ref_xy[k_sw], "s", color="0.3", ms=5, label="desired, after switch")
    for r in results:
        m = r.t >= t_switch
        a.plot(r.signal("x")[m], r.signal("y")[m], lw=1.2, label=_label(r), **_style(r))
    a.set_aspect("equal")
    a.set_xlabel("x [m]")
    a.set_ylabel("y [m]")
    a.set_title("TCP path after the switch")
    handles, labels = a.get_legend_handles_labels()
    for r in results:
        st = _style(r)
        axes[0, 1].plot(r.t, r.tracking_error() * 1e3, lw=1.2, **st)
        axes[1, 0].plot(r.t, r.tcp_speed(), lw=1.2, **st)
        axes[1, 1].plot(r.t, r.signal("q1") / DEG, lw=1.2, **st)
    axes[1, 1].plot(results[0].t, results[0].signal("q1_d") / DEG, color="0.5", ls="--", lw=1,
                    label="desired")
    axes[1, 1].legend(fontsize=8)
    axes[0, 1].set_ylabel(r"$\|r_d - r\|$ [mm]")
    axes[1, 0].set_ylabel("TCP speed [m/s]")
    axes[1, 1].set_ylabel("$q_1$ [deg]")
    for a in (axes[0, 1], axes[1, 0], axes[1, 1]):
        a.set_xlabel("t [s]")
        a.grid(alpha=0.3)
        _mark_events(a, [t_switch])
        if t_range is not None:
            a.set_xlim(*t_range)
    fig.suptitle(title)
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 6), fontsize=8)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    return fig


def plot_lambda_recovery(results, *, experiment: str, title: str, events=(), tol=None,
                         t_range=None):
    """Recovery from a large error for lambda = 0.4, 0.8, 1.5 s, one panel per PSMC family.

    ``experiment="step"`` plots q1 [deg] (reference dashed), ``"switch"`` the
    TCP error [mm] on a log scale with the tolerance band ``tol`` [m].  PID
    (if among the results) is drawn in every panel in grey for comparison.

    Parameters
    ----------
    results : sequence of ExperimentResult
        Runs with ``meta`` ``family`` and ``lambda_s`` (thesis variants).
    experiment : {"step", "switch"}
        Which quantity to plot (see above).
    title : str
        Figure title.
    events : sequence of float
        Times [s] marked with vertical lines.
    tol : float, optional
        Tolerance band [m] drawn for ``"switch"``.
    t_range : (float, float), optional
        Time window [s] to show.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    if experiment not in ("step", "switch"):
        raise ValueError(f"experiment = {experiment!r} is not 'step' or 'switch'")
    results = list(results)
    fams = [f for f in ("PSMC joint Ki=2", "PSMC joint Ki=12", "PSMC task")
            if any(r.meta.get("family") == f for r in results)]
    if not fams:
        raise ValueError("plot_lambda_recovery: no PSMC results")
    pid = [r for r in results if r.meta.get("family") == "PID"]
    fig, axes = new_figure(1, len(fams), figsize=(4.2 * len(fams), 4), sharey=True,
                             squeeze=False)
    for a, fam in zip(axes[0], fams):
        for r in pid + [r for r in results if r.meta.get("family") == fam]:
            is_pid = r.meta.get("family") == "PID"
            st = {"color": "0.6", "ls": "-"} if is_pid else _style(r, by="lambda")
            y = r.signal("q1") / DEG if experiment == "step" else r.tracking_error() * 1e3
            lab = "PID" if is_pid else f"λ = {r.meta.get('lambda_s'):g} s"
            a.plot(r.t, y, lw=1.2, label=lab, **st)
        if experiment == "step":
            a.plot(results[0].t, results[0].signal("q1_d") / DEG, color="k", ls="--",
                   lw=0.8, label="desired")
            a.set_ylabel("$q_1$ [deg]")
        else:
            a.set_yscale("log")
            a.set_ylabel(r"$\|r_d - r\|$ [mm]")
            if tol is not None:
                a.axhline(tol * 1e3, color="k", lw=0.8, ls="--", label=f"{tol * 1e3:g} mm")
        a.set_title(fam)
        a.set_xlabel("t [s]")
        a.grid(alpha=0.3, which="both")
        _mark_events(a, events)
        if t_range is not None:
            a.set_xlim(*t_range)
        a.legend(fontsize=8, loc="best")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def plot_error_traces(panels, *, title: str, t_range=None, sharey: bool = True,
                      ylabel: str = r"$\|r_d - r\|$ [mm]"):
    """Task-space error against time, one panel per entry of ``panels``.

    Parameters
    ----------
    panels : dict
        Panel title -> list of (label, ExperimentResult) or (label,
        ExperimentResult, line-style dict) (figs. 5.11, 5.14).  Without a
        style dict the family/lambda style of the run is used.
    title : str
        Figure title.
    t_range : (float, float), optional
        Time window [s] to show.
    sharey : bool
        Share the error axis between panels.
    ylabel : str
        Label of the error axes.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    if not panels:
        raise ValueError("plot_error_traces: no panels")
    fig, axes = new_figure(len(panels), 1, figsize=(12, 2.6 * len(panels) + 0.6),
                             sharey=sharey, squeeze=False)
    for a, (name, runs) in zip(axes[:, 0], panels.items()):
        for entry in runs:
            label, r = entry[0], entry[1]
            st = entry[2] if len(entry) > 2 else _style(r)
            a.plot(r.t, r.tracking_error() * 1e3, label=label, **{"lw": 1.0, **st})
        a.set_title(name, fontsize=10)
        a.set_ylabel(ylabel)
        a.grid(alpha=0.3)
        a.set_ylim(bottom=0)
        if t_range is not None:
            a.set_xlim(*t_range)
        a.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def plot_tracking_comparison(table):
    """Table 5.2 side by side: toolkit vs thesis mean (bars) and max (markers) error.

    Parameters
    ----------
    table : pandas.DataFrame
        Long format with columns ``variant``, ``family``, ``period_s``,
        ``mean_m``, ``max_m``, ``thesis_mean_m``, ``thesis_max_m``.
    """
    periods = sorted(table.period_s.unique())
    variants = list(dict.fromkeys(table.variant))
    x = np.arange(len(variants))
    fig, axes = new_figure(1, len(periods), figsize=(5 * len(periods), 4.8), sharey=True,
                             squeeze=False)
    for a, P in zip(axes[0], periods):
        g = table[table.period_s == P].set_index("variant").loc[variants]
        cols = [FAMILY_COLORS.get(f, "gray") for f in g.family]
        a.bar(x - 0.2, g.mean_m * 1e3, 0.4, color=cols, label="toolkit mean")
        a.bar(x + 0.2, g.thesis_mean_m * 1e3, 0.4, color=cols, alpha=0.35, hatch="//",
              edgecolor="k", lw=0.3, label="thesis mean")
        a.plot(x - 0.2, g.max_m * 1e3, "v", color="k", ms=5, label="toolkit max")
        a.plot(x + 0.2, g.thesis_max_m * 1e3, "v", mfc="none", color="k", ms=5,
               label="thesis max")
        a.set_xticks(x)
        a.set_xticklabels(variants, rotation=60, ha="right", fontsize=7)
        a.set_title(f"circle P = {P:g} s")
        a.grid(alpha=0.3, axis="y")
        a.set_yscale("log")
    axes[0, 0].set_ylabel(r"$\|r_d - r\|$ [mm] (log)")
    axes[0, 0].legend(fontsize=8, loc="upper left")
    fig.suptitle("Table 5.2: tracking error over 40 s, toolkit (solid) vs thesis hardware "
                 "(hatched); triangles: maximum")
    fig.tight_layout()
    return fig


def plot_smc_chattering(sweep, *, default_gamma: float | None = None, reference=None):
    """Chattering and tracking error vs boundary-layer width, per valve time constant.

    Parameters
    ----------
    sweep : pandas.DataFrame
        One row per run with ``gamma`` [rad/s^2], ``plant_T`` [s] (valve 1),
        ``model`` (label of the controller's valve model), ``chattering_Pa``,
        ``mean_error_m`` and ``diverged``.
    default_gamma : float, optional
        Marked with a vertical line.
    reference : (float, float, str), optional
        Chattering index [Pa] and mean error [m] of a reference controller
        and its label, drawn as horizontal dashed lines.
    """
    fig, axes = new_figure(1, 2, figsize=(12, 4.8))
    Ts = sorted(sweep.plant_T.unique())
    colors = dict(zip(Ts, ("tab:blue", "tab:orange", "tab:red", "tab:purple", "tab:green")))
    models = list(dict.fromkeys(sweep.model))
    styles = dict(zip(models, ("-o", "--s", ":^", "-.d")))
    for (T, model), g in sweep.groupby(["plant_T", "model"], sort=False):
        g = g.sort_values("gamma")
        ok = ~g.diverged.astype(bool)
        lab = f"plant T = {1e3 * T:g} ms, {model}"
        for a, col, scale in ((axes[0], "chattering_Pa", 1 / BAR), (axes[1], "mean_error_m", 1e3)):
            a.plot(g.gamma[ok], g[col][ok] * scale, styles[model], color=colors[T], ms=4,
                   lw=1.3, label=lab)
            if (~ok).any():        # diverged runs: crosses along the top edge
                a.plot(g.gamma[~ok], np.full((~ok).sum(), 0.97), "x", color=colors[T], ms=7,
                       transform=a.get_xaxis_transform(), clip_on=False)
    for a in axes:
        a.set_xscale("log")
        a.set_yscale("log")
        a.set_xlabel(r"boundary-layer width $\Gamma$ [rad/s$^2$]")
        a.grid(alpha=0.3, which="both")
        if default_gamma is not None:
            a.axvline(default_gamma, color="k", lw=0.8, ls=":")
    if reference is not None:
        axes[0].axhline(reference[0] / BAR, color="k", ls="--", lw=1.0, label=reference[2])
        axes[1].axhline(reference[1] * 1e3, color="k", ls="--", lw=1.0, label=reference[2])
    axes[0].set_ylabel(r"chattering: RMS of commanded $\Delta p$ above 5 Hz [bar]")
    axes[1].set_ylabel(r"mean tracking error $\|r_d - r\|$ [mm]")
    axes[0].set_title("chattering (x at the top: run diverged)")
    axes[1].set_title("tracking (circle P = 5 s)")
    axes[1].legend(fontsize=7, loc="best")
    fig.suptitle("Sliding mode control: boundary layer vs valve time constant "
                 "(SISO, realistic sensors; dotted: default Γ)")
    fig.tight_layout()
    return fig


def plot_smc_commands(panels, *, title: str, t_range=None):
    """Commanded Delta p1 [bar] against time, one line per (label, result) entry.

    Parameters
    ----------
    panels : dict
        Panel title -> list of (label, ExperimentResult).
    title : str
        Figure title.
    t_range : (float, float), optional
        Time window [s] to show.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig, axes = new_figure(len(panels), 1, figsize=(10, 2.5 * len(panels) + 0.6),
                             sharex=True, squeeze=False)
    for a, (name, runs) in zip(axes[:, 0], panels.items()):
        for label, r in runs:
            a.plot(r.t, r.signal("dp1") / BAR, lw=0.7, label=label)
        a.set_title(name, fontsize=10)
        a.set_ylabel(r"$\Delta p_1$ command [bar]")
        a.grid(alpha=0.3)
        if len(runs) > 1:
            a.legend(fontsize=8, loc="upper right")
        if t_range is not None:
            a.set_xlim(*t_range)
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


__all__ = ["plot_experiment", "plot_step_comparison", "plot_switch", "plot_lambda_recovery",
           "plot_error_traces", "plot_tracking_comparison", "plot_smc_chattering",
           "plot_smc_commands"]
