"""Residuals of an arm record against the current model, per channel and per subsystem.

The thesis localised its hysteresis error by comparing each subsystem with
measurements on its own (§3.5.1.6).  For an arm record with the valve set
values ``u1..u4``, the measured ``q, qd, p`` (open loop, or a closed loop
whose set values were logged -- the plant is driven exactly as measured
either way) three residuals are formed:

pressure vs the valve model (channels ``p1..p4``, Pa)
    The valve/pressure ODE (3.2), (3.6) with the static valve error (3.12)::

        dp_i/dt = a_i + b_i u_i - kappa_i p_i - n (P_atm + p_i) m_tau,i qd_j / V_i

    with a = v1/T, b = v2/T, kappa = 1/T, integrated over a block of L
    samples [t_a, t_b]:  p_i(t_b) - p_i(t_a) = a_i (t_b - t_a) + b_i Int u_i
    - kappa_i Int p_i - n Int h_i.  Measured p, q, qd drive the right-hand
    side, so the valve is isolated from the arm.  u is held over each sample
    (zero-order hold, exact sum); the other integrals are trapezoidal.
torque vs the rigid-body model (channels ``tau1, tau2``, N m s)
    (3.29) in the integral form of the acceleration-free regressor of
    :mod:`ppamsafety.identify.dynamic` (H qd = W1 theta, Hdot qd = W2 theta,
    C qd + G + tau_f = W3 theta)::

        Int tau dt = [W1 theta]_{t_a}^{t_b} + Int (W3 - W2) theta dt

    with tau = sum_i p_i m_tau,i(q) from the *measured* pressures through the
    torque functions (2.17).  This is the Slotine-Li filtering of (3.26) with
    a box filter instead of the first-order one: no derivative of a noisy
    signal is taken, and -- unlike the first-order filter, whose outputs are
    correlated over ~1/omega -- non-overlapping blocks with distinct end
    samples give residuals that are *independent* under white measurement
    noise, which the statistics of :mod:`ppamsafety.diagnose.arm.selection` need.
angles vs the full simulation (channels ``q1, q2``, rad; also qd, p)
    :func:`replay`: the plant model (:func:`ppamsafety.plant.model.simulate`,
    batched over parameter variants) from the measured first state with the
    measured set values.  Output error: it shows the gap a user sees, not
    where it comes from.

Both block residuals are linear in the *model vector* mu (:data:`MU_NAMES`,
23 entries: a, b, kappa of the four valves, n, theta1..theta6, c1, c2, b1,
b2), ``prediction = X mu``; every candidate effect of
:mod:`ppamsafety.diagnose.arm.candidates` is a direction (or a change of X) in
that space, which is why they can be fitted by linear regression.

The model under test is the arm *as declared*, its ``[effects]`` included
(:class:`ppamsafety.params.effects.Effects`):

* parameter effects (payload, friction, valve offset/gain/lag, polytropic
  exponent) are folded into the plant row (:func:`ppamsafety.plant.packing.pack`),
  so the model vector mu of that row carries them;
* a declared joint torque bias and muscle hysteresis (3.35) -- the arm's delta
  per group, its initial memory -- are torques beside the muscles' at every
  sample (:func:`declared_torque`), moved to the measured side of the torque
  equations;
* a declared valve dead time delays the set values in the design
  (:attr:`BlockSystem.delay0`, :func:`declared_delays`); the dead-time
  candidate profiles *changes* of it.

An arm cannot declare a sensor fault (``[sensors]`` describes the hardware,
not its faults), so the sensor-fault columns always start from none.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..._validation import check_int, check_range
from ...data.measured import MeasuredData
from ...data.measured import P as P_COLS
from ...data.measured import Q as Q_COLS
from ...data.measured import QD as QD_COLS
from ...data.measured import U as U_COLS
from ...identify.dynamic import w_matrices
from ...params.effects import Effects
from ...plant import layout as lay
from ...plant.model import hysteresis_factors, simulate
from ...plant.torque import torque_functions, group_volumes
from ..core.noise import noise_floor, second_difference_sigma
from ..core.record import longest_segment

#: Names and units of the model vector mu (see the module docstring).
MU_NAMES = tuple(f"{k}_valve{i}" for i in range(1, 5) for k in ("a", "b", "kappa")) + (
    "n", "theta1", "theta2", "theta3", "theta4", "theta5", "theta6", "c1", "c2", "b1", "b2")
MU_UNITS = ("Pa/s", "1/s", "1/s") * 4 + ("-", "kg m", "kg m", "kg m^2", "kg m", "kg m", "kg m^2",
                                         "N m", "N m", "N m s/rad", "N m s/rad")
NMU = len(MU_NAMES)
#: Offsets into mu: valve i has a at MU_A + 3 i, b at MU_B + 3 i, kappa at MU_K + 3 i.
MU_A, MU_B, MU_K = 0, 1, 2
MU_N = MU_NAMES.index("n")
MU_THETA = MU_NAMES.index("theta1")        #: theta1..theta6, then c1, c2, b1, b2
MU_COUL = MU_NAMES.index("c1")
MU_VISC = MU_NAMES.index("b1")
#: Residual channels of the block system, their units and subsystems.
CHANNELS = ("p1", "p2", "p3", "p4", "tau1", "tau2")
CHANNEL_UNITS = ("Pa", "Pa", "Pa", "Pa", "N m s", "N m s")
SUBSYSTEM = {"pressure": (0, 1, 2, 3), "torque": (4, 5), "both": (0, 1, 2, 3, 4, 5)}
#: Name of the hysteresis regression columns in ``BlockSystem.extra`` (the candidate of the
#: same name in :mod:`.candidates` reads them).
HYSTERESIS_COLUMNS = "hysteresis"
#: Names of the sensor-fault and torque-bias regression columns in ``BlockSystem.extra``
#: (:func:`sensor_columns`; candidates of the same names in :mod:`.candidates`).
PRESSURE_OFFSET_COLUMNS = "pressure_sensor_offset"
PRESSURE_GAIN_COLUMNS = "pressure_sensor_gain"
ENCODER_OFFSET_COLUMNS = "encoder_offset"
TORQUE_BIAS_COLUMNS = "joint_torque_bias"
#: Step of the finite difference of the residual in the measured angles [rad] (the encoder
#: offset columns): small against the offsets of interest (0.1-5 deg), large against rounding.
ENCODER_STEP = 1e-3
#: Default block length [s]: long against the sample time (endpoint noise averages
#: against the integrated model error), short against the 10 s excitation period.
BLOCK_SECONDS = 0.05


@dataclass(frozen=True, eq=False)
class ArmRecord:
    """The arrays of one gap-free arm record that the diagnosis uses (SI units).

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Time [s].
    q, qd : numpy.ndarray, shape (N, 2)
        Measured angles [rad], velocities [rad/s].
    p : numpy.ndarray, shape (N, 4)
        Measured gauge pressures [Pa].
    u : numpy.ndarray, shape (N, 4)
        Valve set values [Pa] (held over each sample interval).
    dt : float
        Sample time [s].
    source : str
        File or label.
    rows : tuple of (int, int)
        The row range of the data used.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    p: np.ndarray
    u: np.ndarray
    dt: float
    source: str = "<data>"
    rows: tuple = (0, 0)

    def __len__(self) -> int:
        return self.t.size

    def x0(self) -> np.ndarray:
        """Measured first state [q, qd, p] (8,)."""
        return np.concatenate([self.q[0], self.qd[0], self.p[0]])

    def perturbed(self, sq, sqd, sp, rng) -> "ArmRecord":
        """A copy with extra white noise added (the set values unchanged).

        Parameters
        ----------
        sq, sqd, sp : array_like
            Standard deviations for q (2,), qd (2,), p (4,).
        rng : numpy.random.Generator
            Source of the noise.
        """
        n = len(self)
        return ArmRecord(self.t, self.q + rng.normal(size=(n, 2)) * sq,
                         self.qd + rng.normal(size=(n, 2)) * sqd,
                         self.p + rng.normal(size=(n, 4)) * sp, self.u, self.dt, self.source,
                         self.rows)


