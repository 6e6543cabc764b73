"""The hidden-effect data generator, :func:`synthesize`: rehearsal records for the diagnosis.

The arm generator is :mod:`ppamsafety.diagnose.arm.synthesize`, the test-bench
generator :mod:`ppamsafety.diagnose.bench.synthesize`; this front door picks one
by ``kind`` and checks that the options belong to it.
"""

from __future__ import annotations

from .._validation import check_choice
from ..data.measured import MeasuredData, MeasuredDataError
from ..params import thesis_arm
from ..params.arm_file import arm_fingerprint
from ..params.effects import Effects
from .arm.synthesize import (DEFAULT_CONTROLLER, DEFAULT_REFERENCE, MEASUREMENT_BOUNDS,
                             RELATIVE, plant_with, synthesize_arm)
from .bench.synthesize import EFFECT_BOUNDS, _check_effects, synthesize_actuator


def arm_record(arm) -> dict:
    """The ``[arm]`` metadata of a record made with ``arm``: its name and fingerprint.

    Parameters
    ----------
    arm : ArmParameters or None
        The nominal arm (None: the thesis arm).

    Returns
    -------
    dict
        ``{"name": str, "sha256": str}`` (:func:`ppamsafety.params.arm_file.arm_fingerprint`).
    """
    arm = thesis_arm() if arm is None else arm
    return {"name": arm.name, "sha256": arm_fingerprint(arm)}


def synthesize(experiment: str | None = None, effects=None, *, noise: str | None = None,
               seed: int = 0, duration: float | None = None, dt: float = 1e-3, arm=None,
               controller: str = DEFAULT_CONTROLLER, reference: str = DEFAULT_REFERENCE,
               kind: str = "arm", **tester):
    """A record of ``experiment`` on a plant with hidden ``effects``.

    Parameters
    ----------
    experiment : {"open-loop", "closed-loop", "static-sawtooth", "tensile"}, optional
        Arm (default ``"open-loop"``): open-loop Fourier excitation of the
        valves (§3.5.2.4), 10 s period, coefficients drawn with ``seed``; a
        closed-loop thesis experiment (``controller``, ``reference``); or
        ``"static-sawtooth"``, the static gravity-compensation validation of
        §3.5.1.6 -- set angles stepped in a sawtooth
        (:func:`~ppamsafety.diagnose.arm.synthesize.sawtooth_set_angles`), the set values of the static gravity
        compensation at the set angles computed with the *nominal* model
        (:func:`~ppamsafety.diagnose.arm.synthesize.gravity_compensation_set_values`, a feed-forward: no
        feedback), the plant simulated through every ramp and pause, and only
        the samples of the 1 s data windows recorded (columns t, q, qd, p, u,
        the muscle forces F1..F4 of the plant and the set angles q1_d, q2_d;
        ``t`` jumps between windows).
        Actuator (``kind="actuator"``, default ``"tensile"``): a tensile-tester
        record (:func:`ppamsafety.diagnose.bench.synthesize.synthesize_actuator`).
    effects : dict, optional
        ``{name: value}``; default none (the nominal plant).  Actuator effects:
        :data:`ppamsafety.diagnose.bench.synthesize.EFFECTS`.
    noise : {"arm", "table-3.2", "none"} or {"tester", "none"}, optional, keyword-only
        Arm default ``"arm"``: the noise variances the arm declares for its sensors (the
        thesis arm: Table 3.2); ``"table-3.2"``: the thesis' whatever the arm declares (a
        warning names both when they differ); the sawtooth's forces get
        :data:`~ppamsafety.diagnose.arm.synthesize.FORCE_NOISE_STD`
        (:func:`~ppamsafety.diagnose.arm.synthesize.noise_variances`).  Actuator default
        ``"tester"``.
    seed : int, keyword-only
        Seed of the excitation and of the noise.
    duration : float, optional, keyword-only
        Record length [s] (arm only): default 10 s (open and closed loop) or
        the whole sawtooth (about 105 s; a shorter duration keeps the levels
        whose data window ends before it, at least 3).
    dt : float, keyword-only
        Sample time [s] (the control period in closed loop; arm only).
    arm : ArmParameters, optional, keyword-only
        The nominal arm (default the thesis arm; arm only).
    controller : str, keyword-only
        Closed loop only: label of a thesis controller variant (Table 6.1
        order: ``"PID"``, ``"PSMC joint Ki=2 λ=0.4"``, ...,
        ``"PSMC task λ=1.5"``).
    reference : str, keyword-only
        Closed loop only: a thesis experiment of
        :data:`ppamsafety.experiments.catalog.EXPERIMENTS`.
    kind : {"arm", "actuator"}, keyword-only
        What is measured: the arm, or one actuator on a test bench.
    **tester
        Keyword options of
        :func:`~ppamsafety.diagnose.bench.synthesize.synthesize_actuator`
        (``protocol``, ``pressures``, ``cycles``, ``period``, ``eps_range``,
        ``sample_rate``, ``force_law``, ``l0``, ``position``, ``jitter``);
        only with ``kind="actuator"``.

    Returns
    -------
    MeasuredData
        An arm record's metadata carries ``[arm]`` (:func:`arm_record`): which arm it
        came from, so that a diagnosis against another arm can say so.
    """
    kind = check_choice("kind", kind, ("arm", "actuator"))
    try:
        return _synthesize(experiment, effects, noise=noise, seed=seed, duration=duration, dt=dt,
                           arm=arm, controller=controller, reference=reference, kind=kind,
                           **tester)
    except MeasuredDataError as exc:
        given = [f"effects {effects!r}"] if effects else []
        given += [f"{k} = {v!r}" for k, v in tester.items()]
        given += [f"duration = {duration!r}"] if duration is not None else []
        raise ValueError(f"synthesize: {', '.join(given) or 'these options'} give a record that "
                         f"is not physically possible: {exc}") from None


