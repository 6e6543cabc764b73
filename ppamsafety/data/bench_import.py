"""Import a raw test-bench file into the measured-data format.

A bench logger writes what it writes: no header, tabs, milliseconds, mm, bar,
a position that grows when the rod is pushed *in*, a load cell zeroed by hand,
a software timer with jitter and gaps, the odd laser spike.  An **import
profile** (:class:`BenchProfile`, a TOML file or a dict) says once how to read
such a file, and :func:`import_bench` turns every file of the bench into a
validated :class:`~ppamsafety.data.measured.MeasuredData` (SI units, the
format's sign conventions), recording every step in its metadata (``[import]``)
and in ``notes``.  Nobody writes a converter.

The profile (``docs/measured_data.md``, "Importing a raw bench file"):

* the file layout: ``delimiter`` (``"whitespace"``, ``","``, ``";"``, ``"\\t"``),
  ``header`` (false: the columns are named by the profile, in file order),
  ``comment`` (lines starting with it are skipped);
* ``columns``: every column of the file with its unit, parsed by `pint
  <https://pint.readthedocs.io>`_ (``"ms"``, ``"mm"``, ``"um"``, ``"bar"``,
  ``"mbar"``, ``"kPa"``, ``"psi"``, ``"N"``, ``"mN"``, ``"lbf"``, ``"V"``, ...);
  ``"-"`` for a dimensionless column.  An unknown unit is an error naming
  the column;
* ``channels``: which column gives ``t``, ``force``, ``pressure`` and
  ``position`` (or ``contraction``), each with an optional ``sign`` (+1/-1),
  ``offset`` (added after the conversion: a number in SI units or a
  quantity string such as ``"0.37 N"``) and ``zero = "first"`` (tare: the
  first sample becomes 0);
* ``pressure_reference``: ``"gauge"`` or ``"absolute"`` (required: a unit
  cannot say it; absolute pressures get ``p_atm`` subtracted, default 1.013
  bar);
* ``despike``: channels whose isolated one-sample spikes are replaced by the
  line through their neighbours (a laser displacement sensor's dropouts):
  a sample more than ``despike_sigmas`` robust noise levels off that line
  whose two neighbours are off it by about half as much the other way
  (the signature of one bad sample, not of a reversal of the motion);
* ``gap_factor``: an interval longer than this many median intervals is a gap
  (the record is split there; segments shorter than ``min_segment_rows``,
  typically start-up rows before a first long interval, are dropped).

Checks (each a :class:`~ppamsafety.data.measured.MeasuredDataError` naming
the column, or a stated assumption in ``notes``): the number of columns per
line; non-numbers (row and line); missing values (rows dropped, noted);
duplicate or decreasing times (error, rows named); units and their dimension
(a force column in mm is an error); a gauge pressure below vacuum; a **force
sign** opposite to the pressure force; and a **sign mismatch between force and
position**: over closed cycles friction and hysteresis dissipate energy, so
the force minus the nominal law, integrated over the working stroke
(``-sum (F - F_law) dw``), must be positive; a negative value means the
position (or the force) has the wrong sign for the format's convention.
"""

from __future__ import annotations

import functools
import hashlib
import io
import math
import numbers
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .._inputfiles import check_input_file, read_bytes, read_text
from ..units import P_ATM
from .measured import ACTUATOR_TYPES, MeasuredData, MeasuredDataError, check_nominal_pressure

#: Channels of an actuator record and the dimension pint must find for each.
CHANNEL_DIMENSIONS = {"t": "[time]", "force": "[force]", "pressure": "[pressure]",
                      "position": "[length]", "contraction": ""}
#: SI unit of every channel.
CHANNEL_SI = {"t": "s", "force": "N", "pressure": "Pa", "position": "m", "contraction": ""}
DELIMITERS = ("whitespace", ",", ";", "\t", "|")
PRESSURE_REFERENCES = ("gauge", "absolute")
#: Defaults of the profile.
DESPIKE_SIGMAS = 8.0
GAP_FACTOR = 3.0
MIN_SEGMENT_ROWS = 20
#: Fewest strokes of the motion for the sign checks (fewer: a note, no check).
SIGN_CHECK_STROKES = 4
#: Fraction of the strokes that must dissipate the wrong way to call it a sign mismatch.
SIGN_CHECK_FRACTION = 0.8


@functools.lru_cache(maxsize=1)
def unit_registry():
    """The pint unit registry (built once; pint is imported here, when a file is imported).

    Returns
    -------
    pint.UnitRegistry
    """
    import pint

    return pint.UnitRegistry()


def _unit(where: str, unit: str):
    """A pint unit from a string; an error naming ``where`` if pint does not know it."""
    import pint

    if not isinstance(unit, str):
        raise MeasuredDataError(f"{where}: the unit must be a string such as 'mm' or 'bar', "
                                f"got {unit!r}")
    if unit.strip() in ("-", "", "1"):
        return unit_registry().dimensionless
    try:
        return unit_registry().Unit(unit.strip())
    except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError, ValueError,
            AttributeError, TypeError) as exc:
        raise MeasuredDataError(f"{where}: unknown unit {unit!r} ({exc}); give a unit pint "
                                f"knows, e.g. 'ms', 'mm', 'bar', 'N', 'V', or '-'") from None


