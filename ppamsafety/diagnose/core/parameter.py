"""One parameter of a candidate effect: name, SI unit, plausible bounds, meaning.

Shared by the arm library (:mod:`ppamsafety.diagnose.arm.candidates`) and the
test-bench library (:mod:`ppamsafety.diagnose.bench.candidates`).
"""

from __future__ import annotations

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
    """

    name: str
    unit: str
    lo: float
    hi: float
    doc: str = ""


__all__ = ["Parameter"]