def arm_record(data) -> tuple:
    """The longest gap-free segment of an arm record with q, qd, p and u, as an :class:`ArmRecord`.

    Parameters
    ----------
    data : MeasuredData
        kind ``"arm"``, experiment ``"open-loop"`` or ``"closed-loop"`` with
        columns q1, q2, qd1, qd2, p1..p4, u1..u4.

    Returns
    -------
    ArmRecord
    list of str
        Notes (e.g. segments left out).
    """
    if not isinstance(data, MeasuredData):
        raise TypeError(f"data must be a MeasuredData, got {type(data).__name__}")
    if data.kind != "arm" or data.experiment not in ("open-loop", "closed-loop"):
        raise ValueError(f"{data.source}: the arm diagnosis needs an arm open-loop or closed-loop "
                         f"record; this is a {data.kind} {data.experiment} record")
    need = (*Q_COLS, *QD_COLS, *P_COLS, *U_COLS)
    missing = [c for c in need if not data.has(c)]
    if missing:
        raise ValueError(f"{data.source}: the diagnosis replays the record with the measured "
                         f"valve set values and compares q, qd, p; missing column(s) "
                         f"{', '.join(missing)}")
    a, b, notes = longest_segment(data)
    f = data.frame.iloc[a:b]
    t = f["t"].to_numpy(dtype=float)
    if t.size < 200:
        raise ValueError(f"{data.source}: the diagnosed segment has {t.size} samples; at least "
                         f"200 are needed (several 50 ms blocks)")
    dt = float(np.median(np.diff(t)))
    rec = ArmRecord(t=t - t[0], q=f[list(Q_COLS)].to_numpy(dtype=float),
                    qd=f[list(QD_COLS)].to_numpy(dtype=float),
                    p=f[list(P_COLS)].to_numpy(dtype=float),
                    u=f[list(U_COLS)].to_numpy(dtype=float), dt=dt, source=data.source,
                    rows=(int(a), int(b)))
    return rec, notes


def model_vector(row) -> np.ndarray:
    """The model vector mu (:data:`MU_NAMES`) of a packed plant row.

    Parameters
    ----------
    row : numpy.ndarray, shape (NP,)
        :func:`ppamsafety.plant.packing.pack` row.
    """
    read = lay.PLANT.read
    tv, v1, v2 = read(row, "tv"), read(row, "v1"), read(row, "v2")
    mu = np.empty(NMU)
    for i in range(4):
        mu[MU_A + 3 * i] = v1[i] / tv[i]
        mu[MU_B + 3 * i] = v2[i] / tv[i]
        mu[MU_K + 3 * i] = 1.0 / tv[i]
    mu[MU_N] = float(read(row, "n_poly"))
    mu[MU_THETA:MU_THETA + 6] = read(row, "theta")
    mu[MU_COUL:MU_COUL + 2] = read(row, "coulomb")
    mu[MU_VISC:MU_VISC + 2] = read(row, "viscous")
    return mu


