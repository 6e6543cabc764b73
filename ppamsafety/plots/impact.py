"""Figures of the collision and safety analysis (thesis chapter 6).

Each function takes computed data (DataFrames, result objects) and returns a
matplotlib Figure; nothing here simulates.
"""

from __future__ import annotations

import numpy as np

from ..params.head import MAXILLA_FRACTURE_N
from ..params.iso_ts_15066 import SKULL_FOREHEAD
from .figure import new_figure

FAMILY_COLORS = {"PID": "tab:red", "PSMC joint Ki=2": "tab:blue", "PSMC joint Ki=12": "tab:green",
                 "PSMC task": "tab:purple"}


def plot_impact_history(hist, *, head=None, title: str = "", ax=None):
    """Contact force, head acceleration and penetration of one impact.

    Parameters
    ----------
    hist : pandas.DataFrame
        Time history with columns ``t`` [s], ``F`` [N], ``a_head_g`` [g]
        and ``delta`` [m] (:attr:`ImpactResult.histories` entry).
    head : HeadContactModel, optional
        Head model of the impact (accepted for the caller's convenience;
        not drawn).
    title : str
        Figure title (default "impact time history").
    ax : None
        Not supported (three panels are drawn); ignored.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig, axes = new_figure(3, 1, figsize=(7, 6.5), sharex=True)
    t = hist["t"] * 1e3
    axes[0].plot(t, hist["F"], color="k")
    axes[0].axhline(MAXILLA_FRACTURE_N, color="r", ls="--", lw=1, label="maxilla 660 N")
    axes[0].set_ylabel("contact force [N]")
    axes[0].legend(loc="upper right")
    axes[1].plot(t, hist["a_head_g"], color="tab:blue")
    axes[1].set_ylabel("head acceleration [g]")
    axes[2].plot(t, hist["delta"] * 1e3, color="tab:green")
    axes[2].axhline(0, color="k", lw=0.5)
    axes[2].set_ylabel("penetration [mm]")
    axes[2].set_xlabel("time after impact [ms]")
    for a in axes:
        a.grid(alpha=0.3)
    fig.suptitle(title or "impact time history")
    fig.tight_layout()
    return fig


def plot_worst_histories(items, *, title: str = ""):
    """Force and head-acceleration histories of several impacts.

    Parameters
    ----------
    items : sequence of (str, pandas.DataFrame)
        (label, time history with ``t`` [s], ``F`` [N], ``a_head_g`` [g]).
    title : str
        Figure title (default "worst impacts").

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig, axes = new_figure(1, 2, figsize=(11, 4))
    for label, h in items:
        axes[0].plot(h["t"] * 1e3, h["F"], label=label)
        axes[1].plot(h["t"] * 1e3, h["a_head_g"], label=label)
    axes[0].axhline(MAXILLA_FRACTURE_N, color="r", ls="--", lw=1, label="maxilla 660 N")
    axes[0].set_ylabel("contact force [N]")
    axes[1].set_ylabel("head acceleration [g]")
    for a in axes:
        a.set_xlabel("time after impact [ms]")
        a.set_xlim(0, 25)
        a.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle(title or "worst impacts")
    fig.tight_layout()
    return fig


