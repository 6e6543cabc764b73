"""ISO/TS 15066:2016 Annex A body model: every body location, with its values' sources.

ISO/TS 15066:2016 "Robots and robotic devices -- Collaborative robots" is a
*technical specification*, not a standard: its Annex A (informative) gives
biomechanical limits for 29 body locations in 12 body regions (Table A.2): the
maximum permissible quasi-static pressure per location and force per region,
with a multiplier for transient contact; and an effective spring constant K and
an effective mass m_H per region (Table A.3) for its two-body energy-transfer
model.  Its pressure limits are the 75th percentile of the pain-onset pressures
measured on 100 healthy adults in a single study (University of Mainz; a flat
1.4 x 1.4 cm metal probe with a 2 mm edge radius); its force limits come from a
literature review (188 sources) of the lowest energy transfer giving a minor
injury (AIS 1, a bruise).  The TS itself says further studies may change the
values.

Sources and confirmation.  The TS text is not public and was not read here.
Every value carries its citation and whether it is *confirmed*: printed by at
least one public transcription we read (2026-11, text search of public code
and pages; :data:`TRANSCRIPTIONS`):

* **A** -- the source comments of a ROS 2 power-and-force-limiting controller
  reproduce Table A.2 (the pressure of every location, one value per hand
  location, and the force of every region) and Table A.3 (K and m_H of every
  region);
* **B** -- a research note that read the TS text reproduces the head, neck,
  chest, arm and hand rows of Table A.2 (the dominant and non-dominant hand
  values), K and m_H of the neck, hand and lower arm, and footnote c:
  transient limits are 2 x the quasi-static values, and *none is given for
  the skull, forehead and face* (transient contact with them is not
  permissible, clause A.3.2);
* **C** -- a cobot-safety reference page prints K of the skull/forehead
  (150 N/mm) and the face (75 N/mm);
* **D** -- a power-and-force-limiting calculator applies footnote c to the
  pressure as to the force (transient p_T = 2 x p_qs).

So the transient limits of the two head regions are *not* in the TS: the
factor 2 used for them (260 N at the forehead, the limit the report
quotes) is an analogy with the other regions and is flagged
unconfirmed in :attr:`BodyRegion.unconfirmed`; every head verdict is also
given against the quasi-static force (factor 1), the reading of the TS.

A :class:`BodyRegion` is one body *location* of Table A.2 within its body
region.  Region files (TOML, ``format = "ppamsafety-region/1"``) describe a
user's own location or measurement with the same keys, every value with its
unit, source and confirmation (:meth:`BodyRegion.to_toml`, :func:`load_region`,
:func:`resolve_region`); errors name the key.  Measured pain thresholds with
their percentiles (e.g. Behrens et al. 2022, Frontiers in Robotics and AI
8:667818, CC BY 4.0) are :class:`PainThreshold` entries of a region
(``[[pain]]`` in a file).

Two-body model of Annex A (implemented in :mod:`ppamsafety.impact.pfl`):
E = F^2/(2k) = A^2 p^2/(2k), E = mu v_rel^2 / 2 with
mu = (1/m_H + 1/m_R)^-1, hence v_rel,max = F_max / sqrt(mu k).

The full table of values with their sources is ``docs/body_regions.md``.
"""

from __future__ import annotations

import math
import types
from dataclasses import dataclass
from pathlib import Path

from .._inputfiles import read_text
from .._validation import check_range, check_str, did_you_mean
from ..units import si_factor
from .arm_file import ArmFileError, _literal, parse_document

#: Citation of the Annex used by every value of this module.
SOURCE = "ISO/TS 15066:2016, Annex A (informative), Tables A.2 and A.3"
#: The public transcriptions of Annex A that confirm a value (module docstring).
TRANSCRIPTIONS = {
    "A": "Table A.2/A.3 as transcribed in the source comments of a public ROS 2 "
         "power-and-force-limiting controller (text search of public code, 2026-11)",
    "B": "Table A.2/A.3 and footnote c as transcribed in a public research note that read "
         "the TS text (text search of public code, 2026-11)",
    "C": "a public cobot-safety reference page (inmotion, 'ISO/TS 15066 body region force "
         "limits'): effective spring constants of the skull/forehead and face",
    "D": "a public power-and-force-limiting calculator (STIMBA Safety, 'PFL calculator -- "
         "transient contact', safety.stimba.sk/en/pfl, read 2026-11): Table A.2 note c, "
         "transient limits 2 x the quasi-static values for the pressure as for the force, "
         "and the pressure's speed limit v = p_T A / sqrt(mu K) with A the smaller contact "
         "area of the robot's part and the body (A.3.5)",
}

