"""Study files: a safety sweep described in TOML, run by ``ppamsafety sweep STUDY.toml``.

A study file names the cases of :func:`ppamsafety.sweep_cases.safety_case`
(experiments, controller families and gains, impact settings) and the
outputs.  Example (the shipped study ``lambda_ki``)::

    [study]
    name = "lambda-ki"                 # cache key part; default: the file name
    description = "joint PSMC, lambda x Ki"

    [case]                             # parameters shared by every case
    experiment = "step"
    controller = "PSMC joint"

    [impact]                           # impact settings (shared by every case)
    instants = "heuristic"             # "heuristic", "all" (with every = N ms) or one heuristic
    head = "thesis-frontal"            # default; a study that names none takes --head
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

Your arm, your head, effects and design parameters::

    [arm]
    file = "my_arm.toml"               # an arm file (relative to the study file)
    [head]
    file = "my_head.toml"              # a head file (instead of [impact] head)

    [case]
    effects = { hysteresis_delta = 0.299 }        # plant effects of every case
    arm.links.m2 = 1.4                            # any key of the arm file [SI]

    [grid]
    arm.pneumatics.mean_pressure = { linspace = [1.2, 2.0, 5], unit = "bar" }
    effects.payload_mass = [0.0, 0.5, 1.0]        # one effect per axis

A covering and a contact point (``covering``, ``contact``: a built-in name or a covering or
contact point file, read relative to the study file) and the covering's layer
(``covering_thickness``, ``covering_modulus``, ``covering_hysteresis``, with a unit too)::

    [grid]
    covering = ["bare metal", "foam.toml"]
    contact = ["forearm", "gripper_edge.toml"]
    covering_thickness = { values = [2, 8], unit = "mm" }

Dotted keys (``arm.<key of an arm file>``, ``effects.<name>``) are validated like the
arm file; a plain number is in the key's SI unit, ``{value = ..., unit = "..."}`` or a
generator with ``unit`` converts (:mod:`ppamsafety.params.arm_file`; the ``covering_*`` keys
too), and the outputs show a value in the unit the study file wrote it in.  ``--arm`` and
``--head`` on the command line replace ``[arm]`` and ``[head]``.

A safety envelope instead of a grid (:func:`ppamsafety.envelope.safety_envelope`)::

    [envelope]
    parameter = "arm.pneumatics.mean_pressure"    # or "lam", "speed", any numeric key
    range = [1.2e5, 2.0e5]
    # range = { values = [1.2, 2.0], unit = "bar" }   # the same, with a unit
    limit = "F_max"                    # a criterion: "F_max" (maxilla 660 N), "HIC36" (650),
                                       # "iso_ts_15066" (transient), "iso_ts_15066_qs" ...
    # limit_value = 200.0              # another value of that limit [N] (or {value, unit})
    # region = "skull/forehead"        # body region struck and judged (or a region file):
                                       #   a region not of the head on its Annex A body
    tolerance = 0.01                   # relative width of a final bracket
    scan = 9                           # values evaluated first (every crossing bracketed)
    # pose = [50.0, -80.0]             # "speed" only: link angles q1, q2 at impact [deg]
    # direction = [1.0, 0.0]           # "speed" only: joint-space direction (qd1, qd2),
                                       #   scaled so that the tool moves at the speed

The cases are every ``[[variants]]`` entry (or one empty entry) combined with
every grid point, merged over ``[case]`` and ``[impact]``; a parameter may be
set in only one of these places.  :func:`load_study` checks everything
before anything runs; an error names the key by its dotted path (for
example ``grid.lam[2]``) and the allowed values, unknown keys included.
What would fail at run time is refused at load time too: gains beyond the
controllers' limits (the controller of every case is built), stiffnesses the
impact model cannot resolve, durations shorter than the experiment's events,
and an empty study.

Shipped studies: the studies the report's sweep sections run ship with the package
(:data:`STUDY_DATA`, :func:`shipped_studies`): ``lambda_ki`` (the section ``lambda_sweep``) and
``table_6_1`` (the experiments and controller variants of the section ``safety``).
:func:`load_study` (and ``ppamsafety sweep NAME``) takes such a name where no file of that
name exists, so the report and the command line run one definition.

The cases are a :class:`CaseGrid`: generated one by one when read, never a
list, so a study of 10^9 grid points loads at once and is costed by
:func:`estimate_cases` (cases, time, memory) before anything runs.  A run
estimated above :data:`CONFIRM_HOURS` needs ``confirm=True`` (``--yes``) or a
preview (``max_cases``, ``--max-cases``); one whose results would exceed
:data:`ppamsafety._validation.MAX_BYTES` is refused (:func:`check_run_size`).

:func:`run_study_file` writes the output folder through
:class:`ppamsafety.output.OutputFolder` (kind ``"sweep"``): the result CSV,
a copy of the study file (``study.toml``), the histories (``histories/``)
when asked for, and the resume cache ``cache/`` (a work folder: each case is
stored as soon as it finishes).  A folder that holds a previous sweep is
reused with ``resume=True`` (``--resume``: finished cases are not
recomputed) or replaced with ``overwrite=True`` (``--overwrite``: the
previous cache is cleared and everything recomputed).  Beside the CSV the folder
holds a figure of every result against every swept parameter with the 660 N maxilla
line, the HIC 650 line and the ISO/TS 15066 forehead limit (``summary.png``), an HTML
page (``summary.html``: what was run, on which arm and head, the figure and the
table), and the arm and head used (``arm.toml``, ``head.toml``).
"""

from __future__ import annotations

import hashlib
import html
import importlib.util
import itertools
import math
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ._inputfiles import check_input_path, read_text
from ._jit import available_cores
from ._validation import MAX_BYTES, check_int, did_you_mean
from .envelope import SCAN, check_bounds, resolve_limit, safety_envelope
from .experiments.catalog import DEFAULT_DURATIONS, ControllerVariant
from .impact.head import HeadContactModel, load_head
from .output import OutputError, OutputFolder, check_output_path, read_marker
from .design import load_arm
from .params import ArmParameters, is_thesis_arm, thesis_arm
from .params.arm_file import ArmFileError, arm_key, arm_to_toml, read_value
from .params.contact_files import is_contact_file
from .plots.figure import save as save_figure
from .plots.sweep import limit_lines, plot_sweep
from .results import unit_name
from .sweep import BACKENDS, SweepResult, run_sweep
from .sweep_cases import (COVERING_RANGES, DEFAULTS, EXPERIMENTS, IMPACT_POSE_DEG, PARAMETERS,
                          SPEED_MAX, STEP_KEYS, add_verdicts, case_arm, case_function,
                          case_references, check_case, check_impact_case, column_unit,
                          failed_criteria, impact_pose_deg, is_dotted, make_controller,
                          verdict_limits)
from .impact.verdicts import METRICS
from .units import si_factor

#: Folder of the shipped studies (package data): the report's sweep sections run these files.
STUDY_DATA = Path(__file__).parent / "study_data"
#: Keys of a case that build its controller (:func:`~ppamsafety.sweep_cases.make_controller`).
CONTROLLER_KEYS = ("lam", "kp_bar", "ki_bar", "kd_bar", "task_kp", "task_ki", "task_kd")

#: Allowed keys per table of a study file.
SCHEMA = {
    "study": ("name", "description"),
    "case": tuple(k for k in PARAMETERS if k != "histories"),
    "impact": ("instants", "every", "head", "stiffness"),
    "grid": tuple(k for k in PARAMETERS if k != "histories"),
    "variants": tuple(k for k in PARAMETERS if k != "histories"),
    "output": ("csv", "histories"),
    "arm": ("file",),
    "head": ("file",),
    "envelope": ("parameter", "range", "limit", "limit_value", "region", "tolerance", "scan",
                 "pose", "direction"),
}
#: Generators allowed as a grid value: ``{geomspace = [start, stop, num]}`` and ``linspace``.
GENERATORS = ("geomspace", "linspace")
#: Kind recorded in the marker of a sweep output folder.
KIND = "sweep"
#: A generated grid axis of at most this many values is NumPy's array; longer ones are
#: computed value by value when read (:class:`Axis`).
MATERIALISE = 10 ** 6
#: Studies of at most this many cases have each case checked when loaded; larger ones have
#: the representative cases checked (:func:`_check_combinations`).
CHECK_ALL = 10 ** 4


class StudyFileError(ValueError):
    """A study file is not valid; the message names the file and the dotted key."""


