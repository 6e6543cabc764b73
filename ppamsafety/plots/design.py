"""Design figures (thesis ch. 2): torque functions, stiffness map, maximum-load map.

Each function takes a result object of :mod:`ppamsafety.design` and returns a
pyplot-free Figure.
"""

from __future__ import annotations

import numpy as np

from ..units import BAR, DEG
from .figure import GROUP_COLORS, new_figure


def plot_torque_functions(result, *, ax=None):
    """Torque functions m_tau,i [Nm/bar] against the driven joint angle (cf. fig. 2.11).

    Parameters
    ----------
    result : ppamsafety.design.TorqueFunctions
        Output of :func:`ppamsafety.design.torque_function_curves`.
    ax : matplotlib.axes.Axes, optional
        Draw all four groups into this axes (default: a new figure with a
        panel per joint).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    df = result.data
    fig, axes = (ax.figure, [ax, ax]) if ax is not None else new_figure(1, 2, figsize=(9, 3.6))
    for k in range(4):
        sub = df[df["group"] == k + 1]
        a = axes[0] if k < 2 else axes[1]
        a.plot(sub["angle_rad"] / DEG, sub["m_tau_Nm_per_Pa"] * BAR, color=GROUP_COLORS[k],
               label=f"$m_{{\\tau {k + 1}}}$")
    axes[0].set_xlabel("$q_1$ [deg]  ($q_2$ = -80 deg)")
    axes[1].set_xlabel("$q_2$ [deg]")
    for a in axes:
        a.set_ylabel("torque function [Nm/bar]")
        a.axhline(0, color="k", lw=0.5)
        a.grid(alpha=0.3)
        a.legend()
    fig.suptitle("Torque functions (thesis fig. 2.11), Table B.1 muscle model")
    fig.tight_layout()
    return fig


def _joint_grid(df, col):
    q1 = np.unique(df["q1_rad"])
    q2 = np.unique(df["q2_rad"])
    Z = df.pivot_table(index="q2_rad", columns="q1_rad", values=col).to_numpy()
    return q1 / DEG, q2 / DEG, Z


def plot_stiffness_map(result, *, ax=None):
    """Joint stiffness K1, K2 (2.18) over the working area, unholdable region hatched.

    Parameters
    ----------
    result : ppamsafety.design.StiffnessMap
        Output of :func:`ppamsafety.design.stiffness_map`.
    ax : None
        Not supported (the map needs two panels); kept for a uniform
        ``plot(ax=...)`` signature and ignored.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    df = result.data
    fig, axes = new_figure(1, 2, figsize=(10, 4))
    for j, a in enumerate(axes):
        q1, q2, Z = _joint_grid(df, f"K{j + 1}_Nm_per_rad")
        cs = a.contourf(q1, q2, Z, levels=20, cmap="viridis")
        fig.colorbar(cs, ax=a, label=f"$K_{j + 1}$ [Nm/rad]")
        _, _, H = _joint_grid(df.assign(h=df["holdable"].astype(float)), "h")
        a.contourf(q1, q2, H, levels=[-0.5, 0.5], colors="none", hatches=["//"])
        a.contour(q1, q2, H, levels=[0.5], colors="w", linewidths=1)
        a.set_xlabel("$q_1$ [deg]")
        a.set_ylabel("$q_2$ [deg]")
        a.set_title(f"joint {j + 1} stiffness")
    fig.suptitle("Joint stiffness with static $\\Delta p$ pressures "
                 "(hatched: not holdable within [0, $p_{max}$])")
    fig.tight_layout()
    return fig


def _task_space_triangulation(df, xcol, ycol):
    """Triangulate a joint-space grid mapped to task space, following the grid.

    Triangles are built from the (q1, q2) grid cells so the concave task-space
    image of the working area is not bridged by spurious triangles.
    """
    import matplotlib.tri as mtri

    n1 = np.unique(df["q1_rad"]).size
    n2 = np.unique(df["q2_rad"]).size
    d = df.sort_values(["q1_rad", "q2_rad"])
    idx = np.arange(n1 * n2).reshape(n1, n2)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, e = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, e], 1)])
    return mtri.Triangulation(d[xcol].to_numpy(), d[ycol].to_numpy(), triangles)


