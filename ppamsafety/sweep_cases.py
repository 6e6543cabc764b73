"""The physics case of a safety sweep: one experiment, one controller, its impacts.

:func:`safety_case` runs one named thesis experiment with one controller
(family and gains), crashes the arm into a head at chosen instants of the
record and returns a compact dict of results (worst F_max, HIC36, HIC15,
tracking statistics ...).  Its parameters are JSON-serialisable, so it is a
:func:`ppamsafety.sweep.run_sweep` case function; :func:`safety_sweep` runs
it over a grid or a list of cases on every core (or a Dask cluster), and the
study files (:mod:`ppamsafety.study_files`) describe such sweeps in TOML.

Each parameter is checked by :func:`check_case` before anything runs, with
an error that names the parameter, its value and the allowed values.

The arm is the thesis arm or any arm (``arm=``, e.g. from an arm file); a case changes
it with plant effects (``effects={"hysteresis_delta": 0.299}``, or one effect per key:
``"effects.payload_mass": 0.5``) and with any arm parameter by its dotted key
(``"arm.pneumatics.mean_pressure": 2.0e5``, ``"arm.muscles.group1.count": 5``,
``"arm.links.m2": 1.4``; the keys of an arm file, :mod:`ppamsafety.params.arm_file`),
each value validated like the file.  The head is a named model or any
:class:`~ppamsafety.impact.head.HeadContactModel` (``head=``).

With the default parameters (``instants="heuristic"``, no stiffness
override, no sensor noise) the case follows the code path of Table 6.1
(:mod:`ppamsafety.sections.safety`): :func:`run_thesis_experiment` and
:func:`~ppamsafety.impact.instants.evaluate_experiment` with the same
arguments, so it reproduces the table's numbers exactly.
"""

from __future__ import annotations

import functools
import inspect
import math
from collections.abc import Mapping
from dataclasses import fields

import numpy as np
import pandas as pd

from ._validation import did_you_mean
from .control import PID, JointPSMC, TaskPSMC, SensorConfig
from .control.pid import GAIN_MAX
from .control.psmc import LAMBDA_MAX, TASK_GAIN_MAX
from .design import rest_stiffness
from .experiments.catalog import (CIRCLE_PERIODS, CIRCLE_WARMUP, DEFAULT_DURATIONS, STEP_TIMES,
                                  SWITCH_TIME, run_thesis_experiment, ControllerVariant)
from .experiments.metrics import tracking_stats
from .experiments.trajectories import ExperimentReferences, arm_pose, experiment_references
from .impact.anywhere import point_jacobian, simulate_contacts
from .impact.head import HeadContactModel, head_model_names, head_model
from .impact.instants import HEURISTICS, evaluate_experiment, heuristic_instants, impact_states
from .impact.engine import FREE_STRIDE
from .impact.summary import body_model_name, region_body
from .impact.verdicts import (METRICS, check_head_for_region, criteria_for, criterion, evaluate,
                              region_head)
from .impact.model import simulate_impacts, stiffness_limit
from .params import ArmParameters, thesis_arm
from .params.arm_file import ArmFileError, apply_arm_changes, arm_key, effects_from_dict
from .params.contact import arm_contact_points, body_contact, body_contact_names, covering_names
from .params.contact_files import is_contact_file, resolve_contact_point, resolve_covering
from .params.effects import Effects
from .params.iso_ts_15066 import resolve_region
from .plant import geometry as geo
from .sweep import SweepResult, _check_cases, grid_cases, run_sweep
from .units import BAR

#: Experiment names (thesis catalog).
EXPERIMENTS = ("step", "switch", "circle5", "circle10", "circle20")
#: Controller families a case can set.
CONTROLLERS = ("PID", "PSMC joint", "PSMC task")
#: Impact-instant choices: the four heuristic instants, every instant, or one heuristic.
INSTANTS = ("heuristic", "all", *HEURISTICS)
#: TCP speed below which an instant of ``instants="all"`` is skipped [m/s] (as the safety study).
MIN_SPEED = 1e-3
#: Result columns of :func:`safety_case` (``time_histories`` is added when asked for).
RESULT_COLUMNS = ("label", "F_max", "HIC36", "HIC15", "t0_F_max", "t0_HIC36", "instant_HIC36",
                  "tcp_speed", "K1", "K2", "n_impacts", "track_mean", "track_max", "track_rms",
                  "diverged")

#: The first event of each experiment that needs a reference [s]: a shorter duration would
#: never see it (the step's up-step, the switch between circles).
EVENTS = {"step": (STEP_TIMES[0], "up-step"), "switch": (SWITCH_TIME, "switch of circles")}
#: Shortest experiment of a case [s]: a record in which the pneumatic arm can move (its
#: valves take about 0.1 s to respond) and the impact instants of §6.3.3 exist.
MIN_DURATION = 1.0
#: Longest experiment of a case [s]: 1800 s at the 1 kHz control period keeps the reference
#: and the closed-loop log of one case below 2 GB (ppamsafety._validation.MAX_BYTES).
MAX_DURATION = 1800.0
#: Default impact step of :func:`ppamsafety.impact.model.simulate_impacts` [s].
IMPACT_DT = inspect.signature(simulate_impacts).parameters["dt"].default

_JOINT_GAINS = ("kp_bar", "ki_bar", "kd_bar")
_TASK_GAINS = ("task_kp", "task_ki", "task_kd")


def _is_number(v) -> bool:
    if isinstance(v, np.ndarray) and v.ndim == 0:        # 0-d arrays are numbers (_validation)
        v = v[()]
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def _number(name, v, lo=0.0, lo_open=False, unit="", hi=math.inf, why=""):
    if not _is_number(v):
        what = (f"an array of shape {v.shape}" if isinstance(v, np.ndarray) else
                f"{type(v).__name__} {v!r:.60}")
        raise TypeError(f"{name} must be a finite number{' [' + unit + ']' if unit else ''}, got "
                        f"{what}")
    if not math.isfinite(float(v)):
        raise ValueError(f"{name} = {float(v)} is not allowed: it must be a finite number"
                         f"{' [' + unit + ']' if unit else ''}")
    v = float(v)
    if v < lo or (lo_open and v == lo):
        raise ValueError(f"{name} = {v:g} is not allowed: it must be {'>' if lo_open else '>='} "
                         f"{lo:g}{' ' + unit if unit else ''}")
    if v > hi:
        raise ValueError(f"{name} = {v:g}{' ' + unit if unit else ''} is beyond the physical "
                         f"limit {hi:g}{' ' + unit if unit else ''}"
                         f"{' (' + why + ')' if why else ''}")
    return v


#: Upper bounds of the case parameters [their units]: the limits the controllers and the
#: impact model enforce at run time, checked when a study file is loaded.
LIMITS = {"lam": (LAMBDA_MAX, "the JointPSMC/TaskPSMC limit"),
          "kp_bar": (GAIN_MAX / BAR, "the PID/PSMC gain limit 1e9 Pa/rad"),
          "ki_bar": (GAIN_MAX / BAR, "the PID/PSMC gain limit 1e9 Pa/(rad s)"),
          "kd_bar": (GAIN_MAX / BAR, "the PID/PSMC gain limit 1e9 Pa s/rad"),
          "task_kp": (TASK_GAIN_MAX, "the TaskPSMC gain limit"),
          "task_ki": (TASK_GAIN_MAX, "the TaskPSMC gain limit"),
          "task_kd": (TASK_GAIN_MAX, "the TaskPSMC gain limit")}


def _pair(v):
    """A 1-D array of numbers (e.g. a pair) as a list; anything else unchanged."""
    if isinstance(v, np.ndarray) and v.ndim == 1:
        return v.tolist()
    return v


def _gain(name, v, unit):
    """A gain: one number or a pair [joint 1, joint 2], each in [0, its limit]."""
    hi, why = LIMITS.get(name, (math.inf, ""))
    v = _pair(v)
    if isinstance(v, (list, tuple)):
        if len(v) != 2:
            raise ValueError(f"{name} = {v!r} must be one number or a pair [joint 1, joint 2] "
                             f"[{unit}]")
        return [_number(f"{name}[{i}]", x, unit=unit, hi=hi, why=why) for i, x in enumerate(v)]
    return _number(name, v, unit=unit, hi=hi, why=why)


@functools.lru_cache(maxsize=1)
def stiffness_max() -> float:
    """Largest joint stiffness an impact of a case can resolve anywhere [N m/rad].

    The impact engine's limit (:func:`ppamsafety.impact.model.stiffness_limit` at its
    default step) at the most favourable configuration of the working area (a 23 x 21
    grid); a larger override fails every impact, so a study asking for it is refused when
    it is loaded.
    """
    arm = thesis_arm()
    g = arm.geometry
    q1, q2 = np.meshgrid(np.linspace(g.q1_min, g.q1_max, 23), np.linspace(g.q2_min, g.q2_max, 21))
    q = np.stack([q1.ravel(), q2.ravel()], axis=-1)
    return float(stiffness_limit(q, arm, FREE_STRIDE * IMPACT_DT).max())