class Axis(Sequence):
    """The values of one grid key: a TOML list, or a generator computed on demand.

    ``{geomspace = [start, stop, num]}`` and ``{linspace = ...}`` with up to
    :data:`MATERIALISE` values are NumPy's arrays; a longer one is never
    materialised: its i-th value is computed from the formula (equal to NumPy's up to
    rounding), so a grid of 10^9 points costs nothing until it runs.

    The values are in SI units; ``unit`` and ``factor`` say in which unit the study file
    gave them (shown so in the table and figure of the sweep).

    Parameters
    ----------
    values : list, optional
        The values of a TOML list.
    gen : {"geomspace", "linspace"}, optional, keyword-only
        A generator instead of ``values``.
    start, stop : float, keyword-only
        Its first and last values.
    num : int, keyword-only
        Its number of values.
    """

    def __init__(self, values=None, *, gen: str | None = None, start=0.0, stop=0.0, num=0):
        self.gen, self.start, self.stop, self.num = gen, start, stop, num
        self._values = None if values is None else list(values)
        self._reps = None
        #: The unit the study file wrote the values in and its factor to SI (``value_si =
        #: value * factor``); None: SI.
        self.unit, self.factor = None, 1.0
        if gen is not None and num <= MATERIALISE:
            f = np.geomspace if gen == "geomspace" else np.linspace
            self._values = [float(x) for x in f(start, stop, num)]

    def __len__(self) -> int:
        return len(self._values) if self._values is not None else self.num

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        if self._values is not None:
            return self._values[i]
        n = self.num
        i = range(n)[i]
        if i == n - 1:
            return float(self.stop)
        if self.gen == "linspace":
            return float(self.start + (self.stop - self.start) * i / (n - 1))
        a, b = math.log10(self.start), math.log10(self.stop)
        return float(10.0 ** (a + (b - a) * i / (n - 1)))

    def representatives(self) -> list:
        """Indices that stand for every value in the checks: all values of a list of
        non-numbers (or of a short list), else the first, the smallest, the largest and any
        zero (a generator is monotonic: its ends, and a zero it passes through)."""
        if self._reps is not None:
            return self._reps
        n = len(self)
        if n <= 16:
            reps = list(range(n))
        elif self.gen is not None:
            reps = [0, n - 1]
            if self.gen == "linspace" and self.start * self.stop < 0:
                k = round(-self.start / (self.stop - self.start) * (n - 1))
                reps += [i for i in (k - 1, k, k + 1) if 0 <= i < n and self[i] == 0]
        else:
            vals = self._values
            if all(type(v) in (int, float) for v in vals):
                a = np.asarray(vals, dtype=float)
                reps = sorted({0, int(np.argmin(a)), int(np.argmax(a)),
                               *np.flatnonzero(a == 0)[:1].tolist()})
            else:
                reps = list(range(n))
        self._reps = sorted(set(reps))
        return self._reps


