"""Intervals that also cover what an effect too small to name does to the named ones.

A 95 % interval from the fit's covariance covers the truth 95 % of the time *if the
model is right*.  On real records it rarely is exactly: an effect of the library that
sits below its detection limit, left out of the final model M, biases M's coefficients
by ``B phi_c`` (the omitted-variable bias of least squares, ``B = A_MM^-1 A_Mc`` with A
the whitened normal matrix).  The residual still holds what M cannot reproduce of that
effect, so the record says how much of it there may be:

* adding candidate c to M changes M's coefficients by ``-B phi_c_hat`` (``phi_c_hat``
  the fit of c on M's residual, through the Schur complement ``S = A_cc - A_cM B``),
  and adds ``B S^-1 B^T`` to their covariance;
* c has a **hint** in the record when its likelihood-ratio statistic ``r^T S^-1 r``
  (``r = Z_c^T e``, e the whitened residual of M) exceeds the ``1 - HINT_P`` quantile
  of chi2 with c's coefficients as degrees of freedom: well below the naming test (p <
  alpha / K), but more than noise usually leaves;
* the reported interval is the union of M's interval and, for every candidate with a
  hint, the interval of M + c (centre moved, variance added).

If the effect left out is one with a hint, the union holds the interval of the right
model, which covers at its level.  Its width says what the record cannot separate:
where a named effect and a hinted one are nearly collinear (a pressure-sensor gain
against a valve characteristic, in the valve equations) it is wide.  The hint level
was set on tuning seeds of the scenario battery (:mod:`ppamsafety.diagnose.scenarios`)
and the coverage measured on others (``docs/diagnose.md``).  This is a sensitivity
interval over single additions (Leamer 1983's extreme-bounds idea restricted to the
additions the data hint at), not a Bayesian model average: a model average recentres
on the additions with high weight, and on the tuning seeds it covered less than the
fit's own interval where the record held an error outside the library.

Used by the arm (:mod:`ppamsafety.diagnose.arm.detection`) and the muscle bench
(:mod:`ppamsafety.diagnose.bench.detection`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from .criteria import _normal_quantile
from .solve import pinv_psd

#: p-value of a candidate's likelihood-ratio test (against the final model) below which it
#: has a *hint* in the record and widens the named effects' intervals (set on tuning seeds).
HINT_P = 0.2


@dataclass(frozen=True)
class OmittedEffect:
    """What adding a candidate left out of the final model M would do to M's coefficients.

    Attributes
    ----------
    V : numpy.ndarray, shape (k_M, k_M)
        ``B S^+ B^T``: the covariance added to M's coefficients.
    shift : numpy.ndarray, shape (k_M,)
        Change of M's coefficients (``-B phi_c_hat``).
    lr : float
        Likelihood-ratio statistic of adding it (decrease of chi2).
    k : int
        The test's degrees of freedom: the rank of its Schur complement (its number of
        coefficients unless the model reproduces some direction of it).
    """

    V: np.ndarray
    shift: np.ndarray
    lr: float
    k: int

    @property
    def p_value(self) -> float:
        """p-value of its likelihood-ratio test (chi2 with ``k`` degrees of freedom)."""
        return float(stats.chi2.sf(max(self.lr, 0.0), self.k))

    @property
    def hinted(self) -> bool:
        """True if the record holds a hint of it (``p_value < HINT_P``)."""
        return self.p_value < HINT_P


def omitted_effects(A, score, model, candidates: dict, *, rows=None) -> dict:
    """:class:`OmittedEffect` of every candidate against the model's columns.

    Parameters
    ----------
    A : numpy.ndarray, shape (K, K)
        Whitened normal matrix ``Z^T Z`` of every column (model and candidates).
    score : numpy.ndarray, shape (K,)
        ``Z^T e``, e the whitened residual of the final model.
    model : numpy.ndarray of int
        Columns of the final model M.
    candidates : dict
        Name -> its columns (not in ``model``).
    rows : numpy.ndarray of int, optional, keyword-only
        Positions within ``model`` of the coefficients to report on, in their order
        (default all: a model column without a coefficient, such as a profiled dead
        time, is conditioned on and left out).

    Returns
    -------
    dict
        Name -> :class:`OmittedEffect`; a candidate the model reproduces exactly (every
        direction within :data:`COLLINEAR_TOL`) is left out: adding it changes nothing.
    """
    A = np.asarray(A, dtype=float)
    score = np.asarray(score, dtype=float)
    model = np.asarray(model, dtype=int)
    rows = np.arange(model.size) if rows is None else np.asarray(rows, dtype=int)
    Ainv = pinv_psd(A[np.ix_(model, model)])
    out = {}
    for name, cc in candidates.items():
        cc = np.asarray(cc, dtype=int)
        Amc = A[np.ix_(model, cc)]
        B = Ainv @ Amc
        Acc = A[np.ix_(cc, cc)]
        Si, rank = _schur_pinv(Acc - Amc.T @ B, Acc)
        if rank == 0:
            continue                    # M reproduces it exactly: adding it changes nothing
        r = score[cc] - B.T @ score[model]
        phi = Si @ r
        Br = B[rows]
        out[name] = OmittedEffect(V=Br @ Si @ Br.T, shift=-(Br @ phi),
                                  lr=float(max(r @ phi, 0.0)), k=rank)
    return out


#: Fraction of a candidate direction's squared norm that the model must leave unexplained for
#: the direction to count (below it, the Schur complement is rounding error).
COLLINEAR_TOL = 1e-10


def _schur_pinv(S, Acc) -> tuple:
    """Pseudo-inverse and rank of the Schur complement S of a candidate against the model,
    directions judged against the candidate's own columns (``Acc``): a direction the model
    reproduces to within :data:`COLLINEAR_TOL` of its norm is dropped, not inverted (scaled
    by S's own diagonal, rounding error would look like a direction of full size)."""
    d = np.sqrt(np.maximum(np.diag(Acc), 0.0))
    d[d == 0] = 1.0
    w, U = np.linalg.eigh(0.5 * (S + S.T) / d[:, None] / d[None, :])
    keep = w > COLLINEAR_TOL
    Uk = U[:, keep]
    return (Uk / w[keep]) @ Uk.T / d[:, None] / d[None, :], int(keep.sum())


def widened_interval(value: float, se: float, gradient, omitted: dict, *,
                     confidence: float = 0.95) -> tuple:
    """The union of the fit's interval and those of the fit plus each hinted candidate.

    Parameters
    ----------
    value : float
        The parameter's estimate.
    se : float
        Its standard error under the final model (>= 0).
    gradient : numpy.ndarray, shape (k_M,)
        Derivative of the parameter with respect to the final model's coefficients.
    omitted : dict
        Name -> :class:`OmittedEffect` (:func:`omitted_effects`).
    confidence : float, keyword-only
        Level of every interval of the union.

    Returns
    -------
    tuple
        ``(low, high, widened_by)``: the bounds and the candidates whose interval reached
        beyond the fit's, in order of how far.
    """
    if not (math.isfinite(value) and math.isfinite(se) and se >= 0.0):
        raise ValueError(f"value = {value!r}, se = {se!r}: a finite estimate and a finite "
                         f"standard error >= 0 are needed")
    z = _normal_quantile(0.5 + confidence / 2)
    g = np.asarray(gradient, dtype=float)
    lo0, hi0 = value - z * se, value + z * se
    lo, hi = lo0, hi0
    reach = {}
    for name, o in omitted.items():
        if not o.hinted:
            continue
        centre = value + float(g @ o.shift)
        half = z * math.sqrt(se ** 2 + max(float(g @ o.V @ g), 0.0))
        if not (math.isfinite(centre) and math.isfinite(half)):
            raise ValueError(f"candidate {name!r}: its change of the coefficients is not "
                             f"finite (centre {centre!r}, half-width {half!r})")
        beyond = max(lo0 - (centre - half), (centre + half) - hi0, 0.0)
        if beyond > 0:
            reach[name] = beyond
        lo, hi = min(lo, centre - half), max(hi, centre + half)
    return lo, hi, tuple(sorted(reach, key=reach.get, reverse=True))


__all__ = ["HINT_P", "COLLINEAR_TOL", "OmittedEffect", "omitted_effects", "widened_interval"]