def _check_stiffness(v):
    if v is None:
        return None
    hi, why = stiffness_max(), "the largest the impact model resolves at its step of 20 us"
    v = _pair(v)
    if isinstance(v, (list, tuple)):
        if len(v) != 2:
            raise ValueError(f"stiffness = {v!r} must be None, one number or a pair "
                             f"[K1, K2] [Nm/rad]")
        return [_number(f"stiffness[{i}]", x, unit="Nm/rad", hi=hi, why=why)
                for i, x in enumerate(v)]
    return _number("stiffness", v, unit="Nm/rad", hi=hi, why=why)


def _check_duration(v):
    if v is None:
        return None
    return _number("duration", v, lo_open=True, unit="s", hi=MAX_DURATION,
                   why="the longest record one case holds in memory at 1 kHz")


def _check_head(v):
    if isinstance(v, HeadContactModel):
        return v
    names = head_model_names()
    if not isinstance(v, str) or v not in names:
        raise ValueError(f"head = {v!r} is not a head model name; allowed: {names} (a head "
                         f"file: the study file's [head] file, or a HeadContactModel)")
    return v


def _check_region(v):
    """A case's body region: None (the skull/forehead of the thesis), an Annex A name or
    number, a region file (``.toml``) or a BodyRegion."""
    if v is None:
        return v
    if isinstance(v, float) and v.is_integer():
        v = int(v)
    try:
        resolve_region(v)
    except (TypeError, ValueError, OSError) as exc:
        raise ValueError(f"region = {v!r}: {exc}") from None
    return v


def chosen_head(head):
    """The head model a case *chose*: None for the default (``"thesis-frontal"`` by name).

    A non-head region is struck on its own body unless a head model is chosen, which is
    then refused (:func:`~ppamsafety.impact.verdicts.check_head_for_region`).

    Parameters
    ----------
    head : str or HeadContactModel
        A case's ``head``.
    """
    return None if isinstance(head, str) and head == DEFAULTS["head"] else head


#: Contact points a case can name (the defaults of every arm,
#: :func:`ppamsafety.params.contact.arm_contact_points`); ``"all"``: the worst of them.
CONTACT_POINTS = ("tool point", "elbow", "forearm", "upper arm", "all")
#: Keys that route a case through the contact-point engine (covering and body in series).
CONTACT_KEYS = ("contact", "body", "covering", "covering_thickness", "covering_modulus",
                "covering_hysteresis")
#: Ranges of the covering keys (SI): thickness [m], modulus [Pa], hysteresis [s/m].
COVERING_RANGES = {"covering_thickness": (1e-4, 0.2, "m"),
                   "covering_modulus": (1e3, 1e10, "Pa"),
                   "covering_hysteresis": (0.0, 100.0, "s/m")}


def _check_named(name, v, names):
    if v is None:
        return v
    if not isinstance(v, str) or v not in names:
        raise ValueError(f"{name} = {v!r}{did_you_mean(v, names) if isinstance(v, str) else ''}"
                         f" is not allowed; choose from {list(names)}")
    return v


def _check_file_or_name(name, v, names, resolve, what):
    """A name of ``names`` or a ``what`` file (a path ending in ``.toml``), read and validated
    by ``resolve`` (as ``ppamsafety impact`` reads it); the value is returned as given."""
    if v is None or not is_contact_file(v):
        try:
            return _check_named(name, v, names)
        except ValueError as exc:
            raise ValueError(f"{exc} or a {what} (.toml)") from None
    try:
        resolve(v)
    except (TypeError, ValueError, OSError) as exc:
        raise ValueError(f"{name} = {str(v)!r}: {exc}; allowed: {list(names)} or a {what} "
                         f"(.toml)") from None
    return str(v)


def _check_covering_value(name):
    lo, hi, unit = COVERING_RANGES[name]

    def check(v):
        return None if v is None else _number(name, v, lo=lo, unit=unit, hi=hi)
    return check


def _check_effects(v):
    if v is None or (isinstance(v, Mapping) and not v):
        return {}
    if not isinstance(v, Mapping):
        raise TypeError(f"effects = {v!r:.80} must be a table of plant effects, e.g. "
                        f"{{hysteresis_delta = 0.299, payload_mass = 0.5}} (names: "
                        f"ppamsafety.params.effects.Effects)")
    try:
        effects_from_dict(v)
    except ArmFileError as exc:
        raise ValueError(str(exc)) from None
    return dict(v)


#: Prefixes of the dotted case parameters: ``arm.<key of an arm file>`` and
#: ``effects.<effect name>``.
DOTTED = ("arm.", "effects.")


def is_dotted(name) -> bool:
    """True for a dotted case parameter (``arm.links.m2``, ``effects.payload_mass``).

    Parameters
    ----------
    name : str
        A case parameter name.
    """
    return isinstance(name, str) and name.startswith(DOTTED)


def case_arm(arm=None, *, effects=None, changes=None) -> ArmParameters:
    """The arm of one case: ``arm`` with the case's effects and dotted parameters.

    Parameters
    ----------
    arm : ArmParameters, optional
        The base arm (default the thesis arm).
    effects : mapping, optional
        Plant effects to switch on (``{"hysteresis_delta": 0.299}``), validated like an
        arm file's ``[effects]``; the base arm's other effects are kept.
    changes : mapping, optional
        Dotted parameters: ``"arm.<key>"`` (any key of an arm file) and
        ``"effects.<name>"`` -> value (a plain number in SI units, a list, or
        ``{"value": v, "unit": u}``).

    Returns
    -------
    ArmParameters
        ``arm`` itself when nothing changes.

    Raises
    ------
    ValueError
        Naming the dotted key, its value and what is allowed.
    """
    base = thesis_arm() if arm is None else arm
    if not isinstance(base, ArmParameters):
        raise TypeError(f"arm must be an ArmParameters or None, got {type(base).__name__}")
    ch = {}
    for k, v in (effects or {}).items():
        ch[f"effects.{k}"] = v
    for k, v in (changes or {}).items():
        if not is_dotted(k):
            raise ValueError(f"{k!r} is not a dotted case parameter (arm.<key> or "
                             f"effects.<name>)")
        key = k[4:] if k.startswith("arm.") else k
        if key in ch:
            raise ValueError(f"{k} sets {key}, which effects = {effects!r} sets as well; set "
                             f"it in one place")
        ch[key] = v
    if not ch:
        return base
    try:
        return apply_arm_changes(base, ch)
    except ArmFileError as exc:
        msg = str(exc)
        if msg.startswith("arm.effects.") and not any(k.startswith("arm.effects.")
                                                      for k in (changes or {})):
            msg = msg[4:]
        raise ValueError(msg) from None


def _check_choice(name, v, choices):
    if not isinstance(v, str) or v not in choices:
        raise ValueError(f"{name} = {v!r} is not allowed{did_you_mean(v, list(choices))}; "
                         f"choose from {list(choices)}")
    return v


def _check_optional_int(name, v, lo, hi):
    if v is None:
        return None
    if isinstance(v, np.ndarray) and v.ndim == 0:        # 0-d arrays are numbers (_validation)
        v = v[()]
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
        raise TypeError(f"{name} = {v!r} must be an int in [{lo}, {hi}] or None")
    if not lo <= int(v) <= hi:
        raise ValueError(f"{name} = {v} is outside [{lo}, {hi}]")
    return int(v)


def _check_bool(name, v):
    if not isinstance(v, bool):
        raise TypeError(f"{name} = {v!r} must be true or false")
    return v