class CaseGrid(Sequence):
    """The cases of a study, generated on demand (never a list of a million dicts).

    Case ``i`` is ``{**base, **variants[j], **point}`` with ``j = i // P`` and the grid
    point ``i % P`` (``P`` points, the first grid key varying slowest), plus
    ``histories=True`` when the study asks for histories: the order of
    :func:`ppamsafety.sweep.grid_cases` within each ``[[variants]]`` entry.

    Parameters
    ----------
    base : dict
        Parameters of ``[case]`` and ``[impact]``.
    variants : list of dict
        The ``[[variants]]`` entries (one empty entry if none).
    axes : dict of str to Axis
        The grid keys and their values, the first varying slowest.
    histories : bool
        Add ``histories=True`` to every case.
    limit : int, optional
        Only the first ``limit`` cases (a preview); default all.
    """

    def __init__(self, base: dict, variants: list, axes: dict, histories: bool,
                 limit: int | None = None):
        self.base, self.variants, self.axes, self.histories = base, variants, axes, histories
        self.points = math.prod(len(a) for a in axes.values())
        self.total = len(variants) * self.points
        self.limit = self.total if limit is None else min(limit, self.total)

    def __len__(self) -> int:
        return self.limit

    def index(self, j: int, point: dict) -> int:
        """Position of variant ``j`` at the grid point given by axis indices ``point``.

        Parameters
        ----------
        j : int
            Index of the ``[[variants]]`` entry.
        point : dict of str to int
            Index into each axis.
        """
        k = 0
        for key, a in self.axes.items():
            k = k * len(a) + point[key]
        return j * self.points + k

    def case(self, j: int, point: dict) -> dict:
        """The case of variant ``j`` at the grid point given by axis indices ``point``.

        Parameters
        ----------
        j : int
            Index of the ``[[variants]]`` entry.
        point : dict of str to int
            Index into each axis.
        """
        c = {**self.base, **self.variants[j],
             **{key: self.axes[key][point[key]] for key in self.axes}}
        if self.histories:
            c["histories"] = True
        return c

    def origin(self, i: int) -> int:
        """Index of the ``[[variants]]`` entry case ``i`` comes from.

        Parameters
        ----------
        i : int
            Case index.
        """
        return range(self.limit)[i] // self.points

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        i = range(self.limit)[i]
        j, k = divmod(i, self.points)
        point = {}
        for key in reversed(list(self.axes)):
            k, point[key] = divmod(k, len(self.axes[key]))
        return self.case(j, point)

    def head(self, n: int) -> "CaseGrid":
        """The first ``n`` cases (a view).

        Parameters
        ----------
        n : int
            Number of cases.
        """
        return CaseGrid(self.base, self.variants, self.axes, self.histories, limit=n)


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
        Per case, the index of the ``[[variants]]`` entry it came from (computed).
    arm : ArmParameters or None
        The arm of every case (``[arm] file`` or ``--arm``; None: the thesis arm).
    head : HeadContactModel or None
        The head of every case (``[head] file`` or ``--head``; None: the cases' own).
    envelope : dict or None
        The ``[envelope]`` search (parameter, bounds, limit, tolerance, case), if any.
    files : dict
        The covering and contact point files the cases name: the path a case holds (relative
        to the study file's folder, made absolute) -> the text the study file gives.
    units : dict
        Key -> the unit ``[case]`` or ``[[variants]]`` write its value in (``{ value = 4,
        unit = "mm" }``), for the outputs.

    ``cases`` is a :class:`CaseGrid`: the cases are generated when they are read, so a
    study of any size loads at once; :meth:`estimate` says what running it costs.
    """

    name: str
    description: str
    cases: Sequence
    csv: str = "results.csv"
    histories: bool = False
    source: str = ""
    path: Path | None = None
    arm: ArmParameters | None = None
    head: HeadContactModel | None = None
    envelope: dict | None = None
    files: dict = field(default_factory=dict)
    units: dict = field(default_factory=dict)

    @property
    def cache_name(self) -> str:
        """The sweep name of the cache key: :attr:`name`, and the contents of the covering and
        contact point files the cases name (an edited file is never served from the cache)."""
        if not self.files:
            return self.name
        h = hashlib.sha1()
        for f in sorted(self.files):
            h.update(f.encode())
            try:
                h.update(Path(f).read_bytes())
            except OSError:
                h.update(b"missing")
        return f"{self.name} [files {h.hexdigest()[:10]}]"

    def references_text(self) -> str:
        """The reference the study's experiment runs on its arm, in words with units.

        The first case's experiment and ``step_*_deg`` keys on the study's arm
        (:func:`~ppamsafety.sweep_cases.case_references`); a swept working area or experiment
        is said.
        """
        case = dict(self.cases[0]) if len(self.cases) else {}
        arm = self.arm if self.arm is not None else thesis_arm()
        exp = case.get("experiment") or DEFAULTS["experiment"]
        if exp not in EXPERIMENTS:
            return "-"
        refs = case_references(arm, {k: case.get(k) for k in STEP_KEYS})
        text = f"{exp}: {refs.describe('step' if exp == 'step' else 'circle')}"
        swept = self.swept
        if "experiment" in swept:
            text += "; the experiment is swept: this is the first case's"
        if any(k.startswith("arm.geometry.") for k in swept) or any(k in swept
                                                                      for k in STEP_KEYS):
            text += "; swept per case (the working area or the step keys vary)"
        return text

    @property
    def swept(self) -> list:
        """The case parameters that take more than one value (the grid, the variants)."""
        c = self.cases
        if isinstance(c, CaseGrid):      # never generates the cases: axes and variants only
            keys = list(dict.fromkeys([*c.base, *(k for v in c.variants for k in v), *c.axes]))
            keys = [k for k in keys if k != "histories"]
            return [k for k in keys
                    if (len(c.axes[k]) > 1 if k in c.axes else
                        len({repr({**c.base, **v}.get(k)) for v in c.variants}) > 1)]
        keys = list(dict.fromkeys(k for case in c for k in case if k != "histories"))
        return [k for k in keys if len({repr(case.get(k)) for case in c}) > 1]

    def unit_of(self, key: str) -> tuple:
        """(unit, factor to SI) a parameter or result column is shown in: the unit the study
        file gave a grid key in, else its SI unit (:func:`ppamsafety.sweep_cases.column_unit`;
        ``"-"`` dimensionless; None: text, a flag or a list).

        Parameters
        ----------
        key : str
            A case parameter or result column.
        """
        axis = self.cases.axes.get(key) if isinstance(self.cases, CaseGrid) else None
        if axis is not None and axis.unit is not None:
            return axis.unit, axis.factor
        if key in self.units and axis is None:
            si = UNIT_KEYS.get(key) or arm_key(key).unit
            return self.units[key], si_factor(self.units[key], si, name=key)
        if key in DISPLAY_UNITS:
            return DISPLAY_UNITS[key]
        if self.envelope is not None and key == "value":
            return column_unit(self.envelope["parameter"]), 1.0
        if self.envelope is not None and key == "margin":        # limit - metric: its unit
            return column_unit(f"{self.envelope.get('limit', 'F_max')}_margin"), 1.0
        return column_unit(key), 1.0

    @property
    def origins(self) -> list:
        """Per case, the index of the ``[[variants]]`` entry it came from."""
        c = self.cases
        return [c.origin(i) for i in range(len(c))] if isinstance(c, CaseGrid) else \
            [0] * len(c)

    def estimate(self, *, processes: int | None = None, max_cases: int | None = None) -> dict:
        """What running the study would cost: :func:`estimate_cases` of its cases.

        Parameters
        ----------
        processes : int, optional, keyword-only
            Worker processes (default every available core).
        max_cases : int, optional, keyword-only
            Cost only the first ``max_cases`` cases.
        """
        n = len(self.cases) if max_cases is None else min(max_cases, len(self.cases))
        cases = self.cases.head(n) if isinstance(self.cases, CaseGrid) else self.cases[:n]
        return estimate_cases(cases, processes=processes, histories=self.histories)


#: Result columns a person reads in another unit than SI: (unit, factor to SI).  The contact
#: pressure in N/cm^2, the unit of ISO/TS 15066 Annex A's pressure limits and of ``impact``.
DISPLAY_UNITS = {"p_max": ("N/cm^2", 1.0e4)}


def _err(where: str, msg: str) -> StudyFileError:
    return StudyFileError(f"{where}: {msg}")


#: Case keys (besides the dotted arm keys) whose values a study file may give with a unit
#: (``{ value = 5, unit = "mm" }``, ``{ values = [...], unit = "mm" }``): key -> SI unit.
UNIT_KEYS = {k: unit for k, (_, _, unit) in COVERING_RANGES.items()}


def _has_unit(key: str) -> bool:
    return is_dotted(key) or key in UNIT_KEYS


def _grid_values(where: str, key: str, v) -> Axis:
    if isinstance(v, dict) and "unit" in v and _has_unit(key):
        v = dict(v)
        unit = v.pop("unit")
        if len(v) == 1 and next(iter(v)) in GENERATORS:      # the ends in SI, then the grid
            gen, args = next(iter(v.items()))
            if isinstance(args, list) and len(args) == 3:
                args = [_dotted_si(where, f"grid.{key}.{gen}[{i}]", key,
                                   {"value": x, "unit": unit}) for i, x in enumerate(args[:2])
                        ] + args[2:]
            return _with_unit(_grid_values(where, key, {gen: args}), key, unit)
        vals = v.pop("values") if set(v) == {"values"} else None
        if not isinstance(vals, list) or not vals:
            raise _err(where, f"grid.{key} = {v!r}: with a unit give {{values = [...], unit = "
                              f"...}} (a non-empty list) or a generator {{linspace = [start, "
                              f"stop, num], unit = ...}}")
        return _with_unit(Axis([_dotted_si(where, f"grid.{key}[{i}]", key,
                                           {"value": x, "unit": unit})
                                for i, x in enumerate(vals)]), key, unit)
    if isinstance(v, dict):
        _unit_refused(where, f"grid.{key}", key, v)
        if len(v) != 1 or next(iter(v)) not in GENERATORS:
            raise _err(where, f"grid.{key} = {v!r}: an inline table must be one of "
                              f"{{geomspace = [start, stop, num]}} or {{linspace = [start, stop, "
                              f"num]}}" + (" (with unit = \"...\" for a dotted arm key, or "
                                           "{values = [...], unit = \"...\"})"
                                           if _has_unit(key) else ""))
        gen, args = next(iter(v.items()))
        ok = (isinstance(args, list) and len(args) == 3
              and all(isinstance(a, (int, float)) and not isinstance(a, bool) for a in args)
              and isinstance(args[2], int) and args[2] >= 1
              and all(math.isfinite(a) for a in args))
        if not ok or (gen == "geomspace" and min(args[:2]) <= 0):
            raise _err(where, f"grid.{key}.{gen} = {args!r} must be [start, stop, num] with "
                              f"finite numbers and an int num >= 1"
                              f"{' (start, stop > 0)' if gen == 'geomspace' else ''}")
        return Axis(gen=gen, start=float(args[0]), stop=float(args[1]), num=int(args[2]))
    if not isinstance(v, list):
        raise _err(where, f"grid.{key} = {v!r} must be a list of values (or {{geomspace = "
                          f"[start, stop, num]}})")
    if not v:
        raise _err(where, f"grid.{key} is an empty list; give at least one value")
    return Axis(v)


def _unit_refused(where: str, path: str, key: str, v) -> None:
    """Refuse a value with a unit (``{value, unit}``, ``{values, unit}``, a generator with a
    unit) on a key that takes plain numbers, saying the rule and the value in its SI unit."""
    if _has_unit(key) or not (isinstance(v, dict) and "unit" in v):
        return
    si = ENVELOPE_UNITS.get(key) or column_unit(key)
    if si is None or si == "-":
        raise _err(where, f"{path} = {v!r}: {key} takes no unit (only the dotted keys "
                          f"arm.<key of the arm file> and effects.<name>, and "
                          f"{', '.join(UNIT_KEYS)} take one)")
    try:
        f = si_factor(v["unit"], si, name="unit")
    except (TypeError, ValueError):
        f = None
    rest = {k: x for k, x in v.items() if k != "unit"}
    write = ""
    if f is not None and len(rest) == 1:
        (k, x), = rest.items()
        num = lambda a: isinstance(a, (int, float)) and not isinstance(a, bool)  # noqa: E731
        if k == "value" and num(x):
            write = f"{key} = {x * f:.6g}"
        elif k == "values" and isinstance(x, list) and x and all(map(num, x)):
            write = f"{key} = [{', '.join(f'{a * f:.6g}' for a in x)}]"
        elif k in GENERATORS and isinstance(x, list) and len(x) == 3 and all(map(num, x)):
            write = f"{key} = {{ {k} = [{x[0] * f:.6g}, {x[1] * f:.6g}, {x[2]}] }}"
    raise _err(where, f"{path} = {v!r}: only the dotted keys (arm.<key of the arm file>, "
                      f"effects.<name>) and {', '.join(UNIT_KEYS)} take a unit; {key} is a "
                      f"plain number in {si}"
                      + (f": write {write}" if write else f" (convert {v['unit']!r} to {si})"))


def _with_unit(axis: Axis, key: str, unit: str) -> Axis:
    """``axis`` with the unit the study file gave its values in (already checked)."""
    si = UNIT_KEYS.get(key) or arm_key(key).unit
    if si is not None:
        axis.unit, axis.factor = unit, si_factor(unit, si, name=f"grid.{key}.unit")
    return axis


def _dotted_si(where: str, path: str, key: str, v):
    """A dotted parameter's (or a ``UNIT_KEYS`` key's) value in SI units (``{value,
    unit}`` converted; lists as lists)."""
    if not isinstance(v, dict):
        return v
    if key in UNIT_KEYS:
        x = v.get("value")
        if set(v) != {"value", "unit"} or isinstance(x, bool) or not isinstance(
                x, (int, float)) or not math.isfinite(x):
            raise _err(where, f"{path} = {v!r}: give a finite number with its unit, "
                              f"{{ value = ..., unit = \"...\" }} (SI: {UNIT_KEYS[key]})")
        try:
            return float(x) * si_factor(v["unit"], UNIT_KEYS[key], name=f"{path}.unit")
        except (TypeError, ValueError) as exc:
            raise _err(where, f"{path} = {v!r}: {exc}") from None
    try:
        k = arm_key(key)
        if k.unit is None and k.kind != "float":
            raise ArmFileError(f"{key} is a plain {k.kind} (no unit)")
        if not isinstance(v.get("value"), list):       # one number stays one number
            k = type(k)(k.key, k.attr, k.unit, k.kind, 0, k.doc)
        si = read_value(key, k, v)
    except ArmFileError as exc:
        raise _err(where, f"{path} = {v!r}: {exc}") from None
    return list(si) if isinstance(si, tuple) else si


#: Case keys whose value may be a file (a string ending in ``.toml``), read relative to the
#: study file: a covering file and a contact point file.
FILE_KEYS = ("covering", "contact")


def _file_value(key: str, v, base_dir, written: dict):
    """A file value of a :data:`FILE_KEYS` key as a path relative to the study file's folder
    (absolute as a string); ``written`` maps it back to the text of the study file."""
    if key not in FILE_KEYS or not isinstance(v, str) or not is_contact_file(v):
        return v
    p = Path(v).expanduser()
    if not p.is_absolute() and base_dir is not None:
        p = Path(base_dir) / p
    out = str(p.absolute()) if base_dir is not None or p.is_absolute() else v
    written[out] = v
    return out


def _written_unit(units: dict, key: str, v) -> None:
    """Record the unit a ``[case]`` or ``[[variants]]`` value of ``key`` is written in
    (``{value, unit}``); None when two entries write the key in two units (shown in SI)."""
    if not (_has_unit(key) and isinstance(v, dict) and isinstance(v.get("unit"), str)):
        return
    if key in units and units[key] != v["unit"]:
        units[key] = None
    else:
        units.setdefault(key, v["unit"])


def _check_value(where: str, path: str, key: str, v, arm=None, shown=None) -> None:
    _unit_refused(where, path, key, v)
    try:
        if is_dotted(key):
            case_arm(arm, changes={key: v})
        else:
            PARAMETERS[key][0](v)
    except (TypeError, ValueError) as exc:
        shown = v if shown is None else shown
        raise _err(where, f"{path} = {shown!r}: {exc}") from None


#: Keys of a generator or a value with its unit: such an inline table is one value.
_LEAF_KEYS = {"value", "unit", "values", *GENERATORS}


def _flatten(where: str, table: str, d: dict) -> dict:
    """``d`` with nested ``arm`` tables (and, in [grid], ``effects`` tables) as dotted keys.

    TOML reads ``arm.links.m2 = 1.4`` as ``{"arm": {"links": {"m2": 1.4}}}``; the cases
    name it ``"arm.links.m2"``.  In ``[grid]``, ``effects.payload_mass = [0, 0.5]`` is one
    axis per effect; elsewhere ``effects`` stays one table of effects.
    """
    if not isinstance(d, dict):
        return d
    out = {}

    def walk(prefix, v):
        if isinstance(v, dict) and v and not set(v) <= _LEAF_KEYS:
            for k, x in v.items():
                walk(f"{prefix}.{k}", x)
        else:
            out[prefix] = v

    for k, v in d.items():
        if k == "arm" and isinstance(v, dict):
            walk("arm", v)
        elif k == "effects" and table == "grid" and isinstance(v, dict) and not (
                set(v) <= _LEAF_KEYS):
            walk("effects", v)
        else:
            out[k] = v
    return out


def _check_keys(where: str, table: str, d) -> None:
    if not isinstance(d, dict):
        raise _err(where, f"{table} must be a table ([{table}]), got {type(d).__name__} {d!r:.60}")
    allowed = SCHEMA[table.split("[")[0]]
    for k in d:
        if is_dotted(k) and table.split("[")[0] in ("case", "grid", "variants"):
            continue
        if k not in allowed:
            extra = (" ('histories' is set in [output])" if k == "histories" else "")
            raise _err(where, f"unknown key {table}.{k}; allowed keys of [{table.split('[')[0]}]: "
                              f"{list(allowed)}{extra}")


def _arm_and_head(where: str, data: dict, base_dir, arm, head) -> tuple:
    """The study's arm and head: ``--arm``/``--head`` or the ``[arm]``/``[head]`` files."""
    out = []
    for table, given, load, cls in (("arm", arm, load_arm, ArmParameters),
                                    ("head", head, load_head, HeadContactModel)):
        d = data.get(table, {})
        _check_keys(where, table, d)
        if given is not None:
            if not isinstance(given, cls):
                raise TypeError(f"{table} must be a {cls.__name__} or None, got "
                                f"{type(given).__name__}")
            out.append(given)
            continue
        if "file" not in d:
            out.append(None)
            continue
        f = d["file"]
        if not isinstance(f, str) or not f.strip():
            raise _err(where, f"{table}.file = {f!r} must be the path of a {table} file")
        path = Path(f) if base_dir is None or Path(f).is_absolute() else Path(base_dir) / f
        try:
            out.append(load(path))
        except FileNotFoundError:
            rel = ("" if base_dir is None or Path(f).is_absolute() else
                   f" (a relative path is read relative to the study file's folder "
                   f"'{base_dir}')")
            raise _err(where, f"{table}.file = {f!r}: {table} file '{path.resolve()}' does not "
                              f"exist{rel}") from None
        except ValueError as exc:
            raise _err(where, f"{table}.file = {f!r}: {exc}") from None
    return tuple(out)


#: SI units of the envelope parameters that are not dotted arm keys (``range`` may give
#: another unit of the same quantity, ``{ values = [low, high], unit = "mm/s" }``).
ENVELOPE_UNITS = {"speed": "m/s", "lam": "s", "duration": "s", "stiffness": "N m/rad",
                  "task_kp": "N/m", "task_ki": "N/(m s)", "task_kd": "N s/m",
                  "kp_bar": "bar/rad", "ki_bar": "bar/(rad s)", "kd_bar": "bar s/rad",
                  **UNIT_KEYS}


def _envelope_range(where: str, par: str, rng) -> list:
    """``envelope.range`` in SI units: ``[low, high]`` or ``{values = [low, high], unit}``."""
    unit = None
    if isinstance(rng, dict):
        if set(rng) != {"values", "unit"}:
            raise _err(where, f"envelope.range = {rng!r}: with a unit give {{ values = [low, "
                              f"high], unit = \"...\" }}")
        unit, rng = rng["unit"], rng["values"]
    if not (isinstance(rng, list) and len(rng) == 2 and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
            for x in rng) and rng[0] < rng[1]):
        si = ENVELOPE_UNITS.get(par, "SI units")
        raise _err(where, f"envelope.range = {rng!r} must be [low, high], finite, low < high "
                          f"(in {si} of {par}, or {{ values = [low, high], unit = \"...\" }})")
    if unit is None:
        return [float(x) for x in rng]
    if is_dotted(par):
        return [_dotted_si(where, f"envelope.range[{i}]", par, {"value": x, "unit": unit})
                for i, x in enumerate(rng)]
    si = ENVELOPE_UNITS.get(par)
    try:
        f = si_factor(unit, si or "-", name="envelope.range unit")
    except (TypeError, ValueError) as exc:
        raise _err(where, f"envelope.range = {{values = {rng!r}, unit = {unit!r}}}: {exc} "
                          f"({par} is in {si or 'its SI unit'})") from None
    return [float(x) * f for x in rng]