def row_from_mu(row, mu) -> np.ndarray:
    """A copy of plant row ``row`` with the quantities of ``mu`` written back (v1, v2, T, n, theta,
    friction).

    Parameters
    ----------
    row : numpy.ndarray, shape (NP,)
    mu : numpy.ndarray, shape (NMU,)
    """
    out = np.array(row, dtype=float)
    kappa = np.array([mu[MU_K + 3 * i] for i in range(4)])
    if np.any(kappa <= 0):
        raise ValueError(f"row_from_mu: valve 1/T must be > 0, got {kappa}")
    out[lay.PLANT.slice("tv")] = 1.0 / kappa
    out[lay.PLANT.slice("v1")] = [mu[MU_A + 3 * i] / kappa[i] for i in range(4)]
    out[lay.PLANT.slice("v2")] = [mu[MU_B + 3 * i] / kappa[i] for i in range(4)]
    out[lay.PLANT.slice("n_poly")] = mu[MU_N]
    out[lay.PLANT.slice("theta")] = mu[MU_THETA:MU_THETA + 6]
    out[lay.PLANT.slice("coulomb")] = mu[MU_COUL:MU_COUL + 2]
    out[lay.PLANT.slice("viscous")] = mu[MU_VISC:MU_VISC + 2]
    return out


def _cumtrapz(g, dt):
    """Trapezoidal running integral along axis 0, starting at 0."""
    c = np.zeros_like(g)
    c[1:] = np.cumsum(0.5 * (g[1:] + g[:-1]) * dt, axis=0)
    return c


def _cumzoh(u, dt):
    """Running integral of a zero-order-hold signal: C[k] = dt sum_{j<k} u[j]."""
    c = np.zeros_like(u)
    c[1:] = np.cumsum(u[:-1] * dt, axis=0)
    return c


def delayed(u, shift) -> np.ndarray:
    """``u`` delayed by ``shift`` samples (the first value held before the start).

    Parameters
    ----------
    u : numpy.ndarray, shape (N, k)
    shift : int or sequence of k int
        Delay in samples, >= 0: one for every column, or one per column.
    """
    if np.ndim(shift):
        shifts = [int(s) for s in shift]
        if len(set(shifts)) > 1:
            return np.stack([delayed(u[:, [i]], s)[:, 0] for i, s in enumerate(shifts)], 1)
        shift = shifts[0]
    if shift == 0:
        return u
    return np.concatenate([np.repeat(u[:1], shift, axis=0), u[:-shift]])


def declared_delays(arm) -> np.ndarray:
    """The valve dead time the arm declares, per valve, in samples of a record (4,) int.

    ``Effects.valve_dead_time`` counts control periods; the plant takes one input sample per
    control period (:func:`ppamsafety.plant.model.simulate`), so a record is replayed with
    that many samples of delay.  Zeros when the arm declares none.

    Parameters
    ----------
    arm : ArmParameters
    """
    d = arm.effects.valve_dead_time
    return np.zeros(4, dtype=int) if d is None else np.array(d, dtype=int)


def changed_delays(delay0, shift: int) -> tuple:
    """Per-valve delays [samples] ``delay0`` changed by ``shift`` samples, at least 0.

    Parameters
    ----------
    delay0 : sequence of 4 int
        The model's dead time per valve (:func:`declared_delays`).
    shift : int
        The change (the dead-time candidate's profiled shift).
    """
    return tuple(max(int(d) + int(shift), 0) for d in delay0)


def declared_torque_bias(arm) -> np.ndarray:
    """The constant joint torque the arm declares (``Effects.joint_torque_bias``) [N m] (2,).

    Parameters
    ----------
    arm : ArmParameters
    """
    b = arm.effects.joint_torque_bias
    return np.zeros(2) if b is None else np.array(b, dtype=float)


def declared_hysteresis(arm) -> np.ndarray:
    """The hysteresis scale delta the arm declares per muscle group (3.35) [-] (4,).

    Parameters
    ----------
    arm : ArmParameters
    """
    d = arm.effects.hysteresis_delta
    return np.zeros(4) if d is None else np.array(d, dtype=float)


@dataclass(frozen=True, eq=False)
class Columns:
    """Regression columns of a candidate that is not a direction of mu: ``E(mu) = Y + X mu``.

    A sensor fault changes the *measured* signals the equations are built from, so its
    columns depend on the model they are evaluated with (a pressure-sensor offset o changes
    the valve term -kappa Int p by kappa o span: with the valve's fitted kappa, not the
    nominal one).  Both parts are linear in the fault; X (the change of the design) makes
    the columns follow the model as the selection refits it.

    Attributes
    ----------
    Y : numpy.ndarray, shape (nb, nch, k)
        Model-independent part (the change of the measured side y, negated).
    X : numpy.ndarray or None, shape (nb, nch, NMU, k)
        Change of the design per unit fault (None: the columns do not depend on mu).
    """

    Y: np.ndarray
    X: np.ndarray | None = None

    @property
    def k(self) -> int:
        """Number of coefficients."""
        return self.Y.shape[2]

    def at(self, mu) -> np.ndarray:
        """The columns at model vector ``mu`` -> (nb, nch, k).

        Parameters
        ----------
        mu : numpy.ndarray, shape (NMU,)
        """
        if self.X is None:
            return self.Y
        return self.Y + np.einsum("bcmk,m->bck", self.X, mu, optimize=True)

    def take(self, idx) -> "Columns":
        """The rows ``idx`` (blocks) of both parts.

        Parameters
        ----------
        idx : numpy.ndarray of int
        """
        return Columns(self.Y[idx], None if self.X is None else self.X[idx])


