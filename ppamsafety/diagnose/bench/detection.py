"""Detection limits on a muscle record: the smallest change of each candidate the record would reveal.

The arm's construction (:mod:`ppamsafety.diagnose.arm.detection`) on the
whitened design of :mod:`.design`.  For every applicable candidate c and each
of its parameters j, the **detection limit** is the smallest change of that
parameter alone (the others at their nominal values) that the naming rule
would pick up with probability :data:`~ppamsafety.diagnose.core.power.POWER`
(0.9) against the final model M of the diagnosis (without c):

* the likelihood-ratio statistic of adding c is noncentral chi2 with k_c
  degrees of freedom and noncentrality ``lambda = phi^T S phi``, S the Schur
  complement ``Z_c^T (I - P_M) Z_c`` of the whitened columns;
* c is named when the statistic exceeds ``max(chi2_k^-1(1 - alpha/K), k ln m,
  MIN_EFFECT_RMS^2 m)``: the Bonferroni-divided LR test, a lower BIC and --
  unlike the arm -- rule 5 of the muscle's naming rule (:mod:`.selection`),
  which on long records is the binding one;
* the limit of parameter j is ``sqrt(lambda* / S_jj)`` (every muscle
  candidate's parameters are its coefficients, so no unit conversion);
* ``limit_named`` repeats it against M plus the most similar other candidate
  (the largest limit over all of them): above it the effect is told apart
  from every single alternative.  A force-sensor gain, nested in the refitted
  law, has an infinite ``limit_named``: it can never be named, only reported
  as confounded.

:func:`signature_ratio` measures a *given* change (a hidden effect's true
signature on the record, for the scenario battery) against the same
criterion: ``sqrt(lambda_true / lambda*)`` with lambda_true the noncentrality
of c's LR test when the residual holds that signature.  For a one-parameter
candidate whose column is its exact signature this is |change| / limit, the
arm's ratio; for several parameters it measures the change as a whole -- a
uniform scale of the force-law coefficients, which a force gain mimics exactly,
is then (rightly) invisible against that look-alike, while the largest
single-coefficient ratio would call it detectable.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from ..core.omitted import omitted_effects
from ..core.power import POWER, needed_noncentrality
from ..core.solve import lstsq
from .selection import MIN_EFFECT_RMS


def _residualize(Z, X):
    """Z minus its projection on the span of X's columns (X may be empty)."""
    if X is None or X.shape[1] == 0:
        return Z
    return Z - X @ lstsq(X, Z)


def _stack(columns, names):
    names = list(names)
    if not names:
        return None
    return np.concatenate([columns[n] for n in names], axis=1)


def _critical(k: int, m: int, level: float) -> float:
    return max(float(stats.chi2.isf(level, k)), k * math.log(m), MIN_EFFECT_RMS ** 2 * m)


def _level(n_candidates: int, n_model: int, in_model: bool, alpha: float) -> float:
    return alpha / max(n_candidates - n_model + (1 if in_model else 0), 1)


def detection_limits(design, model, *, alpha: float = 0.01, power: float = POWER) -> dict:
    """Detection limit of every parameter of every applicable candidate (module docstring).

    Parameters
    ----------
    design : ActuatorDesign
    model : sequence of str
        The final model's candidates.
    alpha : float, keyword-only
        Level of the LR test before the Bonferroni division.
    power : float, keyword-only
        Probability of naming at the limit.

    Returns
    -------
    dict
        name -> {parameter: {"limit", "limit_named", "closest", "unit", "nominal"}} in the
        parameter's unit (``limit_named`` inf when a look-alike reproduces the parameter's
        column exactly); parameters the record does not fit (a force-law coefficient that is
        not freed) are left out.
    """
    cols = design.columns
    m = design.m
    model = [n for n in model if n in cols]
    out = {}
    for c, ext in design.extensions.items():
        others = [n for n in model if n != c]
        Zc = cols[c]
        k = Zc.shape[1]
        lam = needed_noncentrality(k, _critical(k, m, _level(len(cols), len(model), c in model,
                                                             alpha)), power)
        R = _residualize(Zc, _stack(cols, others))
        S = np.sum(R ** 2, axis=0)
        alts = {a: np.sum(_residualize(Zc, _stack(cols, others + [a])) ** 2, axis=0)
                for a in cols if a != c and a not in others}
        entry = {}
        for i, p in enumerate(ext.parameters):
            rows = np.flatnonzero(ext.T[i] != 0.0)
            if rows.size != 1:
                continue                               # not fitted on this record
            j = int(rows[0])
            scale = abs(float(ext.T[i, j]))
            lim = _limit(S[j], lam)
            worst, closest = lim, None
            for a, Sa in alts.items():
                la = _limit(Sa[j], lam)
                if la > worst:
                    worst, closest = la, a
            entry[p.name] = {"limit": scale * lim, "limit_named": scale * worst,
                             "closest": closest, "unit": p.unit,
                             "nominal": float(ext.nominal[i])}
        out[c] = entry
    return out