def _envelope_pose(where: str, pose, direction, case: dict, arm) -> None:
    """Blame a pose or a direction the speed search cannot use on the pose, not the range."""
    try:
        check_impact_case(0.5 * SPEED_MAX, q1_deg=float(pose[0]), q2_deg=float(pose[1]),
                          direction=[float(x) for x in direction], arm=arm,
                          **{k: v for k, v in case.items()
                             if k not in ("q1_deg", "q2_deg", "direction")})
    except (TypeError, ValueError) as exc:
        msg = str(exc)
        if "direction" in msg:
            raise _err(where, f"envelope.direction = {direction!r}: {msg} (the joint-space "
                              f"velocity direction (qd1, qd2), scaled to the speed)") from None
        if "working area" in msg or "q1_deg" in msg or "q2_deg" in msg:
            hint = ""
            if all(abs(float(x)) <= 2 * math.pi for x in pose):
                deg = [round(math.degrees(float(x)), 1) for x in pose]
                hint = (f"; the pose is in degrees: {list(pose)!r} looks like radians "
                        f"({deg} deg)")
            raise _err(where, f"envelope.pose = {list(pose)!r} [deg]: {msg}{hint}") from None
        raise _err(where, f"envelope.pose = {list(pose)!r}: {msg}") from None


def _envelope(where: str, data: dict, base: dict, arm, base_dir=None) -> dict | None:
    """The checked ``[envelope]`` table: parameter, bounds, limit, tolerance and base case.

    Keys: ``parameter`` (the searched case parameter: ``"speed"`` [m/s], ``"lam"`` [s], a
    gain, ``"stiffness"`` [N m/rad], ``"duration"`` [s] or a dotted arm key such as
    ``"arm.pneumatics.mean_pressure"`` [Pa]); ``range`` ([low, high] in the parameter's SI
    unit, or ``{values = [low, high], unit = "bar"}``); ``limit`` (a criterion name of
    :func:`ppamsafety.impact.verdicts.criterion_names`, default ``"F_max"``);
    ``limit_value`` (another value of that limit, a number in its SI unit or ``{value,
    unit}``); ``region`` (the body region of the criteria: a name, an Annex A number or a
    region file); ``tolerance`` (relative width of a final bracket); ``scan`` (values
    evaluated first, ends included); for ``parameter = "speed"`` only: ``pose`` ([q1, q2]
    link angles at impact in degrees, default [50, -80], thesis §6.3.3) and ``direction``
    ([qd1, qd2], the joint-space direction of the velocity, scaled so that the tool moves
    at the searched speed; default [1, 0], the arm swinging about joint 1).
    """
    env = data.get("envelope")
    if env is None:
        return None
    _check_keys(where, "envelope", env)
    if "grid" in data or "variants" in data:
        raise _err(where, "an [envelope] study searches one parameter: remove [grid] and "
                          "[[variants]] (the envelope evaluates its own cases)")
    par = env.get("parameter")
    if not isinstance(par, str):
        raise _err(where, f"envelope.parameter = {par!r} must be a parameter name such as "
                          f"'lam', 'speed' or 'arm.pneumatics.mean_pressure'")
    rng = _envelope_range(where, par, env.get("range"))
    region = env.get("region")
    if region is not None:
        if not isinstance(region, (str, int)) or isinstance(region, bool):
            raise _err(where, f"envelope.region = {region!r} must be a body region name, an "
                              f"Annex A number or a region file (.toml)")
        if isinstance(region, str) and region.endswith(".toml") and not os.path.isabs(region):
            region = str(Path(base_dir or ".") / region)
    lim = env.get("limit", "F_max")
    lval = env.get("limit_value")
    if isinstance(lval, dict):
        if set(lval) != {"value", "unit"}:
            raise _err(where, f"envelope.limit_value = {lval!r}: give a number or {{ value = "
                              f"..., unit = \"N\" }}")
        try:
            lval = float(lval["value"]) * si_factor(lval["unit"], "N",
                                                    name="envelope.limit_value unit")
        except (TypeError, ValueError) as exc:
            raise _err(where, f"envelope.limit_value: {exc}") from None
    if lval is not None and (isinstance(lval, bool) or not isinstance(lval, (int, float))):
        raise _err(where, f"envelope.limit_value = {lval!r} must be a number (the limit in "
                          f"its SI unit: N for a force)")
    try:
        resolve_limit(lim, lval, region)
    except (TypeError, ValueError) as exc:
        raise _err(where, f"envelope.{'limit_value' if 'limit_value' in str(exc) else 'limit'}"
                          f" = {lval if 'limit_value' in str(exc) else lim!r}: {exc}") from None
    tol = env.get("tolerance", 0.01)
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not 1e-6 <= tol <= 0.5:
        raise _err(where, f"envelope.tolerance = {tol!r} must be a number in [1e-6, 0.5]")
    scan = env.get("scan", SCAN)
    if isinstance(scan, bool) or not isinstance(scan, int) or not 2 <= scan <= 1000:
        raise _err(where, f"envelope.scan = {scan!r} must be an integer in [2, 1000] (values "
                          f"evaluated before bisecting, ends included)")
    case = dict(base)
    if par == "speed":
        extra = [k for k in case if not (is_dotted(k) or k in ("stiffness", "head", "effects"))]
        if extra:
            raise _err(where, f"envelope.parameter = 'speed' is one impact at a pose: "
                              f"{extra} do not apply (set envelope.pose, envelope.direction, "
                              f"[impact] stiffness/head, effects and arm.<key>)")
        pose = env.get("pose")
        if pose is None:        # the arm's own: the thesis pose at the fractions of its ranges
            try:
                pose = list(impact_pose_deg(case_arm(arm, changes={
                    k: v for k, v in case.items() if k.startswith("arm.")})))
            except (TypeError, ValueError):
                pose = list(IMPACT_POSE_DEG)       # the case's own error is said below
        direction = env.get("direction", [1.0, 0.0])
        for k, v in (("pose", pose), ("direction", direction)):
            if not (isinstance(v, list) and len(v) == 2 and all(
                    isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)):
                raise _err(where, f"envelope.{k} = {v!r} must be a pair of numbers"
                                  + (" [q1, q2] in degrees" if k == "pose" else
                                     " [qd1, qd2] (a joint-space direction)"))
        _envelope_pose(where, pose, direction, case, arm)
        case.update(q1_deg=float(pose[0]), q2_deg=float(pose[1]),
                    direction=[float(x) for x in direction])
    else:
        for k in ("pose", "direction"):
            if k in env:
                raise _err(where, f"envelope.{k} applies only to parameter = 'speed'")
        if par in case:
            raise _err(where, f"envelope.parameter = {par!r} is also set in [case]/[impact]; "
                              f"the envelope searches it")
        try:
            if is_dotted(par):
                case_arm(arm, changes={par: float(rng[0])})
            check_case(**case, **{par: float(rng[0])}, arm=arm)
        except (TypeError, ValueError) as exc:
            raise _err(where, f"envelope.parameter = {par!r}: {exc}") from None
    try:                                  # both ends of the range, as the search will run them
        check_bounds(par, (float(rng[0]), float(rng[1])), case, arm=arm)
    except ValueError as exc:
        raise _err(where, f"envelope.range = {env.get('range')!r}: {exc}") from None
    return {"parameter": par, "bounds": (float(rng[0]), float(rng[1])), "limit": lim,
            "limit_value": None if lval is None else float(lval), "region": region,
            "tolerance": float(tol), "scan": int(scan), "case": case}