def plot_safety_table(table, *, experiments=("step", "switch")):
    """F_max and HIC per controller variant with the thesis values and the limit lines.

    F_max panels carry the 660 N maxilla line and the ISO/TS 15066 forehead lines (transient
    2 x 130 N, quasi-static 130 N).

    Parameters
    ----------
    table : pandas.DataFrame
        Columns ``label``, ``family``, ``experiment``, ``F_max`` [N],
        ``HIC36``, ``Fmax_thesis``, ``HIC_thesis`` (the thesis columns are drawn when
        present: the thesis arm).
    experiments : sequence of str
        Experiments to show, one column of panels each.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig, axes = new_figure(2, len(experiments), figsize=(6 * len(experiments), 7.5))
    axes = np.atleast_2d(axes).reshape(2, len(experiments))
    for j, exp in enumerate(experiments):
        sub = table[table["experiment"] == exp].reset_index(drop=True)
        x = np.arange(len(sub))
        colors = [FAMILY_COLORS.get(f, "gray") for f in sub["family"]]
        for i, (col, thcol, ylab) in enumerate((("F_max", "Fmax_thesis", "F_max [N]"),
                                                  ("HIC36", "HIC_thesis", "HIC36 [-]"))):
            a = axes[i, j]
            a.bar(x, sub[col], color=colors, alpha=0.8, label="toolkit")
            if thcol in sub.columns:
                a.plot(x, sub[thcol], "k_", ms=18, mew=2, label="thesis Table 6.1")
            if col == "F_max":
                a.axhline(MAXILLA_FRACTURE_N, color="r", ls="--", lw=1.2, label="maxilla 660 N")
                a.axhline(SKULL_FOREHEAD.force_transient, color="darkorange", ls=":", lw=1.2,
                          label=f"ISO/TS 15066 forehead transient "
                                f"{SKULL_FOREHEAD.force_transient:g} N (not in the TS)")
                a.axhline(SKULL_FOREHEAD.force_quasi_static, color="darkorange", ls="-.",
                          lw=1.0, label=f"ISO/TS 15066 forehead quasi-static "
                                        f"{SKULL_FOREHEAD.force_quasi_static:g} N")
            else:
                a.set_yscale("log")
            a.set_ylabel(ylab)
            a.set_xticks(x)
            a.set_xticklabels(sub["label"], rotation=70, ha="right", fontsize=7)
            a.grid(alpha=0.3, axis="y")
            a.set_title(f"{exp}: {ylab.split()[0]}")
            if i == 0 and j == 0:
                a.legend(fontsize=8)
    fig.tight_layout()
    return fig


def plot_fmax_over_time(items, *, title: str = ""):
    """F_max of an impact at every instant of experiments: items = [(label, summary, marks)].

    Parameters
    ----------
    items : sequence of (str, pandas.DataFrame, dict)
        (panel label, table with columns ``t0`` [s] and ``F_max`` [N],
        {heuristic name: instant t0 [s]} drawn as vertical lines).  A table
        from :func:`~ppamsafety.impact.instants.worst_instant` (columns
        ``F_bound`` and ``simulated``; F_max NaN where pruned) is drawn as the
        bound (grey) and the simulated F_max (dots).
    title : str
        Figure title (default "peak force of an impact at every instant").

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig, axes = new_figure(len(items), 1, figsize=(10, 2.4 * len(items) + 0.5), sharex=True,
                             squeeze=False)
    for a, (label, s, marks) in zip(axes[:, 0], items):
        if "F_bound" in s:
            sim = s["simulated"].to_numpy(bool)
            a.plot(s["t0"], s["F_bound"], color="0.6", lw=0.8, label="upper bound")
            a.plot(s["t0"][sim], s["F_max"][sim], "k.", ms=2, label="simulated F_max")
            a.set_ylim(0.0, 1.3 * max(float(s["F_max"].max()), MAXILLA_FRACTURE_N))
            a.legend(loc="upper right", fontsize=7)
        else:
            a.plot(s["t0"], s["F_max"], color="k", lw=1)
        for name, t0 in marks.items():
            a.axvline(t0, color="tab:orange", lw=0.8, alpha=0.8)
        a.axhline(MAXILLA_FRACTURE_N, color="r", ls="--", lw=1)
        a.set_ylabel("F_max [N]")
        a.set_title(label, fontsize=9)
        a.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("impact instant t0 [s] (orange: the four heuristic instants)")
    fig.suptitle(title or "peak force of an impact at every instant")
    fig.tight_layout()
    return fig


