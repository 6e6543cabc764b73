"""Figures of the identification (thesis §3.5): a least-squares fit, an excitation.

Each function takes the numbers of a result object of :mod:`ppamsafety.identify`
and returns a pyplot-free Figure.
"""

from __future__ import annotations

import numpy as np

from .figure import new_figure


def plot_fit(fit, *, max_points: int = 20000):
    """Measured against predicted, and the residual, of a linear least-squares fit.

    Parameters
    ----------
    fit : ppamsafety.identify.lsq.LSQResult
        The fit (``measured``, ``predicted``, ``quantity``, ``method``,
        ``residual_rms``, ``condition_number``).
    max_points : int, keyword-only
        At most this many (evenly strided) samples are drawn.

    Returns
    -------
    matplotlib.figure.Figure
    """
    stride = max(1, fit.measured.size // int(max_points))
    y, yh = fit.measured[::stride], fit.predicted[::stride]
    fig, (ax1, ax2) = new_figure(1, 2, figsize=(9, 3.5))
    ax1.plot(y, yh, ".", ms=2)
    lo, hi = float(min(y.min(), yh.min())), float(max(y.max(), yh.max()))
    ax1.plot([lo, hi], [lo, hi], "k--", lw=0.8)
    ax1.set_xlabel(f"measured {fit.quantity}")
    ax1.set_ylabel(f"predicted {fit.quantity}")
    ax1.set_title(fit.method)
    ax2.plot(np.arange(y.size) * stride, y - yh, lw=0.6)
    ax2.set_xlabel("equation index [-]")
    ax2.set_ylabel(f"residual {fit.quantity}")
    ax2.set_title(f"RMS {fit.residual_rms:.3g}, cond {fit.condition_number:.3g}")
    fig.tight_layout()
    return fig


def plot_excitation(t, delta_p, *, condition_number: float):
    """A Delta-p excitation over one period, per joint.

    Parameters
    ----------
    t : numpy.ndarray, shape (n,)
        Time [s].
    delta_p : numpy.ndarray, shape (n, 2)
        Pressure difference of each joint [Pa].
    condition_number : float, keyword-only
        Condition number of the excitation's regressor, shown in the title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = new_figure(figsize=(6, 3))
    for j in range(2):
        ax.plot(t, delta_p[:, j] / 1e5, label=f"joint {j + 1}")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("Delta p [bar]")
    ax.set_title(f"cond = {condition_number:.3g}")
    ax.legend()
    return fig


def plot_delta_fit(record, *, delta: float, std_error: float):
    """A tensile-test record against the force law without and with the fitted hysteresis.

    Parameters
    ----------
    record : pandas.DataFrame
        ``eps`` [-], ``force`` (measured), ``force_nominal`` (the force law (3.9), no
        hysteresis) and ``force_fit`` (with the fitted (3.35)) [N], in time order
        (``ppamsafety.hysteresis.tensile.DeltaFit.record``).
    delta, std_error : float
        The fitted hysteresis scale and its standard error [-].

    Returns
    -------
    matplotlib.figure.Figure
        Left: force [N] against contraction [-], the measured loop and both models.
        Right: the force residuals [N] of both models against time order.
    """
    eps = record["eps"].to_numpy(float)
    f = record["force"].to_numpy(float)
    fn = record["force_nominal"].to_numpy(float)
    ff = record["force_fit"].to_numpy(float)
    fig, (a, b) = new_figure(1, 2, figsize=(10, 3.8))
    a.plot(eps, f, ".", ms=2, color="0.5", label="measured")
    a.plot(eps, fn, "-", lw=1.0, color="tab:red", label="force law, no hysteresis")
    a.plot(eps, ff, "-", lw=1.2, color="tab:blue",
           label=f"fitted, delta = {delta:.3g} ± {std_error:.2g}")
    a.set_xlabel("contraction eps [-]")
    a.set_ylabel("muscle force [N]")
    a.grid(alpha=0.3)
    a.legend(fontsize=7)
    k = np.arange(f.size)
    b.plot(k, f - fn, lw=0.8, color="tab:red", label="no hysteresis")
    b.plot(k, f - ff, lw=0.8, color="tab:blue", label="fitted")
    b.axhline(0.0, color="k", lw=0.5)
    b.set_xlabel("sample [-]")
    b.set_ylabel("force residual [N]")
    b.grid(alpha=0.3)
    b.legend(fontsize=7)
    fig.suptitle("hysteresis scale delta of (3.35) from a tensile test (§3.6.5)", fontsize=10)
    fig.tight_layout()
    return fig


__all__ = ["plot_fit", "plot_excitation", "plot_delta_fit"]