#: Parameters of :func:`safety_case`: name -> (validator, description).
PARAMETERS = {
    "experiment": (lambda v: _check_choice("experiment", v, EXPERIMENTS),
                   f"thesis experiment, one of {list(EXPERIMENTS)}"),
    "controller": (lambda v: _check_choice("controller", v, CONTROLLERS),
                   f"controller family, one of {list(CONTROLLERS)}"),
    "lam": (lambda v: None if v is None else _gain("lam", v, "s"),
            "PSMC sliding-surface time constant lambda [s] (Table 5.1: 0.4); PSMC only"),
    "kp_bar": (lambda v: None if v is None else _gain("kp_bar", v, "bar/rad"),
               "Kp [bar/rad], PID and joint PSMC (one number or a pair per joint)"),
    "ki_bar": (lambda v: None if v is None else _gain("ki_bar", v, "bar/(rad s)"),
               "Ki [bar/(rad s)], PID and joint PSMC"),
    "kd_bar": (lambda v: None if v is None else _gain("kd_bar", v, "bar s/rad"),
               "Kd [bar s/rad], PID and joint PSMC"),
    "task_kp": (lambda v: None if v is None else _number("task_kp", v, unit="N/m"),
                "task PSMC virtual coupling Kp [N/m] (Table 5.1: 200)"),
    "task_ki": (lambda v: None if v is None else _number("task_ki", v, unit="N/(m s)"),
                "task PSMC Ki [N/(m s)] (Table 5.1: 100)"),
    "task_kd": (lambda v: None if v is None else _number("task_kd", v, unit="N s/m"),
                "task PSMC Kd [N s/m] (Table 5.1: 10)"),
    "stiffness": (_check_stiffness,
                  "joint stiffness of the impacts [Nm/rad]: None = (2.18) from the pressures "
                  "at the instant, a number for both joints or a pair [K1, K2]"),
    "head": (_check_head, "head contact model name (ppamsafety.impact.head.head_model_names; a "
                          "head file: the study file's [head] table)"),
    "region": (_check_region,
               "body region struck and judged (ISO/TS 15066 Annex A name or number 1-29, or a "
               "region file): a head region on the head model (head, or with a contact key the "
               "head that passes the Hybrid III drop), any other region on its Annex A body "
               "model (effective mass and spring constant, Table A.3); default skull/forehead"),
    "effects": (_check_effects, "plant effects {name = value} (ppamsafety.params.effects."
                                "Effects; one number sets every entry of a vector effect); "
                                "or one effect per key: effects.<name>"),
    "instants": (lambda v: _check_choice("instants", v, INSTANTS),
                 "impact instants: 'heuristic' (the thesis' four), 'all' (every `every`-th "
                 "ms) or one heuristic name"),
    "every": (lambda v: _check_optional_int("every", v, 1, 10 ** 6),
              "stride of instants='all' [ms]"),
    "noise_seed": (lambda v: _check_optional_int("noise_seed", v, 0, 2 ** 63 - 1),
                   "None: no sensor noise (thesis tables); an int: the arm's declared sensor "
                   "noise ([sensors]; the thesis arm: Table 3.2) with this seed"),
    "duration": (_check_duration,
                 "experiment length [s] (default: the catalog's), in [1, 1800] s and longer "
                 "than the experiment's events (step: 2 s, switch: 7.5 s)"),
    "contact": (lambda v: _check_file_or_name("contact", v, CONTACT_POINTS,
                                              lambda f: resolve_contact_point(f, None),
                                              "contact point file"),
                "contact point of the arm hitting the body: None = the tool point with the head "
                f"model (thesis path); one of {list(CONTACT_POINTS)} or a contact point file "
                "(ppamsafety-contact/1, .toml; contact-point engine)"),
    "body": (lambda v: _check_named("body", v, body_contact_names()),
             "body region contact model (ppamsafety.params.contact.body_contact_names); "
             "default with a contact key: the head that passes the Hybrid III drop"),
    "covering": (lambda v: _check_file_or_name("covering", v, covering_names(),
                                               resolve_covering, "covering file"),
                 "robot covering (ppamsafety.params.contact.covering_names) or a covering file "
                 "(ppamsafety-covering/1, .toml); default with a contact key: bare metal, or "
                 "the contact point file's covering, or 'thesis-implied' when a covering_* key "
                 "is given"),
    "covering_thickness": (_check_covering_value("covering_thickness"),
                           "thickness of the covering's layer [m]"),
    "covering_modulus": (_check_covering_value("covering_modulus"),
                         "modulus (stiffness) of the covering's layer [Pa]"),
    "covering_hysteresis": (_check_covering_value("covering_hysteresis"),
                            "Hunt-Crossley hysteresis factor of the covering's layer [s/m]"),
    "step_low_deg": (lambda v: None if v is None else _number("step_low_deg", v, lo=-180.0,
                                                               hi=180.0, unit="deg"),
                     "step only: q1_d before and after the up-step [deg]; default the arm's "
                     "(the thesis' 30 deg at the same fraction of the arm's q1 range); inside "
                     "the arm's working area"),
    "step_high_deg": (lambda v: None if v is None else _number("step_high_deg", v, lo=-180.0,
                                                                 hi=180.0, unit="deg"),
                      "step only: q1_d after the up-step [deg]; default the arm's (the thesis' "
                      "70 deg at the same fraction of the arm's q1 range)"),
    "step_q2_deg": (lambda v: None if v is None else _number("step_q2_deg", v, lo=-180.0,
                                                               hi=180.0, unit="deg"),
                    "step only: q2_d [deg]; default the arm's (the thesis' -80 deg at the same "
                    "fraction of the arm's q2 range)"),
    "histories": (lambda v: _check_bool("histories", v),
                  "return the full time histories (closed loop and worst impact)"),
}


#: Units of the case parameters and result columns of a sweep (what a CSV header, an axis or
#: a table shows beside the name): SI unless the name says otherwise; "-" dimensionless; None
#: text, flags or lists (no unit).  Dotted arm and effect keys carry the unit of their
#: declaration (:func:`column_unit`).
COLUMN_UNITS = {
    "lam": "s", "kp_bar": "bar/rad", "ki_bar": "bar/(rad s)", "kd_bar": "bar s/rad",
    "task_kp": "N/m", "task_ki": "N/(m s)", "task_kd": "N s/m", "stiffness": "Nm/rad",
    "every": "ms", "duration": "s", "noise_seed": "-", "speed": "m/s", "q1_deg": "deg",
    "q2_deg": "deg", "step_low_deg": "deg", "step_high_deg": "deg", "step_q2_deg": "deg",
    "direction": None, "experiment": None, "controller": None, "head": None,
    "instants": None, "effects": None, "histories": None,
    "label": None, "F_max": "N", "HIC36": "-", "HIC15": "-", "t0_F_max": "s", "t0_HIC36": "s",
    "instant_HIC36": None, "tcp_speed": "m/s", "K1": "Nm/rad", "K2": "Nm/rad",
    "n_impacts": "-", "track_mean": "m", "track_max": "m", "track_rms": "m", "diverged": None,
    "status": None, "error": None, "value": None,
    "contact": None, "body": None, "region": None, "body_model": None, "covering": None,
    "covering_thickness": "m",
    "covering_modulus": "Pa", "covering_hysteresis": "s/m", "contact_point": None,
    "body_region": None, "covering_name": None, "p_max": "Pa", "covering_use": "-",
}


def column_unit(name: str):
    """The unit of a sweep column or case parameter, as shown to a reader.

    Parameters
    ----------
    name : str
        A case parameter (``lam``, ``arm.pneumatics.mean_pressure``, ``effects.payload_mass``)
        or a result column (``F_max`` ...).

    Returns
    -------
    str or None
        The SI unit (``"N"``, ``"Nm/rad"``, ``"-"`` for a dimensionless number), or None for a
        text, flag or list column and an unknown name.
    """
    if not isinstance(name, str):
        return None
    if name == "governing_margin_pct":
        return "%"
    if name.endswith("_margin"):                 # a verdict column: the criterion's own unit
        try:
            return METRICS[criterion(name.removesuffix("_margin")).metric] or "-"
        except ValueError:
            return None
    if name.startswith("arm.effects.") or name.startswith("effects."):
        f = {f.name: f for f in fields(Effects)}.get(name.rsplit(".", 1)[-1])
        if f is None or isinstance(f.default, bool) or f.name == "hysteresis_initial":
            return None
        return f.metadata["unit"] or "-"
    if name.startswith("arm."):
        try:
            k = arm_key(name)
        except ArmFileError:
            return None
        return k.unit if k.unit else ("-" if k.kind in ("float", "int") else None)
    return COLUMN_UNITS.get(name)


