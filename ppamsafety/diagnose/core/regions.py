"""Where the final residual sits: its mean, RMS and z per operating region, every record kind.

A region is a named family of groups of equations (the terciles of a pressure, the sign of
a velocity, the time segments of the record); a group is *significant* when its mean
residual is far from zero for its size (|z| beyond the two-sided 99.9 % point) or its RMS
is above the residual/noise limit.  The arm reads it per block channel, a muscle record
for its force; the rows have the same columns (``docs/diagnose.md``).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy import stats

#: |z| of a group's mean residual beyond which it is significant (two-sided 99.9 %).
Z_CRIT = float(stats.norm.isf(0.0005))


def terciles(x, name: str, *, scale: float = 1.0, unit: str = "",
             merge_equal: bool = False) -> dict:
    """Low, middle and high third of ``x`` as labelled masks.

    Parameters
    ----------
    x : numpy.ndarray
        The quantity (SI).
    name : str
        Its symbol in the labels.
    scale : float, keyword-only
        Factor from SI to the unit of the labels.
    unit : str, keyword-only
        Unit of the labels ("" for none).
    merge_equal : bool, keyword-only
        One group when the terciles coincide (a quantity at one level).
    """
    a, b = np.quantile(x, [1 / 3, 2 / 3])
    u = f" {unit}" if unit else ""
    if merge_equal and a == b:
        return {f"{name} = {a * scale:.3g}{u}": np.ones(x.size, bool)}
    return {f"{name} low (< {a * scale:.3g}{u})": x < a, f"{name} mid": (x >= a) & (x < b),
            f"{name} high (>= {b * scale:.3g}{u})": x >= b}


def time_segments(t, *, n: int = 8, digits: int = 3) -> dict:
    """``n`` equal time segments of the record as labelled masks.

    Parameters
    ----------
    t : numpy.ndarray
        Time of every equation [s].
    n : int, keyword-only
    digits : int, keyword-only
        Significant digits of the labels.
    """
    edges = np.linspace(t.min(), t.max() + 1e-12, n + 1)
    return {f"t {edges[i]:.{digits}g}-{edges[i + 1]:.{digits}g} s":
            (t >= edges[i]) & (t < edges[i + 1]) for i in range(n)}


def region_rows(e, groups: dict, channel: str, rho_max: float, *, cluster=None,
                min_n: int = 1) -> list:
    """One row per group of at least ``min_n`` equations: ``channel``, ``region``, ``group``,
    ``blocks``, ``mean``, ``rms``, ``z``, ``significant``.

    Parameters
    ----------
    e : numpy.ndarray, shape (m,)
        Whitened final residual of one channel.
    groups : dict
        Region -> {group label -> bool mask}.
    channel : str
    rho_max : float
        Largest acceptable RMS.
    cluster : numpy.ndarray of int, optional, keyword-only
        Cluster of every equation (a stroke of a cylinder): z is then the mean over the
        standard error of the cluster means (residuals correlated within a cluster), else
        ``mean sqrt(n)`` (whitened, independent equations).
    min_n : int, keyword-only
        Fewest equations of a group reported.
    """
    rows = []
    for region, gs in groups.items():
        for g, m in gs.items():
            n = int(m.sum())
            if n < max(min_n, 1):
                continue
            em = e[m]
            mean = float(em.mean())
            rms = float(np.sqrt(np.mean(em ** 2)))
            if cluster is None:
                z = mean * math.sqrt(n)
            else:
                sm = pd.Series(em).groupby(cluster[m]).mean().to_numpy()
                se = float(np.std(sm, ddof=1) / math.sqrt(sm.size)) if sm.size > 2 \
                    else math.inf
                z = mean / se if se > 0 else math.inf
            rows.append({"channel": channel, "region": region, "group": g, "blocks": n,
                         "mean": mean, "rms": rms, "z": z,
                         "significant": bool(abs(z) > Z_CRIT or rms > rho_max)})
    return rows


def largest_regions(where: pd.DataFrame, n: int = 3) -> pd.DataFrame:
    """The ``n`` significant rows of a residual-by-region table with the largest |z|.

    Parameters
    ----------
    where : pandas.DataFrame
        Rows of :func:`region_rows` (columns ``significant`` and ``z``).
    n : int
        How many rows at most.

    Returns
    -------
    pandas.DataFrame
        Those rows, largest |z| first (empty when none is significant).
    """
    sig = where[where["significant"]]
    return sig.reindex(sig["z"].abs().sort_values(ascending=False).index).head(n)


__all__ = ["terciles", "time_segments", "region_rows", "largest_regions", "Z_CRIT"]