def _check_dimension(where: str, unit, channel: str):
    ureg = unit_registry()
    want = CHANNEL_DIMENSIONS[channel]
    have = ureg.Quantity(1.0, unit).dimensionality
    if (want == "" and not have == ureg.dimensionless.dimensionality) or \
            (want and have != ureg.get_dimensionality(want)):
        raise MeasuredDataError(f"{where}: unit {str(unit)!r} has dimension {have or '1'}, but "
                                f"the channel '{channel}' needs {want or 'no dimension'} "
                                f"(SI: {CHANNEL_SI[channel] or '-'})")


def quantity(where: str, value, si_unit: str) -> float:
    """A number in SI units, or a quantity string (``"25.7 mm"``) converted to ``si_unit``.

    Parameters
    ----------
    where : str
        The field, for messages.
    value : float or str
        A finite number (taken as SI) or a string with a unit.
    si_unit : str
        The SI unit wanted (``"m"``, ``"Pa"``, ``"N"``, ...; ``""``: dimensionless).

    Returns
    -------
    float
    """
    import pint

    if isinstance(value, bool):
        raise MeasuredDataError(f"{where} = {value!r} must be a number or a quantity string")
    if isinstance(value, numbers.Real):
        x = float(value)
    elif isinstance(value, str):
        ureg = unit_registry()
        try:
            q = ureg.Quantity(value.strip())
            x = float(q.to(si_unit or "dimensionless").magnitude) if not isinstance(
                q, numbers.Real) else float(q)
        except pint.errors.DimensionalityError:
            raise MeasuredDataError(f"{where} = {value!r} is not in a unit of {si_unit or '1'}") \
                from None
        except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError, ValueError,
                AttributeError, TypeError) as exc:
            raise MeasuredDataError(f"{where} = {value!r} is not a quantity pint can read "
                                    f"({exc}); e.g. '25.7 mm', '0.37 N'") from None
    else:
        raise MeasuredDataError(f"{where} = {value!r} must be a number (SI) or a quantity "
                                f"string such as '25.7 mm'")
    if not math.isfinite(x):
        raise MeasuredDataError(f"{where} = {value!r} must be finite")
    return x


# --------------------------------------------------------------------------- the profile

@dataclass(frozen=True)
class ChannelMap:
    """Where a channel of the format comes from in a raw file.

    Parameters
    ----------
    column : str
        Name of the raw column (as in :attr:`BenchProfile.columns`).
    sign : int
        +1 or -1, applied after the unit conversion.
    offset : float
        Added after the sign [SI unit of the channel].
    zero : bool
        Tare: subtract the first sample (after sign and offset).
    """

    column: str
    sign: int = 1
    offset: float = 0.0
    zero: bool = False

    def __post_init__(self):
        if not isinstance(self.column, str) or not self.column:
            raise MeasuredDataError(f"channel column must be a non-empty string, got "
                                    f"{self.column!r}")
        if self.sign not in (1, -1) or isinstance(self.sign, bool):
            raise MeasuredDataError(f"channel {self.column!r}: sign = {self.sign!r} must be +1 or "
                                    f"-1")
        if not isinstance(self.zero, bool):
            raise MeasuredDataError(f"channel {self.column!r}: zero must be true or false")