def _checked(case: dict) -> tuple:
    """(checked parameters, the case's arm): :func:`check_case` and the arm it validates."""
    case = dict(case)
    arm = case.pop("arm", None)
    unknown = [k for k in case if k not in PARAMETERS and not is_dotted(k)]
    if unknown:
        raise ValueError(f"unknown safety_case parameter(s) {unknown}; allowed: "
                         f"{list(PARAMETERS)} and the dotted arm.<key of an arm file> (e.g. "
                         f"arm.pneumatics.mean_pressure) and effects.<name>")
    full = {**DEFAULTS, **case}
    for k, v in full.items():
        if not is_dotted(k):
            PARAMETERS[k][0](v)
    dotted = {k: v for k, v in full.items() if is_dotted(k)}
    the_arm = case_arm(arm, effects=full["effects"], changes=dotted)   # validated like the file
    ctrl = full["controller"]
    if ctrl == "PID" and full["lam"] is not None:
        raise ValueError(f"lam = {full['lam']!r} does not apply to controller = 'PID' (PSMC only)")
    if ctrl == "PSMC task":
        given = [k for k in _JOINT_GAINS if full[k] is not None]
        if given:
            raise ValueError(f"{given} do not apply to controller = 'PSMC task' (use task_kp, "
                             f"task_ki, task_kd [SI])")
        if isinstance(full["lam"], list):
            raise ValueError(f"lam = {full['lam']!r}: the task PSMC has one lambda [s]")
    else:
        given = [k for k in _TASK_GAINS if full[k] is not None]
        if given:
            raise ValueError(f"{given} apply only to controller = 'PSMC task', not {ctrl!r}")
    if full["region"] is not None:
        if full["body"] is not None:
            raise ValueError(f"body = {full['body']!r} and region = {full['region']!r}: the "
                             f"region sets the body struck; give one of them")
        check_head_for_region(full["region"], chosen_head(full["head"]))
    if any(full[k] is not None for k in CONTACT_KEYS):
        contact_covering(full)                       # the covering can be built
        if full["head"] != DEFAULTS["head"]:
            raise ValueError(f"head = {full['head']!r} with a contact key "
                             f"({[k for k in CONTACT_KEYS if full[k] is not None]}): the body "
                             f"is set by body (a body contact model), not head")
    step_given = [k for k in STEP_KEYS if full[k] is not None]
    if step_given and full["experiment"] != "step":
        raise ValueError(f"{step_given} apply only to experiment = 'step', not "
                         f"{full['experiment']!r}")
    case_references(the_arm, full)                   # the step inside the arm's working area
    if full["every"] is not None and full["instants"] != "all":
        raise ValueError(f"every = {full['every']} applies only to instants = 'all', not "
                         f"{full['instants']!r}")
    if full["duration"] is not None:
        first = EVENTS.get(full["experiment"])
        if full["duration"] < MIN_DURATION:
            raise ValueError(f"duration = {full['duration']:g} s is too short for an experiment "
                             f"of the arm: at least {MIN_DURATION:g} s (the valves alone take "
                             f"about 0.1 s to respond; default "
                             f"{DEFAULT_DURATIONS[full['experiment']]:g} s)")
        if first is not None and full["duration"] <= first[0]:
            raise ValueError(f"duration = {full['duration']:g} s is shorter than the "
                             f"{full['experiment']} experiment's {first[1]} at {first[0]:g} s; "
                             f"give a duration > {first[0]:g} s (default "
                             f"{DEFAULT_DURATIONS[full['experiment']]:g} s)")
    try:                                  # what the controller itself refuses at run time
        make_controller(ctrl, lam=full["lam"], kp_bar=full["kp_bar"], ki_bar=full["ki_bar"],
                        kd_bar=full["kd_bar"], task_kp=full["task_kp"], task_ki=full["task_ki"],
                        task_kd=full["task_kd"])
    except (TypeError, ValueError) as exc:
        given = {k: full[k] for k in ("lam", *_JOINT_GAINS, *_TASK_GAINS) if full[k] is not None}
        raise ValueError(f"controller = {ctrl!r} with {given or 'the Table 5.1 gains'}: "
                         f"{exc}") from None
    return full, the_arm


#: The case keys that move the step (:func:`case_references`).
STEP_KEYS = ("step_low_deg", "step_high_deg", "step_q2_deg")


def case_references(arm, case: dict) -> ExperimentReferences:
    """Where a case's experiment runs on its arm: the arm's references, the step moved by the
    case's ``step_*_deg`` keys.

    Parameters
    ----------
    arm : ArmParameters
        The case's arm (:func:`case_arm`).
    case : dict
        Checked case parameters (:func:`check_case`).

    Returns
    -------
    ExperimentReferences
        :func:`~ppamsafety.experiments.trajectories.experiment_references` of the arm.

    Raises
    ------
    ValueError
        A step level outside the arm's working area, naming the key, its value and the arm's
        ``geometry.q*_min``/``q*_max``.
    """
    refs = experiment_references(arm)
    if all(case.get(k) is None for k in STEP_KEYS):
        return refs
    return refs.with_step(arm, low=case.get("step_low_deg"), high=case.get("step_high_deg"),
                          q2=case.get("step_q2_deg"), names=STEP_KEYS, unit="deg")


def check_case(**case) -> dict:
    """Check the parameters of one :func:`safety_case`; return them completed with defaults.

    Parameters
    ----------
    **case
        Keyword arguments of :func:`safety_case`, dotted ones (``arm.links.m2``,
        ``effects.payload_mass``) included; ``arm`` (the base arm the dotted ones
        change, checked with it) is used and not returned.

    Returns
    -------
    dict
        Every parameter of :func:`safety_case`, checked.

    Raises
    ------
    TypeError, ValueError
        Naming the parameter, its value and what is allowed (unknown names too).
    """
    return _checked(case)[0]


DEFAULTS = {"experiment": "step", "controller": "PID", "lam": None, "kp_bar": None,
            "ki_bar": None, "kd_bar": None, "task_kp": None, "task_ki": None, "task_kd": None,
            "stiffness": None, "head": "thesis-frontal", "effects": None,
            "instants": "heuristic", "every": None, "noise_seed": None, "duration": None,
            "contact": None, "body": None, "region": None, "covering": None,
            "covering_thickness": None,
            "covering_modulus": None, "covering_hysteresis": None, "step_low_deg": None,
            "step_high_deg": None, "step_q2_deg": None, "histories": False}
"""Default parameters of :func:`safety_case`."""


def _bar(v):
    return None if v is None else (np.asarray(v, float) * BAR if isinstance(v, list) else v * BAR)


def make_controller(controller: str = "PID", *, lam=None, kp_bar=None, ki_bar=None, kd_bar=None,
                    task_kp=None, task_ki=None, task_kd=None):
    """The controller of a case (Table 5.1 gains for every gain left None).

    Parameters
    ----------
    controller : {"PID", "PSMC joint", "PSMC task"}
        Family.
    lam : float or pair, optional
        lambda [s] (PSMC).
    kp_bar, ki_bar, kd_bar : float or pair, optional
        Joint-space gains [bar/rad, bar/(rad s), bar s/rad] (PID, joint PSMC).
    task_kp, task_ki, task_kd : float, optional
        Task-space gains [N/m, N/(m s), N s/m] (task PSMC).

    Returns
    -------
    ppamsafety.control.Controller
        Built exactly as :func:`~ppamsafety.experiments.catalog.thesis_variants`
        builds the same variant.
    """
    kw = {}
    if controller == "PSMC task":
        for k, v in (("lam", lam), ("kp", task_kp), ("ki", task_ki), ("kd", task_kd)):
            if v is not None:
                kw[k] = v
        return TaskPSMC(**kw)
    for k, v in (("kp", kp_bar), ("ki", ki_bar), ("kd", kd_bar)):
        if v is not None:
            kw[k] = _bar(v)
    if controller == "PID":
        return PID(**kw)
    if lam is not None:
        kw["lam"] = lam
    return JointPSMC(**kw)


def contact_covering(p: dict, point=None):
    """The covering of a case with contact keys: the named covering or covering file (default
    the contact point's own covering, bare metal for the arm's points, or ``"thesis-implied"``
    when a ``covering_*`` key is given) with its first layer's thickness, modulus and
    hysteresis replaced by the case's ``covering_*`` values.

    Parameters
    ----------
    p : dict
        The case's parameters (``covering`` and ``covering_*``).
    point : ContactPoint, optional
        The contact point (its covering is the default).
    """
    changes = {k[len("covering_"):]: p[k] for k in COVERING_RANGES if p.get(k) is not None}
    name = p.get("covering") or ("thesis-implied" if changes else None)
    if name is None:
        cov = point.covering if point is not None else resolve_covering("bare metal")
        name = cov.name
    else:
        cov = resolve_covering(name)
    if not changes:
        return cov
    if cov.bare:
        raise ValueError(f"{sorted('covering_' + k for k in changes)} change a covering layer; "
                         f"covering = {name!r} has none (give a covering with a layer, e.g. "
                         f"'thesis-implied')")
    lay = cov.layers[0]
    if lay.law == "power" and "modulus" in changes:
        raise ValueError(f"covering_modulus: the layer of covering {name!r} is a 'power' law "
                         f"(no modulus)")
    label = ", ".join(f"{k} {v:g}" for k, v in changes.items())
    return cov.replace(name=f"{cov.name} ({label})",
                       layers=(lay.replace(**changes),) + cov.layers[1:])