def _synthesize(experiment, effects, *, noise, seed, duration, dt, arm, controller, reference,
                kind, **tester):
    if kind == "actuator":
        if experiment is not None and experiment != "tensile":
            raise ValueError(f"experiment = {experiment!r} is not available for kind = "
                             f"'actuator'; allowed: 'tensile'")
        if arm is not None:
            raise ValueError("arm is not used with kind = 'actuator' (the force law is given "
                             "with force_law=...)")
        if duration is not None or dt != 1e-3:
            raise ValueError("duration and dt are arm options; for kind = 'actuator' use "
                             "cycles, period and sample_rate")
        if controller != DEFAULT_CONTROLLER or reference != DEFAULT_REFERENCE:
            raise ValueError("controller and reference are closed-loop arm options; they do "
                             "not apply to kind = 'actuator'")
        return synthesize_actuator(effects, noise="tester" if noise is None else noise,
                                   seed=seed, **tester)
    if tester:
        raise TypeError(f"synthesize() got option(s) {sorted(tester)} that exist only for "
                        f"kind = 'actuator'")
    data = synthesize_arm("open-loop" if experiment is None else experiment, effects,
                          noise="arm" if noise is None else noise, seed=seed,
                          duration=duration, dt=dt, arm=arm, controller=controller,
                          reference=reference)
    return MeasuredData({**data.meta, "arm": arm_record(arm)}, data.frame, source=data.source)


def effect_unit(kind: str, name: str):
    """The SI unit of a hidden effect ``name`` of :func:`synthesize` for a record ``kind``.

    Parameters
    ----------
    kind : {"arm", "actuator"}
        The record kind.
    name : str
        The effect's name.

    Returns
    -------
    str or None
        Its SI unit; ``"-"`` for a plain number (a factor); None for a name the kind does
        not know.
    """
    if kind == "actuator":
        return EFFECT_BOUNDS.get(name, (None, None, None))[2]
    if name in RELATIVE:
        return "-"
    if name in MEASUREMENT_BOUNDS:
        return MEASUREMENT_BOUNDS[name][2]
    if name == "valve_dead_time":
        return "s"
    if name == "valve_offset_delta":
        return "Pa"
    f = Effects.__dataclass_fields__.get(name)
    return None if f is None else (f.metadata.get("unit") or "-")


def check_effect(kind: str, name: str, value, *, arm=None) -> None:
    """Refuse a hidden effect :func:`synthesize` could not make, before simulating.

    Parameters
    ----------
    kind : {"arm", "actuator"}
        The record kind.
    name : str
        The effect's name.
    value : float, str or sequence
        Its value in SI units (:func:`effect_unit`).
    arm : ArmParameters, optional
        The nominal arm of an arm record (default: the thesis arm).

    Raises
    ------
    ValueError, TypeError
        Naming the effect, its value and what is allowed.
    """
    if kind == "actuator":
        _check_effects({name: value})
    else:
        plant_with(thesis_arm() if arm is None else arm, {name: value})


__all__ = ["synthesize", "arm_record", "effect_unit", "check_effect"]