@dataclass(frozen=True)
class BenchProfile:
    """How to read the raw files of one bench (module docstring; ``docs/measured_data.md``).

    Parameters
    ----------
    columns : tuple of (str, str)
        (name, unit) of every column, in file order (``header=False``) or the
        columns to find by name (``header=True``).
    channels : dict
        Channel (``t``, ``force``, ``pressure``, ``position`` or
        ``contraction``) -> :class:`ChannelMap`.
    pressure_reference : {"gauge", "absolute"}
        What the pressure column measures.
    delimiter : str
        ``"whitespace"`` (tabs or spaces), ``","``, ``";"``, ``"\\t"`` or ``"|"``.
    header : bool
        The file's first (non-comment) line names the columns.
    comment : str
        Lines starting with this are skipped ("" for none).
    p_atm : float
        Atmospheric pressure subtracted from absolute pressures [Pa].
    despike : tuple of str
        Channels whose isolated one-sample spikes are removed.
    despike_sigmas : float
        Spike threshold in robust noise levels, >= 4.
    gap_factor : float
        An interval longer than this many median intervals is a gap, > 1.
    min_segment_rows : int
        Gap-free segments shorter than this are dropped (noted).
    name : str
        A label (the bench, the logger).
    """

    columns: tuple
    channels: dict
    pressure_reference: str
    delimiter: str = "whitespace"
    header: bool = False
    comment: str = "#"
    p_atm: float = P_ATM
    despike: tuple = ()
    despike_sigmas: float = DESPIKE_SIGMAS
    gap_factor: float = GAP_FACTOR
    min_segment_rows: int = MIN_SEGMENT_ROWS
    name: str = ""

    def __post_init__(self):
        cols = tuple(self.columns)
        if not cols:
            raise MeasuredDataError("profile columns: list every column of the file as "
                                    "[name, unit]")
        norm = []
        for i, c in enumerate(cols):
            if not (isinstance(c, (tuple, list)) and len(c) == 2 and isinstance(c[0], str)):
                raise MeasuredDataError(f"profile columns[{i}] = {c!r} must be [name, unit]")
            _unit(f"profile column {c[0]!r}", c[1])
            norm.append((c[0], c[1]))
        names = [c[0] for c in norm]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise MeasuredDataError(f"profile columns: duplicate name(s) {dup}")
        object.__setattr__(self, "columns", tuple(norm))
        if not isinstance(self.channels, dict):
            raise MeasuredDataError(f"profile channels must be a table, got {self.channels!r}")
        ch = {}
        for k, v in self.channels.items():
            if k not in CHANNEL_DIMENSIONS:
                raise MeasuredDataError(f"profile channels: unknown channel {k!r}; allowed: "
                                        f"{', '.join(CHANNEL_DIMENSIONS)}")
            if isinstance(v, dict):
                v = dict(v)
                unknown = set(v) - {"column", "sign", "offset", "zero"}
                if unknown:
                    raise MeasuredDataError(f"profile channels.{k}: unknown key(s) "
                                            f"{sorted(unknown)} (allowed: column, sign, offset, "
                                            f"zero)")
                if "offset" in v:
                    v["offset"] = quantity(f"profile channels.{k}.offset", v["offset"],
                                           CHANNEL_SI[k])
                if v.get("zero") in ("first",):
                    v["zero"] = True
                elif v.get("zero") in ("none",):
                    v["zero"] = False
                v = ChannelMap(**v)
            elif isinstance(v, str):
                v = ChannelMap(v)
            if not isinstance(v, ChannelMap):
                raise MeasuredDataError(f"profile channels.{k} must be a column name or a table "
                                        f"{{column, sign, offset, zero}}, got {v!r}")
            if v.column not in names:
                raise MeasuredDataError(f"profile channels.{k}: column {v.column!r} is not one "
                                        f"of the profile's columns {names}")
            unit = _unit(f"profile column {v.column!r}", dict(norm)[v.column])
            _check_dimension(f"profile column {v.column!r} (channel '{k}')", unit, k)
            ch[k] = v
        for need in ("t", "force", "pressure"):
            if need not in ch:
                raise MeasuredDataError(f"profile channels: no '{need}' (required: t, force, "
                                        f"pressure and position or contraction)")
        if "position" not in ch and "contraction" not in ch:
            raise MeasuredDataError("profile channels: give 'position' or 'contraction'")
        object.__setattr__(self, "channels", ch)
        if self.pressure_reference not in PRESSURE_REFERENCES:
            raise MeasuredDataError(
                f"profile pressure_reference = {self.pressure_reference!r}: say whether the "
                f"pressure column {ch['pressure'].column!r} is 'gauge' or 'absolute' (a unit "
                f"such as bar cannot tell)")
        if self.delimiter not in DELIMITERS:
            raise MeasuredDataError(f"profile delimiter = {self.delimiter!r} is not one of "
                                    f"{DELIMITERS}")
        for nm in ("header",):
            if not isinstance(getattr(self, nm), bool):
                raise MeasuredDataError(f"profile {nm} must be true or false")
        if not isinstance(self.comment, str):
            raise MeasuredDataError(f"profile comment must be a string, got {self.comment!r}")
        object.__setattr__(self, "p_atm", quantity("profile p_atm", self.p_atm, "Pa"))
        if not 5e4 <= self.p_atm <= 1.2e5:
            raise MeasuredDataError(f"profile p_atm = {self.p_atm:g} Pa is not an atmospheric "
                                    f"pressure (50-120 kPa)")
        desp = tuple(self.despike)
        bad = [c for c in desp if c not in ch]
        if bad:
            raise MeasuredDataError(f"profile despike: {bad} are not mapped channels "
                                    f"({list(ch)})")
        object.__setattr__(self, "despike", desp)
        for nm, lo in (("despike_sigmas", 4.0), ("gap_factor", 1.0)):
            v = getattr(self, nm)
            if isinstance(v, bool) or not isinstance(v, numbers.Real) or not v > lo \
                    or not math.isfinite(v):
                raise MeasuredDataError(f"profile {nm} = {v!r} must be a number > {lo:g}")
        m = self.min_segment_rows
        if isinstance(m, bool) or not isinstance(m, numbers.Integral) or m < 3:
            raise MeasuredDataError(f"profile min_segment_rows = {m!r} must be an integer >= 3")

    @classmethod
    def from_dict(cls, d: dict) -> "BenchProfile":
        """A profile from a dict (the TOML layout of ``docs/measured_data.md``).

        Parameters
        ----------
        d : dict
            Keys as the constructor's arguments; ``columns`` a list of
            ``[name, unit]`` pairs or ``{name, unit}`` tables.
        """
        if not isinstance(d, dict):
            raise TypeError(f"profile must be a dict, got {type(d).__name__}")
        d = dict(d)
        known = {"columns", "channels", "pressure_reference", "delimiter", "header", "comment",
                 "p_atm", "despike", "despike_sigmas", "gap_factor", "min_segment_rows", "name"}
        unknown = set(d) - known
        if unknown:
            raise MeasuredDataError(f"profile: unknown key(s) {sorted(unknown)} (allowed: "
                                    f"{', '.join(sorted(known))}; a key after a [table] "
                                    f"header belongs to that table)")
        cols = d.get("columns")
        if not isinstance(cols, list):
            raise MeasuredDataError(f"profile columns must be a list of [name, unit], got "
                                    f"{cols!r}")
        d["columns"] = tuple((c["name"], c["unit"]) if isinstance(c, dict) and
                             set(c) == {"name", "unit"} else tuple(c) if isinstance(c, list)
                             else c for c in cols)
        if "pressure_reference" not in d:
            raise MeasuredDataError("profile: no pressure_reference: say whether the pressure "
                                    "column is 'gauge' or 'absolute'")
        if "channels" not in d:
            raise MeasuredDataError("profile: no [channels] table (t, force, pressure, "
                                    "position)")
        return cls(**d)

    @classmethod
    def from_toml(cls, path) -> "BenchProfile":
        """A profile from a TOML file.

        Parameters
        ----------
        path : path-like
            The profile file.
        """
        p, text = read_text(path, what="import profile", error=MeasuredDataError)
        try:
            d = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise MeasuredDataError(f"{p}: the profile is not valid TOML: {exc}") from None
        return cls.from_dict(d)

    def to_dict(self) -> dict:
        """The profile as a TOML-ready dict (recorded in an imported record's metadata)."""
        return {"name": self.name, "delimiter": self.delimiter, "header": self.header,
                "comment": self.comment, "columns": [list(c) for c in self.columns],
                "channels": {k: {"column": v.column, "sign": v.sign, "offset": v.offset,
                                 "zero": "first" if v.zero else "none"}
                             for k, v in self.channels.items()},
                "pressure_reference": self.pressure_reference, "p_atm": self.p_atm,
                "despike": list(self.despike), "despike_sigmas": float(self.despike_sigmas),
                "gap_factor": float(self.gap_factor),
                "min_segment_rows": int(self.min_segment_rows)}


