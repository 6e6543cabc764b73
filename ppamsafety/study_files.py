"""Study files: a safety sweep described in TOML, run by ``ppamsafety sweep STUDY.toml``.

A study file names the cases of :func:`ppamsafety.sweep_cases.safety_case`
(experiments, controller families and gains, impact settings) and the
outputs.  Example (``studies/lambda_ki.toml``)::

    [study]
    name = "lambda-ki"                 # cache key part; default: the file name
    description = "joint PSMC, lambda x Ki"

    [case]                             # parameters shared by every case
    experiment = "step"
    controller = "PSMC joint"

    [impact]                           # impact settings (shared by every case)
    instants = "heuristic"             # "heuristic", "all" (with every = N ms) or one heuristic
    head = "thesis-frontal"
    # stiffness = 43.0                 # override (2.18) [Nm/rad]: one value or [K1, K2]

    [grid]                             # every combination of these lists
    lam = [0.05, 0.1, 0.2, 0.4, 0.8, 1.5, 2.5]
    ki_bar = [2, 6, 12]
    # stiffness = { geomspace = [1, 6000, 31] }   # or { linspace = [start, stop, num] }

    [[variants]]                       # optional explicit cases, each combined with the grid
    controller = "PID"

    [output]
    csv = "results.csv"                # result table (one row per case)
    histories = false                  # full time histories per case (Parquet or CSV)

The cases are every ``[[variants]]`` entry (or one empty entry) combined with
every grid point, merged over ``[case]`` and ``[impact]``; a parameter may be
set in only one of these places.  :func:`load_study` checks everything
before anything runs; an error names the key by its dotted path (for
example ``grid.lam[2]``) and the allowed values, unknown keys included.

:func:`run_study_file` writes the output folder through
:class:`ppamsafety.output.OutputFolder` (kind ``"sweep"``): the result CSV,
a copy of the study file (``study.toml``), the histories (``histories/``)
when asked for, and the resume cache ``cache/`` (a work folder: each case is
stored as soon as it finishes).  A folder that holds a previous sweep is
reused with ``resume=True`` (``--resume``: finished cases are not
recomputed) or replaced with ``overwrite=True`` (``--overwrite``: the
previous cache is cleared and everything recomputed).
"""

from __future__ import annotations

import importlib.util
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .output import OutputError, OutputFolder, read_marker
from .sweep import BACKENDS, grid_cases, run_sweep
from .sweep_cases import PARAMETERS, check_case, safety_case

#: Allowed keys per table of a study file.
SCHEMA = {
    "study": ("name", "description"),
    "case": tuple(k for k in PARAMETERS if k != "histories"),
    "impact": ("instants", "every", "head", "stiffness"),
    "grid": tuple(k for k in PARAMETERS if k != "histories"),
    "variants": tuple(k for k in PARAMETERS if k != "histories"),
    "output": ("csv", "histories"),
}
#: Generators allowed as a grid value: ``{geomspace = [start, stop, num]}`` and ``linspace``.
GENERATORS = ("geomspace", "linspace")
#: Kind recorded in the marker of a sweep output folder.
KIND = "sweep"


class StudyFileError(ValueError):
    """A study file is not valid; the message names the file and the dotted key."""


@dataclass
class Study:
    """A loaded, checked study file.

    Attributes
    ----------
    name : str
        Sweep name (part of the cache key).
    description : str
        Free text.
    cases : list of dict
        :func:`~ppamsafety.sweep_cases.safety_case` keyword arguments, checked.
    csv : str
        File name of the result table.
    histories : bool
        Write the full time histories of every case.
    source : str
        The TOML text.
    path : pathlib.Path or None
        Where it was read from.
    origins : list of int
        Per case, the index of the ``[[variants]]`` entry it came from.
    """

    name: str
    description: str
    cases: list
    csv: str = "results.csv"
    histories: bool = False
    source: str = ""
    path: Path | None = None
    origins: list = field(default_factory=list)


def _err(where: str, msg: str) -> StudyFileError:
    return StudyFileError(f"{where}: {msg}")


def _grid_values(where: str, key: str, v) -> list:
    if isinstance(v, dict):
        if len(v) != 1 or next(iter(v)) not in GENERATORS:
            raise _err(where, f"grid.{key} = {v!r}: an inline table must be one of "
                              f"{{geomspace = [start, stop, num]}} or {{linspace = [start, stop, "
                              f"num]}}")
        gen, args = next(iter(v.items()))
        ok = (isinstance(args, list) and len(args) == 3
              and all(isinstance(a, (int, float)) and not isinstance(a, bool) for a in args)
              and isinstance(args[2], int) and args[2] >= 1
              and all(math.isfinite(a) for a in args))
        if not ok or (gen == "geomspace" and min(args[:2]) <= 0):
            raise _err(where, f"grid.{key}.{gen} = {args!r} must be [start, stop, num] with "
                              f"finite numbers and an int num >= 1"
                              f"{' (start, stop > 0)' if gen == 'geomspace' else ''}")
        f = np.geomspace if gen == "geomspace" else np.linspace
        return [float(x) for x in f(args[0], args[1], args[2])]
    if not isinstance(v, list):
        raise _err(where, f"grid.{key} = {v!r} must be a list of values (or {{geomspace = "
                          f"[start, stop, num]}})")
    if not v:
        raise _err(where, f"grid.{key} is an empty list; give at least one value")
    return v