def _contact_impacts(result, arm, p):
    """Impacts of a record at a contact point through a covering and a body (contact keys);
    ``contact = "all"``: at every contact point, the point with the largest F_max kept."""
    pts = {c.name: c for c in arm_contact_points(arm)}
    if p["contact"] == "all":
        runs = [_contact_impacts(result, arm, {**p, "contact": name}) for name in pts]
        return max(runs, key=lambda r: float(r[0].summary["F_max"].max()))
    point = resolve_contact_point(p["contact"] or "tool point", arm)
    body = (body_contact(p["body"]) if p["body"] else region_body(p["region"])
            if p["region"] is not None else body_contact())
    st = impact_states(result, arm)
    if p["instants"] == "all":
        idx = np.arange(0, len(st), p["every"] or 1)
        idx = idx[st["tcp_speed"].to_numpy()[idx] >= MIN_SPEED]
        names = None
    else:
        h = heuristic_instants(st)
        names = list(h) if p["instants"] == "heuristic" else [p["instants"]]
        idx = np.array([h[n] for n in names])
    sub = st.iloc[idx]
    K = sub[["K1", "K2"]].to_numpy()
    if p["stiffness"] is not None:
        K = np.broadcast_to(np.asarray(p["stiffness"], float), K.shape).copy()
    res = simulate_contacts(arm, sub[["q1", "q2"]].to_numpy(), sub[["qd1", "qd2"]].to_numpy(),
                            K, point=point, body=body, covering=contact_covering(p, point))
    s = res.summary
    s.insert(0, "t0", sub["t"].to_numpy())
    if names is not None:
        s.insert(0, "instant", names)
    s["tcp_speed"] = s["point_speed"]
    return res, body, point


#: Names of the body models of the named body contacts (the body column of a sweep).
_BODY_MODELS = {"head (forehead)": "validated head"}


def _impacts(result, arm, instants, every, head, stiffness):
    """Impacts of a record; the same calls as the safety study without a stiffness override."""
    if stiffness is None and instants in ("heuristic", "all"):
        kw = {"every": every, "min_speed": MIN_SPEED} if instants == "all" else {}
        return evaluate_experiment(result, arm, instants=instants, head=head, **kw)
    st = impact_states(result, arm)
    if instants == "all":
        idx = np.arange(0, len(st), every)
        idx = idx[st["tcp_speed"].to_numpy()[idx] >= MIN_SPEED]
        names = None
    else:
        h = heuristic_instants(st)
        names = list(h) if instants == "heuristic" else [instants]
        idx = np.array([h[n] for n in names])
    sub = st.iloc[idx]
    K = sub[["K1", "K2"]].to_numpy()
    if stiffness is not None:
        K = np.broadcast_to(np.asarray(stiffness, float), K.shape).copy()
    res = simulate_impacts(arm, sub[["q1", "q2"]].to_numpy(), sub[["qd1", "qd2"]].to_numpy(), K,
                           head=head)
    res.summary.insert(0, "t0", sub["t"].to_numpy())
    if names is not None:
        res.summary.insert(0, "instant", names)
    return res


def safety_case(experiment: str = "step", controller: str = "PID", *, lam=None, kp_bar=None,
                ki_bar=None, kd_bar=None, task_kp=None, task_ki=None, task_kd=None,
                stiffness=None, head="thesis-frontal", effects=None,
                instants: str = "heuristic", every: int | None = None, noise_seed=None,
                duration=None, contact=None, body=None, region=None, covering=None,
                covering_thickness=None, covering_modulus=None, covering_hysteresis=None,
                step_low_deg=None, step_high_deg=None, step_q2_deg=None,
                histories: bool = False, arm=None, **dotted) -> dict:
    """One experiment with one controller, crashed into a head: a compact result row.

    Parameters
    ----------
    experiment : {"step", "switch", "circle5", "circle10", "circle20"}
        Thesis experiment (:mod:`ppamsafety.experiments.catalog`).
    controller : {"PID", "PSMC joint", "PSMC task"}
        Controller family; gains default to Table 5.1.
    lam : float or pair, optional
        PSMC lambda [s] (a pair per joint for joint PSMC).
    kp_bar, ki_bar, kd_bar : float or pair, optional
        Joint-space gains [bar/rad, bar/(rad s), bar s/rad] of PID and joint
        PSMC (one value for both joints or a pair).
    task_kp, task_ki, task_kd : float, optional
        Task-space PSMC gains [N/m, N/(m s), N s/m].
    stiffness : None, float or pair
        Joint stiffness used in the impacts [Nm/rad]: None = (2.18) from the
        pressures at each instant (thesis); a value overrides it (fig. 6.3).
    head : str or HeadContactModel
        Head contact model: a name (:func:`ppamsafety.impact.head.head_model`) or a
        model (e.g. from a head file, :func:`ppamsafety.impact.head.load_head`).
    effects : dict or None
        Plant effects ``{name: value}`` of :class:`ppamsafety.params.effects.Effects`
        (SI units; ``{"value": v, "unit": u}`` accepted; one number sets every entry
        of a vector effect: ``{"hysteresis_delta": 0.299}``), on top of the arm's own.
    instants : str
        ``"heuristic"``: the thesis' four instants (§6.3.3); ``"all"``: every
        ``every``-th ms (instants with the TCP slower than :data:`MIN_SPEED`
        skipped); or one heuristic name such as ``"max TCP speed"``.
    every : int, optional
        Stride of ``instants="all"`` [ms] (default 1).
    noise_seed : int, optional
        None: no sensor noise (as the thesis tables).  An int: Gaussian
        sensor noise of the arm's declared variances (``[sensors]``; the thesis arm: Table
        3.2) with this seed.
    duration : float, optional
        Experiment length [s] (default: the catalog's, e.g. 12 s for the step).
    contact : str, optional
        A contact point of the arm (:data:`CONTACT_POINTS`; ``"all"``: every one, the
        results of the point with the largest F_max) or a contact point file
        (``ppamsafety-contact/1``, a path ending in ``.toml``; a study file's path is relative
        to the study file).  With any of ``contact``,
        ``body``, ``covering`` and ``covering_*`` the impacts go through the contact-point
        engine (:func:`ppamsafety.impact.anywhere.simulate_contacts`): the point (default the
        tool point) hits the body (default the head that passes the Hybrid III drop) through
        the covering in series; ``head`` is then not used.
    body : str, optional
        A body contact model (:func:`ppamsafety.params.contact.body_contact_names`).
    region : str, int, path-like or BodyRegion, optional
        The body region struck (ISO/TS 15066 Annex A, or a region file): a head region on
        the head model (``head``; with contact keys the head that passes the Hybrid III
        drop), any other region on its Annex A body model (its effective mass and spring
        constant, Table A.3; :func:`~ppamsafety.impact.verdicts.region_head`,
        :func:`~ppamsafety.impact.summary.region_body`).  A head model chosen (``head``
        other than the default) for a region that is not part of the head is refused.
        Default: the skull/forehead (``body`` with contact keys).
    covering : str, optional
        A named covering (:func:`ppamsafety.params.contact.covering_names`) or a covering
        file (``ppamsafety-covering/1``, a path ending in ``.toml``); default the contact
        point's covering (bare metal for the arm's points), or ``"thesis-implied"`` when a
        ``covering_*`` value is given.
    covering_thickness, covering_modulus, covering_hysteresis : float, optional
        Replace the thickness [m], modulus [Pa] and hysteresis factor [s/m] of the
        covering's (first) layer (:func:`contact_covering`): the covering as a design
        parameter, in sweeps and envelopes.
    step_low_deg, step_high_deg, step_q2_deg : float, optional
        The step only: q1_d before/after the up-step and q2_d [deg], each inside the arm's
        working area; default the arm's references
        (:func:`~ppamsafety.experiments.trajectories.experiment_references`: the thesis arm's
        30 -> 70 deg, -80 deg; another arm's at the same fractions of its joint ranges).
    histories : bool
        Also return the full time histories under the key ``"time_histories"`` (a result
        may not take a parameter's name, :func:`ppamsafety.sweep.run_sweep`):
        ``{"closed_loop": DataFrame (1 kHz record), "impact": DataFrame (worst
        HIC36 impact)}``.  Off by default: results stay compact.
    arm : ArmParameters, optional
        The arm (default the thesis arm); a sweep passes it to every case.
    **dotted
        Dotted parameters (:func:`case_arm`): ``"arm.<key of an arm file>"``
        (``"arm.pneumatics.mean_pressure"``: the mean pressure p_m of both joints,
        the physical stiffness knob (2.18); ``"arm.muscles.group1.count"``;
        ``"arm.links.m2"``) and ``"effects.<name>"``, each validated like the file.
        Pass them as ``safety_case(**{"arm.links.m2": 1.4})``.

    Returns
    -------
    dict
        ``label``; ``F_max`` [N], ``HIC36``, ``HIC15`` (worst over the
        impacts), ``t0_F_max``, ``t0_HIC36`` [s] (their instants),
        ``instant_HIC36`` (heuristic name or ""), ``body_model`` (the name of the body
        model the impacts were simulated with), ``tcp_speed`` [m/s] (largest
        at impact), ``K1``, ``K2`` [Nm/rad] (stiffness of the worst-HIC
        impact), ``n_impacts``; ``track_mean``, ``track_max``, ``track_rms``
        [m] (task-space tracking error; circles after the 5 s warm-up, NaN if
        the run diverged) and ``diverged``; with contact keys also ``contact_point``,
        ``body_region``, ``covering_name``, ``p_max`` [Pa] (peak mean contact pressure) and
        ``covering_use`` (largest compression of the covering over its limit; 1: bottomed
        out), and ``tcp_speed`` is the contact point's speed.
    """
    p, arm = _checked(dict(experiment=experiment, controller=controller, lam=lam,
                           kp_bar=kp_bar, ki_bar=ki_bar, kd_bar=kd_bar, task_kp=task_kp,
                           task_ki=task_ki, task_kd=task_kd, stiffness=stiffness, head=head,
                           effects=effects, instants=instants, every=every,
                           noise_seed=noise_seed, duration=duration, contact=contact,
                           body=body, region=region, covering=covering,
                           covering_thickness=covering_thickness,
                           covering_modulus=covering_modulus,
                           covering_hysteresis=covering_hysteresis, step_low_deg=step_low_deg,
                           step_high_deg=step_high_deg, step_q2_deg=step_q2_deg,
                           histories=histories, arm=arm, **dotted))
    hm = region_head(p["region"], chosen_head(p["head"]))   # the region's own body
    ctrl = make_controller(p["controller"], lam=p["lam"], kp_bar=p["kp_bar"], ki_bar=p["ki_bar"],
                           kd_bar=p["kd_bar"], task_kp=p["task_kp"], task_ki=p["task_ki"],
                           task_kd=p["task_kd"])
    variant = ControllerVariant.of(ctrl)
    sensors = (None if p["noise_seed"] is None
               else SensorConfig.for_arm(arm, noise=True, seed=p["noise_seed"]))
    res = run_thesis_experiment(arm, p["experiment"], [variant], sensors=sensors,
                                duration=p["duration"], references=case_references(arm, p))[0]
    contact = any(p[k] is not None for k in CONTACT_KEYS)
    if contact:
        ev, body, point = _contact_impacts(res, arm, p)
    else:
        ev = _impacts(res, arm, p["instants"], p["every"] or 1, hm, p["stiffness"])
    s = ev.summary
    if len(s) == 0:
        raise ValueError(f"no impact instant: the TCP never moves faster than {MIN_SPEED} m/s")
    w = s.loc[s["HIC36"].idxmax()]
    wf = s.loc[s["F_max"].idxmax()]
    t_from = min(CIRCLE_WARMUP, res.t[-1] / 2) if p["experiment"] in CIRCLE_PERIODS else 0.0
    tr = tracking_stats(res, t_from=t_from)
    out = {"label": variant.label, "F_max": float(wf.F_max), "HIC36": float(w.HIC36),
           "HIC15": float(s["HIC15"].max()), "t0_F_max": float(wf.t0), "t0_HIC36": float(w.t0),
           "instant_HIC36": str(w.instant) if "instant" in s.columns else "",
           "tcp_speed": float(s["tcp_speed"].max()), "K1": float(w.K1), "K2": float(w.K2),
           "n_impacts": int(len(s)), "track_mean": tr["mean"], "track_max": tr["max"],
           "track_rms": tr["rms"], "diverged": bool(res.diverged),
           "body_model": (hm.name if not contact else body_model_name(p["region"])
                          if p["region"] is not None else _BODY_MODELS.get(body.name, body.name))}
    if contact:
        out.update({"contact_point": point.name, "body_region": body.name,
                    "covering_name": ev.point.covering.name,
                    "p_max": float(s["p_max"].max()),
                    "covering_use": float(s["covering_use"].max()) if "covering_use" in s
                    else 0.0})
    if histories and contact:
        raise ValueError("histories with a contact key: use ppamsafety.impact.anywhere."
                         "simulate_contacts(history=True) for the impact's history")
    if histories:
        worst = int(s["HIC36"].idxmax())
        ev_w = _impacts_one(res, arm, s.iloc[worst], hm)
        out["time_histories"] = {"closed_loop": res.to_pandas(), "impact": ev_w}
    return out


