"""One Gram-matrix class and one fit from it, for every record kind.

Every record kind reduces to a linear design -- a whitened residual and candidate columns
over groups of equations -- whose samples enter the fits only through the Gram matrices
``[Z y]^T W [Z y]`` summed per group (:class:`Gram`).  Any set of candidates, on any union of
groups (a cross-validation fold, a half of the record), with any noise levels per channel,
is then a k x k solve under the diagnosis's one rank rule (:mod:`.solve`), and chi2 per
channel is a quadratic form.  The arm builds one from its block columns (one per dead-time
shift, :mod:`ppamsafety.diagnose.arm.gram`), a cylinder campaign from its strokes
(:mod:`ppamsafety.diagnose.bench.gram`), a muscle record from its cross-validation folds
(:mod:`.linear_selection`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .solve import solve_normal


@dataclass(frozen=True, eq=False)
class Gram:
    """Per-group, per-channel Gram matrices ``[Z y]^T W [Z y]`` of a linear design.

    A group is the unit the record is resampled and cross-validated by: a chunk of
    consecutive blocks of an arm record, a stroke of a cylinder campaign, a fold of a muscle
    record.  Any set of columns on any union of groups is then a k x k solve
    (:func:`solve`, :func:`chi2_at`).

    Attributes
    ----------
    G : numpy.ndarray, shape (ngroup, nch, K + 1, K + 1)
        Unscaled Gram matrices (the candidate columns, then the response).
    slices : dict
        Candidate name -> slice of the K columns (empty when the caller indexes columns).
    shift : int
        Dead time [samples] of the design the set was built from (an arm's profile; 0).
    weight : numpy.ndarray, shape (ngroup,), or None
        Sum of the sample weights per group (:meth:`from_samples`).
    n : numpy.ndarray, shape (ngroup,), or None
        Samples per group (:meth:`from_samples`).
    _cache : dict
        Summed and channel-weighted Grams per group mask (internal).
    """

    G: np.ndarray
    slices: dict = field(default_factory=dict)
    shift: int = 0
    weight: np.ndarray | None = None
    n: np.ndarray | None = None
    _cache: dict = field(default_factory=dict, repr=False)

    @classmethod
    def from_samples(cls, Z, y, w, group, *, groups: int | None = None) -> "Gram":
        """From weighted samples of one channel (a bench record, a campaign's strokes).

        Parameters
        ----------
        Z : numpy.ndarray, shape (N, M)
            Columns.
        y : numpy.ndarray, shape (N,)
            Response.
        w : numpy.ndarray, shape (N,)
            Sample weights (1 / noise variance).
        group : numpy.ndarray of int, shape (N,)
            Group index 0..C-1 of every sample.
        groups : int, optional, keyword-only
            C (default the largest index + 1; a group without samples has a zero matrix).
        """
        group = np.asarray(group, dtype=int)
        A = np.column_stack([Z, y]) * np.sqrt(w)[:, None]
        C = int(group.max()) + 1 if groups is None else int(groups)
        order = np.argsort(group, kind="stable")
        bounds = np.searchsorted(group[order], np.arange(C + 1))
        G = np.empty((C, 1, A.shape[1], A.shape[1]))
        for c in range(C):
            Ac = A[order[bounds[c]:bounds[c + 1]]]
            G[c, 0] = Ac.T @ Ac
        return cls(G=G, weight=np.bincount(group, weights=w, minlength=C),
                   n=np.bincount(group, minlength=C))

    @classmethod
    def from_blocks(cls, P, base, chunk, slices, shift: int) -> "Gram":
        """From the block columns of an arm record (one chunk is a run of blocks).

        Parameters
        ----------
        P : numpy.ndarray, shape (nb, nch, K)
            Prediction change per unit coefficient, every candidate.
        base : numpy.ndarray, shape (nb, nch)
            Residual of the nominal model.
        chunk : numpy.ndarray of int, shape (nb,)
            Chunk of every block (consecutive, 0..nchunk-1).
        slices : dict
            Candidate -> slice of the K columns.
        shift : int
            Dead time [samples].
        """
        A = np.concatenate([P, base[:, :, None]], axis=2)
        nchunk = int(chunk.max()) + 1
        bounds = np.searchsorted(chunk, np.arange(nchunk + 1))
        G = np.empty((nchunk, A.shape[1], A.shape[2], A.shape[2]))
        for c in range(nchunk):
            a = A[bounds[c]:bounds[c + 1]]
            G[c] = np.einsum("bci,bcj->cij", a, a, optimize=True)
        return cls(G=G, slices=dict(slices), shift=int(shift))

    @property
    def K(self) -> int:
        """Number of candidate columns."""
        return self.G.shape[2] - 1

    def columns(self, names) -> np.ndarray:
        """Column indices of the candidates ``names`` (in that order).

        Parameters
        ----------
        names : sequence of str
        """
        idx = [np.arange(self.slices[n].start, self.slices[n].stop) for n in names]
        return np.concatenate(idx) if idx else np.zeros(0, dtype=int)

    def summed(self, chunks=None) -> np.ndarray:
        """Gram matrices summed over ``chunks`` (bool mask; default all) -> (nch, K+1, K+1).

        Remembered per mask (the selection sums the same folds and halves many times).

        Parameters
        ----------
        chunks : numpy.ndarray of bool, optional
        """
        key = ("sum", None if chunks is None else np.asarray(chunks, bool).tobytes())
        if key not in self._cache:
            if len(self._cache) > 512:
                self._cache.clear()
            self._cache[key] = (self.G.sum(axis=0) if chunks is None
                                else self.G[np.asarray(chunks, bool)].sum(axis=0))
        return self._cache[key]

    def weighted(self, chunks, sigma) -> tuple:
        """``(Gs, Aw)``: the summed Grams and their channel-weighted sum sum_c Gs_c / sigma_c^2.

        Parameters
        ----------
        chunks : numpy.ndarray of bool or None
        sigma : numpy.ndarray, shape (nch,)
        """
        sigma = np.asarray(sigma, dtype=float)
        key = ("w", None if chunks is None else np.asarray(chunks, bool).tobytes(),
               sigma.tobytes())
        if key not in self._cache:
            Gs = self.summed(chunks)
            self._cache[key] = (Gs, np.tensordot(1.0 / sigma ** 2, Gs, axes=1))
        return self._cache[key]


@dataclass(frozen=True, eq=False)
class _GramFit:
    """A least-squares fit from summed Gram matrices, every record kind.

    An engine intermediate (the selection makes thousands per diagnosis), never handed to a
    user: what a user receives is the :class:`~ppamsafety.diagnose.core.result.Diagnosis`.
    So it is private and not a result object (no table, no figure of its own).

    Attributes
    ----------
    cols : numpy.ndarray of int
        Columns fitted.
    phi : numpy.ndarray
        Coefficients of ``cols``.
    chi2 : float
        Sum of squared whitened (weighted) residuals over the groups fitted.
    chi2_channel : numpy.ndarray, shape (nch,), or None
        The same per channel.
    A : numpy.ndarray, shape (k, k), or None
        Whitened normal matrix (for covariances).
    wsum : float or None
        Sum of the sample weights fitted (the weighted mean square is ``chi2 / wsum``).
    cov : numpy.ndarray or None
        Cluster-robust covariance (when asked).
    """

    cols: np.ndarray
    phi: np.ndarray
    chi2: float
    chi2_channel: np.ndarray | None = None
    A: np.ndarray | None = None
    wsum: float | None = None
    cov: np.ndarray | None = None

    @property
    def mse(self) -> float:
        """Weighted mean square of the residual (in noise variances when w = 1/sigma^2)."""
        return self.chi2 / self.wsum


def solve(Gs: np.ndarray, cols, sigma, Aw: np.ndarray | None = None, *,
          per_channel: bool = True) -> _GramFit:
    """Weighted least squares of ``base`` on the columns ``cols`` from summed Grams ``Gs``.

    Channels are weighted by 1/sigma_c^2.  The normal equations are solved under the
    diagnosis's one rank rule (:func:`~ppamsafety.diagnose.core.solve.solve_normal`: the
    minimum-norm solution of a rank-deficient problem).

    Parameters
    ----------
    Gs : numpy.ndarray, shape (nch, K+1, K+1)
        Summed Gram matrices (:meth:`Gram.summed`).
    cols : numpy.ndarray of int
        Columns to fit.
    sigma : numpy.ndarray, shape (nch,)
        Noise level of every channel.
    Aw : numpy.ndarray, shape (K+1, K+1), optional
        The channel-weighted sum of ``Gs`` (:meth:`Gram.weighted`), if at hand.
    per_channel : bool, keyword-only
        Also the chi2 of every channel (else ``chi2_channel`` is None).

    Returns
    -------
    _GramFit
    """
    cols = np.asarray(cols, dtype=int)
    K = Gs.shape[1] - 1
    w = 1.0 / np.asarray(sigma, dtype=float) ** 2
    bb_c = Gs[:, K, K] * w
    if cols.size == 0:
        return _GramFit(cols=cols, phi=np.zeros(0), chi2=float(bb_c.sum()), chi2_channel=bb_c,
                       A=np.zeros((0, 0)))
    if Aw is None:
        Aw = np.tensordot(w, Gs, axes=1)
    A = Aw[np.ix_(cols, cols)]
    b = Aw[cols, K]
    phi = solve_normal(A, b)
    if not per_channel:
        chi2 = float(max(Aw[K, K] - 2.0 * (b @ phi) + phi @ A @ phi, 0.0))
        return _GramFit(cols=cols, phi=phi, chi2=chi2, chi2_channel=None, A=A)
    sub = Gs[:, cols][:, :, cols]                      # (nch, k, k)
    bc = Gs[:, cols, K]                                # (nch, k)
    chi2_c = bb_c - 2.0 * (bc @ phi) * w + np.einsum("i,cij,j->c", phi, sub, phi) * w
    chi2_c = np.maximum(chi2_c, 0.0)
    return _GramFit(cols=cols, phi=phi, chi2=float(chi2_c.sum()), chi2_channel=chi2_c, A=A)


def chi2_at(Gs: np.ndarray, cols, phi, sigma, Aw: np.ndarray | None = None) -> float:
    """chi2 of given coefficients on summed Grams (held-out data of a fold).

    Parameters
    ----------
    Gs : numpy.ndarray, shape (nch, K+1, K+1)
    cols : numpy.ndarray of int
    phi : numpy.ndarray
    sigma : numpy.ndarray, shape (nch,)
    Aw : numpy.ndarray, shape (K+1, K+1), optional
        The channel-weighted sum of ``Gs`` (then ``Gs`` may be None).
    """
    cols = np.asarray(cols, dtype=int)
    if Aw is None:
        Aw = np.tensordot(1.0 / np.asarray(sigma, dtype=float) ** 2, Gs, axes=1)
    K = Aw.shape[0] - 1
    if cols.size == 0:
        return float(Aw[K, K])
    c = Aw[K, K] - 2.0 * (Aw[cols, K] @ phi) + phi @ Aw[np.ix_(cols, cols)] @ phi
    return float(max(c, 0.0))


__all__ = ["Gram", "solve", "chi2_at"]
