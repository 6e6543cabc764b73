"""Static identification (thesis §3.5.1): muscle force law, valves, gravity terms.

All three problems are linear in their parameters and solved by (weighted)
least squares with standard errors and confidence intervals
(:func:`ppamsafety.identify.lsq.solve`):

* **Muscle** (3.8)-(3.11): ``F = p (a0/eps + a1 + a2 eps + a3 eps^2 + a4 eps^3)
  = D(p, eps) a`` with D = [p/eps, p, p eps, p eps^2, p eps^3]; one muscle
  (group) at a time, a in N/Pa (= m^2; Table B.1 prints N/bar = 1e-5 N/Pa).
* **Valve** (3.12): ``p = v1 + v2 p_s = [1, p_s] v`` per valve, v1 in Pa.
* **Gravity** (3.13)-(3.16): at rest ``G(q) = K(q) theta = tau`` with the 2x4
  regressor of (3.15) and the static gravity parameters (Table 3.1, in the
  thesis' order)::

      theta = [m1 L_G1 + m2 L1, m2 L_G2, m2 d_G2, m1 d_G1]      [kg m]

  N equilibria give 2N stacked equations.  tau comes from the muscle forces
  through the lever arms (3.17), :func:`torques_from_forces`, or from the
  pressures through the torque functions (2.17).

:func:`static_experiment` generates the §3.5.1.4 data set synthetically from
the plant (equilibria held by the plant's exact static pressures, measured
with seeded noise), for tests and for the discrepancy workflow.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .._validation import check_int, check_nonnegative, check_range, check_seed
from ..params.inertia import BaseParameters
from ..plant.geometry import lever_arms, contractions
from ..plant.muscle import force_function
from ..plant.pneumatics import static_pressures, valve_set_values
from .lsq import LSQResult, as_samples, same_length, solve

#: Names, units of the static gravity parameters in the order of (3.15) / Table 3.1.
GRAVITY_NAMES = ("m1 L_G1 + m2 L1", "m2 L_G2", "m2 d_G2", "m1 d_G1")
GRAVITY_UNITS = ("kg m",) * 4
#: The matching fields of :class:`ppamsafety.params.inertia.BaseParameters`.
GRAVITY_FIELDS = ("m1LG1_m2L1", "m2LG2", "m2dG2", "m1dG1")
MUSCLE_NAMES = ("a0", "a1", "a2", "a3", "a4")
MUSCLE_UNITS = ("N/Pa",) * 5
VALVE_NAMES = ("v1", "v2")
VALVE_UNITS = ("Pa", "-")

#: Measurement noise variances of the muscle forces F1..F4 [N^2], Table 3.2 (first signal).
FORCE_NOISE_VARIANCES = (0.51, 1.02, 0.59, 0.45)
#: Measurement noise variances of q1, q2 [rad^2], Table 3.2 (first signal).
ANGLE_NOISE_VARIANCES = (3.46e-6, 2.59e-6)
#: Pressure-sensor noise standard deviation [Pa].  Not tabulated in the thesis;
#: 500 Pa = 5 mbar, 0.17 % of the 3 bar range, typical of a piezo-resistive
#: transducer (our choice).
PRESSURE_NOISE_STD = 500.0


def muscle_regressor(pressure, contraction) -> np.ndarray:
    """Regressor D(p, eps) of (3.10), shape (N, 5) [Pa].

    Parameters
    ----------
    pressure : array_like, shape (N,)
        Gauge pressures [Pa].
    contraction : array_like, shape (N,)
        Contractions eps (> 0) [-].
    """
    p = as_samples("pressure", pressure)
    e = as_samples("contraction", contraction)
    same_length(pressure=p, contraction=e)
    if np.any(e <= 0.0):
        raise ValueError(f"contraction must be > 0 (the force law has a 1/eps term), "
                         f"got min {e.min():g}")
    return np.stack([p / e, p, p * e, p * e ** 2, p * e ** 3], axis=-1)


def identify_muscle(force, pressure, contraction, *, confidence: float = 0.95) -> LSQResult:
    """Least-squares coefficients a0..a4 of the muscle force law (3.9)-(3.11).

    Parameters
    ----------
    force : array_like, shape (N,)
        Measured muscle forces [N].
    pressure : array_like, shape (N,)
        Measured gauge pressures [Pa].
    contraction : array_like, shape (N,)
        Contractions eps [-], > 0.
    confidence : float, keyword-only
        Level of the confidence intervals.

    Returns
    -------
    LSQResult
        Estimates in N/Pa (multiply by 1e5 for Table B.1's N/bar).  Noise in
        ``pressure``/``contraction`` biases the estimate (thesis §3.5.1.1); the
        intervals assume errors in ``force`` only.
    """
    F = as_samples("force", force)
    D = muscle_regressor(pressure, contraction)
    same_length(force=F, pressure=D)
    return solve(D, F, names=MUSCLE_NAMES, units=MUSCLE_UNITS, confidence=confidence,
                 method="LS muscle (3.10)", quantity="force [N]", what="identify_muscle")


def identify_valve(set_value, pressure, *, confidence: float = 0.95) -> LSQResult:
    """Least-squares static valve model p = v1 + v2 p_s (3.12) of one valve.

    Parameters
    ----------
    set_value : array_like, shape (N,)
        Valve set values p_s [Pa].
    pressure : array_like, shape (N,)
        Measured gauge pressures [Pa].
    confidence : float, keyword-only
        Level of the confidence intervals.

    Returns
    -------
    LSQResult
        v1 [Pa] and v2 [-].
    """
    ps = as_samples("set_value", set_value)
    p = as_samples("pressure", pressure)
    same_length(set_value=ps, pressure=p)
    E = np.stack([np.ones_like(ps), ps], axis=-1)
    return solve(E, p, names=VALVE_NAMES, units=VALVE_UNITS, confidence=confidence,
                 method="LS valve (3.12)", quantity="pressure [Pa]", what="identify_valve")


def identify_valves(set_values, pressures, *, confidence: float = 0.95) -> tuple:
    """:func:`identify_valve` for the four valves at once.

    Parameters
    ----------
    set_values : array_like, shape (N, 4)
        Set values of valves 1..4 [Pa].
    pressures : array_like, shape (N, 4)
        Measured gauge pressures of groups 1..4 [Pa].
    confidence : float, keyword-only
        Level of the confidence intervals.

    Returns
    -------
    tuple of 4 LSQResult
    """
    ps = as_samples("set_values", set_values, ncols=4, ndim=2)
    p = as_samples("pressures", pressures, ncols=4, ndim=2)
    same_length(set_values=ps, pressures=p)
    return tuple(identify_valve(ps[:, i], p[:, i], confidence=confidence) for i in range(4))


def gravity_regressor(q, *, gravity_acc: float = 9.81) -> np.ndarray:
    """K(q) of (3.15), shape (N, 2, 4) [m/s^2]: G(q) = K(q) theta.

    Parameters
    ----------
    q : array_like, shape (N, 2)
        Joint angles [rad].
    gravity_acc : float, keyword-only
        g [m/s^2].
    """
    q = as_samples("q", q, ncols=2, ndim=2)
    g = check_range("gravity_acc", gravity_acc, 0.0, 30.0, lo_open=True, unit="m/s^2")
    q1, q12 = q[:, 0], q[:, 0] + q[:, 1]
    K = np.zeros((q.shape[0], 2, 4))
    K[:, 0, 0] = g * np.cos(q1)
    K[:, 0, 1] = K[:, 1, 1] = g * np.cos(q12)
    K[:, 0, 2] = K[:, 1, 2] = g * np.sin(q12)
    K[:, 0, 3] = g * np.sin(q1)
    return K


def torques_from_forces(q, forces, arm) -> np.ndarray:
    """Joint torques (3.17) from measured muscle forces [N m], shape (N, 2).

    tau_1 = F1 h1(q) + F2 h2(q), tau_2 = F3 h3(q) + F4 h4(q) with the lever
    arms h_i = (e_i x OA_i) . 1_z of the known geometry (A.1)-(A.4).

    Parameters
    ----------
    q : array_like, shape (N, 2)
        Joint angles [rad].
    forces : array_like, shape (N, 4)
        Forces of muscle groups 1..4 [N].
    arm : ArmParameters
        Supplies the geometry.
    """
    q = as_samples("q", q, ncols=2, ndim=2)
    F = as_samples("forces", forces, ncols=4, ndim=2)
    same_length(q=q, forces=F)
    t = F * lever_arms(q, arm)
    return np.stack([t[:, 0] + t[:, 1], t[:, 2] + t[:, 3]], axis=-1)


def _joint_weights(resid: np.ndarray, n: int) -> np.ndarray:
    """Row weights 1/s_j^2 from the per-joint residual variance (rows alternate j = 1, 2)."""
    r = resid.reshape(n, 2)
    var = np.mean(r ** 2, axis=0)
    if np.any(var <= 0):
        return np.ones(2 * n)
    return np.tile(1.0 / var, n)


def identify_gravity(q, tau, *, gravity_acc: float = 9.81, weighting: str = "none",
                     confidence: float = 0.95) -> LSQResult:
    """Static gravity parameters (3.13)-(3.16) from N equilibrium points.

    Parameters
    ----------
    q : array_like, shape (N, 2)
        Measured joint angles at rest [rad].
    tau : array_like, shape (N, 2)
        Joint torques holding the arm there [N m] (:func:`torques_from_forces`
        or :func:`ppamsafety.plant.torque.joint_torques`).
    gravity_acc : float, keyword-only
        g [m/s^2].
    weighting : {"none", "joint"}, keyword-only
        ``"none"``: ordinary LS of the 2N stacked equations (the thesis).
        ``"joint"``: two-step WLS with weights 1/s_j^2 from the per-joint
        residual variance of the first LS pass.
    confidence : float, keyword-only
        Level of the confidence intervals.

    Returns
    -------
    LSQResult
        theta = [m1 L_G1 + m2 L1, m2 L_G2, m2 d_G2, m1 d_G1] [kg m]
        (:data:`GRAVITY_NAMES`); see :func:`gravity_base_parameters`.
    """
    if weighting not in ("none", "joint"):
        raise ValueError(f"weighting = {weighting!r} is not one of 'none', 'joint'")
    K = gravity_regressor(q, gravity_acc=gravity_acc)
    t = as_samples("tau", tau, ncols=2, ndim=2)
    n = same_length(q=K, tau=t)
    A, y = K.reshape(2 * n, 4), t.reshape(2 * n)
    kw = dict(names=GRAVITY_NAMES, units=GRAVITY_UNITS, confidence=confidence,
              quantity="torque [N m]", what="identify_gravity")
    res = solve(A, y, method="LS gravity (3.16)", **kw)
    if weighting == "joint":
        res = solve(A, y, weights=_joint_weights(res.residuals, n), method="WLS gravity (3.16)", **kw)
    return res


def gravity_base_parameters(result: LSQResult, template):
    """A copy of ``template`` (BaseParameters) with the identified gravity terms.

    Parameters
    ----------
    result : LSQResult
        From :func:`identify_gravity`.
    template : BaseParameters
        Supplies the inertial and friction entries the static experiment
        cannot identify.
    """
    if not isinstance(result, LSQResult) or result.names != GRAVITY_NAMES:
        raise TypeError("result must be the LSQResult of identify_gravity")
    if not isinstance(template, BaseParameters):
        raise TypeError(f"template must be a BaseParameters, got {type(template).__name__}")
    return template.replace(**{f: float(v) for f, v in zip(GRAVITY_FIELDS, result.estimates)})


def true_gravity_parameters(base) -> np.ndarray:
    """The four static gravity parameters of a BaseParameters, in the order of (3.15).

    Parameters
    ----------
    base : BaseParameters
        Base parameters; the fields ``GRAVITY_FIELDS`` (m1 L_G1 + m2 L1,
        m2 L_G2, m2 d_G2, m1 d_G1) [kg m] are read.
    """
    return np.array([getattr(base, f) for f in GRAVITY_FIELDS])


def _holdable(q, arm) -> np.ndarray:
    """True where the static pressures and the set values delivering them are in [0, p_max]."""
    pmax = arm.pneumatics.p_max
    p = static_pressures(q, arm)
    v1 = np.array([v.v1 for v in arm.valves.valves])
    v2 = np.array([v.v2 for v in arm.valves.valves])
    ps = (p - v1) / v2
    return np.all((p >= 0) & (p <= pmax) & (ps >= 0) & (ps <= pmax), axis=1)


def equilibrium_configurations(arm, n: int = 31, *, seed: int = 0, margin: float = 0.05) -> np.ndarray:
    """``n`` rest configurations spread over the working area that the plant can hold.

    Stratified sampling: a jittered grid over the working area (2.6)-(2.7),
    shrunk by ``margin`` of each range on both sides, keeping points whose
    static Delta-p pressures (:func:`ppamsafety.plant.pneumatics.static_pressures`)
    and the valve set values delivering them (3.12) lie in [0, p_max] (no
    clipping anywhere); the first ``n`` in a seeded random order.

    Parameters
    ----------
    arm : ArmParameters
    n : int
        Number of configurations (31 in §3.5.1.4).
    seed : int, keyword-only
        Seed of the jitter and order.
    margin : float, keyword-only
        Fraction of each joint range kept free at both ends.

    Returns
    -------
    numpy.ndarray, shape (n, 2) [rad]
    """
    n = check_int("n", n, 1, 10000)
    check_range("margin", margin, 0.0, 0.45)
    rng = np.random.default_rng(check_seed("seed", seed))
    g = arm.geometry
    m = int(np.ceil(np.sqrt(4 * n)))
    lo = np.array([g.q1_min, g.q2_min])
    hi = np.array([g.q1_max, g.q2_max])
    lo, hi = lo + margin * (hi - lo), hi - margin * (hi - lo)
    ij = np.stack(np.meshgrid(np.arange(m), np.arange(m), indexing="ij"), -1).reshape(-1, 2)
    q = lo + (ij + rng.uniform(size=ij.shape)) / m * (hi - lo)
    ok = _holdable(q, arm)
    q = q[ok][rng.permutation(int(ok.sum()))]
    if q.shape[0] < n:
        raise ValueError(f"n = {n}: only {q.shape[0]} holdable configurations found")
    return q[:n]


@dataclass(frozen=True)
class StaticExperiment:
    """A synthetic §3.5.1.4 data set (one reading per equilibrium point).

    Attributes
    ----------
    q_true, q : numpy.ndarray, shape (N, 2)
        True and measured joint angles [rad].
    set_values : numpy.ndarray, shape (N, 4)
        Valve set values [Pa].
    pressures_true, pressures : numpy.ndarray, shape (N, 4)
        True and measured gauge pressures [Pa].
    forces_true, forces : numpy.ndarray, shape (N, 4)
        True and measured muscle forces [N].
    contractions : numpy.ndarray, shape (N, 4)
        Contractions computed from the *measured* angles [-].
    tau : numpy.ndarray, shape (N, 2)
        Torques (3.17) from measured forces and measured angles [N m].
    """

    q_true: np.ndarray
    q: np.ndarray
    set_values: np.ndarray
    pressures_true: np.ndarray
    pressures: np.ndarray
    forces_true: np.ndarray
    forces: np.ndarray
    contractions: np.ndarray
    tau: np.ndarray

    def to_pandas(self) -> pd.DataFrame:
        """One row per equilibrium point, measured signals, SI units."""
        cols = {"q1_rad": self.q[:, 0], "q2_rad": self.q[:, 1],
                "tau1_Nm": self.tau[:, 0], "tau2_Nm": self.tau[:, 1]}
        for i in range(4):
            cols[f"ps{i + 1}_Pa"] = self.set_values[:, i]
            cols[f"p{i + 1}_Pa"] = self.pressures[:, i]
            cols[f"F{i + 1}_N"] = self.forces[:, i]
            cols[f"eps{i + 1}"] = self.contractions[:, i]
        return pd.DataFrame(cols)


def static_experiment(arm, q, *, seed: int = 0, noise: bool = True,
                      force_noise_var=FORCE_NOISE_VARIANCES,
                      angle_noise_var=ANGLE_NOISE_VARIANCES,
                      pressure_noise_std: float = PRESSURE_NOISE_STD) -> StaticExperiment:
    """Synthetic static experiment: the plant held at rest in each ``q``.

    Truth: the plant's exact static Delta-p pressures
    (:func:`ppamsafety.plant.pneumatics.static_pressures`), the set values
    that deliver them through the valve model (3.12), the muscle forces
    p f(eps(q)) of the plant's force law.  Measurements add independent
    zero-mean Gaussian noise (seeded): angles and forces with the Table 3.2
    variances, pressures with ``pressure_noise_std``.  Contractions and
    torques (3.17) are computed from the *measured* angles, as on the real
    rig (errors in variables).

    Parameters
    ----------
    arm : ArmParameters
    q : array_like, shape (N, 2)
        Rest configurations [rad] (e.g. :func:`equilibrium_configurations`).
    seed : int, keyword-only
        Seed of the noise generator.
    noise : bool, keyword-only
        False gives exact measurements.
    force_noise_var : sequence of 4 float, keyword-only
        Variances of F1..F4 [N^2].
    angle_noise_var : sequence of 2 float, keyword-only
        Variances of q1, q2 [rad^2].
    pressure_noise_std : float, keyword-only
        Standard deviation of the pressure readings [Pa].

    Returns
    -------
    StaticExperiment
    """
    q = as_samples("q", q, ncols=2, ndim=2)
    fv = np.asarray(force_noise_var, dtype=float)
    av = np.asarray(angle_noise_var, dtype=float)
    if fv.shape != (4,) or np.any(~np.isfinite(fv)) or np.any(fv < 0):
        raise ValueError(f"force_noise_var must be 4 finite non-negative variances [N^2], got {force_noise_var!r}")
    if av.shape != (2,) or np.any(~np.isfinite(av)) or np.any(av < 0):
        raise ValueError(f"angle_noise_var must be 2 finite non-negative variances [rad^2], got {angle_noise_var!r}")
    check_nonnegative("pressure_noise_std", pressure_noise_std, unit="Pa")
    p = static_pressures(q, arm)
    ok = _holdable(q, arm)
    if not ok.all():
        bad = int(np.flatnonzero(~ok)[0])
        raise ValueError(f"q[{bad}] = {q[bad]} rad cannot be held: static pressures {p[bad]} Pa "
                         f"or their set values are outside [0, {arm.pneumatics.p_max:g}] Pa")
    ps = valve_set_values(p, arm)
    eps_true = contractions(q, arm)
    F = p * np.stack([force_function(i + 1, eps_true[:, i], arm) for i in range(4)], axis=-1)
    rng = np.random.default_rng(check_seed("seed", seed))
    n = q.shape[0]
    if noise:
        qm = q + rng.normal(size=(n, 2)) * np.sqrt(av)
        Fm = F + rng.normal(size=(n, 4)) * np.sqrt(fv)
        pm = p + rng.normal(size=(n, 4)) * pressure_noise_std
    else:
        qm, Fm, pm = q.copy(), F.copy(), p.copy()
    return StaticExperiment(q_true=q, q=qm, set_values=ps, pressures_true=p, pressures=pm,
                            forces_true=F, forces=Fm, contractions=contractions(qm, arm),
                            tau=torques_from_forces(qm, Fm, arm))


__all__ = ["muscle_regressor", "identify_muscle", "identify_valve", "identify_valves",
           "gravity_regressor", "torques_from_forces", "identify_gravity",
           "gravity_base_parameters", "true_gravity_parameters", "equilibrium_configurations",
           "StaticExperiment", "static_experiment", "GRAVITY_NAMES", "GRAVITY_FIELDS",
           "MUSCLE_NAMES", "VALVE_NAMES", "FORCE_NOISE_VARIANCES", "ANGLE_NOISE_VARIANCES",
           "PRESSURE_NOISE_STD"]