@dataclass(frozen=True, eq=False)
class BlockSystem:
    """The block-integral equations of a record: ``y`` (nb, 6) and ``X`` (nb, 6, NMU).

    prediction = X @ mu, residual = y - X @ mu (channels :data:`CHANNELS`).

    Attributes
    ----------
    y : numpy.ndarray, shape (nb, 6)
    X : numpy.ndarray, shape (nb, 6, NMU)
    starts, stops : numpy.ndarray of int, shape (nb,)
        First and last sample of every block.
    u : numpy.ndarray, shape (N, 4)
        The set values (to build the dead-time variants).
    dt : float
        Sample time [s].
    delay0 : tuple of 4 int
        The valve dead time of the model under test per valve [samples]
        (:func:`declared_delays`): the design ``X`` holds the set values delayed by it.
    features : dict
        Per-block operating-region descriptors (mean q, qd, p, time).
    extra : dict
        Regression columns of candidates that are not directions of mu,
        name -> :class:`Columns`, added to the prediction (``Candidate.columns``;
        ``"hysteresis"``: see :func:`hysteresis_signature`; the sensor faults:
        :func:`sensor_columns`, :func:`encoder_columns`).
    """

    y: np.ndarray
    X: np.ndarray
    starts: np.ndarray
    stops: np.ndarray
    u: np.ndarray = field(repr=False)
    dt: float = 0.0
    delay0: tuple = (0, 0, 0, 0)
    features: dict = field(default_factory=dict, repr=False)
    extra: dict = field(default_factory=dict, repr=False)

    @property
    def nb(self) -> int:
        return self.y.shape[0]

    def delays(self, shift: int) -> tuple:
        """Per-valve delay [samples] of the model's dead time changed by ``shift`` samples
        (:func:`changed_delays` of :attr:`delay0`).

        Parameters
        ----------
        shift : int
        """
        return changed_delays(self.delay0, shift)

    def shift_grid(self, max_shift: int) -> tuple:
        """The changes of the dead time a profile tries: every whole sample from no delay
        at all to ``max_shift`` samples more than the model's, except no change.

        Parameters
        ----------
        max_shift : int
            Largest increase [samples].
        """
        return tuple(s for s in range(-max(self.delay0), max_shift + 1) if s != 0)

    def with_dead_time(self, shift: int) -> np.ndarray:
        """X with the valve dead time changed by ``shift`` samples from the model's
        (:meth:`delays`; a dead time changed by ``shift dt``).

        Parameters
        ----------
        shift : int
            Change of the delay in samples (0: X itself, copied).
        """
        X = self.X.copy()
        if shift:
            c = _cumzoh(delayed(self.u, self.delays(shift)), self.dt)
            iu = c[self.stops] - c[self.starts]
            for i in range(4):
                X[:, i, MU_B + 3 * i] = iu[:, i]
        return X


def hysteresis_signature(q, p, arm, *, initial=None) -> tuple:
    """Muscle forces and joint torques of the hysteresis (3.35) per unit delta along measured data.

    The plant's force of group k is ``p_k f_k(eps_k) (1 + delta_k (W_k -
    W_fit(eps_s,k)))`` and its torque contribution ``p_k m_tau,k (1 + ...)``
    (:mod:`ppamsafety.plant.model`).  Here the Preisach output W_k is that of
    the *measured* contraction history (eps_k from the measured q through the
    geometry, each sample committed as the end of one step, exactly as the
    plant commits its steps: :func:`ppamsafety.plant.model.hysteresis_factors`
    with delta = 1), so the torque change is ``delta * h_tau`` with
    ``h_tau,j = sum_{k of joint j} p_k m_tau,k (W_k - W_fit)``.

    Parameters
    ----------
    q : numpy.ndarray, shape (N, 2)
        Measured joint angles [rad], in time order.
    p : numpy.ndarray, shape (N, 4)
        Measured gauge pressures [Pa].
    arm : ArmParameters
        Geometry and muscles of the model.
    initial : str or sequence, keyword-only
        Preisach memory before the first sample (``Effects.hysteresis_initial``;
        default the arm's own, whose default is ``"negative"``: every muscle brought to its
        smallest contraction first, thesis §3.6.6).

    Returns
    -------
    h : numpy.ndarray, shape (N, 4)
        W_k - W_fit(eps_s,k) per group [-].
    h_tau : numpy.ndarray, shape (N, 2)
        Joint torque per unit delta [N m].
    eps : numpy.ndarray, shape (N, 4)
        Contractions [-].
    """
    q = np.asarray(q, dtype=float)
    p = np.asarray(p, dtype=float)
    initial = arm.effects.hysteresis_initial if initial is None else initial
    unit = arm.replace(effects=Effects(hysteresis_delta=(1.0,) * 4, hysteresis_initial=initial))
    states = np.zeros((q.shape[0], 8))
    states[:, :2] = q
    eps, fac = hysteresis_factors(states, unit)
    h = fac - 1.0
    mt = torque_functions(q, arm)
    ph = p * mt * h
    return h, np.stack([ph[:, 0] + ph[:, 1], ph[:, 2] + ph[:, 3]], axis=1), eps


#: Length of the centred moving average that smooths the measured velocity of the Coulomb
#: columns and the measured angles of the hysteresis signature [s]: long against the
#: sample time (white noise / sqrt(n)), short against the arm's motion (a linear signal
#: passes unchanged; the curvature error is qdd dt^2 n^2 / 24, micro-radians per second).
SMOOTH_SECONDS = 0.01


