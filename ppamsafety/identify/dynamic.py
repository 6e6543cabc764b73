"""Dynamic identification (thesis §3.5.2, Appendix B.3-B.5) without accelerations.

Model (3.29), linear in the base parameters (B.6)::

    H(q) qdd + C(q, qd) qd + G(q) + c sgn(qd) + b qd = K(q, qd, qdd) theta = tau

theta = [m1 L_G1 + m2 L1, m1 d_G1, I_zO,1 + m2 L1^2, m2 L_G2, m2 d_G2, I_zS,2,
c1, c2, b1, b2]; without friction only the first six.  K is
:func:`ppamsafety.plant.dynamics.regressor`.

**Acceleration-free filtering** (3.21)-(3.28), Slotine & Li.  Write (B.4)::

    H qd = W1(q, qd) theta,   Hdot qd = W2(q, qd) theta,
    C qd + G + tau_f = W3(q, qd) theta

so that K theta = d/dt(W1 theta) - W2 theta + W3 theta.  Filtering with
F(s) = 1/(s/omega + 1) and using s F(s) = omega (1 - F(s)) gives (3.26)::

    <K theta>_F = [omega (W1 - <W1>_F) + <W3 - W2>_F] theta = K_f(q, qd) theta

which is the thesis' omega W1 + <W3 - W2>_F + <W1>_{F2} with F2 = -omega F
(3.25).  The same F is applied to the torques, <tau>_F, and the first R = 300
filtered samples (transients of the zero initial filter state) are dropped
(B.7).  The exact identity needs qd(0) = 0 (the thesis' assumption, met when a
record starts at rest); otherwise the dropped R samples absorb the transient
omega exp(-omega t) H(q0) qd(0).

**Discretisation.** Bilinear (Tustin) transform of F at the sample time T::

    F(z) = b0 (1 + z^-1) / (1 - a1 z^-1),  b0 = omega T/(2 + omega T),
    a1 = (2 - omega T)/(2 + omega T)

Under this substitution s F(s) = omega (1 - F(s)) stays an exact identity in
z, with s replaced by the trapezoidal (Tustin) derivative; so the discrete
K_f theta equals the discrete filtering of d/dt(W1 theta) taken as the
trapezoidal derivative.  Against filtering the exact K(q, qd, qdd) theta the
discrepancy is the trapezoid-rule error, relative size (w T)^2/12 for a signal
component of angular frequency w (8e-7 at 0.5 Hz, 8e-5 at 5 Hz).

**Estimators** (§3.5.2.6): LS on the stacked 2(N - R) filtered equations, and
two-step WLS with weights 1/s_j^2 from the per-joint variance of the LS
residuals (the role of Table 3.3).  The filtered residuals are strongly
autocorrelated (bandwidth 5 Hz at 1 kHz sampling), so the textbook standard
errors reported are optimistic by roughly sqrt(correlation length); they are
a relative measure of identifiability here, not calibrated intervals.

**Validation** (§3.5.2.7, Table 3.4): mean squared torque error per joint,
averaged over both joints, with accelerations from a zero-phase low-pass of
the velocity and central differences (Pham et al. 2001; Gautier 1997).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..results import Result
from .._validation import check_int, check_range
from ..params.inertia import BaseParameters
from ..plant.dynamics import regressor as plant_regressor
from ..plant.model import state_derivative
from ..plant.torque import joint_torques
from .lsq import LSQResult, as_samples, same_length, solve

#: Filter cut-off of (3.21): 5 Hz, omega = 10 pi rad/s.
FILTER_OMEGA = 10.0 * math.pi
#: Filtered samples dropped at the start of every record (B.7).
DROP_SAMPLES = 300

DYNAMIC_NAMES = ("m1 L_G1 + m2 L1", "m1 d_G1", "I_zO,1 + m2 L1^2", "m2 L_G2", "m2 d_G2", "I_zS,2",
                 "c1", "c2", "b1", "b2")
DYNAMIC_UNITS = ("kg m", "kg m", "kg m^2", "kg m", "kg m", "kg m^2",
                 "N m", "N m", "N m s/rad", "N m s/rad")


def _nparams(friction: bool) -> int:
    return 10 if friction else 6


def _sign(w, sign_velocity):
    return np.sign(w) if sign_velocity is None else np.tanh(w / sign_velocity)


def _check_sign_velocity(sign_velocity):
    if sign_velocity is not None:
        check_range("sign_velocity", sign_velocity, 0.0, 10.0, lo_open=True, unit="rad/s")


def regressor(q, qd, qdd, arm, *, friction: bool = True, sign_velocity: float | None = None,
              gravity_acc: float | None = None) -> np.ndarray:
    """K(q, qd, qdd) of (B.5)/(B.6), shape (N, 2, 10) or (N, 2, 6) without friction.

    Parameters
    ----------
    q, qd, qdd : array_like, shape (N, 2)
        Joint angles [rad], velocities [rad/s], accelerations [rad/s^2].
    arm : ArmParameters
        Supplies L1 and g.
    friction : bool, keyword-only
        Include Coulomb + viscous friction (3.30) (columns c1, c2, b1, b2).
    sign_velocity : float, optional, keyword-only
        None: ideal sgn(qd) in the Coulomb columns (3.30).  A value v_s [rad/s]
        uses tanh(qd/v_s), the plant's smooth Coulomb law
        (``arm.friction_velocity``).
    gravity_acc : float, optional, keyword-only
        g [m/s^2]; default ``arm.gravity``.
    """
    q = as_samples("q", q, ncols=2, ndim=2)
    qd = as_samples("qd", qd, ncols=2, ndim=2)
    qdd = as_samples("qdd", qdd, ncols=2, ndim=2)
    same_length(q=q, qd=qd, qdd=qdd)
    _check_sign_velocity(sign_velocity)
    K = plant_regressor(q, qd, qdd, arm, gravity_acc=gravity_acc)
    if not friction:
        return K[..., :6]
    if sign_velocity is not None:
        K[:, 0, 6] = _sign(qd[:, 0], sign_velocity)
        K[:, 1, 7] = _sign(qd[:, 1], sign_velocity)
    return K


def w_matrices(q, qd, arm, *, friction: bool = True, sign_velocity: float | None = None,
               gravity_acc: float | None = None):
    """W1, W2, W3 of Appendix B.4 (B.4.1 with friction), each shape (N, 2, p).

    H qd = W1 theta, Hdot qd = W2 theta, C qd + G + tau_f = W3 theta.

    Parameters
    ----------
    q, qd : array_like, shape (N, 2)
        Joint angles [rad] and velocities [rad/s].
    arm : ArmParameters
    friction, sign_velocity, gravity_acc
        As in :func:`regressor`.

    Returns
    -------
    tuple of 3 numpy.ndarray
    """
    q = as_samples("q", q, ncols=2, ndim=2)
    qd = as_samples("qd", qd, ncols=2, ndim=2)
    same_length(q=q, qd=qd)
    p = _nparams(friction)
    l1 = arm.geometry.L1
    c2, s2 = np.cos(q[:, 1]), np.sin(q[:, 1])
    w1, w2 = qd[:, 0], qd[:, 1]
    n = q.shape[0]
    W1 = np.zeros((n, 2, p))
    W1[:, 0, 2] = w1
    W1[:, 0, 3] = (2 * w1 + w2) * c2 * l1
    W1[:, 0, 4] = (2 * w1 + w2) * s2 * l1
    W1[:, 0, 5] = W1[:, 1, 5] = w1 + w2
    W1[:, 1, 3] = w1 * c2 * l1
    W1[:, 1, 4] = w1 * s2 * l1
    W2 = np.zeros((n, 2, p))
    W2[:, 0, 3] = -w2 * (2 * w1 + w2) * s2 * l1
    W2[:, 0, 4] = w2 * (2 * w1 + w2) * c2 * l1
    W2[:, 1, 3] = -w1 * w2 * s2 * l1
    W2[:, 1, 4] = w1 * w2 * c2 * l1
    W3 = regressor(q, qd, np.zeros_like(q), arm, friction=friction, sign_velocity=sign_velocity,
                   gravity_acc=gravity_acc)
    return W1, W2, W3


#: Shortest sample time of the identification filters [s] (1 MHz sampling; also the
#: shortest step of :func:`ppamsafety.plant.model.simulate`).
DT_MIN = 1e-6


def filter_coefficients(dt: float, omega: float = FILTER_OMEGA):
    """Bilinear (Tustin) discretisation (b, a) of F(s) = 1/(s/omega + 1) for ``lfilter``.

    Parameters
    ----------
    dt : float
        Sample time [s].
    omega : float
        Cut-off [rad/s].
    """
    dt = check_range("dt", dt, DT_MIN, 1.0, unit="s")
    omega = check_range("omega", omega, 0.0, math.pi / dt, lo_open=True, hi_open=True, unit="rad/s")
    wt = omega * dt
    b0 = wt / (2.0 + wt)
    return np.array([b0, b0]), np.array([1.0, -(2.0 - wt) / (2.0 + wt)])


def filter_signal(x, dt: float, omega: float = FILTER_OMEGA) -> np.ndarray:
    """<x>_F: ``x`` filtered along axis 0 by the discretised F (zero initial state).

    Parameters
    ----------
    x : array_like, shape (N, ...)
        Samples at spacing ``dt``.
    dt : float
        Sample time [s].
    omega : float
        Cut-off [rad/s].
    """
    from scipy.signal import lfilter

    b, a = filter_coefficients(dt, omega)
    return lfilter(b, a, np.asarray(x, dtype=float), axis=0)


def filtered_regressor(q, qd, dt: float, arm, *, friction: bool = True,
                       sign_velocity: float | None = None, omega: float = FILTER_OMEGA,
                       gravity_acc: float | None = None) -> np.ndarray:
    """K_f(q, qd) of (3.26)-(3.27), shape (N, 2, p), no accelerations needed.

    K_f = omega (W1 - <W1>_F) + <W3 - W2>_F (see the module docstring).

    Parameters
    ----------
    q, qd : array_like, shape (N, 2)
        Sampled joint angles [rad] and velocities [rad/s] (record starting at
        rest for an exact first sample).
    dt : float
        Sample time [s].
    arm : ArmParameters
    friction, sign_velocity, gravity_acc
        As in :func:`regressor`.
    omega : float, keyword-only
        Filter cut-off [rad/s] (10 pi).
    """
    W1, W2, W3 = w_matrices(q, qd, arm, friction=friction, sign_velocity=sign_velocity,
                            gravity_acc=gravity_acc)
    # one filter pass over [W1 | W3 - W2]
    both = filter_signal(np.concatenate([W1, W3 - W2], axis=-1), dt, omega)
    p = W1.shape[-1]
    return omega * (W1 - both[..., :p]) + both[..., p:]


@dataclass(frozen=True)
class DynamicData:
    """One sampled record for dynamic identification or validation.

    Attributes
    ----------
    q, qd : numpy.ndarray, shape (N, 2)
        Joint angles [rad] and velocities [rad/s].
    tau : numpy.ndarray, shape (N, 2)
        Joint torques [N m] (from forces (3.17) or pressures (2.17)).
    dt : float
        Sample time [s].
    name : str
        Label (e.g. ``"ES 1"``), used by :func:`validation_table`.
    qdd : numpy.ndarray or None, shape (N, 2)
        Accelerations [rad/s^2] if known (simulation); validation estimates
        them otherwise.  Never used for identification.
    """

    q: np.ndarray
    qd: np.ndarray
    tau: np.ndarray
    dt: float
    name: str = ""
    qdd: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self):
        for nm in ("q", "qd", "tau"):
            object.__setattr__(self, nm, as_samples(f"DynamicData.{nm}", getattr(self, nm),
                                                    ncols=2, ndim=2))
        kw = dict(q=self.q, qd=self.qd, tau=self.tau)
        if self.qdd is not None:
            object.__setattr__(self, "qdd", as_samples("DynamicData.qdd", self.qdd, ncols=2, ndim=2))
            kw["qdd"] = self.qdd
        same_length(**{f"DynamicData.{k}": v for k, v in kw.items()})
        object.__setattr__(self, "dt", check_range("DynamicData.dt", self.dt, 0.0, 1.0,
                                                   lo_open=True, unit="s"))
        if not isinstance(self.name, str):
            raise TypeError(f"DynamicData.name must be a str, got {type(self.name).__name__}")

    def __len__(self) -> int:
        return self.q.shape[0]

    @classmethod
    def from_states(cls, states, arm, dt: float, *, name: str = "", with_qdd: bool = True,
                    set_values=None) -> "DynamicData":
        """Record from plant states (:func:`ppamsafety.plant.model.simulate`).

        tau = joint torques (2.17) of the simulated pressures.  With
        ``with_qdd`` the exact accelerations from the plant's state derivative
        are stored (needs ``set_values``, shape (N, 4) or (N - 1, 4); the last
        input is held for the final state).

        Parameters
        ----------
        states : array_like, shape (N, 8)
        arm : ArmParameters
        dt : float
            Sample time [s].
        name : str, keyword-only
        with_qdd : bool, keyword-only
        set_values : array_like, optional, keyword-only
        """
        X = as_samples("states", states, ncols=8, ndim=2)
        qdd = None
        if with_qdd:
            if set_values is None:
                raise ValueError("from_states: with_qdd=True needs set_values")

            U = as_samples("set_values", set_values, ncols=4, ndim=2)
            if U.shape[0] == X.shape[0] - 1:
                U = np.vstack([U, U[-1:]])
            same_length(states=X, set_values=U)
            qdd = state_derivative(X, U, arm)[:, 2:4]
        return cls(q=X[:, :2], qd=X[:, 2:4], tau=joint_torques(X[:, :2], X[:, 4:8], arm),
                   dt=dt, name=name, qdd=qdd)


def _as_records(data):
    if isinstance(data, DynamicData):
        return [data]
    if isinstance(data, (list, tuple)) and data and all(isinstance(d, DynamicData) for d in data):
        return list(data)
    raise TypeError("data must be a DynamicData or a non-empty list of DynamicData, got "
                    f"{type(data).__name__}")


def filtered_system(data, arm, *, friction: bool = True, sign_velocity: float | None = None,
                    omega: float = FILTER_OMEGA, drop: int = DROP_SAMPLES,
                    gravity_acc: float | None = None):
    """Stacked filtered system (B.7): K_f (2(N - R), p) and tau_f (2(N - R),).

    Rows: all joint-1 equations of every record, then all joint-2 equations.

    Parameters
    ----------
    data : DynamicData or list of DynamicData
    arm : ArmParameters
    friction, sign_velocity, omega, gravity_acc
        As in :func:`filtered_regressor`.
    drop : int, keyword-only
        Filtered samples R dropped at the start of each record.

    Returns
    -------
    Kf : numpy.ndarray, shape (M, 2, p)
    tau_f : numpy.ndarray, shape (M, 2)
    """
    records = _as_records(data)
    drop = check_int("drop", drop, 0, 10 ** 9)
    Ks, ts = [], []
    for d in records:
        if len(d) <= drop:
            raise ValueError(f"record {d.name!r} has {len(d)} samples, not more than drop = {drop}")
        Kf = filtered_regressor(d.q, d.qd, d.dt, arm, friction=friction, sign_velocity=sign_velocity,
                                omega=omega, gravity_acc=gravity_acc)
        Ks.append(Kf[drop:])
        ts.append(filter_signal(d.tau, d.dt, omega)[drop:])
    return np.concatenate(Ks), np.concatenate(ts)


@dataclass(frozen=True)
class DynamicResult(Result):
    """Dynamic parameter estimate (§3.5.2.6) with its statistics.

    Attributes
    ----------
    lsq : LSQResult
        The least-squares solution of the stacked filtered system.
    friction : bool
        Whether the model includes friction (10 vs 6 parameters).
    sign_velocity : float or None
        Smooth-sign velocity used in the Coulomb columns (None: ideal sgn).
    datasets : tuple of str
        Names of the records used.
    omega : float
        Filter cut-off [rad/s].
    joint_sigma : numpy.ndarray, shape (2,)
        RMS of the filtered LS residuals per joint [N m] (WLS weights are 1/sigma^2).
    """

    lsq: LSQResult
    friction: bool
    sign_velocity: float | None
    datasets: tuple
    omega: float
    joint_sigma: np.ndarray

    # forwarded statistics
    @property
    def names(self):
        return self.lsq.names

    @property
    def estimates(self) -> np.ndarray:
        """theta_hat (6 or 10 entries, order of (B.6))."""
        return self.lsq.estimates

    @property
    def std_errors(self) -> np.ndarray:
        return self.lsq.std_errors

    @property
    def ci(self) -> np.ndarray:
        return self.lsq.ci

    @property
    def covariance(self) -> np.ndarray:
        return self.lsq.covariance

    @property
    def condition_number(self) -> float:
        return self.lsq.condition_number

    @property
    def method(self) -> str:
        return self.lsq.method

    @property
    def theta(self) -> np.ndarray:
        """The full 10-vector of (B.6) (friction entries 0 for a frictionless model)."""
        t = np.zeros(10)
        t[:self.estimates.size] = self.estimates
        return t

    def to_pandas(self) -> pd.DataFrame:
        """One row per parameter: estimate, std_error, ci_low, ci_high, unit."""
        return self.lsq.to_pandas()

    def plot(self, **kwargs):
        """Filtered torques measured vs predicted and residuals; a matplotlib Figure.

        Parameters
        ----------
        **kwargs
            Passed to :meth:`ppamsafety.identify.lsq.LSQResult.plot`
            (``max_points``).
        """
        return self.lsq.plot(**kwargs)

    def to_base_parameters(self):
        """The estimate as :class:`ppamsafety.params.inertia.BaseParameters`.

        Raises ValueError (from BaseParameters) when an estimated inertia
        (theta3, theta6) or friction coefficient is not positive.
        """
        t = self.theta
        return BaseParameters(*[float(v) for v in t[:6]], coulomb=(float(t[6]), float(t[7])),
                              viscous=(float(t[8]), float(t[9])))

    def predict_torque(self, q, qd, qdd, arm) -> np.ndarray:
        """Model torques K(q, qd, qdd) theta_hat [N m], shape (N, 2).

        Uses the regressor (B.5)/(B.6) with this result's ``friction`` and
        ``sign_velocity`` settings.

        Parameters
        ----------
        q, qd, qdd : array_like, shape (N, 2)
            Joint angles [rad], velocities [rad/s], accelerations [rad/s^2].
        arm : ArmParameters
            Supplies L1 and g (see :func:`regressor`).
        """
        K = regressor(q, qd, qdd, arm, friction=self.friction, sign_velocity=self.sign_velocity)
        return K @ self.estimates


def identify_dynamic(data, arm, *, friction: bool = True, method: str = "LS",
                     sign_velocity: float | None = None, omega: float = FILTER_OMEGA,
                     drop: int = DROP_SAMPLES, confidence: float = 0.95,
                     gravity_acc: float | None = None) -> DynamicResult:
    """Dynamic base parameters from filtered data (3.28) by LS or two-step WLS.

    Parameters
    ----------
    data : DynamicData or list of DynamicData
        Records (each filtered separately, first ``drop`` samples dropped).
    arm : ArmParameters
        Supplies L1 and g (the known geometry).
    friction : bool, keyword-only
        Model with Coulomb + viscous friction (10 parameters) or without (6).
    method : {"LS", "WLS"}, keyword-only
        WLS: second pass weighted by 1/s_j^2, s_j^2 the per-joint variance of
        the LS residuals.
    sign_velocity : float, optional, keyword-only
        See :func:`regressor`.
    omega : float, keyword-only
        Filter cut-off [rad/s].
    drop : int, keyword-only
        R, filtered samples dropped per record.
    confidence : float, keyword-only
        Level of the (optimistic, see module doc) confidence intervals.
    gravity_acc : float, optional, keyword-only
        g [m/s^2]; default ``arm.gravity``.

    Returns
    -------
    DynamicResult
    """
    if method not in ("LS", "WLS"):
        raise ValueError(f"method = {method!r} is not one of 'LS', 'WLS'")
    if not isinstance(friction, bool):
        raise TypeError(f"friction must be a bool, got {type(friction).__name__}")
    records = _as_records(data)
    Kf, tf = filtered_system(records, arm, friction=friction, sign_velocity=sign_velocity,
                             omega=omega, drop=drop, gravity_acc=gravity_acc)
    p = _nparams(friction)
    m = Kf.shape[0]
    A = np.concatenate([Kf[:, 0, :], Kf[:, 1, :]])          # B.7 row order
    y = np.concatenate([tf[:, 0], tf[:, 1]])
    kw = dict(names=DYNAMIC_NAMES[:p], units=DYNAMIC_UNITS[:p], confidence=confidence,
              quantity="filtered torque [N m]", what="identify_dynamic")
    tag = "with friction" if friction else "frictionless"
    res = solve(A, y, method=f"LS {tag}", **kw)
    r = res.residuals
    sig = np.sqrt(np.array([np.mean(r[:m] ** 2), np.mean(r[m:] ** 2)]))
    if method == "WLS":
        if np.any(sig <= 0):
            raise ValueError("identify_dynamic: WLS needs non-zero residuals on both joints "
                             "(noise-free data: use method='LS')")
        w = np.concatenate([np.full(m, sig[0] ** -2), np.full(m, sig[1] ** -2)])
        res = solve(A, y, weights=w, method=f"WLS {tag}", **kw)
    return DynamicResult(lsq=res, friction=friction, sign_velocity=sign_velocity,
                         datasets=tuple(d.name for d in records), omega=float(omega),
                         joint_sigma=sig)


def estimate_acceleration(qd, dt: float, *, cutoff_hz: float = 5.0, order: int = 4) -> np.ndarray:
    """Accelerations for validation (§3.5.2.7): zero-phase low-pass, central differences.

    A Butterworth low-pass of ``order`` run forward and backward
    (``scipy.signal.filtfilt``) on the velocities, then ``numpy.gradient``
    (central differences inside, one-sided at the ends).

    Parameters
    ----------
    qd : array_like, shape (N, 2)
        Velocities [rad/s].
    dt : float
        Sample time [s].
    cutoff_hz : float, keyword-only
        Cut-off [Hz] (5 Hz, the bandwidth of F; the thesis does not print its value).
    order : int, keyword-only
        Butterworth order.
    """
    from scipy.signal import butter, filtfilt

    qd = as_samples("qd", qd, ncols=2, ndim=2)
    dt = check_range("dt", dt, DT_MIN, 1.0, unit="s")
    check_range("cutoff_hz", cutoff_hz, 0.0, 0.5 / dt, lo_open=True, hi_open=True, unit="Hz")
    order = check_int("order", order, 1, 10)
    b, a = butter(order, cutoff_hz * 2 * dt)
    if qd.shape[0] <= 3 * max(len(a), len(b)):
        raise ValueError(f"qd has {qd.shape[0]} samples, too few for the validation filter")
    try:
        return np.gradient(filtfilt(b, a, qd, axis=0), dt, axis=0)
    except np.linalg.LinAlgError:
        raise ValueError(f"cutoff_hz = {cutoff_hz:g} Hz at dt = {dt:g} s (normalised cut-off "
                         f"{cutoff_hz * 2 * dt:.3g}) gives a filter of order {order} too narrow "
                         f"to evaluate; raise cutoff_hz or lower order") from None


def mean_squared_torque_error(result: DynamicResult, data: DynamicData, arm, *,
                              use_true_qdd: bool = False, cutoff_hz: float = 5.0) -> np.ndarray:
    """e_i = mean_k (tau_i[k] - tau_hat_i[k])^2 per joint [N^2 m^2] (§3.5.2.7).

    Parameters
    ----------
    result : DynamicResult
    data : DynamicData
    arm : ArmParameters
    use_true_qdd : bool, keyword-only
        Use ``data.qdd`` (simulation) instead of the estimated accelerations.
    cutoff_hz : float, keyword-only
        See :func:`estimate_acceleration`.
    """
    if not isinstance(result, DynamicResult):
        raise TypeError(f"result must be a DynamicResult, got {type(result).__name__}")
    if not isinstance(data, DynamicData):
        raise TypeError(f"data must be a DynamicData, got {type(data).__name__}")
    if use_true_qdd:
        if data.qdd is None:
            raise ValueError(f"use_true_qdd: record {data.name!r} has no qdd")
        qdd = data.qdd
    else:
        qdd = estimate_acceleration(data.qd, data.dt, cutoff_hz=cutoff_hz)
    err = data.tau - result.predict_torque(data.q, data.qd, qdd, arm)
    return np.mean(err ** 2, axis=0)


def validation_table(results: dict, datasets, arm, *, use_true_qdd: bool = False,
                     cutoff_hz: float = 5.0) -> pd.DataFrame:
    """Table 3.4: (e1 + e2)/2 for every estimate (columns) on every record (rows).

    An ``"Average"`` row averages each column over the records *not* used for
    that estimate (the thesis' parenthesised self-validations are excluded);
    their positions are listed in ``df.attrs["self_validation"]``.

    Parameters
    ----------
    results : dict of str -> DynamicResult
        Column label -> estimate.
    datasets : list of DynamicData
        Validation records (row labels are their names, which must be unique).
    arm : ArmParameters
    use_true_qdd, cutoff_hz
        See :func:`mean_squared_torque_error`.

    Returns
    -------
    pandas.DataFrame
        Values in N^2 m^2.
    """
    if not isinstance(results, dict) or not results:
        raise TypeError("results must be a non-empty dict of label -> DynamicResult")
    records = _as_records(list(datasets) if not isinstance(datasets, DynamicData) else datasets)
    names = [d.name for d in records]
    if len(set(names)) != len(names):
        raise ValueError(f"datasets must have unique names, got {names}")
    table = pd.DataFrame(index=pd.Index(names, name="validation set"), columns=list(results),
                         dtype=float)
    selfv = []
    for col, res in results.items():
        for d in records:
            e = mean_squared_torque_error(res, d, arm, use_true_qdd=use_true_qdd, cutoff_hz=cutoff_hz)
            table.loc[d.name, col] = 0.5 * float(e.sum())
            if d.name in res.datasets:
                selfv.append((d.name, col))
    avg = {}
    for col, res in results.items():
        rows = [d.name for d in records if d.name not in res.datasets]
        avg[col] = float(table.loc[rows, col].mean()) if rows else np.nan
    table.loc["Average"] = pd.Series(avg)
    table.attrs["self_validation"] = selfv
    table.attrs["unit"] = "N^2 m^2"
    return table


__all__ = ["FILTER_OMEGA", "DROP_SAMPLES", "DYNAMIC_NAMES", "DYNAMIC_UNITS", "regressor",
           "w_matrices", "filter_coefficients", "filter_signal", "filtered_regressor",
           "DynamicData", "filtered_system", "DynamicResult", "identify_dynamic",
           "estimate_acceleration", "mean_squared_torque_error", "validation_table"]