#: Total moving mass of the thesis arm [kg]: "its total mass of around 2.5 kg" (thesis §6.3.5;
#: links about 1.5 kg and just over 1 kg, §3.5).
THESIS_ARM_MASS = 2.5

#: N/cm^2 in Pa.
N_PER_CM2 = 1.0e4
#: N/mm in N/m.
N_PER_MM = 1.0e3

#: The numeric fields of a :class:`BodyRegion` that carry a source: name -> (SI unit, low,
#: high, low open, what it is).
VALUE_FIELDS = {
    "force_quasi_static": ("N", 0.0, 1e4, True, "maximum permissible quasi-static force"),
    "pressure_quasi_static": ("Pa", 0.0, 1e8, True,
                              "maximum permissible quasi-static pressure"),
    "transient_factor": ("-", 1.0, 10.0, False,
                         "multiplier of the quasi-static force for transient contact"),
    "pressure_transient_factor": ("-", 1.0, 10.0, False,
                                  "multiplier of the quasi-static pressure for transient "
                                  "contact"),
    "spring_constant": ("N/m", 0.0, 1e9, True, "effective spring constant K of the region"),
    "effective_mass": ("kg", 0.0, 200.0, True, "effective mass m_H of the body region"),
}
#: Kinds of contact a pain threshold was measured in.
CONTACTS = ("transient", "quasi-static")
#: Quantities a pain threshold bounds: name -> SI unit.
QUANTITIES = {"force": "N", "pressure": "Pa"}


@dataclass(frozen=True)
class PainThreshold:
    """Measured pain thresholds of one body location, by percentile of the subjects.

    Attributes
    ----------
    study : str
        Short name of the study (e.g. ``"behrens2022"``).
    quantity : {"force", "pressure"}
        What was measured (SI: N, Pa).
    contact : {"transient", "quasi-static"}
        Impact or pinching/clamping.
    percentiles : tuple of (float, float)
        ``(percentile in (0, 100), threshold [SI])``, percentiles increasing, thresholds
        non-decreasing (a higher percentile of the subjects feels pain at a higher load).
    source : str
        Citation (table, figure).
    confirmed : bool
        The values were read from the cited source (False: transcribed second hand).
    """

    study: str
    quantity: str
    contact: str
    percentiles: tuple
    source: str = ""
    confirmed: bool = False

    def __post_init__(self):
        check_str("PainThreshold.study", self.study, allow_empty=False)
        check_str("PainThreshold.source", self.source)
        if self.quantity not in QUANTITIES:
            raise ValueError(f"PainThreshold.quantity = {self.quantity!r}: must be one of "
                             f"{list(QUANTITIES)}")
        if self.contact not in CONTACTS:
            raise ValueError(f"PainThreshold.contact = {self.contact!r}: must be one of "
                             f"{list(CONTACTS)}")
        if not isinstance(self.confirmed, bool):
            raise TypeError(f"PainThreshold.confirmed must be True or False, got "
                            f"{self.confirmed!r}")
        pts = tuple(self.percentiles) if isinstance(self.percentiles, (list, tuple)) else None
        if not pts:
            raise ValueError(f"PainThreshold.percentiles = {self.percentiles!r}: give at least "
                             f"one (percentile, threshold) pair")
        out = []
        unit = QUANTITIES[self.quantity]
        for i, pv in enumerate(pts):
            if not (isinstance(pv, (list, tuple)) and len(pv) == 2):
                raise ValueError(f"PainThreshold.percentiles[{i}] = {pv!r}: must be "
                                 f"(percentile, threshold)")
            p = check_range(f"PainThreshold.percentiles[{i}] percentile", pv[0], 0.0, 100.0,
                            lo_open=True, hi_open=True, unit="%")
            v = check_range(f"PainThreshold.percentiles[{i}] threshold", pv[1], 0.0,
                            1e4 if unit == "N" else 1e8, lo_open=True, unit=unit)
            out.append((p, v))
        for (p0, v0), (p1, v1) in zip(out, out[1:]):
            if not p1 > p0:
                raise ValueError(f"PainThreshold.percentiles: percentiles must increase, got "
                                 f"{p0:g} then {p1:g}")
            if v1 < v0:
                raise ValueError(f"PainThreshold.percentiles: the threshold at the {p1:g}th "
                                 f"percentile ({v1:g} {unit}) is below the {p0:g}th's "
                                 f"({v0:g} {unit})")
        object.__setattr__(self, "percentiles", tuple(out))

    @property
    def unit(self) -> str:
        """SI unit of the thresholds (``"N"`` or ``"Pa"``)."""
        return QUANTITIES[self.quantity]


