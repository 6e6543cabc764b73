"""The block system as per-chunk, per-channel Gram matrices: thousands of small fits, fast.

The matrices are the engine's one :class:`~ppamsafety.diagnose.core.gram.Gram` (built by
:meth:`~ppamsafety.diagnose.core.gram.Gram.from_blocks`); this module lays out the chunks.

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

import numpy as np

from ..core.criteria import CV_SEGMENTS


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


__all__ = ["chunk_layout"]
