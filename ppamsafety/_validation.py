"""Helpers that turn bad input into clear ``TypeError`` / ``ValueError`` messages.

Every parameter object and public function validates its input with these
helpers instead of ``assert``: a wrong input names the offending argument, its
value and what is allowed, and never propagates into a kernel (where it would
surface as a numba typing error, an ``AttributeError`` or a silent NaN).

How to validate a public function
---------------------------------
* **Convert, then use the converted value.**  Every helper *returns* the
  checked value in canonical form (``float``, ``int``, ``tuple`` of float,
  C-contiguous float64 ``ndarray``); rebind the argument to it
  (``dt = check_positive("dt", dt, unit="s")``).  Never check a value and then
  pass the original object on: a string that passes a range check by accident
  would reach the kernel.
* **Check every argument at the top of the function**, in signature order,
  before any work is done, with the argument's public name (``"dt"``,
  ``"ArmGeometry.L22"``, ``"valve 2 time_constant"``) so the message can be
  acted upon.  Objects: :func:`check_instance`; scalars: :func:`check_range`
  / :func:`check_positive` / :func:`check_int` / :func:`check_bool` /
  :func:`check_choice`; fixed-length tuples: :func:`check_vector`; arrays:
  :func:`as_float_array` (with ``shape_tail`` / ``ndim`` / ``min_len``), then
  :func:`check_same_rows`, :func:`check_increasing`, :func:`check_range_array`.
* **Give every physical quantity a documented range** (with its unit and,
  where there is one, the thesis section it comes from) instead of only
  "finite"; the range is where the model is valid, not where the arithmetic
  happens not to fail.  Use ``lo_open`` / ``hi_open`` for strict bounds.
* **Check consistency between arguments** after the individual checks
  (``window`` vs ``dt``, ``q1_min < q1_max``, equal row counts) and state both
  values in the message.
* **Guard the result**: if a legal input can still overflow (e.g. ``A**2.5``),
  check the result with :func:`check_finite_result` so no NaN/inf is ever
  returned silently.
* **Test it** with the property tests of ``tests/test_properties.py`` (wrong
  types, NaN/inf, zero/negative/huge values, wrong shapes): each example must
  raise ``TypeError``/``ValueError`` naming the argument or give a finite result.

Conventions
-----------
* ``TypeError`` (actually :class:`InvalidTypeError`, a subclass of both
  ``TypeError`` and ``ValueError``, so that existing ``except ValueError``
  handlers such as the CLI's keep catching it) for a value of the wrong kind:
  ``None``, a string, a dict, a complex number, a nested or ragged list, an
  object array, and **a bool where a number is wanted** (``True`` is an
  ``int`` in Python, but a bool passed as a length, pressure or count is
  always a mistake, so physical quantities and counts reject it).
* ``ValueError`` for a value of the right kind that is not allowed: NaN/inf,
  out of range, wrong shape or length, inconsistent with another argument.
* Python ints, floats, ``fractions.Fraction``, ``decimal.Decimal`` and numpy
  real scalars (or 0-d real arrays) are accepted as real numbers.

Policy on loose types, choices and magnitudes
---------------------------------------------
One rule per kind of looseness, the same in every public function, parameter
set, study file and command-line option:

* **0-d arrays** (``np.array(0.4)``) are real numbers: accepted wherever a
  float or an int is, and converted (:func:`check_real`, :func:`check_int`),
  because NumPy produces them from reductions.  A 1-element *1-D* array or
  list is not a number (``TypeError``): it is a vector of the wrong length.
* **Masked arrays** are refused where an array of numbers is expected when any
  entry is masked (``ValueError`` naming the argument and the count): NumPy
  would silently compute with the hidden values.  Fill them
  (``a.filled(...)``) or pass the valid part.  An unmasked masked array is
  its data.
* **Choices** (controller families, head models, experiments, noise levels,
  sub-command choices) are exact, case-sensitive strings: a mis-cased or
  padded name is refused with the allowed names and the closest one
  (``did you mean 'thesis-frontal'?``), never silently matched, so that one
  name has one spelling in files, caches and reports.  Enum flags of the
  controllers (:func:`ppamsafety.layouts.check_flag`) accept their documented
  lower-case name or the enum member's upper-case name, with ``-``, ``_`` or
  a space between words; no other case (``"Mimo"`` is refused).
* **Magnitudes**: a finite number is not enough.  Every physical quantity
  has a range where the model is valid (a pressure limit of 1e300 Pa is
  refused: gauge pressures and pressure limits stay within
  [-1 atm, :data:`PRESSURE_MAX`]); counts and sizes are bounded so that a
  request is refused with a size estimate *before* memory is allocated
  (:func:`check_size`), never by a ``MemoryError``.
* **Seeds** are integers in [0, 2^63 - 1] (:func:`check_seed`), in every function that
  draws random numbers.
* **Arrays where a pair belongs** (a 1-D array of two numbers for ``stiffness = [K1, K2]``)
  are the pair; a 2-D array is not.
* **Names looked up in a result** (``result.signal("q1")``) raise
  :class:`UnknownNameError` (a ``KeyError`` and a ``ValueError``) with the closest name.
* **Paths** are ``str`` or ``os.PathLike``; an empty path is refused (``Path("")`` would be
  the current folder), never taken for ``.``; input files are read by
  :mod:`ppamsafety._inputfiles`.
* **Arguments that change nothing** in the combination given (an option of another kind of
  record or identification) are refused with the reason, not silently ignored.
* **Numbers as text** (``NAME=VALUE`` on a command line): one number or
  comma-separated numbers (:func:`check_numbers`); ``inf``, ``nan`` and empty
  parts are refused naming the value's owner.
"""

