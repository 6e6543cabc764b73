"""Measured data: the file format, its loader and its validation.

A record is one table of samples (CSV, or Parquet when ``pyarrow`` is
installed) plus a small TOML metadata block, either as a sidecar file next to
it (``DATA.toml`` for ``DATA.csv``/``DATA.parquet``) or, for CSV only, as
commented TOML lines (``# key = value``) at the top of the file.  The full
specification with a worked example is ``docs/measured_data.md``.

Columns (SI units only; the package converts nothing):

* always ``t`` [s];
* arm (``kind = "arm"``): ``q1, q2`` [rad], ``qd1, qd2`` [rad/s], gauge
  pressures ``p1..p4`` [Pa], valve set values ``u1..u4`` [Pa], muscle forces
  ``F1..F4`` [N], closed-loop set angles ``q1_d, q2_d`` [rad];
* single actuator on a tester (``kind = "actuator"``): ``force`` [N],
  ``pressure`` [Pa gauge], ``contraction`` [-] or ``position`` [m] (a muscle:
  its length, eps = (l0 - position)/l0 with ``force_law.l0``; a cylinder,
  ``[actuator] type = "cylinder"``: the rod position, growing as the
  pressure extends the rod).

Raw bench files (other units, signs, offsets, no header) are converted by
:mod:`ppamsafety.data.bench_import`; several records of one actuator form a
campaign (:mod:`ppamsafety.data.campaign`).

Loading validates everything (see :class:`MeasuredData`); bad data raise
:class:`MeasuredDataError` (a ``ValueError``) naming the file, the column and
the row; harmless oddities (unknown columns or metadata keys) give a
:class:`MeasuredDataWarning` and are kept.
"""

from __future__ import annotations

import copy
import importlib.util
import json
import math
import numbers
import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..experiments.catalog import (THESIS_KI_BAR, THESIS_LAMBDAS, label_of, EXPERIMENTS as NAMED,
                                   Family)
from .._inputfiles import check_input_file, read_text
from ..output import atomic_write, check_new_file
from ..params.geometry import thesis_geometry

#: Version of the format written by :meth:`MeasuredData.save` (``format_version`` key).
FORMAT_VERSION = 1
KINDS = ("arm", "actuator")
EXPERIMENTS = ("static-sawtooth", "open-loop", "closed-loop", "tensile")
#: Experiments allowed for each kind.
ALLOWED = {"arm": ("static-sawtooth", "open-loop", "closed-loop"),
           "actuator": ("tensile", "open-loop")}

TIME_UNIT = "s"
ARM_CHANNELS = {"q1": "rad", "q2": "rad", "qd1": "rad/s", "qd2": "rad/s",
                **{f"p{i}": "Pa" for i in range(1, 5)}, **{f"u{i}": "Pa" for i in range(1, 5)},
                **{f"F{i}": "N" for i in range(1, 5)}, "q1_d": "rad", "q2_d": "rad"}
ACTUATOR_CHANNELS = {"force": "N", "pressure": "Pa", "contraction": "-", "position": "m"}
CHANNELS = {"arm": ARM_CHANNELS, "actuator": ACTUATOR_CHANNELS}

Q, QD = ("q1", "q2"), ("qd1", "qd2")
P = tuple(f"p{i}" for i in range(1, 5))
U = tuple(f"u{i}" for i in range(1, 5))
F = tuple(f"F{i}" for i in range(1, 5))
Q_D = ("q1_d", "q2_d")

#: Largest measured data file read [bytes]: 512 MB of CSV, about 4 million rows of the 13
#: columns of an arm record (more than an hour at 1 kHz); its table takes several times
#: that in memory while it is parsed and checked.
MAX_FILE_BYTES = 512 * 2 ** 20
#: Fewest rows of a record per experiment (gravity: 4 parameters from 2 N equations;
#: muscle law: 5 parameters; a dynamic record needs at least some samples to filter).
MIN_ROWS = {"static-sawtooth": 3, "tensile": 6, "open-loop": 10, "closed-loop": 10}
#: Experiments whose records must be uniformly sampled (time series).
UNIFORM = ("open-loop", "closed-loop")
#: Relative tolerance of the sampling interval around its median.
DT_TOLERANCE = 0.05
#: An interval longer than this many median intervals is a gap.
GAP_FACTOR = 1.5

_META_KEYS = ("format_version", "kind", "experiment", "description", "source", "sample_rate",
              "units", "controller", "reference", "force_law", "actuator", "gap_factor",
              "import", "record", "arm")
#: Actuator types of ``[actuator] type`` (default "muscle").
ACTUATOR_TYPES = ("muscle", "cylinder")
#: Declared units that are not SI, with the factor to SI and the SI unit.
_NON_SI = {"bar": (1e5, "Pa"), "mbar": (100.0, "Pa"), "kpa": (1e3, "Pa"), "mpa": (1e6, "Pa"),
           "psi": (6894.757, "Pa"), "deg": (math.pi / 180, "rad"),
           "degree": (math.pi / 180, "rad"), "degrees": (math.pi / 180, "rad"),
           "deg/s": (math.pi / 180, "rad/s"), "mm": (1e-3, "m"), "cm": (1e-2, "m"),
           "ms": (1e-3, "s"), "kn": (1e3, "N"), "%": (0.01, "-")}
_DIMENSIONLESS = ("-", "1", "")
#: Standard atmosphere [Pa]: a gauge pressure cannot be below -P_ATM_STD.
P_ATM_STD = 101325.0


class MeasuredDataError(ValueError):
    """A measured data set is not valid; the message names the file, column and row."""


class MeasuredDataWarning(UserWarning):
    """Something unusual but usable in a measured data set (kept as it is)."""


# --------------------------------------------------------------------------- metadata

def _toml_value(v, where: str) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, numbers.Integral):
        return str(int(v))
    if isinstance(v, numbers.Real):
        x = float(v)
        if not math.isfinite(x):
            raise MeasuredDataError(f"metadata {where} = {x} cannot be written (not finite)")
        return repr(x)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x, f"{where}[{i}]") for i, x in enumerate(v)) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(x, f'{where}.{k}')}"
                               for k, x in v.items()) + "}"
    raise MeasuredDataError(f"metadata {where} = {v!r} cannot be written as TOML "
                            f"(allowed: str, number, bool, lists and tables of them)")


def _toml_key(k) -> str:
    k = str(k)
    if k and all(c.isalnum() or c in "_-" for c in k):
        return k
    return json.dumps(k, ensure_ascii=False)


