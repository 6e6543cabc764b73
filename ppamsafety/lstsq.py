"""Small weighted least-squares problems from an augmented normal matrix, compiled.

The diagnosis ranks thousands of small linear models per record (every
candidate at every forward-selection step, on the whole record, on
cross-validation folds and on the halves of the stability selection).  Each is
given by the augmented normal matrix ``A = [Z y]^T W [Z y]`` of all columns
(``(K+1, K+1)``, the response last) and a set of column indices: its
coefficients solve ``A[c, c] phi = A[c, K]`` and its weighted residual sum of
squares is ``A[K, K] - 2 phi . A[c, K] + phi^T A[c, c] phi``.  A numpy call
per model costs tens of microseconds of overhead; these kernels take one call
per step.

Numerics: the columns are scaled to a unit diagonal and the system is solved by
Cholesky; a pivot below :data:`PIVOT_MIN` (numerically rank-deficient columns,
e.g. a candidate that duplicates one already in the model) falls back to the
minimum-norm solution through the eigen-decomposition, dropping eigenvalues
below :data:`EIG_MIN` of the largest -- as ``numpy.linalg.lstsq`` would.
"""

import numpy as np

from ._jit import kernel

#: Smallest Cholesky pivot (of the unit-diagonal matrix) accepted before the eigen fallback.
PIVOT_MIN = 1e-6
#: Relative eigenvalue below which a direction is dropped (rank deficiency).
EIG_MIN = 1e-12


@kernel
def solve_subset(A, cols, phi):
    """Least squares on the columns ``cols`` of the augmented normal matrix ``A``.

    Parameters
    ----------
    A : float64[:, :]
        (K+1, K+1) augmented normal matrix, the response last.
    cols : int64[:]
        Column indices (< K).
    phi : float64[:]
        Output, length >= len(cols): the coefficients.

    Returns
    -------
    float
        The weighted residual sum of squares (>= 0).
    """
    K = A.shape[0] - 1
    k = cols.shape[0]
    if k == 0:
        return max(A[K, K], 0.0)
    d = np.empty(k)
    for i in range(k):
        v = A[cols[i], cols[i]]
        d[i] = np.sqrt(v) if v > 0.0 else 1.0
    M = np.empty((k, k))
    b = np.empty(k)
    for i in range(k):
        b[i] = A[cols[i], K] / d[i]
        for j in range(k):
            M[i, j] = A[cols[i], cols[j]] / (d[i] * d[j])
    L = np.zeros((k, k))
    ok = True
    for j in range(k):
        s = M[j, j]
        for m in range(j):
            s -= L[j, m] * L[j, m]
        if s <= PIVOT_MIN * PIVOT_MIN:
            ok = False
            break
        L[j, j] = np.sqrt(s)
        for i in range(j + 1, k):
            t = M[i, j]
            for m in range(j):
                t -= L[i, m] * L[j, m]
            L[i, j] = t / L[j, j]
    x = np.empty(k)
    if ok:
        z = np.empty(k)
        for i in range(k):
            t = b[i]
            for m in range(i):
                t -= L[i, m] * z[m]
            z[i] = t / L[i, i]
        for i in range(k - 1, -1, -1):
            t = z[i]
            for m in range(i + 1, k):
                t -= L[m, i] * x[m]
            x[i] = t / L[i, i]
    else:
        w, V = np.linalg.eigh(M)
        wmax = max(w[k - 1], 1e-300)
        for i in range(k):
            x[i] = 0.0
        for e in range(k):
            if w[e] > EIG_MIN * wmax:
                c = 0.0
                for i in range(k):
                    c += V[i, e] * b[i]
                c /= w[e]
                for i in range(k):
                    x[i] += c * V[i, e]
    for i in range(k):
        phi[i] = x[i] / d[i]
    return residual(A, cols, phi)


@kernel
def residual(A, cols, phi):
    """Weighted residual sum of squares of coefficients ``phi`` on columns ``cols`` of ``A``.

    Parameters
    ----------
    A : float64[:, :]
        (K+1, K+1) augmented normal matrix.
    cols : int64[:]
    phi : float64[:]
        Length >= len(cols).

    Returns
    -------
    float
        (>= 0).
    """
    K = A.shape[0] - 1
    k = cols.shape[0]
    r = A[K, K]
    for i in range(k):
        r -= 2.0 * phi[i] * A[cols[i], K]
        for j in range(k):
            r += phi[i] * A[cols[i], cols[j]] * phi[j]
    return max(r, 0.0)


@kernel
def step_scores(A, A_train, A_test, current, cand, ptr, chi2, cv):
    """chi2 and held-out chi2 of ``current`` + each candidate (one forward-selection step).

    Parameters
    ----------
    A : float64[:, :]
        Augmented normal matrix of the data fitted.
    A_train, A_test : float64[:, :, :]
        (F, K+1, K+1): per cross-validation fold, the matrices of the training and of the
        held-out part.
    current : int64[:]
        Columns of the current model.
    cand : int64[:]
        Columns of every candidate, concatenated.
    ptr : int64[:]
        Candidate j owns ``cand[ptr[j]:ptr[j+1]]``.
    chi2, cv : float64[:]
        Outputs per candidate: chi2 on ``A``, and held-out chi2 summed over the folds.
    """
    n = ptr.shape[0] - 1
    nc = current.shape[0]
    kmax = nc
    for j in range(n):
        kmax = max(kmax, nc + ptr[j + 1] - ptr[j])
    phi = np.empty(kmax)
    for j in range(n):
        k = nc + ptr[j + 1] - ptr[j]
        cols = np.empty(k, dtype=np.int64)
        for i in range(nc):
            cols[i] = current[i]
        for i in range(ptr[j], ptr[j + 1]):
            cols[nc + i - ptr[j]] = cand[i]
        chi2[j] = solve_subset(A, cols, phi)
        total = 0.0
        for f in range(A_train.shape[0]):
            solve_subset(A_train[f], cols, phi)
            total += residual(A_test[f], cols, phi)
        cv[j] = total


@kernel
def many_chi2(A, cols, ptr, chi2):
    """chi2 of many column sets on one augmented normal matrix.

    Parameters
    ----------
    A : float64[:, :]
        (K+1, K+1) augmented normal matrix.
    cols : int64[:]
        The column sets, concatenated.
    ptr : int64[:]
        Set j is ``cols[ptr[j]:ptr[j+1]]``.
    chi2 : float64[:]
        Output per set.
    """
    n = ptr.shape[0] - 1
    kmax = 1
    for j in range(n):
        kmax = max(kmax, ptr[j + 1] - ptr[j])
    phi = np.empty(kmax)
    for j in range(n):
        chi2[j] = solve_subset(A, cols[ptr[j]:ptr[j + 1]], phi)


__all__ = ["solve_subset", "residual", "step_scores", "many_chi2", "PIVOT_MIN", "EIG_MIN"]