@dataclass(frozen=True)
class BodyRegion:
    """ISO/TS 15066 Annex A limits and body-model values of one body location.

    Attributes
    ----------
    name : str
        Location label (``"skull/forehead"``, ``"chest/sternum"`` ...).
    force_quasi_static : float
        Maximum permissible quasi-static contact force F_qs [N], in (0, 1e4] (per body
        region in Table A.2).
    pressure_quasi_static : float
        Maximum permissible quasi-static pressure p_qs [Pa], in (0, 1e8]
        (1 N/cm^2 = 1e4 Pa).
    transient_factor : float
        Multiplier of F_qs for transient contact [-], in [1, 10].
    spring_constant : float
        Effective spring constant K of the region [N/m], in (0, 1e9].
    effective_mass : float
        Effective mass m_H of the body region [kg], in (0, 200].
    source : str
        Citation of the values without a source of their own (:attr:`sources`).
    unconfirmed : tuple of str
        Fields whose values no public source we read confirms (module docstring).
    region : str
        Body region of Table A.2/A.3 (``"skull and forehead"``); "" for a user's location
        outside Annex A.
    location : int
        Annex A body location number, 1-29 (0: not an Annex A location).
    location_name : str
        The location as Table A.2 names it (``"middle of forehead"``).
    head : bool
        A location of the head (the head criteria -- fractures, HIC -- apply).
    transient_in_ts : bool
        Table A.2 gives a transient multiplier for this region (False for the skull,
        forehead and face: transient contact with them is not permissible).
    pressure_transient_factor : float or None
        Multiplier of p_qs for transient contact (None: :attr:`transient_factor`).
    sources : tuple of (str, str)
        ``(field, citation)`` for the values with a source other than :attr:`source`.
    pain : tuple of PainThreshold
        Measured pain thresholds of the location (other studies than the TS).

    Notes
    -----
    The transient limits are :attr:`force_transient` = factor x F_qs and
    :attr:`pressure_transient` = pressure factor x p_qs.
    """

    name: str
    force_quasi_static: float
    pressure_quasi_static: float
    transient_factor: float
    spring_constant: float
    effective_mass: float
    source: str = SOURCE
    unconfirmed: tuple = ()
    region: str = ""
    location: int = 0
    location_name: str = ""
    head: bool = False
    transient_in_ts: bool = True
    pressure_transient_factor: float | None = None
    sources: tuple = ()
    pain: tuple = ()

    def __post_init__(self):
        check_str("BodyRegion.name", self.name, allow_empty=False)
        for f in ("source", "region", "location_name"):
            check_str(f"BodyRegion.{f}", getattr(self, f))
        if self.pressure_transient_factor is None:
            object.__setattr__(self, "pressure_transient_factor", self.transient_factor)
        for f, (unit, lo, hi, lo_open, _) in VALUE_FIELDS.items():
            object.__setattr__(self, f, check_range(
                f"BodyRegion.{f} (region {self.name!r})", getattr(self, f), lo, hi,
                lo_open=lo_open, unit=unit))
        for f in ("head", "transient_in_ts"):
            if not isinstance(getattr(self, f), bool):
                raise TypeError(f"BodyRegion.{f} must be True or False, got "
                                f"{getattr(self, f)!r}")
        if isinstance(self.location, bool) or not isinstance(self.location, int) \
                or not 0 <= self.location <= 29:
            raise ValueError(f"BodyRegion.location = {self.location!r}: must be an Annex A body "
                             f"location 1-29, or 0 for none")
        if isinstance(self.unconfirmed, (str, bytes)) or not hasattr(self.unconfirmed, "__iter__"):
            raise TypeError(f"BodyRegion.unconfirmed must be a tuple of field names, got "
                            f"{self.unconfirmed!r}")
        unc = tuple(self.unconfirmed)
        bad = [u for u in unc if u not in VALUE_FIELDS]
        if bad:
            raise ValueError(f"BodyRegion.unconfirmed = {unc!r}: {bad} are not fields; allowed "
                             f"{sorted(VALUE_FIELDS)}")
        object.__setattr__(self, "unconfirmed", tuple(f for f in VALUE_FIELDS if f in unc))
        src = tuple(tuple(s) for s in self.sources) if isinstance(self.sources, (list, tuple)) \
            else None
        if src is None or not all(len(s) == 2 and s[0] in VALUE_FIELDS and isinstance(s[1], str)
                                  for s in src):
            raise ValueError(f"BodyRegion.sources = {self.sources!r}: must be (field, citation) "
                             f"pairs with fields in {sorted(VALUE_FIELDS)}")
        order = list(VALUE_FIELDS)
        object.__setattr__(self, "sources", tuple(sorted(src, key=lambda s: order.index(s[0]))))
        pain = tuple(self.pain) if isinstance(self.pain, (list, tuple)) else None
        if pain is None or not all(isinstance(p, PainThreshold) for p in pain):
            raise TypeError(f"BodyRegion.pain must be a tuple of PainThreshold, got "
                            f"{self.pain!r:.80}")
        object.__setattr__(self, "pain", pain)

    @property
    def force_transient(self) -> float:
        """Maximum permissible transient contact force [N]: factor x F_qs."""
        return self.transient_factor * self.force_quasi_static

    @property
    def pressure_transient(self) -> float:
        """Maximum permissible transient pressure [Pa]: pressure factor x p_qs."""
        return self.pressure_transient_factor * self.pressure_quasi_static

    def source_of(self, name: str) -> str:
        """Citation of one value.

        Parameters
        ----------
        name : str
            A key of :data:`VALUE_FIELDS`.
        """
        if name not in VALUE_FIELDS:
            raise ValueError(f"name = {name!r}: not a value of a body region; choose from "
                             f"{list(VALUE_FIELDS)}")
        return dict(self.sources).get(name, self.source)

    def confirmed(self, name: str) -> bool:
        """Whether a public source we read confirms one value (module docstring).

        Parameters
        ----------
        name : str
            A key of :data:`VALUE_FIELDS`.
        """
        self.source_of(name)
        return name not in self.unconfirmed

    def to_toml(self) -> str:
        """The TOML text of a region file describing this location (exact round trip).

        Returns
        -------
        str
            ``BodyRegion.from_toml(region.to_toml()) == region``.
        """
        lines = [f"format = {_literal(REGION_FORMAT)}", f"name = {_literal(self.name)}",
                 f"region = {_literal(self.region)}", f"location = {self.location}",
                 f"location_name = {_literal(self.location_name)}",
                 f"head = {_literal(self.head)}",
                 f"transient_in_ts = {_literal(self.transient_in_ts)}",
                 f"source = {_literal(self.source)}"]
        for f, (unit, *_rest, doc) in VALUE_FIELDS.items():
            v = getattr(self, f)
            parts = [f"value = {_literal(float(v))}"]
            if unit != "-":
                parts.append(f"unit = {_literal(unit)}")
            if f in dict(self.sources):
                parts.append(f"source = {_literal(dict(self.sources)[f])}")
            parts.append(f"confirmed = {_literal(f not in self.unconfirmed)}")
            lines.append(f"{f} = {{ {', '.join(parts)} }}  # {doc}")
        for p in self.pain:
            lines += ["", "[[pain]]", f"study = {_literal(p.study)}",
                      f"quantity = {_literal(p.quantity)}", f"contact = {_literal(p.contact)}",
                      f"unit = {_literal(p.unit)}",
                      "percentiles = [" + ", ".join(
                          f"[{_literal(float(a))}, {_literal(float(b))}]"
                          for a, b in p.percentiles) + "]  # [percentile, threshold]",
                      f"source = {_literal(p.source)}",
                      f"confirmed = {_literal(p.confirmed)}"]
        return "\n".join(lines) + "\n"

    @classmethod
    def from_toml(cls, text: str, *, where: str = "") -> "BodyRegion":
        """Parse and validate the TOML text of a region file.

        Parameters
        ----------
        text : str
            TOML text (``format = "ppamsafety-region/1"``, see :meth:`to_toml`).
        where : str
            How to name the file in error messages (its path).

        Returns
        -------
        BodyRegion

        Raises
        ------
        ArmFileError
            A ``ValueError`` naming the key, its value and what is allowed.
        """
        return parse_document(text, _region_from_dict, where=where)


