"""Campaigns: several records of one actuator on a bench, diagnosed together.

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
import pandas as pd

from ..results import Result
from .._inputfiles import read_text
from ..plots.bench import plot_campaign
from .._validation import did_you_mean
from .bench_import import Actuator, BenchProfile, import_bench, quantity
from .measured import (MeasuredData, MeasuredDataError, MeasuredDataWarning,
                       check_nominal_pressure, load_measured)

_MANIFEST_KEYS = ("name", "description", "profile", "experiment", "actuator", "records",
                  "source")
_RECORD_KEYS = ("file", "format", "pressure_nominal", "label", "run", "description")


@dataclass(frozen=True, eq=False)
class Campaign(Result):
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

    def to_pandas(self) -> pd.DataFrame:
        """One row per record: ``label``, ``source``, ``samples``, ``duration [s]`` and the
        nominal gauge pressure ``pressure_nominal [bar]``."""
        return pd.DataFrame({
            "label": self.labels(), "source": [r.source for r in self.records],
            "samples": [len(r.frame) for r in self.records],
            "duration [s]": [float(len(r.frame) * r.dt) for r in self.records],
            "pressure_nominal [bar]": self.pressure_levels() / 1e5})

    def plot(self, **kwargs):
        """Measured force against contraction (a cylinder: rod position), one curve per record,
        a matplotlib Figure.

        Parameters
        ----------
        **kwargs
            Passed to :func:`ppamsafety.plots.bench.plot_campaign` (``title``,
            ``max_points``).
        """
        muscle = self.actuator_type == "muscle"
        curves = [(lab, r.contraction() if muscle else r.column("position"), r.column("force"))
                  for lab, r in zip(self.labels(), self.records)]
        xlabel = "contraction [-]" if muscle else "rod position [m]"
        return plot_campaign(curves, xlabel=xlabel, **kwargs)


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

    Raises
    ------
    MeasuredDataError
        Anything wrong with the manifest, its profile or a record, naming the key
        (``records[2].file``) and the file.
    MissingFileError
        The manifest does not exist (a ``FileNotFoundError`` and a ``ValueError``).
    """
    p, text = read_text(path, what="campaign manifest", error=MeasuredDataError)
    if not isinstance(check_signs, bool):
        raise TypeError(f"check_signs must be True or False, got {check_signs!r}")
    try:
        man = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise MeasuredDataError(f"{p}: the manifest is not valid TOML: {exc}") from None
    unknown = [k for k in man if k not in _MANIFEST_KEYS]
    if unknown:
        raise MeasuredDataError(f"{p}: unknown manifest key(s) {unknown} (allowed: "
                                f"{', '.join(_MANIFEST_KEYS)}; a key after a [table] header "
                                f"belongs to that table)")
    for k in ("name", "description", "source", "experiment"):
        if k in man and not isinstance(man[k], str):
            raise MeasuredDataError(f"{p}: {k} = {man[k]!r} must be a string")
    recs = man.get("records")
    if recs is None:
        raise MeasuredDataError(f"{p}: no [[records]] (each with file = ...)")
    if not isinstance(recs, list) or not recs or not all(isinstance(r, dict) for r in recs):
        raise MeasuredDataError(f"{p}: records = {recs!r:.80} must be [[records]] tables (at "
                                f"least one, each with file = ...)")
    base = p.parent
    profile = None
    if "profile" in man:
        prof = man["profile"]
        try:
            if isinstance(prof, str) and prof.strip():
                profile = BenchProfile.from_toml(base / prof)
            elif isinstance(prof, dict):
                profile = BenchProfile.from_dict(prof)
            else:
                raise MeasuredDataError("must be the path of an import profile (relative to "
                                        "the manifest) or a [profile] table")
        except (ValueError, TypeError) as exc:
            raise MeasuredDataError(f"{p}: profile = {prof!r:.80}: {exc}") from None
    actuator = None
    if "actuator" in man:
        try:
            actuator = Actuator.from_dict(man["actuator"])
        except (ValueError, TypeError) as exc:
            raise MeasuredDataError(f"{p}: [actuator]: {exc}") from None
    out = []
    for i, r in enumerate(recs):
        where = f"{p}: records[{i}]"
        if "file" not in r:
            raise MeasuredDataError(f"{where} has no file = ... (the record's file, relative to "
                                    f"the manifest)")
        bad = [k for k in r if k not in _RECORD_KEYS]
        if bad:
            raise MeasuredDataError(f"{where}: unknown key(s) {bad} (allowed: "
                                    f"{', '.join(_RECORD_KEYS)})")
        if not isinstance(r["file"], str) or not r["file"].strip():
            raise MeasuredDataError(f"{where}.file = {r['file']!r} must be the path of a record "
                                    f"file (relative to the manifest)")
        for k, typ, what in (("label", str, "a string"), ("description", str, "a string"),
                             ("format", str, "'raw' or 'measured'"),
                             ("run", int, "an integer")):
            if k in r and (not isinstance(r[k], typ) or isinstance(r[k], bool)):
                raise MeasuredDataError(f"{where}.{k} = {r[k]!r} must be {what}")
        fmt = r.get("format", "raw")
        if fmt not in ("raw", "measured"):
            raise MeasuredDataError(f"{where}.format = {fmt!r} is not 'raw' or 'measured'"
                                    f"{did_you_mean(fmt, ('raw', 'measured'))}")
        f = base / r["file"]
        info = {k: r[k] for k in ("pressure_nominal", "label", "run") if k in r}
        if "pressure_nominal" in info:
            info["pressure_nominal"] = check_nominal_pressure(
                f"{where}.pressure_nominal", quantity(f"{where}.pressure_nominal",
                                                      info["pressure_nominal"], "Pa"))
        if fmt == "raw" and (profile is None or actuator is None):
            raise MeasuredDataError(f"{where} is a raw file: the manifest needs "
                                    f"profile = ... and an [actuator] table")
        try:
            if fmt == "raw":
                d = import_bench(f, profile, actuator=actuator,
                                 experiment=man.get("experiment", "tensile"),
                                 description=r.get("description", ""),
                                 source=man.get("source"), record=info,
                                 check_signs=check_signs)
            else:
                d = load_measured(f)
        except (ValueError, OSError) as exc:         # the record's own error, with its key
            raise MeasuredDataError(f"{where}.file = {r['file']!r}: {exc}") from None
        if fmt == "measured" and info:
            meta = dict(d.meta)
            meta["record"] = {**meta.get("record", {}), **info}
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", MeasuredDataWarning)
                d = MeasuredData(meta, d.frame, source=d.source)
        out.append(d)
    return Campaign(tuple(out), name=str(man.get("name", p.stem)),
                    description=str(man.get("description", "")))


__all__ = ["Campaign", "load_campaign"]