def plot_stiffness_sweep(df, *, reference=None, two_body=None):
    """F_max against joint stiffness (cf. fig. 6.3), with the two-body prediction.

    Parameters
    ----------
    df : pandas.DataFrame
        Columns ``k`` [Nm/rad] and ``F_max`` [N].
    reference : (float, float), optional
        The experiment's joint stiffnesses K1, K2 [Nm/rad], drawn as lines.
    two_body : float, optional
        Two-body F_max [N], drawn as a horizontal line.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig, ax = new_figure(figsize=(7, 4))
    ax.semilogx(df["k"], df["F_max"], "o-", color="k", label="flexible-joint arm model")
    if two_body is not None:
        ax.axhline(two_body, color="tab:blue", ls="--",
                   label=f"two-body, effective mass ({two_body:.0f} N)")
    if reference is not None:
        ax.axvline(reference[0], color="tab:gray", lw=0.8)
        ax.axvline(reference[1], color="tab:gray", lw=0.8, label="K1, K2 of the experiment")
    ax.set_xlabel("joint stiffness k (both joints) [Nm/rad]")
    ax.set_ylabel("F_max [N]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def plot_stiffness_conventions(sweep, *, thesis=None, reference=None):
    """F_max against joint stiffness for each motor-side convention (cf. fig. 6.3).

    Parameters
    ----------
    sweep : pandas.DataFrame
        Columns ``convention`` (``"frozen-equilibrium"``, ``"flexible-joint"``,
        ``"rigid"``), ``B_label``, ``k`` [Nm/rad] (inf for rigid rows) and
        ``F_max`` [N] (the long table of the stiffness study).
    thesis : dict, optional
        Fig. 6.3's reference (:data:`~ppamsafety.impact.thesis_data.FIG_6_3`):
        a band from ``F_level_N`` to ``F_level_N + max_change_N`` over
        ``k_min``..``k_max``.
    reference : (float, float), optional
        The experiment's joint stiffnesses K1, K2 [Nm/rad], drawn as lines.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels: the whole range, and a zoom on 1..6000 Nm/rad (changes in N).
    """
    fig, axes = new_figure(1, 2, figsize=(11, 4.2))
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:olive"]
    fin = sweep[np.isfinite(sweep["k"])]
    kmax = float(fin["k"].max())
    for ax, zoom in zip(axes, (False, True)):
        fr = fin[fin.convention == "frozen-equilibrium"]
        base = fr["F_max"].iloc[0] if zoom else 0.0
        sel = fr[fr.k <= (thesis["k_max"] if zoom and thesis else np.inf)]
        ax.semilogx(sel["k"], sel["F_max"] - base, "o-", color="k", ms=3,
                    label="frozen equilibrium")
        for i, (lab, g) in enumerate(fin[fin.convention == "flexible-joint"].groupby(
                "B_label", sort=False)):
            b0 = g["F_max"].iloc[0] if zoom else 0.0
            gg = g[g.k <= (thesis["k_max"] if zoom and thesis else np.inf)]
            c = colors[i % len(colors)]
            ax.semilogx(gg["k"], gg["F_max"] - b0, "s-", color=c, ms=3,
                        label=f"flexible joint, {lab}")
            rg = sweep[(sweep.convention == "rigid") & (sweep.B_label == lab)]
            if len(rg) and not zoom:
                ax.plot([kmax], [float(rg["F_max"].iloc[0])], marker=">", color=c, ls="none")
        if thesis is not None:
            if zoom:
                ax.fill_between([thesis["k_min"], thesis["k_max"]], 0.0,
                                thesis["max_change_N"], color="tab:red", alpha=0.15,
                                label=f"thesis fig. 6.3: rise < {thesis['max_change_N']:g} N")
            else:
                ax.axhline(thesis["F_level_N"], color="tab:red", ls="--", lw=0.8,
                           label=f"thesis level (Table 6.1, {thesis['F_level_N']:.0f} N)")
        if reference is not None:
            for kk in reference:
                ax.axvline(kk, color="tab:gray", lw=0.6)
        ax.set_xlabel("joint stiffness k (both joints) [Nm/rad]")
        ax.set_ylabel("F_max - F_max(k = 1) [N]" if zoom else "F_max [N]")
        ax.set_title("zoom on fig. 6.3's range" if zoom
                     else "F_max (markers at the right: rigid limit H + diag(B))")
        ax.grid(alpha=0.3, which="both")
    axes[0].legend(fontsize=7, loc="upper left")
    axes[1].legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    return fig


def plot_head_fit(pairs, curve, *, drop=None, title: str = "",
                  label: str = "fitted Hunt-Crossley model"):
    """Table 6.1 (HIC, F_max) pairs against the fitted model's HIC(F_max) curve.

    Parameters
    ----------
    pairs : pandas.DataFrame
        Columns ``experiment``, ``F_max`` [N], ``HIC``.
    curve : pandas.DataFrame
        Columns ``F_max`` [N] and ``HIC36`` of the fitted model.
    drop : None
        Reserved (drop-test marker); ignored.
    title : str
        Axes title (default "one contact model: HIC vs F_max").
    label : str
        Legend label of the model's curve.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig, ax = new_figure(figsize=(6.5, 4.5))
    for exp, marker in (("step", "o"), ("switch", "s")):
        sub = pairs[pairs["experiment"] == exp]
        ax.loglog(sub["F_max"], sub["HIC"], marker, ls="none", label=f"Table 6.1, {exp}")
    ax.loglog(curve["F_max"], curve["HIC36"], "k-", label=label)
    ax.set_xlabel("F_max [N]")
    ax.set_ylabel("HIC36 [-]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    ax.set_title(title or "one contact model: HIC vs F_max")
    fig.tight_layout()
    return fig


def plot_lambda_sweep(df, *, tracking=None):
    """Step-impact F_max and HIC against lambda for each Ki (and tracking error).

    Parameters
    ----------
    df : pandas.DataFrame
        Columns ``lam`` [s], ``Ki_bar`` [bar/(rad s)], ``F_max`` [N],
        ``HIC36`` (and ``tracking``).
    tracking : str, optional
        Column of a tracking error [m] to plot in a third panel.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    ncol = 3 if tracking is not None else 2
    fig, axes = new_figure(1, ncol, figsize=(5 * ncol, 4))
    for ki, sub in df.groupby("Ki_bar"):
        sub = sub.sort_values("lam")
        axes[0].plot(sub["lam"], sub["F_max"], "o-", label=f"Ki = {ki:g} bar/(rad s)")
        axes[1].semilogy(sub["lam"], sub["HIC36"], "o-", label=f"Ki = {ki:g}")
        if tracking is not None:
            axes[2].plot(sub["lam"], sub[tracking] * 1e3, "o-", label=f"Ki = {ki:g}")
    axes[0].axhline(MAXILLA_FRACTURE_N, color="r", ls="--", lw=1, label="maxilla 660 N")
    axes[0].set_ylabel("worst F_max in the step [N]")
    axes[1].set_ylabel("worst HIC36 in the step")
    if tracking is not None:
        axes[2].set_ylabel("mean circle error, P = 10 s [mm]")
    for a in axes:
        a.set_xlabel("lambda [s]")
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=8)
    fig.suptitle("joint-space PSMC: safety and tracking against lambda and Ki")
    fig.tight_layout()
    return fig


def plot_direction_polar(sweeps, *, metric: str = "F_max", title: str = ""):
    """Polar plot of F_max (or HIC36) over the head placement around the tool point.

    One panel per sweep; the angle is the absolute placement direction phi
    (base frame), the radius the engine value; the two-body prediction is
    dashed, the TCP velocity direction (the thesis' placement, fig. 6.2) a
    black ray, and the largest value of the sweep's grid a red marker (the optimiser's
    maximum is in :class:`~ppamsafety.impact.directions.WorstDirection`).

    Parameters
    ----------
    sweeps : sequence of DirectionSweep
        Outputs of :func:`ppamsafety.impact.directions.direction_sweep`.
    metric : {"F_max", "HIC36"}
        Plotted quantity.
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if metric not in ("F_max", "HIC36"):
        raise ValueError(f"metric = {metric!r} must be 'F_max' or 'HIC36'")
    sweeps = list(sweeps)
    if not sweeps:
        raise ValueError("sweeps must hold at least one DirectionSweep")
    pred = {"F_max": "F_pred", "HIC36": "HIC_pred"}[metric]
    unit = " [N]" if metric == "F_max" else ""
    fig, axes = new_figure(1, len(sweeps), figsize=(4.6 * len(sweeps), 5.8), squeeze=False,
                           subplot_kw={"projection": "polar"})
    for ax, sw in zip(axes[0], sweeps):
        t = sw.table
        th = np.radians(t["phi_deg"].to_numpy())
        order = np.argsort(np.unwrap(th - np.radians(sw.velocity_deg)))
        ax.plot(th[order], t[metric].to_numpy()[order], "-", color="tab:blue", label="engine")
        ax.plot(th[order], t[pred].to_numpy()[order], "--", color="tab:gray", lw=1,
                label="two-body prediction")
        rmax = float(max(t[metric].max(), t[pred].max()))
        v = np.radians(sw.velocity_deg)
        ax.plot([v, v], [0, rmax], "k-", lw=1.2, label="TCP velocity (thesis' placement)")
        i = int(np.argmax(t[metric].to_numpy()))
        ax.plot([th[i]], [t[metric].iloc[i]], "o", color="tab:red",
                label=f"grid max: {t[metric].iloc[i]:.4g}{unit} at psi = {t['psi_deg'].iloc[i]:+.1f} deg")
        ax.set_title(sw.label or f"|v_tcp| = {sw.tcp_speed:.2f} m/s", fontsize=9, pad=14)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.06))
    fig.suptitle(title or f"{metric}{unit} over the head placement around the TCP")
    fig.subplots_adjust(left=0.04, right=0.96, top=0.82, bottom=0.27, wspace=0.35)
    return fig