#: The ``format`` string of a region file.
REGION_FORMAT = "ppamsafety-region/1"
#: Plain keys of a region file: key -> (type, required).
_PLAIN_KEYS = {"format": (str, False), "name": (str, True), "region": (str, False),
               "location": (int, False), "location_name": (str, False), "head": (bool, False),
               "transient_in_ts": (bool, False), "source": (str, False)}
_PAIN_KEYS = ("study", "quantity", "contact", "unit", "percentiles", "source", "confirmed")


def _value_entry(key: str, raw) -> tuple:
    """(SI value, source or None, confirmed) of one value key of a region file."""
    unit, lo, hi, lo_open, doc = VALUE_FIELDS[key]
    if not isinstance(raw, dict):
        example = f"{{ value = {raw!r}, unit = \"{unit}\", source = \"...\", confirmed = true }}" \
            if unit != "-" else f"{{ value = {raw!r}, source = \"...\", confirmed = true }}"
        raise ArmFileError(f"{key} = {raw!r}: give the value as a table with its unit, source "
                           f"and confirmation, e.g. {key} = {example}")
    allowed = {"value", "unit", "source", "confirmed"}
    extra = sorted(set(raw) - allowed)
    if extra:
        raise ArmFileError(f"{key}: unknown key(s) {extra}; allowed {sorted(allowed)}")
    if "value" not in raw:
        raise ArmFileError(f"{key}: missing value ({doc})")
    v = raw["value"]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
        raise ArmFileError(f"{key}.value = {v!r}: must be a finite number")
    factor = 1.0
    if unit != "-":
        if "unit" not in raw:
            raise ArmFileError(f"{key}: missing unit (SI: {unit!r})")
        try:
            factor = si_factor(raw["unit"], unit, name=f"{key}.unit")
        except (TypeError, ValueError) as exc:
            raise ArmFileError(str(exc)) from None
    elif "unit" in raw and raw["unit"] not in ("", "-", "1"):
        raise ArmFileError(f"{key}.unit = {raw['unit']!r}: {key} is dimensionless")
    si = float(v) * factor
    op = ">" if lo_open else ">="
    if not ((si > lo if lo_open else si >= lo) and si <= hi):
        raise ArmFileError(f"{key}.value = {v!r} {raw.get('unit', '')}".rstrip()
                           + f": must be {op} {lo:g} and <= {hi:g} {unit if unit != '-' else ''}"
                           .rstrip() + f" ({doc})")
    src = raw.get("source")
    if src is not None and not isinstance(src, str):
        raise ArmFileError(f"{key}.source = {src!r}: must be a string")
    conf = raw.get("confirmed", False)
    if not isinstance(conf, bool):
        raise ArmFileError(f"{key}.confirmed = {conf!r}: must be true or false")
    return si, src, conf