def smooth(x, n: int) -> np.ndarray:
    """Centred moving average of ``n`` samples along axis 0 (shorter windows at the ends).

    Parameters
    ----------
    x : numpy.ndarray, shape (N, k)
    n : int
        Window length (odd, >= 1).
    """
    x = np.asarray(x, dtype=float)
    h = max(int(n), 1) // 2
    if h == 0 or x.shape[0] < 3:
        return x
    c = np.concatenate([np.zeros((1,) + x.shape[1:]), np.cumsum(x, axis=0)])
    i = np.arange(x.shape[0])
    lo = np.maximum(i - h, 0)
    hi = np.minimum(i + h + 1, x.shape[0])
    return (c[hi] - c[lo]) / (hi - lo)[:, None]


def smoothing_samples(dt: float) -> int:
    """Odd window length of :data:`SMOOTH_SECONDS` at sample time ``dt`` (at least 1).

    Parameters
    ----------
    dt : float
        Sample time [s].
    """
    n = int(round(SMOOTH_SECONDS / dt))
    return max(1, n + (1 - n % 2))


def coulomb_velocity(arm, velocity_noise=None) -> np.ndarray:
    """Smoothing velocity of the Coulomb columns, corrected for the velocity noise [rad/s] (2,).

    The plant's Coulomb friction is ``c tanh(qd / v_s)`` (``arm.friction_velocity``).  The
    regressor can only use the *measured* velocity ``qd_m = qd + n``, n ~ N(0, s^2); with
    ``tanh(qd_m / v_s)`` the fitted c is biased low (errors in variables: near a reversal the
    noisy sign is often wrong).  Regression calibration replaces the regressor by its
    expectation given the measurement, ``E[tanh((qd_m - n)/v_s)]``, which with the probit
    approximation tanh(z) ~ erf(sqrt(pi) z / 2) is ``tanh(qd_m / sqrt(v_s^2 + pi s^2 / 2))``:
    the same law with a wider smoothing velocity.

    Parameters
    ----------
    arm : ArmParameters
    velocity_noise : array_like, shape (2,), optional
        Standard deviation of the measured velocities [rad/s]; None: no correction.
    """
    vs = float(arm.friction_velocity)
    if velocity_noise is None:
        return np.array([vs, vs])
    s = np.asarray(velocity_noise, dtype=float)
    return np.sqrt(vs ** 2 + 0.5 * math.pi * s ** 2)


def block_bounds(n: int, dt: float, block_seconds: float, source: str = "<data>") -> tuple:
    """First and last sample of every block (non-overlapping, distinct end samples).

    Parameters
    ----------
    n : int
        Samples of the record.
    dt : float
        Sample time [s].
    block_seconds : float
        Block length [s].
    source : str
        Named in errors.
    """
    block_seconds = check_range("block_seconds", block_seconds, 0.0, 10.0, lo_open=True,
                                unit="s")
    if block_seconds < 3 * dt * (1 - 1e-9):
        raise ValueError(f"block_seconds = {block_seconds:g} s is shorter than 3 samples of the "
                         f"record (dt = {dt:g} s): a block needs at least 3 samples, "
                         f"block_seconds >= {3 * dt:g} s (default 0.05 s)")
    L = max(int(round(block_seconds / dt)), 3)
    starts = np.arange(0, n - L + 1, L)
    stops = starts + L - 1
    if starts.size < 8:
        raise ValueError(f"{source}: {n} samples give only {starts.size} blocks of "
                         f"{L} samples; need at least 8 (shorter block_seconds or a longer record)")
    return starts, stops


def declared_torque(q, p, arm, h=None) -> np.ndarray | None:
    """The joint torques of the effects the arm declares that are columns, not parameters,
    of the model (``Effects.joint_torque_bias``, ``Effects.hysteresis_delta``) [N m] (N, 2).

    The model under test is the arm as declared: its hysteresis (3.35) adds ``sum_k delta_k
    p_k m_tau,k (W_k - W_fit)`` at joint j (over the groups k of joint j, with the arm's own
    delta per group and initial memory) and its torque bias a constant torque; the block and
    rest-point equations move them to the measured side.

    Parameters
    ----------
    q : numpy.ndarray, shape (N, 2)
        Angles [rad] (smoothed as for :func:`hysteresis_signature`).
    p : numpy.ndarray, shape (N, 4)
        Pressures [Pa].
    arm : ArmParameters
    h : numpy.ndarray, shape (N, 4), optional
        W_k - W_fit of :func:`hysteresis_signature` along ``q`` (computed when needed).

    Returns
    -------
    numpy.ndarray or None
        None when the arm declares neither.
    """
    fx = arm.effects
    if fx.hysteresis_delta is None and fx.joint_torque_bias is None:
        return None
    out = np.zeros((np.shape(q)[0], 2)) + declared_torque_bias(arm)[None, :]
    if fx.hysteresis_delta is not None:
        if h is None:
            h, _, _ = hysteresis_signature(q, p, arm)
        ph = np.asarray(p, float) * torque_functions(q, arm) * h * declared_hysteresis(arm)
        out += np.stack([ph[:, 0] + ph[:, 1], ph[:, 2] + ph[:, 3]], axis=1)
    return out