def _check_value(where: str, path: str, key: str, v) -> None:
    try:
        PARAMETERS[key][0](v)
    except (TypeError, ValueError) as exc:
        raise _err(where, f"{path} = {v!r}: {exc}") from None


def _check_keys(where: str, table: str, d) -> None:
    if not isinstance(d, dict):
        raise _err(where, f"{table} must be a table ([{table}]), got {type(d).__name__} {d!r:.60}")
    allowed = SCHEMA[table.split("[")[0]]
    for k in d:
        if k not in allowed:
            extra = (" ('histories' is set in [output])" if k == "histories" else "")
            raise _err(where, f"unknown key {table}.{k}; allowed keys of [{table.split('[')[0]}]: "
                              f"{list(allowed)}{extra}")


def parse_study(text: str, *, where: str = "study file", default_name: str = "study") -> Study:
    """Parse and check the TOML text of a study file.

    Parameters
    ----------
    text : str
        TOML text.
    where : str
        How the file is named in error messages.
    default_name : str
        Sweep name when ``[study] name`` is missing.

    Returns
    -------
    Study
        The checked study.

    Raises
    ------
    StudyFileError
        Naming the key by its dotted path and what is allowed.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _err(where, f"not valid TOML ({exc})") from None
    for k in data:
        if k not in SCHEMA:
            raise _err(where, f"unknown table [{k}]; allowed: {list(SCHEMA)}")
    study = data.get("study", {})
    _check_keys(where, "study", study)
    name = study.get("name", default_name)
    if not isinstance(name, str) or not name.strip():
        raise _err(where, f"study.name = {name!r} must be a non-empty string")
    desc = study.get("description", "")
    if not isinstance(desc, str):
        raise _err(where, f"study.description = {desc!r} must be a string")
    origin = {}                                  # parameter -> dotted path where it is set
    base = {}
    for table in ("case", "impact"):
        d = data.get(table, {})
        _check_keys(where, table, d)
        for k, v in d.items():
            if k in origin:
                raise _err(where, f"{table}.{k} is also set as {origin[k]}; set it in one place")
            _check_value(where, f"{table}.{k}", k, v)
            origin[k], base[k] = f"{table}.{k}", v
    grid = data.get("grid", {})
    _check_keys(where, "grid", grid)
    gvals = {}
    for k, v in grid.items():
        if k in origin:
            raise _err(where, f"grid.{k} is also set as {origin[k]}; set it in one place")
        vals = _grid_values(where, k, v)
        for i, x in enumerate(vals):
            _check_value(where, f"grid.{k}[{i}]", k, x)
        gvals[k] = vals
    variants = data.get("variants", [{}])
    if not isinstance(variants, list) or not variants:
        raise _err(where, "variants must be an array of tables ([[variants]] entries), "
                          "at least one")
    for j, var in enumerate(variants):
        _check_keys(where, f"variants[{j}]", var)
        for k, v in var.items():
            if k in origin or k in gvals:
                other = origin.get(k, f"grid.{k}")
                raise _err(where, f"variants[{j}].{k} is also set as {other}; set it in one place")
            _check_value(where, f"variants[{j}].{k}", k, v)
    out = data.get("output", {})
    _check_keys(where, "output", out)
    csv = out.get("csv", "results.csv")
    if (not isinstance(csv, str) or not csv.endswith(".csv") or "/" in csv or "\\" in csv
            or csv.startswith(".") or csv == "study.toml"):
        raise _err(where, f"output.csv = {csv!r} must be a file name ending in .csv (no folder, "
                          f"not hidden)")
    hist = out.get("histories", False)
    if not isinstance(hist, bool):
        raise _err(where, f"output.histories = {hist!r} must be true or false")
    cases, origins = [], []
    points = grid_cases(gvals) if gvals else [{}]
    for j, var in enumerate(variants):
        for g in points:
            c = {**base, **var, **g}
            if hist:
                c["histories"] = True
            try:
                check_case(**c)
            except (TypeError, ValueError) as exc:
                src = (f"variants[{j}]" if len(variants) > 1 or var else "") + (
                    f" with grid point {g}" if g else "")
                raise _err(where, f"case {len(cases)}{' (' + src.strip() + ')' if src else ''}: "
                                  f"{exc}") from None
            cases.append(c)
            origins.append(j)
    return Study(name=name.strip(), description=desc, cases=cases, csv=csv, histories=hist,
                 source=text, origins=origins)


def load_study(path) -> Study:
    """Read and check a study file (see the module docstring).

    Parameters
    ----------
    path : path-like
        The ``.toml`` file.

    Returns
    -------
    Study
        The checked study (``path`` set).
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"study file '{p}' does not exist or is not a file")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise _err(str(p), f"not UTF-8 text ({exc})") from None
    st = parse_study(text, where=str(p), default_name=p.stem)
    st.path = p
    return st