def plot_max_load(result, *, reference_kg: float | None = 2.0):
    """Maximum load (fig. 2.15 / A.2) in joint space and at the load point in task space.

    Parameters
    ----------
    result : ppamsafety.design.MaxLoadMap
        Output of :func:`ppamsafety.design.max_load_map`.
    reference_kg : float or None
        Load [kg] drawn as a contour line (the thesis' "just over 2 kg");
        None: no line.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    df = result.data
    fig, axes = new_figure(1, 2, figsize=(11, 4.3))
    q1, q2, Z = _joint_grid(df, "M_max_kg")
    levels = np.arange(np.floor(min(Z.min(), 0)), np.ceil(Z.max()) + 0.5, 0.5)
    cs = axes[0].contourf(q1, q2, Z, levels=levels, cmap="RdYlGn")
    if reference_kg is not None:
        axes[0].contour(q1, q2, Z, levels=[reference_kg], colors="k", linewidths=1.5)
    fig.colorbar(cs, ax=axes[0], label="max load [kg]")
    axes[0].set_xlabel("$q_1$ [deg]")
    axes[0].set_ylabel("$q_2$ [deg]")
    axes[0].set_title("joint space (cf. fig. A.2)")
    tri = _task_space_triangulation(df, "xL_m", "yL_m")
    z = df.sort_values(["q1_rad", "q2_rad"])["M_max_kg"].to_numpy()
    tc = axes[1].tricontourf(tri, z, levels=levels, cmap="RdYlGn")
    if reference_kg is not None:
        axes[1].tricontour(tri, z, levels=[reference_kg], colors="k", linewidths=1.5)
    fig.colorbar(tc, ax=axes[1], label="max load [kg]")
    axes[1].set_aspect("equal")
    axes[1].set_xlabel("x [m]")
    axes[1].set_ylabel("y [m]")
    axes[1].set_title("at load point $A_L$ (cf. fig. 2.15)")
    q = np.array(result.argmin) / DEG
    fig.suptitle(f"Maximum load at p = {result.p_max / BAR:g} bar: minimum {result.minimum:.2f} kg "
                 f"at q = ({q[0]:.0f}, {q[1]:.0f}) deg; black line: thesis' 2 kg")
    fig.tight_layout()
    return fig


def plot_arm_summary(stiffness, max_load, *, pose, stiffness_at_pose, name: str = ""):
    """An arm's key design numbers over its working area: K1, K2 and the maximum load.

    Parameters
    ----------
    stiffness : pandas.DataFrame
        ``ppamsafety.design.StiffnessMap.data`` (``q1_rad``, ``q2_rad``,
        ``K1_Nm_per_rad``, ``K2_Nm_per_rad``, ``holdable``).
    max_load : pandas.DataFrame
        ``ppamsafety.design.MaxLoadMap.data`` (``q1_rad``, ``q2_rad``, ``M_max_kg``).
    pose : (float, float)
        Configuration of the stiffness numbers [rad] (starred).
    stiffness_at_pose : (float, float)
        K1, K2 at the pose [N m/rad].
    name : str
        The arm's name (title).

    Returns
    -------
    matplotlib.figure.Figure
        Three maps over (q1, q2) [deg]: K1 and K2 [N m/rad] (not holdable hatched) and the
        maximum load [kg] (its minimum circled).
    """
    fig, axes = new_figure(1, 3, figsize=(14, 4))
    pq = np.asarray(pose, float) / DEG
    for j in range(2):
        a = axes[j]
        q1, q2, Z = _joint_grid(stiffness, f"K{j + 1}_Nm_per_rad")
        cs = a.contourf(q1, q2, Z, levels=20, cmap="viridis")
        fig.colorbar(cs, ax=a, label=f"$K_{j + 1}$ [N m/rad]")
        _, _, H = _joint_grid(stiffness.assign(h=stiffness["holdable"].astype(float)), "h")
        a.contourf(q1, q2, H, levels=[-0.5, 0.5], colors="none", hatches=["//"])
        a.plot(*pq, "r*", ms=12, label=f"pose: {stiffness_at_pose[j]:.3g} N m/rad")
        a.set_title(f"joint {j + 1} stiffness (hatched: not holdable)", fontsize=9)
    q1, q2, Z = _joint_grid(max_load, "M_max_kg")
    cs = axes[2].contourf(q1, q2, Z, levels=20, cmap="RdYlGn")
    fig.colorbar(cs, ax=axes[2], label="max load [kg]")
    k = int(np.argmin(max_load["M_max_kg"].to_numpy(float)))
    r = max_load.iloc[k]
    axes[2].plot(r["q1_rad"] / DEG, r["q2_rad"] / DEG, "ko", mfc="none", ms=12,
                 label=f"minimum {r['M_max_kg']:.3g} kg")
    axes[2].plot(*pq, "r*", ms=12, label="stiffness pose")
    axes[2].set_title("maximum load", fontsize=9)
    for a in axes:
        a.set_xlabel("$q_1$ [deg]")
        a.set_ylabel("$q_2$ [deg]")
        a.legend(fontsize=7, loc="lower right")
    fig.suptitle(f"{name}: design numbers over the working area" if name else
                 "design numbers over the working area")
    fig.tight_layout()
    return fig


__all__ = ["plot_torque_functions", "plot_stiffness_map", "plot_max_load", "plot_arm_summary"]
