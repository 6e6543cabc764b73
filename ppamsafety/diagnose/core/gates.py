"""One rule for "high": the gates a named effect passes to be reported as certain.

A name reaches ``confidence_level = "high"`` only when every gate of its record kind passes;
otherwise it is ``"low"`` (a hint, not a finding).  Every kind judges its names here, with
one implementation of each gate; what differs between kinds is data, a :class:`HighRule`:

* which gates apply, in the order they are reported (the arm has ``not_compensating``, a
  muscle record ``reversals`` and ``pressure_levels``, a cylinder campaign a Wald
  ``significant``, a ``held_out`` gain, ``not_at_edge`` and ``mid_stroke``);
* the thresholds, each set on its kind's battery of tuning seeds and measured on seeds never
  used (``docs/diagnose.md``): the residual factor, the clear ratio, the consistency level,
  the stability threshold where the kind fixes one.

The inclusion probability every kind requires is one constant, :data:`HIGH_WEIGHT`.

==================  ==============================================================
gate                passes when (evidence key)
==================  ==============================================================
weight              ``weight`` >= :attr:`HighRule.weight`
stable              ``stability`` (None: not run) >= ``stability_threshold`` (the
                    record's, or :attr:`HighRule.stability` when the kind fixes it)
admissible          ``admissible`` (the kind judges its parameters' physical range)
moved               ``moved`` (some parameter's interval excludes its nominal value)
clear               ``clear`` (the effect over its detection limit) >=
                    :attr:`HighRule.clear_ratio`
residual_at_noise   nothing ``unexplained`` and every ``rho`` (residual/noise RMS
                    ratio) finite and <= :func:`rho_high` of ``m`` equations
consistent          ``consistency`` (p-value of a constancy test) >=
                    :attr:`HighRule.consistency_alpha`
significant         ``p_value`` < :attr:`HighRule.p_value`
held_out            ``cv_gain`` >= :attr:`HighRule.cv_gain`
not_confounded      not ``confounded``
(other)             the kind's own boolean under the gate's name (``reversals``,
                    ``not_compensating`` ...)
==================  ==============================================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .power import noise_rho_quantile

#: Inclusion probability (the BIC weight of the subsets of the library holding a name) at or
#: above which a name counts as decisive, for every record kind.
HIGH_WEIGHT = 0.95
#: Level of the constancy tests of a named effect's coefficients (across the arm's poses, the
#: halves of a muscle record): below it, the effect stands in for something else.
CONSTANCY_ALPHA = 1e-3


@dataclass(frozen=True)
class HighRule:
    """A record kind's gates and thresholds for "high".

    Attributes
    ----------
    gates : tuple of str
        The gates that apply, in the order they are reported.
    weight : float
        Smallest inclusion probability (``weight`` gate).
    rho_factor : float
        Largest residual/noise ratio, as a factor of the ratio noise alone exceeds with
        probability 1 - ``rho_quantile``.
    rho_quantile : float
    clear_ratio : float
        Smallest effect over its detection limit.
    consistency_alpha : float
        Level of the constancy test.
    stability : float or None
        Stability threshold when the kind fixes it (else the record's, given as evidence).
    p_value : float
        Largest Wald p-value (``significant`` gate).
    cv_gain : float
        Smallest held-out gain (``held_out`` gate).
    """

    gates: tuple
    weight: float = HIGH_WEIGHT
    rho_factor: float = math.inf
    rho_quantile: float = 0.999
    clear_ratio: float = 0.0
    consistency_alpha: float = 0.0
    stability: float | None = None
    p_value: float = 1.0
    cv_gain: float = -math.inf

    def rho_high(self, m: int) -> float:
        """The largest residual/noise RMS ratio on ``m`` equations for "high".

        Parameters
        ----------
        m : int
            Equations (blocks of a channel, samples of a record).
        """
        return self.rho_factor * noise_rho_quantile(max(int(m), 1), self.rho_quantile)


def _stable(rule, ev):
    s = ev.get("stability")
    thr = rule.stability if rule.stability is not None else ev["stability_threshold"]
    return bool(s is not None and s >= thr)


def _at_noise(rule, ev):
    rho = np.asarray(ev["rho"], dtype=float)
    return bool(not ev["unexplained"]
                and np.all(np.isfinite(rho) & (rho <= rule.rho_high(ev["m"]))))


#: Gate -> test of (rule, evidence); a gate not here reads the kind's boolean of its name.
TESTS = {
    "weight": lambda r, ev: bool(ev["weight"] >= r.weight),
    "stable": _stable,
    "admissible": lambda r, ev: bool(ev["admissible"]),
    "moved": lambda r, ev: bool(ev["moved"]),
    "clear": lambda r, ev: bool(ev.get("clear", math.inf) >= r.clear_ratio),
    "residual_at_noise": _at_noise,
    "consistent": lambda r, ev: bool(ev.get("consistency", 1.0) >= r.consistency_alpha),
    "significant": lambda r, ev: bool(ev["p_value"] < r.p_value),
    "held_out": lambda r, ev: bool(ev["cv_gain"] >= r.cv_gain),
    "not_confounded": lambda r, ev: not ev.get("confounded", False),
}


def judge(rule: HighRule, **evidence) -> dict:
    """Every gate of ``rule`` for one named effect.

    Parameters
    ----------
    rule : HighRule
        The record kind's gates and thresholds.
    **evidence
        What the gates read (module docstring).

    Returns
    -------
    dict
        Gate -> bool, in the order of ``rule.gates``.
    """
    missing = [g for g in rule.gates if g not in TESTS and g not in evidence]
    if missing:
        raise TypeError(f"judge(): no evidence for the gate(s) {missing}; the rule's gates "
                        f"are {list(rule.gates)}")
    return {g: TESTS[g](rule, evidence) if g in TESTS else bool(evidence[g])
            for g in rule.gates}


def level(g: dict) -> str:
    """``"high"`` when every gate passes, else ``"low"``.

    Parameters
    ----------
    g : dict
        :func:`judge`.
    """
    return "high" if all(g.values()) else "low"


__all__ = ["HIGH_WEIGHT", "CONSTANCY_ALPHA", "HighRule", "TESTS", "judge", "level"]