def _blocks(rec: ArmRecord, arm, starts, stops, velocity_noise=None, h=None) -> tuple:
    """y (nb, 6), X (nb, 6, NMU) of the block equations of the model under test (the arm with
    its declared effects) and the running integrals they use."""
    dt = rec.dt
    mt = torque_functions(rec.q, arm)
    vol = group_volumes(rec.q, arm)
    patm = arm.pneumatics.p_atm
    w = np.repeat(rec.qd, 2, axis=1)                   # qd_j of each group (1, 1, 2, 2)
    g = mt * w / vol
    c_p = _cumtrapz(rec.p, dt)
    c_h = _cumtrapz((patm + rec.p) * g, dt)
    c_u = _cumzoh(delayed(rec.u, declared_delays(arm)), dt)
    nb = starts.size
    X = np.zeros((nb, 6, NMU))
    y = np.zeros((nb, 6))
    span = (stops - starts) * dt
    for i in range(4):
        X[:, i, MU_A + 3 * i] = span
        X[:, i, MU_B + 3 * i] = c_u[stops, i] - c_u[starts, i]
        X[:, i, MU_K + 3 * i] = -(c_p[stops, i] - c_p[starts, i])
        X[:, i, MU_N] = -(c_h[stops, i] - c_h[starts, i])
        y[:, i] = rec.p[stops, i] - rec.p[starts, i]
    W1, W2, W3 = w_matrices(rec.q, rec.qd, arm, friction=True,
                            sign_velocity=arm.friction_velocity)
    if velocity_noise is not None:
        # errors in variables: the sign of a noisy velocity is often wrong near a reversal
        # or at rest; the regressor is the expected sign given a smoothed velocity (its
        # noise is the velocity noise over sqrt(n))
        n = smoothing_samples(dt)
        qs = smooth(rec.qd, n)
        vc = coulomb_velocity(arm, np.asarray(velocity_noise, float) / math.sqrt(n))
        W3[:, 0, 6] = np.tanh(qs[:, 0] / vc[0])
        W3[:, 1, 7] = np.tanh(qs[:, 1] / vc[1])
    c_w = _cumtrapz(W3 - W2, dt)
    tau = np.stack([rec.p[:, 0] * mt[:, 0] + rec.p[:, 1] * mt[:, 1],
                    rec.p[:, 2] * mt[:, 2] + rec.p[:, 3] * mt[:, 3]], axis=1)
    decl = declared_torque(smooth(rec.q, smoothing_samples(dt)), rec.p, arm, h)
    if decl is not None:
        # the declared torques act beside the muscles': tau + tau_declared = X theta
        tau = tau + decl
    c_tau = _cumtrapz(tau, dt)
    X[:, 4:6, MU_THETA:] = (W1[stops] - W1[starts]) + (c_w[stops] - c_w[starts])
    y[:, 4:6] = c_tau[stops] - c_tau[starts]
    return y, X, {"mt": mt, "g": g, "c_u": c_u, "span": span}


def block_system(rec: ArmRecord, arm, *, block_seconds: float = BLOCK_SECONDS,
                 extra: bool = True, velocity_noise=None) -> BlockSystem:
    """Build the block-integral equations of ``rec`` for the geometry/muscles of ``arm``.

    Parameters
    ----------
    rec : ArmRecord
    arm : ArmParameters
        Known geometry, muscle force law and friction smoothing (the model).
    block_seconds : float, keyword-only
        Block length [s]; blocks have distinct end samples and do not overlap.
    extra : bool, keyword-only
        Also build the regression columns of the non-mu candidates
        (:attr:`BlockSystem.extra`): the hysteresis torque (one column shared by the four
        groups), the pressure-sensor offsets and gains and the joint torque bias
        (:func:`sensor_columns`) and the encoder offsets (a finite difference in q).
    velocity_noise : array_like, shape (2,), optional, keyword-only
        Noise of the measured velocities [rad/s]: the Coulomb columns use the expected
        sign given the measurement (:func:`coulomb_velocity`); None: the plain law.

    Returns
    -------
    BlockSystem
    """
    dt = rec.dt
    starts, stops = block_bounds(len(rec), dt, block_seconds, rec.source)
    h = None
    if extra or arm.effects.hysteresis_delta is not None:
        # the Preisach memory of the *measured* angles would see a reversal in every noise
        # wiggle: the signature uses the smoothed angles
        h, h_tau, _ = hysteresis_signature(smooth(rec.q, smoothing_samples(dt)), rec.p, arm)
    y, X, parts = _blocks(rec, arm, starts, stops, velocity_noise, h)
    span = parts["span"]
    nb = starts.size

    def bint(x):
        c = _cumtrapz(x, dt)
        return c[stops] - c[starts]

    feats = {"t": 0.5 * (rec.t[starts] + rec.t[stops]), "q": bint(rec.q) / span[:, None],
             "qd": bint(rec.qd) / span[:, None], "p": bint(rec.p) / span[:, None]}
    ext = {}
    if extra:
        c_h = _cumtrapz(h_tau, dt)
        E = np.zeros((nb, 6, 1))
        # the measured torque is tau(p) + delta h_tau = X theta, so the block residual
        # y - X mu = -delta Int h_tau: the prediction gains -Int h_tau per unit delta
        E[:, 4:6, 0] = -(c_h[stops] - c_h[starts])
        ext[HYSTERESIS_COLUMNS] = Columns(E)
        mt, g, c_u = parts["mt"], parts["g"], parts["c_u"]
        ext.update(sensor_columns(
            span=span, int_u=c_u[stops] - c_u[starts], int_g=bint(g), int_mt=bint(mt),
            int_pmt=bint(rec.p * mt), patm=arm.pneumatics.p_atm))

        def residual_of(q):
            r = ArmRecord(rec.t, q, rec.qd, rec.p, rec.u, dt, rec.source, rec.rows)
            yq, Xq, _ = _blocks(r, arm, starts, stops, velocity_noise)
            return yq, Xq

        ext[ENCODER_OFFSET_COLUMNS] = encoder_columns(residual_of, rec.q, y, X)
    return BlockSystem(y=y, X=X, starts=starts, stops=stops, u=rec.u, dt=dt,
                       delay0=tuple(int(d) for d in declared_delays(arm)), features=feats,
                       extra=ext)


