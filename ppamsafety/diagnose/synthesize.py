"""The generator of hidden-effect data (issue 10 item 6): rehearse the diagnosis.

:func:`synthesize` simulates an experiment on a plant that differs from the
nominal arm by the given effects, adds seeded measurement noise and returns a
record in the measured-data format (:class:`ppamsafety.data.MeasuredData`,
``.save(path)``).  The record carries **no hint** of what is hidden: the
metadata are the same for every effect (kind, experiment, sample rate, a
generic description and the seed), the set values are those the experimenter
computed with the *nominal* arm, and nothing else is written.

Effects (``NAME=VALUE``; vectors as comma-separated values, a single value
is used for every joint/valve):

* every field of :class:`ppamsafety.params.effects.Effects` (absolute values
  in SI units): ``payload_mass`` [kg], ``friction_coulomb`` [N m],
  ``friction_viscous`` [N m s/rad], ``valve_offset`` [Pa], ``valve_gain``
  [-], ``valve_time_constant`` [s], ``polytropic_n`` [-], and the fields
  other branches add (e.g. ``hysteresis_delta``);
* relative forms: ``friction_coulomb_factor``, ``friction_viscous_factor``,
  ``valve_gain_factor``, ``valve_time_constant_factor`` (x nominal),
  ``valve_offset_delta`` [Pa] (+ nominal);
* ``valve_dead_time`` [s]: the set values act this much later (realised as
  a delayed input, exact for an open-loop record);
* effects outside the diagnosis library, to test that it refuses to name
  them: ``geometry.<field>`` (e.g. ``geometry.L1`` [m], a wrong link
  length in the model), ``pressure_sensor_offset`` [Pa] (added to the
  recorded p, every muscle or a vector of 4).

Noise ``"table-3.2"``: white Gaussian noise with the Table 3.2 variances on
q (3.46e-6, 2.59e-6 rad^2) and qd (1.63e-4, 2.32e-5 rad^2/s^2) and 500 Pa
standard deviation on p (our choice, see
:data:`ppamsafety.identify.static.PRESSURE_NOISE_STD`); ``"none"``: exact
samples.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from .._validation import check_choice, check_int, check_range

EXPERIMENTS = ("open-loop",)
NOISES = ("table-3.2", "none")
RELATIVE = {"friction_coulomb_factor": ("friction_coulomb", 2), "friction_viscous_factor":
            ("friction_viscous", 2), "valve_gain_factor": ("valve_gain", 4),
            "valve_time_constant_factor": ("valve_time_constant", 4)}
_VECTOR_LEN = {"friction_coulomb": 2, "friction_viscous": 2, "valve_offset": 4, "valve_gain": 4,
               "valve_time_constant": 4, "hysteresis_delta": 4}


def _as_list(name, value, n):
    if isinstance(value, str):
        value = [float(v) for v in value.split(",")]
    if np.isscalar(value):
        value = [float(value)] * n
    value = [float(v) for v in value]
    if len(value) == 1:
        value = value * n
    if len(value) != n:
        raise ValueError(f"effect {name} needs 1 or {n} values, got {len(value)}: {value}")
    return tuple(value)


def _nominal_vector(arm, field):
    if field == "friction_coulomb":
        return np.array(arm.plant_base.coulomb)
    if field == "friction_viscous":
        return np.array(arm.plant_base.viscous)
    vs = arm.valves.valves
    return np.array({"valve_gain": [v.v2 for v in vs], "valve_offset": [v.v1 for v in vs],
                     "valve_time_constant": [v.time_constant for v in vs]}[field])


def plant_with(arm, effects: dict):
    """The plant (ArmParameters) and the extra hidden quantities for ``effects``.

    Parameters
    ----------
    arm : ArmParameters
        Nominal arm.
    effects : dict
        ``{name: value}`` (see the module docstring).

    Returns
    -------
    plant : ArmParameters
    dead_time : float
        [s]
    sensor_offset : numpy.ndarray, shape (4,)
        [Pa]
    """
    from ..params.effects import Effects

    if not isinstance(effects, dict):
        raise TypeError(f"effects must be a dict {{name: value}}, got {type(effects).__name__}")
    fx, geo = {}, {}
    dead, offset = 0.0, np.zeros(4)
    fields = Effects.__dataclass_fields__
    for name, value in effects.items():
        if name in RELATIVE:
            f, n = RELATIVE[name]
            fx[f] = tuple(_nominal_vector(arm, f) * np.array(_as_list(name, value, n)))
        elif name == "valve_offset_delta":
            fx["valve_offset"] = tuple(_nominal_vector(arm, "valve_offset")
                                       + np.array(_as_list(name, value, 4)))
        elif name == "valve_dead_time":
            dead = check_range("effect valve_dead_time", float(value), 0.0, 1.0, unit="s")
        elif name == "pressure_sensor_offset":
            offset = np.array(_as_list(name, value, 4))
        elif name.startswith("geometry."):
            geo[name.split(".", 1)[1]] = float(value)
        elif name in fields:
            fx[name] = _as_list(name, value, _VECTOR_LEN[name]) if name in _VECTOR_LEN else (
                float(value) if not isinstance(value, (list, tuple)) else tuple(value))
        else:
            raise ValueError(f"unknown effect {name!r}; allowed: Effects fields "
                             f"{sorted(fields)}, {sorted(RELATIVE)}, valve_offset_delta, "
                             f"valve_dead_time, pressure_sensor_offset, geometry.<field>")
    plant = arm
    if geo:
        plant = plant.replace(geometry=plant.geometry.replace(**geo))
    if fx:
        plant = plant.replace(effects=Effects(**fx))
    return plant, dead, offset


def synthesize(experiment: str = "open-loop", effects=None, *, noise: str = "table-3.2",
               seed: int = 0, duration: float = 10.0, dt: float = 1e-3, arm=None):
    """A record of ``experiment`` on a plant with hidden ``effects`` (module docstring).

    Parameters
    ----------
    experiment : {"open-loop"}
        Open-loop Fourier excitation of the valves (§3.5.2.4), 10 s period,
        coefficients drawn with ``seed``.
    effects : dict, optional
        ``{name: value}``; default none (the nominal plant).
    noise : {"table-3.2", "none"}, keyword-only
    seed : int, keyword-only
        Seed of the excitation and of the noise.
    duration : float, keyword-only
        Record length [s].
    dt : float, keyword-only
        Sample time [s].
    arm : ArmParameters, optional, keyword-only
        The nominal arm (default the thesis arm).

    Returns
    -------
    MeasuredData
    """
    from ..data.measured import MeasuredData
    from ..data.synthetic import VELOCITY_NOISE_VARIANCES, _arm, default_excitation
    from ..identify.excitation import equilibrium_for
    from ..identify.static import ANGLE_NOISE_VARIANCES, PRESSURE_NOISE_STD
    from ..plant.model import rest_state, simulate
    from .residuals import delayed

    experiment = check_choice("experiment", experiment, EXPERIMENTS)
    noise = check_choice("noise", noise, NOISES)
    seed = check_int("seed", seed, 0)
    duration = check_range("duration", duration, 0.5, 3600.0, unit="s")
    dt = check_range("dt", dt, 1e-4, 0.01, unit="s")
    arm = _arm(arm)
    plant, dead, offset = plant_with(arm, {} if effects is None else effects)
    exc = default_excitation(arm, seed=seed)
    q0 = equilibrium_for(exc.delta_p([0.0])[0], arm)
    x0, _ = rest_state(q0, plant)
    n = int(round(duration / dt))
    t = np.arange(n) * dt
    u = exc.set_values(t, arm)
    shift = int(round(dead / dt))
    substeps = max(2, int(math.ceil(dt / min(1e-3, 0.5 * min(
        v.time_constant for v in arm.valves.valves)))))
    X = simulate(plant, x0, delayed(u, shift), dt=dt, substeps=substeps)[:n]
    q, qd, p = X[:, :2].copy(), X[:, 2:4].copy(), X[:, 4:8].copy() + offset
    if noise == "table-3.2":
        rng = np.random.default_rng(seed)
        q += rng.normal(size=q.shape) * np.sqrt(ANGLE_NOISE_VARIANCES)
        qd += rng.normal(size=qd.shape) * np.sqrt(VELOCITY_NOISE_VARIANCES)
        p += rng.normal(size=p.shape) * PRESSURE_NOISE_STD
    cols = {"t": t, "q1": q[:, 0], "q2": q[:, 1], "qd1": qd[:, 0], "qd2": qd[:, 1]}
    for i in range(4):
        cols[f"p{i + 1}"] = p[:, i]
    for i in range(4):
        cols[f"u{i + 1}"] = u[:, i]
    meta = {"kind": "arm", "experiment": "open-loop", "sample_rate": 1.0 / dt,
            "description": "synthetic open-loop Fourier excitation record",
            "source": f"ppamsafety synthesize (seed {seed}, noise {noise})"}
    return MeasuredData(meta, pd.DataFrame(cols), source="synthesize")


__all__ = ["synthesize", "plant_with", "EXPERIMENTS", "NOISES"]
