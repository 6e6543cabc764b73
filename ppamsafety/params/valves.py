"""Pressure-regulating servo valves (Kolvenbach KPS 3/4-00).

Sources: thesis §2.4.3, eq. (3.2) (first-order response), eq. (3.12) and
Table B.2 (static valve error p = v1 + v2 p_s).

Time constants are *not* tabulated in the thesis.  What it says:

* §3.5.2: T is measured as rise time / ln 9 for a 1 bar step into a closed
  volume (no value given);
* "Challenges" (Part II intro): pressures take "over 100 ms for large pressure
  steps" to settle;
* §4.2.5: the sliding-mode example uses first-order actuator dynamics with
  T = 0.06 s.

Our documented choice: T = 0.06 s for the valves feeding the four-muscle
groups 1 and 3 and T = 0.045 s (scaled by the number of muscles, i.e. by the
volume to fill) for the three-muscle groups 2 and 4.  A first-order response
with these constants settles to 5 % in 3T = 135-180 ms, consistent with "over
100 ms for large steps".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from .._validation import check_range
from ..units import BAR


@dataclass(frozen=True)
class Valve:
    """One valve: static error model (3.12) and first-order time constant.

    Attributes
    ----------
    v1 : float
        Static offset of the delivered pressure [Pa] (Table B.2 gives bar).
    v2 : float
        Static gain of the delivered pressure, dimensionless.
    time_constant : float
        First-order time constant T of (3.2) [s].  ``math.inf`` models a
        closed valve (the muscle is a sealed polytropic volume).
    """

    v1: float
    v2: float
    time_constant: float

    def __post_init__(self):
        check_range("Valve.v1", self.v1, -0.5 * BAR, 0.5 * BAR, unit="Pa")
        check_range("Valve.v2", self.v2, 0.5, 1.5)
        if self.time_constant != math.inf:
            check_range("Valve.time_constant", self.time_constant, 1e-4, 10.0, unit="s")


@dataclass(frozen=True)
class ValveSet:
    """The four valves, one per muscle group (index 0 = group 1)."""

    valves: tuple

    def __post_init__(self):
        if len(self.valves) != 4 or not all(isinstance(v, Valve) for v in self.valves):
            raise ValueError("ValveSet.valves must be a tuple of 4 Valve")
        object.__setattr__(self, "valves", tuple(self.valves))

    def replace(self, **changes) -> "ValveSet":
        """Return a copy with some fields changed (validated again)."""
        return replace(self, **changes)

    def with_time_constants(self, time_constants) -> "ValveSet":
        """Return a copy with new time constants [s] (one per valve)."""
        if len(time_constants) != 4:
            raise ValueError("with_time_constants needs 4 values [s]")
        return ValveSet(tuple(replace(v, time_constant=float(t))
                              for v, t in zip(self.valves, time_constants)))


#: Table B.2: v1 [bar] and v2 [-] per valve.
TABLE_B2 = ((0.0447, 0.9933), (0.0097, 0.9939), (0.0314, 0.9975), (0.0078, 0.9736))

#: Chosen time constants [s] (see module docstring).
DEFAULT_TIME_CONSTANTS = (0.06, 0.045, 0.06, 0.045)


def thesis_valves() -> ValveSet:
    """Valves with the static model of Table B.2 and our chosen time constants."""
    return ValveSet(tuple(Valve(v1=v1 * BAR, v2=v2, time_constant=t)
                          for (v1, v2), t in zip(TABLE_B2, DEFAULT_TIME_CONSTANTS)))


__all__ = ["Valve", "ValveSet", "thesis_valves", "TABLE_B2", "DEFAULT_TIME_CONSTANTS"]