def plot_direction_ratios(table):
    """How much worse the worst head placement is than the thesis placement, per experiment.

    Parameters
    ----------
    table : pandas.DataFrame
        One row per experiment and controller, with columns ``experiment``, ``label``,
        ``ratio_F_max`` and ``ratio_HIC36`` (worst placement / thesis placement, every
        instant), e.g. ``WorstDirectionFindings.table``.

    Returns
    -------
    matplotlib.figure.Figure
        Bars of the excess F_max and HIC36 [%].
    """
    t = table
    fig, ax = new_figure(1, 1, figsize=(8, 4))
    x = np.arange(len(t))
    ax.bar(x - 0.2, 100 * (t["ratio_F_max"] - 1), 0.4, label="F_max", color="tab:blue")
    ax.bar(x + 0.2, 100 * (t["ratio_HIC36"] - 1), 0.4, label="HIC36", color="tab:orange")
    ax.set_xticks(x)
    ax.set_xticklabels([f"{e}: {lab}" for e, lab in zip(t["experiment"], t["label"])],
                       rotation=75, fontsize=6)
    ax.set_ylabel("worst placement vs head along the TCP velocity [%]")
    ax.set_title("how much worse the worst head placement is (every instant)")
    ax.legend()
    fig.tight_layout()
    return fig