from __future__ import annotations

import difflib
import math
import numbers
import operator
from typing import Iterable

import numpy as np

__all__ = ["InvalidTypeError", "UnknownNameError", "PRESSURE_MAX", "SEED_MAX", "MAX_BYTES",
           "describe", "check_real", "check_finite", "check_range",
           "check_positive", "check_nonnegative", "check_int", "check_bool", "check_str",
           "check_choice", "check_instance", "check_vector", "check_numbers", "check_seed",
           "check_size", "did_you_mean", "as_float_array", "check_shape",
           "check_same_rows", "check_increasing", "check_range_array", "check_finite_result"]


#: Largest gauge pressure or pressure limit accepted anywhere [Pa]: 100 bar, ten times the
#: industrial compressed-air supply; no pneumatic muscle or valve comes near it.
PRESSURE_MAX = 1.0e7
#: Largest seed of a random stream (numpy accepts more; 2^63 - 1 keeps seeds in int64 columns
#: of sweep tables and in TOML files).
SEED_MAX = 2 ** 63 - 1
#: Largest memory one request may allocate for its results [bytes] (2 GB): a larger request is
#: refused with its size estimate before anything is allocated (:func:`check_size`).
MAX_BYTES = 2 * 10 ** 9


class InvalidTypeError(TypeError, ValueError):
    """A value of the wrong kind (a ``TypeError``; also a ``ValueError`` for old handlers)."""


class UnknownNameError(KeyError, ValueError):
    """A name that is not one of a result's (a ``KeyError`` for a lookup, and a ``ValueError``
    like every other bad input); its message is shown as written (no ``KeyError`` quotes)."""

    def __str__(self):
        return str(self.args[0]) if self.args else ""


def describe(value, limit: int = 60) -> str:
    """Short ``repr`` of ``value`` for error messages (type name added, long reprs cut)."""
    try:
        r = repr(value)
    except Exception:  # pragma: no cover - exotic objects
        r = f"<{type(value).__name__}>"
    if len(r) > limit:
        r = r[:limit - 3] + "..."
    t = type(value).__name__
    if isinstance(value, (bool, np.bool_, str, type(None))) or t in r:
        return r
    return f"{r} ({t})"


def _fmt(v: float) -> str:
    return f"{v:g}"


def check_real(name: str, value, *, unit: str = "") -> float:
    """Return ``value`` as a Python float; ``TypeError`` unless it is a real number.

    NaN and inf are returned as they are (use :func:`check_finite` to refuse
    them).  Bools, strings, ``None``, complex numbers, containers and arrays
    with more than one element raise :class:`InvalidTypeError`.
    """
    if isinstance(value, (bool, np.bool_)):
        raise InvalidTypeError(f"{name} must be a real number, got a bool ({value!r})")
    if value is np.ma.masked:
        raise ValueError(f"{name} is a masked value (numpy.ma.masked), not a number")
    value = _unmasked(name, value)
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
        return float(value)
    if isinstance(value, numbers.Real) and not isinstance(value, np.ndarray):
        try:
            return float(value)
        except (OverflowError, ValueError):
            raise ValueError(f"{name} = {describe(value)} is too large for a float") from None
    what = "a complex number" if isinstance(value, (complex, np.complexfloating)) else \
        describe(value)
    u = f" [{unit}]" if unit else ""
    raise InvalidTypeError(f"{name} must be a real number{u}, got {what}")