def _pain_from_dict(i: int, d) -> PainThreshold:
    where = f"pain[{i}]"
    if not isinstance(d, dict):
        raise ArmFileError(f"{where} must be a table ([[pain]]), got {d!r:.60}")
    extra = sorted(set(d) - set(_PAIN_KEYS))
    if extra:
        raise ArmFileError(f"{where}: unknown key(s) {extra}; allowed {list(_PAIN_KEYS)}")
    for k in ("study", "quantity", "contact", "unit", "percentiles"):
        if k not in d:
            raise ArmFileError(f"{where}.{k} is missing")
    q = d["quantity"]
    if q not in QUANTITIES:
        raise ArmFileError(f"{where}.quantity = {q!r}: must be one of {list(QUANTITIES)}")
    try:
        factor = si_factor(d["unit"], QUANTITIES[q], name=f"{where}.unit")
    except (TypeError, ValueError) as exc:
        raise ArmFileError(str(exc)) from None
    pts = d["percentiles"]
    if not (isinstance(pts, list) and pts and all(
            isinstance(x, list) and len(x) == 2 and all(
                isinstance(y, (int, float)) and not isinstance(y, bool) for y in x)
            for x in pts)):
        raise ArmFileError(f"{where}.percentiles = {pts!r}: must be a list of [percentile, "
                           f"threshold] pairs of numbers")
    try:
        return PainThreshold(study=d["study"], quantity=q, contact=d["contact"],
                             percentiles=tuple((float(a), float(b) * factor) for a, b in pts),
                             source=d.get("source", ""), confirmed=d.get("confirmed", False))
    except (TypeError, ValueError) as exc:
        raise ArmFileError(f"{where}: {str(exc).replace('PainThreshold.', '')}") from None