def sensor_columns(*, span, int_u, int_g, int_mt, int_pmt, patm) -> dict:
    """Regression columns of pressure-sensor faults and a joint torque bias (block or rest point).

    A pressure sensor with offset o_i and gain g_i reads ``p_m = (1 + g_i) p + o_i``; the
    equations hold for the true pressure ``p = (p_m - o_i) / (1 + g_i)``, so the residual of
    the measured record is the true residual plus ``E(mu) phi`` (prediction = X mu + E phi,
    phi = the sensor faults), :class:`Columns` with, for valve i of joint j,

    * offset, pressure channel i: ``kappa_i span + n Int g_i`` (the -kappa Int p and the
      volume term -n Int (P_atm + p) g_i see the offset), with the kappa_i and n of the
      model the columns are evaluated at; torque channel j: ``Int m_tau,i`` (the torque of
      the measured pressure is too large by o_i m_tau,i);
    * gain, pressure channel i: ``a_i span + b_i Int u_i - n P_atm Int g_i`` (the valve's
      drive: a sensor reading (1 + g) p sees every pressure change (1 + g) times; the
      model's prediction, not the measured change, whose noise would bias g);
      torque channel j: ``Int p_i m_tau,i``;

    exact in o; for the gain the pressure columns are exact in g and the torque columns
    are exact in ``g / (1 + g)``, so a gain is fitted to first order (an error of g^2, 0.04
    % of the torque at g = 2 %); an offset and a gain of the same sensor together carry a
    product term of second order, which is left out.  A torque bias b_j (a constant torque
    the model lacks, e.g. a cable or a spring, ``Effects.joint_torque_bias``) adds to the
    muscle torques: the torque channel j gains ``-span`` per unit b_j.  Rest points use the
    same formulas with ``span = 1``, window means for the integrals and ``g = 0`` (no
    motion).

    Parameters
    ----------
    span : numpy.ndarray, shape (nb,)
        Block lengths [s] (1 for rest points).
    int_u : numpy.ndarray, shape (nb, 4), or None
        Block integrals of the set values (None: no valve equations, as for rest points
        without set values).
    int_g, int_mt, int_pmt : numpy.ndarray, shape (nb, 4)
        Block integrals of g = m_tau qd / V, m_tau, p m_tau (window means at rest).
    patm : float
        Atmospheric pressure [Pa].

    Returns
    -------
    dict
        :data:`PRESSURE_OFFSET_COLUMNS`, :data:`PRESSURE_GAIN_COLUMNS`,
        :data:`TORQUE_BIAS_COLUMNS` -> :class:`Columns`.
    """
    nb = span.size
    oY, oX = np.zeros((nb, 6, 4)), np.zeros((nb, 6, NMU, 4))
    gY, gX = np.zeros((nb, 6, 4)), np.zeros((nb, 6, NMU, 4))
    bias = np.zeros((nb, 6, 2))
    for i in range(4):
        j = 4 + i // 2
        if int_u is not None:
            oX[:, i, MU_K + 3 * i, i] = span
            oX[:, i, MU_N, i] = int_g[:, i]
            gX[:, i, MU_A + 3 * i, i] = span
            gX[:, i, MU_B + 3 * i, i] = int_u[:, i]
            gX[:, i, MU_N, i] = -patm * int_g[:, i]
        oY[:, j, i] = int_mt[:, i]
        gY[:, j, i] = int_pmt[:, i]
    bias[:, 4, 0] = -span
    bias[:, 5, 1] = -span
    return {PRESSURE_OFFSET_COLUMNS: Columns(oY, oX), PRESSURE_GAIN_COLUMNS: Columns(gY, gX),
            TORQUE_BIAS_COLUMNS: Columns(bias)}


def encoder_columns(residual_of, q, y, X) -> Columns:
    """Regression columns of an encoder offset per joint (finite difference in the angles).

    An encoder with offset o_j reads ``q_m = q + o_j``: the residual of the true angles is
    ``r(q_m - o) ~ r(q_m) - o dr/dq_j`` with ``r = y - X mu``, so the prediction gains
    ``dr/dq_j = dy/dq_j - dX/dq_j mu`` per unit o_j (central differences with
    :data:`ENCODER_STEP`), a :class:`Columns` that follows the model.

    Parameters
    ----------
    residual_of : callable
        ``q -> (y, X)`` of the equations with the measured angles replaced by ``q``.
    q : numpy.ndarray, shape (N, 2)
        Measured angles [rad].
    y, X : numpy.ndarray
        The equations at the measured angles (shapes (nb, nch), (nb, nch, NMU)).

    Returns
    -------
    Columns
        k = 2 (joints 1, 2).
    """
    Ys, Xs = [], []
    for j in range(2):
        dq = np.zeros(2)
        dq[j] = ENCODER_STEP
        yp, Xp = residual_of(q + dq)
        ym, Xm = residual_of(q - dq)
        Ys.append((yp - ym) / (2 * ENCODER_STEP))
        Xs.append(-(Xp - Xm) / (2 * ENCODER_STEP))
    return Columns(np.stack(Ys, axis=2), np.stack(Xs, axis=3))


