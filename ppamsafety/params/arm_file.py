"""Arm description files: a whole :class:`~ppamsafety.params.ArmParameters` in TOML.

A user who builds their own PPAM arm describes it in one file (``docs/arm_files.md`` is
the reference; ``ppamsafety arm export --out my_arm.toml`` writes the thesis arm as a
commented template)::

    format = "ppamsafety-arm/1"
    name = "my arm"
    gravity = { value = 9.81, unit = "m/s^2" }
    friction_velocity = { value = 0.01, unit = "rad/s" }

    [geometry]
    source = "CAD drawing 2024-03"
    X11 = { value = 0.039, unit = "m" }
    ...

    [muscles.group1]
    count = 4
    l0 = { value = 0.06, unit = "m" }
    force_law = { value = [8.2e-05, 0.00295, ...], unit = "N/Pa" }

Rules
-----
* Every dimensioned value is an inline table ``{ value = ..., unit = "..." }``; the unit
  is the SI unit of the key or one of the few alternatives of
  :data:`ppamsafety.units.UNIT_ALIASES` (``mm``, ``bar``, ``deg``, ``N/bar`` ...),
  converted to SI on reading.  Dimensionless numbers, counts, names and switches are
  plain values (a dimensionless number may also be ``{ value = 0.3, unit = "1" }``).
* Every table may carry a ``source`` string (its provenance); the arm keeps them
  (``ArmParameters.sources``) and writes them back.
* Unknown keys and tables are refused; a missing key is named with its unit.
* Validation is that of the parameter classes; an error names the dotted key, its value
  and what is allowed, e.g. ``muscles.group3.l0 = -0.1 m: must be in (0, 1] m``.
* ``[effects]`` is optional and lists only the effects that are on (a missing key is
  off); ``[sensors]`` is optional (default: the thesis hardware).
* :func:`arm_to_toml` (``ArmParameters.to_toml``) writes floats with their shortest exact
  representation, so ``ArmParameters.from_toml(arm.to_toml()) == arm``, names and sources
  included.  :func:`read_arm_file` (``ArmParameters.from_file``) reads a file with these
  data checks; :func:`ppamsafety.design.load_arm`, what every command uses, adds the checks
  that need the arm's physics (``ppamsafety.design.check_arm``).

The same keys address parameters in sweeps: :func:`apply_arm_changes` sets
``"pneumatics.mean_pressure"``, ``"muscles.group1.count"``, ``"links.m2"``,
``"effects.hysteresis_delta"`` (a sweep writes them ``arm.<key>``) and validates each
value like the file.  This module only reads and writes data: a derived quantity of an
arm (stiffness, maximum load) is computed by the physics that owns it
(:func:`ppamsafety.design.arm_summary`).
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import math
import re
import tomllib
from dataclasses import dataclass, fields

import tomli_w

from .._inputfiles import read_text
from ..units import si_factor
from .effects import Effects
from .geometry import ArmGeometry
from .inertia import BaseParameters, LinkInertia
from .muscles import MuscleGroup, MuscleSet
from .pneumatics import PneumaticParams
from .sensors import SensorHardware
from .valves import Valve, ValveSet

#: The ``format`` string of an arm file (optional on reading; refused if different).
ARM_FORMAT = "ppamsafety-arm/1"
#: Units of dimensionless numbers a file may state (``{value = 0.3, unit = "1"}``).
DIMENSIONLESS = ("1", "-", "")


class ArmFileError(ValueError):
    """An arm (or head) file is not valid; the message names the dotted key."""


@dataclass(frozen=True)
class Key:
    """One key of a table of an arm file.

    Attributes
    ----------
    key : str
        Name in the file.
    attr : str
        Field of the parameter class it fills.
    unit : str or None
        SI unit: the value is written ``{value, unit}``; None: a plain value.
    kind : str
        ``"float"``, ``"int"``, ``"str"`` or ``"bool"`` (of each entry for vectors).
    length : int
        0 for a scalar, else the number of entries.
    doc : str
        What it is (the template's comment), with its range.
    """

    key: str
    attr: str
    unit: str | None
    kind: str = "float"
    length: int = 0
    doc: str = ""


def _k(key, unit, doc, *, attr=None, kind="float", length=0):
    return Key(key, attr or key, unit, kind, length, doc)


_GEOMETRY_DOCS = {
    "X11": "group 1 base attachment A11 = (-X11, Y11), x distance", "Y11": "... y distance",
    "X21": "group 2 base attachment A21 = (X21, -Y21), x distance", "Y21": "... y distance",
    "L12": "group 1 attachment on the upper arm, along the link",
    "d12": "... perpendicular offset", "L22": "group 2 attachment on the upper arm, along",
    "d22": "... perpendicular", "L32": "group 3 attachment on the upper arm, along",
    "d32": "... perpendicular", "L42": "group 4 attachment on the upper arm, along",
    "d42": "... perpendicular", "L33": "group 3 attachment on the forearm, along",
    "d33": "... perpendicular", "L43": "group 4 attachment on the forearm, along",
    "d43": "... perpendicular", "L1": "upper arm length O-S", "L2": "forearm length S-TCP",
    "LL": "load point A_L on the forearm, along", "dL": "... perpendicular",
    "q1_min": "working area of joint 1 (2.6), from", "q1_max": "... to",
    "q2_min": "working area of joint 2 (2.7), from", "q2_max": "... to",
}


def _geometry_keys():
    out = []
    for f in fields(ArmGeometry):
        n = f.name
        if n.startswith("q"):
            unit, rng = "rad", "in (-pi, pi)"
        elif n.startswith("d"):
            unit, rng = "m", "in [-0.5, 0.5] m"
        else:
            unit, rng = "m", "in (0, 5] m" if n in ("L1", "L2") else "in [0, 5] m"
        out.append(_k(n, unit, f"{_GEOMETRY_DOCS[n]}; {rng}"))
    return tuple(out)


GEOMETRY_KEYS = _geometry_keys()
MUSCLE_SET_KEYS = (
    _k("eps_min", None, "smallest contraction of groups 1, 3 at their longest (2.14); in "
                        "(0, 0.4)"),
    _k("eps_max", None, "largest contraction of groups 2, 4 at their shortest (A.36); in "
                        "(0, 0.4], > eps_min"),
)
MUSCLE_GROUP_KEYS = (
    _k("name", None, "label", kind="str"),
    _k("count", None, "PPAMs in series n_m; in [1, 20]", attr="n_muscles", kind="int"),
    _k("l0", "m", "uncontracted membrane length of one muscle; in (0, 1] m"),
    _k("slenderness", None, "l0/R; in [1, 50]"),
    _k("force_law", "N/Pa", "(a0 .. a4) of F = p (a0/eps + a1 + a2 eps + a3 eps^2 + a4 eps^3) "
                            "(3.9), one muscle; a0 >= 0", attr="coefficients", length=5),
)
VALVE_KEYS = (
    _k("offset", "Pa", "static offset v1 of the delivered pressure (3.12); in [-0.5, 0.5] bar",
       attr="v1"),
    _k("gain", None, "static gain v2 of the delivered pressure (3.12); in [0.5, 1.5]",
       attr="v2"),
    _k("time_constant", "s", "first-order time constant T (3.2); in [1 ms, 10 s] or inf "
                             "(closed valve)"),
)
PNEUMATICS_KEYS = (
    _k("mean_pressure", "Pa", "mean gauge pressure p_m of the pair of joint 1, 2 (Delta-p "
                              "approach (3.7), stiffness (2.18)); in [0, max_pressure]",
       attr="p_mean", length=2),
    _k("max_pressure", "Pa", "largest gauge pressure (set values clipped); in (0, 6] bar",
       attr="p_max"),
    _k("atmospheric_pressure", "Pa", "in [0.5, 1.5] bar", attr="p_atm"),
    _k("polytropic_n", None, "polytropic exponent n (3.3); in [1, 1.67]"),
)
LINK_KEYS = (
    _k("m1", "kg", "upper arm mass; in (0, 100] kg"), _k("m2", "kg", "forearm mass; in (0, 100] kg"),
    _k("LG1", "m", "upper arm centre of gravity, along the link; in [-2, 2] m"),
    _k("dG1", "m", "... perpendicular; in [-2, 2] m"),
    _k("LG2", "m", "forearm centre of gravity, along the link; in [-2, 2] m"),
    _k("dG2", "m", "... perpendicular; in [-2, 2] m"),
    _k("IG1", "kg m^2", "upper arm centroidal inertia about z; in (0, 100] kg m^2"),
    _k("IG2", "kg m^2", "forearm centroidal inertia about z; in (0, 100] kg m^2"),
    _k("coulomb", "N m", "Coulomb friction c per joint (3.30); in [0, 100] N m", length=2),
    _k("viscous", "N m s/rad", "viscous friction b per joint (3.30); in [0, 100] N m s/rad",
       length=2),
)
MODEL_KEYS = (
    _k("m1LG1_m2L1", "kg m", "theta1 = m1 L_G1 + m2 L1 (B.5); in [-10, 10] kg m"),
    _k("m1dG1", "kg m", "theta2 = m1 d_G1; in [-10, 10] kg m"),
    _k("IO1_m2L1sq", "kg m^2", "theta3 = I_zO,1 + m2 L1^2; in (0, 100] kg m^2"),
    _k("m2LG2", "kg m", "theta4 = m2 L_G2; in [-10, 10] kg m"),
    _k("m2dG2", "kg m", "theta5 = m2 d_G2; in [-10, 10] kg m"),
    _k("IS2", "kg m^2", "theta6 = I_zS,2; in (0, 100] kg m^2"),
    _k("coulomb", "N m", "Coulomb friction per joint (3.30); in [0, 100] N m", length=2),
    _k("viscous", "N m s/rad", "viscous friction per joint; in [0, 100] N m s/rad", length=2),
)
SENSOR_KEYS = (
    _k("encoder_resolution", "rad", "angle per encoder count (thesis: 2 pi/8000); in (0, pi/2]"),
    _k("timing_clock", "Hz", "clock of the inter-pulse timing board; in (0, 1e12] Hz",
       attr="clock_hz"),
    _k("counter_bits", None, "width of the pulse-interval counter; in [4, 32]", kind="int"),
    _k("dead_band", "rad/s", "velocities below this read zero; in [0, 1000] rad/s"),
    _k("angle_noise_variance", "rad^2", "variance of the measured q1, q2 (Table 3.2); each "
                                        "in [0, 1]", attr="angle_noise_variances", length=2),
    _k("velocity_noise_variance", "rad^2/s^2", "variance of the measured qd1, qd2 "
                                               "(Table 3.2); each in [0, 1e6]",
       attr="velocity_noise_variances", length=2),
)
ROOT_KEYS = (
    _k("gravity", "m/s^2", "gravitational acceleration along -y (0: horizontal arm); in "
                           "[0, 30] m/s^2"),
    _k("friction_velocity", "rad/s", "velocity scale of the smooth Coulomb friction "
                                     "c tanh(qd/v_s); in [1e-5, 1] rad/s"),
)

_EFFECT_DOCS = {
    "payload_mass": "point mass at the load point A_L; in [0, 5] kg",
    "friction_coulomb": "plant Coulomb friction per joint (overrides links.coulomb); in "
                        "[0, 10] N m",
    "friction_viscous": "plant viscous friction per joint; in [0, 10] N m s/rad",
    "valve_offset": "plant valve offsets v1 (override valves); in [-0.5, 0.5] bar",
    "valve_gain": "plant valve gains v2; in [0.5, 1.5]",
    "valve_time_constant": "plant valve time constants T; in [1 ms, 10 s] or inf",
    "polytropic_n": "plant polytropic exponent; in [1, 1.4]",
    "hysteresis_delta": "muscle force hysteresis (3.35) per group; in [0, 1] (25 fibres: "
                        "0.139, 40 fibres: 0.299, §3.6.5)",
    "hysteresis_initial": "Preisach memory at t = 0: \"negative\", \"positive\" or past "
                          "inputs in [-1, 1] (one list, or four)",
    "hysteresis_exact_stages": "exact Preisach output in every RK4 stage",
    "valve_dead_time": "transport delay of each valve's set value, in control periods; "
                       "in [0, 100]",
    "joint_torque_bias": "constant torque per joint the model lacks; in [-20, 20] N m",
}
#: Example values of the effects for the template (commented out: every effect is off).
_EFFECT_EXAMPLES = {
    "payload_mass": 0.5, "friction_coulomb": (0.3, 0.3), "friction_viscous": (1.0, 0.1),
    "valve_offset": (5000.0,) * 4, "valve_gain": (0.95,) * 4,
    "valve_time_constant": (0.09, 0.07, 0.09, 0.07), "polytropic_n": 1.2,
    "hysteresis_delta": (0.139,) * 4, "hysteresis_initial": "negative",
    "hysteresis_exact_stages": False, "valve_dead_time": (2,) * 4,
    "joint_torque_bias": (0.2, 0.0),
}


def _effect_keys():
    out = []
    for f in fields(Effects):
        unit = f.metadata["unit"] or None
        length = f.metadata["length"]
        if f.name == "hysteresis_initial":
            kind, unit, length = "memory", None, 0
        elif isinstance(f.default, bool):
            kind = "bool"
        elif unit == "control periods":
            kind, unit = "int", None
        else:
            kind = "float"
        out.append(Key(f.name, f.name, unit, kind, length if length > 1 else 0,
                       _EFFECT_DOCS.get(f.name, f.name)))
    return tuple(out)


EFFECT_KEYS = _effect_keys()

GROUPS = tuple(f"group{k}" for k in range(1, 5))
VALVES = tuple(f"valve{k}" for k in range(1, 5))
#: Every table of an arm file and its keys (``source`` is allowed in each as well).
TABLES = {"": ROOT_KEYS, "geometry": GEOMETRY_KEYS, "muscles": MUSCLE_SET_KEYS,
          **{f"muscles.{g}": MUSCLE_GROUP_KEYS for g in GROUPS},
          **{f"valves.{v}": VALVE_KEYS for v in VALVES},
          "pneumatics": PNEUMATICS_KEYS, "links": LINK_KEYS, "model": MODEL_KEYS,
          "model_gravity": MODEL_KEYS, "effects": EFFECT_KEYS, "sensors": SENSOR_KEYS}
#: Comment heading each table in a written file.
TABLE_DOCS = {
    "geometry": "Kinematics and muscle attachment points (thesis fig. 2.9, Tables 2.1, 2.2)",
    "muscles": "Muscle groups: 1 (joint 1, top), 2 (joint 1, bottom), 3 (joint 2, top), "
               "4 (joint 2, bottom)",
    "valves": "One pressure valve per muscle group (static error (3.12), lag (3.2))",
    "pneumatics": "Pressure operating point and gas model (§3.3)",
    "links": "Physical mass properties of the plant (what the simulator integrates)",
    "model": "The controllers' identified dynamic model (base parameters (B.5) + friction)",
    "model_gravity": "The identified gravity model of the static gravity compensation "
                     "(3.18)-(3.19)",
    "effects": "Optional plant effects, all off when absent (params.effects); the controllers "
               "never see them",
    "sensors": "Joint sensors: encoders, inter-pulse timing board, noise (§2.4.5, Table 3.2)",
}
_ROOT_EXTRA = ("format", "name", "source")


# ----------------------------------------------------------------------------- reading
def _err(where: str, msg: str) -> ArmFileError:
    return ArmFileError(f"{where}: {msg}" if where else msg)


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _fmt(v) -> str:
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return f"{v:g}" if _is_number(v) else repr(v)


def _scalar(dotted: str, key: Key, v, factor: float):
    if key.kind == "int":
        if isinstance(v, bool) or not (isinstance(v, int) or (isinstance(v, float)
                                                               and float(v).is_integer())):
            raise ArmFileError(f"{dotted} = {_fmt(v)}: must be an integer")
        return int(v)
    if key.kind == "str":
        if not isinstance(v, str):
            raise ArmFileError(f"{dotted} = {v!r}: must be a string")
        return v
    if key.kind == "bool":
        if not isinstance(v, bool):
            raise ArmFileError(f"{dotted} = {v!r}: must be true or false")
        return v
    if not _is_number(v):
        raise ArmFileError(f"{dotted} = {v!r}: must be a number"
                           + (f" [{key.unit}]" if key.unit else ""))
    return float(v) * factor if factor != 1.0 else float(v)


def read_value(dotted: str, key: Key, raw, *, broadcast: bool = False):
    """Convert one value of an arm file to the SI value of its parameter field.

    Parameters
    ----------
    dotted : str
        The key's dotted path (for messages), e.g. ``"muscles.group1.l0"``.
    key : Key
        Its declaration (unit, kind, length).
    raw
        The TOML value: ``{value = ..., unit = "..."}`` for a dimensioned key, a
        plain value otherwise.
    broadcast : bool
        Accept one number for a vector key and repeat it (sweeps: ``0.299`` for
        the four groups' ``hysteresis_delta``).

    Returns
    -------
    float, int, str, bool or tuple
        The value in SI units, a tuple for a vector key.

    Raises
    ------
    ArmFileError
        Naming ``dotted``, the value and what is allowed.
    """
    factor = 1.0
    if key.kind == "memory":
        return _memory(dotted, raw)
    if isinstance(raw, dict):
        if set(raw) != {"value", "unit"}:
            raise ArmFileError(f"{dotted} = {raw!r}: an inline table must have exactly the "
                               f"keys 'value' and 'unit'")
        if key.kind not in ("float",):
            raise ArmFileError(f"{dotted} is a plain {key.kind} (no unit), got {raw!r}")
        unit, raw = raw["unit"], raw["value"]
        if key.unit is None:
            if unit not in DIMENSIONLESS:
                raise ArmFileError(f"{dotted} is dimensionless: unit = {unit!r} must be one of "
                                   f"{list(DIMENSIONLESS)}")
        else:
            try:
                factor = si_factor(unit, key.unit, name=f"{dotted} unit")
            except (TypeError, ValueError) as exc:
                raise ArmFileError(str(exc)) from None
    elif key.unit is not None:
        raise ArmFileError(f"{dotted} = {_fmt(raw)}: give the value with its unit, e.g. "
                           f"{dotted.rsplit('.', 1)[-1]} = {{ value = {_fmt(raw)}, unit = "
                           f"\"{key.unit}\" }}")
    if key.length:
        if broadcast and (_is_number(raw) or isinstance(raw, bool)):
            raw = [raw] * key.length
        if not isinstance(raw, list):
            raise ArmFileError(f"{dotted} = {_fmt(raw)}: must be a list of {key.length} "
                               f"values" + (f" [{key.unit}]" if key.unit else ""))
        if len(raw) != key.length:
            raise ArmFileError(f"{dotted} = {_fmt(raw)}: must have {key.length} entries, got "
                               f"{len(raw)}")
        return tuple(_scalar(f"{dotted}[{i}]", key, x, factor) for i, x in enumerate(raw))
    return _scalar(dotted, key, raw, factor)


def _memory(dotted, raw):
    if isinstance(raw, str):
        return raw
    if isinstance(raw, list):
        return tuple(tuple(x) if isinstance(x, list) else x for x in raw)
    raise ArmFileError(f"{dotted} = {raw!r}: must be \"negative\", \"positive\" or a list of "
                       f"past inputs (one list, or four)")


def _table(data: dict, path: str, *, required: bool, extra=()) -> tuple:
    """(attr -> SI value, source) of the table ``path``; unknown and missing keys refused."""
    keys = TABLES[path]
    allowed = [k.key for k in keys] + ["source", *extra]
    for k in data:
        if k not in allowed:
            raise ArmFileError(f"unknown key {_dot(path, k)}; allowed in "
                               f"{'[' + path + ']' if path else 'the top level'}: {allowed}")
    out = {}
    for key in keys:
        dotted = _dot(path, key.key)
        if key.key not in data:
            if required and not (key.key == "name" and path.startswith("muscles.")):
                unit = f" [{key.unit}]" if key.unit else ""
                raise ArmFileError(f"missing key {dotted}{unit} ({key.doc})")
            continue
        out[key.attr] = read_value(dotted, key, data[key.key])
    source = data.get("source", "")
    if not isinstance(source, str):
        raise ArmFileError(f"{_dot(path, 'source')} = {source!r}: must be a string")
    return out, source


def _dot(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _sub(data: dict, name: str, *, required: bool = True) -> dict:
    v = data.get(name)
    if v is None:
        if required:
            raise ArmFileError(f"missing table [{name}]")
        return {}
    if not isinstance(v, dict):
        raise ArmFileError(f"{name} must be a table ([{name}]), got {v!r:.60}")
    return v


#: (class name, field) -> dotted key of the file, to name the key in a parameter class's error.
def _field_keys() -> dict:
    out = {}
    for path, cls in (("geometry", "ArmGeometry"), ("pneumatics", "PneumaticParams"),
                      ("links", "LinkInertia"), ("sensors", "SensorHardware"),
                      ("muscles", "MuscleSet"), ("", "ArmParameters")):
        for key in TABLES[path]:
            out[(cls, key.attr)] = _dot(path, key.key)
    for key in EFFECT_KEYS:
        out[("Effects", key.attr)] = f"effects.{key.key}"
    return out


_FIELD_KEYS = _field_keys()
_PREFIX = re.compile(r"^(?P<cls>[A-Za-z]+)\.(?P<attr>\w+)(?P<idx>\[\d+\])?"
                     r"(?: \((?:[^()]|\([^()]*\))*\))?")
_OUTSIDE = re.compile(r"^ = (?P<val>.+?) is outside (?P<rng>.+)$", re.S)


def _translate(exc: Exception, keys_of: dict) -> ArmFileError:
    """A parameter class's error restated with the dotted keys of the file.

    ``keys_of`` maps (class name, field) to dotted keys for the object being built.
    """
    msg = str(exc)
    m = _PREFIX.match(msg)
    if m:
        dotted = keys_of.get((m["cls"], m["attr"])) or _FIELD_KEYS.get((m["cls"], m["attr"]))
        if dotted:
            idx, rest = m["idx"] or "", msg[m.end():]
            out = _OUTSIDE.match(rest)
            if out:
                return ArmFileError(f"{dotted}{idx} = {out['val']}: must be in {out['rng']}")
            rest = rest.lstrip()
            return ArmFileError(f"{dotted}{idx} {rest}" if rest.startswith("=")
                                else f"{dotted}{idx}: {rest}")
    for (cls, attr), dotted in {**_FIELD_KEYS, **keys_of}.items():
        msg = re.sub(rf"\b{cls}\.{attr}\b", dotted, msg)
    group = re.search(r"muscle group (\d)", msg)
    msg = msg.replace("MuscleGroup.n_muscles/l0", f"muscles.group{group[1] if group else 'N'}"
                                                   f".count/l0")
    msg = msg.replace("MuscleSet.eps_min/eps_max", "muscles.eps_min/eps_max")
    for cls, table in (("ArmParameters", ""), ("ArmGeometry", "geometry: "),
                       ("MuscleSet", "muscles: "), ("LinkInertia", "links: "),
                       ("ValveSet", "valves: "), ("Effects", "effects: ")):
        if msg.startswith(f"{cls}: "):
            msg = table + msg[len(cls) + 2:]
    return ArmFileError(msg)


def _build(cls, kwargs: dict, keys_of: dict):
    try:
        return cls(**kwargs)
    except (TypeError, ValueError) as exc:
        raise _translate(exc, keys_of) from None


def _keys_of(cls_name: str, path: str, keys) -> dict:
    return {(cls_name, k.attr): _dot(path, k.key) for k in keys}


def _check_arm(arm) -> None:
    """TypeError unless ``arm`` is an ArmParameters (duck-typed: this module sits below
    :mod:`ppamsafety.params.arm`, which imports it for ``ArmParameters.to_toml``)."""
    if type(arm).__name__ != "ArmParameters" or not hasattr(arm, "geometry"):
        raise TypeError(f"arm must be an ArmParameters, got {type(arm).__name__}")


def arm_from_dict(data: dict, *, cls):
    """Build and validate an arm from the parsed TOML of an arm file.

    Parameters
    ----------
    data : dict
        ``tomllib.loads(text)`` of an arm file (see the module docstring).
    cls : type
        :class:`~ppamsafety.params.ArmParameters` (``ArmParameters.from_toml`` passes
        itself).

    Returns
    -------
    ArmParameters

    Raises
    ------
    ArmFileError
        Naming the dotted key, its value and what is allowed.
    """
    if not isinstance(data, dict):
        raise ArmFileError(f"an arm file must be a TOML document (a table), got "
                           f"{type(data).__name__}")
    tables = ("geometry", "muscles", "valves", "pneumatics", "links", "model", "model_gravity",
              "effects", "sensors")
    fmt = data.get("format", ARM_FORMAT)
    if fmt != ARM_FORMAT:
        what = " (a head file?)" if isinstance(fmt, str) and "head" in fmt else ""
        raise ArmFileError(f"format = {fmt!r} is not {ARM_FORMAT!r}{what}")
    for k, v in data.items():
        if k not in tables and k not in [x.key for x in ROOT_KEYS] + list(_ROOT_EXTRA):
            raise ArmFileError(f"unknown key or table {k!r} at the top level; allowed: "
                               f"{[x.key for x in ROOT_KEYS] + list(_ROOT_EXTRA)} and the "
                               f"tables {list(tables)}")
    name = data.get("name", "")
    if not isinstance(name, str):
        raise ArmFileError(f"name = {name!r}: must be a string")
    root = {k: v for k, v in data.items() if k not in tables and k not in ("format", "name")}
    top, src = _table(root, "", required=True)
    sources = [("arm", src)] if src else []

    def part(path, cls, cls_name, keys, d):
        kw, s = _table(d, path, required=True)
        if s:
            sources.append((path, s))
        return _build(cls, kw, _keys_of(cls_name, path, keys))

    geometry = part("geometry", ArmGeometry, "ArmGeometry", GEOMETRY_KEYS, _sub(data, "geometry"))
    mus = _sub(data, "muscles")
    extra = [k for k in mus if k not in GROUPS and k not in [x.key for x in MUSCLE_SET_KEYS]
             and k != "source"]
    if extra:
        raise ArmFileError(f"unknown key muscles.{extra[0]}; allowed: "
                           f"{[x.key for x in MUSCLE_SET_KEYS] + ['source', *GROUPS]}")
    groups = []
    for k, g in enumerate(GROUPS):
        d = _sub(mus, g) if g in mus else None
        if d is None:
            raise ArmFileError(f"missing table [muscles.{g}]")
        kw, s = _table(d, f"muscles.{g}", required=True)
        kw.setdefault("name", f"group {k + 1}")
        if s:
            sources.append((f"muscles.{g}", s))
        groups.append(_build(MuscleGroup, kw, _keys_of("MuscleGroup", f"muscles.{g}",
                                                        MUSCLE_GROUP_KEYS)))
    kw, s = _table({k: v for k, v in mus.items() if k not in GROUPS}, "muscles", required=True)
    if s:
        sources.append(("muscles", s))
    muscles = _build(MuscleSet, {"groups": tuple(groups), **kw},
                     _keys_of("MuscleSet", "muscles", MUSCLE_SET_KEYS))
    val = _sub(data, "valves")
    extra = [k for k in val if k not in VALVES and k != "source"]
    if extra:
        raise ArmFileError(f"unknown key valves.{extra[0]}; allowed: {['source', *VALVES]}")
    if val.get("source"):
        if not isinstance(val["source"], str):
            raise ArmFileError(f"valves.source = {val['source']!r}: must be a string")
        sources.append(("valves", val["source"]))
    valves = []
    for v in VALVES:
        if v not in val:
            raise ArmFileError(f"missing table [valves.{v}]")
        kw, s = _table(_sub(val, v), f"valves.{v}", required=True)
        if s:
            sources.append((f"valves.{v}", s))
        valves.append(_build(Valve, kw, _keys_of("Valve", f"valves.{v}", VALVE_KEYS)))
    pneumatics = part("pneumatics", PneumaticParams, "PneumaticParams", PNEUMATICS_KEYS,
                      _sub(data, "pneumatics"))
    links = part("links", LinkInertia, "LinkInertia", LINK_KEYS, _sub(data, "links"))
    model = part("model", BaseParameters, "BaseParameters", MODEL_KEYS, _sub(data, "model"))
    model_gravity = part("model_gravity", BaseParameters, "BaseParameters", MODEL_KEYS,
                         _sub(data, "model_gravity"))
    kw, s = _table(_sub(data, "effects", required=False), "effects", required=False)
    if s:
        sources.append(("effects", s))
    effects = _build(Effects, kw, _keys_of("Effects", "effects", EFFECT_KEYS))
    if "sensors" in data:
        sensors = part("sensors", SensorHardware, "SensorHardware", SENSOR_KEYS,
                       _sub(data, "sensors"))
    else:
        sensors = SensorHardware()
    kw = dict(geometry=geometry, muscles=muscles, valves=ValveSet(tuple(valves)),
              pneumatics=pneumatics, links=links, model=model, model_gravity=model_gravity,
              effects=effects, sensors=sensors, name=name, sources=tuple(sources), **top)
    return _build(cls, kw, _keys_of("ArmParameters", "", ROOT_KEYS))


def arm_from_toml(text: str, *, cls, where: str = ""):
    """Parse and validate the TOML text of an arm file.

    Parameters
    ----------
    text : str
        TOML text (see the module docstring).
    cls : type
        :class:`~ppamsafety.params.ArmParameters`.
    where : str
        How to name the file in error messages (its path).

    Returns
    -------
    ArmParameters

    Raises
    ------
    ArmFileError
        ``"<where>: <dotted key> = <value>: <what is allowed>"``.
    """
    return parse_document(text, lambda data: arm_from_dict(data, cls=cls), where=where)


def read_arm_file(path, *, cls):
    """Read and validate an arm file's data (:func:`ppamsafety.design.load_arm` is the front
    door: it adds the checks that need the arm's physics).

    Parameters
    ----------
    path : path-like
        The ``.toml`` file.
    cls : type
        :class:`~ppamsafety.params.ArmParameters`.

    Returns
    -------
    ArmParameters
    """
    p, text = read_text(path, what="arm file", error=ArmFileError)
    return arm_from_toml(text, cls=cls, where=str(p))


# ----------------------------------------------------------------------------- writing
def parse_document(text: str, build, *, where: str = ""):
    """Parse the TOML text of a parameter file and build its object from the table.

    Parameters
    ----------
    text : str
        TOML text.
    build : callable
        ``build(table) -> object``, raising :class:`ArmFileError` naming the key.
    where : str
        How to name the file in error messages (its path): every error starts with it.

    Returns
    -------
    object
        What ``build`` returns.
    """
    if not isinstance(text, str):
        raise TypeError(f"text must be the TOML text (a str), got {type(text).__name__}")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _err(where, f"not valid TOML ({exc})") from None
    try:
        return build(data)
    except ArmFileError as exc:
        raise _err(where, str(exc)) from None


def _literal(v) -> str:
    """One TOML value (exact floats: Python's shortest round-trip repr, via tomli-w)."""
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_literal(x) for x in v) + "]"
    if isinstance(v, float) and math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return tomli_w.dumps({"x": v})[4:-1]


def _value_text(key: Key, v) -> str:
    if key.kind == "memory":
        return _literal(v)
    if key.unit is None:
        return _literal(v)
    return f"{{ value = {_literal(v)}, unit = {_literal(key.unit)} }}"


def _line(key: Key, v, comments: bool, *, commented: bool = False) -> str:
    text = f"{'# ' if commented else ''}{key.key} = {_value_text(key, v)}"
    if comments and key.doc:
        text = f"{text}  # {key.doc}" if len(text) < 60 else f"# {key.doc}\n{text}"
    return text


def arm_to_dict(arm) -> dict:
    """The arm as the nested dict of its arm file (SI values, ``{value, unit}`` tables).

    ``ArmParameters.from_dict(arm_to_dict(arm)) == arm``.  Effects that are off are left out.

    Parameters
    ----------
    arm : ArmParameters
        Any arm.

    Returns
    -------
    dict
    """
    _check_arm(arm)
    src = dict(arm.sources)

    def table(path, obj, keys, *, skip_default=None):
        d = {}
        if src.get(path):
            d["source"] = src[path]
        for key in keys:
            v = getattr(obj, key.attr)
            if skip_default is not None and v == getattr(skip_default, key.attr):
                continue
            v = list(v) if isinstance(v, tuple) and key.kind != "memory" else v
            if key.kind == "memory" and not isinstance(v, str):
                v = [list(h) for h in v]
            d[key.key] = v if key.unit is None else {"value": v, "unit": key.unit}
        return d

    out = {"format": ARM_FORMAT}
    if arm.name:
        out["name"] = arm.name
    out.update(table("arm", arm, ROOT_KEYS))
    out["geometry"] = table("geometry", arm.geometry, GEOMETRY_KEYS)
    mus = table("muscles", arm.muscles, MUSCLE_SET_KEYS)
    for g, grp in zip(GROUPS, arm.muscles.groups):
        mus[g] = table(f"muscles.{g}", grp, MUSCLE_GROUP_KEYS)
    out["muscles"] = mus
    val = {"source": src["valves"]} if src.get("valves") else {}
    for v, valve in zip(VALVES, arm.valves.valves):
        val[v] = table(f"valves.{v}", valve, VALVE_KEYS)
    out["valves"] = val
    out["pneumatics"] = table("pneumatics", arm.pneumatics, PNEUMATICS_KEYS)
    out["links"] = table("links", arm.links, LINK_KEYS)
    out["model"] = table("model", arm.model, MODEL_KEYS)
    out["model_gravity"] = table("model_gravity", arm.model_gravity, MODEL_KEYS)
    eff = table("effects", arm.effects, EFFECT_KEYS, skip_default=Effects())
    if eff:
        out["effects"] = eff
    out["sensors"] = table("sensors", arm.sensors, SENSOR_KEYS)
    return out


def arm_to_toml(arm, *, comments: bool = True) -> str:
    """The TOML text of an arm file describing ``arm`` (see the module docstring).

    Floats are written exactly, so ``ArmParameters.from_toml(arm_to_toml(arm)) == arm``
    with the same name and sources.

    Parameters
    ----------
    arm : ArmParameters
        Any arm.
    comments : bool
        Comment every key (what it is, its range) and list the effects that are off as
        commented-out examples: a template to edit.  Without comments the text is
        canonical (:func:`arm_fingerprint` hashes it).

    Returns
    -------
    str
    """
    d = arm_to_dict(arm)
    lines = []
    if comments:
        lines += ["# ppamsafety arm file (docs/arm_files.md).  Every dimensioned value is",
                  "# { value = ..., unit = \"...\" } in SI units (or mm, bar, deg, N/bar ...:",
                  "# ppamsafety.units.UNIT_ALIASES); every table may carry a `source`.",
                  "# Check it with `ppamsafety arm check FILE`.", ""]
    lines.append(f"format = {_literal(ARM_FORMAT)}")
    if "name" in d:
        lines.append(f"name = {_literal(d['name'])}")
    if "source" in d:
        lines.append(f"source = {_literal(d['source'])}")
    for key in ROOT_KEYS:
        lines.append(_line(key, getattr(arm, key.attr), comments))

    def emit(path, keys, tbl, obj, *, doc=None):
        lines.append("")
        if comments and doc:
            lines.append(f"# {doc}")
        lines.append(f"[{path}]")
        if "source" in tbl:
            lines.append(f"source = {_literal(tbl['source'])}")
        for key in keys:
            if key.key in tbl:
                lines.append(_line(key, getattr(obj, key.attr), comments))

    emit("geometry", GEOMETRY_KEYS, d["geometry"], arm.geometry, doc=TABLE_DOCS["geometry"])
    emit("muscles", MUSCLE_SET_KEYS, d["muscles"], arm.muscles, doc=TABLE_DOCS["muscles"])
    for g, grp in zip(GROUPS, arm.muscles.groups):
        emit(f"muscles.{g}", MUSCLE_GROUP_KEYS, d["muscles"][g], grp)
    if "source" in d["valves"] or comments:
        lines.append("")
        if comments:
            lines.append(f"# {TABLE_DOCS['valves']}")
        lines.append("[valves]")
        if "source" in d["valves"]:
            lines.append(f"source = {_literal(d['valves']['source'])}")
    for v, valve in zip(VALVES, arm.valves.valves):
        emit(f"valves.{v}", VALVE_KEYS, d["valves"][v], valve)
    for path, keys, obj in (("pneumatics", PNEUMATICS_KEYS, arm.pneumatics),
                            ("links", LINK_KEYS, arm.links), ("model", MODEL_KEYS, arm.model),
                            ("model_gravity", MODEL_KEYS, arm.model_gravity)):
        emit(path, keys, d[path], obj, doc=TABLE_DOCS[path])
    eff = d.get("effects", {})
    if eff or comments:
        emit("effects", EFFECT_KEYS, eff, arm.effects, doc=TABLE_DOCS["effects"])
        if comments:
            off = [k for k in EFFECT_KEYS if k.key not in eff]
            if off:
                lines.append("# off (uncomment and edit to switch one on):")
            for key in off:
                lines.append(_line(key, _EFFECT_EXAMPLES.get(key.key, getattr(Effects(),
                                                                               key.attr)),
                                   comments, commented=True))
    emit("sensors", SENSOR_KEYS, d["sensors"], arm.sensors, doc=TABLE_DOCS["sensors"])
    return "\n".join(lines) + "\n"


def arm_fingerprint(arm) -> str:
    """SHA-256 of the arm's canonical file text (no comments): which arm a record came from.

    Two arms with the same parameters, names and sources have the same fingerprint.

    Parameters
    ----------
    arm : ArmParameters
        Any arm.

    Returns
    -------
    str
        64 hex digits.
    """
    return hashlib.sha256(arm_to_toml(arm, comments=False).encode("utf-8")).hexdigest()


# ----------------------------------------------------------------------------- changes
def _resolve(path: str):
    """(table path, Key, index or None) of a dotted arm key such as ``links.coulomb[1]``."""
    if not isinstance(path, str) or not path:
        raise ArmFileError(f"arm parameter path {path!r} must be a non-empty string such as "
                           f"'links.m2'")
    m = re.fullmatch(r"(?P<p>[A-Za-z_][\w.]*?)(?:\[(?P<i>\d+)\])?", path)
    if not m:
        raise ArmFileError(f"arm parameter {path!r} is not a dotted key such as 'links.m2' or "
                           f"'pneumatics.mean_pressure[0]'")
    table, _, key = m["p"].rpartition(".")
    keys = TABLES.get(table)
    match = None if keys is None else next((k for k in keys if k.key == key), None)
    if match is None or (table == "" and key in _ROOT_EXTRA):
        raise ArmFileError(f"unknown arm parameter {path!r}; examples: "
                           f"'pneumatics.mean_pressure', 'muscles.group1.count', 'links.m2', "
                           f"'effects.hysteresis_delta', 'geometry.L1' (the keys of an arm "
                           f"file, docs/arm_files.md)")
    idx = None if m["i"] is None else int(m["i"])
    if idx is not None and not match.length:
        raise ArmFileError(f"arm parameter {path!r}: {m['p']} is not a list (no index)")
    if idx is not None and idx >= match.length:
        raise ArmFileError(f"arm parameter {path!r}: index {idx} outside [0, "
                           f"{match.length - 1}]")
    return table, match, idx


def arm_key(path: str) -> Key:
    """The declaration (unit, kind, length) of a dotted arm parameter.

    Parameters
    ----------
    path : str
        ``"links.m2"``, ``"arm.pneumatics.mean_pressure"`` (the ``arm.`` of a sweep is
        accepted), ``"effects.payload_mass"``; an index selects one entry.

    Returns
    -------
    Key
        For an indexed path, the key of one entry (``length`` 0).
    """
    path = path[4:] if isinstance(path, str) and path.startswith("arm.") else path
    _, key, idx = _resolve(path)
    return key if idx is None else Key(key.key, key.attr, key.unit, key.kind, 0, key.doc)


def arm_parameter_paths() -> list:
    """Every dotted key an arm change or a sweep can set (``arm.`` omitted).

    Returns
    -------
    list of str
    """
    out = []
    for table, keys in TABLES.items():
        out += [_dot(table, k.key) for k in keys if not (table == "" and k.key in _ROOT_EXTRA)]
    return out


_CLASS_OF = {"": "ArmParameters", "geometry": "ArmGeometry", "muscles": "MuscleSet",
             "pneumatics": "PneumaticParams", "links": "LinkInertia", "model": "BaseParameters",
             "model_gravity": "BaseParameters", "effects": "Effects", "sensors": "SensorHardware",
             **{f"muscles.{g}": "MuscleGroup" for g in GROUPS},
             **{f"valves.{v}": "Valve" for v in VALVES}}


def _part(arm, table: str):
    """The parameter object holding the keys of ``table``."""
    if table == "":
        return arm
    if table.startswith("muscles.group"):
        return arm.muscles.groups[int(table[-1]) - 1]
    if table.startswith("valves.valve"):
        return arm.valves.valves[int(table[-1]) - 1]
    return getattr(arm, table)


#: A dotted key of a table (``links.m2``, ``muscles.group1.l0``) not yet written ``arm.<key>``,
#: as a sweep names it (the root keys are left alone: "gravity" is also a word).
_ARM_KEY = re.compile(r"(?<![\w.])(" + "|".join(
    re.escape(k) for k in sorted((k for k in arm_parameter_paths() if "." in k), key=len,
                                 reverse=True)) + r")(?![\w])")


def apply_arm_changes(arm, changes):
    """A copy of ``arm`` with parameters set by their dotted keys, validated like a file.

    Only the parts that change are rebuilt (and validated, with the whole arm's
    consistency checks), so a sweep pays a fraction of a millisecond per case.

    Parameters
    ----------
    arm : ArmParameters
        The arm to change.
    changes : mapping of str to value
        Dotted key of an arm file (``"pneumatics.mean_pressure"``,
        ``"muscles.group1.count"``, ``"links.m2"``, ``"effects.payload_mass"``; an
        index selects one entry: ``"links.coulomb[1]"``) -> value: a plain number in
        the key's SI unit, ``{"value": v, "unit": u}``, or a list for a vector key;
        one number for a vector key sets every entry (``"effects.hysteresis_delta":
        0.299``).

    Returns
    -------
    ArmParameters
        ``arm`` itself if ``changes`` is empty.

    Raises
    ------
    ArmFileError
        Naming the dotted key (``arm.<key>`` as a sweep writes it is accepted), its
        value and what is allowed.
    """
    _check_arm(arm)
    if not hasattr(changes, "items"):
        raise TypeError(f"changes must be a dict of dotted key -> value, got {changes!r:.80}")
    if not changes:
        return arm
    by_table = {}
    for path, value in changes.items():
        path = path[4:] if isinstance(path, str) and path.startswith("arm.") else path
        table, key, idx = _resolve(path)
        dotted = f"arm.{path}"
        v = value
        if key.unit is not None and not isinstance(value, dict):
            v = {"value": value, "unit": key.unit}        # plain numbers are SI
        kw = by_table.setdefault(table, {})
        if idx is not None:
            cur = kw.get(key.attr, getattr(_part(arm, table), key.attr))
            if cur is None:          # an effect that is off has no entries to index
                raise ArmFileError(f"{dotted}: set the whole list first (the effect "
                                   f"{key.key} is off in this arm)")
            full = list(cur)
            full[idx] = read_value(dotted, Key(key.key, key.attr, key.unit, key.kind, 0), v)
            kw[key.attr] = tuple(full)
        else:
            kw[key.attr] = read_value(dotted, key, v, broadcast=True)
    try:
        return _rebuild(arm, by_table)
    except ArmFileError as exc:
        msg = str(exc)
        if not msg.startswith("arm."):
            base = msg.split(" ", 1)[0].split("[", 1)[0].rstrip(":")
            if base not in arm_parameter_paths():
                # a consistency check of the whole arm: name what was changed
                what = ", ".join(f"arm.{k[4:] if k.startswith('arm.') else k} = {_fmt(v)}"
                                 for k, v in changes.items())
                msg = f"{what}: {msg}"
            elif "." not in base:          # a root key ("gravity"): _ARM_KEY leaves those
                msg = "arm." + msg
        raise ArmFileError(_ARM_KEY.sub(r"arm.\1", msg)) from None


def _rebuild(arm, by_table: dict):
    """``arm`` with the fields ``by_table[table]`` (attr -> SI value) replaced, validated."""
    new = {}
    for table, kw in by_table.items():
        if table == "":
            continue
        obj = _part(arm, table)
        new[table] = _build(functools.partial(dataclasses.replace, obj), kw,
                            _keys_of(_CLASS_OF[table], table, TABLES[table]))
    top = dict(by_table.get("", {}))
    groups = [new.get(f"muscles.{g}", grp) for g, grp in zip(GROUPS, arm.muscles.groups)]
    muscles = new.get("muscles", arm.muscles)
    if any(f"muscles.{g}" in new for g in GROUPS):
        muscles = _build(functools.partial(dataclasses.replace, muscles),
                         {"groups": tuple(groups)}, {})
    if muscles is not arm.muscles:
        top["muscles"] = muscles
    if any(f"valves.{v}" in new for v in VALVES):
        top["valves"] = ValveSet(tuple(new.get(f"valves.{v}", val)
                                       for v, val in zip(VALVES, arm.valves.valves)))
    for table in ("geometry", "pneumatics", "links", "model", "model_gravity", "effects",
                  "sensors"):
        if table in new:
            top[table] = new[table]
    return _build(arm.replace, top, _keys_of("ArmParameters", "", ROOT_KEYS))


def effects_from_dict(effects, base: Effects | None = None) -> Effects:
    """``base`` (default: all off) with some effects set, validated like ``[effects]``.

    Parameters
    ----------
    effects : mapping of str to value
        Effect name -> value: a plain number (SI unit of the effect), ``{"value": v,
        "unit": u}``, a list for a vector effect, or one number for every entry of a
        vector effect (``{"hysteresis_delta": 0.299}`` sets the four groups).
    base : Effects, optional
        The effects the changes apply to.

    Returns
    -------
    Effects

    Raises
    ------
    ArmFileError
        Naming ``effects.<name>``, the value and what is allowed.
    """
    base = Effects() if base is None else base
    if not isinstance(base, Effects):
        raise TypeError(f"base must be an Effects, got {type(base).__name__}")
    if not hasattr(effects, "items"):
        raise ArmFileError(f"effects = {effects!r:.80}: must be a table of effect name -> value "
                           f"(e.g. {{ payload_mass = 0.5 }})")
    keys = {k.key: k for k in EFFECT_KEYS}
    kw = {}
    for name, v in effects.items():
        if name not in keys:
            raise ArmFileError(f"unknown effect effects.{name}; allowed: {list(keys)}")
        key = keys[name]
        if key.unit is not None and not isinstance(v, dict):
            v = {"value": v, "unit": key.unit}           # plain numbers are SI
        kw[key.attr] = read_value(f"effects.{name}", key, v, broadcast=True)
    if not kw:
        return base
    return _build(base.replace, kw, _keys_of("Effects", "effects", EFFECT_KEYS))


__all__ = ["ARM_FORMAT", "ArmFileError", "Key", "TABLES", "read_value", "arm_from_dict",
           "arm_from_toml", "read_arm_file", "arm_to_dict", "arm_to_toml", "arm_fingerprint",
           "apply_arm_changes", "effects_from_dict", "arm_parameter_paths", "arm_key"]