def _region_from_dict(data) -> BodyRegion:
    fmt = data.get("format", REGION_FORMAT)
    if fmt != REGION_FORMAT:
        what = (" (a head file?)" if isinstance(fmt, str) and "head" in fmt else
                " (an arm file?)" if isinstance(fmt, str) and "arm" in fmt else "")
        raise ArmFileError(f"format = {fmt!r} is not {REGION_FORMAT!r}{what}")
    allowed = [*_PLAIN_KEYS, *VALUE_FIELDS, "pain"]
    for k in data:
        if k not in allowed:
            raise ArmFileError(f"unknown key {k!r} in a region file{did_you_mean(k, allowed)}; "
                               f"allowed: {allowed}")
    kw = {}
    for k, (typ, required) in _PLAIN_KEYS.items():
        if k not in data:
            if required:
                raise ArmFileError(f"missing key {k}")
            continue
        v = data[k]
        if typ is int and (isinstance(v, bool) or not isinstance(v, int)):
            raise ArmFileError(f"{k} = {v!r}: must be an integer")
        if typ is not int and not isinstance(v, typ):
            raise ArmFileError(f"{k} = {v!r}: must be {'true or false' if typ is bool else 'a string'}")
        if k != "format":
            kw[k] = v
    if "location" in kw and not 0 <= kw["location"] <= 29:
        raise ArmFileError(f"location = {kw['location']}: must be an Annex A body location 1-29, "
                           f"or 0 for a location outside Annex A")
    unconfirmed, sources = [], []
    for k in VALUE_FIELDS:
        if k not in data:
            if k == "pressure_transient_factor":
                continue
            raise ArmFileError(f"missing key {k} ({VALUE_FIELDS[k][4]}, "
                               f"{{ value = ..., unit = \"{VALUE_FIELDS[k][0]}\" }})")
        si, src, conf = _value_entry(k, data[k])
        kw[k] = si
        if src is not None:
            sources.append((k, src))
        if not conf:
            unconfirmed.append(k)
    pain = data.get("pain", [])
    if not isinstance(pain, list):
        raise ArmFileError(f"pain must be an array of tables ([[pain]]), got {pain!r:.60}")
    kw["pain"] = tuple(_pain_from_dict(i, d) for i, d in enumerate(pain))
    try:
        return BodyRegion(unconfirmed=tuple(unconfirmed), sources=tuple(sources), **kw)
    except (TypeError, ValueError) as exc:
        raise ArmFileError(str(exc).replace("BodyRegion.", "")) from None


def load_region(path) -> BodyRegion:
    """Read and validate a region file (:meth:`BodyRegion.from_toml`).

    Parameters
    ----------
    path : path-like
        The ``.toml`` file.

    Returns
    -------
    BodyRegion
    """
    p, text = read_text(path, what="region file", error=ArmFileError)
    return BodyRegion.from_toml(text, where=str(p))


