"""Model-selection criteria and the naming rule of one step, shared by every record kind.

The statistics behind them (known noise level, BIC rather than AICc, the
likelihood-ratio test with a Bonferroni division, cross-validation) are
explained in :mod:`ppamsafety.diagnose.arm.selection`; the tester's linear
selection (:mod:`.linear_selection`) applies the same rule.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy import special, stats

#: Significance level of the likelihood-ratio test (before the Bonferroni division).
ALPHA = 0.01
#: Largest residual-to-noise RMS ratio of a channel that counts as "explained".
RHO_MAX = 1.5
#: Number of time segments alternated between the two cross-validation folds.
CV_SEGMENTS = 8


@functools.lru_cache(maxsize=8)
def _normal_quantile(p: float) -> float:
    """``scipy.stats.norm.ppf(p)``, remembered (the parameter tables ask for the same level)."""
    return float(stats.norm.ppf(p))


def _chi2_sf(x: float, df: int) -> float:
    """Upper tail of the chi2 distribution, P(X > x) with ``df`` degrees of freedom.

    The value of ``scipy.stats.chi2.sf(x, df)`` (both call the same special function,
    ``scipy.special.chdtrc``) without the distribution object's argument handling: 2 us
    per call instead of 130 us, and the selection evaluates it for every candidate of
    every step of every bootstrap replicate.  ``x`` >= 0 and ``df`` >= 1 (the callers'
    likelihood-ratio statistics).
    """
    return float(special.chdtrc(df, x))


def bic(chi2: float, k: int, m: int) -> float:
    """Bayesian information criterion with a known noise level: chi2 + k ln m.

    Parameters
    ----------
    chi2 : float
        Sum of squared whitened residuals.
    k : int
        Number of fitted parameters.
    m : int
        Number of equations (> 0).

    Returns
    -------
    float
    """
    return chi2 + k * math.log(m)


def aicc(chi2: float, k: int, m: int) -> float:
    """Small-sample corrected AIC with a known noise level: chi2 + 2k + 2k(k+1)/(m-k-1).

    Parameters
    ----------
    chi2 : float
        Sum of squared whitened residuals.
    k : int
        Number of fitted parameters.
    m : int
        Number of equations.

    Returns
    -------
    float
        ``inf`` when m <= k + 1.
    """
    return chi2 + 2 * k + (2 * k * (k + 1) / (m - k - 1) if m - k - 1 > 0 else math.inf)


@dataclass(frozen=True, eq=False)
class Step:
    """One forward-selection step: the ranking of every candidate tried.

    Attributes
    ----------
    current : tuple of str
        Effects already in the model.
    table : list of dict
        Per candidate: name, k, chi2, bic, aicc, delta_bic, lr_stat, lr_df,
        p_value, cv_chi2, cv_gain, bic_weight, eligible.
    chosen : str or None
    current_bic, current_cv : float
        BIC and held-out chi2 of the current model.
    current_weight : float
        BIC weight of keeping the current model.
    confounded : tuple of str
        Candidates the record cannot tell from ``chosen`` (each explains the
        same part of the residual: neither adds significantly to the other);
        empty when the choice is clear.
    """

    current: tuple
    table: list
    chosen: str | None
    current_bic: float
    current_cv: float
    current_weight: float
    confounded: tuple = ()


def rank_step(rows: list, current_bic: float, *, alpha: float, n_candidates: int,
              extra_rule=None):
    """The naming rule of one forward-selection step, shared by arm and tester records.

    A candidate is *eligible* when (a) its BIC is below the current model's,
    (b) the likelihood-ratio test gives p < ``alpha / n_candidates``
    (Bonferroni), (c) the cross-validation gain is positive, (d) its parameters
    are admissible (``row["in_bounds"]``) and ``extra_rule(row)`` holds when
    given.  BIC weights are computed among the admissible models (the current
    one and every candidate whose parameters are physically possible); the
    rows are sorted by BIC and the best eligible one is chosen, with its
    evidence ratio (log10) against the runner-up.

    Parameters
    ----------
    rows : list of dict
        One row per candidate with ``name``, ``bic``, ``delta_bic``,
        ``p_value``, ``cv_gain`` and ``in_bounds``; completed in place with
        ``eligible``, ``bic_weight`` and, for the chosen one,
        ``evidence_ratio_log10``, and sorted by BIC.
    current_bic : float
        BIC of the current model.
    alpha : float, keyword-only
        Level of the likelihood-ratio test before the Bonferroni division.
    n_candidates : int, keyword-only
        Number of candidates compared in this step (Bonferroni divisor).
    extra_rule : callable, optional, keyword-only
        ``row -> bool``, a further eligibility rule (the tester's effect size).

    Returns
    -------
    chosen : str or None
        The named candidate, or None when none is eligible.
    current_weight : float
        BIC weight of the current model.
    """
    for r in rows:
        r["eligible"] = bool(r["delta_bic"] < 0 and r["p_value"] < alpha / n_candidates
                             and r["cv_gain"] > 0 and r["in_bounds"]
                             and (extra_rule is None or extra_rule(r)))
    adm = [r for r in rows if r["in_bounds"]]
    bics = np.array([current_bic] + [r["bic"] for r in adm])
    w = np.exp(-(bics - bics.min()) / 2)
    w /= w.sum()
    for r in rows:
        r["bic_weight"] = 0.0
    for r, wi in zip(adm, w[1:]):
        r["bic_weight"] = float(wi)
    rows.sort(key=lambda r: r["bic"])
    ok = [r for r in rows if r["eligible"]]
    chosen = ok[0]["name"] if ok else None
    if chosen is not None:
        others = [r["bic"] for r in adm if r["name"] != chosen] + [current_bic]
        ok[0]["evidence_ratio_log10"] = float((min(others) - ok[0]["bic"]) / 2 / math.log(10))
    return chosen, float(w[0])


def false_selection_bound(q: float, threshold: float, p: int):
    """Bound on the expected number of false selections among the stable names.

    ``q^2 / ((2 pi - 1) p)`` (Meinshausen & Buehlmann 2010, Theorem 1; Shah & Samworth 2013
    for complementary pairs, under the same exchangeability assumption).

    Parameters
    ----------
    q : float
        Mean number of candidates selected per half of the record.
    threshold : float
        pi: the selection frequency at which a name counts as stable.
    p : int
        Number of candidates.

    Returns
    -------
    float or None
        None when ``threshold <= 0.5`` (no bound) or ``p < 1``.
    """
    if threshold <= 0.5 or p < 1:
        return None
    return q * q / ((2 * threshold - 1) * p)


__all__ = ["ALPHA", "RHO_MAX", "CV_SEGMENTS", "bic", "aicc", "Step", "rank_step",
           "false_selection_bound"]