def history_format() -> str:
    """``"parquet"`` if pandas can write Parquet here (pyarrow or fastparquet), else ``"csv"``.

    Parquet is compact and typed; pyarrow is not a dependency of ppamsafety
    (a ~55 MB wheel, only needed for this optional output), so without it the
    histories are written as CSV.
    """
    for mod in ("pyarrow", "fastparquet"):
        if importlib.util.find_spec(mod) is not None:
            return "parquet"
    return "csv"


def _write_histories(df: pd.DataFrame, folder: Path) -> list:
    fmt = history_format()
    folder.mkdir(parents=True, exist_ok=True)
    files = []
    for i, h in zip(df.index, df["histories"]):
        if not isinstance(h, dict):
            continue                                  # failed case
        for kind, frame in h.items():
            f = folder / f"case{i:05d}_{kind}.{fmt}"
            if fmt == "parquet":
                frame.to_parquet(f, index=False)
            else:
                frame.to_csv(f, index=False)
            files.append(f.name)
    return files


def run_study_file(study, outdir, *, backend: str = "local", scheduler=None,
                   processes: int | None = None, resume: bool = False, overwrite: bool = False,
                   max_cases: int | None = None, progress: bool = True) -> pd.DataFrame:
    """Run a study and write its output folder.

    Parameters
    ----------
    study : Study or path-like
        A :class:`Study` or the path of a study file.
    outdir : path-like
        Output folder (kind ``"sweep"``).  New or empty; a previous sweep is
        reused with ``resume`` or replaced with ``overwrite``; a folder with
        files ppamsafety did not write is refused.
    backend : {"local", "dask"}
        Where the cases run (:func:`ppamsafety.sweep.run_sweep`).
    scheduler : None, str or dask.distributed.Client
        Dask scheduler (None: a LocalCluster for the run).
    processes : int, optional
        Local worker processes or LocalCluster workers (default: every core).
    resume : bool
        Reuse the finished cases in ``outdir/cache`` (allowed without
        ``overwrite`` for a folder holding a previous sweep).
    overwrite : bool
        Replace a previous ppamsafety output in ``outdir`` and recompute
        every case (the previous cache is cleared).
    max_cases : int, optional
        Run only the first ``max_cases`` cases (a preview or a test).
    progress : bool
        Progress bar.

    Returns
    -------
    pandas.DataFrame
        The result table as written (without the histories).
    """
    st = study if isinstance(study, Study) else load_study(study)
    for nm, v in (("resume", resume), ("overwrite", overwrite), ("progress", progress)):
        if not isinstance(v, bool):
            raise TypeError(f"{nm} must be True or False, got {v!r}")
    if backend not in BACKENDS:
        raise ValueError(f"backend = {backend!r} is not one of {list(BACKENDS)}")
    cases = st.cases
    if max_cases is not None:
        if isinstance(max_cases, bool) or not isinstance(max_cases, int) or max_cases < 1:
            raise ValueError(f"max_cases = {max_cases!r} must be a positive int or None")
        cases = cases[:max_cases]
    out = Path(outdir)
    ow, clean = overwrite, True
    if resume:
        marker = read_marker(out) if out.is_dir() else None
        nonempty = out.is_dir() and any(out.iterdir())
        if nonempty and (marker is None or marker.get("kind") != KIND):
            raise OutputError(f"--resume: output folder '{out}' is not a ppamsafety sweep folder "
                              f"(marker kind {KIND!r}); choose the folder of the interrupted "
                              f"sweep, or a new folder without --resume")
        ow, clean = True, False
    elif not overwrite and out.is_dir() and (read_marker(out) or {}).get("kind") == KIND:
        raise OutputError(f"output folder '{out}' holds a previous sweep; pass --resume "
                          f"(resume=True) to continue it without recomputing its finished cases, "
                          f"or --overwrite (overwrite=True) to recompute everything")
    folder = OutputFolder(out, kind=KIND, overwrite=ow, clean=clean)
    with folder as stage:
        cache = folder.workdir("cache", fresh=not resume)
        df = run_sweep(safety_case, cases, name=st.name, cache_dir=cache, processes=processes,
                       progress=progress, on_error="record", backend=backend, scheduler=scheduler)
        if "histories" in df.columns:
            _write_histories(df, stage / "histories")
            df = df.drop(columns=["histories"])
        df.to_csv(stage / st.csv, index=False)
        (stage / "study.toml").write_text(st.source, encoding="utf-8")
    return df


__all__ = ["SCHEMA", "GENERATORS", "KIND", "Study", "StudyFileError", "parse_study",
           "load_study", "history_format", "run_study_file"]
