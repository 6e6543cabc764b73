"""The named thesis experiments and controller variants (§5.3.4, Tables 5.1, 5.2, 6.1).

* :func:`thesis_variants` -- the ten controller variants of Table 6.1 (and
  the rows of Table 5.2), in that order: PID; joint-space PSMC with
  Ki = 2 bar/(rad s) and lambda = 0.4, 0.8, 1.5 s; joint-space PSMC with
  Ki = 12 bar/(rad s) and the same lambdas; task-space PSMC with the same
  lambdas.  All other gains are those of Table 5.1.  Each is a
  :class:`ControllerVariant` that carries the fields the thesis tables are
  keyed by (:attr:`~ControllerVariant.family`, ``ki_bar``, ``lambda_s``;
  see :mod:`ppamsafety.experiments.thesis_data`).
* :func:`thesis_reference` -- the reference of a named experiment:
  ``"step"`` (fig. 5.17), ``"switch"`` (fig. 5.15), ``"circle5"``,
  ``"circle10"``, ``"circle20"`` (20 cm circle with period 5/10/20 s,
  Table 5.2).
* :func:`run_thesis_experiment` -- one named experiment for many variants in
  one compiled batch; every result carries its variant (and its label and
  fields) in ``result.meta``.

Durations (our choice where the thesis is silent): circles run
``CIRCLE_WARMUP`` = 5 s of warm-up followed by the thesis' "40 seconds of
measurements" (Table 5.2 caption), i.e. 45 s; the step runs 12 s (q1_d steps
up at 2 s, down at 7 s); the switch runs 15 s (switch at 7.5 s).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from .._validation import check_instance, check_range, check_str, check_vector
from ..control import PID, JointPSMC, SensorConfig, TaskPSMC
from ..control.base import Controller
from ..params.arm import ArmParameters
from ..units import BAR
from . import trajectories as tr
from .case import ExperimentCase
from .closed_loop import run_batch

#: Names of the thesis experiments.
EXPERIMENTS = ("step", "switch", "circle5", "circle10", "circle20")
#: Circle periods of Table 5.2 [s].
CIRCLE_PERIODS = {"circle5": 5.0, "circle10": 10.0, "circle20": 20.0}
#: lambda values varied in §5.3.4 and Table 6.1 [s].
THESIS_LAMBDAS = (0.4, 0.8, 1.5)
#: Integral gains of the joint-space PSMC variants [bar/(rad s)] (Table 5.1, §5.3.4).
THESIS_KI_BAR = (2.0, 12.0)
#: Warm-up before the circle evaluation window [s] and the window itself [s] (Table 5.2).
CIRCLE_WARMUP = 5.0
CIRCLE_EVAL = 40.0
#: Default duration of each experiment [s].
DEFAULT_DURATIONS = {"step": 12.0, "switch": 15.0, "circle5": CIRCLE_WARMUP + CIRCLE_EVAL,
                     "circle10": CIRCLE_WARMUP + CIRCLE_EVAL,
                     "circle20": CIRCLE_WARMUP + CIRCLE_EVAL}
#: Times of the discontinuities of the step and switch references [s].
STEP_TIMES = (2.0, 7.0)
SWITCH_TIME = 7.5


class Family(str, enum.Enum):
    """Controller family of a variant (the value is the controller's ``name``)."""

    PID = "PID"
    PSMC_JOINT = "PSMC joint"
    PSMC_TASK = "PSMC task"
    SMC = "SMC"
    GRAVITY = "gravity compensation"


def _family_of(controller: Controller) -> Family:
    try:
        return Family(controller.name)
    except ValueError:
        raise ValueError(f"controller {controller.name!r} is not of a known family; allowed: "
                         f"{[f.value for f in Family]}") from None


def _fields_of(controller: Controller) -> tuple:
    """(family, ki_bar, lambda_s) of a controller (NaN where the gain does not apply)."""
    fam = _family_of(controller)
    ki = lam = math.nan
    if isinstance(controller, (PID, JointPSMC)):
        ki = float(controller.ki[0] / BAR)
    if isinstance(controller, JointPSMC):
        lam = float(controller.lam[0])
    elif isinstance(controller, TaskPSMC):
        lam = float(controller.lam)
    return fam, ki, lam


def _as_gain(name: str, value) -> float:
    """A gain field: float >= 0, or NaN (None also means NaN: not applicable)."""
    if value is None:
        return math.nan
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise TypeError(f"ControllerVariant.{name} must be a float or NaN, got "
                            f"{value!r}") from None
    v = float(value)
    if not (math.isnan(v) or (math.isfinite(v) and v >= 0)):
        raise ValueError(f"ControllerVariant.{name} = {v!r} must be >= 0 (or NaN where it does "
                         "not apply)")
    return v


def _same(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or a == b


def label_of(family, ki_bar: float, lambda_s: float) -> str:
    """Short label of a variant from its fields, e.g. ``"PSMC joint Ki=2 λ=0.4"``.

    Parameters
    ----------
    family : Family or str
        Controller family.
    ki_bar : float
        Integral gain [bar/(rad s)] (joint PSMC), NaN where it does not apply.
    lambda_s : float
        Sliding-mode time constant lambda [s] (PSMC), NaN otherwise.
    """
    fam = Family(family)
    if fam is Family.PSMC_JOINT:
        return f"PSMC joint Ki={ki_bar:g} λ={lambda_s:g}"
    if fam is Family.PSMC_TASK:
        return f"PSMC task λ={lambda_s:g}"
    return fam.value


@dataclass(frozen=True, eq=False)
class ControllerVariant:
    """A controller variant with the fields the thesis tables are keyed by.

    Parameters
    ----------
    family : Family or str
        ``"PID"``, ``"PSMC joint"``, ``"PSMC task"``, ``"SMC"`` or
        ``"gravity compensation"``; must be the controller's family.
    ki_bar : float
        Integral gain Ki of joint 1 [bar/(rad s)] for PID and joint PSMC
        (Table 5.1), NaN otherwise; must equal the controller's.
    lambda_s : float
        Sliding-mode time constant lambda [s] of a PSMC (joint 1 for joint
        space), NaN otherwise; must equal the controller's.
    controller : Controller
        The controller.
    name : str, optional
        Label overriding the one derived from the fields (e.g. for
        ablation variants that share the fields).

    Raises
    ------
    TypeError
        For a controller that is not a Controller or a non-numeric gain.
    ValueError
        For an unknown family or a field that contradicts the controller.

    See Also
    --------
    ControllerVariant.of : the variant of a controller, fields inferred.
    """

    family: Family
    ki_bar: float
    lambda_s: float
    controller: Controller
    name: str | None = None

    def __post_init__(self):
        if not isinstance(self.controller, Controller):
            raise TypeError(f"ControllerVariant.controller must be a Controller, got "
                            f"{type(self.controller).__name__}")
        try:
            fam = Family(self.family)
        except ValueError:
            raise ValueError(f"ControllerVariant.family = {self.family!r} is not one of "
                             f"{[f.value for f in Family]}") from None
        object.__setattr__(self, "family", fam)
        object.__setattr__(self, "ki_bar", _as_gain("ki_bar", self.ki_bar))
        object.__setattr__(self, "lambda_s", _as_gain("lambda_s", self.lambda_s))
        if self.name is not None and not isinstance(self.name, str):
            raise TypeError(f"ControllerVariant.name must be a str or None, got {self.name!r}")
        want = dict(zip(("family", "ki_bar", "lambda_s"), _fields_of(self.controller)))
        if want["family"] is not fam:
            raise ValueError(f"ControllerVariant.family = {fam.value!r} but the controller is a "
                             f"{want['family'].value!r}")
        for f in ("ki_bar", "lambda_s"):
            if not _same(getattr(self, f), want[f]):
                raise ValueError(f"ControllerVariant.{f} = {getattr(self, f)!r} but the "
                                 f"controller has {want[f]!r}")

    @classmethod
    def of(cls, controller: Controller, name: str | None = None) -> "ControllerVariant":
        """The variant of ``controller``, its fields read from the controller.

        Parameters
        ----------
        controller : Controller
        name : str, optional
            Label; default derived from the fields (:func:`label_of`).
        """
        if not isinstance(controller, Controller):
            raise TypeError(f"controller must be a Controller, got {type(controller).__name__}")
        fam, ki, lam = _fields_of(controller)
        if name is not None and name == label_of(fam, ki, lam):
            name = None
        return cls(fam, ki, lam, controller, name)

    @property
    def label(self) -> str:
        """Display label, e.g. ``"PSMC joint Ki=2 λ=0.4"`` (``name`` if given)."""
        return self.name if self.name is not None else label_of(self.family, self.ki_bar,
                                                                 self.lambda_s)

    @property
    def group(self) -> str:
        """Group of the tables and figures: the family, joint PSMC split by Ki.

        ``"PID"``, ``"PSMC joint Ki=2"``, ``"PSMC joint Ki=12"``, ``"PSMC
        task"``, ...; stored as ``meta["family"]`` of the results.
        """
        if self.family is Family.PSMC_JOINT:
            return f"PSMC joint Ki={self.ki_bar:g}"
        return self.family.value

    def keys(self) -> dict:
        """The join keys of the thesis tables (:data:`~.thesis_data.VARIANT_KEYS`)."""
        return {"controller_family": self.family.value, "ki_bar": self.ki_bar,
                "lambda_s": self.lambda_s}

    def __iter__(self):
        """``label, controller = variant`` (compatibility with the old pairs)."""
        return iter((self.label, self.controller))

    def __repr__(self) -> str:
        return f"ControllerVariant({self.label!r})"


def as_variant(v) -> ControllerVariant:
    """A :class:`ControllerVariant`, or a ``(label, Controller)`` pair converted to one.

    Parameters
    ----------
    v : ControllerVariant or (str, Controller)
    """
    if isinstance(v, ControllerVariant):
        return v
    if (isinstance(v, tuple) and len(v) == 2 and isinstance(v[0], str)
            and isinstance(v[1], Controller)):
        return ControllerVariant.of(v[1], name=v[0])
    raise ValueError(f"variants must be ControllerVariant objects or (label, Controller) pairs, "
                     f"got {v!r:.80}")


def variant_label(controller: Controller) -> str:
    """Short label of a controller's variant, e.g. ``"PSMC joint Ki=2 λ=0.4"``.

    Parameters
    ----------
    controller : Controller
        The controller.
    """
    return ControllerVariant.of(controller).label


def variant_family(controller: Controller) -> str:
    """Group of a controller's variant: ``"PID"``, ``"PSMC joint Ki=2"``, ``"PSMC task"``, ...

    Parameters
    ----------
    controller : Controller
        The controller.
    """
    return ControllerVariant.of(controller).group


def variant_lambda(controller: Controller) -> float:
    """lambda [s] of a PSMC variant (joint 1 for joint space), NaN otherwise.

    Parameters
    ----------
    controller : Controller
        The controller.
    """
    return ControllerVariant.of(controller).lambda_s


def _check_name(name) -> str:
    """A thesis experiment name (str, one of :data:`EXPERIMENTS`)."""
    check_str("name", name)
    if name not in EXPERIMENTS:
        raise ValueError(f"unknown thesis experiment name = {name!r}; choose from "
                         f"{list(EXPERIMENTS)}")
    return name


def _check_arm(arm):
    return check_instance("arm", arm, ArmParameters)


def thesis_variants(*, lambdas=THESIS_LAMBDAS) -> list:
    """The controller variants of Table 6.1 / Table 5.2.

    Parameters
    ----------
    lambdas : sequence of float, keyword-only
        Sliding-mode time constants lambda [s] of the PSMC variants (default
        0.4, 0.8, 1.5 s as in the thesis).

    Returns
    -------
    list of ControllerVariant
        PID; joint PSMC Ki = 2 bar/(rad s) for each lambda; joint PSMC
        Ki = 12 bar/(rad s) for each lambda; task PSMC for each lambda.
        Gains in SI units (Pa/rad, Pa/(rad s), Pa s/rad; N/m, ...), Table 5.1
        otherwise; gravity compensation at the defaults of the controllers.
    """
    lams = list(check_vector("lambdas", lambdas, None, 0.0, 100.0, unit="s"))
    if not lams:
        raise ValueError("lambdas must not be empty")
    out = [PID()]
    for ki in THESIS_KI_BAR:
        out += [JointPSMC(lam=lam, ki=ki * BAR) for lam in lams]
    out += [TaskPSMC(lam=lam) for lam in lams]
    return [ControllerVariant.of(c) for c in out]


def thesis_reference(arm, name: str, *, duration: float | None = None, dt: float = 1e-3,
                     references: tr.ExperimentReferences | None = None):
    """Reference trajectory of the named thesis experiment.

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    name : {"step", "switch", "circle5", "circle10", "circle20"}
        The experiment.
    duration : float, optional
        Length [s]; default :data:`DEFAULT_DURATIONS`.  The step needs more
        than 2 s, the switch more than 7.5 s (the discontinuity must occur).
    dt : float
        Sample period [s].
    references : ExperimentReferences, optional, keyword-only
        Where the experiment runs (the step's levels, the circle's centre and radius);
        default :func:`~ppamsafety.experiments.trajectories.experiment_references` of the
        arm (the thesis arm: the thesis' references; another arm: derived from its working
        area).

    Returns
    -------
    Reference
    """
    _check_arm(arm)
    name = _check_name(name)
    refs = tr.experiment_references(arm) if references is None else check_instance(
        "references", references, tr.ExperimentReferences)
    d = DEFAULT_DURATIONS[name] if duration is None else check_range(
        "duration", duration, 0.0, 1e5, lo_open=True, unit="s")
    if name == "step":
        if d <= STEP_TIMES[0]:
            raise ValueError(f"step experiment: duration = {d:g} s must exceed the up-step at "
                             f"{STEP_TIMES[0]} s")
        return tr.step(arm, low=refs.step_low, high=refs.step_high, q2=refs.step_q2,
                       t_up=STEP_TIMES[0], t_down=STEP_TIMES[1], duration=d, dt=dt)
    circle = {"center": refs.circle_center, "radius": refs.circle_radius}
    if name == "switch":
        if d <= SWITCH_TIME:
            raise ValueError(f"switch experiment: duration = {d:g} s must exceed {SWITCH_TIME} s")
        return tr.trajectory_switch(arm, t_switch=SWITCH_TIME, duration=d, dt=dt, **circle)
    return tr.circle(arm, period=CIRCLE_PERIODS[name], duration=d, dt=dt, **circle)


def run_thesis_experiment(arm, name: str, variants=None, *, sensors: SensorConfig | None = None,
                          duration: float | None = None, dt: float = 1e-3,
                          substeps: int = 1,
                          references: tr.ExperimentReferences | None = None) -> list:
    """Run one named thesis experiment for many controller variants (one batch).

    Parameters
    ----------
    arm : ArmParameters
        The plant (and the controllers' model).
    name : {"step", "switch", "circle5", "circle10", "circle20"}
        The experiment.
    variants : sequence of ControllerVariant, optional
        Default :func:`thesis_variants`.  ``(label, Controller)`` pairs are
        accepted too (fields read from the controller, see
        :meth:`ControllerVariant.of`).
    sensors : SensorConfig, optional
        Sensor models (default: realistic encoders and timing board of the
        arm's sensor hardware, ``SensorConfig.for_arm(arm)``).
    duration : float, optional
        Experiment length [s] (default :data:`DEFAULT_DURATIONS`).
    dt : float
        Control period [s].
    substeps : int
        RK4 steps per control period.
    references : ExperimentReferences, optional
        Where the experiment runs (:func:`thesis_reference`; default derived from the arm).

    Returns
    -------
    list of ExperimentResult
        In the order of ``variants``; ``meta`` holds ``variant`` (the
        :class:`ControllerVariant`), ``label``, ``experiment``, ``family``
        (the variant's :attr:`~ControllerVariant.group`, e.g.
        ``"PSMC joint Ki=2"``), ``controller_family`` (its family, e.g.
        ``"PSMC joint"``), ``ki_bar`` [bar/(rad s)] and ``lambda_s`` [s].
        A diverged run has ``diverged`` set with ``divergence_reason`` (and
        a ``UserWarning`` names it).
    """
    _check_arm(arm)
    name = _check_name(name)
    if variants is not None and (isinstance(variants, (str, bytes, ControllerVariant, Controller))
                                 or not hasattr(variants, "__iter__")):
        raise TypeError(f"variants must be a sequence of ControllerVariant, got "
                        f"{type(variants).__name__}")
    variants = thesis_variants() if variants is None else [as_variant(v) for v in variants]
    if not variants:
        raise ValueError("variants must not be empty")
    sens = SensorConfig.for_arm(arm) if sensors is None else check_instance(
        "sensors", sensors, SensorConfig)
    ref = thesis_reference(arm, name, duration=duration, dt=dt, references=references)
    cases = [ExperimentCase(arm, v.controller, ref, sensors=sens, name=f"{name}: {v.label}",
                            meta={"label": v.label, "experiment": name, "family": v.group,
                                  "lambda_s": v.lambda_s, "ki_bar": v.ki_bar,
                                  "controller_family": v.family.value, "variant": v})
             for v in variants]
    return run_batch(cases, dt=dt, substeps=substeps)


def results_by_label(results) -> dict:
    """The runs of :func:`run_thesis_experiment` keyed by their variant label.

    Parameters
    ----------
    results : iterable of ExperimentResult
        Runs whose ``meta["label"]`` names their variant (e.g. ``"PSMC joint Ki=2 λ=0.4"``).

    Returns
    -------
    dict
        Label -> run (a later run with the same label replaces an earlier one).
    """
    return {r.meta["label"]: r for r in results}


__all__ = ["EXPERIMENTS", "CIRCLE_PERIODS", "THESIS_LAMBDAS", "THESIS_KI_BAR", "CIRCLE_WARMUP",
           "CIRCLE_EVAL", "DEFAULT_DURATIONS", "STEP_TIMES", "SWITCH_TIME", "Family",
           "ControllerVariant", "as_variant", "label_of", "variant_label", "variant_family",
           "variant_lambda",
           "thesis_variants", "thesis_reference", "run_thesis_experiment", "results_by_label"]
