"""Open-loop excitation for dynamic identification (thesis §3.5.2.4).

The valves are driven, without a position controller, by finite Fourier series
of the Delta-p inputs (one per joint, Delta-p approach (3.7))::

    Delta p_i(t) = Delta p_0,i + sum_{k=1}^{5} (a_k,i sin(k w0 t) + b_k,i cos(k w0 t)),
    w0 = 2 pi / 10 s

The thesis' series has no constant term.  On our plant Delta p = 0 holds the
arm at an equilibrium that need not be central, so we add a constant offset
Delta p_0 = the static gravity-compensation Delta-p of a centre configuration
(default: the middle of the working area); pass ``offset=(0, 0)`` for the pure
thesis form.  Desired pressures p_m +- Delta p become valve set values by
inverting the valve model (3.12).

:func:`design_excitation` chooses the coefficients by minimising the condition
number of the column-normalised K_f^T K_f (Otani & Kakizaki 1993), K_f from
the second of two simulated periods (the first holds the start transient),
subject to the working area and |qd_i| <= 2 rad/s, |qdd_i| <= 5 rad/s^2 (the
thesis' limits), as penalties.  The simulation assumes the plant known (as
the thesis had to assume its model).  Budget: a seeded random search over a
batch of candidates, then Nelder-Mead from the best; a few seconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..results import Result
from .._validation import check_int, check_range, check_seed, check_size
from ..plant.model import rest_state, simulate
from ..plant.pneumatics import delta_p_pressures, valve_set_values, gravity_compensation
from ..plots.identify import plot_excitation
from .dynamic import DynamicData, filtered_regressor

#: Thesis limits on the excitation response (§3.5.2.4).
VELOCITY_LIMIT = 2.0        # rad/s
ACCELERATION_LIMIT = 5.0    # rad/s^2


@dataclass(frozen=True)
class FourierExcitation:
    """Delta-p excitation: constant offset plus a finite Fourier series per joint.

    Attributes
    ----------
    a, b : numpy.ndarray, shape (H, 2)
        Sine and cosine coefficients of harmonic k = 1..H per joint [Pa].
    offset : numpy.ndarray, shape (2,)
        Constant Delta-p per joint [Pa].
    period : float
        Fundamental period [s] (10 s).
    """

    a: np.ndarray
    b: np.ndarray
    offset: np.ndarray
    period: float = 10.0

    def __post_init__(self):
        a = np.asarray(self.a, dtype=float)
        b = np.asarray(self.b, dtype=float)
        if a.ndim != 2 or a.shape[1] != 2 or b.shape != a.shape:
            raise ValueError(f"a and b must both have shape (H, 2), got {a.shape} and {b.shape}")
        off = np.asarray(self.offset, dtype=float)
        if off.shape != (2,):
            raise ValueError(f"offset must have shape (2,), got {off.shape}")
        for nm, v in (("a", a), ("b", b), ("offset", off)):
            if not np.all(np.isfinite(v)):
                raise ValueError(f"FourierExcitation.{nm} contains NaN or inf")
        object.__setattr__(self, "a", a)
        object.__setattr__(self, "b", b)
        object.__setattr__(self, "offset", off)
        object.__setattr__(self, "period", check_range("period", self.period, 0.0, 1e4,
                                                       lo_open=True, unit="s"))

    @property
    def harmonics(self) -> int:
        return self.a.shape[0]

    @property
    def amplitude_bound(self) -> np.ndarray:
        """Upper bound of |Delta p_i(t) - offset_i| per joint, sum_k sqrt(a^2 + b^2) [Pa]."""
        return np.hypot(self.a, self.b).sum(axis=0)

    def delta_p(self, t) -> np.ndarray:
        """Delta p(t) [Pa], shape (N, 2) for times ``t`` (N,) [s].

        Parameters
        ----------
        t : array_like
            Times [s]; flattened to shape (N,).
        """
        t = np.asarray(t, dtype=float).reshape(-1)
        k = np.arange(1, self.harmonics + 1)
        ph = 2.0 * math.pi / self.period * np.outer(t, k)
        return self.offset + np.sin(ph) @ self.a + np.cos(ph) @ self.b

    def set_values(self, t, arm) -> np.ndarray:
        """Valve set values [Pa], shape (N, 4): p_m +- Delta p (clipped), inverted (3.12).

        Parameters
        ----------
        t : array_like
            Times [s]; flattened to shape (N,).
        arm : ArmParameters
            Supplies the mean pressures, p_max and the valve statics (3.12).
        """
        return valve_set_values(delta_p_pressures(self.delta_p(t), arm), arm)

    def to_pandas(self) -> pd.DataFrame:
        """Coefficients per harmonic and joint [Pa]."""
        k = np.arange(1, self.harmonics + 1)
        return pd.DataFrame({"k": k, "a_k1_Pa": self.a[:, 0], "b_k1_Pa": self.b[:, 0],
                             "a_k2_Pa": self.a[:, 1], "b_k2_Pa": self.b[:, 1]}).set_index("k")

    def to_vector(self) -> np.ndarray:
        """[a.ravel(), b.ravel()] (design variables)."""
        return np.concatenate([self.a.ravel(), self.b.ravel()])

    @classmethod
    def from_vector(cls, x, offset, period: float = 10.0) -> "FourierExcitation":
        """Inverse of :meth:`to_vector`.

        Parameters
        ----------
        x : array_like, shape (4 H,)
            ``[a.ravel(), b.ravel()]`` with ``a``, ``b`` of shape (H, 2) [Pa].
        offset : array_like, shape (2,)
            Constant Delta-p per joint [Pa].
        period : float
            Fundamental period [s] (default 10 s).

        Raises
        ------
        ValueError
            If the size of ``x`` is not a positive multiple of 4 (and the
            validation of the constructor).
        """
        x = np.asarray(x, dtype=float)
        h = x.size // 4
        if x.size != 4 * h or h == 0:
            raise ValueError(f"x must have 4 H entries, got {x.size}")
        return cls(a=x[:2 * h].reshape(h, 2), b=x[2 * h:].reshape(h, 2), offset=offset, period=period)


def centre_configuration(arm) -> np.ndarray:
    """Middle of the working area (2.6)-(2.7) [rad].

    Parameters
    ----------
    arm : ArmParameters
        Supplies the joint limits ``arm.geometry.q1_min`` .. ``q2_max`` [rad].
    """
    g = arm.geometry
    return np.array([0.5 * (g.q1_min + g.q1_max), 0.5 * (g.q2_min + g.q2_max)])


def default_offset(arm, q_centre=None) -> np.ndarray:
    """Plant gravity-compensation Delta-p at ``q_centre`` (default the middle) [Pa].

    Computed with the plant's base parameters (``arm.plant_base``), shape (2,).

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    q_centre : array_like, shape (2,), optional
        Configuration [rad]; default :func:`centre_configuration`.
    """
    q = centre_configuration(arm) if q_centre is None else np.asarray(q_centre, dtype=float)
    return gravity_compensation(q, arm, params=arm.plant_base)


def amplitude_limit(arm, offset) -> np.ndarray:
    """Largest Fourier amplitude per joint keeping p_m +- Delta p inside [0, p_max] [Pa].

    min(p_m - |offset|, p_max - p_m - |offset|) per joint, shape (2,).

    Parameters
    ----------
    arm : ArmParameters
        Supplies the mean pressures p_m and p_max [Pa].
    offset : array_like, shape (2,)
        Constant Delta-p per joint [Pa].
    """
    pm = np.asarray(arm.pneumatics.p_mean, dtype=float)
    pmax = arm.pneumatics.p_max
    off = np.asarray(offset, dtype=float)
    return np.minimum(pm - np.abs(off), pmax - pm - np.abs(off))


def equilibrium_for(delta_p, arm, *, q_guess=None) -> np.ndarray:
    """Rest configuration held by constant Delta-p inputs (static equilibrium (3.13)) [rad].

    Solves Delta p_gc(q) = ``delta_p`` for q with the plant's exact
    gravity compensation (3.18)-(3.19) (the thesis computes its initial
    conditions this way, §3.5.2.4).

    Parameters
    ----------
    delta_p : array_like, shape (2,)
        Constant Delta-p per joint [Pa].
    arm : ArmParameters
    q_guess : array_like, shape (2,), optional, keyword-only
        Start of the search (default the centre configuration) [rad].
    """
    from scipy.optimize import fsolve


    dp = np.asarray(delta_p, dtype=float)
    if dp.shape != (2,) or not np.all(np.isfinite(dp)):
        raise ValueError(f"delta_p must be 2 finite values [Pa], got {delta_p!r}")
    q0 = centre_configuration(arm) if q_guess is None else np.asarray(q_guess, dtype=float)
    q, info, ier, msg = fsolve(lambda q: (gravity_compensation(q, arm, params=arm.plant_base) - dp) / 1e5,
                               q0, full_output=True, xtol=1e-13)
    if ier != 1:
        raise ValueError(f"delta_p = {dp} Pa: no static equilibrium found near {q0} rad ({msg})")
    return q


#: Memory of one sample of :func:`simulate_excitation` [bytes] (set values, states, the
#: record; 280 bytes measured with ``tracemalloc``, rounded up).
EXCITATION_BYTES_PER_SAMPLE = 400


def simulate_excitation(arm, excitation: FourierExcitation, *, periods: float = 2, dt: float = 1e-3,
                        substeps: int = 2, q0=None, name: str = "", discard_periods: int = 0,
                        with_qdd: bool = True) -> DynamicData:
    """Open-loop response of the plant to ``excitation`` as a :class:`DynamicData`.

    Starts at rest at ``q0`` with the pressures holding it
    (:func:`ppamsafety.plant.model.rest_state`); by default ``q0`` is the
    equilibrium of the initial input Delta p(0) (:func:`equilibrium_for`), so
    the record starts without a step (thesis §3.5.2.4).  The set values are
    sampled at the start of every interval and held (ZOH).

    Parameters
    ----------
    arm : ArmParameters
    excitation : FourierExcitation
    periods : float, keyword-only
        Simulated length in periods.
    dt : float, keyword-only
        Sample time [s].
    substeps : int, keyword-only
        RK4 steps per sample.
    q0 : array_like, optional, keyword-only
        Start configuration [rad] (default: equilibrium of Delta p(0)).
    name : str, keyword-only
        Record label.
    discard_periods : int, keyword-only
        Whole periods dropped from the start of the record (transients).
    with_qdd : bool, keyword-only
        Store the exact accelerations (for validation tests).
    """
    if not isinstance(excitation, FourierExcitation):
        raise TypeError(f"excitation must be a FourierExcitation, got {type(excitation).__name__}")
    periods = check_range("periods", periods, 0.0, 1e4, lo_open=True)
    dt = check_range("dt", dt, 1e-6, 1.0, unit="s")
    discard_periods = check_int("discard_periods", discard_periods, 0, 10 ** 6)
    n = int(round(periods * excitation.period / dt))
    check_size(f"periods = {periods:g} of {excitation.period:g} s at dt = {dt:g} s ({n:,} "
               f"samples)", n * EXCITATION_BYTES_PER_SAMPLE,
               remedy="simulate fewer periods or use a larger dt")
    if q0 is None:
        q0 = equilibrium_for(excitation.delta_p([0.0])[0], arm)
    x0, _ = rest_state(np.asarray(q0, dtype=float), arm)
    t = np.arange(n) * dt
    U = excitation.set_values(t, arm)
    X = simulate(arm, x0, U, dt=dt, substeps=substeps)[:n]
    k0 = int(round(discard_periods * excitation.period / dt))
    if k0 >= n:
        raise ValueError(f"discard_periods = {discard_periods} leaves no samples of {periods} periods")
    return DynamicData.from_states(X[k0:], arm, dt, name=name, with_qdd=with_qdd,
                                   set_values=U[k0:] if with_qdd else None)


@dataclass(frozen=True)
class ExcitationDesign(Result):
    """Result of :func:`design_excitation`.

    Attributes
    ----------
    excitation : FourierExcitation
        The optimised coefficients.
    condition_number : float
        cond of the column-normalised K_f^T K_f (second period).
    initial_condition_number : float
        The same for the best random candidate before local refinement.
    feasible : bool
        True if working area, velocity and acceleration limits hold.
    max_velocity, max_acceleration : numpy.ndarray, shape (2,)
        Peak |qd_i| [rad/s] and |qdd_i| [rad/s^2] over the second period.
    q_range : numpy.ndarray, shape (2, 2)
        [[q1_min, q1_max], [q2_min, q2_max]] reached [rad].
    evaluations : int
        Simulations run.
    """

    excitation: FourierExcitation
    condition_number: float
    initial_condition_number: float
    feasible: bool
    max_velocity: np.ndarray
    max_acceleration: np.ndarray
    q_range: np.ndarray
    evaluations: int

    def to_pandas(self) -> pd.DataFrame:
        """The Fourier coefficients [Pa] (achieved numbers in ``attrs``)."""
        df = self.excitation.to_pandas()
        df.attrs.update(condition_number=self.condition_number, feasible=self.feasible)
        return df

    def plot(self, arm=None):
        """Delta-p over one period per joint; returns a matplotlib Figure.

        Parameters
        ----------
        arm : ArmParameters, optional
            Not used: the curve depends on the excitation only.
        """
        t = np.linspace(0.0, self.excitation.period, 1001)
        return plot_excitation(t, self.excitation.delta_p(t), condition_number=self.condition_number)


def _metrics(X, dt, arm, n_period, friction, sign_velocity):
    """cond, violation (>= 0), max |qd|, max |qdd|, q range from states of 2 periods."""
    g = arm.geometry
    q, qd = X[:, :2], X[:, 2:4]
    Kf = filtered_regressor(q, qd, dt, arm, friction=friction, sign_velocity=sign_velocity)[-n_period:]
    A = np.concatenate([Kf[:, 0], Kf[:, 1]])
    nrm = np.linalg.norm(A, axis=0)
    if np.any(nrm == 0):
        cond = 1e16
    else:
        s = np.linalg.svd(A / nrm, compute_uv=False)
        cond = float((s[0] / s[-1]) ** 2) if s[-1] > 0 else 1e16
    q2, qd2 = q[-n_period:], qd[-n_period:]
    qdd2 = np.diff(qd[-n_period - 1:], axis=0) / dt
    vmax, amax = np.abs(qd2).max(axis=0), np.abs(qdd2).max(axis=0)
    lo, hi = np.array([g.q1_min, g.q2_min]), np.array([g.q1_max, g.q2_max])
    viol = (np.maximum(lo - q2.min(axis=0), 0).sum() + np.maximum(q2.max(axis=0) - hi, 0).sum()
            + np.maximum(vmax / VELOCITY_LIMIT - 1, 0).sum()
            + np.maximum(amax / ACCELERATION_LIMIT - 1, 0).sum())
    qr = np.stack([q2.min(axis=0), q2.max(axis=0)], axis=-1)
    return cond, float(viol), vmax, amax, qr


def design_excitation(arm, *, harmonics: int = 5, period: float = 10.0, friction: bool = True,
                      offset=None, n_random: int = 8, maxfev: int = 24, seed: int = 0,
                      dt: float = 2e-3, sign_velocity: float | None = None) -> ExcitationDesign:
    """Fourier Delta-p excitation minimising cond(normalised K_f^T K_f) (§3.5.2.4).

    Parameters
    ----------
    arm : ArmParameters
        The plant simulated for every candidate.
    harmonics : int, keyword-only
        N' (5).
    period : float, keyword-only
        Period [s] (10).
    friction : bool, keyword-only
        Regressor with or without friction (the thesis designed one of each).
    offset : array_like, shape (2,), optional, keyword-only
        Constant Delta-p [Pa]; default :func:`default_offset`.
    n_random : int, keyword-only
        Random candidates (one batched simulation).
    maxfev : int, keyword-only
        Simulations of the Nelder-Mead refinement.
    seed : int, keyword-only
        Seed of the random candidates.
    dt : float, keyword-only
        Sample time of the design simulations [s] (2 ms, RK4 at 1 ms).
    sign_velocity : float, optional, keyword-only
        Coulomb sign law of the regressor, see
        :func:`ppamsafety.identify.dynamic.regressor`.

    Returns
    -------
    ExcitationDesign
    """
    from scipy.optimize import minimize


    harmonics = check_int("harmonics", harmonics, 1, 50)
    check_range("period", period, 0.1, 1000.0, unit="s")
    n_random = check_int("n_random", n_random, 1, 10000)
    maxfev = check_int("maxfev", maxfev, 0, 100000)
    check_range("dt", dt, 1e-4, 0.01, unit="s")
    off = default_offset(arm) if offset is None else np.asarray(offset, dtype=float)
    if off.shape != (2,) or not np.all(np.isfinite(off)):
        raise ValueError(f"offset must be 2 finite Delta-p values [Pa], got {offset!r}")
    lim = amplitude_limit(arm, off)
    if np.any(lim <= 0):
        raise ValueError(f"offset = {off} Pa leaves no pressure range for the excitation")
    x0, _ = rest_state(centre_configuration(arm), arm)
    n_period = int(round(period / dt))
    t = np.arange(2 * n_period) * dt
    rng = np.random.default_rng(check_seed("seed", seed))
    nvar = 4 * harmonics

    def excitation_of(x):
        e = FourierExcitation.from_vector(x, off, period)
        bound = e.amplitude_bound
        scale = np.minimum(1.0, 0.98 * lim / np.maximum(bound, 1e-300))   # stay inside [0, p_max]
        return FourierExcitation(a=e.a * scale, b=e.b * scale, offset=off, period=period)

    def objective_from_states(X):
        if not np.all(np.isfinite(X)):
            return 1e6, (np.inf, np.inf, np.full(2, np.inf), np.full(2, np.inf), np.full((2, 2), np.nan))
        cond, viol, vmax, amax, qr = _metrics(X, dt, arm, n_period, friction, sign_velocity)
        return math.log10(cond) + 100.0 * viol, (cond, viol, vmax, amax, qr)

    count = [0]

    def run(xs):
        U = np.stack([excitation_of(x).set_values(t, arm) for x in xs])
        count[0] += len(xs)
        X = simulate(arm, x0, U, dt=dt, substeps=max(1, int(round(dt / 1e-3))))
        return X if X.ndim == 3 else X[None]

    # random candidates: amplitudes falling off as 1/k keep accelerations bounded
    kscale = np.repeat(1.0 / np.arange(1, harmonics + 1), 2)
    cand = rng.normal(size=(n_random, nvar)) * np.tile(kscale, 2) * np.tile(lim, 2 * harmonics) * 0.3
    Xs = run(list(cand))
    scores = [objective_from_states(X[:-1])[0] for X in Xs]
    best = int(np.argmin(scores))
    x_best, f0 = cand[best], scores[best]
    cond0 = objective_from_states(Xs[best][:-1])[1][0]

    if maxfev > 0:
        step = 1e4                                                   # Pa: design variables in 0.1 bar
        sol = minimize(lambda z: objective_from_states(run([z * step])[0, :-1])[0], x_best / step,
                       method="Nelder-Mead", options={"maxfev": maxfev, "xatol": 1e-3, "fatol": 1e-4})
        if sol.fun < f0:
            x_best = sol.x * step
    exc = excitation_of(x_best)
    X = run([x_best])[0]
    _, (cond, viol, vmax, amax, qr) = objective_from_states(X[:-1])
    return ExcitationDesign(excitation=exc, condition_number=float(cond),
                            initial_condition_number=float(cond0), feasible=bool(viol == 0.0),
                            max_velocity=vmax, max_acceleration=amax, q_range=qr,
                            evaluations=count[0])


__all__ = ["FourierExcitation", "ExcitationDesign", "design_excitation", "simulate_excitation",
           "centre_configuration", "default_offset", "equilibrium_for", "amplitude_limit", "VELOCITY_LIMIT",
           "ACCELERATION_LIMIT"]
