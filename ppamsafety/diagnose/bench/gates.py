"""The gates before "high" confidence on a muscle record.

A named effect reaches ``confidence_level = "high"`` only through every gate
below; otherwise it is ``"low"`` (a hint, not a finding).  They are judged by the one rule
of every record kind (:mod:`ppamsafety.diagnose.core.gates`): the arm's gates where they
apply, plus two that say what a muscle record must contain; this module holds the muscle
record's thresholds (:data:`MUSCLE_RULE`) and the evidence only a muscle record gives.
The thresholds were set on the randomized battery of muscle records (:mod:`.scenarios`,
seeds 0-299) and the claim -- of all effects named "high", at least 97 % are right -- is
measured on unseen seeds (``docs/diagnose.md``).

===================  ===========================================================
gate                 passes when
===================  ===========================================================
weight               its inclusion probability (the BIC weights of the admissible
                     subsets of the library that hold it, :mod:`.selection`) is
                     >= :data:`~ppamsafety.diagnose.core.gates.HIGH_WEIGHT`
stable               the naming rule picked it in >= ``THRESHOLD`` of the halves
                     of the record's loops (:mod:`.stability`)
admissible           every parameter it moved has its 95 % interval inside the
                     physical range and no other lies significantly outside it
                     (friction and delta >= 0, delta <= 1, a gain > -1, a
                     refitted force function > 0 at the contraction quantiles)
moved                some parameter's interval excludes its nominal value (the
                     refit: the force function at a quantile node)
clear                the fitted effect stands >= ``MUSCLE_RULE.clear_ratio`` (2) x its
                     detection limit (:func:`~.detection.limit_ratio`: sqrt of its
                     likelihood-ratio statistic over the noncentrality the naming rule
                     needs, the arm's ``clear`` gate): close to the limit a small error
                     the library does not hold can pose as the effect
residual_at_noise    the final residual/noise RMS ratio is <= ``MUSCLE_RULE.rho_factor`` (1.15) x
                     the 99.9 % point of the ratio under noise alone and nothing
                     is unexplained
consistent           its coefficients are the same in the first and the second half
                     of the record (:mod:`.consistency`: a drifting load-cell zero
                     taken for a refitted law fits different values early and late)
reversals            the candidates that need it (``MuscleCandidate.needs``: friction and
                     hysteresis, which show at reversals): at least
                     :data:`MIN_REVERSALS_HIGH` reversals of the motion (fewer
                     cannot tell them from a slow drift)
pressure_levels      the candidates that need it (the refitted law and the sensor
                     offsets): several pressure
                     levels (at one level a constant force, a force -o f(eps) and
                     a refitted law p f(eps) are nearly one column)
not_confounded       no other candidate explains the same part of the residual
                     (:mod:`.confounded`; confounded groups are never named)
===================  ===========================================================
"""

from __future__ import annotations

import math

from ..core.gates import CONSTANCY_ALPHA, HighRule, judge, level
from .candidates import MUSCLE_LIBRARY

#: Fewest reversals of the motion for a history effect to be "high": two full loops.
MIN_REVERSALS_HIGH = 4
#: Effects that show at the reversals of the motion (the candidates that need ``reversals``).
HISTORY_EFFECTS = MUSCLE_LIBRARY.needing("reversals")
#: Effects that need several pressure levels to be told from one another (the candidates that
#: need ``pressure_levels``).
PRESSURE_EFFECTS = MUSCLE_LIBRARY.needing("pressure_levels")
#: The muscle record's rule for "high": its gates in the order they are reported; the largest
#: final residual/noise RMS ratio as a factor of the 99.9 % point of the ratio under noise
#: alone, 1.15 (x 1.02-1.06: the estimated noise level is good to a few per cent, a model
#: error of half the noise is not); the smallest fitted effect over its detection limit of a
#: "high" name, 2.  The arm uses 5
#: (:mod:`ppamsafety.diagnose.arm.gates`); on the muscle battery's tuning seeds 0-199 every
#: name that passed the other gates was right at every ratio from 1 to 5 (67 names at 1, 65
#: at 2, 51 at 5) and the two wrong names (at any level) stood 6.6 and 9.6 x their limits,
#: stopped by other gates: 2 keeps the gate's purpose (no "high" at the edge of visibility)
#: without dropping right names for nothing.
MUSCLE_RULE = HighRule(gates=("weight", "stable", "admissible", "moved", "clear",
                              "residual_at_noise", "consistent", "reversals", "pressure_levels",
                              "not_confounded"),
                       rho_factor=1.15, rho_quantile=0.999, clear_ratio=2.0,
                       consistency_alpha=CONSTANCY_ALPHA)


def gates(name: str, extension, phi, cov, *, weight: float, stability: float | None,
          stability_threshold: float, rho: float, m: int, unexplained: bool, turns: int,
          one_level: bool, consistency: float = 1.0, confounded: bool = False,
          clear: float = math.inf) -> dict:
    """Every gate of the module docstring for one named effect.

    Parameters
    ----------
    name : str
        Candidate name.
    extension : Extension
        Its extension on the record.
    phi, cov : numpy.ndarray
        Its coefficients and their covariance in the final model.
    weight : float, keyword-only
        Its inclusion probability.
    stability : float or None, keyword-only
        Selection frequency over the halves (None: not run; the gate fails).
    stability_threshold : float, keyword-only
    rho : float, keyword-only
        Final residual/noise RMS ratio.
    m : int, keyword-only
        Equations.
    unexplained : bool, keyword-only
    turns : int, keyword-only
        Reversals of the motion.
    one_level : bool, keyword-only
        The pressure takes essentially one level.
    consistency : float, keyword-only
        p-value of the constancy test (:func:`~.consistency.time_consistency`).
    confounded : bool, keyword-only
    clear : float, keyword-only
        The effect over its detection limit (:func:`~.detection.limit_ratio`; inf when
        the limits were not computed).

    Returns
    -------
    dict
        Gate -> bool, in the order of ``MUSCLE_RULE.gates``.
    """
    needs = MUSCLE_LIBRARY[name].needs
    return judge(MUSCLE_RULE, weight=weight, stability=stability,
                 stability_threshold=stability_threshold,
                 admissible=extension.physically_admissible(phi, cov),
                 moved=extension.moved(phi, cov), clear=clear, rho=rho, m=m,
                 unexplained=unexplained, consistency=consistency,
                 reversals="reversals" not in needs or turns >= MIN_REVERSALS_HIGH,
                 pressure_levels="pressure_levels" not in needs or not one_level,
                 confounded=confounded)


__all__ = ["MUSCLE_RULE", "MIN_REVERSALS_HIGH", "HISTORY_EFFECTS", "PRESSURE_EFFECTS",
           "gates", "level"]