@dataclass(frozen=True)
class Actuator:
    """The actuator on the bench: type and nominal force law.

    Parameters
    ----------
    type : {"cylinder", "muscle"}
        A cylinder: F = p A, position = the rod position (growing as the
        pressure extends the rod); a muscle: the law (3.9) with ``a`` and
        ``l0``.
    bore : float or str, optional
        Cylinder bore [m] (or ``"25.7 mm"``); the area is pi/4 bore^2.
    area : float or str, optional
        Cylinder working area [m^2] (instead of the bore).
    a : sequence of 5 float, optional
        Muscle law coefficients a0..a4 [N/Pa].
    l0 : float or str, optional
        Muscle length at zero contraction [m].
    name : str
        A label.
    """

    type: str
    bore: object = None
    area: object = None
    a: tuple = None
    l0: object = None
    name: str = ""

    def __post_init__(self):
        if self.type not in ACTUATOR_TYPES:
            raise MeasuredDataError(f"actuator type = {self.type!r} is not one of "
                                    f"{', '.join(map(repr, ACTUATOR_TYPES))}")
        if self.type == "cylinder":
            if (self.bore is None) == (self.area is None):
                raise MeasuredDataError("a cylinder needs its bore or its area (one of them)")
            if self.bore is not None:
                b = quantity("actuator bore", self.bore, "m")
                if not 0 < b <= 1:
                    raise MeasuredDataError(f"actuator bore = {b:g} m is outside (0, 1] m")
                object.__setattr__(self, "bore", b)
            else:
                ar = quantity("actuator area", self.area, "m**2")
                if not 0 < ar <= 1:
                    raise MeasuredDataError(f"actuator area = {ar:g} m^2 is outside (0, 1]")
                object.__setattr__(self, "area", ar)
        else:
            if self.a is None:
                raise MeasuredDataError("a muscle needs its force law a = [a0..a4] [N/Pa]")
            object.__setattr__(self, "a", tuple(float(x) for x in self.a))
            if self.l0 is not None:
                object.__setattr__(self, "l0", quantity("actuator l0", self.l0, "m"))

    @property
    def working_area(self) -> float:
        """The cylinder's area [m^2] (NaN for a muscle)."""
        if self.type != "cylinder":
            return math.nan
        return self.area if self.area is not None else math.pi / 4 * self.bore ** 2

    @classmethod
    def from_dict(cls, d: dict) -> "Actuator":
        """From a ``[actuator]`` table.

        Parameters
        ----------
        d : dict
            Keys type, bore or area (cylinder), a and l0 (muscle), name.
        """
        if not isinstance(d, dict):
            raise MeasuredDataError(f"actuator must be a table, got {d!r}")
        unknown = set(d) - {"type", "bore", "area", "a", "l0", "name"}
        if unknown:
            raise MeasuredDataError(f"actuator: unknown key(s) {sorted(unknown)}")
        if "type" not in d:
            raise MeasuredDataError("actuator: no type ('cylinder' or 'muscle')")
        return cls(**d)

    def meta(self) -> dict:
        """The ``actuator`` and ``force_law`` tables of the measured-data format."""
        if self.type == "cylinder":
            act = {"type": "cylinder", "name": self.name}
            if self.bore is not None:
                act["bore"] = self.bore
            return {"actuator": act,
                    "force_law": {"name": "p A (cylinder)",
                                  "a": [0.0, self.working_area, 0.0, 0.0, 0.0]}}
        law = {"name": self.name or "nominal", "a": list(self.a)}
        if self.l0 is not None:
            law["l0"] = self.l0
        return {"actuator": {"type": "muscle", "name": self.name}, "force_law": law}


# --------------------------------------------------------------------------- reading

#: Largest raw bench file read [bytes] (decompressed): 256 MB, some 600 times the largest
#: shipped record; the table it becomes takes a few times that in memory.
MAX_BENCH_BYTES = 256 * 2 ** 20


def _open_text(p: Path) -> str:
    _, raw = read_bytes(p, what="bench file", max_bytes=MAX_BENCH_BYTES,
                        error=MeasuredDataError, compressed=True)
    if b"\0" in raw:
        k = raw.index(b"\0")
        raise MeasuredDataError(f"{p}: a binary file (a NUL byte at offset {k}), not the text "
                                f"table of a bench record")
    try:
        return raw.decode("utf-8-sig"), raw            # a byte-order mark is skipped
    except UnicodeDecodeError:
        return raw.decode("latin-1"), raw


