"""The generator of hidden-effect data: rehearse the diagnosis.

:func:`synthesize` simulates an experiment on a plant that differs from the
nominal arm by the given effects, adds seeded measurement noise and returns a
record in the measured-data format (:class:`ppamsafety.data.MeasuredData`,
``.save(path)``).  The record carries **no hint** of what is hidden: the
metadata are the same for every effect (kind, experiment, sample rate, a
generic description and the seed), the set values are those the experimenter
computed with the *nominal* arm, and nothing else is written.

Effects (``NAME=VALUE``; vectors as comma-separated values, a single value
is used for every joint/valve) act on top of the effects the arm declares
(its ``[effects]``): a hidden value of a field the arm declares replaces the
declared one (a hidden change of it), a relative form multiplies or shifts
the arm's value with its declared effects, and a hidden ``valve_dead_time``
replaces a declared dead time:

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
* sensor faults (in the diagnosis library, :mod:`.candidates`):
  ``pressure_sensor_offset`` [Pa] and ``pressure_sensor_gain`` [-] (the
  recorded ``p_m = (1 + g) p + o``, every muscle or a vector of 4; offsets at
  most 1 bar), ``encoder_offset`` [rad] (``q_m = q + o``, per joint);
* effects outside the diagnosis library, to test that it refuses to name
  them: ``geometry.<field>`` (e.g. ``geometry.L1`` [m], a wrong link
  length in the model), ``link.<field>`` (a field of
  :class:`~ppamsafety.params.inertia.LinkInertia`: a link mass, centre of
  gravity or inertia the model has wrong), ``encoder_gain`` [-] (``q_m = (1 +
  g) q``), ``velocity_sensor_gain`` [-] (``qd_m = (1 + g) qd``),
  ``encoder_backlash`` [rad] (play between joint and encoder: the reading
  follows the joint only once the play is taken up), ``valve_nonlinearity``
  [-] (the valves respond to ``u + k (u - 1.5 bar)^2 / 3 bar`` instead of the
  logged ``u``), ``noise_correlation_time`` [s] (the measurement noise is
  coloured: first-order autoregressive with this correlation time and the
  same variance), ``outlier_rate`` [-] (that fraction of samples of one
  channel each carry a spike of 10-50 noise levels).

Noise ``"arm"`` (the default): white Gaussian noise with the variances the arm declares for
its sensors (``[sensors] angle_noise_variance``, ``velocity_noise_variance``; the thesis arm:
Table 3.2, 3.46e-6, 2.59e-6 rad^2 on q and 1.63e-4, 2.32e-5 rad^2/s^2 on qd) and 500 Pa
standard deviation on p (our choice, see :data:`ppamsafety.identify.static.PRESSURE_NOISE_STD`;
an arm file declares no pressure-sensor noise); ``"table-3.2"``: the thesis' Table 3.2
variances whatever the arm declares (a deliberate choice for another arm: a warning names
both); ``"none"``: exact samples.

Experiments
-----------
``"open-loop"``
    The Fourier excitation of the valves (§3.5.2.4), coefficients drawn with
    the seed; the set values are computed in advance, so a valve dead time
    is realised exactly as a delayed input.
``"closed-loop"``
    A thesis experiment of the catalogue (``reference``: ``"step"``,
    ``"switch"``, ``"circle5"``, ``"circle10"``, ``"circle20"``) under a
    thesis controller variant (``controller``: a label of
    :func:`ppamsafety.experiments.catalog.thesis_variants`, e.g.
    ``"PSMC joint Ki=2 λ=0.4"``), run by the compiled closed loop
    (:func:`ppamsafety.experiments.closed_loop.run_batch`) on the plant
    with the hidden effects while the controller keeps the nominal model.
    The record holds what the controller saw and sent: the angles and
    velocities it measured (exact sensors plus the chosen noise, drawn by
    :class:`~ppamsafety.control.sensors.SensorConfig` with the seed, so the
    measurement noise is *fed back* into the set values, as on the real
    arm), the pressures (+ 500 Pa noise, an independent seeded stream) and
    the set values u1..u4 the controller sent (before any valve dead time,
    which here is the plant effect ``Effects.valve_dead_time`` inside the
    loop).  Metadata: ``reference`` and ``[controller] variant`` as
    ``docs/measured_data.md`` specifies -- the same whatever is hidden.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd
from scipy.signal import lfilter

from ..._validation import (InvalidTypeError, check_bool, check_choice, check_numbers, check_range,
                            check_seed, check_size)
from ...control.sensors import SensorConfig
from ...data.measured import MeasuredData
from ...data.synthetic import VELOCITY_NOISE_VARIANCES, _arm, default_excitation
from ...experiments.case import ExperimentCase
from ...experiments.catalog import EXPERIMENTS as NAMED, thesis_reference, thesis_variants
from ...experiments.closed_loop import run_batch
from ...experiments.trajectories import (SAWTOOTH_Q1_DEG, SAWTOOTH_Q2_DEG,  # noqa: F401
                                         experiment_references)
from ...identify.excitation import equilibrium_for
from ...identify.static import ANGLE_NOISE_VARIANCES, PRESSURE_NOISE_STD
from ...params.effects import EffectKind, Effects
from ...plant.geometry import contractions
from ...plant.model import hysteresis_factors, rest_state, simulate
from ...plant.muscle import muscle_force
from ...plant.pneumatics import delta_p_pressures, gravity_compensation, valve_set_values
from .residuals import delayed

EXPERIMENTS = ("open-loop", "closed-loop", "static-sawtooth")
#: Defaults of the closed-loop record: controller variant label and catalogue reference.
DEFAULT_CONTROLLER = "PSMC joint Ki=2 λ=0.4"
DEFAULT_REFERENCE = "circle10"
#: Teeth of the default sawtooth.
SAWTOOTH_TEETH = 2
#: Gradual change, pause and data window per level [s] (§3.5.1.6: "a 3 second pause ...
#: then data was taken during 1 second"; the 1 s ramp is our choice).
SAWTOOTH_RAMP_S, SAWTOOTH_SETTLE_S, SAWTOOTH_WINDOW_S = 1.0, 3.0, 1.0
#: Standard deviation of the synthetic muscle-force noise [N] (our choice; the thesis gives
#: no force-sensor noise).
FORCE_NOISE_STD = 2.0
NOISES = ("arm", "table-3.2", "none")
#: Relative effect forms: ``<field>_factor`` multiplies the nominal value of the field (the
#: magnitude axes that declare one, ``Effects.axes()``).
RELATIVE = {a.name: (a.name[:-len("_factor")], Effects.length(a.name[:-len("_factor")]))
            for a in Effects.axes() if a.name.endswith("_factor")}
#: Memory per simulated sample while a record is built (states, set values, the plant's
#: log and the record's columns) [bytes], an upper estimate.
SAMPLE_BYTES = 500
#: Length of the whole default sawtooth [s] (an upper bound, for the size check).
SAWTOOTH_SECONDS_MAX = 200.0
#: Largest |pressure_sensor_offset| [Pa]: one bar is no calibration error but a broken sensor.
PRESSURE_OFFSET_MAX = 1.0e5
#: Number of values of each vector effect (``Effects.length``).
_VECTOR_LEN = {n: Effects.length(n) for n in Effects.names() if Effects.length(n) > 1}


def _as_list(name, value, n):
    """``value`` (a number, a comma-separated text or a sequence) as ``n`` floats; a single
    value is used for every joint/valve.  Errors name the effect."""
    vals = check_numbers(f"effect {name}", value, (1, n) if n > 1 else (1,))
    return tuple(vals * n) if len(vals) == 1 else tuple(vals)


def _option(name, value):
    """An option field of :class:`Effects` (``hysteresis_initial``, ``..._exact_stages``)."""
    default = Effects.__dataclass_fields__[name].default
    if isinstance(default, bool):
        if isinstance(value, str) and value.strip().lower() in ("true", "false"):
            return value.strip().lower() == "true"
        return check_bool(f"effect {name}", value)
    return value


def plant_vector(arm, field) -> np.ndarray:
    """The plant's value of a vector effect field: the arm's declared effect, else its
    nominal parameter (a relative effect form multiplies or shifts it).

    Parameters
    ----------
    arm : ArmParameters
    field : str
        ``"friction_coulomb"``, ``"friction_viscous"``, ``"valve_offset"``, ``"valve_gain"``
        or ``"valve_time_constant"``.
    """
    declared = getattr(arm.effects, field)
    if declared is not None:
        return np.array(declared, dtype=float)
    if field == "friction_coulomb":
        return np.array(arm.plant_base.coulomb)
    if field == "friction_viscous":
        return np.array(arm.plant_base.viscous)
    vs = arm.valves.valves
    return np.array({"valve_gain": [v.v2 for v in vs], "valve_offset": [v.v1 for v in vs],
                     "valve_time_constant": [v.time_constant for v in vs]}[field])


#: Names of the measurement-side effects (sensor faults and recording imperfections) and the
#: number of values each takes.
MEASUREMENT_EFFECTS = {"pressure_sensor_offset": 4, "pressure_sensor_gain": 4,
                       "encoder_offset": 2, "encoder_gain": 2, "velocity_sensor_gain": 2,
                       "encoder_backlash": 2, "valve_nonlinearity": 1,
                       "noise_correlation_time": 1, "outlier_rate": 1}
#: Bounds of the measurement-side effects (what a sensor can plausibly do and still be a
#: sensor), name -> (lo, hi, unit).
MEASUREMENT_BOUNDS = {"pressure_sensor_offset": (-PRESSURE_OFFSET_MAX, PRESSURE_OFFSET_MAX, "Pa"),
                      "pressure_sensor_gain": (-0.5, 0.5, "-"),
                      "encoder_offset": (-0.5, 0.5, "rad"),
                      "encoder_gain": (-0.2, 0.2, "-"),
                      "velocity_sensor_gain": (-0.5, 0.5, "-"),
                      "encoder_backlash": (0.0, 0.05, "rad"),
                      "valve_nonlinearity": (-0.5, 0.5, "-"),
                      "noise_correlation_time": (0.0, 1.0, "s"),
                      "outlier_rate": (0.0, 0.05, "-")}
#: Set value about which :data:`MEASUREMENT_EFFECTS` ``valve_nonlinearity`` bends the valve
#: response, and its scale [Pa].
VALVE_NONLINEARITY_CENTRE, VALVE_NONLINEARITY_SCALE = 1.5e5, 3.0e5


@dataclass(frozen=True)
class Measurement:
    """How the recorded signals differ from the plant's (sensor faults, recording imperfections).

    Attributes
    ----------
    pressure_sensor_offset : tuple of 4 float
        [Pa]: ``p_m = (1 + g) p + o``.
    pressure_sensor_gain : tuple of 4 float
        g [-].
    encoder_offset : tuple of 2 float
        [rad]: ``q_m = (1 + g_q) q + o_q``.
    encoder_gain : tuple of 2 float
        g_q [-].
    velocity_sensor_gain : tuple of 2 float
        [-]: ``qd_m = (1 + g_v) qd``.
    encoder_backlash : tuple of 2 float
        Play between joint and encoder [rad].
    valve_nonlinearity : float
        k [-]: the valves receive ``u + k (u - 1.5 bar)^2 / 3 bar``.
    noise_correlation_time : float
        Correlation time of the AR(1) measurement noise [s] (0: white).
    outlier_rate : float
        Fraction of samples with a spike of 10-50 noise levels [-].
    """

    pressure_sensor_offset: tuple = (0.0,) * 4
    pressure_sensor_gain: tuple = (0.0,) * 4
    encoder_offset: tuple = (0.0,) * 2
    encoder_gain: tuple = (0.0,) * 2
    velocity_sensor_gain: tuple = (0.0,) * 2
    encoder_backlash: tuple = (0.0,) * 2
    valve_nonlinearity: float = 0.0
    noise_correlation_time: float = 0.0
    outlier_rate: float = 0.0

    def sensors(self, q, qd, p):
        """Sensor faults applied to true angles, velocities, pressures (copies returned).

        Parameters
        ----------
        q, qd : array_like, shape (N, 2)
            True angles [rad] and velocities [rad/s] (in time order: backlash has memory).
        p : array_like, shape (N, 4)
            True gauge pressures [Pa].
        """
        q = _backlash(np.asarray(q, float), np.asarray(self.encoder_backlash))
        q = q * (1.0 + np.asarray(self.encoder_gain)) + np.asarray(self.encoder_offset)
        qd = np.asarray(qd, float) * (1.0 + np.asarray(self.velocity_sensor_gain))
        p = (np.asarray(p, float) * (1.0 + np.asarray(self.pressure_sensor_gain))
             + np.asarray(self.pressure_sensor_offset))
        return q, qd, p

    def valve_input(self, u) -> np.ndarray:
        """What the valves receive when ``u`` is logged (the valve nonlinearity).

        Parameters
        ----------
        u : numpy.ndarray
            Logged set values [Pa].
        """
        if self.valve_nonlinearity == 0.0:
            return u
        return u + self.valve_nonlinearity * (u - VALVE_NONLINEARITY_CENTRE) ** 2 \
            / VALVE_NONLINEARITY_SCALE

    def noise(self, shape, std, dt, rng) -> np.ndarray:
        """Measurement noise of standard deviation ``std`` (white, or AR(1) coloured).

        Parameters
        ----------
        shape : tuple
            (samples, channels).
        std : array_like
            Standard deviation per channel.
        dt : float
            Sample time [s].
        rng : numpy.random.Generator
        """
        w = rng.normal(size=shape) * np.asarray(std)
        tau = self.noise_correlation_time
        if tau <= 0.0 or w.shape[0] < 2:
            return w
        a = math.exp(-dt / tau)
        return lfilter([math.sqrt(1.0 - a * a)], [1.0, -a], w, axis=0)

    def outliers(self, x, std, rng) -> np.ndarray:
        """``x`` with spikes of 10-50 noise levels on ``outlier_rate`` of the samples.

        Parameters
        ----------
        x : array_like, shape (N, k)
        std : array_like, shape (k,)
            Noise level per channel.
        rng : numpy.random.Generator
        """
        if self.outlier_rate <= 0.0:
            return x
        x = np.array(x, dtype=float)
        n, k = x.shape
        m = rng.random(n) < self.outlier_rate
        ch = rng.integers(0, k, size=n)
        amp = rng.uniform(10.0, 50.0, size=n) * rng.choice([-1.0, 1.0], size=n)
        idx = np.nonzero(m)[0]
        x[idx, ch[idx]] += amp[idx] * np.asarray(std)[ch[idx]]
        return x


def _backlash(q, play):
    """Encoder readings of a joint with play ``play`` [rad] per joint (a dead band of that width
    around the reading: the reading moves only when the joint pushes it)."""
    if not np.any(play > 0):
        return q
    out = np.empty_like(q)
    r = q[0].copy()
    half = 0.5 * play
    for k in range(q.shape[0]):
        r = np.where(q[k] > r + half, q[k] - half, np.where(q[k] < r - half, q[k] + half, r))
        out[k] = r
    return out


def hidden_effects(arm, effects: dict) -> tuple:
    """The plant, the valve dead time and the :class:`Measurement` of ``effects``.

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
    measurement : Measurement
    """
    if not isinstance(effects, dict):
        raise TypeError(f"effects must be a dict {{name: value}}, got {type(effects).__name__}")
    plant_fx, meas = {}, {}
    for name, value in effects.items():
        if isinstance(name, str) and name in MEASUREMENT_EFFECTS:
            lo, hi, unit = MEASUREMENT_BOUNDS[name]
            n = MEASUREMENT_EFFECTS[name]
            vals = _as_list(name, value, n)
            vals = tuple(check_range(f"effect {name}" + (f"[{i}]" if n > 1 else ""), v, lo, hi,
                                     unit=unit) for i, v in enumerate(vals))
            meas[name] = vals if n > 1 else vals[0]
        else:
            plant_fx[name] = value
    plant, dead, _ = plant_with(arm, plant_fx)
    return plant, dead, Measurement(**meas)


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
    if not isinstance(effects, dict):
        raise TypeError(f"effects must be a dict {{name: value}}, got {type(effects).__name__}")
    fx, geo, links = {}, {}, {}
    dead, offset = 0.0, np.zeros(4)
    fields = Effects.__dataclass_fields__
    geo_fields = tuple(arm.geometry.__dataclass_fields__)
    link_fields = tuple(arm.links.__dataclass_fields__)
    for name, value in effects.items():
        if not isinstance(name, str):
            raise InvalidTypeError(f"effects: an effect name must be a str, got {name!r}")
        if name in RELATIVE:
            f, n = RELATIVE[name]
            fx[f] = tuple(plant_vector(arm, f) * np.array(_as_list(name, value, n)))
        elif name == "valve_offset_delta":
            fx["valve_offset"] = tuple(plant_vector(arm, "valve_offset")
                                       + np.array(_as_list(name, value, 4)))
        elif name == "valve_dead_time":
            dead = check_range("effect valve_dead_time", _as_list(name, value, 1)[0], 0.0, 1.0,
                               unit="s")
            fx["valve_dead_time"] = None        # the hidden one replaces what the arm declares
        elif name == "pressure_sensor_offset":
            offset = np.array([check_range(f"effect pressure_sensor_offset[{i}]", v,
                                           -PRESSURE_OFFSET_MAX, PRESSURE_OFFSET_MAX, unit="Pa")
                               for i, v in enumerate(_as_list(name, value, 4))])
        elif name.startswith("geometry."):
            g = name.split(".", 1)[1]
            if g not in geo_fields:
                raise ValueError(f"unknown effect {name!r}: {g!r} is not a field of the arm "
                                 f"geometry; allowed: geometry.<{'|'.join(geo_fields)}>")
            geo[g] = _as_list(name, value, 1)[0]
        elif name.startswith("link."):
            g = name.split(".", 1)[1]
            if g not in link_fields:
                raise ValueError(f"unknown effect {name!r}: {g!r} is not a field of the link "
                                 f"inertias; allowed: link.<{'|'.join(link_fields)}>")
            vals = _as_list(name, value, 2 if g in ("coulomb", "viscous") else 1)
            links[g] = vals if g in ("coulomb", "viscous") else vals[0]
        elif name in fields and Effects.kind(name) is EffectKind.OPTION:
            fx[name] = _option(name, value)
        elif name in fields:
            fx[name] = _as_list(name, value, _VECTOR_LEN[name]) if name in _VECTOR_LEN else (
                _as_list(name, value, 1)[0])
        else:
            raise ValueError(f"unknown effect {name!r}; allowed: Effects fields "
                             f"{sorted(fields)}, {sorted(RELATIVE)}, valve_offset_delta, "
                             f"valve_dead_time, {', '.join(MEASUREMENT_EFFECTS)}, "
                             f"geometry.<field>, link.<field>")
    plant = arm
    try:
        if geo:
            plant = plant.replace(geometry=plant.geometry.replace(**geo))
        if links:
            plant = plant.replace(links=replace(plant.links, **links))
        if fx:
            # on top of the arm's declared effects (a hidden value of a declared effect
            # replaces it)
            plant = plant.replace(effects=replace(plant.effects, **fx))
    except (TypeError, ValueError) as exc:   # the parameter sets' own ranges: name the effect
        given = ", ".join(f"{k}={v!r}" for k, v in effects.items())
        raise type(exc)(f"effect(s) {given}: {exc}") from None
    return plant, dead, offset


def sawtooth_set_angles(levels=None, *, dt: float = 1e-3, ramp: float = SAWTOOTH_RAMP_S,
                        settle: float = SAWTOOTH_SETTLE_S, window: float = SAWTOOTH_WINDOW_S):
    """Set angles of the static sawtooth (thesis §3.5.1.6) and its data windows.

    The first level is held for ``settle + window``; every further level is
    reached by a raised-cosine ramp of ``ramp`` seconds and held for
    ``settle + window``; data are taken in the last ``window`` seconds.

    Parameters
    ----------
    levels : array_like, shape (m, 2), optional
        Set angles per level [rad], m >= 3; default :data:`SAWTOOTH_TEETH`
        teeth of :data:`SAWTOOTH_Q1_DEG` / :data:`SAWTOOTH_Q2_DEG` (the thesis arm's; another
        arm's: ``experiment_references(arm).sawtooth_levels(SAWTOOTH_TEETH)``), closed at
        the start level.
    dt : float, keyword-only
        Sample time [s].
    ramp, settle, window : float, keyword-only
        Durations [s] (> 0).

    Returns
    -------
    t : numpy.ndarray, shape (N,)
        Time [s].
    q_d : numpy.ndarray, shape (N, 2)
        Set angles [rad].
    windows : numpy.ndarray of int, shape (m, 2)
        First and one-past-last sample of each data window.
    """
    if levels is None:
        q1 = SAWTOOTH_Q1_DEG * SAWTOOTH_TEETH + SAWTOOTH_Q1_DEG[:1]
        q2 = SAWTOOTH_Q2_DEG * SAWTOOTH_TEETH + SAWTOOTH_Q2_DEG[:1]
        levels = np.radians(np.stack([q1, q2], 1))
    lv = np.asarray(levels, dtype=float)
    if lv.ndim != 2 or lv.shape[1] != 2 or lv.shape[0] < 3 or not np.all(np.isfinite(lv)):
        raise ValueError(f"levels must be finite with shape (m >= 3, 2) [rad], got shape "
                         f"{lv.shape}")
    dt = check_range("dt", dt, 1e-4, 0.01, unit="s")
    for name, v in (("ramp", ramp), ("settle", settle), ("window", window)):
        check_range(name, v, 0.0, 600.0, lo_open=True, unit="s")
    hold = settle + window
    m = lv.shape[0]
    starts = np.array([0.0] + [hold + i * (ramp + hold) for i in range(m - 1)])
    n = int(round((hold + (m - 1) * (ramp + hold)) / dt))
    t = np.arange(n) * dt
    q = np.tile(lv[0], (n, 1))
    for i in range(1, m):
        s = np.clip((t - starts[i]) / ramp, 0.0, 1.0)
        on = t >= starts[i]
        q[on] = lv[i - 1] + (0.5 * (1 - np.cos(np.pi * s[on])))[:, None] * (lv[i] - lv[i - 1])
    ends = starts + np.where(np.arange(m) > 0, ramp, 0.0) + hold
    k1 = np.minimum(np.round(ends / dt).astype(int), n)
    k0 = k1 - int(round(window / dt))
    return t, q, np.stack([k0, k1], 1)


def gravity_compensation_set_values(q_d, arm) -> np.ndarray:
    """Valve set values of the static gravity compensation at the set angles (§3.5.1.5) [Pa].

    Delta p_gc of (3.18)-(3.19) with the identified gravity terms (Table 3.1),
    the pressures p_m +- Delta p (clipped to [0, p_max]) and the inverse of
    the static valve model (3.12): what the experimenter computes with the
    nominal model, whatever the plant hides.

    Parameters
    ----------
    q_d : array_like, shape (N, 2)
        Set angles [rad].
    arm : ArmParameters
        The nominal model.

    Returns
    -------
    numpy.ndarray, shape (N, 4)
    """
    dp = gravity_compensation(q_d, arm)
    return valve_set_values(delta_p_pressures(dp, arm), arm)


def _logged_for(meas, u):
    """The set values to log so that the valves, receiving ``u``, see
    ``meas.valve_input(logged)`` = u (inverse of the quadratic distortion)."""
    k = meas.valve_nonlinearity
    if k == 0.0:
        return u
    c, s = VALVE_NONLINEARITY_CENTRE, VALVE_NONLINEARITY_SCALE
    # solve x + k (x - c)^2 / s = u for the root near u
    a = k / s
    d = u - c
    y = (-1.0 + np.sqrt(np.maximum(1.0 + 4.0 * a * d, 0.0))) / (2.0 * a)
    return c + y


def _sawtooth(plant, arm, noise, seed, duration, dt, dead, meas):
    """Samples of the data windows of the static sawtooth (see :func:`synthesize`)."""
    # the thesis arm's levels, or the same fractions of another arm's working area
    t, qd_set, windows = sawtooth_set_angles(
        experiment_references(arm).sawtooth_levels(SAWTOOTH_TEETH), dt=dt)
    if duration is not None:
        keep = int(np.sum(t[windows[:, 1] - 1] < duration))
        if keep < 3:
            raise ValueError(f"duration = {duration} s holds {keep} sawtooth levels; at least 3 "
                             f"are needed (one level takes "
                             f"{SAWTOOTH_RAMP_S + SAWTOOTH_SETTLE_S + SAWTOOTH_WINDOW_S} s)")
        windows = windows[:keep]
        t, qd_set = t[:windows[-1, 1]], qd_set[:windows[-1, 1]]
    u = gravity_compensation_set_values(qd_set, arm)
    x0, _ = rest_state(qd_set[0], plant)
    shift = int(round(dead / dt))
    substeps = max(2, int(math.ceil(dt / min(1e-3, 0.5 * min(
        v.time_constant for v in arm.valves.valves)))))
    X = simulate(plant, x0, delayed(meas.valve_input(u), shift), dt=dt,
                 substeps=substeps)[:t.size]
    if plant.effects.hysteresis_delta is not None:
        eps, fac = hysteresis_factors(X, plant)
    else:
        eps, fac = contractions(X[:, :2], arm), np.ones((t.size, 4))
    F = np.stack([muscle_force(k + 1, eps[:, k], X[:, 4 + k], arm) for k in range(4)], 1) * fac
    idx = np.concatenate([np.arange(a, b) for a, b in windows])
    # sensor faults (backlash needs the whole history) on every sample, then the windows
    qa, qda, pa = meas.sensors(X[:, :2], X[:, 2:4], X[:, 4:8])
    q, qd, p, F = qa[idx].copy(), qda[idx].copy(), pa[idx].copy(), F[idx]
    std = noise_std(arm, noise)
    if std is not None:
        rng = np.random.default_rng(seed)
        q += meas.noise(q.shape, std[0], dt, rng)
        qd += meas.noise(qd.shape, std[1], dt, rng)
        p += meas.noise(p.shape, PRESSURE_NOISE_STD, dt, rng)
        F += rng.normal(size=F.shape) * FORCE_NOISE_STD
        if meas.outlier_rate > 0.0:
            x = meas.outliers(np.concatenate([q, qd, p], axis=1), np.concatenate([
                std[0], std[1], np.full(4, PRESSURE_NOISE_STD)]),
                np.random.default_rng([seed, 7]))
            q, qd, p = x[:, :2], x[:, 2:4], x[:, 4:8]
    cols = {"t": t[idx], "q1": q[:, 0], "q2": q[:, 1], "qd1": qd[:, 0], "qd2": qd[:, 1]}
    for name, arr in (("p", p), ("u", u[idx]), ("F", F)):
        for i in range(4):
            cols[f"{name}{i + 1}"] = arr[:, i]
    cols["q1_d"], cols["q2_d"] = qd_set[idx, 0], qd_set[idx, 1]
    meta = {"kind": "arm", "experiment": "static-sawtooth",
            "description": "synthetic static gravity-compensation sawtooth (thesis 3.5.1.6): "
                           f"{len(windows)} rest points, {SAWTOOTH_WINDOW_S:g} s of data each",
            "source": f"ppamsafety synthesize (seed {seed}, noise {noise})"}
    return meta, pd.DataFrame(cols)


def noise_variances(arm, noise: str, *, warn: bool = False):
    """Variances of the measurement noise of q [rad^2] and qd [rad^2/s^2] of a record.

    Parameters
    ----------
    arm : ArmParameters
        The nominal arm (its ``sensors``).
    noise : {"arm", "table-3.2", "none"}
        The arm's declared sensor noise, the thesis' Table 3.2 or none.
    warn : bool, keyword-only
        Warn (``UserWarning``) when ``"table-3.2"`` differs from what the arm declares.

    Returns
    -------
    tuple of 2 tuples of 2 float, or None
        (q, qd) variances; None for ``"none"``.
    """
    noise = check_choice("noise", noise, NOISES)
    if noise == "none":
        return None
    hw = arm.sensors
    if noise == "table-3.2":
        if warn and (tuple(hw.angle_noise_variances), tuple(hw.velocity_noise_variances)) != (
                tuple(ANGLE_NOISE_VARIANCES), tuple(VELOCITY_NOISE_VARIANCES)):
            warnings.warn(
                f"noise = 'table-3.2': the thesis' Table 3.2 variances (q "
                f"{list(ANGLE_NOISE_VARIANCES)} rad^2, qd {list(VELOCITY_NOISE_VARIANCES)} "
                f"rad^2/s^2), not the arm's declared [sensors] (q "
                f"{list(hw.angle_noise_variances)} rad^2, qd "
                f"{list(hw.velocity_noise_variances)} rad^2/s^2); noise = 'arm' (the default) "
                f"uses the arm's", UserWarning, stacklevel=4)
        return tuple(ANGLE_NOISE_VARIANCES), tuple(VELOCITY_NOISE_VARIANCES)
    return tuple(hw.angle_noise_variances), tuple(hw.velocity_noise_variances)


def noise_std(arm, noise: str):
    """(q [rad], qd [rad/s]) standard deviations of :func:`noise_variances`, or None.

    Parameters
    ----------
    arm : ArmParameters
    noise : {"arm", "table-3.2", "none"}
    """
    var = noise_variances(arm, noise)
    return None if var is None else (np.sqrt(var[0]), np.sqrt(var[1]))


def synthesize_arm(experiment: str = "open-loop", effects=None, *, noise: str = "arm",
                   seed: int = 0, duration: float | None = None, dt: float = 1e-3, arm=None,
                   controller: str = DEFAULT_CONTROLLER, reference: str = DEFAULT_REFERENCE):
    """An arm record of ``experiment`` on a plant with hidden ``effects``.

    The arm part of :func:`ppamsafety.diagnose.synthesize` (module docstring).

    Parameters
    ----------
    experiment : {"open-loop", "closed-loop", "static-sawtooth"}
        Open-loop Fourier excitation of the valves (§3.5.2.4), 10 s period,
        coefficients drawn with ``seed``; a closed-loop thesis experiment
        (``controller``, ``reference``); or the static gravity-compensation
        validation of §3.5.1.6 (:func:`sawtooth_set_angles`,
        :func:`gravity_compensation_set_values`; only the samples of the 1 s data
        windows are recorded, ``t`` jumps between windows).
    effects : dict, optional
        ``{name: value}`` of hidden plant effects; default none (the nominal plant).
    noise : {"arm", "table-3.2", "none"}, keyword-only
        Measurement noise (:func:`noise_variances`; default the arm's declared sensor noise; the
        sawtooth's forces then get :data:`FORCE_NOISE_STD`).
    seed : int, keyword-only
        Seed of the excitation and of the noise.
    duration : float, optional, keyword-only
        Record length [s]: default 10 s (open and closed loop) or the whole
        sawtooth (about 105 s; a shorter duration keeps the levels whose data
        window ends before it, at least 3).
    dt : float, keyword-only
        Sample time [s] (the control period in closed loop).
    arm : ArmParameters, optional, keyword-only
        The nominal arm (default the thesis arm).
    controller : str, keyword-only
        Closed loop only: label of a thesis controller variant.
    reference : str, keyword-only
        Closed loop only: a thesis experiment of
        :data:`ppamsafety.experiments.catalog.EXPERIMENTS`.

    Returns
    -------
    MeasuredData
    """
    experiment = check_choice("experiment", experiment, EXPERIMENTS)
    noise = check_choice("noise", noise, NOISES)
    seed = check_seed("seed", seed)
    noise_variances(_arm(arm), noise, warn=True)
    if duration is not None:
        duration = check_range("duration", duration, 0.5, 3600.0, unit="s")
    dt = check_range("dt", dt, 1e-4, 0.01, unit="s")
    n = (SAWTOOTH_SECONDS_MAX if duration is None and experiment == "static-sawtooth" else
         10.0 if duration is None else duration) / dt
    check_size(f"duration = {duration if duration is not None else 'default'} s at dt = "
               f"{dt:g} s ({n:.3g} samples)", n * SAMPLE_BYTES,
               remedy="use a shorter duration or a larger dt")
    arm = _arm(arm)
    plant, dead, meas = hidden_effects(arm, {} if effects is None else effects)
    if experiment == "static-sawtooth":
        meta, frame = _sawtooth(plant, arm, noise, seed, duration, dt, dead, meas)
        return MeasuredData(meta, frame, source="synthesize")
    duration = 10.0 if duration is None else duration
    if experiment == "closed-loop":
        return _closed_loop(arm, plant, dead, meas, noise=noise, seed=seed,
                            duration=duration, dt=dt, controller=controller,
                            reference=reference, p_std=PRESSURE_NOISE_STD)
    return _open_loop(arm, plant, dead, meas, noise=noise, seed=seed, duration=duration,
                      dt=dt, p_std=PRESSURE_NOISE_STD)


def _recorded(meas, q, qd, p, *, std, seed, dt, p_std, qnoise=True, rng_p=None):
    """The recorded q, qd, p: sensor faults, then measurement noise, then outliers.

    The noise streams do not depend on the measurement effects (a record and its twin
    without them carry the same noise): q, qd and p from ``default_rng(seed)`` in that order,
    or p from ``rng_p`` when given; outliers from their own stream.  ``std``: the (q, qd)
    standard deviations of :func:`noise_std`, None without noise.
    """
    q, qd, p = meas.sensors(q, qd, p)
    if std is not None:
        rng = np.random.default_rng(seed)
        sq, sqd = std
        if qnoise:
            q = q + meas.noise(q.shape, sq, dt, rng)
            qd = qd + meas.noise(qd.shape, sqd, dt, rng)
        p = p + meas.noise(p.shape, p_std, dt, rng if rng_p is None else rng_p)
        if meas.outlier_rate > 0.0:
            x = meas.outliers(np.concatenate([q, qd, p], axis=1),
                              np.concatenate([sq, sqd, np.full(4, p_std)]),
                              np.random.default_rng([seed, 7]))
            q, qd, p = x[:, :2], x[:, 2:4], x[:, 4:8]
    return q, qd, p


def _open_loop(arm, plant, dead, meas, *, noise, seed, duration, dt, p_std):
    """The open-loop Fourier-excitation record (see :func:`synthesize`)."""
    exc = default_excitation(arm, seed=seed)
    q0 = equilibrium_for(exc.delta_p([0.0])[0], arm)
    x0, _ = rest_state(q0, plant)
    n = int(round(duration / dt))
    t = np.arange(n) * dt
    u = exc.set_values(t, arm)
    shift = int(round(dead / dt))
    substeps = max(2, int(math.ceil(dt / min(1e-3, 0.5 * min(
        v.time_constant for v in arm.valves.valves)))))
    X = simulate(plant, x0, delayed(meas.valve_input(u), shift), dt=dt, substeps=substeps)[:n]
    q, qd, p = _recorded(meas, X[:, :2], X[:, 2:4], X[:, 4:8], std=noise_std(arm, noise),
                         seed=seed, dt=dt, p_std=p_std)
    meta = {"kind": "arm", "experiment": "open-loop", "sample_rate": 1.0 / dt,
            "description": "synthetic open-loop Fourier excitation record",
            "source": f"ppamsafety synthesize (seed {seed}, noise {noise})"}
    return _record(meta, t, q, qd, p, u)


def _record(meta, t, q, qd, p, u, extra=None):
    cols = {"t": t, "q1": q[:, 0], "q2": q[:, 1], "qd1": qd[:, 0], "qd2": qd[:, 1]}
    for i in range(4):
        cols[f"p{i + 1}"] = p[:, i]
    for i in range(4):
        cols[f"u{i + 1}"] = u[:, i]
    return MeasuredData(meta, pd.DataFrame(cols), source="synthesize")


def closed_loop_case(arm, plant, *, controller: str = DEFAULT_CONTROLLER,
                     reference: str = DEFAULT_REFERENCE, duration: float = 10.0,
                     dt: float = 1e-3, noise=True, seed: int = 0, dead_time: float = 0.0):
    """The closed-loop case a synthetic closed-loop record is made of (see :func:`synthesize`).

    Parameters
    ----------
    arm : ArmParameters
        Nominal arm (the reference is planned on it).
    plant : ArmParameters
        The plant truth (with the hidden effects).
    controller : str, keyword-only
        Thesis variant label.
    reference : str, keyword-only
        Thesis experiment name.
    duration : float, keyword-only
        Length [s].
    dt : float, keyword-only
        Control period [s].
    noise : bool or {"arm", "table-3.2", "none"}, keyword-only
        Noise on the measured q, qd (fed back): True or ``"arm"`` the arm's declared sensor
        noise, ``"table-3.2"`` the thesis' (:func:`noise_variances`), False or ``"none"`` none.
    seed : int, keyword-only
        Seed of that noise.
    dead_time : float, keyword-only
        Valve dead time [s], realised as ``Effects.valve_dead_time`` in
        whole control periods.

    Returns
    -------
    ExperimentCase
    """
    variants = {v.label: v for v in thesis_variants()}
    if not isinstance(controller, str) or controller not in variants:
        raise ValueError(f"controller = {controller!r} is not a thesis variant label; "
                         f"allowed: {list(variants)}")
    reference = check_choice("reference", reference, NAMED)
    ref = thesis_reference(arm, reference, duration=duration, dt=dt)
    k = int(round(check_range("dead_time", dead_time, 0.0, 0.1, unit="s") / dt))
    if k:
        plant = plant.replace(effects=plant.effects.replace(valve_dead_time=(k,) * 4))
    var = noise_variances(arm, "arm" if noise is True else "none" if noise is False else noise)
    sens = SensorConfig(encoder=False, velocity="ideal", noise=var is not None, seed=seed,
                        **({} if var is None else {"noise_variances": var[0] + var[1]}))
    return ExperimentCase(plant, variants[controller].controller, ref, sensors=sens,
                          name=f"{reference}: {controller}")


def _closed_loop(arm, plant, dead, meas, *, noise, seed, duration, dt, controller,
                 reference, p_std):
    """The closed-loop record (see :func:`synthesize`).

    The controller sees the plant's angles and velocities with the chosen noise (fed
    back); the recorded ones also carry the measurement effects (sensor faults, coloured
    noise, outliers), added afterwards: the diagnosis replays the logged set values, so
    what the controller saw does not enter it.  A valve nonlinearity is realised on the
    log (the set values written are those whose distorted value the valves received).
    """
    case = closed_loop_case(arm, plant, controller=controller, reference=reference,
                            duration=duration, dt=dt, noise=noise, seed=seed,
                            dead_time=dead)
    res = run_batch([case], dt=dt)[0]
    if res.diverged:
        raise ValueError(f"the closed loop diverged with these effects "
                         f"({res.divergence_reason}); no record")
    n = int(round(duration / dt))
    sig = res.signals
    q = sig("q1_meas", "q2_meas")[:n].copy()
    qd = sig("qd1_meas", "qd2_meas")[:n].copy()
    p = sig("p1", "p2", "p3", "p4")[:n].copy()
    u = sig("u1", "u2", "u3", "u4")[:n].copy()
    u = _logged_for(meas, u)
    t = np.arange(q.shape[0]) * dt
    # the controller's noise is already in q, qd (white, fed back); add the faults, the
    # pressure noise (its own stream, the same whatever the measurement effects) and, for
    # coloured noise, a coloured part on q, qd
    q, qd, p = _recorded(meas, q, qd, p, std=noise_std(arm, noise), seed=seed + 1, dt=dt,
                         p_std=p_std,
                         qnoise=meas.noise_correlation_time > 0.0,
                         rng_p=np.random.default_rng([seed, 1]))
    meta = {"kind": "arm", "experiment": "closed-loop", "sample_rate": 1.0 / dt,
            "description": f"synthetic closed-loop record: {reference}, {controller}",
            "source": f"ppamsafety synthesize (seed {seed}, noise {noise})",
            "reference": reference, "controller": {"variant": controller}}
    return _record(meta, t, q, qd, p, u)


__all__ = ["synthesize_arm", "plant_with", "plant_vector", "hidden_effects", "Measurement",
           "MEASUREMENT_EFFECTS", "closed_loop_case", "sawtooth_set_angles",
           "gravity_compensation_set_values", "EXPERIMENTS", "NOISES", "FORCE_NOISE_STD",
           "noise_std", "noise_variances",
           "DEFAULT_CONTROLLER", "DEFAULT_REFERENCE"]