def _impacts_one(result, arm, row, head) -> pd.DataFrame:
    """Time history of one impact (a summary row of :func:`_impacts`)."""
    st = impact_states(result, arm)
    k = int(np.argmin(np.abs(st["t"].to_numpy() - row.t0)))
    r = st.iloc[k]
    res = simulate_impacts(arm, r[["q1", "q2"]].to_numpy(float), r[["qd1", "qd2"]].to_numpy(float),
                           [float(row.K1), float(row.K2)], head=head, history=True)
    return res.histories[0]


#: Default pose of :func:`impact_case` [deg]: the step-response impact configuration
#: q = (50, -80) deg of thesis §6.3.3.
IMPACT_POSE_DEG = (50.0, -80.0)


def impact_pose_deg(arm=None) -> tuple:
    """The default impact pose of ``arm`` [deg]: :data:`IMPACT_POSE_DEG` (thesis §6.3.3) at
    the same fractions of the arm's joint ranges
    (:func:`~ppamsafety.experiments.trajectories.arm_pose`; the thesis arm's is unchanged).

    Parameters
    ----------
    arm : ArmParameters, optional
        The arm (default the thesis arm).

    Returns
    -------
    tuple of 2 float
        (q1, q2) [deg].
    """
    arm = thesis_arm() if arm is None else arm
    q = np.radians(IMPACT_POSE_DEG)
    mapped = arm_pose(arm, q)
    if np.array_equal(mapped, q):           # the thesis arm's area: the thesis numbers exactly
        return IMPACT_POSE_DEG
    return tuple(float(x) for x in np.degrees(mapped))


def impact_case(speed: float, *, q1_deg=None, q2_deg=None, direction=(1.0, 0.0), stiffness=None,
                head="thesis-frontal", region=None, contact=None, effects=None, arm=None,
                **dotted) -> dict:
    """One impact of the arm moving at a given speed (the ``speed`` of an envelope).

    The arm is at rest-state pressures in pose ``q`` and moves along the joint-space
    ``direction`` with its tool point at ``speed``; it hits the head along its tool
    velocity (the worst case of fig. 6.2).

    Parameters
    ----------
    speed : float
        Tool (TCP) speed at impact [m/s], in (0, 10].
    q1_deg, q2_deg : float, keyword-only
        Pose at impact [deg]; in the working area.  Default :func:`impact_pose_deg`: the
        thesis pose (50, -80) deg (§6.3.3) at the same fractions of the arm's joint ranges.
    direction : pair of float, keyword-only
        Joint-space velocity direction (qd1, qd2) (default (1, 0): the arm swinging
        about joint 1); scaled so that the tool moves at ``speed``.
    stiffness : None, float or pair, keyword-only
        Joint stiffness [Nm/rad]: None = (2.18) with the static pressures of the pose.
    head : str or HeadContactModel, keyword-only
        Head model of a head region (a chosen one is refused for another region).
    region : optional, keyword-only
        The body region struck (as :func:`safety_case`; default the skull/forehead).
    contact : str, optional, keyword-only
        A contact point of the arm (:data:`CONTACT_POINTS` but ``"all"``): the impact goes
        through the contact-point engine (bare, as ``ppamsafety impact --contact``) into the
        region's body (:func:`~ppamsafety.impact.summary.region_body`) and ``speed`` is that
        point's speed.
    effects : dict, optional, keyword-only
        Plant effects (as :func:`safety_case`).
    arm : ArmParameters, optional, keyword-only
        The arm (default the thesis arm).
    **dotted
        ``"arm.<key>"`` and ``"effects.<name>"`` parameters (as :func:`safety_case`).

    Returns
    -------
    dict
        ``F_max`` [N], ``HIC36``, ``HIC15``, ``tcp_speed`` [m/s] (with ``contact``: the
        point's speed), ``K1``, ``K2`` [Nm/rad], ``body_model`` (the body struck); with
        ``contact`` also ``contact_point``, ``body_region`` and ``p_max`` [Pa].
    """
    v, q, d, st, hm, arm = _impact_inputs(speed, q1_deg, q2_deg, direction, stiffness, head,
                                          effects, arm, dotted, region, contact)
    if st is None:
        K = np.array(rest_stiffness(arm, q).stiffness)
    else:
        K = np.broadcast_to(np.asarray(st, float), (2,)).copy()
    if contact is None:
        tcp = geo.jacobian(q, arm) @ d
        qd = d * (v / float(np.hypot(*tcp)))
        s = simulate_impacts(arm, q, qd, K, head=hm).summary.iloc[0]
        return {"F_max": float(s.F_max), "HIC36": float(s.HIC36), "HIC15": float(s.HIC15),
                "tcp_speed": float(s.tcp_speed), "K1": float(K[0]), "K2": float(K[1]),
                "body_model": hm.name}
    point = {c.name: c for c in arm_contact_points(arm)}[contact]
    pv = point_jacobian(q, arm, point) @ d
    qd = d * (v / float(np.hypot(*pv)))
    chosen = chosen_head(head)
    body = region_body(region, head=chosen if resolve_region(region).head else None)
    s = simulate_contacts(arm, q, qd, K, point=point, body=body).summary.iloc[0]
    return {"F_max": float(s.F_max), "HIC36": float(s.HIC36), "HIC15": float(s.HIC15),
            "tcp_speed": float(s.point_speed), "K1": float(K[0]), "K2": float(K[1]),
            "body_model": body_model_name(region, head=chosen if resolve_region(region).head
                                          else None),
            "contact_point": point.name, "body_region": body.name, "p_max": float(s.p_max)}


