"""Figures of contacts anywhere on the arm: one impact through layers, and the arm's margins.

Each function takes computed data and returns a matplotlib Figure; nothing here simulates.
"""

from __future__ import annotations

import math

import numpy as np

from .figure import new_figure


def plot_contact_history(hist, *, point: str = "", body: str = "", title: str = ""):
    """Contact force, body acceleration and the compression of each layer of one impact.

    Parameters
    ----------
    hist : pandas.DataFrame
        Columns ``t`` [s], ``F`` [N], ``a_body_g`` [g], ``delta`` [m] and ``delta1``..
        (each layer's compression [m]) (:attr:`ContactResult.histories` entry).
    point, body : str
        Names for the title.
    title : str
        Figure title (default "<point> against <body>").

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = new_figure(3, 1, figsize=(7, 6.5), sharex=True)
    t = hist["t"] * 1e3
    axes[0].plot(t, hist["F"], color="k")
    axes[0].set_ylabel("contact force [N]")
    axes[1].plot(t, hist["a_body_g"], color="tab:blue")
    axes[1].set_ylabel("body acceleration [g]")
    axes[2].plot(t, hist["delta"] * 1e3, color="k", label="total")
    for c in hist.columns:
        if c.startswith("delta") and c[5:].isdigit():
            axes[2].plot(t, hist[c] * 1e3, lw=1, label=f"layer {c[5:]}")
    axes[2].axhline(0, color="k", lw=0.5)
    axes[2].set_ylabel("compression [mm]")
    axes[2].set_xlabel("time after impact [ms]")
    axes[2].legend(loc="upper right", fontsize=8)
    for a in axes:
        a.grid(alpha=0.3)
    fig.suptitle(title or (f"{point} against {body}" if point or body else "impact"))
    fig.tight_layout()
    return fig


def _margin_scale(margins):
    """(colormap, norm) of margins to a limit [%]: red below zero (the limit exceeded), green
    above, symmetric about zero and at least +-1 %."""
    from matplotlib import colormaps, colors

    m = np.asarray(margins, dtype=float)
    span = max(1.0, float(np.nanmax(np.abs(m)))) if np.isfinite(m).any() else 1.0
    return colormaps["RdYlGn"], colors.TwoSlopeNorm(vmin=-span, vcenter=0.0, vmax=span)


def plot_contact_margins(drawing: dict, *, title: str = ""):
    """The arm with each contact point's worst body region and its margin to the limit.

    Parameters
    ----------
    drawing : dict
        ``links`` (array (3, 2): shoulder, elbow, tool point [m]), ``points`` (DataFrame
        with ``point``, ``x``, ``y`` [m], ``body``, ``value``, ``limit``, ``margin_pct``,
        ``t0`` [s]), ``criterion`` and ``unit`` (of the values), as built by
        :meth:`ppamsafety.impact.anywhere.WorstContact.plot`.
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        Points coloured by margin (red: the limit is exceeded); without limits, by value.
    """
    from matplotlib import colormaps, colors

    fig, ax = new_figure(1, 1, figsize=(7.5, 6.0))
    L = np.asarray(drawing["links"], dtype=float)
    ax.plot(L[:, 0], L[:, 1], "-", color="0.6", lw=10, solid_capstyle="round", zorder=1)
    ax.plot(L[:2, 0], L[:2, 1], "o", color="0.3", ms=9, zorder=2)
    pts = drawing["points"]
    unit = drawing.get("unit", "")
    u = f" {unit}" if unit and unit != "-" else ""
    has_lim = bool(np.any(np.isfinite(pts["limit"].to_numpy(dtype=float))))
    if has_lim:
        cval = pts["margin_pct"].to_numpy(dtype=float)
        cmap, norm = _margin_scale(cval)
        clabel = "margin to the limit [%]"
    else:
        cval = pts["value"].to_numpy(dtype=float)
        norm = colors.Normalize(vmin=0.0, vmax=float(np.nanmax(cval)) or 1.0)
        cmap = colormaps["viridis"]
        clabel = f"{drawing.get('criterion', '')}{u}"
    sc = ax.scatter(pts["x"], pts["y"], c=cval, cmap=cmap, norm=norm, s=220, zorder=3,
                    edgecolors="k")
    for _, r in pts.iterrows():
        txt = f"{r['point']}: {r['body']}\n{drawing.get('criterion', '')} {r['value']:.4g}{u}"
        if has_lim and math.isfinite(r["limit"]):
            txt += f" / {r['limit']:.4g}{u}\nmargin {r['margin_pct']:+.0f} %"
        txt += f" (t0 = {r['t0']:.3f} s)"
        ax.annotate(txt, (r["x"], r["y"]), xytext=(12, 10), textcoords="offset points",
                    fontsize=8, zorder=4,
                    bbox=dict(boxstyle="round", fc="white", alpha=0.8, lw=0.5))
    fig.colorbar(sc, ax=ax, label=clabel)
    ax.set_aspect("equal")
    pad = 0.12
    allx = np.concatenate([L[:, 0], pts["x"].to_numpy(dtype=float)])
    ally = np.concatenate([L[:, 1], pts["y"].to_numpy(dtype=float)])
    ax.set_xlim(allx.min() - pad, allx.max() + 2 * pad)
    ax.set_ylim(ally.min() - pad, ally.max() + pad)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)
    ax.set_title(title or "worst body region and its margin at each contact point "
                          "(arm at the overall worst instant)")
    fig.tight_layout()
    return fig


__all__ = ["plot_contact_history", "plot_contact_margins"]


def plot_region_margins(grid, *, title: str = ""):
    """The margin of every body region at every contact point, as a colour grid.

    Parameters
    ----------
    grid : pandas.DataFrame
        One row per body region: the column ``body_region`` and one column per (contact
        point, covering) holding the governing criterion's margin to its limit [%] (negative:
        the limit is exceeded), as :attr:`ppamsafety.sections.person.PersonFindings.margin_grid`
        builds it.
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        Red: the limit is exceeded; green: below it; each cell annotated with its margin.
    """
    cols = [c for c in grid.columns if c != "body_region"]
    m = grid[cols].to_numpy(dtype=float)
    fig, ax = new_figure(1, 1, figsize=(1.4 * len(cols) + 3.0, 0.42 * len(grid) + 2.2))
    cmap, norm = _margin_scale(m)
    im = ax.imshow(m, cmap=cmap, norm=norm, aspect="auto")
    for i in range(m.shape[0]):
        for j in range(m.shape[1]):
            if math.isfinite(m[i, j]):
                ax.text(j, i, f"{m[i, j]:+.0f}", ha="center", va="center", fontsize=8)
    ax.set_xticks(range(len(cols)))
    ax.set_xticklabels([c.removesuffix(" [% margin]") for c in cols], rotation=35, ha="right",
                       fontsize=8)
    ax.set_yticks(range(len(grid)))
    ax.set_yticklabels(grid["body_region"], fontsize=8)
    ax.set_xlabel("contact point, covering")
    ax.set_ylabel("body region (ISO/TS 15066 Annex A)")
    fig.colorbar(im, ax=ax, label="margin of the governing criterion to its limit [%]")
    if title:
        ax.set_title(title)
    return fig
