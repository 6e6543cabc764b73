"""Figures of the effects study (:mod:`ppamsafety.sections.effects`).

Each function takes computed data and returns a matplotlib Figure (no pyplot);
nothing here simulates.
"""

from __future__ import annotations

import numpy as np

from .figure import new_figure

PLANT_STYLES = {"nominal": dict(color="tab:gray", marker="o", mfc="none"),
                "hysteresis": dict(color="tab:red", marker="s")}


def plot_sawtooth_angles(windows: dict):
    """Set and settled angles per data window (cf. thesis fig. 3.1).

    Parameters
    ----------
    windows : dict
        Plant label -> :func:`ppamsafety.sections.effects.sawtooth_windows` table.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels (q1, q2): set angle and window-mean angle [deg] against
        the window number (not true time, as in fig. 3.1).
    """
    fig, axes = new_figure(2, 1, figsize=(7, 5.5), sharex=True)
    first = next(iter(windows.values()))
    for j, ax in enumerate(axes, start=1):
        ax.step(first.level, first[f"q{j}_d_deg"], where="mid", color="k", lw=1, label="set")
        for lab, w in windows.items():
            ax.plot(w.level, w[f"q{j}_deg"], ls="none", label=lab, **PLANT_STYLES.get(lab, {}))
        ax.set_ylabel(f"q{j} [deg]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("data window (3 s after each change, 1 s mean)")
    fig.suptitle("gravity compensation alone, sawtooth set angles")
    fig.tight_layout()
    return fig


def plot_sawtooth_errors(windows: dict):
    """Angle error q - q_d per window, coloured by the direction of the last change.

    Parameters
    ----------
    windows : dict
        Plant label -> :func:`ppamsafety.sections.effects.sawtooth_windows` table.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per joint: error [deg] against the set angle, rising and
        falling approaches marked separately, one line per plant.
    """
    fig, axes = new_figure(1, 2, figsize=(9, 3.8))
    for j, ax in enumerate(axes, start=1):
        for lab, w in windows.items():
            st = PLANT_STYLES.get(lab, {})
            for d, mk in (("rising", "^"), ("falling", "v")):
                s = w[w[f"dir{j}"] == d]
                ax.plot(s[f"q{j}_d_deg"], s[f"e{j}_deg"], ls="none", marker=mk,
                        color=st.get("color"), mfc=st.get("mfc", st.get("color")),
                        label=f"{lab}, {d}")
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xlabel(f"q{j} set angle [deg]")
        ax.set_ylabel(f"q{j} - q{j}_d [deg]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    return fig


def plot_sawtooth_forces(window, *, groups=(3, 4)):
    """Plant muscle forces vs the nominal model per window (cf. thesis fig. 3.2).

    Parameters
    ----------
    window : pandas.DataFrame
        :func:`ppamsafety.sections.effects.sawtooth_windows` table of the
        plant with hysteresis.
    groups : sequence of int
        Muscle groups drawn (default the link-2 muscles 3 and 4).

    Returns
    -------
    matplotlib.figure.Figure
        One panel per group: plant and model force [N] against the window.
    """
    fig, axes = new_figure(len(groups), 1, figsize=(7, 2.6 * len(groups)), sharex=True)
    axes = np.atleast_1d(axes)
    for k, ax in zip(groups, axes):
        ax.plot(window.level, window[f"F{k}_model"], "o--", mfc="none", color="tab:gray",
                label="model (3.9) at the same p, ε")
        ax.plot(window.level, window[f"F{k}_plant"], "s-", color="tab:red",
                label="plant (hysteresis)")
        ax.set_ylabel(f"F{k} [N]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("data window")
    fig.tight_layout()
    return fig


def plot_ratio_shift(comparison: dict, table_6_1: dict):
    """Ratio toolkit / thesis without (x) and with (y) hysteresis, Tables 5.2 and 6.1.

    Parameters
    ----------
    comparison : dict
        Plant label -> :func:`ppamsafety.sections.tracking.compare_with_thesis` table.
    table_6_1 : dict
        Plant label -> Table 6.1 table with ``HIC_ratio``, ``Fmax_ratio``.

    Returns
    -------
    matplotlib.figure.Figure
        Log-log scatter per table; points nearer the line y = 1 than
        x = 1 moved toward the thesis.
    """
    fig, axes = new_figure(1, 2, figsize=(9, 4))
    a, b = comparison["nominal"], comparison["hysteresis"]
    ax = axes[0]
    for col, mk in (("ratio_mean", "o"), ("ratio_max", "^")):
        ax.plot(a[col], b[col], ls="none", marker=mk, label=col.replace("ratio_", ""))
    ax.set_title("Table 5.2 (circle errors)")
    a, b = table_6_1["nominal"], table_6_1["hysteresis"]
    axes[1].plot(a.HIC_ratio, b.HIC_ratio, "o", ls="none", label="HIC36")
    axes[1].plot(a.Fmax_ratio, b.Fmax_ratio, "^", ls="none", label="F_max")
    axes[1].set_title("Table 6.1 (impacts)")
    for ax in axes:
        ax.set_xscale("log")
        ax.set_yscale("log")
        lo, hi = ax.get_xlim()
        ax.plot([lo, hi], [lo, hi], color="k", lw=0.6, label="unchanged")
        ax.axhline(1, color="tab:green", lw=0.8)
        ax.axvline(1, color="tab:green", lw=0.8)
        ax.set_xlabel("ratio toolkit / thesis, nominal plant [-]")
        ax.set_ylabel("ratio, with hysteresis [-]")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


