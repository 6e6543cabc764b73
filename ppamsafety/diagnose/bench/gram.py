"""Weighted least squares from per-cluster Gram matrices: fits, cross-validation, robust tests.

The matrices are the engine's one :class:`~ppamsafety.diagnose.core.gram.Gram`, one group
per cluster and one channel (:meth:`~ppamsafety.diagnose.core.gram.Gram.from_samples`); the
fit is its :class:`~ppamsafety.diagnose.core.gram._GramFit`.

A bench campaign has tens of thousands of samples and a few hundred candidate
columns, and the selection fits thousands of small models (every candidate,
every profiled variant, every step, every stability subset).  The samples
enter only through the **per-cluster Gram matrices** ``G_c = [Z y]^T W [Z y]``
(a cluster is one stroke of the motion: the residual of a real bench is
correlated within a stroke, not between strokes), computed once; any model
(a set of columns J) on any set of clusters is then a small linear solve:

* coefficients ``phi = G_JJ^-1 b_J`` under the diagnosis's one rank rule
  (:mod:`ppamsafety.diagnose.core.solve`: the minimum-norm solution for exactly collinear
  columns);
* weighted SSE ``y^T W y - 2 phi^T b_J + phi^T G_JJ phi``;
* held-out SSE of a fold from the other fold's fit;
* the cluster-robust ("sandwich") covariance with strokes as clusters,
  ``G_JJ^-1 (sum_c u_c u_c^T) G_JJ^-1 C/(C-1)``, ``u_c = b_cJ - G_cJJ phi``:
  the naive OLS standard errors are several times too small on correlated
  bench residuals (groundwork: ~10x).
"""

from __future__ import annotations

import numpy as np
from scipy import special

from ..core.gram import Gram, _GramFit
from ..core.solve import pinv_psd, solve_normal


def _phi(G, cols):
    """Coefficients of the columns ``cols`` of a summed Gram (:func:`~..core.solve.solve_normal`)."""
    return solve_normal(G[np.ix_(cols, cols)], G[cols, -1]) if cols.size else np.zeros(0)


def sse_of(G, cols, phi) -> float:
    """Weighted SSE of coefficients ``phi`` on the columns ``cols`` of a summed Gram.

    Parameters
    ----------
    G : numpy.ndarray, shape (M + 1, M + 1)
        Summed Gram matrix.
    cols : numpy.ndarray of int
        Column indices.
    phi : numpy.ndarray
        Coefficients.
    """
    y = G.shape[0] - 1
    if cols.size == 0:
        return float(G[y, y])
    A = G[np.ix_(cols, cols)]
    b = G[cols, y]
    return float(G[y, y] - 2.0 * phi @ b + phi @ A @ phi)


def fit(cg: Gram, clusters, cols, *, robust: bool = False, Gsum=None) -> _GramFit:
    """Fit the columns ``cols`` on the clusters ``clusters``.

    Parameters
    ----------
    cg : Gram
        The per-cluster Grams (one channel).
    clusters : numpy.ndarray of int
        Clusters used.
    cols : array_like of int
        Column indices.
    robust : bool, keyword-only
        Also compute the cluster-robust covariance.
    Gsum : numpy.ndarray, optional, keyword-only
        ``cg.G[clusters, 0].sum(0)`` if already known.

    Returns
    -------
    _GramFit
    """
    cols = np.asarray(cols, int)
    G = cg.G[clusters, 0].sum(axis=0) if Gsum is None else Gsum
    phi = _phi(G, cols)
    sse = sse_of(G, cols, phi)
    wsum = float(cg.weight[clusters].sum())
    cov = None
    if robust and cols.size:
        inv = pinv_psd(G[np.ix_(cols, cols)])
        y = G.shape[0] - 1
        cl = np.asarray(clusters)
        # only the (cluster, J, J) and (cluster, J, y) blocks: copying every cluster's whole
        # Gram (hundreds of columns) dominated the selection's time
        G1 = cg.G[:, 0]
        u = G1[np.ix_(cl, cols, [y])][..., 0] - np.einsum(
            "cij,j->ci", G1[np.ix_(cl, cols, cols)], phi)
        C = len(clusters)
        meat = u.T @ u * (C / max(C - 1, 1))
        cov = inv @ meat @ inv
    return _GramFit(cols=cols, phi=phi, chi2=sse, wsum=wsum, cov=cov)


def cv_mse(cg: Gram, folds: list, cols) -> float:
    """Held-out weighted MSE of 2-fold cross-validation over cluster sets.

    Parameters
    ----------
    cg : Gram
        The per-cluster Grams.
    folds : list of (numpy.ndarray, numpy.ndarray)
        Summed Grams (G_fold0, G_fold1) and their weight sums as
        ``[(G0, w0), (G1, w1)]``.
    cols : array_like of int
        Column indices.
    """
    cols = np.asarray(cols, int)
    (G0, w0), (G1, w1) = folds
    p0, p1 = _phi(G0, cols), _phi(G1, cols)
    return (sse_of(G1, cols, p0) + sse_of(G0, cols, p1)) / (w0 + w1)


def wald(phi, cov, block) -> tuple:
    """Wald statistic of ``phi[block] = 0`` with the covariance ``cov``; (stat, df, p).

    Parameters
    ----------
    phi : numpy.ndarray
        Coefficients.
    cov : numpy.ndarray
        Their covariance.
    block : slice or array of int
        The coefficients tested.
    """
    b = phi[block]
    V = cov[block][:, block] if not isinstance(block, slice) else cov[block, block]
    Vi, df = pinv_psd(V, rank=True)
    stat = float(b @ Vi @ b)
    return stat, df, float(special.chdtrc(max(df, 1), stat))


__all__ = ["fit", "cv_mse", "wald", "sse_of"]
