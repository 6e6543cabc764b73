"""Figures of a bench campaign (real or synthetic cylinder records): force-stroke loops.

Each function takes a campaign diagnosis (duck-typed: ``curves``, ``records``,
``names``, ``source``) or plain arrays and returns a pyplot-free Figure.
"""

from __future__ import annotations

import numpy as np

from .figure import new_figure


def _check(dg):
    if not all(hasattr(dg, a) for a in ("curves", "records", "names", "source")):
        raise TypeError(f"dg must be a BenchDiagnosis, got {type(dg).__name__}")


def campaign_loops_figure(dg, *, max_points: int = 4000):
    """Force minus p A against the rod position, per record: before (left) and after (right).

    The residual after is drawn on the samples the diagnosis uses (NaN elsewhere: before a
    record's first reversal and at turning points).

    Parameters
    ----------
    dg : BenchDiagnosis
        A campaign diagnosis.
    max_points : int, keyword-only
        Points drawn per record and panel (every k-th sample).

    Returns
    -------
    matplotlib.figure.Figure
    """
    _check(dg)
    labels = list(dg.curves)
    n = max(len(labels), 1)
    fig, axes = new_figure(n, 2, figsize=(10, 1.9 * n + 0.8), layout="constrained",
                           squeeze=False)
    for i, lab in enumerate(labels):
        c = dg.curves[lab]
        step = max(1, c["x"].size // max_points)
        sl = slice(None, None, step)
        x = 1e3 * c["x"][sl]
        for j, key in enumerate(("before", "after")):
            ax = axes[i, j]
            for sgn, col, nm in ((1, "C0", "extending"), (-1, "C3", "pushed in")):
                m = c["s"][sl] == sgn
                ax.plot(x[m], c[key][sl][m], ".", ms=1.0, color=col, label=nm)
            ax.axhline(0.0, color="0.6", lw=0.5)
            rms = float(np.sqrt(np.nanmean(c[key][c["used"]] ** 2)))
            ax.set_title(f"{lab}: {'F - p A (nominal law)' if key == 'before' else 'residual after'}"
                         f", RMS {rms:.3g} N", fontsize=7)
            ax.tick_params(labelsize=6)
            if i == n - 1:
                ax.set_xlabel("rod position [mm]", fontsize=7)
            if j == 0:
                ax.set_ylabel("force [N]", fontsize=7)
        if i == 0:
            axes[0, 0].legend(fontsize=6, markerscale=6)
    fig.suptitle(f"{dg.source}: " + (", ".join(dg.names) or "nothing named"), fontsize=8)
    return fig


def campaign_residual_figure(dg, *, max_points: int = 4000):
    """Final residual over the repeatability level against time, one panel per record.

    Parameters
    ----------
    dg : BenchDiagnosis
        A campaign diagnosis.
    max_points : int, keyword-only
        Points drawn per record.

    Returns
    -------
    matplotlib.figure.Figure
    """
    _check(dg)
    labels = list(dg.curves)
    n = max(len(labels), 1)
    fig, axes = new_figure(n, 1, figsize=(9, 1.5 * n + 0.8), layout="constrained", squeeze=False)
    rec = dg.records.set_index("label") if len(dg.records) else None
    for i, lab in enumerate(labels):
        c = dg.curves[lab]
        sig = float(rec.loc[lab, "sigma_repeat_N"]) if rec is not None else 1.0
        step = max(1, c["t"].size // max_points)
        sl = slice(None, None, step)
        ax = axes[i, 0]
        ax.plot(c["t"][sl], c["before"][sl] / sig, color="C3", lw=0.4, label="before")
        ax.plot(c["t"][sl], c["after"][sl] / sig, color="C0", lw=0.4, label="after")
        ax.axhspan(-1.5, 1.5, color="0.9", zorder=0)
        ax.set_ylabel(f"{lab}\n[repeat. noise]", fontsize=6)
        ax.tick_params(labelsize=6)
    axes[-1, 0].set_xlabel("t [s]", fontsize=7)
    axes[0, 0].legend(fontsize=6)
    return fig


def seal_parameters_figure(table, *, params=("c0", "c1")):
    """Fitted parameters of several seals against pressure (report section).

    Parameters
    ----------
    table : pandas.DataFrame
        Columns ``seal``, ``pressure_bar``, ``friction_N``, ``friction_se_N``
        (the Coulomb level c(p) at each record's pressure) and, optional,
        ``presliding_N``, ``presliding_se_N``.
    params : tuple of str, keyword-only
        Unused (kept for a stable signature).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = new_figure(1, 2, figsize=(9, 3.2), layout="constrained", squeeze=False)
    for k, (col, title) in enumerate((("friction", "Coulomb level c(p) [N]"),
                                      ("presliding", "presliding step h(p) [N]"))):
        ax = axes[0, k]
        if f"{col}_N" not in table.columns:
            continue
        for i, (seal, g) in enumerate(table.groupby("seal", sort=False)):
            ok = np.isfinite(g[f"{col}_N"].to_numpy(float))
            if not ok.any():
                continue
            ax.errorbar(g["pressure_bar"][ok], g[f"{col}_N"][ok],
                        yerr=1.96 * g[f"{col}_se_N"][ok], fmt="o-", ms=3, color=f"C{i}",
                        label=seal, capsize=2)
        ax.set_xlabel("pressure [bar]", fontsize=7)
        ax.set_title(title, fontsize=8)
        ax.tick_params(labelsize=6)
        ax.legend(fontsize=6)
    return fig


__all__ = ["campaign_loops_figure", "campaign_residual_figure", "seal_parameters_figure"]


def plot_campaign(curves, *, xlabel: str, title: str = "", max_points: int = 4000):
    """Measured force against the actuator's position variable, one curve per record.

    Parameters
    ----------
    curves : list of (str, array_like, array_like)
        ``(label, x, force [N])`` per record.
    xlabel : str
        Label of x with its unit (``"contraction [-]"``, ``"rod position [m]"``).
    title : str
        Axes title (default "campaign: measured force").
    max_points : int
        Points drawn per record at most (evenly thinned).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = new_figure(figsize=(6.5, 4.5))
    for label, x, f in curves:
        x, f = np.asarray(x, float), np.asarray(f, float)
        step = max(1, x.size // max_points)
        ax.plot(x[::step], f[::step], lw=0.8, label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("force [N]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title(title or "campaign: measured force")
    fig.tight_layout()
    return fig
