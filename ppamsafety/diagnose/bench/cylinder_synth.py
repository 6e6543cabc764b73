"""Synthetic friction campaigns of a pneumatic cylinder (rehearsal data for the campaign diagnosis).

:func:`synthesize_cylinder` imitates the shipped bench (Zillen 2021,
``ppamsafety.data.datasets``): a rod driven through triangle cycles of
``stroke`` at each pressure of ``pressures``, extending at 14.5 mm/s and
pushed in at a speed that falls with the pressure (13.3 -> 7 mm/s from 1 to 7
bar, as the real drive), reversals rounded over about 40 ms, a slow wobble of
the speed, a regulated pressure that rises by 1.5 % while the rod is pushed in,
software-timed sampling (10 ms, 15 % of the intervals 11-19 ms, one or two
gaps of 40-300 ms per record) and the sensor noise of the real bench (force
0.028 N, pressure 180 Pa, position 13 um).  Each record is a validated
cylinder record (``[actuator] type = "cylinder"``) with its nominal pressure;
together a :class:`~ppamsafety.data.campaign.Campaign`.

Force on the load cell: ``F = p A_true - phi`` with ``phi`` the friction
opposing the motion, integrated along the path by the Dahl recursion
(:func:`ppamsafety.hysteresis.dahl.dahl_path`): after a reversal it moves from one side to the
other over ``presliding`` metres of travel (1 um without the effect: an
abrupt Coulomb step), toward the steady level

    F_ss = c0 + c1 p + c2 p^2 + b |v| + dS exp(-(v/v_s)^2) + profile(x) + cd t

Hidden effects (``{name: value}``, SI; the library of :mod:`.friction`):
``coulomb`` [N], ``coulomb_pressure`` [N/Pa], ``coulomb_pressure2``
[N/Pa^2], ``viscous`` [N s/m], ``stribeck`` [N] (with ``stribeck_speed``
[m/s], default 0.1 x the stroke speed), ``presliding`` [m],
``stroke_profile`` [N] (RMS of a smooth random profile of the friction along
the bore, and as much again of a direction-independent force),
``stroke_profile_pressure`` [N] (RMS at 5 bar of a force along the bore
proportional to p), ``friction_drift`` [N/s], ``force_sensor_offset`` [N],
``force_sensor_gain`` [-], ``pressure_sensor_offset`` [Pa],
``pressure_sensor_gain`` [-], ``area_error`` [-] (the true area is
(1 + e) A).  Outside the library: ``stroke_scatter`` [N] (a random friction
level per stroke, SD), ``ripple`` [N] (force noise correlated over 50 ms),
``slow_transient`` [N] (after each reversal the force lags by this much,
decaying over 0.25 s of *time*, like the pressure settling of the real
bench), ``record_offset`` [N] (a random constant per record, SD).  Default
nuisance: ``stroke_scatter`` 0.15 N and ``ripple`` 0.1 N, as the real bench
(its repeatability is 2-6 x its sensor noise).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
from scipy.signal import lfilter

from ..._validation import (check_bool, check_choice, check_int, check_range, check_seed,
                            check_vector)
from ...data.campaign import Campaign
from ...data.measured import MeasuredData, MeasuredDataWarning
from ...hysteresis.dahl import dahl_path

EFFECTS = ("coulomb", "coulomb_pressure", "coulomb_pressure2", "viscous", "stribeck",
           "stribeck_speed", "presliding", "stroke_profile", "stroke_profile_pressure",
           "friction_drift", "force_sensor_offset", "force_sensor_gain",
           "pressure_sensor_offset", "pressure_sensor_gain", "area_error")
NUISANCES = ("stroke_scatter", "ripple", "slow_transient", "record_offset")
DEFAULT_NUISANCE = {"stroke_scatter": 0.15, "ripple": 0.1}
#: Which library candidate (or confounded group member) each hidden effect is.
LIBRARY_NAME = {"coulomb": "coulomb", "coulomb_pressure": "coulomb_pressure",
                "coulomb_pressure2": "coulomb_pressure2", "viscous": "viscous",
                "stribeck": "stribeck", "presliding": "presliding",
                "stroke_profile": "stroke_profile",
                "stroke_profile_pressure": "stroke_profile_pressure",
                "friction_drift": "friction_drift", "force_sensor_offset": "force_sensor_offset",
                "force_sensor_gain": "force_sensor_gain",
                "pressure_sensor_offset": "pressure_sensor_offset",
                "pressure_sensor_gain": "pressure_sensor_gain", "area_error": "force_law_refit"}
_LIMITS = {"coulomb": (0.0, 1e3, "N"), "coulomb_pressure": (0.0, 1e-3, "N/Pa"),
           "coulomb_pressure2": (0.0, 1e-9, "N/Pa^2"), "viscous": (0.0, 1e4, "N s/m"),
           "stribeck": (0.0, 1e3, "N"), "stribeck_speed": (1e-5, 1.0, "m/s"),
           "presliding": (0.0, 0.01, "m"), "stroke_profile": (0.0, 1e3, "N"),
           "stroke_profile_pressure": (0.0, 1e3, "N"), "friction_drift": (-10.0, 10.0, "N/s"),
           "force_sensor_offset": (-1e3, 1e3, "N"), "force_sensor_gain": (-0.5, 0.5, "-"),
           "pressure_sensor_offset": (-1e5, 1e5, "Pa"), "pressure_sensor_gain": (-0.5, 0.5, "-"),
           "area_error": (-0.5, 0.5, "-"), "stroke_scatter": (0.0, 100.0, "N"),
           "ripple": (0.0, 100.0, "N"), "slow_transient": (0.0, 100.0, "N"),
           "record_offset": (0.0, 100.0, "N")}
#: Sensor noise of the real bench (groundwork, medians over 15 files).
FORCE_NOISE, PRESSURE_NOISE, POSITION_NOISE = 0.028, 180.0, 13e-6
EXTEND_SPEED = 14.5e-3
#: Pushed-in speed at 1 bar and its fall per bar (the drive of the real bench).
PUSH_SPEED, PUSH_SPEED_PER_BAR = 13.3e-3, 1.05e-3


def _check(d, allowed, what):
    if d is None:
        return {}
    if not isinstance(d, dict):
        raise TypeError(f"{what} must be a dict {{name: value}}, got {type(d).__name__}")
    out = {}
    for k, v in d.items():
        if k not in allowed:
            raise ValueError(f"unknown {what[:-1]} {k!r}; allowed: {', '.join(allowed)}")
        lo, hi, unit = _LIMITS[k]
        out[k] = check_range(f"{what[:-1]} {k}", v, lo, hi, unit=unit)
    return out


def _profile(rng, x, L, rms, n=8):
    """A smooth random profile along [0, L] with the given RMS (sum of n sines)."""
    if rms == 0:
        return np.zeros_like(x)
    k = np.arange(1, n + 1)
    a = rng.normal(0, 1, n) / k
    ph = rng.uniform(0, 2 * math.pi, n)
    g = np.linspace(0, L, 400)
    f = lambda z: np.sum(a[:, None] * np.sin(math.pi * k[:, None] * z[None, :] / L
                                             + ph[:, None]), axis=0)
    fg = f(g)
    mu, sd = fg.mean(), fg.std()
    return rms * (f(x) - mu) / sd


def _record(rng, p_bar, fx, nz, *, cycles, stroke, area, protocol, noise, prof, t_scale):
    dt_f = 1e-3
    v_ext = EXTEND_SPEED
    v_push = max(PUSH_SPEED - PUSH_SPEED_PER_BAR * (p_bar - 1.0), 3e-3)
    # triangle knots: start at the pushed-in end (x = 0), extend to L, push back ...
    T, X = [0.0], [0.0]
    for c in range(cycles):
        fac = (1.0, 0.5, 1.5)[c % 3] if protocol == "varied-speed" else 1.0
        T += [T[-1] + stroke / (v_ext * fac), 0.0]
        X += [stroke, 0.0]
        T[-1] = T[-2] + stroke / (v_push * fac)
    T, X = np.array(T), np.array(X)
    tf = np.arange(0.0, T[-1] + 0.5, dt_f)
    xf = np.interp(tf, T, X)
    # speed wobble: a slow random time warp of 3 %
    w = np.convolve(rng.normal(0, 1, tf.size), np.ones(500) / 500, mode="same")
    w = 0.03 * w / max(w.std(), 1e-12)
    tw = np.cumsum(1.0 + w) * dt_f
    xf = np.interp(tw, tf, xf)
    k = 20                                           # rounded reversals: 40 ms boxcar
    xf = np.convolve(np.pad(xf, k, mode="edge"), np.ones(2 * k + 1) / (2 * k + 1), "valid")
    v = np.gradient(xf, dt_f)
    p_true = p_bar * 1e5 * (1.0 + 0.015 * (v < 0)) * (1.0 + 0.003 * np.sin(
        2 * math.pi * tf / 7.3 + rng.uniform(0, 6.3)))
    tc = tf - 0.5 * tf[-1]
    vs = fx.get("stribeck_speed", 0.1 * 0.5 * (v_ext + v_push))
    target = (fx.get("coulomb", 0.0) + fx.get("coulomb_pressure", 0.0) * p_true
              + fx.get("coulomb_pressure2", 0.0) * p_true ** 2
              + fx.get("viscous", 0.0) * np.abs(v)
              + fx.get("stribeck", 0.0) * np.exp(-(v / vs) ** 2)
              + prof["friction"](xf) + fx.get("friction_drift", 0.0) * tc)
    # per-stroke scatter of the friction level (outside the library)
    sgn = np.sign(np.diff(xf, prepend=xf[0]))
    for i in range(1, sgn.size):
        if sgn[i] == 0:
            sgn[i] = sgn[i - 1]
    stroke_id = np.concatenate([[0], np.cumsum(np.diff(sgn) != 0)])
    if nz.get("stroke_scatter", 0.0) > 0:
        lev = rng.normal(0, nz["stroke_scatter"], int(stroke_id.max()) + 1)
        target = target + lev[stroke_id]
    target = np.maximum(target, 0.0)
    xd = fx.get("presliding", 0.0) or 1e-6
    phi = dahl_path(np.ascontiguousarray(xf), np.ascontiguousarray(target), float(xd),
                    -float(target[0]))
    A_true = area * (1.0 + fx.get("area_error", 0.0))
    F = p_true * A_true - phi + prof["force"](xf) + (p_true / 5e5) * prof["pressure"](xf)
    if nz.get("slow_transient", 0.0) > 0:
        rev = np.flatnonzero(np.diff(stroke_id) != 0) + 1
        last = np.zeros(tf.size)
        for r_ in rev:
            last[r_:] = tf[r_]
        dtr = np.where(np.arange(tf.size) >= (rev[0] if rev.size else tf.size), tf - last, np.inf)
        F = F + nz["slow_transient"] * sgn * np.exp(-dtr / 0.25)
    if nz.get("ripple", 0.0) > 0:
        a = math.exp(-dt_f / 0.05)
        e = rng.normal(0, nz["ripple"] * math.sqrt(1 - a * a), tf.size)
        e[0] = rng.normal(0, nz["ripple"])
        F = F + lfilter([1.0], [1.0, -a], e)       # AR(1), correlation time 50 ms
    # logger times: 10 ms, 15 % of the intervals 11-19 ms, 1-2 gaps of 40-300 ms
    n_est = int(tf[-1] / 0.0095) + 10
    d = np.where(rng.uniform(size=n_est) < 0.15, rng.uniform(0.011, 0.019, n_est), 0.010)
    for g in rng.choice(np.arange(50, n_est - 50), size=rng.integers(1, 3), replace=False):
        d[g] = rng.uniform(0.04, 0.3)
    ts = np.concatenate([[0.0], np.cumsum(d)])
    ts = ts[ts <= tf[-1] - 0.05] * t_scale
    pos = np.interp(ts, tf, xf)
    Fm = np.interp(ts, tf, F)
    pm = np.interp(ts, tf, p_true)
    Fm = Fm * (1.0 + fx.get("force_sensor_gain", 0.0)) + fx.get("force_sensor_offset", 0.0)
    pm = pm * (1.0 + fx.get("pressure_sensor_gain", 0.0)) + fx.get("pressure_sensor_offset", 0.0)
    if noise:
        Fm = Fm + rng.normal(0, FORCE_NOISE, ts.size)
        pm = pm + rng.normal(0, PRESSURE_NOISE, ts.size)
        pos = pos + rng.normal(0, POSITION_NOISE, ts.size)
    return ts, Fm, pm, pos


def synthesize_cylinder(effects=None, *, seed: int = 0, pressures=(1e5, 3e5, 5e5, 7e5),
                        cycles: int = 10, stroke: float = 0.042, bore: float = 0.0257,
                        nuisance=None, protocol: str = "fixed-speed", noise: bool = True,
                        repeats: int = 1) -> Campaign:
    """A synthetic friction campaign of one cylinder with hidden effects (module docstring).

    Parameters
    ----------
    effects : dict, optional
        ``{name: value}`` from :data:`EFFECTS` (SI).
    seed : int, keyword-only
        Seed of every random draw (noise, sampling, profiles, nuisances).
    pressures : sequence of float, keyword-only
        Gauge pressures of the records [Pa], each in (0, 20] bar.
    cycles : int, keyword-only
        Triangle cycles per record, 2..100.
    stroke : float, keyword-only
        Stroke [m], (0.002, 0.5].
    bore : float, keyword-only
        Bore [m] (the nominal area pi/4 bore^2), (0, 0.5].
    nuisance : dict, optional, keyword-only
        Out-of-library structure (:data:`NUISANCES`); default
        :data:`DEFAULT_NUISANCE`; ``{}`` for none.
    protocol : {"fixed-speed", "varied-speed"}, keyword-only
        Speeds fixed by direction and pressure (the real bench), or cycles at
        0.5, 1 and 1.5 x that speed (viscous friction then identifiable).
    noise : bool, keyword-only
        Add the real bench's sensor noise.
    repeats : int, keyword-only
        Records per pressure (1..5).

    Returns
    -------
    Campaign
    """
    fx = _check(effects, EFFECTS, "effects")
    nz = _check(DEFAULT_NUISANCE if nuisance is None else nuisance, NUISANCES, "nuisances")
    seed = check_seed("seed", seed)
    pressures = check_vector("pressures", pressures, None, 0.0, 2e6, lo_open=True, unit="Pa")
    if not pressures:
        raise ValueError("pressures must hold at least one pressure [Pa]")
    cycles = check_int("cycles", cycles, 2, 100)
    stroke = check_range("stroke", stroke, 0.002, 0.5, lo_open=True, unit="m")
    bore = check_range("bore", bore, 0.0, 0.5, lo_open=True, unit="m")
    protocol = check_choice("protocol", protocol, ("fixed-speed", "varied-speed"))
    noise = check_bool("noise", noise)
    repeats = check_int("repeats", repeats, 1, 5)
    rng = np.random.default_rng(seed)
    area = math.pi / 4 * bore ** 2
    xs = np.linspace(0, stroke, 2000)
    prof_f = _profile(rng, xs, stroke, fx.get("stroke_profile", 0.0) / math.sqrt(2))
    prof_e = _profile(rng, xs, stroke, fx.get("stroke_profile", 0.0) / math.sqrt(2))
    prof_p = _profile(rng, xs, stroke, fx.get("stroke_profile_pressure", 0.0))
    prof = {"friction": lambda z: np.interp(z, xs, prof_f),
            "force": lambda z: np.interp(z, xs, prof_e),
            "pressure": lambda z: np.interp(z, xs, prof_p)}
    recs = []
    for rep in range(repeats):
        for p in pressures:
            ts, F, pm, pos = _record(rng, p / 1e5, fx, nz, cycles=cycles, stroke=stroke,
                                     area=area, protocol=protocol, noise=noise, prof=prof,
                                     t_scale=1.0)
            if nz.get("record_offset", 0.0) > 0:
                F = F + rng.normal(0, nz["record_offset"])
            lab = f"{p / 1e5:g} bar" + (f" run {rep + 1}" if repeats > 1 else "")
            meta = {"kind": "actuator", "experiment": "tensile",
                    "description": "synthetic cylinder friction record",
                    "source": f"ppamsafety synthesize_cylinder (seed {seed})", "gap_factor": 3.0,
                    "actuator": {"type": "cylinder", "bore": bore, "name": "synthetic"},
                    "force_law": {"name": "p A (cylinder)", "a": [0.0, area, 0.0, 0.0, 0.0]},
                    "record": {"pressure_nominal": float(p), "label": lab}}
            frame = pd.DataFrame({"t": ts, "force": F, "pressure": pm, "position": pos})


            with warnings.catch_warnings():
                warnings.simplefilter("ignore", MeasuredDataWarning)
                recs.append(MeasuredData(meta, frame, source=f"synthetic {lab}"))
    return Campaign(tuple(recs), name=f"synthetic cylinder (seed {seed})")


def raw_text(data, *, spikes: int = 0, seed: int = 0) -> str:
    """A record as the shipped bench's raw file would hold it (7 TAB columns, CRLF, no header).

    time [ms], laser [V], pressure [V], force [V], position [mm] (growing when
    the rod is pushed in), pressure [bar], force [N]; a start-up row 273 ms
    before the record; ``spikes`` isolated laser spikes of 0.3-0.5 mm (at least 5 rows apart).

    Parameters
    ----------
    data : MeasuredData
        A cylinder record.
    spikes : int, keyword-only
        Laser spikes to add (>= 0).
    seed : int, keyword-only
        Seed of the spike rows and sizes.

    Returns
    -------
    str
    """
    spikes = check_int("spikes", spikes, 0)
    rng = np.random.default_rng(check_seed("seed", seed))
    t = data.column("t") * 1e3 + 273.0
    x = -data.column("position") * 1e3
    if spikes:
        rows = rng.choice(np.arange(20, t.size - 20, 5), size=spikes, replace=False)
        x[rows] += rng.choice([-1, 1], spikes) * rng.uniform(0.3, 0.5, spikes)
    p = data.column("pressure") / 1e5
    F = data.column("force")
    t = np.concatenate([[0.0], t])
    x, p, F = (np.concatenate([[a[0]], a]) for a in (x, p, F))
    lines = [f"{a:.3f}\t{b / 13.338 + 4.5:.3f}\t{c / 2 + 0.006:.3f}\t{d / 46.52 + 0.008:.3f}\t"
             f"{b:.3f}\t{c:.3f}\t{d:.3f}" for a, b, c, d in zip(np.rint(t), x, p, F)]
    return "\r\n".join(lines) + "\r\n"


__all__ = ["synthesize_cylinder", "raw_text", "EFFECTS", "NUISANCES", "DEFAULT_NUISANCE",
           "LIBRARY_NAME"]
