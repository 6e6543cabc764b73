"""Covering files and contact point files: a robot's covering and its own contact points in TOML.

Like head and region files, every number is given with its unit and read into SI, every
file names its format, and an error names the key, its value and what is allowed.

Covering file (``format = "ppamsafety-covering/1"``)::

    format = "ppamsafety-covering/1"
    name = "10 mm PU foam"
    source = "supplier data sheet"
    [[layer]]                       # outermost first; none: bare metal
    name = "PU foam"
    law = "thin-layer"              # thin-layer | hertz | power
    modulus = { value = 1.2, unit = "MPa" }
    thickness = { value = 10, unit = "mm" }
    strain_limit = 0.8              # bottoms out at 80 % of its thickness
    hysteresis = { value = 9.8, unit = "s/m" }
    source = "..."

Contact point file (``format = "ppamsafety-contact/1"``)::

    format = "ppamsafety-contact/1"
    name = "gripper edge"
    link = 2
    position = { value = 320, unit = "mm" }   # from the link's joint along the link
    shape = "edge"                            # sphere | cylinder | edge | flat
    radius = { value = 2, unit = "mm" }       # omit for a flat face
    covering = "bare metal"                   # a covering name or a covering file
    source = "..."

The fields are those of :class:`~ppamsafety.params.contact.Layer`,
:class:`~ppamsafety.params.contact.Covering` and
:class:`~ppamsafety.params.contact.ContactPoint` (docs/impact_models.md).
"""

from __future__ import annotations

import math
from pathlib import Path

from .._inputfiles import read_text
from .._validation import did_you_mean
from ..units import si_factor
from .arm_file import ArmFileError, _literal, parse_document
from .contact import (SHAPES, ContactPoint, Covering, Layer, arm_contact_points,
                      check_point_on_arm, covering, covering_names)

COVERING_FORMAT = "ppamsafety-covering/1"
CONTACT_FORMAT = "ppamsafety-contact/1"
#: Numbers of a layer given with a unit: key -> SI unit.
LAYER_UNITS = {"modulus": "Pa", "thickness": "m", "hysteresis": "s/m", "stiffness": "N/m^n",
               "damping": "N s/m^(n+1)"}
#: Dimensionless numbers of a layer.
LAYER_PLAIN = ("poisson", "strain_limit", "exponent")


def _format(data, want, what):
    fmt = data.get("format", want)
    if fmt != want:
        raise ArmFileError(f"format = {fmt!r} is not {want!r} (a {what} file)")


def _unknown(data, allowed, where):
    for k in data:
        if k not in allowed:
            raise ArmFileError(f"unknown key {where}{k!r}{did_you_mean(k, list(allowed))}; "
                               f"allowed: {list(allowed)}")


def _quantity(key, raw, si_unit):
    """A number with its unit (``{ value = ..., unit = "..." }``) in SI."""
    if not isinstance(raw, dict) or "value" not in raw or "unit" not in raw:
        raise ArmFileError(f"{key} = {raw!r}: give the value with its unit, e.g. {key} = "
                           f"{{ value = ..., unit = \"{si_unit}\" }}")
    _unknown(raw, ("value", "unit"), f"in {key}: ")
    v = raw["value"]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
        raise ArmFileError(f"{key}.value = {v!r}: must be a finite number")
    if si_unit in ("s/m", "N/m^n", "N s/m^(n+1)"):
        if raw["unit"] != si_unit:
            raise ArmFileError(f"{key}.unit = {raw['unit']!r}: give it in {si_unit!r}")
        return float(v)
    try:
        return float(v) * si_factor(raw["unit"], si_unit, name=f"{key}.unit")
    except (TypeError, ValueError) as exc:
        raise ArmFileError(str(exc)) from None


