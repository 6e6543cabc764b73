"""Detection limits: the smallest change of each effect that a record would have revealed.

When nothing (or not everything) is named, a user must be able to tell
"absent" from "too small to see".  For every candidate c and each of its
parameters j, the **detection limit** is the smallest change of that
parameter alone (the others at their nominal values) that the naming rule
would pick up with probability :data:`POWER` on *this* record, at its noise
level and length, against the final model M of the diagnosis (without c):

* the likelihood-ratio statistic of adding c is noncentral chi2 with k_c
  degrees of freedom and noncentrality ``lambda = phi^T S phi``, S the
  Schur complement ``Z_c^T (I - P_M) Z_c`` of the whitened columns (what of
  c's signature the model M cannot already reproduce);
* c is named when the statistic exceeds ``max(chi2_k^-1(1 - alpha/K), k ln m)``
  (the Bonferroni-divided LR test and a lower BIC);
* the needed noncentrality lambda* solves ``P(chi2_k(lambda*) > crit) = POWER``,
  and the limit of parameter j is ``sqrt(lambda* / S_jj)`` in coefficient
  units, converted to the parameter's unit through the candidate's physical
  map (its derivative at the nominal model);
* detected is not yet *named*: a candidate whose signature another one can
  mimic on this record is reported as confounded with it.  ``limit_named``
  repeats the computation against the final model plus the most similar
  other candidate (the largest limit over all of them): above it, the effect
  is told apart from every single alternative.

The dead time enters through the linearisation of the design in the shift
(one sample).  The limits are first-order: the battery of
:mod:`ppamsafety.diagnose.scenarios` checks them (named rate of effects
above and below their limit).  "High" confidence needs more than naming (a
stable choice on each half of the record, a residual at the noise): about
sqrt(2) x the limit.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from ..core.omitted import omitted_effects
from ..core.power import POWER, needed_noncentrality
from .candidates import REGISTRY, library
from ..core.solve import pinv_psd
from .selection import Problem, _directions, _gram_set


def _design(prob: Problem, fit, universe, *, blocks: bool = False):
    """Whitened normal matrix of every candidate's columns (the dead time linearised in its
    shift: one sample of delay) at the final model; columns per candidate; with ``blocks``
    also the columns themselves, whitened, shape (nb, 6, K)."""
    shift = int(fit.shift)
    lin = [n for n in universe if not REGISTRY[n].grid]
    gs, _ = _gram_set(prob, tuple(universe), shift)
    Gs = gs.summed()
    w = 1.0 / prob.sigma ** 2
    K = gs.K
    A = np.tensordot(w, Gs[:, :K, :K], axes=1)
    cols = {n: gs.columns([n]) for n in lin}
    grid = [n for n in universe if REGISTRY[n].grid]
    P = None
    if grid or blocks:
        X0 = prob.X(shift)
        nb, nc, nm = X0.shape
        D, _, _, E = _directions(prob, lin)
        P = (X0.reshape(nb * nc, nm) @ D).reshape(nb, nc, D.shape[1])
        if E is not None:
            P = P + E
    if grid:
        X1 = prob.X(shift + 1)
        col = ((X1 - X0).reshape(nb * nc, nm) @ prob.mu0).reshape(nb, nc)
        cross = np.einsum("bci,c,bc->i", P, w, col)
        A2 = np.zeros((K + 1, K + 1))
        A2[:K, :K] = A
        A2[:K, K] = A2[K, :K] = cross
        A2[K, K] = float(np.einsum("bc,c,bc->", col, w, col))
        A = A2
        cols[grid[0]] = np.array([K])
        if blocks:
            P = np.concatenate([P, col[:, :, None]], axis=2)
    if blocks:
        return A, cols, P / prob.sigma[None, :, None]
    return A, cols


def _schur(A, cc, cm):
    Acc = A[np.ix_(cc, cc)]
    if cm.size == 0:
        return Acc
    Acm = A[np.ix_(cc, cm)]
    return Acc - Acm @ pinv_psd(A[np.ix_(cm, cm)]) @ Acm.T


def detection_limits(prob: Problem, fit, candidates=None, *, alpha: float = 0.01,
                     power: float = POWER, shadows=()) -> dict:
    """Detection limit of every parameter of every candidate on this record (module docstring).

    Parameters
    ----------
    prob : Problem
        The problem at the final model's noise levels.
    fit : _Fit
        The final fit (its names form the model M).
    candidates : sequence of str, optional
        The library searched (default all).
    alpha : float, keyword-only
        Level of the LR test before the Bonferroni division.
    power : float, keyword-only
        Probability of naming at the limit.
    shadows : sequence of str, keyword-only
        Candidates outside the library that the diagnosis tries as look-alikes
        (:func:`.subsets.search`): they count as ``closest`` too, since a name they can
        replace is reported as confounded.

    Returns
    -------
    dict
        name -> {parameter: {"limit", "limit_named", "closest", "unit", "nominal"}}:
        ``limit`` the change of the parameter (from its nominal value) detected with
        probability ``power`` against the final model; ``limit_named`` the change at which
        it would also be told apart from the candidate ``closest`` that looks most like it
        (detected against the final model plus that candidate: below it the two would be
        reported as confounded, not named).
    """
    universe = tuple(c.name for c in library(candidates))
    shadows = tuple(n for n in shadows if n not in universe)
    A, cols = _design(prob, fit, universe + shadows)
    m = prob.bs.nb * prob.bs.y.shape[1]
    model = [n for n in fit.names]
    out = {}
    n_rest = max(len(universe) - len(fit.names), 1)
    for c in library(universe):
        others = [n for n in model if n != c.name]
        cm = np.concatenate([cols[n] for n in others]) if others else np.zeros(0, dtype=int)
        cc = cols[c.name]
        S = _schur(A, cc, cm)
        alts = {}
        for a in universe + shadows:
            if a == c.name or a in others:
                continue
            alts[a] = _schur(A, cc, np.concatenate([cm, cols[a]]))
        k = len(c.parameters)
        level = alpha / (n_rest + (1 if c.name in fit.names else 0))
        crit = max(float(stats.chi2.isf(level, k)), k * math.log(m))
        lam = needed_noncentrality(k, crit, power)
        entry = {}
        for j, p in enumerate(c.parameters):
            lim = _limit(S, j, lam)
            worst, closest = lim, None
            for a, Sa in alts.items():
                la = _limit(Sa, j, lam)
                if la > worst:
                    worst, closest = la, a
            scale, nominal = _physical_slope(prob, c, j, 1.0 if not np.isfinite(lim) else lim)
            entry[p.name] = {"limit": float(abs(scale) * lim), "limit_named": float(
                abs(scale) * worst), "closest": closest, "unit": p.unit, "nominal": nominal}
        out[c.name] = entry
    return out


def omitted(prob: Problem, fit, candidates=None, *, shadows=()) -> dict:
    """What adding each candidate the diagnosis did not name would do to the named ones
    (:mod:`ppamsafety.diagnose.core.omitted`).

    Parameters
    ----------
    prob : Problem
        The problem at the final model's noise levels.
    fit : _Fit
        The final fit (its names form M; ``fit.e`` formed).
    candidates : sequence of str, optional
        The library searched (default all).
    shadows : sequence of str, keyword-only
        Opt-in candidates outside the library that the diagnosis tried as look-alikes: a
        user's arm may hold them as well.

    Returns
    -------
    dict
        Name of every candidate not in M -> :class:`~ppamsafety.diagnose.core.omitted.
        OmittedEffect` in the coordinates of ``fit.phi`` (a named dead time, which has no
        coefficient, is conditioned on).
    """
    universe = tuple(c.name for c in library(candidates))
    shadows = tuple(n for n in shadows if n not in universe)
    names = tuple(fit.names)
    if not any(not REGISTRY[n].grid for n in names):
        return {}
    A, cols, Z = _design(prob, fit, tuple(dict.fromkeys(universe + shadows + names)),
                         blocks=True)
    cm = np.concatenate([cols[n] for n in names])
    rows = np.zeros(fit.phi.size, dtype=int)       # positions in cm of fit.phi's entries
    at = 0
    for n in names:
        if not REGISTRY[n].grid:
            rows[fit.slices[n]] = np.arange(at, at + cols[n].size)
        at += cols[n].size
    score = np.einsum("bck,bc->k", Z, fit.e)
    rest = {c.name: cols[c.name] for c in library(universe + shadows) if c.name not in names}
    return omitted_effects(A, score, cm, rest, rows=rows)


def _limit(S, j, lam):
    """Coefficient change of column j detected with noncentrality lam (inf: not at all)."""
    sjj = float(S[j, j]) if S.size else 0.0
    return math.sqrt(lam / sjj) if sjj > 1e-300 else math.inf


def _physical_slope(prob, c, j, dphi):
    """d(parameter j)/d(phi_j) of candidate c at the nominal model, and the nominal value."""
    if c.grid:
        return prob.bs.dt, 0.0
    D, slices, _, _ = _directions(prob, [c.name])
    k = D.shape[1]
    phi0 = np.zeros(k)
    v0 = np.asarray(c.physical(prob.mu0, phi0, 0.0), float)
    h = 1e-6 * max(dphi, 1e-12)
    phi1 = phi0.copy()
    phi1[j] = h
    v1 = np.asarray(c.physical(prob.mu0 + D @ phi1, phi1, 0.0), float)
    nominal = float(v0[j]) if c.directions is not None else 0.0
    return (v1[j] - v0[j]) / h, nominal


__all__ = ["detection_limits", "omitted", "POWER"]
