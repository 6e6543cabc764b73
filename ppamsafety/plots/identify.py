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


__all__ = ["plot_fit", "plot_excitation"]
