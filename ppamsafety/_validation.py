"""Small helpers that turn bad input into clear ``ValueError`` messages.

Every parameter object and public function validates its input with these
helpers instead of ``assert``, so that a wrong value names the offending field
and the allowed range and never propagates as a silent NaN.
"""

from __future__ import annotations

import math
from typing import Iterable

import numpy as np


def check_finite(name: str, value) -> float:
    """Return ``value`` as float; raise ``ValueError`` if it is not finite."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v}")
    return v


def check_range(name: str, value, lo: float = -math.inf, hi: float = math.inf,
                *, lo_open: bool = False, hi_open: bool = False, unit: str = "") -> float:
    """Check ``lo <= value <= hi`` (open ends with ``lo_open``/``hi_open``).

    Returns the value as float.  The error message names the field, the value
    and the allowed interval, e.g. ``"valve 2 time_constant = -0.1 s is outside
    (0, inf) s"``.
    """
    v = check_finite(name, value)
    below = v <= lo if lo_open else v < lo
    above = v >= hi if hi_open else v > hi
    if below or above:
        lb = "(" if lo_open else "["
        rb = ")" if hi_open else "]"
        u = f" {unit}" if unit else ""
        raise ValueError(f"{name} = {v:g}{u} is outside {lb}{lo:g}, {hi:g}{rb}{u}")
    return v


def check_positive(name: str, value, *, unit: str = "") -> float:
    """Check ``value > 0``."""
    return check_range(name, value, 0.0, math.inf, lo_open=True, unit=unit)


def check_nonnegative(name: str, value, *, unit: str = "") -> float:
    """Check ``value >= 0``."""
    return check_range(name, value, 0.0, math.inf, unit=unit)


def check_int(name: str, value, lo: int, hi: int) -> int:
    """Check that ``value`` is an integer in ``[lo, hi]``."""
    if isinstance(value, bool) or int(value) != value:
        raise ValueError(f"{name} must be an integer, got {value!r}")
    v = int(value)
    if not lo <= v <= hi:
        raise ValueError(f"{name} = {v} is outside [{lo}, {hi}]")
    return v


def as_float_array(name: str, value, *, shape_tail: tuple[int, ...] | None = None,
                   allow_nonfinite: bool = False) -> np.ndarray:
    """Convert to a float64 array and check the trailing shape and finiteness.

    Parameters
    ----------
    name : str
        Name used in error messages.
    value : array_like
        Input.
    shape_tail : tuple of int, optional
        Required trailing dimensions, e.g. ``(2,)`` for joint vectors.
    allow_nonfinite : bool
        If False (default), NaN or inf raise ``ValueError``.
    """
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be numeric, got {type(value).__name__}") from None
    if shape_tail is not None:
        n = len(shape_tail)
        if arr.ndim < n or tuple(arr.shape[arr.ndim - n:]) != tuple(shape_tail):
            raise ValueError(f"{name} must have trailing shape {shape_tail}, got {arr.shape}")
    if not allow_nonfinite and not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or inf")
    return arr


def check_choice(name: str, value, choices: Iterable[str]) -> str:
    """Check that ``value`` is one of ``choices``."""
    choices = tuple(choices)
    if value not in choices:
        raise ValueError(f"{name} = {value!r} is not one of {', '.join(map(repr, choices))}")
    return value