def limit_ratio(design, model, name: str, lr_stat: float, *, alpha: float = 0.01,
                power: float = POWER) -> float:
    """How far above its detection limit a *fitted* effect stands: ``sqrt(LR / lambda*)``.

    ``LR`` is the likelihood-ratio statistic of ``name`` against the final model
    without it, ``lambda*`` the noncentrality the naming rule needs to pick the
    effect up with probability ``power`` (module docstring).  For a one-parameter
    candidate this is about |change| / limit (the arm's ratio of the ``clear`` gate);
    for several parameters it measures the fitted change as a whole, as
    :func:`signature_ratio` does for a true one.

    Parameters
    ----------
    design : ActuatorDesign
    model : sequence of str
        The final model's candidates.
    name : str
        A member of ``model``.
    lr_stat : float
        Its likelihood-ratio statistic given the other members (>= 0).
    alpha, power : float, keyword-only
        As :func:`detection_limits`.

    Returns
    -------
    float
    """
    cols = design.columns
    if name not in cols:
        raise ValueError(f"name = {name!r} is not an applicable candidate of the record; "
                         f"allowed {list(cols)}")
    if not (lr_stat >= 0.0):
        raise ValueError(f"lr_stat = {lr_stat!r}: a likelihood-ratio statistic is >= 0")
    model = [n for n in model if n in cols]
    k = cols[name].shape[1]
    lam = needed_noncentrality(k, _critical(k, design.m, _level(len(cols), len(model),
                                                             name in model, alpha)), power)
    return math.sqrt(lr_stat / lam)


def omitted(design, fit) -> dict:
    """What adding each applicable candidate left out of the final model would do to its
    coefficients (:mod:`ppamsafety.diagnose.core.omitted`).

    Parameters
    ----------
    design : ActuatorDesign
    fit : _LinearFit
        The final fit (``fit.e`` the whitened residual on the design's samples).

    Returns
    -------
    dict
        Name -> :class:`~ppamsafety.diagnose.core.omitted.OmittedEffect` in the
        coordinates of ``fit.phi``.
    """
    cols = design.columns
    names = [n for n in fit.names if n in cols]
    if not names:
        return {}
    rest = [c for c in cols if c not in names]
    Z = np.concatenate([cols[n] for n in names + rest], axis=1)
    k_m = sum(cols[n].shape[1] for n in names)
    at, idx = k_m, {}
    for c in rest:
        idx[c] = np.arange(at, at + cols[c].shape[1])
        at += cols[c].shape[1]
    return omitted_effects(Z.T @ Z, Z.T @ fit.e, np.arange(k_m), idx)


def _limit(s, lam):
    return math.sqrt(lam / s) if s > 1e-12 * lam else math.inf


def signature_ratio(design, model, name: str, signature, *, alpha: float = 0.01,
                    power: float = POWER) -> tuple:
    """How far above its detection limit a given change of candidate ``name`` is (module docstring).

    Parameters
    ----------
    design : ActuatorDesign
    model : sequence of str
        The final model's candidates.
    name : str
        An applicable candidate.
    signature : numpy.ndarray, shape (N,)
        The change's force signature on every sample of the record [N] (e.g. the
        residual of a record with the effect minus that of its twin without it).
    alpha, power : float, keyword-only
        As :func:`detection_limits`.

    Returns
    -------
    ratio : float
        sqrt(lambda_true / lambda*) against the final model without ``name``.
    ratio_named : float
        The same against that model plus the look-alike that hides the change best.
    """
    cols = design.columns
    if name not in cols:
        return 0.0, 0.0
    model = [n for n in model if n in cols]
    others = [n for n in model if n != name]
    d = design.whiten(signature)
    Zc = cols[name]
    k = Zc.shape[1]
    lam = needed_noncentrality(k, _critical(k, design.m, _level(len(cols), len(model),
                                                             name in model, alpha)), power)

    def lam_true(base):
        X = _stack(cols, base)
        R = _residualize(Zc, X)
        r = _residualize(d[:, None], X)[:, 0]
        fitted = R @ lstsq(R, r)
        return float(fitted @ fitted)

    lt = lam_true(others)
    named = [lam_true(others + [a]) for a in cols if a != name and a not in others]
    ln = min(named, default=lt)
    return math.sqrt(lt / lam), math.sqrt(ln / lam)


__all__ = ["detection_limits", "signature_ratio", "limit_ratio", "omitted", "POWER"]