def _table(text: str, profile: BenchProfile, src: str) -> tuple:
    """(DataFrame of strings, file line of data row 0)."""
    lines = text.splitlines()
    skip = 0
    while skip < len(lines) and (not lines[skip].strip() or (
            profile.comment and lines[skip].lstrip().startswith(profile.comment))):
        skip += 1
    body = "\n".join(lines[skip:])
    sep = r"\s+" if profile.delimiter == "whitespace" else profile.delimiter
    try:
        df = pd.read_csv(io.StringIO(body), sep=sep, header=0 if profile.header else None,
                         dtype=str, comment=profile.comment or None, engine="python",
                         skip_blank_lines=True)
    except pd.errors.EmptyDataError:
        raise MeasuredDataError(f"{src}: no data") from None
    except pd.errors.ParserError as exc:
        raise MeasuredDataError(f"{src}: the lines do not split into the same number of "
                                f"columns with delimiter {profile.delimiter!r}: {exc}") from None
    names = [c[0] for c in profile.columns]
    first_line = skip + (2 if profile.header else 1)
    if profile.header:
        df.columns = [str(c).strip() for c in df.columns]
        missing = [n for n in names if n not in df.columns]
        if missing:
            raise MeasuredDataError(f"{src}: the header has no column(s) {missing} (header: "
                                    f"{list(df.columns)})")
        df = df[names]
    elif df.shape[1] != len(names):
        raise MeasuredDataError(f"{src}: {df.shape[1]} columns per line, but the profile lists "
                                f"{len(names)} ({', '.join(names)}); line {first_line}: "
                                f"{lines[skip][:120]!r}")
    else:
        df.columns = names
    short = np.flatnonzero(df.isna().to_numpy().any(axis=1))
    if short.size:
        k = int(short[0])
        nf = int(df.iloc[k].notna().sum())
        raise MeasuredDataError(f"{src}: line {first_line + k} has {nf} field(s), the profile "
                                f"lists {len(names)} columns ({', '.join(names)}); "
                                f"{short.size} such line(s) (a truncated or ragged line)")
    return df, first_line


def _interp_residual(t, x):
    """Each interior sample against the line through its neighbours, normalised (white: sigma)."""
    w = (t[2:] - t[1:-1]) / (t[2:] - t[:-2])
    d = x[1:-1] - (w * x[:-2] + (1.0 - w) * x[2:])
    return d / np.sqrt(1.0 + w ** 2 + (1.0 - w) ** 2), w


def despike(t, x, sigmas: float = DESPIKE_SIGMAS) -> tuple:
    """Replace isolated one-sample spikes by the line through their neighbours.

    A sample k is a spike when its interpolation residual ``d[k]`` exceeds
    ``sigmas`` x the robust noise level (1.4826 MAD) and both neighbours'
    residuals have the opposite sign and 25-75 % of its size (a single bad
    sample y shifts its neighbours' residuals by about -y/2; a reversal of
    the motion leaves them near 0).  Three passes.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Strictly increasing times.
    x : numpy.ndarray, shape (N,)
        The channel.
    sigmas : float
        Threshold in robust noise levels.

    Returns
    -------
    numpy.ndarray
        The cleaned channel (a copy).
    numpy.ndarray of int
        Indices replaced.
    """
    x = np.array(x, float)
    out = []
    if x.size < 7:
        return x, np.zeros(0, int)
    for _ in range(3):
        d, w = _interp_residual(t, x)
        s = 1.4826 * float(np.median(np.abs(d)))
        if not s > 0:
            break
        big = np.flatnonzero(np.abs(d) > sigmas * s)
        hits = []
        for j in big:                       # j indexes d; sample k = j + 1
            if j == 0 or j == d.size - 1:
                continue
            a, lft, rgt = d[j], d[j - 1], d[j + 1]
            if not (abs(a) >= abs(lft) and abs(a) >= abs(rgt)):
                continue
            if all(np.sign(n) == -np.sign(a) and 0.25 <= abs(n) / abs(a) <= 0.75
                   for n in (lft, rgt)):
                hits.append(j + 1)
        if not hits:
            break
        for k in hits:
            wk = (t[k + 1] - t[k]) / (t[k + 1] - t[k - 1])
            x[k] = wk * x[k - 1] + (1.0 - wk) * x[k + 1]
        out += hits
    return x, np.array(sorted(set(out)), int)


def _strokes(w, thr):
    """Direction of motion (+1/-1, 0 before any) with a dead band ``thr`` on w."""
    d = np.zeros(w.size, int)
    cur, ext = 0, w[0]
    lo = hi = w[0]
    for k in range(w.size):
        x = w[k]
        if cur == 0:
            lo, hi = min(lo, x), max(hi, x)
            if x - lo > thr:
                cur, ext = 1, x
            elif hi - x > thr:
                cur, ext = -1, x
        elif cur > 0:
            if x > ext:
                ext = x
            elif ext - x > thr:
                cur, ext = -1, x
        else:
            if x < ext:
                ext = x
            elif x - ext > thr:
                cur, ext = 1, x
        d[k] = cur
    return d


