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

from .._validation import (InvalidTypeError, check_instance, check_range, check_real,
                           check_vector)
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
        First-order time constant T of (3.2) [s], in [1 ms, 10 s]
        (:data:`MIN_TIME_CONSTANT`).  ``math.inf`` models a closed valve (the
        muscle is a sealed polytropic volume).

    Ranges: ``v1`` in [-0.5, 0.5] bar, ``v2`` in [0.5, 1.5] (Table B.2 values
    are within 0.05 bar and 3 % of ideal).
    """

    v1: float
    v2: float
    time_constant: float

    def __post_init__(self):
        object.__setattr__(self, "v1", check_range("Valve.v1", self.v1, -0.5 * BAR, 0.5 * BAR,
                                                   unit="Pa"))
        object.__setattr__(self, "v2", check_range("Valve.v2", self.v2, 0.5, 1.5))
        object.__setattr__(self, "time_constant",
                           check_time_constant("Valve.time_constant", self.time_constant))


#: Smallest valve time constant [s].  The closed loop integrates the valve lag (3.2)
#: with classical RK4 at h = 1 ms / ``substeps`` (1 kHz control loop); RK4 is stable
#: for h/T < 2.78, so T >= 1 ms keeps every supported step stable with margin and the
#: response resolved by at least one step per time constant.  Real pressure valves are
#: much slower (tens of ms, module docstring).
MIN_TIME_CONSTANT = 1.0e-3
#: Largest finite time constant [s]; ``math.inf`` (a closed valve) is also allowed.
MAX_TIME_CONSTANT = 10.0


def check_time_constant(name: str, value) -> float:
    """A valve time constant in [1 ms, 10 s] or ``math.inf`` (closed valve); returns a float.

    Parameters
    ----------
    name : str
        Argument name for the error messages.
    value : float
        Time constant [s].

    Raises
    ------
    TypeError, ValueError
        If ``value`` is not a real number or is outside the range.
    """
    t = check_real(name, value, unit="s")
    if t == math.inf:
        return t
    return check_range(name, t, MIN_TIME_CONSTANT, MAX_TIME_CONSTANT, unit="s")


@dataclass(frozen=True)
class ValveSet:
    """The four valves, one per muscle group (index 0 = group 1).

    Attributes
    ----------
    valves : tuple of 4 Valve
        Valve of groups 1..4 (static error (3.12) and time constant (3.2)).
    """

    valves: tuple

    def __post_init__(self):
        if not isinstance(self.valves, (tuple, list)):
            raise InvalidTypeError(f"ValveSet.valves must be a tuple of 4 Valve, "
                                   f"got {type(self.valves).__name__}")
        if len(self.valves) != 4:
            raise ValueError(f"ValveSet.valves must have 4 Valve, got {len(self.valves)}")
        for i, v in enumerate(self.valves):
            check_instance(f"ValveSet.valves[{i}]", v, Valve)
        object.__setattr__(self, "valves", tuple(self.valves))

    def replace(self, **changes) -> "ValveSet":
        """Return a copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            New values of fields of :class:`ValveSet`, by field name (as for
            :func:`dataclasses.replace`); the copy is checked like a newly
            constructed object.
        """
        return replace(self, **changes)

    def with_time_constants(self, time_constants) -> "ValveSet":
        """Return a copy with new time constants [s] (one per valve, see :class:`Valve`).

        Parameters
        ----------
        time_constants : sequence of 4 float
            Time constants T_i of (3.2) [s], each in [1 ms, 10 s] or ``math.inf``
            (closed valve).
        """
        if isinstance(time_constants, (tuple, list)) and len(time_constants) == 4:
            ts = [check_time_constant(f"valve {i + 1} time_constant", t)
                  for i, t in enumerate(time_constants)]
        else:   # refuse with the standard message (type or length)
            ts = check_vector("time_constants", time_constants, 4, unit="s")
        return ValveSet(tuple(replace(v, time_constant=t) for v, t in zip(self.valves, ts)))


#: Table B.2: v1 [bar] and v2 [-] per valve.
TABLE_B2 = ((0.0447, 0.9933), (0.0097, 0.9939), (0.0314, 0.9975), (0.0078, 0.9736))

#: Chosen time constants [s] (see module docstring).
DEFAULT_TIME_CONSTANTS = (0.06, 0.045, 0.06, 0.045)


def thesis_valves() -> ValveSet:
    """Valves with the static model of Table B.2 and our chosen time constants."""
    return ValveSet(tuple(Valve(v1=v1 * BAR, v2=v2, time_constant=t)
                          for (v1, v2), t in zip(TABLE_B2, DEFAULT_TIME_CONSTANTS)))


__all__ = ["Valve", "ValveSet", "thesis_valves", "TABLE_B2", "DEFAULT_TIME_CONSTANTS",
           "MIN_TIME_CONSTANT", "MAX_TIME_CONSTANT", "check_time_constant"]