#: Largest tool speed of :func:`impact_case` [m/s].
SPEED_MAX = 10.0


def _impact_inputs(speed, q1_deg, q2_deg, direction, stiffness, head, effects, arm, dotted,
                   region=None, contact=None):
    """The checked arguments of :func:`impact_case` (speed, q [rad], direction, stiffness,
    the body struck at the tool point (:func:`~ppamsafety.impact.verdicts.region_head`), arm)."""
    v = _number("speed", speed, lo_open=True, unit="m/s")
    if v > SPEED_MAX:
        raise ValueError(f"speed = {v:g} m/s is outside (0, {SPEED_MAX:g}] m/s")
    if isinstance(direction, np.ndarray) and direction.ndim == 1:
        direction = direction.tolist()
    d = np.asarray([_number(f"direction[{i}]", x, lo=-math.inf) for i, x in
                    enumerate(direction)] if isinstance(direction, (list, tuple)) and
                   len(direction) == 2 else [], float)
    if d.size != 2 or not np.any(d):
        raise ValueError(f"direction = {direction!r} must be a non-zero pair (qd1, qd2)")
    st = _check_stiffness(stiffness)
    _check_head(head)
    _check_region(region)
    hm = region_head(region, chosen_head(head))     # refuses a head model for another region
    if contact is not None and (not isinstance(contact, str) or contact not in CONTACT_POINTS
                                or contact == "all"):
        raise ValueError(f"contact = {contact!r}: one of {list(CONTACT_POINTS[:-1])} (one "
                         f"impact has one contact point)")
    _check_effects(effects)
    arm = case_arm(arm, effects=effects or {}, changes=dotted)
    default = impact_pose_deg(arm)
    q1_deg = default[0] if q1_deg is None else q1_deg
    q2_deg = default[1] if q2_deg is None else q2_deg
    q = np.radians([_number("q1_deg", q1_deg, lo=-360.0, hi=360.0, unit="deg"),
                    _number("q2_deg", q2_deg, lo=-360.0, hi=360.0, unit="deg")])
    if not bool(geo.in_working_area(q, arm)):
        raise ValueError(f"q = ({q1_deg:g}, {q2_deg:g}) deg is outside the arm's working area")
    return v, q, d, st, hm, arm


def check_impact_case(speed: float, *, q1_deg=None, q2_deg=None, direction=(1.0, 0.0),
                      stiffness=None,
                      head="thesis-frontal", region=None, contact=None, effects=None,
                      arm=None, **dotted) -> None:
    """Check the arguments of :func:`impact_case` without simulating.

    Parameters
    ----------
    speed : float
        Tool (TCP) speed at impact [m/s], in (0, :data:`SPEED_MAX`].
    q1_deg, q2_deg : float, keyword-only
        Pose at impact [deg], in the working area (default :func:`impact_pose_deg`).
    direction : pair of float, keyword-only
        Joint-space velocity direction (qd1, qd2), not zero.
    stiffness : None, float or pair, keyword-only
        Joint stiffness [Nm/rad].
    head : str or HeadContactModel, keyword-only
        Head model.
    region : optional, keyword-only
        The body region struck.
    contact : str, optional, keyword-only
        A contact point of the arm.
    effects : dict, optional, keyword-only
        Plant effects.
    arm : ArmParameters, optional, keyword-only
        The arm (default the thesis arm).
    **dotted
        ``"arm.<key>"`` and ``"effects.<name>"`` parameters.

    Raises
    ------
    TypeError, ValueError
        Naming the parameter, its value and what is allowed.
    """
    _impact_inputs(speed, q1_deg, q2_deg, direction, stiffness, head, effects, arm, dotted,
                   region, contact)


def case_function(arm=None, head=None, *, kind: str = "safety"):
    """:func:`safety_case` bound to an arm and a head model (a sweep's case function).

    Parameters
    ----------
    arm : ArmParameters, optional
        The arm of every case (None: the thesis arm, :func:`safety_case` itself).
    head : HeadContactModel, optional
        The head of every case that does not name one (None: ``"thesis-frontal"``).
    kind : {"safety", "impact"}, keyword-only
        :func:`safety_case` (an experiment crashed into the head) or
        :func:`impact_case` (one impact at a given tool speed).

    Returns
    -------
    callable
        :func:`safety_case` / :func:`impact_case`, or a :func:`functools.partial` of it.  The sweep cache
        key hashes the partial's arguments, so another arm or head never reuses a
        cached result.
    """
    if arm is not None and not isinstance(arm, ArmParameters):
        raise TypeError(f"arm must be an ArmParameters or None, got {type(arm).__name__}")
    if head is not None and not isinstance(head, HeadContactModel):
        raise TypeError(f"head must be a HeadContactModel or None, got {type(head).__name__}")
    if kind not in ("safety", "impact"):
        raise ValueError(f"kind = {kind!r} is not one of 'safety', 'impact'")
    func = safety_case if kind == "safety" else impact_case
    kw = {}
    if arm is not None:
        kw["arm"] = arm
    if head is not None:
        kw["head"] = head
    return functools.partial(func, **kw) if kw else func


def _row_criteria(df: pd.DataFrame, criteria=None, region=None):
    """(index, row, criteria) of every row of a sweep table: the row's ``region`` column, or
    ``region``, decides its criteria (:func:`~ppamsafety.impact.verdicts.criteria_for`)
    unless ``criteria`` are given."""
    regs = (df["region"] if "region" in df.columns
            else pd.Series([None] * len(df), index=df.index, dtype=object))
    cache = {}
    for i, r in df.iterrows():
        reg = regs[i] if regs[i] is not None and not (
            isinstance(regs[i], float) and math.isnan(regs[i])) else region
        key = reg if isinstance(reg, (str, int, type(None))) else id(reg)
        if key not in cache:
            cache[key] = criteria_for(reg) if criteria is None else tuple(criteria)
        yield i, r, cache[key]


def add_verdicts(df: pd.DataFrame, criteria=None, *, region=None, head=None) -> pd.DataFrame:
    """A sweep's result table with the verdict of every case against the criteria.

    The same verdicts as ``ppamsafety impact``, the envelopes and the report
    (:func:`ppamsafety.impact.verdicts.evaluate`).

    Parameters
    ----------
    df : pandas.DataFrame
        Result rows with ``F_max``/``HIC36``/``HIC15`` and, where the contact geometry gives
        one, ``p_max`` [Pa] (failed rows get no verdict).  A ``region`` column (the case's
        body region) sets each row's region; a ``body_model`` column names the body each
        case was simulated with.
    criteria : sequence of Criterion, optional
        Default :func:`~ppamsafety.impact.verdicts.criteria_for` each row's region.
    region : optional
        The body region of rows without a ``region`` (default ``"skull/forehead"``).
    head : str or HeadContactModel, optional
        The body model of rows without ``body_model`` or ``head`` (default
        ``"thesis-frontal"``).

    Returns
    -------
    pandas.DataFrame
        ``df`` with ``head_model`` (the body model simulated), ``verdict``
        (``"pass"``/``"fail"``), ``governing`` (the criterion with the smallest relative
        margin), ``governing_margin_pct`` and per criterion judged in at least one row
        ``<name>_margin`` (limit - value, in the limit's unit: N, Pa or HIC) and
        ``<name>_pass``.  A criterion is judged where its result exists (``p_max`` only
        with a contact geometry; its columns only when some case has it).
    """
    out = df.copy()
    default = head.name if isinstance(head, HeadContactModel) else (head or "thesis-frontal")
    if "body_model" in out.columns:            # a failed case simulated no body
        names = out["body_model"].map(lambda b: None if b is None or b != b else str(b))
    elif "head" in out.columns:
        names = out["head"].map(lambda h: h.name if isinstance(h, HeadContactModel) else str(h))
    else:
        names = pd.Series(default, index=out.index)
    cols = {"head_model": [], "verdict": [], "governing": [], "governing_margin_pct": []}
    judged, used = {}, {}
    for i, r, crit in _row_criteria(out, criteria, region):
        used[id(crit)] = crit
        vals = {m: r[m] for m in {c.metric for c in crit}
                if m in r and r[m] is not None and pd.notna(r[m])}
        ok = r.get("status", "ok") == "ok" and "F_max" in vals
        t = evaluate(vals, crit, head=names[i]) if ok else None
        cols["head_model"].append(names[i])
        if t is None or not len(t):
            for k in ("verdict", "governing", "governing_margin_pct"):
                cols[k].append(None)
            judged[i] = {}
            continue
        g = t.loc[t["margin_pct"].idxmin()]
        cols["verdict"].append("pass" if t["passed"].all() else "fail")
        cols["governing"].append(g.criterion)
        cols["governing_margin_pct"].append(float(g.margin_pct))
        judged[i] = {row.criterion: (float(row.margin), bool(row.passed))
                     for row in t.itertuples()}
    names_judged = []
    for crit in used.values():
        for c in crit:
            if c.name not in names_judged and (c.metric != "p_max" or any(
                    c.name in j for j in judged.values())):
                names_judged.append(c.name)
    for n in names_judged:
        cols[f"{n}_margin"] = [judged[i].get(n, (None, None))[0] for i in out.index]
        cols[f"{n}_pass"] = [judged[i].get(n, (None, None))[1] for i in out.index]
    for k, v in cols.items():
        out[k] = v
    return out