def parse_study(text: str, *, where: str = "study file", default_name: str = "study",
                base_dir=None, arm=None, head=None) -> Study:
    """Parse and check the TOML text of a study file.

    Parameters
    ----------
    text : str
        TOML text.
    where : str
        How the file is named in error messages.
    default_name : str
        Sweep name when ``[study] name`` is missing.
    base_dir : path-like, optional
        Folder the ``[arm]`` and ``[head]`` files are relative to (the study file's;
        default the working directory).
    arm : ArmParameters, optional
        The arm (``--arm``): replaces ``[arm] file``.
    head : HeadContactModel, optional
        The head (``--head``): replaces ``[head] file``.

    Returns
    -------
    Study
        The checked study.

    Raises
    ------
    StudyFileError
        Naming the key by its dotted path and what is allowed.
    """
    if not isinstance(text, str):
        raise TypeError(f"text must be the TOML text of a study file (str), got "
                        f"{type(text).__name__}; to read a file use load_study(path)")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _err(where, f"not valid TOML ({exc})") from None
    for k in data:
        if k not in SCHEMA:
            raise _err(where, f"unknown table [{k}]; allowed: {list(SCHEMA)}")
    arm, head = _arm_and_head(where, data, base_dir, arm, head)
    for table in ("case", "grid"):
        if table in data:
            data[table] = _flatten(where, table, data[table])
    if isinstance(data.get("variants"), list):
        data["variants"] = [_flatten(where, "variants", v) for v in data["variants"]]
    study = data.get("study", {})
    _check_keys(where, "study", study)
    name = study.get("name", default_name)
    if not isinstance(name, str) or not name.strip():
        raise _err(where, f"study.name = {name!r} must be a non-empty string")
    desc = study.get("description", "")
    if not isinstance(desc, str):
        raise _err(where, f"study.description = {desc!r} must be a string")
    origin = {}                                  # parameter -> dotted path where it is set
    written = {}                                 # a file value -> as the study file gives it
    units = {}                                   # key -> the unit [case]/[[variants]] give
    base = {}
    for table in ("case", "impact"):
        d = data.get(table, {})
        _check_keys(where, table, d)
        for k, v in d.items():
            if k in origin:
                raise _err(where, f"{table}.{k} is also set as {origin[k]}; set it in one place")
            if k == "head" and head is not None:
                raise _err(where, f"{table}.head = {v!r} and the [head] file (or --head) both "
                                  f"set the head; set it in one place")
            _written_unit(units, k, v)
            v = _dotted_si(where, f"{table}.{k}", k, v) if _has_unit(k) else v
            given, v = v, _file_value(k, v, base_dir, written)
            _check_value(where, f"{table}.{k}", k, v, arm, shown=given)
            origin[k], base[k] = f"{table}.{k}", v
    envelope = _envelope(where, data, base, arm, base_dir)
    grid = data.get("grid", {})
    _check_keys(where, "grid", grid)
    gvals = {}
    for k, v in grid.items():
        if k in origin:
            raise _err(where, f"grid.{k} is also set as {origin[k]}; set it in one place")
        if k == "head" and head is not None:
            raise _err(where, "grid.head and the [head] file (or --head) both set the head")
        given = v
        if k in FILE_KEYS and isinstance(v, list):
            v = [_file_value(k, x, base_dir, written) for x in v]
        axis = _grid_values(where, k, v)
        idx = range(len(axis)) if axis.gen is None else axis.representatives()
        for i in idx:
            shown = (given[i] if given is not v else
                     f"{axis[i] / axis.factor:g} {axis.unit}" if axis.unit else None)
            _check_value(where, f"grid.{k}[{i}]", k, axis[i], arm, shown=shown)
        gvals[k] = axis
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
            if k == "head" and head is not None:
                raise _err(where, f"variants[{j}].head and the [head] file (or --head) both "
                                  f"set the head")
            _written_unit(units, k, v)
            v = _dotted_si(where, f"variants[{j}].{k}", k, v) if _has_unit(k) else v
            given, v = v, _file_value(k, v, base_dir, written)
            var[k] = v
            _check_value(where, f"variants[{j}].{k}", k, v, arm, shown=given)
    if not any(t in data for t in ("case", "impact", "grid", "variants", "envelope")):
        raise _err(where, "the study defines no case: give a [case] table, a [grid], "
                          "[[variants]] entries or an [envelope] (see studies/*.toml); an "
                          "empty study file is refused rather than run as the default case")
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
    if envelope is not None:
        if hist:
            raise _err(where, "output.histories does not apply to an [envelope] study")
        return Study(name=name.strip(), description=desc, cases=[], csv=csv, histories=False,
                     source=text, arm=arm, head=head, envelope=envelope, files=written,
                     units=units)
    cases = CaseGrid(base, variants, gvals, hist)
    _check_combinations(where, cases, arm)
    return Study(name=name.strip(), description=desc, cases=cases, csv=csv, histories=hist,
                 source=text, arm=arm, head=head, files=written,
                 units={k: u for k, u in units.items() if u is not None})


