"""Campaigns: several records of one actuator on a bench, diagnosed together (issue 20 item 2).

A bench campaign is what an experimenter's logbook holds: one actuator, one
set-up, records at several pressures (and repeats).  :class:`Campaign` keeps
the validated records in order with their per-record facts (nominal
pressure, label, run); :func:`load_campaign` reads a manifest::

    name = "O-ring257"
    profile = "profile.toml"        # import profile of the raw files (relative to the manifest)
    experiment = "tensile"

    [actuator]
    type = "cylinder"
    bore = "25.7 mm"

    [[records]]
    file = "O-ring257_1bar.csv.xz"
    pressure_nominal = "1 bar"
    [[records]]
    file = "O-ring257_3bar.csv.xz"
    pressure_nominal = "3 bar"

A record with ``format = "measured"`` is a file already in the measured-data
format (:func:`~ppamsafety.data.measured.load_measured`); the default,
``format = "raw"``, imports it with the profile
(:func:`~ppamsafety.data.bench_import.import_bench`).  Every record must
describe the same actuator (type and nominal force law).
"""

from __future__ import annotations

import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .bench_import import Actuator, BenchProfile, import_bench, quantity
from .measured import MeasuredData, MeasuredDataError, MeasuredDataWarning, load_measured

_MANIFEST_KEYS = ("name", "description", "profile", "experiment", "actuator", "records",
                  "source")
_RECORD_KEYS = ("file", "format", "pressure_nominal", "label", "run", "description")


@dataclass(frozen=True, eq=False)
class Campaign:
    """Records of one actuator, diagnosed together (:func:`ppamsafety.diagnose.diagnose`).

    Parameters
    ----------
    records : sequence of MeasuredData
        ``kind = "actuator"`` records of the same actuator (same type and
        nominal force law).
    name : str
        A label.
    description : str
        Free text.

    Attributes
    ----------
    notes : tuple of str
        Remarks made while assembling (e.g. nominal pressures taken from the data).
    """

    records: tuple
    name: str = "campaign"
    description: str = ""
    notes: tuple = field(default=(), init=False)

    def __post_init__(self):
        recs = tuple(self.records)
        if not recs:
            raise ValueError("records: a campaign needs at least one record")
        for i, r in enumerate(recs):
            if not isinstance(r, MeasuredData):
                raise TypeError(f"records[{i}] must be a MeasuredData, got {type(r).__name__}")
            if r.kind != "actuator":
                raise ValueError(f"records[{i}] ({r.source}) is kind = {r.kind!r}; a bench "
                                 f"campaign holds actuator records")
        if not isinstance(self.name, str) or not isinstance(self.description, str):
            raise TypeError("name and description must be strings")
        t0 = recs[0].actuator_type
        a0 = np.asarray(recs[0].meta["force_law"]["a"], float)
        for i, r in enumerate(recs[1:], 1):
            if r.actuator_type != t0:
                raise ValueError(f"records[{i}] ({r.source}) is a {r.actuator_type}, records[0] a "
                                 f"{t0}: a campaign is one actuator")
            a = np.asarray(r.meta["force_law"]["a"], float)
            if not np.allclose(a, a0, rtol=1e-9, atol=0):
                raise ValueError(f"records[{i}] ({r.source}) has force_law.a = {a.tolist()}, "
                                 f"records[0] {a0.tolist()}: a campaign is one actuator with one "
                                 f"nominal law")
        notes = []
        for i, r in enumerate(recs):
            if "pressure_nominal" not in r.meta.get("record", {}):
                notes.append(f"records[{i}] ({Path(r.source).name}): no record.pressure_nominal; "
                             f"the median measured pressure "
                             f"{np.median(r.column('pressure')) / 1e5:.3g} bar is used as its "
                             f"level")
        object.__setattr__(self, "records", recs)
        object.__setattr__(self, "notes", tuple(notes))

    def __len__(self) -> int:
        return len(self.records)

    @property
    def actuator_type(self) -> str:
        """``"cylinder"`` or ``"muscle"``."""
        return self.records[0].actuator_type

    @property
    def force_law(self) -> np.ndarray:
        """Nominal a0..a4 [N/Pa] (a cylinder: ``[0, A, 0, 0, 0]``)."""
        return np.asarray(self.records[0].meta["force_law"]["a"], float)

    def pressure_levels(self) -> np.ndarray:
        """Nominal gauge pressure of every record [Pa] (declared, else the median measured)."""
        return np.array([float(r.meta.get("record", {}).get(
            "pressure_nominal", np.median(r.column("pressure")))) for r in self.records])

    def labels(self) -> list:
        """A short label per record (``record.label``, else the file name)."""
        out = []
        for r in self.records:
            lab = r.meta.get("record", {}).get("label")
            out.append(str(lab) if lab else Path(r.source).name)
        return out


