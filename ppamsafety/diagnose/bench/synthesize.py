"""Hidden-effect records of one actuator on a tensile tester (rehearsal data for the tester diagnosis).

:func:`synthesize_actuator` writes a record in the measured-data format
(``kind = "actuator"``, ``experiment = "tensile"``) whose metadata are the
same whatever is hidden: kind, experiment, sample rate (omitted with
jittered sampling), the *nominal* force law, a generic description and the
seed.

Protocols:

``"sawtooth"`` (default)
    Position-controlled quasi-static test: at each pressure of
    ``pressures`` (default 1, 1.5 and 2.5 bar, the thesis' tensile records,
    §3.6.5) the contraction follows ``cycles`` triangles between
    ``eps_range`` (default 5 % .. 25 %, around the 7-20 % range of
    applications, §3.6.6), each of period ``period`` x (1, 0.6, 1.4, ...)
    (varying speeds, as the thesis' manual loops of 8 s and 40 s, §3.6.1),
    after a 2 s hold at the lower contraction during which the pressure
    moves to its new level (ramp of 1 s).
``"pressure-sweep"``
    Fixed contraction (the middle of ``eps_range``), the pressure swept
    ``cycles`` times between the lowest and the highest of ``pressures``.

The regulated pressure is not constant (as on a real bench): a 1 % slow
ripple and a -1.5 kPa dip while the muscle contracts (the regulator lags
the volume change); the record carries it, so it is no discrepancy.

Effects (``{name: value}``, SI):

in the tester library (:mod:`.candidates`)
    ``hysteresis_delta`` [-]: (3.35) with the Preisach operator of §3.6,
    memory from negative saturation (the test starts on the stretched
    muscle, §3.6.6); ``friction_coulomb`` [N] and ``friction_viscous``
    [N s/m]: a force ``c sign(v) + b v`` opposing the motion (v = l0 d eps/dt,
    the sign kept through rests); ``force_law_scale`` [-]: the true law is
    (1 + s) x the nominal one (a slenderness l0/R known only roughly,
    §3.6.1); ``force_law_delta`` [N/Pa]: five values added to a0..a4;
    sensor faults: ``force_sensor_offset`` [N] (added to the
    recorded force), ``force_sensor_gain`` [-] (the recorded force is
    (1 + g) x the force), ``pressure_sensor_offset`` [Pa] (added to the
    recorded pressure) and ``pressure_sensor_gain`` [-] (the recorded
    pressure is (1 + g) x the pressure; on a muscle record the same as a
    force gain -g/(1 + g): both scale p f(eps));
outside the library
    ``backlash`` [m]: play of total width ``backlash`` between the measured
    crosshead position and the muscle end (the muscle's contraction is the
    play operator of the measured one); ``leak_rate`` [1/s]: the muscle
    leaks behind the pressure sensor, which sits at the regulator: its
    pressure decays as exp(-leak_rate tau) after each pressure change tau
    seconds ago while the sensor keeps reading the regulated pressure;
    ``force_sensor_drift`` [N/s]: the load cell's zero drifts linearly from
    the start of the record (warming); ``pressure_sensor_lag`` [s]: the
    pressure reading is the true pressure through a first-order lag of this
    time constant (a slow transducer or a long tube); ``noise_correlation_time``
    [s]: the measurement noise of every channel is coloured (first-order
    autoregressive with this correlation time and the same variance: the
    same draws filtered); ``outlier_rate`` [-]: that fraction of the samples
    each carry a spike of 10-50 noise levels on one channel (force, pressure
    or position; their own random stream, so the record is otherwise the
    same).

Noise ``"tester"``: white Gaussian noise of 1 N on the force (a 0.1 %
class load cell of a few kN), 500 Pa on the pressure (the arm's choice,
:data:`ppamsafety.identify.static.PRESSURE_NOISE_STD`) and 10 um on the
position (contraction noise 10 um / l0); ``"none"``: exact samples.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ..._validation import (as_float_array, check_bool, check_choice, check_int, check_numbers,
                            check_range, check_seed, check_size, check_vector)
from ...data.measured import MeasuredData
from ...hysteresis import EPS_MAX, preisach_response, scaled_input, w_fit
from ...hysteresis.tensile import DEFAULT_FORCE_LAW

NOISES = ("tester", "none")
PROTOCOLS = ("sawtooth", "pressure-sweep")
#: Noise of the "tester" level: force [N], pressure [Pa], position [m] (module docstring).
FORCE_NOISE_STD = 1.0
PRESSURE_NOISE_STD = 500.0
POSITION_NOISE_STD = 10e-6
#: Thesis tensile pressures (§3.6.5) [Pa] and muscle length l0 = 6 cm (fig. 3.16) [m].
THESIS_PRESSURES = (1.0e5, 1.5e5, 2.5e5)
THESIS_L0 = 0.06
EFFECTS = ("hysteresis_delta", "friction_coulomb", "friction_viscous", "force_law_scale",
           "force_law_delta", "force_sensor_offset", "force_sensor_gain", "pressure_sensor_offset",
           "pressure_sensor_gain", "backlash", "leak_rate", "force_sensor_drift",
           "pressure_sensor_lag", "noise_correlation_time", "outlier_rate")
#: Range of every scalar effect: (lo, hi, unit).
EFFECT_BOUNDS = {"hysteresis_delta": (0.0, 0.5, "-"), "friction_coulomb": (0.0, 1e5, "N"),
                 "friction_viscous": (0.0, 1e7, "N s/m"), "force_law_scale": (-0.5, 0.5, "-"),
                 "force_sensor_offset": (-1e5, 1e5, "N"), "force_sensor_gain": (-0.5, 0.5, "-"),
                 "pressure_sensor_offset": (-1e6, 1e6, "Pa"),
                 "pressure_sensor_gain": (-0.5, 0.5, "-"), "backlash": (0.0, 0.05, "m"),
                 "leak_rate": (0.0, 10.0, "1/s"), "force_sensor_drift": (-1e3, 1e3, "N/s"),
                 "pressure_sensor_lag": (0.0, 10.0, "s"),
                 "noise_correlation_time": (0.0, 100.0, "s"), "outlier_rate": (0.0, 0.05, "-")}
#: Spikes of ``outlier_rate``: amplitude range in noise levels.
OUTLIER_LEVELS = (10.0, 50.0)
#: Hold at each pressure change [s] and the pressure ramp inside it [s].
HOLD_SECONDS, RAMP_SECONDS = 2.0, 1.0


def _check_effects(effects) -> dict:
    if effects is None:
        return {}
    if not isinstance(effects, dict):
        raise TypeError(f"effects must be a dict {{name: value}}, got {type(effects).__name__}")
    out = {}
    for name, value in effects.items():
        if name not in EFFECTS:
            raise ValueError(f"unknown effect {name!r} for kind='actuator'; allowed: "
                             f"{', '.join(EFFECTS)}")
        if name == "force_law_delta":
            out[name] = np.array(check_vector(
                f"effect {name}", check_numbers(f"effect {name}", value, (5,)), 5, -1.0, 1.0,
                unit="N/Pa"))
            continue
        v = check_numbers(f"effect {name}", value, (1,))[0]
        lim = EFFECT_BOUNDS[name]
        out[name] = check_range(f"effect {name}", v, lim[0], lim[1], unit=lim[2])
    return out


def _knots(protocol, pressures, cycles, period, eps_range):
    """Piecewise-linear (time, eps, p_set) knots of the protocol."""
    lo, hi = eps_range
    speeds = (1.0, 0.6, 1.4)
    T, E, P = [0.0], [lo], [pressures[0]]
    if protocol == "sawtooth":
        for i, p in enumerate(pressures):
            if i:
                T += [T[-1] + RAMP_SECONDS]
                E += [lo]
                P += [p]
            T += [T[-1] + HOLD_SECONDS - (RAMP_SECONDS if i else 0.0)]
            E += [lo]
            P += [p]
            for c in range(cycles):
                tc = period * speeds[c % 3]
                T += [T[-1] + tc / 2, T[-1] + tc]
                E += [hi, lo]
                P += [p, p]
    else:
        mid = 0.5 * (lo + hi)
        pmin, pmax = min(pressures), max(pressures)
        T, E, P = [0.0, HOLD_SECONDS], [mid, mid], [pmin, pmin]
        for c in range(cycles):
            tc = period * speeds[c % 3]
            T += [T[-1] + tc / 2, T[-1] + tc]
            E += [mid, mid]
            P += [pmax, pmin]
    return np.array(T), np.array(E), np.array(P)


def _lag(t, x, tau):
    """``x`` through a first-order lag of time constant ``tau`` [s] (exact for a held input)."""
    y = np.empty_like(x)
    y[0] = x[0]
    g = 1.0 - np.exp(-np.diff(t) / tau)
    for k in range(1, x.size):
        y[k] = y[k - 1] + g[k - 1] * (x[k] - y[k - 1])
    return y


def _ar1(t, w, tau):
    """White noise ``w`` made first-order autoregressive with correlation time ``tau`` [s] and
    the same variance (non-uniform sampling: the coefficient of each step from its length)."""
    a = np.exp(-np.diff(t) / tau)
    b = np.sqrt(1.0 - a * a)
    y = np.empty_like(w)
    y[0] = w[0]
    for k in range(1, w.size):
        y[k] = a[k - 1] * y[k - 1] + b[k - 1] * w[k]
    return y


def _outliers(channels, stds, rate, rng):
    """Spikes of :data:`OUTLIER_LEVELS` noise levels on ``rate`` of the samples, one channel each."""
    out = [np.array(c, dtype=float) for c in channels]
    n = out[0].size
    hit = rng.random(n) < rate
    ch = rng.integers(0, len(out), size=n)
    amp = rng.uniform(*OUTLIER_LEVELS, size=n) * rng.choice([-1.0, 1.0], size=n)
    for k in np.flatnonzero(hit):
        out[ch[k]][k] += amp[k] * stds[ch[k]]
    return tuple(out)


def _play(x, half):
    """Play (backlash) operator of half-width ``half`` on a sampled input, starting centred."""
    y = np.empty_like(x)
    y[0] = x[0]
    for k in range(1, x.size):
        y[k] = min(max(y[k - 1], x[k] - half), x[k] + half)
    return y


def synthesize_actuator(effects=None, *, noise: str = "tester", seed: int = 0,
                        protocol: str = "sawtooth", pressures=THESIS_PRESSURES,
                        cycles: int = 3, period: float = 20.0, eps_range=(0.05, 0.25),
                        sample_rate: float = 50.0, force_law=None, l0: float = THESIS_L0,
                        position: bool = False, jitter: float = 0.0):
    """A tensile-tester record of one actuator with hidden ``effects`` (module docstring).

    Parameters
    ----------
    effects : dict, optional
        ``{name: value}`` from :data:`EFFECTS` (SI units); default none.
    noise : {"tester", "none"}, keyword-only
        Measurement noise level.
    seed : int, keyword-only
        Seed of the noise, the ripple phase and the sampling jitter.
    protocol : {"sawtooth", "pressure-sweep"}, keyword-only
        Contraction sawtooth at constant pressures, or a pressure sweep at fixed contraction.
    pressures : sequence of float, keyword-only
        Gauge pressures [Pa], each in (0, 10] bar; default 1, 1.5, 2.5 bar.
    cycles : int, keyword-only
        Triangles per pressure (sawtooth) or pressure sweeps, 1..100.
    period : float, keyword-only
        Nominal period of one cycle [s], 0.5..3600 (cycles alternate x1, x0.6, x1.4).
    eps_range : (float, float), keyword-only
        Lowest and highest contraction [-], 0 < lo < hi < 0.45.
    sample_rate : float, keyword-only
        Mean sampling rate [Hz], 1..10^4.
    force_law : sequence of 5 float, optional, keyword-only
        Nominal a0..a4 of (3.9) [N/Pa] written in the metadata (default
        Table B.1 group 1); a cylinder: ``[0, A, 0, 0, 0]``.
    l0 : float, keyword-only
        Uncontracted length [m], (0, 1].
    position : bool, keyword-only
        Write the length ``position`` [m] instead of ``contraction``.
    jitter : float, keyword-only
        Relative jitter of the sampling intervals, [0, 0.9]; > 0 gives
        non-uniform sampling (no sample_rate in the metadata).

    Returns
    -------
    MeasuredData
    """
    fx = _check_effects(effects)
    noise = check_choice("noise", noise, NOISES)
    seed = check_seed("seed", seed)
    protocol = check_choice("protocol", protocol, PROTOCOLS)
    pressures = check_vector("pressures", pressures, None, 0.0, 1e6, lo_open=True, unit="Pa")
    if not pressures:
        raise ValueError("pressures must hold at least one pressure [Pa]")
    cycles = check_int("cycles", cycles, 1, 100)
    period = check_range("period", period, 0.5, 3600.0, unit="s")
    eps_range = check_vector("eps_range", eps_range, 2, 0.0, 0.45, lo_open=True)
    if not eps_range[0] < eps_range[1]:
        raise ValueError(f"eps_range = {eps_range} must be (lo, hi) with lo < hi")
    rate = check_range("sample_rate", sample_rate, 1.0, 1e4, unit="Hz")
    a = np.asarray(DEFAULT_FORCE_LAW if force_law is None else
                   as_float_array("force_law", force_law), float)
    if a.shape != (5,) or a[0] < 0 or np.max(np.abs(a)) > 1.0 or not a.any():
        raise ValueError(f"force_law = {a.tolist()} must be 5 coefficients a0..a4 in N/Pa with "
                         f"a0 >= 0, |a_i| <= 1 and not all 0")
    l0 = check_range("l0", l0, 0.0, 1.0, lo_open=True, unit="m")
    position = check_bool("position", position)
    jitter = check_range("jitter", jitter, 0.0, 0.9)
    rng = np.random.default_rng(seed)

    T, E, P = _knots(protocol, pressures, cycles, period, eps_range)
    dt = 1.0 / rate
    check_size(f"cycles = {cycles}, period = {period:g} s, {len(pressures)} pressure(s) at "
               f"sample_rate = {rate:g} Hz ({T[-1]:.4g} s, {T[-1] * rate:.3g} samples)",
               T[-1] * rate * 8 * 30, remedy="use fewer cycles, a shorter period or a lower "
                                             "sample_rate")
    n_est = int(T[-1] * rate) + 1
    if jitter > 0:
        steps = dt * (1.0 + jitter * rng.uniform(-1.0, 1.0, n_est + 10))
        t = np.concatenate([[0.0], np.cumsum(steps)])
        t = t[t <= T[-1]]
    else:
        t = np.arange(n_est) * dt
    eps_cmd = np.interp(t, T, E)
    p_set = np.interp(t, T, P)
    # direction and speed of the commanded motion (exact, from the knots)
    seg = np.clip(np.searchsorted(T, t, side="right") - 1, 0, T.size - 2)
    rate_cmd = (E[seg + 1] - E[seg]) / (T[seg + 1] - T[seg])
    s = np.sign(rate_cmd)
    for k in range(1, s.size):                    # keep the sign of the last motion at rest
        if s[k] == 0:
            s[k] = s[k - 1]
    eps_true = eps_cmd
    if "backlash" in fx:
        eps_true = _play(eps_cmd, 0.5 * fx["backlash"] / l0)
    phase = rng.uniform(0, 2 * math.pi)
    p_reg = p_set * (1.0 + 0.01 * np.sin(2 * math.pi * t / 9.7 + phase)) - 1500.0 * (s > 0) * (
        rate_cmd != 0)
    p_muscle = p_reg
    if fx.get("leak_rate", 0.0) > 0:
        changes = T[np.flatnonzero(np.diff(P) != 0)]
        last = np.zeros_like(t)
        for c in changes:
            last = np.where(t >= c, c, last)
        p_muscle = p_reg * np.exp(-fx["leak_rate"] * (t - last))
    a_true = a * (1.0 + fx.get("force_law_scale", 0.0)) + fx.get("force_law_delta", 0.0)
    e = eps_true
    f_law = p_muscle * ((a_true[0] / e if a_true[0] != 0 else 0.0) + a_true[1]
                        + e * (a_true[2] + e * (a_true[3] + e * a_true[4])))
    force = f_law.copy()
    if fx.get("hysteresis_delta", 0.0) > 0:
        es = scaled_input(e, EPS_MAX)
        W = preisach_response(es, initial="negative", clip=True)
        sl, ic = w_fit()
        force = f_law * (1.0 + fx["hysteresis_delta"] * (W - (sl * es + ic)))
    v = l0 * rate_cmd
    force = force - fx.get("friction_coulomb", 0.0) * s - fx.get("friction_viscous", 0.0) * v
    # the sensors: the load cell (gain, zero, drifting zero) and the pressure transducer (lag,
    # gain, zero) read the muscle's force and the regulated pressure
    force = ((1.0 + fx.get("force_sensor_gain", 0.0)) * force + fx.get("force_sensor_offset", 0.0)
             + fx.get("force_sensor_drift", 0.0) * t)
    p_read = _lag(t, p_reg, fx["pressure_sensor_lag"]) if fx.get("pressure_sensor_lag", 0.0) > 0 \
        else p_reg
    p_rec = (1.0 + fx.get("pressure_sensor_gain", 0.0)) * p_read + fx.get(
        "pressure_sensor_offset", 0.0)
    pos = l0 * (1.0 - eps_cmd)
    stds = (FORCE_NOISE_STD, PRESSURE_NOISE_STD, POSITION_NOISE_STD)
    if noise == "tester":
        tau = fx.get("noise_correlation_time", 0.0)
        w = [rng.normal(0.0, sd, t.size) for sd in stds]
        if tau > 0:
            w = [_ar1(t, x, tau) for x in w]
        force, p_rec, pos = force + w[0], p_rec + w[1], pos + w[2]
    if fx.get("outlier_rate", 0.0) > 0:
        force, p_rec, pos = _outliers((force, p_rec, pos), stds, fx["outlier_rate"],
                                      np.random.default_rng([seed, 7]))
    cols = {"t": t, "force": force, "pressure": p_rec}
    if position:
        cols["position"] = pos
    else:
        cols["contraction"] = (l0 - pos) / l0
    meta = {"kind": "actuator", "experiment": "tensile",
            "description": "synthetic tensile-tester record of one actuator",
            "source": f"ppamsafety synthesize (seed {seed}, noise {noise})",
            "force_law": {"name": "nominal", "a": [float(x) for x in a], "l0": float(l0)}}
    if jitter == 0:
        meta = {**{k: meta[k] for k in ("kind", "experiment")}, "sample_rate": rate,
                **{k: meta[k] for k in ("description", "source", "force_law")}}
    return MeasuredData(meta, pd.DataFrame(cols), source="synthesize")


__all__ = ["synthesize_actuator", "EFFECTS", "EFFECT_BOUNDS", "OUTLIER_LEVELS", "NOISES", "PROTOCOLS", "THESIS_PRESSURES",
           "THESIS_L0", "FORCE_NOISE_STD", "PRESSURE_NOISE_STD", "POSITION_NOISE_STD"]