def plot_hic_windows(table, *, title: str = ""):
    """HIC of each record drawn over its maximising window.

    Parameters
    ----------
    table : pandas.DataFrame
        Columns ``HIC`` [-], ``t1 [s]``, ``t2 [s]`` (``HICResult.to_pandas()``).
    title : str
        Axes title (default "HIC and its maximising window").

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = new_figure(figsize=(6.5, 4.0))
    for k, row in enumerate(table.itertuples(index=False)):
        hic, t1, t2 = row[0], row[1], row[2]
        ax.plot([1e3 * t1, 1e3 * t2], [hic, hic], "-", lw=3, color=f"C{k % 10}")
        ax.annotate(f"{hic:.4g}", (1e3 * (t1 + t2) / 2, hic), textcoords="offset points",
                    xytext=(0, 4), ha="center", fontsize=7)
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("HIC [-]")
    ax.grid(alpha=0.3)
    ax.set_title(title or "HIC and its maximising window")
    fig.tight_layout()
    return fig


def plot_worst_instants(table, *, worst_F: float, worst_HIC: float, title: str = ""):
    """F_max and HIC36 over the impact instant t0: the rigorous bounds, the screening values
    and the exactly simulated instants, with the worst instants marked.

    Parameters
    ----------
    table : pandas.DataFrame
        ``WorstInstants.table``: ``t0`` [s], ``F_bound`` [N], ``HIC36_bound``, ``F_screen``,
        ``HIC36_screen``, ``F_max`` [N], ``HIC36`` (NaN where not evaluated).
    worst_F, worst_HIC : float
        Instants [s] of the largest F_max and HIC36.
    title : str
        Figure title (default "worst impact instant").

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = new_figure(2, 1, figsize=(7, 5.5), sharex=True)
    t = 1e3 * table["t0"].to_numpy()
    for ax, (bound, screen, exact, worst, unit) in zip(axes, (
            ("F_bound", "F_screen", "F_max", worst_F, "F_max [N]"),
            ("HIC36_bound", "HIC36_screen", "HIC36", worst_HIC, "HIC36 [-]"))):
        ax.plot(t, table[bound], "-", color="0.6", lw=0.8, label="upper bound")
        ax.plot(t, table[screen], ".", ms=3, color="tab:blue", label="screened")
        ax.plot(t, table[exact], "o", ms=4, color="tab:red", label="simulated")
        ax.axvline(1e3 * worst, color="k", ls="--", lw=0.8, label="worst instant")
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    axes[1].set_xlabel("impact instant t0 [ms]")
    axes[0].set_title(title or "worst impact instant")
    fig.tight_layout()
    return fig