def _check_combinations(where: str, cases: CaseGrid, arm=None) -> None:
    """:func:`~ppamsafety.sweep_cases.check_case` on every case, or on the representatives.

    The rules between parameters (controller and gains, instants and every, experiment and
    duration, the controller's own limits) are thresholds and zero tests, so the cases
    built from every value of the lists of names and the smallest, largest and zero values
    of the numeric axes (:meth:`Axis.representatives`) meet every rule any case meets.
    A study of up to :data:`CHECK_ALL` cases has each case checked.
    """
    keys = list(cases.axes)
    if cases.total <= CHECK_ALL:
        reps = {k: range(len(a)) for k, a in cases.axes.items()}
    else:
        reps = {k: a.representatives() for k, a in cases.axes.items()}
    for j, var in enumerate(cases.variants):
        for combo in itertools.product(*(reps[k] for k in keys)):
            point = dict(zip(keys, combo))
            c = cases.case(j, point)
            try:
                check_case(**c, arm=arm)
            except (TypeError, ValueError) as exc:
                g = {k: cases.axes[k][point[k]] for k in keys}
                src = (f"variants[{j}]" if len(cases.variants) > 1 or var else "") + (
                    f" with grid point {g}" if g else "")
                raise _err(where, f"case {cases.index(j, point)}"
                                  f"{' (' + src.strip() + ')' if src else ''}: {exc}") from None


#: Rough cost model of one :func:`~ppamsafety.sweep_cases.safety_case` on one core
#: (``benchmarks/bench_case_cost.py``; measured on the shared 2-core machine under load,
#: the model is 0.8-1.7 times the measured time): a fixed part [s] (plus the circle
#: references' inverse kinematics), the closed loop per simulated second [s/s], one impact
#: [s]; result row and closed-loop history per second of record [bytes].
COST = {"fixed": 0.05, "fixed_circle": 0.6, "per_second": 0.012, "impact": 0.004,
        "row_bytes": 4000, "history_bytes_per_second": 400_000,
        "impact_history_bytes": 400_000}
#: A run estimated to take longer than this [h] of wall time needs ``confirm=True``
#: (``--yes``) or ``max_cases``.
CONFIRM_HOURS = 1.0


def _case_cost(c: dict) -> tuple:
    """(seconds, bytes) of one case by :data:`COST`."""
    dur = c.get("duration") or DEFAULT_DURATIONS[c.get("experiment") or DEFAULTS["experiment"]]
    inst = c.get("instants", "heuristic")
    n_imp = (4 if inst == "heuristic" else
             max(1, int(dur * 1000 / (c.get("every") or 1))) if inst == "all" else 1)
    exp = c.get("experiment") or DEFAULTS["experiment"]
    sec = (COST["fixed"] + (COST["fixed_circle"] if exp.startswith("circle") else 0.0)
           + COST["per_second"] * dur + COST["impact"] * n_imp)
    nbytes = COST["row_bytes"]
    if c.get("histories"):
        nbytes += COST["history_bytes_per_second"] * dur + COST["impact_history_bytes"]
    return sec, nbytes


def estimate_cases(cases, *, processes: int | None = None, histories: bool = False) -> dict:
    """Count the cases and estimate the time and memory of running them, before anything runs.

    Parameters
    ----------
    cases : sequence of dict
        The cases (a :class:`CaseGrid` is costed without generating a million dicts: every
        distinct (experiment, duration, instants, every) of its representatives is costed
        and the total scaled).
    processes : int, optional
        Worker processes (default every available core; at most the available cores count:
        more workers than cores run no faster).
    histories : bool
        Whether the histories are kept.

    Returns
    -------
    dict
        ``cases``; ``cpu_seconds`` and ``wall_seconds`` (on ``processes`` workers);
        ``bytes`` (results held in memory until the table is written).
    """
    n = len(cases)
    procs = min(processes or available_cores(), available_cores())   # more workers: no faster
    if isinstance(cases, CaseGrid) and n > CHECK_ALL:
        reps = {k: a.representatives() for k, a in cases.axes.items()}
        costs = [_case_cost(cases.case(j, dict(zip(reps, combo))))
                 for j in range(len(cases.variants))
                 for combo in itertools.product(*reps.values())]
        sec = max(c[0] for c in costs) * n                    # an upper estimate
        nbytes = max(c[1] for c in costs) * n
    else:
        sec = nbytes = 0.0
        for c in cases:
            a, b = _case_cost(c)
            sec += a
            nbytes += b
    return {"cases": n, "cpu_seconds": sec, "wall_seconds": sec / max(1, min(procs, max(n, 1))),
            "bytes": nbytes, "processes": procs}


def _duration_text(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    if seconds < 86400 * 3:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.3g} days"


def describe_estimate(est: dict) -> str:
    """One line: cases, time and memory of an :func:`estimate_cases` result.

    Parameters
    ----------
    est : dict
        The result of :func:`estimate_cases`.
    """
    return (f"{est['cases']:,} cases, about {_duration_text(est['wall_seconds'])} on "
            f"{est['processes']} process{'es' if est['processes'] > 1 else ''} "
            f"({_duration_text(est['cpu_seconds'])} of CPU), "
            f"{est['bytes'] / 1e6:.3g} MB of results in memory")


def check_run_size(study, est: dict, *, confirm: bool = False) -> None:
    """Refuse a run too large for this machine, with the numbers and the way to go on.

    Parameters
    ----------
    study : Study
        The study (named in the message).
    est : dict
        Its :func:`estimate_cases` for the cases about to run.
    confirm : bool
        The user confirmed a long run (``--yes``): only the memory limit applies.
    """
    what = f"study '{study.path or study.name}'"
    total = len(study.cases)
    if est["bytes"] > MAX_BYTES:
        fit = int(est["cases"] * MAX_BYTES / est["bytes"])
        raise StudyFileError(
            f"{what}: {describe_estimate(est)}: more than the {MAX_BYTES / 1e9:g} GB one run "
            f"may hold; run at most {fit:,} cases at a time (--max-cases {fit}, max_cases="
            f"{fit}; with --yes if that takes more than {CONFIRM_HOURS:g} h), split the grid "
            f"into several studies{', or leave out the histories' if study.histories else ''}")
    if est["wall_seconds"] > CONFIRM_HOURS * 3600 and not confirm:
        raise StudyFileError(
            f"{what}: {describe_estimate(est)}"
            f"{' (of ' + format(total, ',') + ')' if total != est['cases'] else ''}; "
            f"runs longer than {CONFIRM_HOURS:g} h are not started without confirmation: "
            f"preview the first cases with --max-cases N (max_cases=N), confirm with --yes "
            f"(confirm=True), or run it on a cluster (--backend dask --scheduler ADDRESS)")


def shipped_studies() -> list:
    """Names of the shipped studies (:data:`STUDY_DATA`), e.g. ``["lambda_ki", "table_6_1"]``."""
    return sorted(p.stem for p in STUDY_DATA.glob("*.toml"))


def shipped_study(name: str) -> Path:
    """The file of a shipped study.

    Parameters
    ----------
    name : str
        One of :func:`shipped_studies`.

    Returns
    -------
    pathlib.Path
    """
    names = shipped_studies()
    if not isinstance(name, str) or name not in names:
        raise ValueError(f"study = {name!r} is not a shipped study; shipped: {names}"
                         f"{did_you_mean(name, names)}")
    return STUDY_DATA / f"{name}.toml"


def study_path(study) -> Path:
    """The file a study argument names: a path, or the name of a shipped study.

    A name without a folder or suffix that is no file in the working directory and is a
    shipped study (:func:`shipped_studies`) gives that study's file; anything else is a path
    (checked when read).

    Parameters
    ----------
    study : str or os.PathLike
        A study file or a shipped study's name.

    Returns
    -------
    pathlib.Path
    """
    p = check_input_path("study", study)
    if not p.exists() and p.suffix == "" and p.name == str(study):
        names = shipped_studies()
        if p.name in names:
            return shipped_study(p.name)
        raise StudyFileError(f"study = {str(study)!r}: no such file, and not a shipped study "
                             f"(shipped: {names}){did_you_mean(p.name, names)}")
    return p


