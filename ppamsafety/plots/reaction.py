"""Plots of closed-loop head collisions: contact force, positions, detection and reactions.

Every function takes :class:`~ppamsafety.impact.collision.CollisionResult`
objects (or a reaction study) and returns a pyplot-free matplotlib Figure;
nothing here simulates.
"""

from __future__ import annotations

import numpy as np

from .figure import new_figure


def plot_collision(result, *, title: str | None = None, t_range=None):
    """Contact force, TCP and head trajectories and observer residuals vs time, detection marked.

    The trajectories are projected on the direction u from the TCP to the head centre at
    the closest approach, measured from the head's initial surface point [mm].

    Parameters
    ----------
    result : CollisionResult
        One closed-loop collision run.
    title : str, optional
        Figure title (default: the run's name and reaction).
    t_range : (float, float), optional
        Time window [s] (default: 20 ms before the first contact to the end).
    """
    e = result.experiment
    t = e.t
    if t_range is None:
        t0 = result.t_contact if np.isfinite(result.t_contact) else t[0]
        t_range = (max(t[0], t0 - 0.02), t[-1])
    fig, axes = new_figure(3, 1, figsize=(7.5, 7.5), sharex=True)
    ft = result.fine_t
    axes[0].plot(ft, result.fine[:, 0], color="tab:red", lw=1.0, label="contact force")
    axes[0].set_ylabel("F [N]")
    df = result.to_pandas()
    # trajectories along the initial impact direction u (TCP -> head centre at the start),
    # from the head's initial surface point: the gap between the curves is the clearance
    xh0 = df[["x_head", "y_head"]].to_numpy()[0]
    k = int(np.argmin(df["gap"].to_numpy()))
    r_k = df[["x", "y"]].to_numpy()[k]
    u = (xh0 - r_k) / max(float(np.hypot(*(xh0 - r_k))), 1e-12)
    surf0 = xh0 - result.head.radius * u
    tcp_u = (df[["x", "y"]].to_numpy() - surf0) @ u
    head_u = (df[["x_head", "y_head"]].to_numpy() - xh0) @ u
    axes[1].plot(t, tcp_u * 1e3, color="tab:blue", lw=1.0, label="TCP along u")
    axes[1].plot(t, head_u * 1e3, color="tab:orange", lw=1.0, label="head surface along u")
    axes[1].set_ylabel("position along u [mm]")
    for i, c in enumerate(("tab:green", "tab:purple")):
        axes[2].plot(t, np.abs(df[f"r{i + 1}"]), color=c, lw=1.0,
                     label=f"|r{i + 1}| (5.54)")
        if np.isfinite(result.threshold[i]):
            axes[2].axhline(result.threshold[i], color=c, ls=":", lw=1.0,
                            label=f"threshold {result.threshold[i]:.2g} N m")
    axes[2].set_ylabel("residual [N m]")
    axes[2].set_xlabel("t [s]")
    for ax in axes:
        if np.isfinite(result.t_detect):
            ax.axvline(result.t_detect, color="k", lw=0.8, ls="-.", label="detection")
        ax.grid(alpha=0.3)
        ax.set_xlim(*t_range)
        ax.legend(fontsize=7, loc="best")
    axes[0].set_title(title or f"{e.name}: reaction {result.reaction.name}")
    fig.tight_layout()
    return fig


def plot_reactions(results, *, title: str = "Head collision: reactions", window: float = 0.3):
    """Contact force and muscle pressure p1 of several reactions to the same collision.

    Parameters
    ----------
    results : sequence of CollisionResult
        Runs of one case with different reactions.
    title : str
        Figure title.
    window : float
        Time shown after the first contact [s], > 0.
    """
    fig, axes = new_figure(2, 1, figsize=(7.5, 6.0), sharex=True)
    t0 = min(r.t_contact for r in results if np.isfinite(r.t_contact)) \
        if any(np.isfinite(r.t_contact) for r in results) else 0.0
    for r in results:
        ft = r.fine_t - t0
        axes[0].plot(ft * 1e3, r.fine[:, 0], lw=1.0, label=r.reaction.name)
        axes[1].plot((r.t - t0) * 1e3, r.experiment.signal("p1") / 1e5, lw=1.0,
                     label=r.reaction.name)
    det = [r.t_detect for r in results if np.isfinite(r.t_detect)]
    for ax in axes:
        if det:
            ax.axvline((det[0] - t0) * 1e3, color="k", lw=0.8, ls="-.", label="detection")
        ax.set_xlim(-10.0, window * 1e3)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("contact force [N]")
    axes[1].set_ylabel("p1 [bar gauge]")
    axes[1].set_xlabel("time after the first contact [ms]")
    axes[0].legend(fontsize=8, loc="best")
    axes[0].set_title(title)
    fig.tight_layout()
    return fig


__all__ = ["plot_collision", "plot_reactions"]
