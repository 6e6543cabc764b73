"""Plots of physical interaction: force estimation and admittance control (figs. 5.21, 5.22).

Every function takes :class:`~ppamsafety.experiments.closed_loop.ExperimentResult`
objects (runs with a force estimator) or DataFrames computed elsewhere and
returns a pyplot-free matplotlib Figure; nothing here simulates.
"""

from __future__ import annotations

import numpy as np

from .figure import new_figure


def plot_force_estimates(result, *, title: str = "External force estimation (cf. fig. 5.21)",
                         t_range=None):
    """Both force estimates (RLS, observer) and, if known, the applied force vs time.

    Parameters
    ----------
    result : ExperimentResult
        A run with a force estimator (signals ``Fx_rls`` ... ``Fy_mo``).
    title : str
        Figure title.
    t_range : (float, float), optional
        Time window [s].
    """
    t = result.t
    fig, axes = new_figure(2, 1, figsize=(7.5, 5.0), sharex=True)
    names = result.signal_names()
    for ax, c in zip(axes, ("x", "y")):
        if f"F{c}_ext" in names:
            ax.plot(t, result.signal(f"F{c}_ext"), color="0.5", lw=2.5, alpha=0.6,
                    label="applied")
        ax.plot(t, result.signal(f"F{c}_mo"), color="tab:red", lw=1.0,
                label="momentum observer (5.56)")
        ax.plot(t, result.signal(f"F{c}_rls"), color="tab:blue", lw=1.0,
                label="recursive least squares (5.47)")
        ax.set_ylabel(f"$F_{c}$ [N]")
        ax.grid(alpha=0.3)
        if t_range is not None:
            ax.set_xlim(*t_range)
    axes[0].legend(fontsize=8, loc="best")
    axes[-1].set_xlabel("t [s]")
    axes[0].set_title(title)
    fig.tight_layout()
    return fig


def plot_observer_step(t, estimate, closed_form, *, k_i: float, title: str | None = None):
    """Observer step response against the first-order closed form 1 - exp(-K_I t).

    Parameters
    ----------
    t : array_like
        Time since the force step [s].
    estimate : array_like
        Normalised observer estimate (estimate / applied force) [-].
    closed_form : array_like
        1 - exp(-K_I t) [-].
    k_i : float
        Observer gain [rad/s] (for the label).
    title : str, optional
        Figure title.
    """
    fig, axes = new_figure(2, 1, figsize=(7.0, 4.5), sharex=True)
    t = np.asarray(t)
    axes[0].plot(t * 1e3, closed_form, color="0.5", lw=2.5, alpha=0.6,
                 label=f"1 - exp(-K_I t), K_I = {k_i:.4g} rad/s")
    axes[0].plot(t * 1e3, estimate, color="tab:red", lw=1.0, label="observer (simulated)")
    axes[0].axvline(1e3 / k_i, color="0.6", ls=":", lw=0.8)
    axes[0].set_ylabel("F_mo / F [-]")
    axes[0].legend(fontsize=8)
    axes[1].plot(t * 1e3, np.asarray(estimate) - np.asarray(closed_form), color="tab:red")
    axes[1].set_ylabel("difference [-]")
    axes[1].set_xlabel("time after the step [ms]")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].set_title(title or "Momentum observer: first-order lag with pole K_I (5.53)")
    fig.tight_layout()
    return fig


def plot_interaction_path(result, *, waypoints=None, labels=("A", "B", "C"), f_min: float = 3.0,
                          dot_every: float = 0.1, arrow_scale: float = 0.01,
                          title: str = "Admittance control: actual and desired TCP path "
                                       "(cf. fig. 5.22)"):
    """Actual and admittance-desired TCP paths with estimated-force arrows.

    Parameters
    ----------
    result : ExperimentResult
        An :class:`~ppamsafety.control.admittance.AdmittancePSMC` run
        (signals ``x``, ``y``, ``x_adm``, ``y_adm``, ``Fx_dz``, ``Fy_dz``).
    waypoints : array_like, shape (m, 2), optional
        Points to mark [m].
    labels : sequence of str
        Their labels.
    f_min : float
        Forces with a norm above this are drawn [N].
    dot_every : float
        Spacing of the time dots [s] (thesis 0.1 s).
    arrow_scale : float
        Arrow length per newton [m/N] (thesis: 0.1 m per 10 N).
    title : str
        Figure title.
    """
    fig, ax = new_figure(1, 1, figsize=(7.5, 6.0))
    x, y = result.signal("x"), result.signal("y")
    xa, ya = result.signal("x_adm"), result.signal("y_adm")
    ax.plot(xa, ya, color="tab:blue", lw=1.0, ls="--", label="desired (admittance)")
    ax.plot(x, y, color="black", lw=1.0, label="actual")
    dt = result.reference.dt
    step = max(1, int(round(dot_every / dt)))
    idx = np.arange(0, x.size, step)
    ax.plot(x[idx], y[idx], ".", color="black", ms=3)
    fx, fy = result.signal("Fx_dz")[idx], result.signal("Fy_dz")[idx]
    big = np.hypot(fx, fy) > f_min
    if np.any(big):
        ax.quiver(x[idx][big], y[idx][big], fx[big] * arrow_scale, fy[big] * arrow_scale,
                  angles="xy", scale_units="xy", scale=1.0, color="tab:red", width=0.003,
                  label=f"estimated force ({arrow_scale * 10:.2g} m per 10 N)")
    if waypoints is not None:
        for (px, py), lab in zip(np.asarray(waypoints), labels):
            ax.plot(px, py, "o", color="tab:green", ms=6)
            ax.annotate(lab, (px, py), textcoords="offset points", xytext=(6, 6))
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)
    # the path is tall and narrow: keep the legend beside it, not over the axis labels
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    ax.set_title(title)
    fig.tight_layout()
    return fig


def plot_release(results, *, t_release: float, labels=None,
                 title: str = "Pushed away and released (§6.3 hazard)"):
    """TCP distance from the set point and TCP speed around the release, per controller.

    Parameters
    ----------
    results : sequence of ExperimentResult
        Runs with a hand that releases the arm at ``t_release``.
    t_release : float
        Release time [s].
    labels : sequence of str, optional
        Legend labels (default the controller names).
    title : str
        Figure title.
    """
    fig, axes = new_figure(2, 1, figsize=(7.5, 5.0), sharex=True)
    for i, r in enumerate(results):
        lab = labels[i] if labels is not None else r.controller.get("controller", r.name)
        d = np.hypot(r.signal("x") - r.signal("x_d"), r.signal("y") - r.signal("y_d"))
        axes[0].plot(r.t, d * 1e3, lw=1.0, label=lab)
        axes[1].plot(r.t, r.tcp_speed(), lw=1.0, label=lab)
    for ax in axes:
        ax.axvline(t_release, color="0.6", ls=":", lw=0.8)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("|r - r_d| [mm]")
    axes[1].set_ylabel("TCP speed [m/s]")
    axes[1].set_xlabel("t [s]")
    axes[0].legend(fontsize=8)
    axes[0].set_title(title)
    fig.tight_layout()
    return fig


__all__ = ["plot_force_estimates", "plot_observer_step", "plot_interaction_path",
           "plot_release"]
