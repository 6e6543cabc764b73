"""Plots of clamping and ISO/TS 15066 power and force limiting (pyplot-free).

Every function takes data computed elsewhere (:class:`~ppamsafety.impact.clamping.ClampingResult`
or :class:`~ppamsafety.sections.iso_15066.IsoFindings`) and returns a Figure.
"""

from __future__ import annotations

import numpy as np

from ..params.iso_ts_15066 import FACE, SKULL_FOREHEAD
from .figure import new_figure


def _limit_lines(ax, *, transient=True, quasi_static=True, horizontal=True):
    styles = []
    if transient:
        styles += [(SKULL_FOREHEAD.force_transient, "tab:red", "--", "forehead transient (2x)"),
                   (FACE.force_transient, "tab:orange", "--", "face transient (2x)")]
    if quasi_static:
        styles += [(SKULL_FOREHEAD.force_quasi_static, "tab:red", ":", "forehead quasi-static"),
                   (FACE.force_quasi_static, "tab:orange", ":", "face quasi-static")]
    for val, c, ls, lab in styles:
        (ax.axhline if horizontal else ax.axvline)(val, color=c, ls=ls, lw=1.2, label=lab)


def plot_clamping_histories(results):
    """Tool-head and head-wall forces of every case of a clamping simulation.

    Parameters
    ----------
    results : ClampingResult
        Output of :func:`ppamsafety.impact.clamping.simulate_clamping`.
    """
    fig, ax = new_figure(figsize=(7.0, 4.0))
    for i in range(results.force.shape[0]):
        line, = ax.plot(results.t * 1e3, results.force[i], lw=1.2, label=f"case {i} tool")
        ax.plot(results.t * 1e3, results.wall_force[i], lw=1.0, ls="--", color=line.get_color())
    ax.set_xlabel("t - t0 [ms]")
    ax.set_ylabel("force [N] (solid: tool-head, dashed: head-wall)")
    ax.set_title(f"Transient clamping: head {results.head}, wall {results.wall}")
    ax.grid(alpha=0.3)
    return fig


def plot_clamping_vs_limits(study):
    """Clamped and free peak forces per controller against the ISO head limits.

    Parameters
    ----------
    study : IsoFindings
        Output of :func:`ppamsafety.sections.iso_15066.compute`.
    """
    ct = study.clamp_transient
    labels = list(dict.fromkeys(ct.label))
    fig, ax = new_figure(figsize=(9.0, 4.8))
    x = np.arange(len(labels))
    hc = next((h for h in dict.fromkeys(ct["head_model"]) if h not in ("skull/forehead", "face")),
              "thesis HC")      # the Hunt-Crossley head: "thesis HC", or the report's
    for k, (head, c) in enumerate((("skull/forehead", "tab:red"), ("face", "tab:orange"),
                                   (hc, "tab:blue"))):
        s = ct[ct["head_model"] == head].set_index("label").loc[labels]
        ax.plot(x + (k - 1) * 0.2, s.F_clamped, "o", color=c, label=f"clamped, {head}")
        ax.plot(x + (k - 1) * 0.2, s.F_free, "x", color=c, ms=8, label=f"free, {head}")
    _limit_lines(ax)
    ax.set_yscale("log")
    ax.set_xticks(x)
    ax.set_xticklabels(labels, rotation=35, ha="right", fontsize=7)
    ax.set_ylabel("peak contact force [N]")
    ax.set_title("Transient clamping vs ISO/TS 15066 head limits")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=6, ncol=3)
    fig.tight_layout()
    return fig


