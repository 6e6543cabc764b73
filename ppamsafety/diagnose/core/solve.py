"""The one least-squares solve of the diagnosis and its one rank rule, for every record kind.

Every fit of the diagnosis -- an arm's chunk x channel Grams, a muscle bench's equations, a
cylinder campaign's strokes -- is a small weighted least-squares problem given by its
normal matrix ``A = Z^T W Z`` and right-hand side ``b = Z^T W y``.  One rule decides its
rank, whichever kind of record it comes from:

* the columns are scaled to a unit diagonal (the candidates' columns differ by orders of
  magnitude: a payload in kg, a sensor offset in Pa);
* a direction of the scaled matrix whose eigenvalue is below
  :data:`~ppamsafety.lstsq.EIG_MIN` (1e-12) of the largest is dropped -- a singular value
  below 1e-6 of the largest in the scaled columns -- and the minimum-norm solution is
  returned.  Nested candidates (a force gain inside a refitted force law, a gain inside a
  valve offset-and-gain pair) make the matrix singular; the legitimate directions of every
  library stay far above it.

The solve itself is the compiled one (:func:`ppamsafety.lstsq.solve_subset`: Cholesky of the
scaled matrix, the eigen-decomposition when a pivot falls below
:data:`~ppamsafety.lstsq.PIVOT_MIN`), so that the thousands of small fits of a forward
selection and the few fits here agree to rounding.  The covariance of a fit is the
pseudo-inverse under the same rule (:func:`pinv_psd`).
"""

from __future__ import annotations

import numpy as np

from ...lstsq import EIG_MIN, solve_subset


def unit_diagonal(A) -> tuple:
    """``(A / (d d^T), d)``: a symmetric matrix scaled to a unit diagonal, and the scale.

    Parameters
    ----------
    A : numpy.ndarray, shape (k, k)
        Symmetric positive semi-definite (a zero diagonal entry keeps scale 1).
    """
    A = np.asarray(A, dtype=float)
    d = np.sqrt(np.maximum(np.diag(A), 0.0))
    d[d == 0] = 1.0
    return A / d[:, None] / d[None, :], d


def solve_normal(A, b) -> np.ndarray:
    """Minimum-norm solution of the normal equations ``A phi = b`` under the rank rule.

    Parameters
    ----------
    A : numpy.ndarray, shape (k, k)
        Normal matrix (symmetric positive semi-definite).
    b : numpy.ndarray, shape (k,) or (k, r)
        Right-hand side(s).

    Returns
    -------
    numpy.ndarray, shape of ``b``
    """
    A = np.asarray(A, dtype=float)
    b = np.asarray(b, dtype=float)
    k = A.shape[0]
    if b.ndim == 2:
        return np.column_stack([solve_normal(A, b[:, j]) for j in range(b.shape[1])]) \
            if b.shape[1] else np.zeros((k, 0))
    if k == 0:
        return np.zeros(0)
    aug = np.zeros((k + 1, k + 1))
    aug[:k, :k] = A
    aug[:k, k] = b
    aug[k, :k] = b
    phi = np.empty(k)
    solve_subset(aug, np.arange(k, dtype=np.int64), phi)
    return phi


def lstsq(X, y) -> np.ndarray:
    """Least squares ``X coef ~ y`` under the rank rule (tall, narrow ``X``).

    Through the normal equations of the column-scaled ``X`` (:func:`solve_normal`): a
    LAPACK QR or SVD of a tall matrix spends its time synchronising threads on a shared
    machine, and the diagnosis solves thousands of them.

    Parameters
    ----------
    X : numpy.ndarray, shape (m, k)
    y : numpy.ndarray, shape (m,) or (m, r)

    Returns
    -------
    numpy.ndarray, shape (k,) or (k, r)
    """
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float)
    if X.shape[1] == 0:
        return np.zeros((0,) + y.shape[1:])
    s = np.sqrt(np.sum(X * X, axis=0))
    s[s == 0] = 1.0
    Xs = X / s
    coef = solve_normal(Xs.T @ Xs, Xs.T @ y)
    return coef / (s if coef.ndim == 1 else s[:, None])


def pinv_psd(A, *, rank: bool = False):
    """Pseudo-inverse of a symmetric positive semi-definite matrix under the rank rule.

    Parameters
    ----------
    A : numpy.ndarray, shape (k, k)
    rank : bool, keyword-only
        Also return the number of directions kept.

    Returns
    -------
    numpy.ndarray, shape (k, k), or (that, int) when ``rank``
    """
    A = np.asarray(A, dtype=float)
    if A.size == 0:
        return (np.zeros((0, 0)), 0) if rank else np.zeros((0, 0))
    As, d = unit_diagonal(A)
    w, U = np.linalg.eigh(As)
    keep = w > EIG_MIN * max(float(w[-1]), 1e-300)
    Uk = U[:, keep]
    inv = (Uk / w[keep]) @ Uk.T / d[:, None] / d[None, :]
    return (inv, int(keep.sum())) if rank else inv


__all__ = ["EIG_MIN", "unit_diagonal", "solve_normal", "lstsq", "pinv_psd"]
