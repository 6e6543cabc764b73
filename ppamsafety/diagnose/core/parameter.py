"""One parameter of a candidate effect: name, SI unit, plausible and physical bounds, meaning.

Shared by the arm library (:mod:`ppamsafety.diagnose.arm.candidates`) and the
test-bench library (:mod:`ppamsafety.diagnose.bench.candidates`).
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


__all__ = ["Parameter"]