def controller_variants(study: Study) -> list:
    """The controller variant of every ``[[variants]]`` entry of a study, in file order.

    Each variant's controller is built by :func:`~ppamsafety.sweep_cases.make_controller`
    from the entry's gains merged over ``[case]`` (as every case of the study builds it); the
    label and the fields the thesis tables are keyed by follow from it
    (:meth:`~ppamsafety.experiments.catalog.ControllerVariant.of`).

    Parameters
    ----------
    study : Study
        A loaded study whose cases come from a grid (not an ``[envelope]``).

    Returns
    -------
    list of ControllerVariant
    """
    if not isinstance(study, Study) or not isinstance(study.cases, CaseGrid):
        raise TypeError(f"study must be a Study of a grid, got {type(study).__name__}")
    out = []
    for var in study.cases.variants:
        p = {**DEFAULTS, **study.cases.base, **var}
        out.append(ControllerVariant.of(make_controller(
            p["controller"], **{k: p[k] for k in CONTROLLER_KEYS})))
    return out


def load_study(path, *, arm=None, head=None) -> Study:
    """Read and check a study file (see the module docstring).

    Parameters
    ----------
    path : path-like
        The ``.toml`` file, or the name of a shipped study (:func:`study_path`).
    arm : ArmParameters, optional, keyword-only
        Replaces the study's ``[arm] file`` (``--arm``).
    head : HeadContactModel, optional, keyword-only
        Replaces the study's ``[head] file`` (``--head``).

    Returns
    -------
    Study
        The checked study (``path`` set).
    """
    p, text = read_text(study_path(path), what="study file", error=StudyFileError)
    st = parse_study(text, where=str(p), default_name=p.stem, base_dir=p.parent, arm=arm,
                     head=head)
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
    for i, h in zip(df.index, df["time_histories"]):
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
                   max_cases: int | None = None, progress: bool = True, confirm: bool = False,
                   replace_kind: bool = False, arm=None, head=None) -> SweepResult:
    """Run a study and write its output folder.

    Parameters
    ----------
    study : Study or path-like
        A :class:`Study`, the path of a study file or a shipped study's name
        (:func:`study_path`).
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
    confirm : bool
        Run even if the estimate (:meth:`Study.estimate`) exceeds :data:`CONFIRM_HOURS` of
        wall time on this machine (``--yes``); not needed on a dask cluster given by its
        ``scheduler``.  A run whose results would not fit in
        :data:`ppamsafety._validation.MAX_BYTES` is refused either way.
    replace_kind : bool
        With ``overwrite``: allow replacing a previous ppamsafety output of another kind
        (``--replace-other-kind``).
    arm : ArmParameters, optional
        Replaces the study file's ``[arm] file`` (a path ``study`` only).
    head : HeadContactModel, optional
        Replaces the study file's ``[head] file`` (a path ``study`` only).

    Returns
    -------
    SweepResult
        Its ``.table``: the result table as written (without the histories, in SI units);
        for an ``[envelope]`` study, its evaluations (the envelope's lines in
        ``table.attrs["envelope_lines"]``).
    """
    if isinstance(study, Study) and (arm is not None or head is not None):
        raise ValueError("arm and head apply to a study file path; a loaded Study has them "
                         "(load_study(path, arm=..., head=...))")
    out = check_output_path("outdir", outdir)                # checked before the study runs
    st = study if isinstance(study, Study) else load_study(check_input_path("study", study),
                                                           arm=arm, head=head)
    for nm, v in (("resume", resume), ("overwrite", overwrite), ("progress", progress),
                  ("confirm", confirm), ("replace_kind", replace_kind)):
        if not isinstance(v, bool):
            raise TypeError(f"{nm} must be True or False, got {v!r}")
    if backend not in BACKENDS:
        raise ValueError(f"backend = {backend!r} is not one of {list(BACKENDS)}")
    if max_cases is not None:
        max_cases = check_int("max_cases", max_cases, 1)
    n = len(st.cases) if max_cases is None else min(max_cases, len(st.cases))
    cases = st.cases.head(n) if isinstance(st.cases, CaseGrid) else st.cases[:n]
    # on a cluster (a scheduler address or client) the time is the cluster's: not limited here
    check_run_size(st, estimate_cases(cases, processes=processes, histories=st.histories),
                   confirm=confirm or (backend == "dask" and scheduler is not None))
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
    folder = OutputFolder(out, kind=KIND, overwrite=ow, clean=clean, replace_kind=replace_kind)
    with folder as stage:
        cache = folder.workdir("cache", fresh=not resume)
        if st.envelope is not None:
            env = _run_envelope(st, cache, processes, progress)
            df = env.to_pandas()
            df.attrs["envelope_lines"] = env.lines()
        else:
            env = None
            df = run_sweep(case_function(st.arm, st.head), cases, name=st.cache_name,
                           cache_dir=cache,
                           processes=processes, progress=progress, on_error="record",
                           backend=backend, scheduler=scheduler).table
            df = add_verdicts(df, head=st.head)
        if "time_histories" in df.columns:
            _write_histories(df, stage / "histories")
            # the frames are in histories/; the flag is [output], not a parameter of the cases
            df = df.drop(columns=[c for c in ("time_histories", "histories") if c in df.columns])
        display_table(st, df).to_csv(stage / st.csv, index=False)   # units in the header
        (stage / "study.toml").write_text(st.source, encoding="utf-8")
        _write_summary(st, df, stage, env)
    return SweepResult(df, name=st.name, units={c: column_unit(c) for c in df.columns})


def _run_envelope(st: Study, cache, processes, progress):
    """The ``[envelope]`` search of a study (:func:`ppamsafety.envelope.safety_envelope`)."""
    e = st.envelope
    return safety_envelope(e["parameter"], e["bounds"], limit=e["limit"],
                           limit_value=e["limit_value"], region=e["region"], case=e["case"],
                           arm=st.arm, head=st.head, tolerance=e["tolerance"], scan=e["scan"],
                           processes=processes, progress=progress, cache_dir=cache,
                           name=st.name)


#: Files of a sweep folder besides the result CSV and ``study.toml``.
SUMMARY_FIGURE, SUMMARY_PAGE, ARM_COPY, HEAD_COPY = ("summary.png", "summary.html", "arm.toml",
                                                     "head.toml")


def _in_unit(v, factor: float):
    """A value shown in a unit of SI factor ``factor`` (numbers and lists of numbers)."""
    if factor == 1.0:
        return v
    if isinstance(v, (list, tuple)):
        return [_in_unit(x, factor) for x in v]
    if isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool):
        return float(v) / factor
    return v


def unit_label(name: str, unit) -> str:
    """A column or axis name with its unit: ``F_max [N]``, ``HIC36 [-]``; a text column as is.

    Parameters
    ----------
    name : str
        The name.
    unit : str or None
        Its unit (``"-"``: dimensionless; None: none).
    """
    return unit_name(name, unit)


def display_table(st: Study, df: pd.DataFrame) -> pd.DataFrame:
    """The result table as a person reads it (the CSV, the HTML page): every column named with
    its unit (``[-]`` dimensionless), a grid key's values in the unit the study file gave them
    in (a mean pressure written in bar, in bar).

    Parameters
    ----------
    st : Study
        The study.
    df : pandas.DataFrame
        Its result table in SI units (:func:`run_study_file`'s).

    Returns
    -------
    pandas.DataFrame
    """
    out = {}
    for col in df.columns:
        if col in FILE_KEYS and st.files:                 # a file as the study file names it
            out[col] = df[col].map(lambda v: st.files.get(v, v))
            continue
        unit, factor = st.unit_of(col)
        label = (f"{st.envelope['parameter']} [{unit}]" if col == "value" and st.envelope
                 else unit_label(col, unit))
        out[label] = df[col].map(lambda v, f=factor: _in_unit(v, f)) if factor != 1.0 else \
            df[col]
    return pd.DataFrame(out)


def _write_summary(st: Study, df: pd.DataFrame, stage: Path, envelope=None) -> None:
    """The figure, the HTML page and the arm and head of a finished study."""
    if st.arm is not None:
        (stage / ARM_COPY).write_text(arm_to_toml(st.arm), encoding="utf-8")
    if st.head is not None:
        (stage / HEAD_COPY).write_text(st.head.to_toml(), encoding="utf-8")
    title = f"{st.name}: {st.description}" if st.description else st.name
    if envelope is not None:
        fig = envelope.plot(title=title, unit=st.unit_of(envelope.parameter)[0])
        swept, what = [envelope.parameter], " ".join(envelope.lines())
    else:       # what varies among the cases run (--max-cases may run fewer)
        swept = [k for k in st.swept if k in df.columns and df[k].map(repr).nunique() > 1]
        fig = sweep_figure(st, df, swept, title)
        what = (f"{len(df)} cases, {int((df.get('status') == 'ok').sum())} ok"
                if "status" in df.columns else f"{len(df)} cases")
    save_figure(fig, stage / SUMMARY_FIGURE)
    (stage / SUMMARY_PAGE).write_text(summary_page(st, df, what, swept), encoding="utf-8")