def check_finite(name: str, value, *, unit: str = "") -> float:
    """Return ``value`` as float; ``TypeError`` if not real, ``ValueError`` if NaN/inf."""
    v = check_real(name, value, unit=unit)
    if not math.isfinite(v):
        u = f" {unit}" if unit else ""
        raise ValueError(f"{name} = {v}{u} is not allowed: it must be a finite number")
    return v


def check_range(name: str, value, lo: float = -math.inf, hi: float = math.inf,
                *, lo_open: bool = False, hi_open: bool = False, unit: str = "") -> float:
    """Check ``lo <= value <= hi`` (open ends with ``lo_open``/``hi_open``); return a float.

    The error message names the field, the value and the allowed interval, e.g.
    ``"valve 2 time_constant = -0.1 s is outside (0, inf) s"``.  NaN and inf are
    refused even if the interval is unbounded.
    """
    v = check_finite(name, value, unit=unit)
    below = v <= lo if lo_open else v < lo
    above = v >= hi if hi_open else v > hi
    if below or above:
        lb = "(" if lo_open or lo == -math.inf else "["
        rb = ")" if hi_open or hi == math.inf else "]"
        u = f" {unit}" if unit else ""
        raise ValueError(f"{name} = {_fmt(v)}{u} is outside {lb}{_fmt(lo)}, {_fmt(hi)}{rb}{u}")
    return v


def check_positive(name: str, value, *, unit: str = "") -> float:
    """Check ``0 < value < inf``; return a float."""
    return check_range(name, value, 0.0, math.inf, lo_open=True, unit=unit)


def check_nonnegative(name: str, value, *, unit: str = "") -> float:
    """Check ``0 <= value < inf``; return a float."""
    return check_range(name, value, 0.0, math.inf, unit=unit)


def check_int(name: str, value, lo: int | None = None, hi: int | None = None) -> int:
    """Check that ``value`` is an integer in ``[lo, hi]``; return a Python int.

    Python/numpy integers and integral floats (``3.0``) are accepted; bools,
    strings, ``None`` and other non-numbers raise :class:`InvalidTypeError`;
    non-integral or non-finite floats and out-of-range values ``ValueError``.
    """
    if isinstance(value, (bool, np.bool_)):
        raise InvalidTypeError(f"{name} must be an integer, got a bool ({value!r})")
    try:
        v = operator.index(value)
    except TypeError:
        v = check_real(name, value)   # TypeError for non-numbers, naming the argument
        if not math.isfinite(v) or v != math.floor(v):
            raise ValueError(f"{name} must be an integer, got {describe(value)}") from None
        v = int(v)
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        lb = "-inf" if lo is None else str(lo)
        hb = "inf" if hi is None else str(hi)
        raise ValueError(f"{name} = {v} is outside [{lb}, {hb}]")
    return int(v)


def check_seed(name: str, value) -> int:
    """A seed of a random stream: an integer in [0, :data:`SEED_MAX`]; return it as int."""
    return check_int(name, value, 0, SEED_MAX)


def check_size(what: str, nbytes: float, *, limit: float = MAX_BYTES, remedy: str = "") -> None:
    """Refuse a request whose arrays would need more than ``limit`` bytes, before allocating.

    Parameters
    ----------
    what : str
        What is being sized, with the numbers it comes from (e.g. ``"duration = 1e+05 s at
        dt = 0.001 s: 1e+08 samples"``).
    nbytes : float
        Estimated memory [bytes].
    limit : float
        Largest memory allowed [bytes] (default :data:`MAX_BYTES`).
    remedy : str
        How to go on (e.g. ``"use a shorter duration"``).
    """
    if not nbytes <= limit:
        raise ValueError(f"{what} would need about {nbytes / 1e9:.3g} GB of memory (limit "
                         f"{limit / 1e9:.3g} GB){'; ' + remedy if remedy else ''}")