def channel_noise(rec: ArmRecord) -> dict:
    """Measurement-noise standard deviations of q, qd, p estimated from the data.

    See :mod:`ppamsafety.diagnose.core.noise`; floored for noise-free records.

    Parameters
    ----------
    rec : ArmRecord

    Returns
    -------
    dict
        ``{"q": (2,), "qd": (2,), "p": (4,)}``.
    """
    sq = noise_floor(second_difference_sigma(rec.q), np.ptp(rec.q, axis=0) + 1.0)
    sqd = noise_floor(second_difference_sigma(rec.qd), np.ptp(rec.qd, axis=0) + 1.0)
    sp = noise_floor(second_difference_sigma(rec.p), np.ptp(rec.p, axis=0) + 1e5)
    return {"q": sq, "qd": sqd, "p": sp}


def noise_draws(rec: ArmRecord, arm, noise: dict, *, block_seconds: float = BLOCK_SECONDS,
                draws: int = 4, seed: int = 0, velocity_noise: bool = False) -> tuple:
    """Changes of the block system caused by extra measurement noise (Monte Carlo).

    White noise of the estimated standard deviations (``noise``) is added to
    q, qd and p (seeded) and the block system rebuilt; the changes dY, dX
    give the noise part of the residual of *any* model vector mu as
    dY - dX mu (the residual is linear in mu), see :func:`block_noise`.

    Parameters
    ----------
    rec : ArmRecord
    arm : ArmParameters
    noise : dict
        ``{"q": (2,), "qd": (2,), "p": (4,)}`` standard deviations.
    block_seconds : float, keyword-only
    draws : int, keyword-only
    seed : int, keyword-only
    velocity_noise : bool, keyword-only
        Build the systems with the noise-corrected Coulomb columns
        (``block_system(..., velocity_noise=noise["qd"])``), as the diagnosis does.

    Returns
    -------
    dY : numpy.ndarray, shape (draws, nb, 6)
    dX : numpy.ndarray, shape (draws, nb, 6, NMU)
    """
    draws = check_int("draws", draws, 1, 1000)
    vn = noise["qd"] if velocity_noise else None
    base = block_system(rec, arm, block_seconds=block_seconds, extra=False, velocity_noise=vn)
    rng = np.random.default_rng(seed)
    dY, dX = [], []
    for _ in range(draws):
        s = block_system(rec.perturbed(noise["q"], noise["qd"], noise["p"], rng), arm,
                         block_seconds=block_seconds, extra=False, velocity_noise=vn)
        dY.append(s.y - base.y)
        dX.append(s.X - base.X)
    return np.array(dY), np.array(dX)


def block_noise(dY, dX, mu, scale=None) -> np.ndarray:
    """Standard deviation of each block-residual channel due to measurement noise alone.

    For a correct model the residual would have this standard deviation (the
    record's own noise is already in it; adding the same amount again changes
    the residual by a statistically equal amount, to first order).  It
    depends on the model (e.g. velocity noise enters through H(q) qd), hence
    on ``mu``.

    Parameters
    ----------
    dY, dX : numpy.ndarray
        From :func:`noise_draws`.
    mu : numpy.ndarray, shape (NMU,)
        Model vector.
    scale : numpy.ndarray, shape (6,), optional
        Channel magnitudes for the floor of a noise-free record.

    Returns
    -------
    numpy.ndarray, shape (6,)
        In the units of :data:`CHANNEL_UNITS`.
    """
    sig = np.sqrt(np.mean((dY - dX @ mu) ** 2, axis=(0, 1)))
    scale = np.array([1e5] * 4 + [1.0] * 2) if scale is None else scale
    return noise_floor(sig, scale)


def replay(rec: ArmRecord, rows, *, shifts=None, substeps: int = 1, x0=None) -> np.ndarray:
    """Simulate the record with the measured set values for every plant row (one batched call).

    Parameters
    ----------
    rec : ArmRecord
    rows : numpy.ndarray, shape (B, NP)
        Packed plant rows (model variants).
    shifts : sequence of int, optional
        Per row, a valve dead time in samples (the set values delayed).
    substeps : int, keyword-only
        RK4 steps per sample (1 is enough at 1 kHz for valve time constants
        >= 2 ms: h/T <= 0.5).
    x0 : array_like, shape (8,) or (B, 8), optional, keyword-only
        Initial state(s) (default the measured first state).

    Returns
    -------
    numpy.ndarray, shape (B, N, 8)
        Simulated [q, qd, p] at the sample times.
    """
    rows = np.atleast_2d(rows)
    B = rows.shape[0]
    U = np.empty((B, len(rec) - 1, 4))
    for b in range(B):
        s = 0 if shifts is None else int(shifts[b])
        U[b] = delayed(rec.u, s)[:-1]
    return simulate(None, rec.x0() if x0 is None else np.asarray(x0, dtype=float), U, dt=rec.dt,
                    substeps=substeps, params=rows)


__all__ = ["ArmRecord", "arm_record", "Columns", "BlockSystem", "smooth", "smoothing_samples",
           "SMOOTH_SECONDS", "block_system", "block_bounds",
           "coulomb_velocity", "sensor_columns", "encoder_columns", "PRESSURE_OFFSET_COLUMNS",
           "PRESSURE_GAIN_COLUMNS", "ENCODER_OFFSET_COLUMNS", "TORQUE_BIAS_COLUMNS",
           "block_noise", "channel_noise", "noise_draws", "replay", "hysteresis_signature",
           "model_vector", "row_from_mu", "delayed", "declared_delays", "changed_delays",
           "declared_torque", "declared_torque_bias", "declared_hysteresis", "MU_NAMES",
           "MU_UNITS", "NMU", "CHANNELS", "CHANNEL_UNITS", "SUBSYSTEM", "BLOCK_SECONDS"]