def dissipation_by_stroke(t, w, r) -> np.ndarray:
    """Per stroke of the motion: ``-sum r dw / sum |dw|`` [force unit].

    Friction and hysteresis take energy out of the actuator's work on the
    load, so with the format's conventions (``r = F - F_law``, w the working
    coordinate: contraction of a muscle, rod position of a cylinder) this is
    positive (about the Coulomb level) on every stroke.  Strokes of less than
    20 noise levels of w are skipped.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Times [s].
    w : numpy.ndarray, shape (N,)
        Working coordinate.
    r : numpy.ndarray, shape (N,)
        Force minus the nominal law [N].

    Returns
    -------
    numpy.ndarray
        One value per stroke.
    """
    if w.size < 10:
        return np.zeros(0)
    d, _ = _interp_residual(t, w)
    sig = max(1.4826 * float(np.median(np.abs(d))), 1e-12 * max(np.ptp(w), 1e-300))
    k = 5
    ws = np.convolve(w, np.ones(2 * k + 1) / (2 * k + 1), mode="same") if w.size > 4 * k else w
    ws[:k], ws[-k:] = w[:k], w[-k:]
    s = _strokes(ws, 20 * sig)
    out = []
    edges = np.flatnonzero(np.diff(s) != 0) + 1
    bounds = np.concatenate([[0], edges, [w.size]])
    for a, b in zip(bounds[:-1], bounds[1:]):
        if s[a] == 0 or b - a < 5:
            continue
        dw = np.diff(ws[a:b])
        rm = 0.5 * (r[a:b][1:] + r[a:b][:-1])
        L = float(np.sum(np.abs(dw)))
        if L > 20 * sig:
            out.append(-float(np.sum(rm * dw)) / L)
    return np.array(out)


# --------------------------------------------------------------------------- the import