def dumps_toml(meta: dict) -> str:
    """Metadata as TOML text (scalars first, then one ``[table]`` per dict value).

    Parameters
    ----------
    meta : dict
        Metadata: str/number/bool values, lists of them, tables (dicts) whose
        values may again be tables (written inline).

    Returns
    -------
    str
    """
    if not isinstance(meta, dict):
        raise TypeError(f"meta must be a dict, got {type(meta).__name__}")
    lines, tables = [], []
    for k, v in meta.items():
        if isinstance(v, dict):
            tables.append((k, v))
        else:
            lines.append(f"{_toml_key(k)} = {_toml_value(v, str(k))}")
    for k, v in tables:
        lines.append(f"\n[{_toml_key(k)}]")
        lines += [f"{_toml_key(kk)} = {_toml_value(vv, f'{k}.{kk}')}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


def _parse_toml(text: str, where: str) -> dict:
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise MeasuredDataError(f"{where}: the metadata is not valid TOML: {exc}") from None


def _thesis_variant_labels() -> tuple:
    labels = ["PID"]
    labels += [label_of("PSMC joint", ki, lam) for ki in THESIS_KI_BAR for lam in THESIS_LAMBDAS]
    labels += [label_of("PSMC task", math.nan, lam) for lam in THESIS_LAMBDAS]
    return tuple(labels)


def _finite_number(where: str, v) -> float:
    if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(float(v)):
        raise MeasuredDataError(f"{where} = {v!r} must be a finite number")
    return float(v)


def _check_meta(meta: dict, src: str, columns, warn) -> dict:
    """Validate the metadata; return a deep copy."""
    if not isinstance(meta, dict):
        raise TypeError(f"meta must be a dict, got {type(meta).__name__}")
    meta = copy.deepcopy(meta)
    for key in ("kind", "experiment"):
        if key not in meta:
            raise MeasuredDataError(f"{src}: metadata has no '{key}' (required; allowed: "
                                    f"{', '.join(map(repr, KINDS if key == 'kind' else EXPERIMENTS))})")
    kind, exp = meta["kind"], meta["experiment"]
    if kind not in KINDS:
        raise MeasuredDataError(f"{src}: metadata kind = {kind!r} is not one of "
                                f"{', '.join(map(repr, KINDS))}")
    if exp not in EXPERIMENTS:
        raise MeasuredDataError(f"{src}: metadata experiment = {exp!r} is not one of "
                                f"{', '.join(map(repr, EXPERIMENTS))}")
    if exp not in ALLOWED[kind]:
        raise MeasuredDataError(f"{src}: experiment = {exp!r} is not allowed for kind = {kind!r} "
                                f"(allowed: {', '.join(map(repr, ALLOWED[kind]))})")
    if "format_version" in meta and meta["format_version"] != FORMAT_VERSION:
        raise MeasuredDataError(f"{src}: format_version = {meta['format_version']!r} is not "
                                f"supported (this version reads {FORMAT_VERSION})")
    for key in ("description", "source"):
        if key in meta and not isinstance(meta[key], str):
            raise MeasuredDataError(f"{src}: metadata {key} must be a string, got {meta[key]!r}")
    if "sample_rate" in meta:
        r = _finite_number(f"{src}: metadata sample_rate [Hz]", meta["sample_rate"])
        if r <= 0:
            raise MeasuredDataError(f"{src}: metadata sample_rate = {r:g} Hz must be > 0")
    if "gap_factor" in meta:
        g = _finite_number(f"{src}: metadata gap_factor", meta["gap_factor"])
        if not g > 1.0:
            raise MeasuredDataError(f"{src}: metadata gap_factor = {g:g} must be > 1 (an "
                                    f"interval longer than gap_factor x the median is a gap)")
    for key in ("import", "record"):
        if key in meta and not isinstance(meta[key], dict):
            raise MeasuredDataError(f"{src}: metadata {key} must be a table, got {meta[key]!r}")
    if isinstance(meta.get("record"), dict) and "pressure_nominal" in meta["record"]:
        check_nominal_pressure(f"{src}: metadata record.pressure_nominal",
                               meta["record"]["pressure_nominal"])
    if "units" in meta:
        _check_units(meta["units"], src, kind)
    # closed loop: controller and reference
    if exp == "closed-loop":
        _check_controller(meta.get("controller"), src)
        _stray(meta["controller"], ("variant", "family", "gains", "name"), "controller", src,
               warn)
        ref = meta.get("reference")
        has_cols = all(c in columns for c in Q_D)
        if ref is None or ref == "columns":
            if not has_cols:
                raise MeasuredDataError(
                    f"{src}: a closed-loop record needs its reference: metadata reference = one "
                    f"of {', '.join(map(repr, NAMED))} (a thesis experiment) or the columns "
                    f"q1_d, q2_d [rad]")
        else:
            if ref not in NAMED:
                raise MeasuredDataError(f"{src}: metadata reference = {ref!r} is not a thesis "
                                        f"experiment ({', '.join(map(repr, NAMED))}) nor "
                                        f"'columns'")
            if has_cols:
                raise MeasuredDataError(f"{src}: the reference is given twice (reference = "
                                        f"{ref!r} and columns q1_d, q2_d); keep one")
    else:
        for key in ("controller", "reference"):
            if key in meta:
                warn(f"{src}: metadata '{key}' is used only for closed-loop records (kept)")
    if kind == "actuator":
        atype = _check_actuator(meta.get("actuator"), src)
        _check_force_law(meta.get("force_law"), src, "position" in columns and atype == "muscle")
        _stray(meta["force_law"], ("a", "l0", "name"), "force_law", src, warn)
        if atype == "cylinder":
            _check_cylinder_law(meta, src, "contraction" in columns)
            _stray(meta["actuator"], ("type", "bore", "name"), "actuator", src, warn)
    else:
        for key in ("force_law", "actuator"):
            if key in meta:
                warn(f"{src}: metadata '{key}' is used only for kind = 'actuator' (kept)")
    if "arm" in meta:
        _check_arm_record(meta["arm"], src)
        _stray(meta["arm"], ("name", "sha256"), "arm", src, warn)
        if kind != "arm":
            warn(f"{src}: metadata 'arm' is used only for kind = 'arm' records (kept)")
    unknown = [k for k in meta if k not in _META_KEYS]
    if unknown:
        warn(f"{src}: unknown metadata key(s) {', '.join(map(repr, unknown))} (kept)")
    return meta


def check_nominal_pressure(where: str, value) -> float:
    """A record's nominal gauge pressure [Pa]: a number in [-1 atm, the actuator maximum].

    Parameters
    ----------
    where : str
        The field, for the message.
    value : float
        The pressure [Pa] (a number; a campaign manifest's "3 bar" is converted before).
    """
    hi = PLAUSIBILITY["actuator"]["pressure"][1]
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or \
            not math.isfinite(float(value)):
        raise MeasuredDataError(f"{where} = {value!r} must be a finite gauge pressure [Pa]")
    if not -P_ATM_STD <= float(value) <= hi:
        raise MeasuredDataError(f"{where} = {float(value):g} Pa is physically impossible: a gauge "
                                f"pressure is in [-1 atm, {hi / 1e5:g} bar] = [{-P_ATM_STD:g}, "
                                f"{hi:g}] Pa")
    return float(value)


def _check_arm_record(arm, src):
    """The ``[arm]`` table of a record: which arm file it came from (name, sha256)."""
    if not isinstance(arm, dict):
        raise MeasuredDataError(f"{src}: metadata arm must be a table (name = \"...\", "
                                f"sha256 = \"...\"), got {arm!r:.60}")
    if "sha256" not in arm:
        raise MeasuredDataError(f"{src}: metadata arm needs sha256 (the fingerprint of the "
                                f"arm file, ppamsafety.params.arm_file.arm_fingerprint)")
    h = arm["sha256"]
    if not (isinstance(h, str) and len(h) == 64 and all(c in "0123456789abcdef" for c in h)):
        raise MeasuredDataError(f"{src}: metadata arm.sha256 = {h!r} must be 64 lower-case hex "
                                f"digits")
    if not isinstance(arm.get("name", ""), str):
        raise MeasuredDataError(f"{src}: metadata arm.name = {arm['name']!r} must be a string")


def _stray(table: dict, known, name, src, warn):
    extra = [k for k in table if k not in known]
    if extra:
        warn(f"{src}: unknown key(s) {', '.join(map(repr, extra))} in [{name}] (kept; a TOML key "
             f"written after a [table] header belongs to that table: put top-level keys first)")


def _check_units(units, src, kind):
    if not isinstance(units, dict):
        raise MeasuredDataError(f"{src}: metadata units must be a table (column = \"unit\"), "
                                f"got {units!r}")
    known = {"t": TIME_UNIT, **CHANNELS[kind]}
    for col, u in units.items():
        if not isinstance(u, str):
            raise MeasuredDataError(f"{src}: units.{col} must be a string, got {u!r}")
        if col not in known:
            continue                               # free unit for an extra column
        want = known[col]
        ok = u.strip() in _DIMENSIONLESS if want == "-" else u.strip() == want
        if not ok:
            hint = ""
            conv = _NON_SI.get(u.strip().lower())
            if conv is not None:
                hint = f"; convert: value [{conv[1]}] = value [{u}] * {conv[0]:g}"
            raise MeasuredDataError(f"{src}: column {col!r} is declared in {u!r}, but the format "
                                    f"is SI only: {col} must be in {want!r}{hint}")


def _check_controller(ctrl, src):
    if not isinstance(ctrl, dict):
        raise MeasuredDataError(
            f"{src}: a closed-loop record needs a [controller] table: variant = a thesis variant "
            f"(e.g. 'PID', 'PSMC joint Ki=2 λ=0.4'), or family = ... with a gains table; "
            f"got {ctrl!r}")
    if "variant" in ctrl:
        labels = _thesis_variant_labels()
        if ctrl["variant"] not in labels:
            raise MeasuredDataError(f"{src}: controller.variant = {ctrl['variant']!r} is not a "
                                    f"thesis variant; allowed: {', '.join(map(repr, labels))}")
        if "family" in ctrl:
            raise MeasuredDataError(f"{src}: give controller.variant or controller.family, "
                                    f"not both")
        return

    fams = [f.value for f in Family]
    if ctrl.get("family") not in fams:
        raise MeasuredDataError(f"{src}: controller.family = {ctrl.get('family')!r} is not one "
                                f"of {', '.join(map(repr, fams))} (or give controller.variant)")
    gains = ctrl.get("gains")
    if not isinstance(gains, dict) or not gains:
        raise MeasuredDataError(f"{src}: controller.gains must be a non-empty table of SI gains "
                                f"(name = number or [number, number]), got {gains!r}")
    for k, g in gains.items():
        vals = g if isinstance(g, list) else [g]
        for v in vals:
            _finite_number(f"{src}: controller.gains.{k}", v)


def _check_actuator(act, src) -> str:
    """The ``[actuator]`` table (optional; default a muscle); returns its type."""
    if act is None:
        return "muscle"
    if not isinstance(act, dict):
        raise MeasuredDataError(f"{src}: metadata actuator must be a table (type = "
                                f"{' | '.join(map(repr, ACTUATOR_TYPES))}), got {act!r}")
    atype = act.get("type", "muscle")
    if atype not in ACTUATOR_TYPES:
        raise MeasuredDataError(f"{src}: actuator.type = {atype!r} is not one of "
                                f"{', '.join(map(repr, ACTUATOR_TYPES))}")
    if "bore" in act:
        b = _finite_number(f"{src}: actuator.bore [m]", act["bore"])
        if not 0 < b <= 1.0:
            raise MeasuredDataError(f"{src}: actuator.bore = {b:g} m is outside (0, 1] m"
                                    f"{' (mm? give metres)' if b > 1 else ''}")
    return atype


def _check_cylinder_law(meta, src, has_contraction):
    """A cylinder's force law is F = p A: a = [0, A, 0, 0, 0] with A > 0 (and the bore's area)."""
    a = meta["force_law"]["a"]
    if a[1] <= 0 or any(a[j] != 0 for j in (0, 2, 3, 4)):
        raise MeasuredDataError(f"{src}: a cylinder's force law is F = p A: force_law.a must be "
                                f"[0, A, 0, 0, 0] with A > 0 [m^2], got {a}")
    bore = meta["actuator"].get("bore")
    if bore is not None:
        area = math.pi / 4 * float(bore) ** 2
        if abs(a[1] - area) > 1e-6 * area:
            raise MeasuredDataError(f"{src}: actuator.bore = {bore:g} m gives A = {area:.6g} m^2, "
                                    f"but force_law.a[1] = {a[1]:.6g} m^2; give one or make them "
                                    f"agree")
    if has_contraction:
        raise MeasuredDataError(f"{src}: a cylinder record gives its rod position in 'position' "
                                f"[m], not a 'contraction'")


def _check_force_law(law, src, has_position):
    if not isinstance(law, dict):
        raise MeasuredDataError(
            f"{src}: an actuator record needs its nominal force law: [force_law] a = [a0, a1, a2, "
            f"a3, a4] in N/Pa (thesis (3.9); a cylinder: a = [0, A, 0, 0, 0]), l0 = ... [m]; "
            f"got {law!r}")
    a = law.get("a")
    if not isinstance(a, list) or len(a) != 5:
        raise MeasuredDataError(f"{src}: force_law.a must be a list of 5 coefficients a0..a4 "
                                f"[N/Pa], got {a!r}")
    a = [_finite_number(f"{src}: force_law.a[{i}]", x) for i, x in enumerate(a)]
    if a[0] < 0:
        raise MeasuredDataError(f"{src}: force_law.a[0] = {a[0]:g} N/Pa must be >= 0 (the 1/eps "
                                f"term pulls)")
    if not any(a):
        raise MeasuredDataError(f"{src}: force_law.a = {a}: every coefficient is 0, a law of "
                                f"no force; give the actuator's nominal law (3.9) in N/Pa")
    if max(abs(x) for x in a) > 1.0:
        raise MeasuredDataError(f"{src}: force_law.a = {a} looks like N/bar or N/kPa (a |a_i| "
                                f"> 1 N/Pa = 1 m^2); give N/Pa (N/bar * 1e-5)")
    if "l0" in law:
        l0 = _finite_number(f"{src}: force_law.l0 [m]", law["l0"])
        if not 0 < l0 <= 1.0:
            raise MeasuredDataError(f"{src}: force_law.l0 = {l0:g} m is outside (0, 1] m"
                                    f"{' (mm? give metres)' if l0 > 1 else ''}")
    elif has_position:
        raise MeasuredDataError(f"{src}: column 'position' needs force_law.l0 [m] (the "
                                f"uncontracted length) to give the contraction")


# --------------------------------------------------------------------------- columns

def _required(kind: str, exp: str) -> list:
    """Groups of required columns: each entry a list of alternatives (tuples of columns)."""
    if kind == "actuator":
        return [[("force",)], [("pressure",)], [("contraction",), ("position",)]]
    if exp == "static-sawtooth":
        return [[Q], [F, P]]
    if exp == "open-loop":
        return [[Q], [QD], [P]]
    return [[Q]]                                      # closed loop (reference checked in meta)


def _row_text(first, k: int) -> str:
    """'row k (line L)' for a CSV, 'row k' otherwise."""
    return f"row {k}" if first is None else f"row {k} (line {first + k})"


class _Ctx:
    """Where the data came from, for messages."""

    def __init__(self, source: str, first_line):
        self.src = source
        self.first_line = first_line      # file line of data row 0 (CSV), or None

    def row(self, k: int) -> str:
        return _row_text(self.first_line, int(k))


def _check_columns(df: pd.DataFrame, kind: str, exp: str, ctx: _Ctx, warn) -> pd.DataFrame:
    cols = [str(c).strip() for c in df.columns]
    dup = sorted({c for c in cols if cols.count(c) > 1})
    # pandas renames duplicates 'x' -> 'x.1'
    dup += sorted(c for c in cols if "." in c and c.rsplit(".", 1)[0] in cols
                  and c.rsplit(".", 1)[1].isdigit())
    if dup:
        raise MeasuredDataError(f"{ctx.src}: duplicate column(s) {', '.join(map(repr, dup))}")
    df = df.copy()
    df.columns = cols
    if "t" not in cols:
        sep = next((f"{name} ({c!r})" for c, name in ((";", "semicolons"), ("\t", "tabs"),
                                                      ("|", "bars"), (" ", "spaces"))
                    if any(c in x for x in cols)), None)
        hint = (f"; the header holds {sep} between the names: the format is CSV with ',' "
                f"between the values and '.' as the decimal point (a spreadsheet's "
                f"'CSV (semicolon)' export with decimal commas is not), re-export it"
                if sep else "")
        raise MeasuredDataError(f"{ctx.src}: no time column 't' [s] (columns: "
                                f"{', '.join(repr(c) for c in cols[:12]) or 'none'}){hint}")
    for group in _required(kind, exp):
        if not any(all(c in cols for c in alt) for alt in group):
            alts = " or ".join("(" + ", ".join(a) + ")" for a in group)
            missing = [c for c in group[0] if c not in cols]
            raise MeasuredDataError(f"{ctx.src}: a {kind} {exp} record needs the column(s) {alts}; "
                                    f"missing {', '.join(missing)} (columns present: "
                                    f"{', '.join(cols)})")
    known = {"t", *CHANNELS[kind]}
    unknown = [c for c in cols if c not in known]
    if unknown:
        warn(f"{ctx.src}: unknown column(s) {', '.join(map(repr, unknown))} for kind = {kind!r} "
             f"(kept, not used; known: t, {', '.join(CHANNELS[kind])})")
    for c in cols:
        if c not in known:
            continue
        s = df[c]
        if s.dtype.kind in "fiu":
            df[c] = s.astype(float)
            continue
        if s.dtype.kind == "b":
            raise MeasuredDataError(f"{ctx.src}: column {c!r} holds booleans, not numbers")
        num = pd.to_numeric(s, errors="coerce")
        bad = np.flatnonzero(num.isna().to_numpy() & s.notna().to_numpy())
        if bad.size:
            k = int(bad[0])
            raise MeasuredDataError(f"{ctx.src}: column {c!r}, {ctx.row(k)}: {s.iloc[k]!r} is "
                                    f"not a number ({bad.size} such value(s))")
        df[c] = num.astype(float)
    return df


def _first_rows(idx: np.ndarray, ctx: _Ctx, n: int = 3) -> str:
    more = ", ..." if idx.size > n else ""
    return ", ".join(ctx.row(k) for k in idx[:n]) + more


def _check_finite(df, channels, ctx, allow_gaps, warn):
    """Refuse NaN/inf in known channels, or drop those rows with ``allow_gaps``."""
    bad_rows = np.zeros(len(df), dtype=bool)
    report = []
    for c in channels:
        bad = ~np.isfinite(df[c].to_numpy())
        if bad.any():
            idx = np.flatnonzero(bad)
            report.append(f"{c}: {idx.size} NaN/inf (first at {_first_rows(idx, ctx)})")
            bad_rows |= bad
    if not report:
        return df, 0
    if not allow_gaps:
        raise MeasuredDataError(f"{ctx.src}: missing or non-finite values in "
                                f"{bad_rows.sum()} row(s): {'; '.join(report)}. Fix the data, or "
                                f"load with allow_gaps=True (--allow-gaps) to drop these rows "
                                f"and split the record at them")
    warn(f"{ctx.src}: dropped {int(bad_rows.sum())} row(s) with missing or non-finite values "
         f"({'; '.join(report)})")
    return df.loc[~bad_rows].reset_index(drop=True), int(bad_rows.sum())


def _check_time(t: np.ndarray, meta: dict, exp: str, ctx: _Ctx, allow_gaps, orig_rows, warn):
    """Monotonic t, uniform sampling, gaps; returns (segments, gaps, dt)."""
    d = np.diff(t)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        k = int(bad[0])
        r0, r1 = orig_rows[k], orig_rows[k + 1]
        raise MeasuredDataError(f"{ctx.src}: column 't' must increase strictly, but {ctx.row(r0)} "
                                f"has t = {t[k]:.9g} s and {ctx.row(r1)} has t = {t[k + 1]:.9g} s "
                                f"({bad.size} such step(s))")
    if d.size == 0:
        return ((0, t.size),), (), math.nan
    med = float(np.median(d))
    uniform = exp in UNIFORM or "sample_rate" in meta
    if "gap_factor" in meta and not uniform:
        # declared: intervals longer than gap_factor x the median are known gaps of a
        # jittered record (e.g. a software-timed logger); the record is split there
        gap_idx = np.flatnonzero(d > float(meta["gap_factor"]) * med)
        gaps = tuple((float(t[k]), float(t[k + 1])) for k in gap_idx)
        if gaps:
            listed = ", ".join(f"{a:.6g}..{b:.6g} s" for a, b in gaps[:5])
            more = f" and {len(gaps) - 5} more" if len(gaps) > 5 else ""
            warn(f"{ctx.src}: record split at {len(gaps)} gap(s) (intervals > gap_factor = "
                 f"{float(meta['gap_factor']):g} x the median {med:.6g} s): {listed}{more}")
        bounds = [0, *(int(k) + 1 for k in gap_idx), t.size]
        return tuple((bounds[i], bounds[i + 1]) for i in range(len(bounds) - 1)), gaps, med
    if not uniform:
        return ((0, t.size),), (), med
    gap_idx = np.flatnonzero(d > float(meta.get("gap_factor", GAP_FACTOR)) * med)
    regular = np.setdiff1d(np.arange(d.size), gap_idx)
    dev = np.abs(d[regular] - med) / med
    if dev.size and dev.max() > DT_TOLERANCE:
        j = int(regular[np.argmax(dev)])
        raise MeasuredDataError(
            f"{ctx.src}: column 't' is not uniformly sampled: the interval before "
            f"{ctx.row(orig_rows[j + 1])} (t = {t[j + 1]:.9g} s) is {d[j]:.6g} s, the median "
            f"{med:.6g} s (tolerance ±{100 * DT_TOLERANCE:g} %); resample the record")
    if "sample_rate" in meta:
        rate = float(meta["sample_rate"])
        if abs(1.0 / med - rate) > DT_TOLERANCE * rate:
            raise MeasuredDataError(f"{ctx.src}: metadata sample_rate = {rate:g} Hz, but the "
                                    f"median interval of 't' is {med:.6g} s ({1 / med:.6g} Hz)")
    gaps = tuple((float(t[k]), float(t[k + 1])) for k in gap_idx)
    if gaps:
        listed = ", ".join(f"{a:.6g}..{b:.6g} s" for a, b in gaps[:5])
        more = f" and {len(gaps) - 5} more" if len(gaps) > 5 else ""
        if not allow_gaps:
            raise MeasuredDataError(
                f"{ctx.src}: {len(gaps)} gap(s) in 't' (intervals > {GAP_FACTOR:g} x the median "
                f"{med:.6g} s): {listed}{more}. Load with allow_gaps=True (--allow-gaps) to split "
                f"the record at the gaps")
        warn(f"{ctx.src}: record split at {len(gaps)} gap(s): {listed}{more}")
    bounds = [0, *(int(k) + 1 for k in gap_idx), t.size]
    segments = tuple((bounds[i], bounds[i + 1]) for i in range(len(bounds) - 1))
    return segments, gaps, med


#: Physical plausibility per column: values outside ``impossible`` are refused
#: whatever ``strict_units`` says; values outside ``plausible`` give a one-line warning.
#: Ranges [SI], per kind: ``(impossible_lo, impossible_hi, plausible_lo, plausible_hi)``.
#: Gauge pressures cannot be below -1 atm (vacuum); a pneumatic muscle works below 8 bar
#: (the thesis PPAMs at up to 3 bar, 4 bar tolerated, §2.2.2; commercial fluidic muscles
#: 6-8 bar), so an arm pressure above 10 bar is impossible and one above 5 bar suspicious;
#: an actuator on a tester may be a cylinder (pneumatic cylinders are rated to 10-16 bar).
#: Joint angles of this arm lie within one turn (else: degrees); forces of a muscle of this
#: size stay far below 10^5 N (the thesis PPAMs pull up to about 5 kN at 3 bar).
PLAUSIBILITY = {
    "arm": {**{c: (-P_ATM_STD, 1.0e6, -2.0e4, 5.0e5) for c in P + U},
            **{c: (-2 * math.pi, 2 * math.pi, None, None) for c in Q + Q_D},
            **{c: (-1.0e3, 1.0e3, -50.0, 50.0) for c in QD},
            **{c: (-200.0, 1.0e5, -50.0, 2.0e4) for c in F}},
    "actuator": {"pressure": (-P_ATM_STD, 2.0e6, -2.0e4, 1.0e6),
                 "force": (-1.0e5, 1.0e5, -100.0, 5.0e4),
                 "contraction": (-1.0, 1.0, -0.1, 0.6),
                 "position": (0.0, math.inf, None, None)},
}
#: A cylinder's ``position`` is its rod position [m] with any zero (not a length): it may be
#: negative, but no bench cylinder travels 10 m (millimetres read as metres do).
CYLINDER_POSITION = (-10.0, 10.0, None, None)
#: Margin [rad] beyond the thesis arm's working area (2.6)-(2.7) at which a recorded angle
#: is called suspicious.
AREA_MARGIN = math.radians(10.0)
#: Why a value is impossible, per column group (for the messages).
_WHY = {"pressure": "a gauge pressure is at least -1 atm (vacuum) and no pneumatic muscle or "
                    "valve of this kind reaches {hi:g} Pa ({hib:g} bar)",
        "angle": "a joint angle of this arm lies within one turn (|q| <= 2 pi rad); degrees? "
                 "multiply by pi/180",
        "velocity": "a joint speed beyond 1000 rad/s (10^4 rpm) is no robot arm's",
        "force": "a muscle only pulls: a force below -200 N is a sign convention, not noise, "
                 "and no muscle of this size pulls 10^5 N",
        "actuator_force": "no actuator of this size pulls or pushes 10^5 N",
        "contraction": "a contraction eps = (l0 - l)/l0 lies in (-1, 1): at 1 the actuator "
                       "would have no length (percent? divide by 100)",
        "position": "the actuator's length must be positive",
        "rod_position": "no bench cylinder's rod travels 10 m (millimetres? divide by 1000)"}


def _plausible(kind: str, meta: dict) -> dict:
    """The :data:`PLAUSIBILITY` table of a record: a cylinder's position is not a length."""
    table = PLAUSIBILITY[kind]
    act = meta.get("actuator")
    if kind == "actuator" and isinstance(act, dict) and act.get("type") == "cylinder":
        table = {**table, "position": CYLINDER_POSITION}
    return table


def _group(c: str) -> str:
    if c in P + U or c == "pressure":
        return "pressure"
    if c in Q + Q_D:
        return "angle"
    if c in QD:
        return "velocity"
    if c in F:
        return "force"
    if c == "force":
        return "actuator_force"
    return c


def _plausibility(df, meta, ctx, strict, warn, orig_rows):
    """Refuse impossible values, hint at wrong units, warn about suspicious values.

    Three tiers per column (rows named as in the file):

    * impossible (:data:`PLAUSIBILITY`): refused whatever ``strict`` says;
    * looks like another unit (bar, degrees, deg/s, mm, percent): refused with
      ``strict``, else a warning (the historical unit hints);
    * suspicious (outside the plausible range, or the arm's working area): a warning.
    """
    kind = meta["kind"]
    if len(df) == 0:
        return
    cylinder = kind == "actuator" and _plausible(kind, meta)["position"] is CYLINDER_POSITION
    for c, (lo, hi, plo, phi) in _plausible(kind, meta).items():
        if c not in df.columns:
            continue
        x = df[c].to_numpy()
        # open bounds: a length > 0 (not a cylinder's rod position)
        openb = c == "contraction" or (c == "position" and not cylinder)
        bad = np.flatnonzero((x <= lo) | (x >= hi) if openb else (x < lo) | (x > hi))
        if bad.size:
            k = int(bad[np.argmax(np.abs(x[bad]))])
            group = "rod_position" if c == "position" and cylinder else _group(c)
            why = _WHY[group].format(hi=hi, hib=hi / 1e5)
            raise MeasuredDataError(
                f"{ctx.src}: column {c!r}, {ctx.row(orig_rows[k])}: {x[k]:.6g} is physically "
                f"impossible ({why}; allowed {'(' if openb else '['}{lo:.6g}, {hi:.6g}"
                f"{')' if openb else ']'} {CHANNELS[kind][c]}); {bad.size} such value(s)")
    if kind == "actuator" and "position" in df.columns and "l0" in meta.get("force_law", {}):
        l0 = float(meta["force_law"]["l0"])
        eps = (l0 - df["position"].to_numpy()) / l0
        bad = np.flatnonzero((eps <= -1.0) | (eps >= 1.0))
        if bad.size:
            k = int(bad[0])
            raise MeasuredDataError(
                f"{ctx.src}: column 'position', {ctx.row(orig_rows[k])}: "
                f"{df['position'].iloc[k]:.6g} m with force_law.l0 = {l0:g} m gives the "
                f"contraction {eps[k]:.4g}, physically impossible (allowed (-1, 1): the length "
                f"is between 0 and 2 l0); check l0 and the unit of 'position' [m]"
                f"{' (mm? multiply by 1e-3)' if np.max(df['position'].to_numpy()) > 1.0 else ''}"
                f" ({bad.size} such value(s))")
    # the historical unit hints (strict: refused; loose: warned)
    checks = []
    if kind == "arm":
        checks += [(c, "pressure") for c in P + U]
        checks += [(c, "velocity") for c in QD]
    else:
        checks += [("pressure", "pressure"), ("position", "position")]
    hinted = set()
    for c, what in checks:
        if c not in df.columns:
            continue
        x = np.abs(df[c].to_numpy())
        k = int(np.argmax(x))
        m = float(x[k])
        row = ctx.row(orig_rows[k])
        msg = None
        if what == "pressure" and 0.0 < m < 10.0:
            msg = (f"column {c!r} peaks at {m:.4g}, which looks like bar: the format wants Pa "
                   f"(gauge); multiply by 1e5")
        elif what == "velocity" and m > 50.0:
            msg = (f"column {c!r} reaches {df[c].iloc[k]:.4g} ({row}), which looks like "
                   f"deg/s (> 50 rad/s): the format wants rad/s; multiply by pi/180")
        elif what == "position" and m > 1.0:
            msg = (f"column {c!r} reaches {df[c].iloc[k]:.4g} ({row}), which looks like mm "
                   f"(> 1 m for an actuator): the format wants m; multiply by 1e-3")
        if msg is None and what == "pressure" and 10.0 <= m < 1.0e4 and all(
                10.0 <= np.max(np.abs(df[o].to_numpy())) < 1.0e4
                for o, w in checks if w == "pressure" and o in df.columns and o[0] == c[0]):
            # every pressure (or set value) column peaks below 0.1 bar: no arm or actuator
            # under load works so (one vented muscle is fine: the others are not)
            msg = (f"column {c!r} peaks at {m:.4g} Pa ({m / 1e5:.3g} bar), like every "
                   f"{'pressure' if c[0] != 'u' else 'set value'} column: kPa (multiply by "
                   f"1e3) or mbar/hPa (multiply by 100)? the format wants Pa (gauge)")
        if msg is not None:
            hinted.add(c)
            if strict:
                raise MeasuredDataError(f"{ctx.src}: {msg} (or load with strict_units=False if "
                                        f"the values are right)")
            warn(f"{ctx.src}: {msg}")
    # suspicious: one warning per column
    for c, (lo, hi, plo, phi) in _plausible(kind, meta).items():
        if c not in df.columns or c in hinted:
            continue
        x = df[c].to_numpy()
        if _group(c) == "pressure":
            m = float(np.max(np.abs(x)))
            if 10.0 <= m < 1.0e4:
                warn(f"{ctx.src}: column {c!r} peaks at {m:.4g} Pa ({m / 1e5:.3g} bar), too "
                     f"low for a pressurised muscle: kPa (x 1e3) or mbar/hPa (x 100)?")
                continue
        if plo is None:
            continue
        out = np.flatnonzero((x < plo) | (x > phi))
        if out.size:
            k = int(out[np.argmax(np.abs(x[out]))])
            warn(f"{ctx.src}: column {c!r} reaches {x[k]:.6g} {CHANNELS[kind][c]} "
                 f"({ctx.row(orig_rows[k])}), outside the plausible [{plo:g}, {phi:g}] "
                 f"{CHANNELS[kind][c]} ({out.size} value(s)); check the units and the sign")
    if kind == "arm":
        g = thesis_geometry()
        area = {"q1": (g.q1_min, g.q1_max), "q2": (g.q2_min, g.q2_max),
                "q1_d": (g.q1_min, g.q1_max), "q2_d": (g.q2_min, g.q2_max)}
        for c, (a, b) in area.items():
            if c not in df.columns:
                continue
            x = df[c].to_numpy()
            out = np.flatnonzero((x < a - AREA_MARGIN) | (x > b + AREA_MARGIN))
            if out.size:
                k = int(out[0])
                warn(f"{ctx.src}: column {c!r} reaches {x[k]:.4g} rad = "
                     f"{math.degrees(x[k]):.4g} deg ({ctx.row(orig_rows[k])}), outside the "
                     f"thesis arm's working area [{math.degrees(a):.4g}, {math.degrees(b):.4g}] "
                     f"deg by more than {math.degrees(AREA_MARGIN):g} deg ({out.size} "
                     f"value(s)): another arm, an offset, or degrees scaled?")


# --------------------------------------------------------------------------- the record

@dataclass(frozen=True, eq=False)
class MeasuredData:
    """One validated measured record: metadata and samples (SI units).

    Constructing it validates ``meta`` and ``frame`` (the same checks as
    :func:`load_measured`): kind and experiment; required columns per
    kind/experiment; unknown columns and metadata keys (warned, kept);
    declared units (SI only); values that look like bar, degrees, deg/s, mm
    or percent (refused, or warned with ``strict_units=False``); strictly
    increasing ``t``, uniform sampling for open/closed-loop records or when
    ``sample_rate`` is given (tolerance :data:`DT_TOLERANCE`), gaps
    (intervals > :data:`GAP_FACTOR` x median); NaN/inf in known channels;
    too few rows (:data:`MIN_ROWS`).

    Parameters
    ----------
    meta : dict
        Metadata (see ``docs/measured_data.md``); deep-copied.
    frame : pandas.DataFrame
        Samples, one column per channel; copied.
    allow_gaps : bool
        False (default): NaN/inf values and time gaps are errors.  True: rows
        with NaN/inf in a known channel are dropped and the record is split
        into :attr:`segments` at the resulting or existing gaps.
    strict_units : bool
        True (default): values that look like the wrong unit are errors;
        False: warnings.
    source : str
        Where the data came from (file name), used in messages.
    first_line : int, optional
        File line number of data row 0 (CSV), so messages can name lines.

    Attributes
    ----------
    segments : tuple of (int, int)
        Row ranges [start, stop) of the gap-free pieces (one unless
        ``allow_gaps`` split the record).
    gaps : tuple of (float, float)
        (t before, t after) of every gap [s].
    dropped_rows : int
        Rows dropped for NaN/inf.
    notes : tuple of str
        The warnings issued during validation.
    """

    meta: dict
    frame: pd.DataFrame = field(repr=False)
    allow_gaps: bool = False
    strict_units: bool = True
    source: str = "<data>"
    segments: tuple = field(init=False, default=())
    gaps: tuple = field(init=False, default=())
    dropped_rows: int = field(init=False, default=0)
    notes: tuple = field(init=False, default=(), repr=False)
    first_line: int | None = field(default=None, repr=False)

    def __post_init__(self):
        for nm in ("allow_gaps", "strict_units"):
            if not isinstance(getattr(self, nm), bool):
                raise TypeError(f"{nm} must be True or False, got {getattr(self, nm)!r}")
        if not isinstance(self.source, str):
            raise TypeError(f"source must be a str, got {type(self.source).__name__}")
        if self.first_line is not None and (isinstance(self.first_line, bool) or
                                            not isinstance(self.first_line, int)):
            raise TypeError(f"first_line must be an int or None, got {self.first_line!r}")
        if not isinstance(self.frame, pd.DataFrame):
            raise TypeError(f"frame must be a pandas DataFrame, got {type(self.frame).__name__}")
        notes = []

        def warn(msg):
            notes.append(msg)
            warnings.warn(msg, MeasuredDataWarning, stacklevel=4)

        ctx = _Ctx(self.source, self.first_line)
        meta = _check_meta(self.meta, ctx.src, [str(c).strip() for c in self.frame.columns], warn)
        kind, exp = meta["kind"], meta["experiment"]
        df = _check_columns(self.frame, kind, exp, ctx, warn)
        channels = [c for c in ("t", *CHANNELS[kind]) if c in df.columns]
        df["_row"] = np.arange(len(df))
        df, dropped = _check_finite(df, channels, ctx, self.allow_gaps, warn)
        orig_rows = df.pop("_row").to_numpy()
        n_min = MIN_ROWS[exp]
        if len(df) < n_min:
            extra = f" after dropping {dropped} row(s) with NaN/inf" if dropped else ""
            raise MeasuredDataError(f"{ctx.src}: the record is too short: {len(df)} row(s)"
                                    f"{extra}, a {exp} record needs at least {n_min}")
        segments, gaps, _ = _check_time(df["t"].to_numpy(), meta, exp, ctx, self.allow_gaps,
                                        orig_rows, warn)
        _plausibility(df, meta, ctx, self.strict_units, warn, orig_rows)
        object.__setattr__(self, "meta", meta)
        object.__setattr__(self, "frame", df)
        object.__setattr__(self, "segments", segments)
        object.__setattr__(self, "gaps", gaps)
        object.__setattr__(self, "dropped_rows", dropped)
        object.__setattr__(self, "notes", tuple(notes))

    # -- accessors --------------------------------------------------------------------
    @property
    def kind(self) -> str:
        """``"arm"`` or ``"actuator"``."""
        return self.meta["kind"]

    @property
    def experiment(self) -> str:
        """``"static-sawtooth"``, ``"open-loop"``, ``"closed-loop"`` or ``"tensile"``."""
        return self.meta["experiment"]

    @property
    def channels(self) -> tuple:
        """Known channels present (without ``t``), in the format's order."""
        return tuple(c for c in CHANNELS[self.kind] if c in self.frame.columns)

    @property
    def extra_columns(self) -> tuple:
        """Columns the format does not know (kept, not used)."""
        known = {"t", *CHANNELS[self.kind]}
        return tuple(c for c in self.frame.columns if c not in known)

    @property
    def dt(self) -> float:
        """Median sampling interval of ``t`` [s] (NaN for a single row)."""
        t = self.frame["t"].to_numpy()
        return float(np.median(np.diff(t))) if t.size > 1 else math.nan

    def __len__(self) -> int:
        return len(self.frame)

    def has(self, *columns) -> bool:
        """True if every one of ``columns`` is present.

        Parameters
        ----------
        *columns : str
            Column names.
        """
        return all(c in self.frame.columns for c in columns)

    def column(self, *names) -> np.ndarray:
        """Samples of one column (shape (N,)) or several (shape (N, k)), a float64 copy.

        Parameters
        ----------
        *names : str
            Column names.
        """
        missing = [n for n in names if n not in self.frame.columns]
        if missing or not names:
            raise KeyError(f"{self.source}: no column(s) {missing or names}; present: "
                           f"{', '.join(self.frame.columns)}")
        a = self.frame[list(names)].to_numpy(dtype=float, copy=True)
        return a[:, 0] if len(names) == 1 else a

    def segment_frames(self) -> list:
        """The gap-free pieces as DataFrames (copies)."""
        return [self.frame.iloc[a:b].reset_index(drop=True) for a, b in self.segments]

    @property
    def actuator_type(self) -> str:
        """``"muscle"`` or ``"cylinder"`` (``[actuator] type``) for an actuator record, else ``""``."""
        if self.kind != "actuator":
            return ""
        return self.meta.get("actuator", {}).get("type", "muscle")

    def contraction(self) -> np.ndarray:
        """Contraction of a muscle record [-]: the column, or (l0 - position)/l0."""
        if self.kind != "actuator":
            raise ValueError(f"{self.source}: contraction() is for actuator records, this is "
                             f"kind = {self.kind!r}")
        if self.actuator_type == "cylinder":
            raise ValueError(f"{self.source}: a cylinder has no contraction; its rod position "
                             f"is the column 'position' [m]")
        if self.has("contraction"):
            return self.column("contraction")
        l0 = float(self.meta["force_law"]["l0"])
        return (l0 - self.column("position")) / l0

    def nominal_force(self) -> np.ndarray:
        """Force of the nominal law (3.9) in the metadata at the recorded p, eps [N]."""
        a = np.asarray(self.meta["force_law"]["a"], dtype=float) if self.kind == "actuator" \
            else None
        if a is None:
            raise ValueError(f"{self.source}: nominal_force() is for actuator records")
        if self.actuator_type == "cylinder":
            return self.column("pressure") * a[1]
        e = self.contraction()
        if a[0] != 0.0 and np.any(e <= 0):
            raise ValueError(f"{self.source}: the force law has an a0/eps term but a contraction "
                             f"is <= 0 (min {e.min():g})")
        poly = (a[0] / e if a[0] != 0.0 else 0.0) + a[1] + e * (a[2] + e * (a[3] + e * a[4]))
        return self.column("pressure") * poly

    def to_pandas(self) -> pd.DataFrame:
        """The samples (a copy); the metadata in ``attrs["meta"]``."""
        df = self.frame.copy()
        df.attrs["meta"] = copy.deepcopy(self.meta)
        return df

    # -- writing ---------------------------------------------------------------------
    def save(self, path, *, overwrite: bool = False, sidecar: bool = False) -> Path:
        """Write the record in the format (never replacing a file unless asked).

        CSV (``.csv``): the metadata as a commented TOML header, or with
        ``sidecar=True`` as ``<stem>.toml`` next to it.  Parquet (``.parquet``,
        needs ``pyarrow``): always with the sidecar.  Written atomically
        through :mod:`ppamsafety.output`.

        Parameters
        ----------
        path : path-like
            Data file to write; its folder must exist.
        overwrite : bool, keyword-only
            Replace existing files.
        sidecar : bool, keyword-only
            CSV only: metadata in a sidecar file instead of the header.

        Returns
        -------
        pathlib.Path
            ``path``.
        """
        p, fmt, sidecar = _save_target(path, overwrite, sidecar)
        meta = {"format_version": FORMAT_VERSION, **self.meta}
        text = dumps_toml(meta)
        df = self.frame
        side = p.with_suffix(".toml")
        if fmt == "parquet":
            atomic_write(p, lambda tmp: df.to_parquet(tmp, index=False), overwrite=overwrite,
                         name="measured data file")
        else:
            head = "" if sidecar else "".join(
                ("# " + ln).rstrip() + "\n" for ln in text.splitlines())

            def write_csv(tmp):
                with open(tmp, "w", encoding="utf-8", newline="") as fh:
                    fh.write(head)
                    df.to_csv(fh, index=False, lineterminator="\n")

            atomic_write(p, write_csv, overwrite=overwrite, name="measured data file")
        if sidecar:
            atomic_write(side, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"),
                         overwrite=overwrite, name="metadata file")
        return p


def _save_target(path, overwrite, sidecar):
    """(path, format, sidecar) of :meth:`MeasuredData.save`, checked before writing."""
    if not isinstance(sidecar, bool):
        raise TypeError(f"sidecar must be True or False, got {sidecar!r}")
    p = check_new_file(path, overwrite=overwrite, name="measured data file")
    fmt = _format_of(p)
    if fmt == "parquet":
        _need_pyarrow("write")
        sidecar = True
    if sidecar:
        check_new_file(p.with_suffix(".toml"), overwrite=overwrite, name="metadata file")
    return p, fmt, sidecar


def check_save_path(path, *, overwrite: bool = False, sidecar: bool = False) -> Path:
    """Check, before computing a record, that :meth:`MeasuredData.save` could write ``path``.

    Parameters
    ----------
    path : path-like
        ``.csv`` or ``.parquet`` file; its folder must exist.
    overwrite : bool, keyword-only
        Replace existing files.
    sidecar : bool, keyword-only
        CSV with a sidecar metadata file.

    Returns
    -------
    pathlib.Path
    """
    return _save_target(path, overwrite, sidecar)[0]


# --------------------------------------------------------------------------- loading

def _format_of(p: Path) -> str:
    suf = p.suffix.lower()
    if suf == ".csv":
        return "csv"
    if suf in (".parquet", ".pq"):
        return "parquet"
    hint = {".toml": " (a .toml bench campaign manifest is read by `ppamsafety diagnose` and "
                     "load_campaign)",
            ".xz": " (a compressed raw bench file is imported with a profile: a campaign "
                   "manifest, or import_bench)",
            ".gz": " (a compressed raw bench file is imported with a profile: a campaign "
                   "manifest, or import_bench)"}.get(suf, "")
    raise MeasuredDataError(f"{p}: unknown data file type {p.suffix!r}; the format is CSV (.csv) "
                            f"or Parquet (.parquet){hint}")


def _need_pyarrow(what: str) -> None:
    if importlib.util.find_spec("pyarrow") is None:
        raise MeasuredDataError(f"to {what} Parquet files ppamsafety needs pyarrow, which is not "
                                f"installed: python -m pip install pyarrow (or use CSV)")


def _split_header(text: str) -> tuple:
    """(TOML text of the leading '#' block with one line per file line, number of lines)."""
    out, n = [], 0
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("#"):
            body = s[1:]
            out.append(body[1:] if body.startswith(" ") else body)
            n += 1
        elif not s:
            out.append("")
            n += 1
        else:
            break
    return "\n".join(out), n


def read_metadata(path) -> dict:
    """The metadata of a data file (header block or sidecar), not validated.

    Parameters
    ----------
    path : path-like
        CSV or Parquet data file.

    Returns
    -------
    dict
    """
    p = Path(path)
    meta, _ = _read_meta(p, _format_of(p))
    return meta


def _read_meta(p: Path, fmt: str):
    side = p.with_suffix(".toml")
    head_meta, n_head = {}, 0
    if fmt == "csv":
        with open(p, "r", encoding="utf-8-sig") as fh:        # a byte-order mark is allowed
            lines = []
            for line in fh:
                if line.strip() and not line.lstrip().startswith("#"):
                    break
                lines.append(line)
        block, n_head = _split_header("".join(lines))
        if block.strip():
            head_meta = _parse_toml(block, f"{p} (header block, line numbers are file lines)")
    side_meta = _parse_toml(read_text(side, what="metadata sidecar", error=MeasuredDataError)[1],
                            str(side)) if side.is_file() else {}
    if head_meta and side_meta:
        raise MeasuredDataError(f"{p}: metadata given twice (header block and {side.name}); "
                                f"keep one")
    if not head_meta and not side_meta:
        where = f"a sidecar {side.name}" + (" or a '# key = value' header block" if fmt == "csv"
                                            else "")
        raise MeasuredDataError(f"{p}: no metadata: give {where} with at least kind and "
                                f"experiment (see docs/measured_data.md)")
    return head_meta or side_meta, n_head


def load_measured(path, *, allow_gaps: bool = False, strict_units: bool = True) -> MeasuredData:
    """Read and validate a measured data file (CSV or Parquet + metadata).

    Parameters
    ----------
    path : path-like
        ``DATA.csv`` (metadata in a ``# key = value`` header block or in
        ``DATA.toml``) or ``DATA.parquet`` (metadata in ``DATA.toml``; needs
        pyarrow).
    allow_gaps : bool, keyword-only
        Drop rows with NaN/inf and split the record at gaps instead of
        refusing it (see :class:`MeasuredData`).
    strict_units : bool, keyword-only
        Refuse values that look like bar/degrees/mm (default) or only warn.

    Returns
    -------
    MeasuredData

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    MeasuredDataError
        Anything wrong with the data or metadata; the message names file,
        column and row.
    """
    p = check_input_file(path, what="measured data file")
    size = p.stat().st_size
    if size > MAX_FILE_BYTES:
        raise MeasuredDataError(f"{p}: {size / 2 ** 20:.4g} MB, more than the "
                                f"{MAX_FILE_BYTES / 2 ** 20:g} MB a measured data file may hold "
                                f"(its table would need several times that in memory); split "
                                f"the record (a campaign manifest diagnoses several together) or "
                                f"decimate it")
    fmt = _format_of(p)
    if fmt == "parquet":
        _need_pyarrow("read")
    try:
        meta, n_head = _read_meta(p, fmt)
        if fmt == "csv":
            df = pd.read_csv(p, skiprows=n_head, skipinitialspace=True, encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        where = exc.object[max(0, exc.start - 20):exc.start] if isinstance(exc.object, bytes) \
            else b""
        raise MeasuredDataError(
            f"{p}: not a UTF-8 text file (byte 0x{exc.object[exc.start]:02x} at offset "
            f"{exc.start}, after {where!r}): a data file is CSV text in UTF-8 (or a Parquet "
            f"file named .parquet); re-save it as UTF-8") from None
    except pd.errors.EmptyDataError:
        raise MeasuredDataError(f"{p}: no column header and no data after the metadata") \
            from None
    except pd.errors.ParserError as exc:
        raise MeasuredDataError(f"{p}: not a valid CSV table: {exc}") from None
    if fmt == "csv":
        first = n_head + 2
    else:
        df = pd.read_parquet(p)
        first = None
    return MeasuredData(meta, df, allow_gaps=allow_gaps, strict_units=strict_units,
                        source=str(p), first_line=first)


__all__ = ["check_save_path", "FORMAT_VERSION", "KINDS", "EXPERIMENTS", "ALLOWED", "ARM_CHANNELS",
           "ACTUATOR_TYPES", "ACTUATOR_CHANNELS", "MIN_ROWS", "MAX_FILE_BYTES", "DT_TOLERANCE",
           "GAP_FACTOR", "MeasuredData", "check_nominal_pressure",
           "MeasuredDataError", "MeasuredDataWarning", "load_measured", "read_metadata",
           "dumps_toml"]