def check_bool(name: str, value) -> bool:
    """Check that ``value`` is a bool (Python or numpy); ints 0/1 and strings are refused."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise InvalidTypeError(f"{name} must be True or False, got {describe(value)}")


def check_str(name: str, value, *, allow_empty: bool = True) -> str:
    """Check that ``value`` is a string; return it."""
    if not isinstance(value, str):
        raise InvalidTypeError(f"{name} must be a string, got {describe(value)}")
    if not allow_empty and not value.strip():
        raise ValueError(f"{name} must not be empty")
    return value


def check_choice(name: str, value, choices: Iterable[str]) -> str:
    """Check that ``value`` is one of ``choices``; return it.

    Choices are exact (case-sensitive); a value that differs only in case or surrounding
    blanks is refused with the right spelling (module docstring).  A value of another type
    than the (string) choices raises :class:`InvalidTypeError`.
    """
    choices = tuple(choices)
    allowed = ", ".join(map(repr, choices))
    if all(isinstance(c, str) for c in choices) and not isinstance(value, str):
        raise InvalidTypeError(f"{name} must be one of {allowed}, got {describe(value)}")
    try:
        ok = value in choices
    except TypeError:   # unhashable / incomparable
        ok = False
    if not ok:
        raise ValueError(f"{name} = {value!r} is not one of {allowed}"
                         f"{did_you_mean(value, choices)}")
    return value


def did_you_mean(value, choices) -> str:
    """``"; did you mean 'x'?"`` for a name that differs from a choice only in case, blanks,
    ``-``/``_``, or by a typo or two; ``""`` otherwise."""
    if not isinstance(value, str):
        return ""

    def norm(x):
        return " ".join(str(x).replace("_", " ").replace("-", " ").split()).lower()

    v = norm(value)
    same = [c for c in choices if isinstance(c, str) and norm(c) == v]
    if same:
        return f"; did you mean {same[0]!r}? (names are case-sensitive)"
    close = difflib.get_close_matches(value, [c for c in choices if isinstance(c, str)], n=1,
                                      cutoff=0.75)
    return f"; did you mean {close[0]!r}?" if close else ""


def check_instance(name: str, value, cls):
    """Check ``isinstance(value, cls)`` (``cls`` a class or tuple of classes); return it."""
    if not isinstance(value, cls):
        names = " or ".join(c.__name__ for c in (cls if isinstance(cls, tuple) else (cls,)))
        raise InvalidTypeError(f"{name} must be a {names}, got {describe(value)}")
    return value


def _sequence(name: str, value, length: int | None):
    """``value`` as a list of items; refuse strings, mappings, sets and scalars."""
    if isinstance(value, np.ndarray):
        if value.ndim != 1:
            raise ValueError(f"{name} must be 1-D, got an array of shape {value.shape}")
        items = list(value)
    elif isinstance(value, (list, tuple)):
        items = list(value)
    else:
        what = f"{length} " if length is not None else ""
        raise InvalidTypeError(f"{name} must be a sequence (tuple or list) of {what}numbers, "
                               f"got {describe(value)}")
    if length is not None and len(items) != length:
        raise ValueError(f"{name} must have {length} entries, got {len(items)}")
    return items


def check_vector(name: str, value, length: int | None = None, lo: float = -math.inf,
                 hi: float = math.inf, *, lo_open: bool = False, hi_open: bool = False,
                 unit: str = "") -> tuple:
    """Check a fixed-length sequence of real numbers, each in ``[lo, hi]``; return a tuple.

    Entries are named ``name[i]`` in messages, e.g. ``"PneumaticParams.p_mean[1]"``.
    """
    items = _sequence(name, value, length)
    return tuple(check_range(f"{name}[{i}]", x, lo, hi, lo_open=lo_open, hi_open=hi_open,
                             unit=unit) for i, x in enumerate(items))


def check_numbers(name: str, value, lengths: Iterable[int] | None = None, *,
                  unit: str = "") -> tuple:
    """One number, a sequence of numbers or their text (``"0.4"``, ``"1,2,3"``) as a tuple.

    The form of a value given on a command line or in a file (``NAME=VALUE``):
    a comma-separated text is split, each part must be a finite number.

    Parameters
    ----------
    name : str
        Name used in messages (e.g. ``"effect payload_mass"``).
    value : number, str or sequence of numbers
        The value.
    lengths : iterable of int, optional
        Allowed numbers of values (e.g. ``(1, 4)``: one for all, or one each).
    unit : str
        Unit named in messages.

    Returns
    -------
    tuple of float
    """
    if isinstance(value, str):
        text = value.strip()
        if not text:
            raise ValueError(f"{name} = {value!r} is empty: give a number"
                             f"{' or comma-separated numbers' if lengths != (1,) else ''}")
        parts = [p.strip() for p in text.split(",")]
        items = []
        for i, p in enumerate(parts):
            where = f"{name}[{i}]" if len(parts) > 1 else name
            try:
                items.append(float(p))
            except ValueError:
                raise ValueError(f"{where} = {p!r} is not a number"
                                 f"{f' (in {value!r})' if len(parts) > 1 else ''}") from None
        vals = tuple(check_finite(f"{name}[{i}]" if len(items) > 1 else name, v, unit=unit)
                     for i, v in enumerate(items))
    elif isinstance(value, (np.ndarray, list, tuple)) and np.ndim(value) != 0:
        vals = check_vector(name, value, None, unit=unit)
    else:
        vals = (check_finite(name, value, unit=unit),)
    if lengths is not None:
        allowed = tuple(lengths)
        if len(vals) not in allowed:
            want = " or ".join(map(str, allowed))
            raise ValueError(f"{name} takes {want} value{'s' if allowed != (1,) else ''}, got "
                             f"{len(vals)}: {value!r}")
    return vals


def _unmasked(name: str, value):
    """The data of a masked array without masked entries; refuse one with masked entries."""
    if isinstance(value, np.ma.MaskedArray):
        n = int(np.ma.count_masked(value))
        if n:
            raise ValueError(f"{name} is a masked array with {n} masked entr"
                             f"{'y' if n == 1 else 'ies'}: their hidden values would be used; "
                             f"fill them (a.filled(...)) or pass only the valid entries")
        return np.ma.getdata(value)
    return value


def as_float_array(name: str, value, *, shape_tail: tuple[int, ...] | None = None,
                   ndim: int | tuple[int, ...] | None = None, min_len: int | None = None,
                   allow_nonfinite: bool = False) -> np.ndarray:
    """Convert to a float64 array and check its kind, shape and finiteness.

    Parameters
    ----------
    name : str
        Name used in error messages.
    value : array_like
        Real numbers (Python/numpy ints and floats).  Strings, ``None``,
        dicts, bools, complex and object arrays raise :class:`InvalidTypeError`;
        ragged nested lists ``ValueError``.
    shape_tail : tuple of int, optional
        Required trailing dimensions, e.g. ``(2,)`` for joint vectors.
    ndim : int or tuple of int, optional
        Allowed numbers of dimensions.
    min_len : int, optional
        Minimum length of the last axis (e.g. 2 samples).
    allow_nonfinite : bool
        If False (default), NaN or inf raise ``ValueError``.

    Returns
    -------
    numpy.ndarray
        float64 array (a copy only if a conversion was needed).
    """
    if value is None or isinstance(value, (str, bytes, dict, set, frozenset)):
        raise InvalidTypeError(f"{name} must be an array of real numbers, got {describe(value)}")
    value = _unmasked(name, value)
    if isinstance(value, np.ndarray):
        raw = value
    else:
        try:
            raw = np.asarray(value)
        except ValueError:
            raise ValueError(f"{name} must be a rectangular array of real numbers; "
                             f"got a ragged nested sequence") from None
    kind = raw.dtype.kind
    if kind == "b":
        raise InvalidTypeError(f"{name} must be an array of real numbers, got a bool array")
    if kind == "c":
        raise InvalidTypeError(f"{name} must be an array of real numbers, got complex values")
    if kind in "OUSV":
        # object arrays of plain numbers (e.g. mixed int/Fraction) are fine if they convert
        if kind == "O":
            try:
                if all(isinstance(x, numbers.Real) and not isinstance(x, (bool, np.bool_))
                       for x in raw.ravel()):
                    raw = raw.astype(float)
                    kind = "f"
            except (TypeError, ValueError, OverflowError):
                pass
        if kind != "f":
            what = {"U": "strings", "S": "bytes", "V": "structured records"}.get(
                kind, "objects that are not real numbers or overflow float64")
            raise InvalidTypeError(f"{name} must be an array of real numbers, got {what} "
                                   f"(dtype {raw.dtype})")
    if kind == "M" or kind == "m":
        raise InvalidTypeError(f"{name} must be an array of real numbers, got dtype {raw.dtype}")
    arr = np.asarray(raw, dtype=float)
    if ndim is not None:
        allowed = (ndim,) if isinstance(ndim, int) else tuple(ndim)
        if arr.ndim not in allowed:
            want = " or ".join(map(str, allowed))
            raise ValueError(f"{name} must be {want}-D, got shape {arr.shape}")
    if shape_tail is not None:
        n = len(shape_tail)
        if arr.ndim < n or tuple(arr.shape[arr.ndim - n:]) != tuple(shape_tail):
            lead = "(..., " + ", ".join(map(str, shape_tail)) + ")"
            raise ValueError(f"{name} must have trailing shape {lead}, got shape {arr.shape}")
    if min_len is not None and (arr.ndim == 0 or arr.shape[-1] < min_len):
        got = "a scalar" if arr.ndim == 0 else f"{arr.shape[-1]}"
        raise ValueError(f"{name} needs at least {min_len} entries along its last axis, "
                         f"got {got} (shape {arr.shape})")
    if not allow_nonfinite and not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))
        where = f" at index {tuple(int(i) for i in bad[0])}" if arr.ndim else ""
        raise ValueError(f"{name} contains NaN or inf ({len(bad)} entr"
                         f"{'y' if len(bad) == 1 else 'ies'}, first{where})")
    return arr


def check_shape(name: str, arr: np.ndarray, shape: tuple) -> np.ndarray:
    """Check ``arr.shape`` against ``shape`` (``None`` entries match any length)."""
    ok = arr.ndim == len(shape) and all(s is None or s == a for s, a in zip(shape, arr.shape))
    if not ok:
        want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + \
            ("," if len(shape) == 1 else "") + ")"
        raise ValueError(f"{name} must have shape {want}, got {arr.shape}")
    return arr


def check_same_rows(name_a: str, a: np.ndarray, name_b: str, b: np.ndarray) -> int:
    """Check that two arrays have the same number of rows (leading length); return it.

    Message e.g. ``"qd has 4 rows, q has 1"``.
    """
    na = a.shape[0] if a.ndim else 1
    nb = b.shape[0] if b.ndim else 1
    if na != nb:
        raise ValueError(f"{name_b} has {nb} rows, {name_a} has {na}")
    return na


def check_increasing(name: str, arr: np.ndarray, *, strict: bool = True) -> np.ndarray:
    """Check that a 1-D array is (strictly) increasing."""
    d = np.diff(arr)
    bad = np.nonzero(d <= 0 if strict else d < 0)[0]
    if bad.size:
        i = int(bad[0])
        word = "strictly increasing" if strict else "non-decreasing"
        raise ValueError(f"{name} must be {word}, but {name}[{i}] = {_fmt(arr[i])} and "
                         f"{name}[{i + 1}] = {_fmt(arr[i + 1])}")
    return arr


def check_range_array(name: str, arr: np.ndarray, lo: float = -math.inf, hi: float = math.inf,
                      *, unit: str = "") -> np.ndarray:
    """Check that every entry of a finite array lies in ``[lo, hi]``; name the first offender."""
    out = (arr < lo) | (arr > hi)
    if out.any():                   # the common case (all in range) costs one pass
        bad = np.argwhere(out)
        idx = tuple(int(i) for i in bad[0])
        u = f" {unit}" if unit else ""
        where = f"[{', '.join(map(str, idx))}]" if arr.ndim else ""
        raise ValueError(f"{name}{where} = {_fmt(arr[idx] if arr.ndim else float(arr))}{u} is "
                         f"outside [{_fmt(lo)}, {_fmt(hi)}]{u} ({len(bad)} entries out of range)")
    return arr


def check_finite_result(what: str, value, cause: str):
    """Refuse a NaN/inf result of legal-looking input: ``ValueError`` naming the ``cause``.

    ``value`` is a float or an array; returned unchanged when finite.
    """
    if not np.all(np.isfinite(value)):
        raise ValueError(f"{what} is not finite (overflow) for {cause}; use smaller values")
    return value