#: Columns of :func:`verdict_limits`.
LIMIT_COLUMNS = ("metric", "criterion", "region", "limit", "unit", "label", "confirmed",
                 "governs", "fails")


def verdict_limits(df: pd.DataFrame, criteria=None, *, region=None) -> pd.DataFrame:
    """The limits of a sweep's verdicts that a reader must see: each criterion that governs
    or fails at least one case (:func:`add_verdicts`'s columns), and for a result judged
    but decided by none, its tightest criterion.

    Parameters
    ----------
    df : pandas.DataFrame
        A table with :func:`add_verdicts`'s columns (``governing``, ``<name>_pass``) and,
        optionally, the cases' ``region``.
    criteria : sequence of Criterion, optional
        The criteria the verdicts used (default: each row's region's, as :func:`add_verdicts`).
    region : optional
        The region of rows without a ``region`` (default ``"skull/forehead"``).

    Returns
    -------
    pandas.DataFrame
        :data:`LIMIT_COLUMNS`, one row per (region, criterion): the result column it bounds
        (``F_max``, ``HIC36``, ``p_max``), the limit (SI) and its unit, its label, whether a
        public source confirms it, how many cases it governs and how many fail it; ordered
        by metric, then limit.  Empty for a table without verdicts.
    """
    if "governing" not in df.columns:
        return pd.DataFrame(columns=list(LIMIT_COLUMNS))
    rows, judged = {}, {}
    for i, r, crit in _row_criteria(df, criteria, region):
        for c in crit:
            passed = r.get(f"{c.name}_pass")
            if passed is None or (isinstance(passed, float) and math.isnan(passed)):
                continue
            key = (c.region, c.name)
            row = {"metric": c.metric, "criterion": c.name, "region": c.region,
                   "limit": c.limit, "unit": c.unit, "label": c.label,
                   "confirmed": c.confirmed, "governs": 0, "fails": 0}
            if c.metric not in judged or c.limit < judged[c.metric]["limit"]:
                judged[c.metric] = row
            gov, fail = r.get("governing") == c.name, not bool(passed)
            if not (gov or fail):
                continue
            rows.setdefault(key, dict(row))
            rows[key]["governs"] += int(gov)
            rows[key]["fails"] += int(fail)
    for metric, row in judged.items():       # a result judged but decided by no limit: its
        if not any(v["metric"] == metric for v in rows.values()):     # tightest criterion
            rows[(row["region"], row["criterion"])] = row
    out = pd.DataFrame(list(rows.values()), columns=list(LIMIT_COLUMNS))
    return out.sort_values(["metric", "limit"], kind="stable").reset_index(drop=True)


def failed_criteria(df: pd.DataFrame, metric: str, criteria=None, *, region=None) -> pd.Series:
    """The criteria on one result that each case fails (:func:`add_verdicts`'s
    ``<name>_pass``).

    Parameters
    ----------
    df : pandas.DataFrame
        A table with :func:`add_verdicts`'s columns.
    metric : str
        The result (``"F_max"``, ``"HIC36"``, ``"p_max"``).
    criteria : sequence of Criterion, optional
        The criteria of the verdicts (default: each row's region's).
    region : optional
        The region of rows without a ``region`` column.

    Returns
    -------
    pandas.Series of str
        Aligned with ``df``: the labels of the failed criteria (``"; "``-separated, an
        unconfirmed limit marked ``[unconfirmed]``), ``""`` where the case fails none.
    """
    out = []
    for i, r, crit in _row_criteria(df, criteria, region):
        out.append("; ".join(c.label + ("" if c.confirmed else " [unconfirmed]")
                             for c in crit if c.metric == metric
                             and r.get(f"{c.name}_pass") is not None
                             and not (isinstance(r.get(f"{c.name}_pass"), float)
                                      and math.isnan(r.get(f"{c.name}_pass")))
                             and not bool(r.get(f"{c.name}_pass"))))
    return pd.Series(out, index=df.index, dtype=object)


def safety_sweep(cases=None, *, grid=None, name: str = "safety", cache_dir=None,
                 processes: int | None = None, progress: bool = True, on_error: str = "record",
                 backend: str = "local", scheduler=None, arm=None, head=None) -> SweepResult:
    """Run :func:`safety_case` over a grid or a list of cases (all cores by default).

    Parameters
    ----------
    cases : sequence of dict, optional
        :func:`safety_case` keyword arguments per case; each is checked
        (:func:`check_case`) before anything runs.
    grid : mapping of str to list, optional
        Parameter grid combined with every case (:func:`ppamsafety.sweep.grid_cases`).
    name : str
        Sweep name (part of the cache key).
    cache_dir : path-like, optional
        Resume folder (see :func:`ppamsafety.sweep.run_sweep`).
    processes : int, optional
        Worker processes, default every available core.
    progress : bool
        Progress bar.
    on_error : {"record", "raise"}
        Failing cases: a row with ``status="failed"`` and ``error``, or stop.
    backend : {"local", "dask"}
        Where the cases run (see :func:`ppamsafety.sweep.run_sweep`).
    scheduler : None, str or dask.distributed.Client
        Dask scheduler (None: a LocalCluster for the sweep).
    arm : ArmParameters, optional
        The arm of every case (default the thesis arm); cases change it with
        ``effects`` and dotted parameters (``"arm.links.m2"``).
    head : HeadContactModel, optional
        The head of every case that names none (default ``"thesis-frontal"``).

    Returns
    -------
    SweepResult
        Its table (``.table``): case parameters, ``status``, ``error``, the
        :func:`safety_case` results and their verdicts against the criteria of the
        skull/forehead (:func:`add_verdicts`); ``.plot()`` draws them against the swept
        parameters.
    """
    all_cases = _check_cases([{}] if cases is None else cases)
    if grid is not None:
        all_cases = [{**c, **g} for c in all_cases for g in grid_cases(grid)]
    elif cases is None:
        raise TypeError("safety_sweep needs cases (a list of dicts) or grid (a dict of lists)")
    func = case_function(arm, head)
    for i, c in enumerate(all_cases):
        if "arm" in c:
            raise ValueError(f"case {i}: the arm is an argument of the sweep (arm=...), not a "
                             f"case parameter; a case changes it with arm.<key> parameters")
        try:
            check_case(**c, arm=arm)
        except (TypeError, ValueError) as exc:
            raise type(exc)(f"case {i} {c!r}: {exc}") from None
    df = run_sweep(func, all_cases, name=name, cache_dir=cache_dir, processes=processes,
                   progress=progress, on_error=on_error, backend=backend, scheduler=scheduler)
    table = add_verdicts(df.table, head=head)
    return SweepResult(table, name=name, units={c: column_unit(c) for c in table.columns})


__all__ = ["EXPERIMENTS", "CONTROLLERS", "INSTANTS", "MIN_SPEED", "PARAMETERS", "DEFAULTS",
           "STEP_KEYS", "case_references",
           "DOTTED", "RESULT_COLUMNS", "check_case", "make_controller", "safety_case",
           "CONTACT_KEYS", "CONTACT_POINTS", "contact_covering",
           "safety_sweep", "case_arm", "case_function", "is_dotted", "impact_case",
           "check_impact_case", "SPEED_MAX", "IMPACT_POSE_DEG", "impact_pose_deg", "add_verdicts", "COLUMN_UNITS",
           "column_unit", "verdict_limits", "failed_criteria", "LIMIT_COLUMNS", "chosen_head"]
