"""What the naming rule's statistics do under noise alone and under an effect: power and null quantiles.

Shared by the detection limits and the gates of every record kind:

* :func:`needed_noncentrality`: the likelihood-ratio statistic of adding an
  effect with k coefficients is noncentral chi2 with k degrees of freedom and
  noncentrality ``lambda = phi^T S phi`` (S the part of its whitened columns
  that the rest of the model cannot reproduce); the effect is named when the
  statistic exceeds a critical value, so the smallest lambda named with a
  given probability (the *power*) fixes the detection limit;
* :func:`noise_rho_quantile`: the residual-to-noise RMS ratio that noise alone
  exceeds with a small probability on m independent equations,
  ``sqrt(chi2_m^-1(q) / m)`` (1.06 for 1200 equations at q = 0.999, 1.02 for
  10^4): a "residual at the noise" gate is a small factor times it.
"""

from __future__ import annotations

import math

from scipy import optimize, stats

from ..._validation import check_int, check_range

#: Probability with which an effect at its detection limit is named.
POWER = 0.9


def needed_noncentrality(df: int, crit: float, power: float = POWER) -> float:
    """Smallest lambda with P(noncentral chi2_df(lambda) > crit) >= power.

    Parameters
    ----------
    df : int
        Degrees of freedom (>= 1).
    crit : float
        Critical value of the statistic (>= 0).
    power : float
        Probability in (0, 1).

    Returns
    -------
    float
    """
    df = check_int("df", df, 1)
    crit = check_range("crit", crit, 0.0, math.inf)
    power = check_range("power", power, 0.0, 1.0, lo_open=True, hi_open=True)

    def f(lam):
        return stats.ncx2.sf(crit, df, lam) - power
    if f(1e-9) >= 0:
        return 1e-9
    hi = max(1.0, crit)
    while f(hi) < 0:
        hi *= 2.0
    return float(optimize.brentq(f, 1e-9, hi, xtol=1e-6))


def noise_rho_quantile(m: int, q: float = 0.999) -> float:
    """The residual/noise RMS ratio that noise alone exceeds with probability 1 - q on m
    independent equations: sqrt(chi2_m^-1(q) / m).

    Parameters
    ----------
    m : int
        Equations (>= 1).
    q : float
        Quantile in (0, 1).
    """
    m = check_int("m", m, 1)
    q = check_range("q", q, 0.0, 1.0, lo_open=True, hi_open=True)
    return math.sqrt(float(stats.chi2.ppf(q, m)) / m)


__all__ = ["needed_noncentrality", "noise_rho_quantile", "POWER"]