def import_bench(path, profile, *, actuator, experiment: str = "tensile", description: str = "",
                 source: str | None = None, record: dict | None = None,
                 check_signs: bool = True) -> MeasuredData:
    """Read a raw bench file with an import profile; return a validated SI record.

    Parameters
    ----------
    path : path-like
        The raw file (plain text, or ``.gz``/``.xz``/``.bz2`` compressed).
    profile : BenchProfile, dict or path-like
        The import profile (a TOML file path is read with
        :meth:`BenchProfile.from_toml`).
    actuator : Actuator or dict, keyword-only
        The actuator on the bench (type, bore or law).
    experiment : {"tensile", "open-loop"}, keyword-only
        The record's experiment (``docs/measured_data.md``).
    description : str, keyword-only
        Free text for the metadata.
    source : str, optional, keyword-only
        Where the data come from (default: the file name and its sha256).
    record : dict, optional, keyword-only
        Per-record facts kept under ``[record]`` (e.g. ``pressure_nominal``
        [Pa] or ``"3 bar"``, ``label``, ``run``).
    check_signs : bool, keyword-only
        Run the force-sign and dissipation checks (module docstring).

    Returns
    -------
    MeasuredData
        ``kind = "actuator"``; columns ``t`` [s], ``force`` [N], ``pressure``
        [Pa gauge], ``position`` [m] or ``contraction``; metadata
        ``[import]`` with the profile, the file's sha256, the rows dropped,
        the spikes replaced and the notes (also in ``notes``).

    Raises
    ------
    MeasuredDataError
        Anything wrong with the file or the profile, naming the column.
    """
    p = check_input_file(path, what="bench file")
    if isinstance(profile, dict):
        profile = BenchProfile.from_dict(profile)
    elif isinstance(profile, (str, Path)):
        profile = BenchProfile.from_toml(profile)
    if not isinstance(profile, BenchProfile):
        raise TypeError(f"profile must be a BenchProfile, a dict or a TOML path, got "
                        f"{type(profile).__name__}")
    if isinstance(actuator, dict):
        actuator = Actuator.from_dict(actuator)
    if not isinstance(actuator, Actuator):
        raise TypeError(f"actuator must be an Actuator or a dict, got {type(actuator).__name__}")
    if not isinstance(check_signs, bool):
        raise TypeError(f"check_signs must be True or False, got {check_signs!r}")
    if record is not None and not isinstance(record, dict):
        raise TypeError(f"record must be a dict, got {type(record).__name__}")
    if actuator.type == "cylinder" and "contraction" in profile.channels:
        raise MeasuredDataError("a cylinder's profile maps 'position' (the rod position), not "
                                "'contraction'")
    record = dict(record or {})
    if "pressure_nominal" in record:
        record["pressure_nominal"] = check_nominal_pressure(
            "record pressure_nominal", quantity("record pressure_nominal",
                                                record["pressure_nominal"], "Pa"))
    src = str(p)
    text, raw = _open_text(p)
    sha = hashlib.sha256(raw).hexdigest()
    df, first_line = _table(text, profile, src)
    notes = []
    units = dict(profile.columns)
    ureg = unit_registry()

    def line(k):
        return f"row {k} (line {first_line + k})"

    # numbers, units, signs, offsets
    out = {}
    for ch, m in profile.channels.items():
        s = df[m.column]
        num = pd.to_numeric(s.str.strip(), errors="coerce")
        bad = np.flatnonzero(num.isna().to_numpy() & s.notna().to_numpy()
                             & (s.fillna("").str.strip().str.lower() != "nan").to_numpy())
        if bad.size:
            k = int(bad[0])
            raise MeasuredDataError(f"{src}: column {m.column!r} (channel '{ch}'), {line(k)}: "
                                    f"{s.iloc[k]!r} is not a number ({bad.size} such value(s))")
        unit = _unit(f"profile column {m.column!r}", units[m.column])
        x = num.to_numpy(float, copy=True)
        si = CHANNEL_SI[ch] or "dimensionless"
        fin = np.isfinite(x)
        x[fin] = ureg.Quantity(x[fin], unit).to(si).magnitude
        x = m.sign * x + m.offset
        out[ch] = x
    n_read = len(df)
    keep = np.ones(n_read, bool)
    for ch, x in out.items():
        bad = ~np.isfinite(x)
        if bad.any():
            idx = np.flatnonzero(bad)
            notes.append(f"column {profile.channels[ch].column!r} (channel '{ch}'): {idx.size} "
                         f"missing value(s) (first at {line(int(idx[0]))}); those rows are "
                         f"dropped and the record is split there")
            keep &= ~bad
    rows = np.flatnonzero(keep)
    if rows.size < 10:
        raise MeasuredDataError(f"{src}: only {rows.size} complete row(s)")
    t_raw = out["t"][rows]
    dt = np.diff(t_raw)
    tcol = profile.channels["t"].column
    if np.any(dt == 0):
        k = int(np.flatnonzero(dt == 0)[0])
        raise MeasuredDataError(f"{src}: column {tcol!r} (time) repeats: {line(int(rows[k]))} and "
                                f"{line(int(rows[k + 1]))} have the same time {df[tcol].iloc[rows[k]]} "
                                f"{units[tcol]} ({int(np.sum(dt == 0))} duplicate(s)); remove the "
                                f"duplicated rows")
    if np.any(dt < 0):
        k = int(np.flatnonzero(dt < 0)[0])
        raise MeasuredDataError(f"{src}: column {tcol!r} (time) goes backwards: "
                                f"{line(int(rows[k]))} has {df[tcol].iloc[rows[k]]}, "
                                f"{line(int(rows[k + 1]))} has {df[tcol].iloc[rows[k + 1]]} "
                                f"{units[tcol]} ({int(np.sum(dt < 0))} such step(s))")
    # gaps: segments; short ones (start-up rows) dropped
    med = float(np.median(dt))
    cut = np.flatnonzero(dt > profile.gap_factor * med) + 1
    bounds = np.concatenate([[0], cut, [rows.size]])
    segs = [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]
    short = [(a, b) for a, b in segs if b - a < profile.min_segment_rows]
    segs = [(a, b) for a, b in segs if b - a >= profile.min_segment_rows]
    if not segs:
        raise MeasuredDataError(f"{src}: no gap-free segment of at least "
                                f"{profile.min_segment_rows} rows (gap_factor = "
                                f"{profile.gap_factor:g})")
    if cut.size:
        gl = ", ".join(f"{1e3 * dt[c - 1]:.0f} ms before {line(int(rows[c]))}" for c in cut[:6])
        notes.append(f"{cut.size} gap(s) in {tcol!r} (intervals > {profile.gap_factor:g} x the "
                     f"median {1e3 * med:.4g} ms): {gl}{' ...' if cut.size > 6 else ''}; the "
                     f"record is split there")
    if short:
        notes.append(f"dropped {len(short)} segment(s) shorter than {profile.min_segment_rows} "
                     f"rows ({sum(b - a for a, b in short)} row(s): "
                     + ", ".join(f"rows {rows[a]}..{rows[b - 1]}" for a, b in short[:4])
                     + "), e.g. start-up rows before a first long interval")
    sel = np.concatenate([np.arange(a, b) for a, b in segs])
    idx = rows[sel]
    data = {ch: out[ch][idx] for ch in out}
    t0 = float(data["t"][0])
    data["t"] = data["t"] - t0
    # segments in the kept rows
    seg_bounds, n = [], 0
    for a, b in segs:
        seg_bounds.append((n, n + b - a))
        n += b - a
    jit = np.diff(data["t"])
    spread = float(np.quantile(jit, 0.95) / np.quantile(jit, 0.05)) if jit.size > 20 else 1.0
    if spread > 1.2:
        notes.append(f"non-uniform sampling (5-95 % of the intervals {1e3 * np.quantile(jit, 0.05):.3g}"
                     f"-{1e3 * np.quantile(jit, 0.95):.3g} ms, median {1e3 * med:.3g} ms): the "
                     f"actual times are used")
    # tare
    for ch, m in profile.channels.items():
        if m.zero:
            z = float(data[ch][0])
            data[ch] = data[ch] - z
            notes.append(f"channel '{ch}' tared: the first sample ({z:.6g} {CHANNEL_SI[ch]}) "
                         f"subtracted")
    # pressure reference
    pcol = profile.channels["pressure"].column
    if profile.pressure_reference == "absolute":
        if np.min(data["pressure"]) < 0:
            k = int(np.argmin(data["pressure"]))
            raise MeasuredDataError(f"{src}: column {pcol!r} is declared absolute but reaches "
                                    f"{data['pressure'][k]:.6g} Pa < 0 ({line(int(idx[k]))})")
        data["pressure"] = data["pressure"] - profile.p_atm
        notes.append(f"pressure column {pcol!r} is absolute: p_atm = {profile.p_atm:g} Pa "
                     f"subtracted (gauge pressure)")
    if np.min(data["pressure"]) < -profile.p_atm:
        k = int(np.argmin(data["pressure"]))
        raise MeasuredDataError(f"{src}: column {pcol!r} reaches a gauge pressure of "
                                f"{data['pressure'][k]:.6g} Pa, below vacuum (-{profile.p_atm:g} "
                                f"Pa) at {line(int(idx[k]))}: check its unit, offset and "
                                f"pressure_reference")
    # despike
    despiked = {}
    for ch in profile.despike:
        reps = []
        for a, b in seg_bounds:
            x, k = despike(data["t"][a:b], data[ch][a:b], profile.despike_sigmas)
            data[ch][a:b] = x
            reps += list(a + k)
        if reps:
            col = profile.channels[ch].column
            amp = np.abs(out[ch][idx[reps]] - data[ch][reps])
            despiked[ch] = {"count": len(reps), "rows": [int(idx[k]) for k in reps[:50]],
                            "largest": float(amp.max())}
            notes.append(f"despiked column {col!r} (channel '{ch}'): {len(reps)} isolated "
                         f"one-sample spike(s) (largest {amp.max():.3g} {CHANNEL_SI[ch]}, first "
                         f"at {line(int(idx[reps[0]]))}) replaced by the line through their "
                         f"neighbours")
    frame = pd.DataFrame({"t": data["t"], "force": data["force"], "pressure": data["pressure"],
                          **({"position": data["position"]} if "position" in data else
                             {"contraction": data["contraction"]})})
    am = actuator.meta()
    # sign checks
    wch = "position" if "position" in data else "contraction"
    if actuator.type == "muscle" and wch == "position":
        w = -data["position"]                      # contraction grows as the length falls
        law = am["force_law"]
        if "l0" not in law:
            raise MeasuredDataError("a muscle with a position (length) column needs actuator l0")
        eps = (law["l0"] - data["position"]) / law["l0"]
    else:
        w = data[wch]
        eps = data[wch] if wch == "contraction" else None
    a = np.asarray(am["force_law"]["a"], float)
    if actuator.type == "cylinder":
        f_nom = a[1] * data["pressure"]
    else:
        e = eps
        with np.errstate(divide="ignore", invalid="ignore"):
            f_nom = data["pressure"] * ((a[0] / e if a[0] else 0.0) + a[1]
                                        + e * (a[2] + e * (a[3] + e * a[4])))
    checks = {}
    if check_signs:
        fcol = profile.channels["force"].column
        ok = np.isfinite(f_nom)
        fn, fm = float(np.median(f_nom[ok])), float(np.median(data["force"][ok]))
        checks["force_over_law_median"] = fm / fn if fn != 0 else math.nan
        if fn != 0 and abs(fn) > 1e-3 and fm / fn < -0.3:
            raise MeasuredDataError(
                f"{src}: sign mismatch: the force column {fcol!r} is opposite to the pressure "
                f"force (median force {fm:.4g} N, nominal law {fn:.4g} N): the format wants the "
                f"actuator's force on the load positive (a cylinder: compression, a muscle: "
                f"tension); set sign = -1 for channel 'force' (or check the pressure column "
                f"{pcol!r})")
        per = np.concatenate([dissipation_by_stroke(data["t"][a_:b_], w[a_:b_],
                                                    (data["force"] - f_nom)[a_:b_])
                              for a_, b_ in seg_bounds])
        checks["strokes"] = int(per.size)
        if per.size >= SIGN_CHECK_STROKES:
            neg = float(np.mean(per < 0))
            checks["dissipation_median_N"] = float(np.median(per))
            checks["strokes_giving_energy_back"] = neg
            if neg >= SIGN_CHECK_FRACTION:
                wcol = profile.channels[wch].column
                raise MeasuredDataError(
                    f"{src}: sign mismatch between force and {wch}: with these signs the "
                    f"actuator would give energy back on {100 * neg:.0f} % of its {per.size} "
                    f"strokes (median {np.median(per):+.3g} N; friction and hysteresis take "
                    f"energy out, so it must be > 0).  The format's {wch} grows as "
                    + ("the pressure extends the rod" if actuator.type == "cylinder" else
                       "the muscle contracts") + f": set sign = -1 for column {wcol!r} "
                    f"(or, if the force is the one flipped, for {fcol!r}); import with "
                    f"check_signs=False to keep them")
        else:
            notes.append(f"sign check: only {per.size} stroke(s) of the motion (< "
                         f"{SIGN_CHECK_STROKES}): the dissipation sign was not checked")
    imp = {"file": p.name, "sha256": sha, "rows_read": int(n_read),
           "rows_kept": int(idx.size), "first_time": t0,
           "profile": profile.to_dict(), "despiked": despiked, "checks": checks,
           "notes": list(notes)}
    meta = {"kind": "actuator", "experiment": experiment,
            "description": description or f"{p.name} imported with profile "
                                          f"{profile.name or '(unnamed)'}",
            "source": source or f"{p.name} (sha256 {sha[:16]}...)",
            "gap_factor": float(profile.gap_factor), **am, "import": imp}
    if record:
        meta["record"] = record
    md = MeasuredData(meta, frame, source=src)
    object.__setattr__(md, "notes", tuple(notes) + md.notes)
    return md


def import_notes(data) -> list:
    """The notes of an import stored in a record's metadata (``[import] notes``; empty if none).

    Parameters
    ----------
    data : MeasuredData
    """
    imp = data.meta.get("import", {})
    return list(imp.get("notes", [])) if isinstance(imp, dict) else []


__all__ = ["BenchProfile", "ChannelMap", "Actuator", "import_bench", "despike", "quantity",
           "unit_registry", "dissipation_by_stroke", "import_notes", "CHANNEL_DIMENSIONS",
           "PRESSURE_REFERENCES", "DELIMITERS"]