def plot_verdicts(table, *, title: str = ""):
    """Every verdict as its value over its limit, one bar per criterion and head model.

    Parameters
    ----------
    table : pandas.DataFrame
        Verdict rows (``ppamsafety.impact.verdicts.VERDICT_COLUMNS``): ``criterion``,
        ``value``, ``limit``, ``unit``, ``passed``, ``head_model``, ``region``.
    title : str
        Axes title (default: the region and contact point of the first row).

    Returns
    -------
    matplotlib.figure.Figure
        Horizontal bars of value / limit [%] (green: passes, red: fails), the limit at
        100 % dashed; each bar is labelled with its value and limit in their units.
    """
    t = table.reset_index(drop=True)
    n = len(t)
    fig, ax = new_figure(figsize=(8.5, 1.2 + 0.38 * max(n, 1)))
    ratio = 100.0 * t["value"].to_numpy(float) / t["limit"].to_numpy(float)
    y = np.arange(n)
    heads = t["head_model"].astype(str)
    several = heads.nunique() > 1
    labels = [f"{c} ({h})" if several and h else str(c)
              for c, h in zip(t["criterion"], heads)]
    ax.barh(y, ratio, color=np.where(t["passed"].to_numpy(bool), "tab:green", "tab:red"),
            alpha=0.8)
    for k, r in t.iterrows():
        unit = f" {r['unit']}" if str(r["unit"]) not in ("", "-") else ""
        ax.text(max(ratio[k], 0.0) + 1.0, k, f"{r['value']:.4g}{unit} / {r['limit']:.4g}{unit}",
                va="center", fontsize=7)
    ax.axvline(100.0, color="k", ls="--", lw=1.0, label="limit")
    ax.set_yticks(y)
    ax.set_yticklabels(labels, fontsize=7)
    ax.invert_yaxis()
    ax.set_xlim(0.0, max(130.0, 1.25 * float(np.nanmax(ratio)) if n else 130.0))
    ax.set_xlabel("value / limit [%]")
    ax.grid(alpha=0.3, axis="x")
    ax.legend(fontsize=7, loc="lower right")
    if not title and n:
        title = f"{t['region'].iloc[0]}, contact at {t['contact_point'].iloc[0]}"
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def plot_drop_test(history, *, corridor_g, peak_g_cfc: float, title: str = ""):
    """The head drop's acceleration against time, raw and filtered, with the corridor.

    Parameters
    ----------
    history : pandas.DataFrame
        ``t`` [s], ``a_g`` and ``a_g_cfc`` [g] (``ppamsafety.impact.bodies.DropTest.history``).
    corridor_g : (float, float)
        The standard's corridor of the filtered peak [g]
        (``ppamsafety.impact.bodies.HYBRID3_CORRIDOR_G``).
    peak_g_cfc : float
        The filtered peak [g] (marked).
    title : str
        Axes title.

    Returns
    -------
    matplotlib.figure.Figure
        Resultant acceleration [g] against time after first touch [ms], the corridor shaded.
    """
    h = history
    t_ms = 1e3 * h["t"].to_numpy(float)
    a = h["a_g"].to_numpy(float)
    af = h["a_g_cfc"].to_numpy(float)
    lo, hi = corridor_g
    k = int(np.argmax(af))
    low = np.nonzero(np.abs(af[k:]) <= 0.01 * max(af[k], 1e-300))[0]
    end = min(2.0 * t_ms[k + low[0]], t_ms[-1]) if low.size else t_ms[-1]
    fig, ax = new_figure(figsize=(6.5, 4.2))
    ax.axhspan(lo, hi, color="tab:green", alpha=0.15, label=f"corridor {lo:g}-{hi:g} g")
    ax.plot(t_ms, a, color="0.6", lw=1.0, label="raw")
    ax.plot(t_ms, af, color="tab:blue", lw=1.5, label="CFC 1000")
    ax.plot(t_ms[k], af[k], "o", color="tab:red",
            label=f"filtered peak {peak_g_cfc:.0f} g")
    ax.set_xlim(0.0, end)
    ax.set_xlabel("time after first touch [ms]")
    ax.set_ylabel("resultant head acceleration [g]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title or "Hybrid III head drop (49 CFR 572.32)", fontsize=9)
    fig.tight_layout()
    return fig


def plot_direction_optimum(evaluated, *, psi_F: float, psi_HIC: float, title: str = ""):
    """F_max and HIC36 at every head placement the search evaluated, the optima marked.

    Parameters
    ----------
    evaluated : pandas.DataFrame
        ``psi`` [rad from the TCP velocity], ``F_max`` [N], ``HIC36`` [-], one row per
        engine run (``ppamsafety.impact.directions.DirectionOptimum.evaluated``).
    psi_F, psi_HIC : float
        Placements maximising F_max and HIC36 [rad].
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels against psi [deg]: F_max [N] and HIC36 [-], psi = 0 (the head along
        the TCP velocity, the thesis' placement) dotted, the worst placement starred.
    """
    e = evaluated.sort_values("psi")
    deg = np.degrees(e["psi"].to_numpy(float))
    fig, axes = new_figure(1, 2, figsize=(10, 3.8))
    for ax, col, psi, unit in ((axes[0], "F_max", psi_F, "[N]"),
                               (axes[1], "HIC36", psi_HIC, "[-]")):
        v = e[col].to_numpy(float)
        ax.plot(deg, v, "o-", ms=3, lw=0.8, label="evaluated placements")
        k = int(np.argmin(np.abs(e["psi"].to_numpy(float) - psi)))
        ax.plot(deg[k], v[k], "*", color="tab:red", ms=12,
                label=f"worst: {v[k]:.4g} at {np.degrees(psi):.1f} deg")
        ax.axvline(0.0, color="k", ls=":", lw=0.8, label="along the TCP velocity")
        ax.set_xlabel("head placement psi from the TCP velocity [deg]")
        ax.set_ylabel(f"{col} {unit}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(title or "worst head placement of one impact state", fontsize=10)
    fig.tight_layout()
    return fig
