"""The gates before "high" confidence on an arm record: its rule, :data:`ARM_RULE`.

A name reaches ``confidence_level = "high"`` only through every gate below; otherwise it is
``"low"`` (a hint, not a finding).  The gates are judged by the one rule of every record
kind (:mod:`ppamsafety.diagnose.core.gates`); this module holds the arm's thresholds and the
evidence only an arm gives (moved and admissible parameters).  The gates and their
thresholds were set on the randomized scenario battery
(:mod:`ppamsafety.diagnose.scenarios`, ``ARM_BATTERY.tuning``) and the claim they make -- of
all effects named "high", at least 97 % are right -- is measured on unseen seeds
(``ARM_BATTERY.measure``; ``docs/diagnose.md``, the report section ``diagnose_trust``).

==================  ==============================================================
gate                passes when
==================  ==============================================================
weight              its inclusion probability (the BIC weights of the subsets of
                    the library that hold it, :mod:`.subsets`) is >=
                    :data:`~..core.gates.HIGH_WEIGHT`: decisive against every other small model
stable              the complementary-pairs stability selection picked it in >=
                    ``Stability.threshold`` of the halves of the record (the
                    name does not hinge on a part of the record)
admissible          every parameter the effect moved (interval excluding the
                    nominal value) has its raw 95 % interval inside the physical
                    range, and no other parameter lies significantly outside it
                    (a negative mass, a friction < 0, n > 1.4 are symptoms of
                    something else; a viscous friction of -0.002 +- 0.01 is a zero)
moved               some parameter's interval excludes its nominal value (the
                    dead time: a delay of at least one sample)
clear               some parameter moved by >= ``ARM_RULE.clear_ratio`` (5) x its detection
                    limit on the record (:mod:`.detection`): close to the limit a
                    small error the library does not hold can pose as the effect
residual_at_noise   every block channel's final residual/noise RMS ratio is
                    <= ``ARM_RULE.rho_factor`` (1.2) x the 99.9 % point of the ratio under
                    the noise alone (sqrt(chi2_m(0.999) / m) for m blocks: 1.06
                    for 1200 blocks, 1.49 for the 21 rest points of a sawtooth),
                    and nothing is unexplained (an unexplained error elsewhere
                    may leak into this subsystem)
consistent          the effect's parameters are the same in the low and the high
                    third of each joint's range (a Chow test at
                    ``core.gates.CONSTANCY_ALPHA``): an effect standing in for
                    something else (an encoder gain taken for an offset, a heavier
                    link for a payload) fits different values in different poses;
                    and so are those of every other named effect sharing a
                    subsystem with it (one inconsistent effect means the model of
                    that subsystem is wrong, and its partners absorb the rest)
not_compensating    it does not cancel another named effect in some channel
                    (``selection.compensating``): a sensor offset whose pressure
                    signature a valve offset cancels is a torque error the library
                    does not hold
not_confounded      no other candidate explains the same part of the residual
                    (confounded groups are never named at all)
==================
"""

from __future__ import annotations

import math

from ..core.gates import CONSTANCY_ALPHA, HighRule, judge, level
from ..core.parameter import physically_admissible as core_admissible
from .candidates import REGISTRY

#: The arm's rule for "high": its gates in the order they are reported; the largest final
#: residual/noise RMS ratio of every block channel as a factor of the 99.9 % point under
#: noise alone (under a correct model the ratio is 1 within a few per cent; 1.2 leaves room
#: for a noise estimate that is somewhat off, not for a model error of half the noise); the
#: smallest magnitude over the detection limit of a "high" name, 5.
ARM_RULE = HighRule(gates=("weight", "stable", "admissible", "moved", "clear",
                           "residual_at_noise", "consistent", "not_compensating",
                           "not_confounded"),
                    rho_factor=1.2, rho_quantile=0.999, clear_ratio=5.0,
                    consistency_alpha=CONSTANCY_ALPHA)


def moved_parameters(name: str, table: dict) -> tuple:
    """Parameters of effect ``name`` whose 95 % interval excludes the nominal value.

    Parameters
    ----------
    name : str
        Candidate name.
    table : dict
        Its parameter table ({parameter: :class:`~ppamsafety.diagnose.core.result.Estimate`}).
    """
    if REGISTRY[name].grid:
        return tuple(p for p, d in table.items() if d.ci_low > 0.0)
    return tuple(p for p, d in table.items() if d.moved)


def physically_admissible(name: str, table: dict) -> bool:
    """The raw interval of every moved parameter inside its physical range; every other
    parameter's interval reaching into it.

    Parameters
    ----------
    name : str
        Candidate name.
    table : dict
        Its parameter table ({parameter: :class:`~ppamsafety.diagnose.core.result.Estimate`},
        with the raw intervals when the reported ones were cut at the physical range).
    """
    return core_admissible(REGISTRY[name].parameters, table, moved_parameters(name, table))


def gates(name: str, table: dict, *, weight: float, stability: float | None,
          stability_threshold: float, rho, unexplained: bool, confounded: bool,
          consistency: float = 1.0, blocks: int = 10 ** 6, clear: float = math.inf,
          compensating: bool = False) -> dict:
    """Every gate of the module docstring for one named effect.

    Parameters
    ----------
    name : str
        Candidate name.
    table : dict
        Its parameter table.
    weight : float, keyword-only
        Inclusion probability of the effect.
    stability : float or None, keyword-only
        Its stability-selection frequency (None: not run, the gate fails).
    stability_threshold : float, keyword-only
    rho : array_like, keyword-only
        Final residual/noise RMS ratio of every block channel.
    unexplained : bool, keyword-only
    confounded : bool, keyword-only
    consistency : float, keyword-only
        Smallest p-value of the region-constancy test
        (:func:`~.selection.region_consistency`).
    blocks : int, keyword-only
        Blocks per channel (``ARM_RULE.rho_high``).
    clear : float, keyword-only
        Largest change of a parameter over its detection limit.
    compensating : bool, keyword-only
        It cancels another named effect in some channel.

    Returns
    -------
    dict
        Gate -> bool, in the order of ``ARM_RULE.gates``.
    """
    return judge(ARM_RULE, weight=weight, stability=stability,
                 stability_threshold=stability_threshold,
                 admissible=physically_admissible(name, table),
                 moved=bool(moved_parameters(name, table)), clear=clear, rho=rho, m=blocks,
                 unexplained=unexplained, consistency=consistency,
                 not_compensating=not compensating, confounded=confounded)


__all__ = ["ARM_RULE", "gates", "level",
           "moved_parameters", "physically_admissible"]