# ------------------------------------------------------------------------ the Annex A data
#: The 12 body regions of Table A.2/A.3: name -> (short name, F_qs [N], K [N/mm], m_H [kg],
#: transient multiplier given in the TS, head, which transcriptions print F_qs, K and m_H).
REGIONS = {
    "skull and forehead": ("skull", 130.0, 150.0, 4.4, False, True, "AB", "AC", "A"),
    "face": ("face", 65.0, 75.0, 4.4, False, True, "AB", "AC", "A"),
    "neck": ("neck", 150.0, 50.0, 1.2, True, False, "AB", "AB", "AB"),
    "back and shoulders": ("back", 210.0, 35.0, 40.0, True, False, "A", "A", "A"),
    "chest": ("chest", 140.0, 25.0, 40.0, True, False, "AB", "A", "A"),
    "abdomen": ("abdomen", 110.0, 10.0, 40.0, True, False, "A", "A", "A"),
    "pelvis": ("pelvis", 180.0, 25.0, 40.0, True, False, "A", "A", "A"),
    "upper arms and elbow joints": ("upper arm", 150.0, 30.0, 3.0, True, False, "AB", "A",
                                    "A"),
    "lower arms and wrist joints": ("lower arm", 160.0, 40.0, 2.0, True, False, "AB", "AB",
                                    "AB"),
    "hands and fingers": ("hand", 140.0, 75.0, 0.6, True, False, "AB", "AB", "AB"),
    "thighs and knees": ("thigh", 220.0, 50.0, 75.0, True, False, "A", "A", "A"),
    "lower legs": ("lower leg", 130.0, 60.0, 75.0, True, False, "A", "A", "A"),
}
#: The 29 body locations of Table A.2: (number, region, location, short name, p_qs
#: [N/cm^2], transcriptions printing p_qs).
LOCATIONS = (
    (1, "skull and forehead", "middle of forehead", "skull/forehead", 130.0, "AB"),
    (2, "skull and forehead", "temple", "skull/temple", 110.0, "AB"),
    (3, "face", "masticatory muscle", "face", 110.0, "AB"),
    (4, "neck", "neck muscle", "neck/muscle", 140.0, "AB"),
    (5, "neck", "seventh neck muscle", "neck/seventh muscle", 210.0, "AB"),
    (6, "back and shoulders", "shoulder joint", "back/shoulder joint", 160.0, "A"),
    (7, "back and shoulders", "fifth lumbar vertebra", "back/fifth lumbar vertebra", 210.0,
     "A"),
    (8, "chest", "sternum", "chest/sternum", 120.0, "AB"),
    (9, "chest", "pectoral muscle", "chest/pectoral muscle", 170.0, "AB"),
    (10, "abdomen", "abdominal muscle", "abdomen", 140.0, "A"),
    (11, "pelvis", "pelvic bone", "pelvis", 210.0, "A"),
    (12, "upper arms and elbow joints", "deltoid muscle", "upper arm/deltoid muscle", 190.0,
     "AB"),
    (13, "upper arms and elbow joints", "humerus", "upper arm/humerus", 220.0, "AB"),
    (14, "lower arms and wrist joints", "radial bone", "lower arm/radial bone", 190.0, "AB"),
    (15, "lower arms and wrist joints", "forearm muscle", "lower arm/forearm muscle", 180.0,
     "AB"),
    (16, "lower arms and wrist joints", "arm nerve", "lower arm/arm nerve", 180.0, "AB"),
    (17, "hands and fingers", "forefinger pad, dominant hand", "hand/forefinger pad D", 300.0,
     "AB"),
    (18, "hands and fingers", "forefinger pad, non-dominant hand", "hand/forefinger pad ND",
     270.0, "B"),
    (19, "hands and fingers", "forefinger end joint, dominant hand",
     "hand/forefinger end joint D", 280.0, "AB"),
    (20, "hands and fingers", "forefinger end joint, non-dominant hand",
     "hand/forefinger end joint ND", 220.0, "B"),
    (21, "hands and fingers", "thenar eminence", "hand/thenar eminence", 200.0, "AB"),
    (22, "hands and fingers", "palm, dominant hand", "hand/palm D", 260.0, "AB"),
    (23, "hands and fingers", "palm, non-dominant hand", "hand/palm ND", 260.0, "AB"),
    (24, "hands and fingers", "back of the hand, dominant hand", "hand/back D", 200.0, "AB"),
    (25, "hands and fingers", "back of the hand, non-dominant hand", "hand/back ND", 190.0,
     "B"),
    (26, "thighs and knees", "thigh muscle", "thigh/muscle", 250.0, "A"),
    (27, "thighs and knees", "kneecap", "thigh/kneecap", 220.0, "A"),
    (28, "lower legs", "middle of shin", "lower leg/middle of shin", 220.0, "A"),
    (29, "lower legs", "calf muscle", "lower leg/calf muscle", 210.0, "A"),
)


def _cite(which: str) -> str:
    return ("confirmed by transcription " if len(which) == 1 else
            "confirmed by transcriptions ") + ", ".join(which)


def _annex_location(number, region, location, name, p, p_by) -> BodyRegion:
    short, F, K, m, in_ts, head, F_by, K_by, m_by = REGIONS[region]
    where = f"{SOURCE}: body region {region!r}, location {number} ({location})"
    sources = [("force_quasi_static", f"{SOURCE}, Table A.2: {region} ({_cite(F_by)})"),
               ("pressure_quasi_static",
                f"{SOURCE}, Table A.2: location {number}, {location} ({_cite(p_by)}); the 75th "
                f"percentile of the Mainz pain-onset pressures"),
               ("spring_constant", f"{SOURCE}, Table A.3: {region} ({_cite(K_by)})"),
               ("effective_mass", f"{SOURCE}, Table A.3: {region} ({_cite(m_by)})")]
    if in_ts:
        note = (f"{SOURCE}, Table A.2 footnote c: transient limits are 2 x the quasi-static "
                f"values (confirmed by transcription B)")
        unconfirmed = ()
        p_note = (f"{SOURCE}, Table A.2 footnote c: transient limits are 2 x the quasi-static "
                  f"values, the pressure's as the force's (confirmed by transcriptions B, D)")
    else:
        note = ("not in the TS: Table A.2 gives no transient multiplier for the skull, "
                "forehead and face (footnote c, transcription B; transient contact with them "
                "is not permissible, A.3.2); 2 by analogy with the other regions (the 260 N "
                "forehead limit the report quotes); the quasi-static force is the TS reading")
        unconfirmed = ("transient_factor", "pressure_transient_factor")
        p_note = note
    sources += [("transient_factor", note), ("pressure_transient_factor", p_note)]
    return BodyRegion(name=name, force_quasi_static=F, pressure_quasi_static=p * N_PER_CM2,
                      transient_factor=2.0, spring_constant=K * N_PER_MM, effective_mass=m,
                      source=where, unconfirmed=unconfirmed, region=region, location=number,
                      location_name=location, head=head, transient_in_ts=in_ts,
                      sources=tuple(sources))