def _layer(i, d) -> Layer:
    where = f"layer[{i}]"
    if not isinstance(d, dict):
        raise ArmFileError(f"{where} must be a table ([[layer]])")
    _unknown(d, ("name", "law", "source", *LAYER_UNITS, *LAYER_PLAIN), f"in {where}: ")
    for k in ("name", "law"):
        if k not in d:
            raise ArmFileError(f"{where}.{k} is missing")
    kw = {"name": d["name"], "law": d["law"], "source": d.get("source", "")}
    for k, u in LAYER_UNITS.items():
        if k in d:
            kw[k] = _quantity(f"{where}.{k}", d[k], u)
    for k in LAYER_PLAIN:
        if k in d:
            v = d[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ArmFileError(f"{where}.{k} = {v!r}: must be a number")
            kw[k] = float(v)
    try:
        return Layer(**kw)
    except (TypeError, ValueError) as exc:
        raise ArmFileError(f"{where}: {str(exc).replace('Layer.', '')}") from None


def _covering_from_dict(data) -> Covering:
    _format(data, COVERING_FORMAT, "covering")
    _unknown(data, ("format", "name", "source", "layer"), "")
    if "name" not in data:
        raise ArmFileError("missing key name")
    lays = data.get("layer", [])
    if not isinstance(lays, list):
        raise ArmFileError("layer must be an array of tables ([[layer]])")
    try:
        return Covering(name=data["name"], layers=tuple(_layer(i, d) for i, d in enumerate(lays)),
                        source=data.get("source", ""))
    except (TypeError, ValueError) as exc:
        raise ArmFileError(str(exc).replace("Covering.", "")) from None


def is_contact_file(value) -> bool:
    """``value`` names a covering or contact point file (a path, or a string ending in
    ``.toml``), not a built-in name.

    Parameters
    ----------
    value : object
        A covering or contact point argument.
    """
    return isinstance(value, Path) or (isinstance(value, str) and value.endswith(".toml"))


def load_covering(path) -> Covering:
    """Read and validate a covering file.

    Parameters
    ----------
    path : path-like
        The ``.toml`` file.

    Returns
    -------
    Covering
    """
    p, text = read_text(path, what="covering file", error=ArmFileError)
    return parse_document(text, _covering_from_dict, where=str(p))


def resolve_covering(value) -> Covering:
    """A covering from a name (:func:`~ppamsafety.params.contact.covering_names`), a covering
    file (a path or a string ending in ``.toml``) or a :class:`Covering`.

    Parameters
    ----------
    value : str, path-like or Covering
    """
    if isinstance(value, Covering):
        return value
    if is_contact_file(value):
        return load_covering(value)
    if isinstance(value, str):
        if value not in covering_names():
            raise ValueError(f"unknown covering {value!r}{did_you_mean(value, covering_names())}"
                             f"; choose from {covering_names()} or a covering file (.toml)")
        return covering(value)
    raise TypeError(f"covering must be a covering name, a covering file or a Covering, got "
                    f"{type(value).__name__}")


def covering_to_toml(cov: Covering) -> str:
    """The TOML text of a covering file (read back equal by :func:`load_covering`).

    Parameters
    ----------
    cov : Covering
    """
    lines = [f"format = {_literal(COVERING_FORMAT)}", f"name = {_literal(cov.name)}",
             f"source = {_literal(cov.source)}"]
    for lay in cov.layers:
        lines += ["", "[[layer]]", f"name = {_literal(lay.name)}", f"law = {_literal(lay.law)}"]
        for k, u in LAYER_UNITS.items():
            v = getattr(lay, k)
            if isinstance(v, float) and (math.isnan(v) or math.isinf(v)):
                continue
            if k in ("hysteresis", "damping") and v == 0.0:
                continue
            lines.append(f"{k} = {{ value = {_literal(float(v))}, unit = {_literal(u)} }}")
        for k in LAYER_PLAIN:
            v = getattr(lay, k)
            if not (isinstance(v, float) and math.isnan(v)):
                lines.append(f"{k} = {_literal(float(v))}")
        lines.append(f"source = {_literal(lay.source)}")
    return "\n".join(lines) + "\n"


def _contact_from_dict(data, base: Path | None) -> ContactPoint:
    _format(data, CONTACT_FORMAT, "contact point")
    allowed = ("format", "name", "link", "position", "shape", "radius", "covering", "source")
    _unknown(data, allowed, "")
    for k in ("name", "link", "position", "shape"):
        if k not in data:
            raise ArmFileError(f"missing key {k}")
    link = data["link"]
    if isinstance(link, bool) or link not in (1, 2):
        raise ArmFileError(f"link = {link!r}: must be 1 (upper arm) or 2 (forearm)")
    shape = data["shape"]
    if shape not in SHAPES:
        raise ArmFileError(f"shape = {shape!r}: must be one of {list(SHAPES)}")
    if shape == "flat":
        if "radius" in data:
            raise ArmFileError("radius: a flat face has none (leave radius out)")
        radius = math.inf
    elif "radius" not in data:
        raise ArmFileError(f"missing key radius (the {shape}'s radius, "
                           f"{{ value = ..., unit = \"mm\" }})")
    else:
        radius = _quantity("radius", data["radius"], "m")
    cov = data.get("covering", "bare metal")
    try:
        if is_contact_file(cov) and base is not None and not Path(cov).is_absolute():
            cov = base / cov
        cov = resolve_covering(cov)
    except (TypeError, ValueError, OSError) as exc:
        raise ArmFileError(f"covering = {data.get('covering')!r}: {exc}") from None
    try:
        return ContactPoint(name=data["name"], link=link,
                            position=_quantity("position", data["position"], "m"),
                            shape=shape, radius=radius, covering=cov,
                            source=data.get("source", ""))
    except (TypeError, ValueError) as exc:
        raise ArmFileError(str(exc).replace("ContactPoint.", "")) from None


def load_contact_point(path) -> ContactPoint:
    """Read and validate a contact point file (a covering file it names is read relative to it).

    Parameters
    ----------
    path : path-like
        The ``.toml`` file.

    Returns
    -------
    ContactPoint
    """
    p, text = read_text(path, what="contact point file", error=ArmFileError)
    return parse_document(text, lambda d: _contact_from_dict(d, Path(p).parent), where=str(p))


def resolve_contact_point(value, arm) -> ContactPoint:
    """A contact point from a name of the arm's points
    (:func:`~ppamsafety.params.contact.arm_contact_points`), a contact point file or a
    :class:`ContactPoint`.

    Parameters
    ----------
    value : str, path-like or ContactPoint
    arm : ArmParameters or None
        The arm whose default points are meant, and on whose links a point must lie
        (:func:`~ppamsafety.params.contact.check_point_on_arm`).  None (a study file read
        before its cases name their arm) reads and validates a file alone; the point is
        checked on the arm when a case is built.
    """
    if isinstance(value, ContactPoint):
        return value if arm is None else check_point_on_arm(value, arm)
    if is_contact_file(value):
        point = load_contact_point(value)
        if arm is None:
            return point
        try:
            return check_point_on_arm(point, arm)
        except ValueError as exc:
            raise ArmFileError(f"{value}: {exc}") from None
    if isinstance(value, str):
        pts = {p.name: p for p in arm_contact_points(arm)}
        if value not in pts:
            raise ValueError(f"unknown contact point {value!r}{did_you_mean(value, list(pts))}; "
                             f"choose from {list(pts)} or a contact point file (.toml)")
        return pts[value]
    raise TypeError(f"contact point must be a name, a contact point file or a ContactPoint, got "
                    f"{type(value).__name__}")


def contact_point_to_toml(point: ContactPoint, *, covering_file: str | None = None) -> str:
    """The TOML text of a contact point file.

    Parameters
    ----------
    point : ContactPoint
    covering_file : str, optional
        Name the covering by this file instead of by its name (a covering that is not one of
        :func:`~ppamsafety.params.contact.covering_names` needs its file).
    """
    lines = [f"format = {_literal(CONTACT_FORMAT)}", f"name = {_literal(point.name)}",
             f"link = {point.link}",
             f"position = {{ value = {_literal(float(point.position))}, unit = \"m\" }}",
             f"shape = {_literal(point.shape)}"]
    if point.shape != "flat":
        lines.append(f"radius = {{ value = {_literal(float(point.radius))}, unit = \"m\" }}")
    lines += [f"covering = {_literal(covering_file or point.covering.name)}",
              f"source = {_literal(point.source)}"]
    return "\n".join(lines) + "\n"


__all__ = ["COVERING_FORMAT", "CONTACT_FORMAT", "is_contact_file", "load_covering", "resolve_covering",
           "covering_to_toml", "load_contact_point", "resolve_contact_point",
           "contact_point_to_toml"]
