"""Synthetic measured records in the format of :mod:`ppamsafety.data.measured`.

For tests, examples and the discrepancy workflow: each function simulates an
experiment, adds seeded Gaussian measurement noise with the thesis' variances
(Table 3.2) and returns a validated :class:`~ppamsafety.data.measured.MeasuredData`
(``.save(path)`` writes it).

* :func:`synthetic_static` -- 31 equilibrium readings (§3.5.1.4) from
  :func:`ppamsafety.identify.static.static_experiment`.
* :func:`synthetic_tensile` -- one muscle on a tensile tester: pressure levels
  times a contraction sweep, force by a force law (3.9) (the nominal one by
  default; another ``coefficients`` hides a discrepancy).
* :func:`synthetic_excitation` -- the open-loop Fourier excitation record
  (§3.5.2.4), the same simulation as
  :func:`ppamsafety.identify.excitation.simulate_excitation`, with the
  pressures and set values it does not return.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .._validation import check_bool, check_int, check_range, check_seed, check_size, check_vector
from ..identify.excitation import FourierExcitation, default_offset, equilibrium_for
from ..identify.static import (equilibrium_configurations, static_experiment, FORCE_NOISE_VARIANCES,
                               PRESSURE_NOISE_STD)
from ..params import thesis_arm
from ..params.arm import ArmParameters
from ..plant.model import rest_state, simulate
from .measured import MeasuredData

#: Velocity noise variances of qd1, qd2 [rad^2/s^2], Table 3.2 (first signal).
VELOCITY_NOISE_VARIANCES = (1.63e-4, 2.32e-5)


def _arm(arm):
    if arm is None:
        return thesis_arm()
    if not isinstance(arm, ArmParameters):
        raise TypeError(f"arm must be an ArmParameters or None, got {type(arm).__name__}")
    return arm


def synthetic_static(arm=None, *, n: int = 31, seed: int = 0, noise: bool = True,
                     interval: float = 10.0) -> MeasuredData:
    """Equilibrium readings of the static experiment (§3.5.1.4) as a measured record.

    Parameters
    ----------
    arm : ArmParameters, optional
        The plant ("truth"); default the thesis arm.
    n : int, keyword-only
        Number of equilibrium points (31 in the thesis).
    seed : int, keyword-only
        Seed of the configurations and of the noise.
    noise : bool, keyword-only
        Add the Table 3.2 noise to q and F and 500 Pa to p.
    interval : float, keyword-only
        Time between readings [s] (the arm settles in between).

    Returns
    -------
    MeasuredData
        kind ``"arm"``, experiment ``"static-sawtooth"``; columns t, q1, q2,
        F1..F4, p1..p4, u1..u4.
    """
    arm = _arm(arm)
    n = check_int("n", n, 3, 10000)
    seed = check_seed("seed", seed)
    noise = check_bool("noise", noise)
    interval = check_range("interval", interval, 0.0, 1e5, lo_open=True, unit="s")
    q = equilibrium_configurations(arm, n, seed=seed)
    ex = static_experiment(arm, q, seed=seed, noise=noise)
    cols = {"t": np.arange(n) * interval, "q1": ex.q[:, 0], "q2": ex.q[:, 1]}
    for i in range(4):
        cols[f"F{i + 1}"] = ex.forces[:, i]
    for i in range(4):
        cols[f"p{i + 1}"] = ex.pressures[:, i]
    for i in range(4):
        cols[f"u{i + 1}"] = ex.set_values[:, i]
    meta = {"kind": "arm", "experiment": "static-sawtooth",
            "description": f"synthetic: {n} equilibrium readings of the plant (thesis §3.5.1.4)",
            "source": f"ppamsafety.data.synthetic.synthetic_static(n={n}, seed={seed}, "
                      f"noise={noise})"}
    return MeasuredData(meta, pd.DataFrame(cols), source="synthetic_static")


def synthetic_tensile(arm=None, *, group: int = 1, coefficients=None,
                      pressures=(1e5, 2e5, 3e5), contractions=(0.05, 0.30), n_per_level: int = 26,
                      seed: int = 0, noise: bool = True, position: bool = False,
                      sample_rate: float = 10.0) -> MeasuredData:
    """One muscle of ``group`` on a tensile tester: force at pressure levels x contractions.

    Parameters
    ----------
    arm : ArmParameters, optional
        Supplies the nominal law of the group (metadata) and l0.
    group : int, keyword-only
        Muscle group 1..4 whose muscle is tested.
    coefficients : sequence of 5 float, optional, keyword-only
        The true law a0..a4 [N/Pa] generating the forces (default: the nominal
        one, which the metadata always declares).
    pressures : sequence of float, keyword-only
        Gauge pressure levels [Pa], each in (0, 4e5].
    contractions : (float, float), keyword-only
        Contraction sweep [eps_lo, eps_hi], 0 < eps_lo < eps_hi < 0.4.
    n_per_level : int, keyword-only
        Samples per pressure level.
    seed : int, keyword-only
        Noise seed.
    noise : bool, keyword-only
        Force noise with the Table 3.2 variance of the group, pressure noise 500 Pa.
    position : bool, keyword-only
        Record the length ``position`` = l0 (1 - eps) [m] instead of the contraction.
    sample_rate : float, keyword-only
        Sampling rate [Hz] of the uniform time column.

    Returns
    -------
    MeasuredData
        kind ``"actuator"``, experiment ``"tensile"``.
    """
    arm = _arm(arm)
    group = check_int("group", group, 1, 4)
    g = arm.muscles.groups[group - 1]
    nominal = np.array(g.coefficients, dtype=float)
    a = nominal if coefficients is None else np.array(
        check_vector("coefficients", coefficients, 5, unit="N/Pa"))
    ps = np.array(check_vector("pressures", pressures, None, 0.0, 4e5, lo_open=True, unit="Pa"))
    if ps.size == 0:
        raise ValueError("pressures must not be empty")
    lo, hi = check_vector("contractions", contractions, 2, 0.0, 0.4, lo_open=True, hi_open=True)
    if not lo < hi:
        raise ValueError(f"contractions = {contractions!r}: the first must be below the second")
    n_per_level = check_int("n_per_level", n_per_level, 2, 100000)
    noise = check_bool("noise", noise)
    position = check_bool("position", position)
    rate = check_range("sample_rate", sample_rate, 0.0, 1e6, lo_open=True, unit="Hz")
    eps = np.tile(np.linspace(lo, hi, n_per_level), ps.size)
    p = np.repeat(ps, n_per_level)
    force = p * (a[0] / eps + a[1] + eps * (a[2] + eps * (a[3] + eps * a[4])))
    rng = np.random.default_rng(seed)
    if noise:
        force = force + rng.normal(size=force.size) * np.sqrt(FORCE_NOISE_VARIANCES[group - 1])
        p = p + rng.normal(size=p.size) * PRESSURE_NOISE_STD
    cols = {"t": np.arange(force.size) / rate, "force": force, "pressure": p}
    if position:
        cols["position"] = g.l0 * (1.0 - eps)
    else:
        cols["contraction"] = eps
    meta = {"kind": "actuator", "experiment": "tensile", "sample_rate": rate,
            "description": f"synthetic tensile test of one muscle of group {group}",
            "source": f"ppamsafety.data.synthetic.synthetic_tensile(group={group}, seed={seed}, "
                      f"noise={noise}, true law {'nominal' if coefficients is None else 'given'})",
            "force_law": {"name": f"thesis Table B.1 group {group}",
                          "a": [float(x) for x in nominal], "l0": float(g.l0)}}
    return MeasuredData(meta, pd.DataFrame(cols), source="synthetic_tensile")


def default_excitation(arm=None, *, seed: int = 0, amplitude: float = 3e4):
    """A seeded 5-harmonic Fourier Delta-p excitation (amplitudes ``amplitude``/k) [Pa].

    Parameters
    ----------
    arm : ArmParameters, optional
        Supplies the offset (:func:`ppamsafety.identify.excitation.default_offset`).
    seed : int, keyword-only
        Seed of the coefficients.
    amplitude : float, keyword-only
        Scale of the first harmonic [Pa].

    Returns
    -------
    FourierExcitation
    """
    arm = _arm(arm)
    amplitude = check_range("amplitude", amplitude, 0.0, 3e5, lo_open=True, unit="Pa")
    rng = np.random.default_rng(check_seed("seed", seed))
    k = np.arange(1, 6)[:, None]
    return FourierExcitation(a=rng.normal(size=(5, 2)) * amplitude / k,
                             b=rng.normal(size=(5, 2)) * amplitude / k,
                             offset=default_offset(arm))


#: Memory of one sample of :func:`synthetic_excitation` [bytes] (the simulation, the noise
#: and the record's table; 420 bytes measured with ``tracemalloc``, rounded up).
EXCITATION_RECORD_BYTES = 600


def synthetic_excitation(arm=None, excitation=None, *, periods: float = 1.0, dt: float = 1e-3,
                         substeps: int = 2, seed: int = 0, noise: bool = True,
                         velocity_noise_var=None) -> MeasuredData:
    """Open-loop excitation record (§3.5.2.4): q, qd, p, u sampled at ``dt``.

    The simulation of :func:`ppamsafety.identify.excitation.simulate_excitation`
    (start at rest at the equilibrium of Delta p(0), set values held over each
    interval); noise: q and qd with the variances the arm's sensors declare
    (``arm.sensors``; the thesis arm's are Table 3.2), p with 500 Pa.

    Parameters
    ----------
    arm : ArmParameters, optional
        The plant; default the thesis arm.
    excitation : FourierExcitation, optional
        Default :func:`default_excitation`.
    periods : float, keyword-only
        Record length in excitation periods.
    dt : float, keyword-only
        Sample time [s].
    substeps : int, keyword-only
        RK4 steps per sample.
    seed : int, keyword-only
        Noise seed.
    noise : bool, keyword-only
        Add measurement noise.
    velocity_noise_var : sequence of 2 float, keyword-only
        Variances of the qd1, qd2 noise [rad^2/s^2]; default the arm's declared
        ``sensors.velocity_noise_variances`` (the thesis arm: Table 3.2).  White
        velocity noise passes the high-pass omega (W1 - <W1>_F) of the
        filtered regressor unattenuated and biases the inertia estimates
        (errors in variables); (0, 0) leaves the velocities exact.

    Returns
    -------
    MeasuredData
        kind ``"arm"``, experiment ``"open-loop"``; columns t, q1, q2, qd1,
        qd2, p1..p4, u1..u4.
    """
    arm = _arm(arm)
    exc = default_excitation(arm) if excitation is None else excitation
    if not isinstance(exc, FourierExcitation):
        raise TypeError(f"excitation must be a FourierExcitation, got {type(exc).__name__}")
    periods = check_range("periods", periods, 0.0, 1e3, lo_open=True)
    dt = check_range("dt", dt, 1e-6, 0.1, unit="s")   # simulate() steps at >= 1 us
    substeps = check_int("substeps", substeps, 1, 1000)
    seed = check_seed("seed", seed)
    noise = check_bool("noise", noise)
    if velocity_noise_var is None:
        velocity_noise_var = arm.sensors.velocity_noise_variances
    vvar = np.array(check_vector("velocity_noise_var", velocity_noise_var, 2, 0.0,
                                 unit="rad^2/s^2"))
    n = int(round(periods * exc.period / dt))
    check_size(f"periods = {periods:g} of {exc.period:g} s at dt = {dt:g} s ({n:,} samples)",
               n * EXCITATION_RECORD_BYTES, remedy="record fewer periods or use a larger dt")
    q0 = equilibrium_for(exc.delta_p([0.0])[0], arm)
    x0, _ = rest_state(q0, arm)
    t = np.arange(n) * dt
    u = exc.set_values(t, arm)
    X = simulate(arm, x0, u, dt=dt, substeps=substeps)[:n]
    q, qd, p = X[:, :2].copy(), X[:, 2:4].copy(), X[:, 4:8].copy()
    if noise:
        rng = np.random.default_rng(seed)
        q += rng.normal(size=q.shape) * np.sqrt(np.asarray(arm.sensors.angle_noise_variances))
        qd += rng.normal(size=qd.shape) * np.sqrt(vvar)
        p += rng.normal(size=p.shape) * PRESSURE_NOISE_STD
    cols = {"t": t, "q1": q[:, 0], "q2": q[:, 1], "qd1": qd[:, 0], "qd2": qd[:, 1]}
    for i in range(4):
        cols[f"p{i + 1}"] = p[:, i]
    for i in range(4):
        cols[f"u{i + 1}"] = u[:, i]
    meta = {"kind": "arm", "experiment": "open-loop", "sample_rate": 1.0 / dt,
            "description": f"synthetic open-loop Fourier excitation, {periods:g} period(s) of "
                           f"{exc.period:g} s",
            "source": f"ppamsafety.data.synthetic.synthetic_excitation(periods={periods:g}, "
                      f"dt={dt:g}, seed={seed}, noise={noise}, "
                      f"velocity_noise_var={[float(v) for v in vvar]})"}
    return MeasuredData(meta, pd.DataFrame(cols), source="synthetic_excitation")


__all__ = ["synthetic_static", "synthetic_tensile", "synthetic_excitation",
           "default_excitation", "VELOCITY_NOISE_VARIANCES"]