def _limit_text(r) -> str:
    """A limit as a legend or page shows it: its label, whether it is confirmed, what it
    decided."""
    return (f"{r.label}{'' if r.confirmed else ' [unconfirmed: not in the TS or no public source]'}"
            f": governs {r.governs}, fails {r.fails} of the cases")


def sweep_figure(st: Study, df: pd.DataFrame, swept, title: str = ""):
    """The figure of a finished sweep: its results against the swept parameters (in the study
    file's units), the limits that decide the verdicts and the failing cases ringed.

    Parameters
    ----------
    st : Study
        The study.
    df : pandas.DataFrame
        Its result table in SI units, with the verdict columns.
    swept : sequence of str
        The parameters that vary.
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    shown = df.copy()
    for k in shown.columns:      # the swept values in the study file's unit, p_max in N/cm^2
        if st.unit_of(k)[1] != 1.0:
            shown[k] = df[k].map(lambda v, f=st.unit_of(k)[1]: _in_unit(v, f))
    limits, failed = _verdict_marks(df)
    return plot_sweep(shown, swept, title=title,
                      units={k: st.unit_of(k)[0] for k in [*swept, *shown.columns]},
                      limits={m: [(_in_unit(v, st.unit_of(m)[1]), _legend_text(r))
                                  for v, _, r in ls]
                              for m, ls in limits.items()} or None,
                      failed={m: (f != "").to_numpy() for m, f in failed.items()} or None)


def _legend_text(r) -> str:
    """A limit as a figure's legend shows it: short, with what it decided."""
    u = f" {r.unit}" if r.unit else ""
    return (f"{r.region} {r.criterion} {r.limit:g}{u}"
            f"{'' if r.confirmed else ' [unconfirmed]'} (governs {r.governs}, fails {r.fails})")


def _verdict_marks(df: pd.DataFrame) -> tuple:
    """The limits that decide a sweep's verdicts and the cases that fail them.

    Returns
    -------
    tuple
        ``({metric: [(limit, text, row)]}, {metric: Series of failed criteria per case})``,
        both empty for a table without verdicts (the fixed limit lines are drawn then).
    """
    lims = verdict_limits(df)
    if not len(lims) and "governing" not in df.columns:
        return {}, {}
    limits = {}
    for r in lims.itertuples():
        limits.setdefault(r.metric, []).append((r.limit, _limit_text(r), r))
    for m in METRICS:                    # a result no criterion of the regions judges: no line
        if m in df.columns and m not in limits:
            limits[m] = []
    failed = {m: failed_criteria(df, m) for m in METRICS if m in df.columns}
    return limits, failed


def _mark_above(shown: pd.DataFrame, failed=None) -> tuple:
    """The displayed table as HTML cell texts, the cases that fail a verdict marked (red,
    ``▲``, the limits failed in the tooltip) -- without verdicts, the values above a limit
    line of the figure --; and the sentence that says so.

    Parameters
    ----------
    shown : pandas.DataFrame
        The displayed table (:func:`display_table`).
    failed : dict, optional
        Result -> the failed criteria of each case (:func:`_verdict_marks`).
    """
    out = shown.copy()
    count = [0]

    def number(v):
        if v is None or isinstance(v, (bool, np.bool_, str)):
            return None, html.escape("" if v is None else str(v))
        if not isinstance(v, (int, float, np.integer, np.floating)):
            return None, html.escape(str(v))
        if not np.isfinite(v):
            return None, ""
        return v, f"{v:.4g}"

    def marked(text, why):
        count[0] += 1
        return f'<span class="above" title="{html.escape(why)}">{text} ▲</span>'

    def cell(v, lines):
        x, text = number(v)
        over = [t for lim, t, *_ in lines if x is not None and x > lim]
        return marked(text, "above: " + "; ".join(over)) if over else text

    for col in shown.columns:
        base = col.split(" [")[0]
        if failed is not None and base in failed:
            why = failed[base].to_numpy()
            out[col] = [marked(number(v)[1], f"fails: {w}") if w else number(v)[1]
                        for v, w in zip(shown[col], why)]
        elif failed is not None and base == "verdict":
            out[col] = [f'<span class="above">{html.escape(str(v))}</span>' if v == "fail"
                        else number(v)[1] for v in shown[col]]
        else:
            lines = [] if failed is not None else limit_lines(base)
            out[col] = shown[col].map(lambda v, lines=lines: cell(v, lines))
    if failed is not None:
        note = (f'<p><span class="above">▲</span> {count[0]} values fail a verdict (hover over '
                f"a value for the limits it fails).</p>" if count[0] else
                "<p>No value fails a verdict.</p>")
    else:
        note = (f'<p><span class="above">▲</span> {count[0]} values above a limit line of the '
                f"figure (hover over a value for the limit).</p>" if count[0] else
                "<p>No value above a limit line of the figure.</p>")
    return out, note


def summary_page(st: Study, df: pd.DataFrame, what: str, swept) -> str:
    """The HTML summary of a sweep folder: what was run, on which arm, the figure, the table.

    Parameters
    ----------
    st : Study
        The study.
    df : pandas.DataFrame
        Its result table (or an envelope's evaluations).
    what : str
        One line: the cases run, or the envelope found.
    swept : sequence of str
        The parameters that vary.

    Returns
    -------
    str
        A self-contained page (the figure is ``summary.png`` beside it).
    """
    arm = (st.arm.name or "unnamed arm") if st.arm is not None else "the thesis arm"
    if "head_model" in df.columns and df["head_model"].notna().any():
        used = df["head_model"].dropna().map(str).value_counts(sort=False)
        head = "; ".join(f"{n} ({c} case{'s' if c > 1 else ''})" for n, c in used.items())
        if "thesis-frontal" in used.index and st.arm is not None and not is_thesis_arm(st.arm):
            head += ("; thesis-frontal is a contact fitted to the thesis arm's Table 6.1 "
                     "impacts, not to this arm")
    else:
        head = st.head.name if st.head is not None else "per case (see the table)"
    decided, failed = _verdict_marks(df)
    if decided:
        limits = "; ".join(t for ls in decided.values() for _, t, _ in ls) or "none judged"
    else:
        fixed = [t for c in ("F_max", "HIC36") for _, t, *_ in limit_lines(c)]
        limits = "; ".join(fixed)
    shown = display_table(st, df.drop(columns=[c for c in ("error",) if c in df.columns
                                               and not df[c].any()]))
    rows = [("study", st.name), ("description", st.description or "-"),
            ("arm", arm + (" (arm.toml)" if st.arm is not None else "")),
            ("body model simulated", head + (" (head.toml)" if st.head is not None else "")),
            ("experiment reference", st.references_text()),
            ("swept", ", ".join(unit_label(k, st.unit_of(k)[0]) for k in swept) or "-"),
            ("result", what),
            ("limits that decide the verdicts" if decided else "limits drawn", limits)]
    meta = "".join(f"<tr><th>{html.escape(k)}</th><td>{html.escape(str(v))}</td></tr>"
                   for k, v in rows)
    marked, note = _mark_above(shown, failed or None)
    table = marked.to_html(index=False, na_rep="", escape=False, border=0, classes="results")
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(st.name)}: ppamsafety sweep</title>
<style>body{{font-family:sans-serif;max-width:80em;margin:1em auto;padding:0 1em}}
table{{border-collapse:collapse;font-size:0.85em}}td,th{{border:1px solid #ccc;padding:2px 6px}}
th{{background:#f3f3f3;text-align:left}}img{{max-width:100%}}
.above{{color:#b00;font-weight:bold}}</style></head>
<body><h1>{html.escape(st.name)}</h1>
<table>{meta}</table>
<p><img src="{SUMMARY_FIGURE}" alt="results against the swept parameters"></p>
<p>Files: the table <a href="{html.escape(st.csv)}">{html.escape(st.csv)}</a>, the study
<a href="study.toml">study.toml</a>.</p>
{note}
{table}
</body></html>
"""


__all__ = ["SCHEMA", "GENERATORS", "KIND", "MATERIALISE", "CHECK_ALL", "COST", "CONFIRM_HOURS",
           "Axis", "CaseGrid", "Study", "StudyFileError", "parse_study", "load_study",
           "estimate_cases", "describe_estimate", "check_run_size", "history_format",
           "run_study_file", "summary_page", "sweep_figure", "display_table", "unit_label", "STUDY_DATA",
           "shipped_studies", "shipped_study", "study_path", "controller_variants", "FILE_KEYS",
           "UNIT_KEYS"]