def plot_quasi_static(study):
    """Closed-loop clamping force histories per controller with the static bound and limits.

    Parameters
    ----------
    study : IsoFindings
        Output of :func:`ppamsafety.sections.iso_15066.compute`.
    """
    fig, ax = new_figure(figsize=(8.0, 4.5))
    for label, (t, f) in study.qs_histories.items():
        ax.plot(t, f, lw=1.0, label=label)
    bound = float(study.static_bounds.set_index("mode").loc["hardware", "F_max_N"])
    ax.axhline(bound, color="k", ls="-.", lw=1.2, label="static bound (0..3 bar, anywhere)")
    _limit_lines(ax, transient=False)
    ax.set_ylim(0, max(1.2 * SKULL_FOREHEAD.force_quasi_static, 1.1 * bound))
    ax.set_xlabel("time since clamping [s]")
    ax.set_ylabel("contact force |f| [N]")
    ax.set_title("Quasi-static clamping in the closed loop (step 30->70 deg)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    return fig


def plot_lambda_limits(study):
    """Worst free-impact force and tool speed against lambda per PSMC family and region.

    Parameters
    ----------
    study : IsoFindings
        Output of :func:`ppamsafety.sections.iso_15066.compute`.
    """
    fig, axes = new_figure(1, 2, figsize=(10.0, 4.2))
    free = study.free
    worst = free.loc[free.groupby(["label", "head_model"], sort=False)["F_max"].idxmax()]
    colors = {"PSMC joint Ki=2": "tab:blue", "PSMC joint Ki=12": "tab:green",
              "PSMC task": "tab:purple"}
    for fam, c in colors.items():
        for head, ls in (("skull/forehead", "-"), ("face", "--")):
            s = worst[(worst.family == fam) & (worst["head_model"] == head)].sort_values("lambda")
            axes[0].plot(s["lambda"], s.F_max, ls, color=c, marker="o", ms=3,
                         label=f"{fam}, {head}")
        s = worst[(worst.family == fam) & (worst["head_model"] == "face")].sort_values("lambda")
        axes[1].plot(s["lambda"], s.tcp_speed, color=c, marker="o", ms=3, label=fam)
    _limit_lines(axes[0])
    lim = study.limits
    for _, r in lim.iterrows():
        axes[1].axhline(r.v_max, ls="--" if r.factor > 1 else ":",
                        color="tab:red" if r.region == "skull/forehead" else "tab:orange",
                        lw=1.0, label=f"v_max {r.region} ({r.factor:g}x)")
    for ax in axes:
        ax.set_xscale("log")
        ax.set_xlabel("lambda [s]")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=6)
    axes[0].set_yscale("log")
    axes[0].set_ylabel("worst free-impact F_max [N] (ISO linear head)")
    axes[1].set_ylabel("tool speed at the worst impact [m/s]")
    fig.suptitle("Power and force limiting: admissible lambda per PSMC family")
    fig.tight_layout()
    return fig


def plot_hc_vs_linear(study):
    """Peak force against speed: the ISO linear springs vs the thesis Hunt-Crossley head.

    Parameters
    ----------
    study : IsoFindings
        Output of :func:`ppamsafety.sections.iso_15066.compute`.
    """
    c = study.hc_curve
    fig, ax = new_figure(figsize=(7.0, 4.5))
    ax.plot(c.speed, c.F_linear_forehead, color="tab:red", label="ISO linear, forehead 150 N/mm")
    ax.plot(c.speed, c.F_linear_face, color="tab:orange", label="ISO linear, face 75 N/mm")
    ax.plot(c.speed, c.F_hunt_crossley, color="tab:blue", label="Hunt-Crossley (thesis head)")
    _limit_lines(ax, quasi_static=False)
    for _, r in study.limits[study.limits.factor > 1].iterrows():
        ax.axvline(r.v_max, color="tab:red" if r.region == "skull/forehead" else "tab:orange",
                   ls=":", lw=1.0)
    ax.set_xlabel("relative speed [m/s]")
    ax.set_ylabel("peak force [N] (two-body, m_R = M/2, m_H = 4.4 kg)")
    ax.set_title("Linear-spring estimate vs Hunt-Crossley (dotted: v_max)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


__all__ = ["plot_clamping_histories", "plot_clamping_vs_limits", "plot_quasi_static",
           "plot_lambda_limits", "plot_hc_vs_linear"]