def load_campaign(path, *, check_signs: bool = True) -> Campaign:
    """Read a campaign manifest (module docstring) and import or load its records.

    Parameters
    ----------
    path : path-like
        The manifest (TOML); record files and the profile are relative to it.
    check_signs : bool, keyword-only
        Passed to :func:`~ppamsafety.data.bench_import.import_bench`.

    Returns
    -------
    Campaign
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"campaign manifest '{p}' does not exist")
    try:
        man = tomllib.loads(p.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise MeasuredDataError(f"{p}: the manifest is not valid TOML: {exc}") from None
    unknown = [k for k in man if k not in _MANIFEST_KEYS]
    if unknown:
        raise MeasuredDataError(f"{p}: unknown manifest key(s) {unknown} (allowed: "
                                f"{', '.join(_MANIFEST_KEYS)}; a key after a [table] header "
                                f"belongs to that table)")
    recs = man.get("records")
    if not isinstance(recs, list) or not recs:
        raise MeasuredDataError(f"{p}: no [[records]] (each with file = ...)")
    base = p.parent
    profile = None
    if "profile" in man:
        profile = BenchProfile.from_toml(base / man["profile"]) if isinstance(
            man["profile"], str) else BenchProfile.from_dict(man["profile"])
    actuator = Actuator.from_dict(man["actuator"]) if "actuator" in man else None
    out = []
    for i, r in enumerate(recs):
        if not isinstance(r, dict) or "file" not in r:
            raise MeasuredDataError(f"{p}: records[{i}] must be a table with file = ...")
        bad = [k for k in r if k not in _RECORD_KEYS]
        if bad:
            raise MeasuredDataError(f"{p}: records[{i}]: unknown key(s) {bad} (allowed: "
                                    f"{', '.join(_RECORD_KEYS)})")
        fmt = r.get("format", "raw")
        f = base / r["file"]
        info = {k: r[k] for k in ("pressure_nominal", "label", "run") if k in r}
        if "pressure_nominal" in info:
            info["pressure_nominal"] = quantity(f"{p}: records[{i}].pressure_nominal",
                                                info["pressure_nominal"], "Pa")
        if fmt == "raw":
            if profile is None or actuator is None:
                raise MeasuredDataError(f"{p}: records[{i}] is a raw file: the manifest needs "
                                        f"profile = ... and an [actuator] table")
            out.append(import_bench(f, profile, actuator=actuator,
                                    experiment=man.get("experiment", "tensile"),
                                    description=r.get("description", ""),
                                    source=man.get("source"), record=info,
                                    check_signs=check_signs))
        elif fmt == "measured":
            d = load_measured(f)
            if info:
                meta = dict(d.meta)
                meta["record"] = {**meta.get("record", {}), **info}
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", MeasuredDataWarning)
                    d = MeasuredData(meta, d.frame, source=d.source)
            out.append(d)
        else:
            raise MeasuredDataError(f"{p}: records[{i}].format = {fmt!r} is not 'raw' or "
                                    f"'measured'")
    return Campaign(tuple(out), name=str(man.get("name", p.stem)),
                    description=str(man.get("description", "")))


__all__ = ["Campaign", "load_campaign"]
