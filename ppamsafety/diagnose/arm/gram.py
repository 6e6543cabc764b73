"""The block system as per-chunk, per-channel Gram matrices: thousands of small fits, fast.

The forward selection, its cross-validation, the confounding checks and the
stability selection fit many models (every candidate, every step, every
half of the record).  Every candidate is linear in its coefficients phi once
the valve dead time is fixed: the whitened residual of block b, channel c is

    e_bc(phi) = (base_bc - P_bc . phi) / sigma_c,
    base = y - X(shift) mu0,   P = X(shift) D + E

(D the candidates' directions in the model vector mu, E their own columns,
:mod:`ppamsafety.diagnose.arm.selection`).  The blocks enter only through
the **Gram matrices** ``[P base]^T [P base]`` summed over each *chunk* (a run
of consecutive blocks) and each channel, kept unscaled, so that

* any set of candidates, on any union of chunks (a cross-validation fold, a
  half of the record), with any noise levels sigma_c, is a k x k solve;
* chi2 per channel is a quadratic form, so the residual-to-noise ratio of
  every channel comes for free.

Chunks nest in the cross-validation segments
(:data:`~ppamsafety.diagnose.core.criteria.CV_SEGMENTS`) and are the units the
stability selection halves the record by: residuals of neighbouring blocks
may be correlated by a model error, so they stay together.

The dead time (a profiled shift of the set values, not a linear coefficient)
is handled by one Gram set per shift: the selection builds the set of the
shift it has chosen.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.criteria import CV_SEGMENTS
from ..core.solve import solve_normal


def chunk_layout(nb: int, *, segments: int = CV_SEGMENTS, length: int | None = None) -> tuple:
    """Chunks of consecutive blocks that nest in the cross-validation segments.

    Parameters
    ----------
    nb : int
        Number of blocks.
    segments : int, keyword-only
        Number of cross-validation segments (alternating folds).
    length : int, optional, keyword-only
        Blocks per chunk; default ceil(nb^(1/3)) (the usual block length of a
        resampling scheme for weakly dependent data), at least 1.

    Returns
    -------
    chunk : numpy.ndarray of int, shape (nb,)
        Chunk index of every block (0, 1, ... in time order).
    fold : numpy.ndarray of int, shape (nchunk,)
        Cross-validation fold (0/1) of every chunk.
    """
    L = max(1, int(math.ceil(nb ** (1.0 / 3.0)))) if length is None else max(1, int(length))
    seg = np.minimum((np.arange(nb) * segments) // nb, segments - 1)
    chunk = np.empty(nb, dtype=int)
    fold = []
    c = 0
    for s in range(segments):
        idx = np.nonzero(seg == s)[0]
        if idx.size == 0:
            continue
        n = max(1, int(round(idx.size / L)))
        parts = np.array_split(idx, n)
        for part in parts:
            chunk[part] = c
            fold.append(s % 2)
            c += 1
    return chunk, np.array(fold, dtype=int)


@dataclass(frozen=True, eq=False)
class GramSet:
    """Per-chunk, per-channel Gram matrices of ``[P base]`` at one dead-time shift.

    Attributes
    ----------
    G : numpy.ndarray, shape (nchunk, nch, K + 1, K + 1)
        Unscaled Gram matrices (columns of every candidate, then ``base``).
    slices : dict
        Candidate name -> slice of the K columns.
    shift : int
        Dead time [samples] of the design the set was built from.
    _cache : dict
        Summed and channel-weighted Grams per chunk mask (internal).
    """

    G: np.ndarray
    slices: dict
    shift: int
    _cache: dict = field(default_factory=dict, repr=False)

    @classmethod
    def build(cls, P, base, chunk, slices, shift: int) -> "GramSet":
        """From the block columns.

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
class GramFit:
    """A least-squares fit from summed Gram matrices.

    Attributes
    ----------
    cols : numpy.ndarray of int
        Columns fitted.
    phi : numpy.ndarray
        Coefficients of ``cols``.
    chi2 : float
        Sum of squared whitened residuals over the chunks fitted.
    chi2_channel : numpy.ndarray, shape (nch,)
        The same per channel.
    A : numpy.ndarray, shape (k, k)
        Whitened normal matrix (for covariances).
    """

    cols: np.ndarray
    phi: np.ndarray
    chi2: float
    chi2_channel: np.ndarray
    A: np.ndarray


def solve(Gs: np.ndarray, cols, sigma, Aw: np.ndarray | None = None, *,
          per_channel: bool = True) -> GramFit:
    """Weighted least squares of ``base`` on the columns ``cols`` from summed Grams ``Gs``.

    Channels are weighted by 1/sigma_c^2.  The normal equations are solved under the
    diagnosis's one rank rule (:func:`~ppamsafety.diagnose.core.solve.solve_normal`: the
    minimum-norm solution of a rank-deficient problem).

    Parameters
    ----------
    Gs : numpy.ndarray, shape (nch, K+1, K+1)
        Summed Gram matrices (:meth:`GramSet.summed`).
    cols : numpy.ndarray of int
        Columns to fit.
    sigma : numpy.ndarray, shape (nch,)
        Noise level of every channel.
    Aw : numpy.ndarray, shape (K+1, K+1), optional
        The channel-weighted sum of ``Gs`` (:meth:`GramSet.weighted`), if at hand.
    per_channel : bool, keyword-only
        Also the chi2 of every channel (else ``chi2_channel`` is None).

    Returns
    -------
    GramFit
    """
    cols = np.asarray(cols, dtype=int)
    K = Gs.shape[1] - 1
    w = 1.0 / np.asarray(sigma, dtype=float) ** 2
    bb_c = Gs[:, K, K] * w
    if cols.size == 0:
        return GramFit(cols=cols, phi=np.zeros(0), chi2=float(bb_c.sum()), chi2_channel=bb_c,
                       A=np.zeros((0, 0)))
    if Aw is None:
        Aw = np.tensordot(w, Gs, axes=1)
    A = Aw[np.ix_(cols, cols)]
    b = Aw[cols, K]
    phi = solve_normal(A, b)
    if not per_channel:
        chi2 = float(max(Aw[K, K] - 2.0 * (b @ phi) + phi @ A @ phi, 0.0))
        return GramFit(cols=cols, phi=phi, chi2=chi2, chi2_channel=None, A=A)
    sub = Gs[:, cols][:, :, cols]                      # (nch, k, k)
    bc = Gs[:, cols, K]                                # (nch, k)
    chi2_c = bb_c - 2.0 * (bc @ phi) * w + np.einsum("i,cij,j->c", phi, sub, phi) * w
    chi2_c = np.maximum(chi2_c, 0.0)
    return GramFit(cols=cols, phi=phi, chi2=float(chi2_c.sum()), chi2_channel=chi2_c, A=A)


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


__all__ = ["GramSet", "GramFit", "chunk_layout", "solve", "chi2_at"]