def _build() -> types.MappingProxyType:
    return types.MappingProxyType({loc[3]: _annex_location(*loc) for loc in LOCATIONS})


_REGIONS = _build()

SKULL_FOREHEAD = _REGIONS["skull/forehead"]
FACE = _REGIONS["face"]


def body_region(name) -> BodyRegion:
    """A named body location of ISO/TS 15066 Annex A: one of :func:`body_region_names`.

    Parameters
    ----------
    name : str or int
        A location name (``"skull/forehead"``, ``"chest/sternum"``, ``"hand/back D"``) or
        its Annex A number 1-29 (an int, or a string of digits as a command line gives it).

    Returns
    -------
    BodyRegion
    """
    if isinstance(name, str) and name.strip().lstrip("+-").isdigit():
        name = int(name)                    # "12" on a command line is location 12
    if isinstance(name, int) and not isinstance(name, bool):
        if not 1 <= name <= len(LOCATIONS):
            raise ValueError(f"name = {name}: an Annex A body location number is 1-"
                             f"{len(LOCATIONS)} (or give a name such as 'chest/sternum', or a "
                             f"region file, .toml)")
        return _REGIONS[LOCATIONS[name - 1][3]]
    check_str("name", name)
    if name not in _REGIONS:
        raise ValueError(f"name = {name!r}: unknown body region{did_you_mean(name, list(_REGIONS))}"
                         f"; choose from {list(_REGIONS)}, an Annex A location number 1-"
                         f"{len(LOCATIONS)} (or a region file, .toml)")
    return _REGIONS[name]


def body_region_names() -> list:
    """Names accepted by :func:`body_region`, in the order of Annex A (locations 1-29)."""
    return list(_REGIONS)


def resolve_region(region=None) -> BodyRegion:
    """A body region from a name, a number, a region file or a :class:`BodyRegion`.

    Parameters
    ----------
    region : str, int, path-like, BodyRegion or None
        None: ``"skull/forehead"`` (where the thesis' head is hit); a name or number of
        :func:`body_region`; the path of a region file (a string ending in ``.toml``).

    Returns
    -------
    BodyRegion
    """
    if region is None:
        return SKULL_FOREHEAD
    if isinstance(region, BodyRegion):
        return region
    if isinstance(region, Path) or (isinstance(region, str) and region.endswith(".toml")):
        return load_region(region)
    if isinstance(region, (str, int)) and not isinstance(region, bool):
        return body_region(region)
    raise TypeError(f"region must be a body region name, an Annex A number, a region file or a "
                    f"BodyRegion, got {type(region).__name__} {region!r:.60}")


def annex_a_table() -> str:
    """The 29 locations with every value and which transcriptions confirm it (Markdown).

    ``docs/body_regions.md`` holds this table (a test keeps it equal).

    Returns
    -------
    str
        A Markdown table, one row per Annex A body location.
    """
    head = ("| # | body region | location | name in the toolkit | p_qs [N/cm^2] | F_qs [N] | "
            "transient factor | F_transient [N] | K [N/mm] | m_H [kg] | confirmed by |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|\n")
    rows = []
    for number, region, location, name, p, p_by in LOCATIONS:
        short, F, K, m, in_ts, hd, F_by, K_by, m_by = REGIONS[region]
        fac = "2" if in_ts else "none in the TS (2 by analogy, unconfirmed)"
        rows.append(f"| {number} | {region} | {location} | `{name}` | {p:g} | {F:g} | {fac} | "
                    f"{2 * F:g} | {K:g} | {m:g} | p: {', '.join(p_by)}; F: {', '.join(F_by)}; "
                    f"K: {', '.join(K_by)}; m_H: {', '.join(m_by)} |")
    return head + "\n".join(rows) + "\n"


__all__ = ["annex_a_table", "BodyRegion", "PainThreshold", "SKULL_FOREHEAD", "FACE", "body_region",
           "body_region_names", "resolve_region", "load_region", "REGIONS", "LOCATIONS",
           "VALUE_FIELDS", "REGION_FORMAT", "TRANSCRIPTIONS", "THESIS_ARM_MASS", "SOURCE",
           "N_PER_CM2", "N_PER_MM"]
