"""The named thesis experiments and controller variants (§5.3.4, Tables 5.1, 5.2, 6.1).

* :func:`thesis_variants` -- the ten controller variants of Table 6.1 (and
  the rows of Table 5.2), in that order: PID; joint-space PSMC with
  Ki = 2 bar/(rad s) and lambda = 0.4, 0.8, 1.5 s; joint-space PSMC with
  Ki = 12 bar/(rad s) and the same lambdas; task-space PSMC with the same
  lambdas.  All other gains are those of Table 5.1.
* :func:`thesis_reference` -- the reference of a named experiment:
  ``"step"`` (fig. 5.17), ``"switch"`` (fig. 5.15), ``"circle5"``,
  ``"circle10"``, ``"circle20"`` (20 cm circle with period 5/10/20 s,
  Table 5.2).
* :func:`run_thesis_experiment` -- one named experiment for many variants in
  one compiled batch; every result carries its variant label in
  ``result.meta["label"]``.

Durations (our choice where the thesis is silent): circles run
``CIRCLE_WARMUP`` = 5 s of warm-up followed by the thesis' "40 seconds of
measurements" (Table 5.2 caption), i.e. 45 s; the step runs 12 s (q1_d steps
up at 2 s, down at 7 s); the switch runs 15 s (switch at 7.5 s).
"""

from __future__ import annotations

from ..control import PID, JointPSMC, SensorConfig, TaskPSMC
from ..control.base import Controller
from ..units import BAR
from . import trajectories as tr
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


def variant_label(controller: Controller) -> str:
    """Short label of a PID / joint PSMC / task PSMC controller, e.g. ``"PSMC joint Ki=2 λ=0.4"``."""
    if isinstance(controller, PID):
        return "PID"
    if isinstance(controller, JointPSMC):
        return f"PSMC joint Ki={controller.ki[0] / BAR:g} λ={controller.lam[0]:g}"
    if isinstance(controller, TaskPSMC):
        return f"PSMC task λ={controller.lam:g}"
    return controller.name


def variant_family(controller: Controller) -> str:
    """Controller family of a variant: ``"PID"``, ``"PSMC joint Ki=2"``, ``"PSMC joint Ki=12"``, ``"PSMC task"``."""
    if isinstance(controller, JointPSMC):
        return f"PSMC joint Ki={controller.ki[0] / BAR:g}"
    if isinstance(controller, TaskPSMC):
        return "PSMC task"
    return controller.name


def variant_lambda(controller: Controller) -> float:
    """lambda [s] of a PSMC variant (joint 1 for joint space), NaN otherwise."""
    if isinstance(controller, JointPSMC):
        return float(controller.lam[0])
    if isinstance(controller, TaskPSMC):
        return float(controller.lam)
    return float("nan")


def thesis_variants(*, lambdas=THESIS_LAMBDAS) -> list:
    """The controller variants of Table 6.1 / Table 5.2 as (label, controller) pairs.

    Parameters
    ----------
    lambdas : sequence of float, keyword-only
        Sliding-mode time constants lambda [s] of the PSMC variants (default
        0.4, 0.8, 1.5 s as in the thesis).

    Returns
    -------
    list of (str, Controller)
        PID; joint PSMC Ki = 2 bar/(rad s) for each lambda; joint PSMC
        Ki = 12 bar/(rad s) for each lambda; task PSMC for each lambda.
        Gains in SI units (Pa/rad, Pa/(rad s), Pa s/rad; N/m, ...), Table 5.1
        otherwise; gravity compensation at the defaults of the controllers.
    """
    lams = [float(x) for x in lambdas]
    if not lams:
        raise ValueError("thesis_variants: lambdas must not be empty")
    out = [PID()]
    for ki in THESIS_KI_BAR:
        out += [JointPSMC(lam=lam, ki=ki * BAR) for lam in lams]
    out += [TaskPSMC(lam=lam) for lam in lams]
    return [(variant_label(c), c) for c in out]


def thesis_reference(arm, name: str, *, duration: float | None = None, dt: float = 1e-3):
    """Reference trajectory of the named thesis experiment.

    Parameters
    ----------
    arm : ArmParameters
    name : {"step", "switch", "circle5", "circle10", "circle20"}
    duration : float, optional
        Length [s]; default :data:`DEFAULT_DURATIONS`.  The step needs more
        than 2 s, the switch more than 7.5 s (the discontinuity must occur).
    dt : float
        Sample period [s].

    Returns
    -------
    Reference
    """
    if name not in EXPERIMENTS:
        raise ValueError(f"unknown thesis experiment {name!r}; choose from {list(EXPERIMENTS)}")
    d = DEFAULT_DURATIONS[name] if duration is None else float(duration)
    if name == "step":
        if d <= STEP_TIMES[0]:
            raise ValueError(f"step experiment: duration = {d:g} s must exceed {STEP_TIMES[0]} s")
        return tr.step(arm, t_up=STEP_TIMES[0], t_down=STEP_TIMES[1], duration=d, dt=dt)
    if name == "switch":
        if d <= SWITCH_TIME:
            raise ValueError(f"switch experiment: duration = {d:g} s must exceed {SWITCH_TIME} s")
        return tr.trajectory_switch(arm, t_switch=SWITCH_TIME, duration=d, dt=dt)
    return tr.circle(arm, period=CIRCLE_PERIODS[name], duration=d, dt=dt)


def run_thesis_experiment(arm, name: str, variants=None, *, sensors: SensorConfig | None = None,
                          duration: float | None = None, dt: float = 1e-3,
                          substeps: int = 1) -> list:
    """Run one named thesis experiment for many controller variants (one batch).

    Parameters
    ----------
    arm : ArmParameters
        The plant (and the controllers' model).
    name : {"step", "switch", "circle5", "circle10", "circle20"}
    variants : sequence of (str, Controller), optional
        Labelled controllers; default :func:`thesis_variants`.
    sensors : SensorConfig, optional
        Sensor models (default: realistic encoders and timing board).
    duration : float, optional
        Experiment length [s] (default :data:`DEFAULT_DURATIONS`).
    dt : float
        Control period [s].
    substeps : int
        RK4 steps per control period.

    Returns
    -------
    list of ExperimentResult
        In the order of ``variants``; ``meta`` holds ``label``,
        ``experiment``, ``family`` (:func:`variant_family`) and ``lambda_s``.
    """
    variants = thesis_variants() if variants is None else list(variants)
    for v in variants:
        if not (isinstance(v, tuple) and len(v) == 2 and isinstance(v[1], Controller)):
            raise ValueError("variants must be (label, Controller) pairs")
    ref = thesis_reference(arm, name, duration=duration, dt=dt)
    sens = SensorConfig() if sensors is None else sensors
    cases = [{"arm": arm, "controller": c, "reference": ref, "sensors": sens,
              "name": f"{name}: {label}",
              "meta": {"label": label, "experiment": name, "family": variant_family(c),
                       "lambda_s": variant_lambda(c)}}
             for label, c in variants]
    return run_batch(cases, dt=dt, substeps=substeps)


__all__ = ["EXPERIMENTS", "CIRCLE_PERIODS", "THESIS_LAMBDAS", "THESIS_KI_BAR", "CIRCLE_WARMUP",
           "CIRCLE_EVAL", "DEFAULT_DURATIONS", "STEP_TIMES", "SWITCH_TIME", "variant_label",
           "variant_family", "variant_lambda",
           "thesis_variants", "thesis_reference", "run_thesis_experiment"]
