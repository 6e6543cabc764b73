"""One parameter of a candidate effect: name, SI unit, plausible and physical bounds, meaning.

Shared by the arm library (:mod:`ppamsafety.diagnose.arm.candidates`) and the
test-bench library (:mod:`ppamsafety.diagnose.bench.candidates`), and the physical-range
check of a fitted parameter table (:func:`physically_admissible`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Parameter:
    """One parameter of a candidate.

    Attributes
    ----------
    name : str
        Name in ``diagnosis.json``.
    unit : str
        SI unit.
    lo, hi : float
        Plausible bounds (used by the naming rules of
        :mod:`ppamsafety.diagnose.arm.selection` and :mod:`.linear_selection`).
    doc : str
        Meaning, with the thesis reference.
    phys_lo, phys_hi : float
        Physical range: values outside it are impossible (a negative mass, a
        polytropic exponent above the isentropic 1.4, a negative friction).  A fit
        outside it is a symptom of something else, not an effect (the admissibility gate
        of :mod:`ppamsafety.diagnose.arm.gates`); reported intervals are intersected with
        it.  Default: unbounded.
    """

    name: str
    unit: str
    lo: float
    hi: float
    doc: str = ""
    phys_lo: float = -math.inf
    phys_hi: float = math.inf

    def __post_init__(self):
        if not (self.phys_lo <= self.lo < self.hi <= self.phys_hi):
            raise ValueError(f"parameter {self.name!r}: need phys_lo <= lo < hi <= phys_hi, "
                             f"got {self.phys_lo}, {self.lo}, {self.hi}, {self.phys_hi}")


def physically_admissible(parameters, table: dict, moved) -> bool:
    """The raw 95 % interval of every moved parameter inside its physical range, and no other
    parameter's interval entirely outside it.

    A fit outside the physical range (a negative friction, a hysteresis loop that gives
    energy back) is a symptom of something else, not an effect.  A parameter that did not
    move (its interval holds the nominal value) only has to reach into the range: a viscous
    friction of -0.002 +- 0.01 is a zero.

    Parameters
    ----------
    parameters : iterable of Parameter
    table : dict
        Parameter name -> :class:`~ppamsafety.diagnose.core.result.Estimate` (its raw
        interval when the reported one was cut at the range).
    moved : collection of str
        Names of the parameters whose interval excludes the nominal value.

    Returns
    -------
    bool
    """
    moved = set(moved)
    for p in parameters:
        lo, hi = table[p.name].raw_interval
        if p.name in moved:
            if not (p.phys_lo <= lo and hi <= p.phys_hi):
                return False
        elif hi < p.phys_lo or lo > p.phys_hi:
            return False
    return True


__all__ = ["Parameter", "physically_admissible"]
