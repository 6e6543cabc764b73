"""All small models at once: the best subset of the library, inclusion probabilities, look-alikes.

Forward selection is greedy: on a record where two effects together mimic a
third (on a static sawtooth a free valve gain plus a pressure-sensor gain
reproduce a payload's torques), its first step can take a wrong turn that no
later step undoes.  :func:`search` therefore also fits **every subset** of the
library up to a few effects (from the per-chunk Gram matrices of
:mod:`.gram`, a k x k solve each), ranks them by BIC, and

* takes the best subset, among those with **no more fitted parameters than
  the forward path's model**, whose members are each admissible, significant
  given the others (LR test at alpha/K) and predictive (2-fold
  cross-validation).  The search is a guard against the greedy path's wrong
  turns, not a licence for bigger models: on long records the BIC penalty is
  small against any slight misspecification, and among hundreds of subsets
  some combination of many parameters always fits a little more (measured on
  the scenario battery: closed-loop records whose true payload lost to
  15-parameter combinations);
* gives every candidate its **inclusion probability**, the sum of the BIC
  weights ``exp(-BIC/2)`` of the admissible subsets that hold it, among the
  subsets within :data:`CHECK_BIC` of the chosen one and no more complex than
  it plus one effect (the posterior probability of "this effect is in the
  model" under equal prior weights of those subsets; Raftery 1995), and
* finds the **look-alikes** of each member: the best subset that replaces it
  by another candidate, with its BIC difference.  A member whose replacement
  is nearly as good (BIC within :data:`LOOKALIKE_BIC`) cannot be told from it
  on this record: the two are reported as confounded.  Opt-in candidates the
  user left out of the library (``shadows``: ``joint_torque_bias``) are tried
  as replacements too, never as members: a constant torque the model lacks
  poses as an encoder offset on many records, and a name the record cannot
  tell from a plausible cause outside the chosen library is not a name.

The dead time is held at the shift profiled for it (the search is linear).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from ..core.criteria import _chi2_sf
from .candidates import REGISTRY
from ...lstsq import many_chi2
from ..core.criteria import bic
from ..core.linear_selection import CHECK_BIC
from .selection import Problem, _gram_set, gram_cv, gram_fit, in_bounds

#: Largest subset size searched exhaustively.
MAX_SIZE = 4
#: A replacement whose BIC is within this of the best model's is a look-alike (an evidence
#: ratio below exp(6/2) = 20 against it: "positive" evidence at most, Kass & Raftery 1995).
LOOKALIKE_BIC = 6.0


@dataclass(frozen=True)
class _SubsetSearch:
    """The outcome of :func:`search`.

    An engine intermediate (the selection makes thousands per diagnosis), never handed to a
    user: what a user receives is the :class:`~ppamsafety.diagnose.core.result.Diagnosis`.
    So it is private and not a result object (no table, no figure of its own).

    Attributes
    ----------
    names : tuple of str
        The best admissible subset.
    bic : float
        Its BIC.
    inclusion : dict
        Candidate -> inclusion probability in [0, 1].
    lookalikes : dict
        Member -> list of (replacement, delta_bic) with delta_bic < :data:`LOOKALIKE_BIC`.
    evidence : dict
        Member -> {lr_stat, lr_df, p_value, delta_bic, cv_gain}: the member against the
        best subset without it.
    evaluated : int
        Subsets fitted.
    greedy_bic : float
        BIC of the forward path's model, for the notes.
    ranking : list of dict
        The 20 best subsets by BIC (``subset``, ``k``, ``chi2``, ``bic``, ``admissible``).
    """

    names: tuple
    bic: float
    inclusion: dict
    lookalikes: dict
    evidence: dict
    evaluated: int
    greedy_bic: float = math.nan
    ranking: list = field(default_factory=list)


def search(prob: Problem, universe, *, greedy, shift: int, alpha: float,
           max_size: int = MAX_SIZE, shadows=()) -> _SubsetSearch:
    """Fit every subset of ``universe`` up to ``max_size`` effects and pick the best (module
    docstring).

    Parameters
    ----------
    prob : Problem
        At the forward path's final model (noise levels and model-dependent columns there).
    universe : sequence of str
        The library searched.
    greedy : sequence of str
        The forward path's model (always among the subsets scored).
    shift : int, keyword-only
        Dead time [samples] held in subsets that contain the dead-time candidate.
    alpha : float, keyword-only
        Level of the LR test before the Bonferroni division.
    max_size : int, keyword-only
    shadows : sequence of str, keyword-only
        Candidates outside ``universe`` tried only as look-alikes (replacements of a
        member), never selected.

    Returns
    -------
    _SubsetSearch
    """
    universe = tuple(universe)
    shadows = tuple(n for n in shadows if n not in universe)
    wide = universe + shadows
    size = max(min(max_size, len(universe)), len(greedy))
    fits = {}

    def fit(names, univ=universe):
        key = (tuple(sorted(names, key=univ.index)), univ)
        if key not in fits:
            fits[key] = gram_fit(prob, key[0], universe=univ, shift=shift, cov=False)
        return fits[key]

    subsets = [()]
    for k in range(1, size + 1):
        subsets += list(itertools.combinations(universe, k))
    if tuple(sorted(greedy, key=universe.index)) not in subsets:
        subsets.append(tuple(sorted(greedy, key=universe.index)))
    bics, ks, chis = _bics(prob, universe, subsets, shift)
    order = sorted(subsets, key=lambda s: bics[s])
    best_bic = bics[order[0]]
    level = alpha / max(len(universe), 1)
    admissible = {}

    def ok(s, univ=universe):
        if (s, univ) in admissible:
            return admissible[s, univ]
        good = True
        if s:
            full = gram_fit(prob, s, universe=univ, shift=shift)
            cv_full = gram_cv(prob, s, universe=univ, shift=shift)
            for c in s:
                rest = tuple(n for n in s if n != c)
                fr = fit(rest, univ)
                d = max(fr.chi2 - full.chi2, 0.0)
                if not (in_bounds(prob, full, c) and _chi2_sf(d, max(full.k - fr.k, 1)) < level
                        and fr.bic > full.bic
                        and gram_cv(prob, rest, universe=univ, shift=shift) > cv_full):
                    good = False
                    break
        admissible[s, univ] = good
        return good

    g = tuple(sorted(greedy, key=universe.index))
    kmax = ks[g]
    small = [s for s in order if ks[s] <= kmax]
    best = ()
    for s in small:
        if ok(s):
            best = s
            break
    # BIC weights over the admissible subsets near the top (the rest weigh nothing)
    kbest = ks[best]
    near = [s for s in small if ks[s] <= max(kbest, 1) + _largest_k(universe)
            and bics[s] - bics[best] <= CHECK_BIC and ok(s)]
    if best not in near:
        near.insert(0, best)
    b = np.array([bics[s] for s in near])
    w = np.exp(-(b - b.min()) / 2.0)
    w /= w.sum()
    inclusion = {c: float(sum(wi for s, wi in zip(near, w) if c in s)) for c in universe}
    look = {}
    replaced = {c: tuple(sorted([n for n in best if n != c] + [a], key=wide.index))
                for c in best for a in shadows}
    shadow_bics = _bics(prob, wide, sorted(set(replaced.values())), shift)[0] if replaced \
        else {}
    for c in best:
        alts = []
        for a in universe:
            if a in best:
                continue
            s = tuple(sorted([n for n in best if n != c] + [a], key=universe.index))
            if s in bics and ok(s) and bics[s] - bics[best] < LOOKALIKE_BIC:
                alts.append((a, float(bics[s] - bics[best])))
        for a in shadows:
            s = tuple(sorted([n for n in best if n != c] + [a], key=wide.index))
            if shadow_bics[s] - bics[best] < LOOKALIKE_BIC and ok(s, wide):
                alts.append((a, float(shadow_bics[s] - bics[best])))
        look[c] = sorted(alts, key=lambda x: x[1])
    evidence = {}
    if best:
        full = fit(best)
        cv_full = gram_cv(prob, best, universe=universe, shift=shift)
        for c in best:
            rest = tuple(n for n in best if n != c)
            fr = fit(rest)
            d = max(fr.chi2 - full.chi2, 0.0)
            df = max(full.k - fr.k, 1)
            evidence[c] = {"lr_stat": d, "lr_df": df, "p_value": _chi2_sf(d, df),
                           "delta_bic": full.bic - fr.bic,
                           "cv_gain": gram_cv(prob, rest, universe=universe, shift=shift)
                           - cv_full}
    ranking = [{"subset": "+".join(s) or "nominal", "k": int(ks[s]), "chi2": chis[s],
                "bic": bics[s], "admissible": admissible.get((s, universe))} for s in order[:20]]
    return _SubsetSearch(names=best, bic=float(bics[best]), inclusion=inclusion, lookalikes=look,
                        evidence=evidence, evaluated=len(bics), greedy_bic=float(bics[g]),
                        ranking=ranking)


def _bics(prob, universe, subsets, shift):
    """BIC, number of parameters and chi2 of every subset from the Gram matrices (one compiled
    call per dead-time design)."""
    out, ks, chis = {}, {}, {}
    m = prob.bs.nb * prob.bs.y.shape[1]
    for grid in (False, True):
        group = [s for s in subsets if any(REGISTRY[n].grid for n in s) == grid]
        if not group:
            continue
        gs, _ = _gram_set(prob, tuple(universe), shift if grid else 0)
        A = gs.weighted(None, prob.sigma)[1]
        cols = [gs.columns([n for n in s if not REGISTRY[n].grid]).astype(np.int64)
                for s in group]
        ptr = np.concatenate([[0], np.cumsum([c.size for c in cols])]).astype(np.int64)
        chi2 = np.empty(len(group))
        many_chi2(A, np.concatenate(cols) if cols else np.zeros(0, np.int64), ptr, chi2)
        for s, c, x in zip(group, cols, chi2):
            ks[s] = c.size + (1 if grid else 0)
            chis[s] = float(x)
            out[s] = bic(float(x), ks[s], m)
    return out, ks, chis


def _largest_k(universe) -> int:
    return max(len(REGISTRY[n].parameters) for n in universe) if universe else 0


__all__ = ["search", "MAX_SIZE", "LOOKALIKE_BIC", "CHECK_BIC"]
