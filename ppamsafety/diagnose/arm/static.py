"""Static-sawtooth records (thesis §3.5.1.6): rest points, their balances and their angles.

The static gravity-compensation validation of §3.5.1.6 steps the set angles
in a sawtooth, waits 3 s for static equilibrium and records 1 s of data.  A
record (``experiment = "static-sawtooth"``) holds the samples of these data
windows (``t`` jumps between them; one row per rest point is accepted too).
Each window is one **rest point** (window means; the noise of a mean is the
sample noise / sqrt(samples)), and the subsystems are compared at rest:

torque balance (channels ``tau1, tau2``, N m)
    ``tau(p, q) = sum_k p_k m_tau,k(q)`` against ``G(q) = W3(q, 0) theta``
    (the rigid-body regressor at zero velocity: gravity only) -- linear in
    the model vector mu like the block equations of
    :mod:`ppamsafety.diagnose.arm.residuals`, so the same candidates and the
    same selection apply (payload: a gravity direction; hysteresis: the
    column ``-mean(h_tau)`` of :func:`~.residuals.hysteresis_signature`,
    whose Preisach memory runs over every recorded sample in order: between
    two rest points the contraction moves monotonically along a ramp, and a
    Preisach operator is rate independent, so the memory at the next rest
    point is the one the plant had);
static valve (channels ``p1..p4``, Pa/s; only with the set values ``u``)
    ``0 = a + b u - kappa p`` (3.2) with (3.12) at rest;
muscle forces (``F1..F4``, N; only with measured forces)
    the localisation of §3.5.1.6 (fig. 3.2): measured force minus the force
    (3.9) predicted from the measured pressure and contraction.  Reported
    per muscle (before and after the fitted hysteresis, and a delta fitted
    on the forces alone), not used by the selection: it tells *which*
    subsystem is wrong -- the muscle forces, not the valves or the links.

Angles vs the model: :func:`static_equilibria` solves the model's rest
angles point after point (quasi-static continuation, Preisach memory
carried along): from the set values through the static valve model when
``u`` is recorded, else from the measured pressures.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import fsolve

from ...data.measured import MeasuredData
from ...hysteresis.force import hysteresis_factor, scaled_contraction
from ...hysteresis.memory import preisach_peek, preisach_update
from ...identify.dynamic import w_matrices
from ...plant import layout as lay
from ...plant.dynamics import gravity_torque
from ...plant.model import initial_effect_state
from ...plant.muscle import muscle_force
from ...plant.torque import torque_functions, group_contraction, torque_kernel
from ..core.noise import noise_floor, second_difference_sigma
from .candidates import default_candidates
from .residuals import (ENCODER_OFFSET_COLUMNS, HYSTERESIS_COLUMNS, MU_A, MU_B, MU_K,
                        MU_THETA, NMU, BlockSystem, Columns, declared_hysteresis,
                        declared_torque, encoder_columns, hysteresis_signature,
                        sensor_columns)

#: An interval of ``t`` longer than this many median intervals separates two rest points.
WINDOW_GAP_FACTOR = 1.5
#: The default candidates of a static record (those that show at rest: no friction, lag,
#: dead time or volume term), derived from the registry (``Candidate.at_rest``).
STATIC_CANDIDATES = default_candidates(static=True)
#: Relative resolution of a rest point: lower bound of the noise level of the torque and
#: force balances as a fraction of the RMS muscle torque / force.  A rest-point record has no
#: samples of the transitions, whose overshoot leaves minor Preisach loops the model cannot
#: replay (measured on the synthetic sawtooth with delta = 0.139: up to 0.26 % in the force
#: factor, typically 0.1 %), and 1 s windows of a real arm are not perfectly settled; the
#: mean of 1000 samples alone would claim a precision of 0.01 %.
RESOLUTION = 3e-3
#: Resolution of the static valve balance [Pa] (times 1/T): settling of the pressures.
PRESSURE_RESOLUTION = 20.0
#: Interpolation steps of the quasi-static continuation between two rest points.
CONTINUATION_STEPS = 12


@dataclass(frozen=True, eq=False)
class StaticRecord:
    """The samples of a static-sawtooth record grouped into rest points (SI units).

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Time [s].
    q : numpy.ndarray, shape (N, 2)
        Joint angles [rad].
    p : numpy.ndarray, shape (N, 4)
        Gauge pressures [Pa].
    u : numpy.ndarray or None
        Valve set values (N, 4) [Pa].
    F : numpy.ndarray or None
        Muscle forces (N, 4) [N].
    windows : numpy.ndarray of int, shape (m, 2)
        Sample ranges [start, stop) of the rest points.
    source : str
        File or label.
    """

    t: np.ndarray
    q: np.ndarray
    p: np.ndarray
    u: np.ndarray | None
    F: np.ndarray | None
    windows: np.ndarray
    source: str = "<data>"

    @property
    def m(self) -> int:
        """Number of rest points."""
        return int(self.windows.shape[0])

    def means(self, x) -> np.ndarray:
        """Window means of a sample array ``x`` (N, k) -> (m, k).

        Parameters
        ----------
        x : numpy.ndarray, shape (N, k)
        """
        return np.stack([x[a:b].mean(axis=0) for a, b in self.windows])

    def counts(self) -> np.ndarray:
        """Samples per rest point (m,)."""
        return (self.windows[:, 1] - self.windows[:, 0]).astype(float)


def static_record(data) -> tuple:
    """The rest points of a static-sawtooth arm record.

    Parameters
    ----------
    data : MeasuredData
        kind ``"arm"``, experiment ``"static-sawtooth"`` with t, q1, q2,
        p1..p4 (u1..u4 and F1..F4 optional).

    Returns
    -------
    StaticRecord
    list of str
        Notes.
    """
    if not isinstance(data, MeasuredData):
        raise TypeError(f"data must be a MeasuredData, got {type(data).__name__}")
    if data.kind != "arm" or data.experiment != "static-sawtooth":
        raise ValueError(f"{data.source}: a static-sawtooth arm record is needed; this is a "
                         f"{data.kind} {data.experiment} record")
    need = ("q1", "q2", "p1", "p2", "p3", "p4")
    missing = [c for c in need if not data.has(c)]
    if missing:
        raise ValueError(f"{data.source}: the static diagnosis compares the torque of the "
                         f"measured pressures with gravity; missing column(s) "
                         f"{', '.join(missing)}")
    f = data.frame
    t = f["t"].to_numpy(dtype=float)
    notes = []
    d = np.diff(t)
    med = float(np.median(d))
    cut = np.flatnonzero(d > WINDOW_GAP_FACTOR * med) + 1
    bounds = np.concatenate([[0], cut, [t.size]])
    windows = np.stack([bounds[:-1], bounds[1:]], 1)
    if windows.shape[0] < 3:
        # one row per rest point (uniform t): every row is a rest point
        windows = np.stack([np.arange(t.size), np.arange(t.size) + 1], 1)
        notes.append("no gaps in t: every row is taken as one rest point")
    if windows.shape[0] < 3:
        raise ValueError(f"{data.source}: {windows.shape[0]} rest points; at least 3 are needed")

    def cols(prefix):
        names = [f"{prefix}{i}" for i in range(1, 5)]
        return f[names].to_numpy(dtype=float) if all(data.has(c) for c in names) else None

    rec = StaticRecord(t=t, q=f[["q1", "q2"]].to_numpy(dtype=float), p=cols("p"), u=cols("u"),
                       F=cols("F"), windows=windows, source=data.source)
    if rec.u is None:
        notes.append("no valve set values u1..u4: the valves are not checked and the model's "
                     "rest angles are solved from the measured pressures")
    if rec.F is None:
        notes.append("no muscle forces F1..F4: the force subsystem is not checked")
    return rec, notes


def static_noise(rec: StaticRecord) -> dict:
    """Sample noise of q, p (and F) from second differences (window edges are outliers of the MAD).

    Parameters
    ----------
    rec : StaticRecord

    Returns
    -------
    dict
        ``{"q": (2,), "p": (4,), "F": (4,) or None}`` standard deviations.
    """
    def est(x, scale):
        if x.shape[0] < 5:
            return noise_floor(np.zeros(x.shape[1]), scale)
        return noise_floor(second_difference_sigma(x), scale)

    return {"q": est(rec.q, np.ptp(rec.q, axis=0) + 1.0),
            "p": est(rec.p, np.ptp(rec.p, axis=0) + 1e5),
            "F": None if rec.F is None else est(rec.F, np.ptp(rec.F, axis=0) + 1.0)}


def _equations(qm, pm, um, arm, declared=None):
    """y (m, 6) and X (m, 6, NMU) of the rest-point balances from window means; ``declared``
    (m, 2): the window means of the torques of the arm's declared column effects
    (:func:`~.residuals.declared_torque`), moved to the measured side."""
    m = qm.shape[0]
    X = np.zeros((m, 6, NMU))
    y = np.zeros((m, 6))
    if um is not None:
        for i in range(4):
            X[:, i, MU_A + 3 * i] = 1.0
            X[:, i, MU_B + 3 * i] = um[:, i]
            X[:, i, MU_K + 3 * i] = -pm[:, i]
    mt = torque_functions(qm, arm)
    y[:, 4] = pm[:, 0] * mt[:, 0] + pm[:, 1] * mt[:, 1]
    y[:, 5] = pm[:, 2] * mt[:, 2] + pm[:, 3] * mt[:, 3]
    if declared is not None:
        y[:, 4:6] += declared
    _, _, W3 = w_matrices(qm, np.zeros_like(qm), arm, friction=True,
                          sign_velocity=arm.friction_velocity)
    X[:, 4:6, MU_THETA:] = W3
    return y, X


def static_system(rec: StaticRecord, arm) -> BlockSystem:
    """The rest-point balances of ``rec`` as a :class:`~.residuals.BlockSystem` (one 'block' per rest point).

    Parameters
    ----------
    rec : StaticRecord
    arm : ArmParameters
        The model (geometry, muscles).

    Returns
    -------
    BlockSystem
        Channels p1..p4 [Pa/s] (zero rows without u), tau1, tau2 [N m];
        ``extra["hysteresis"]``; features ``t``, ``q``, ``p`` (window means)
        and ``qd`` = the change of the mean angle since the previous rest
        point (the direction of approach, the region where hysteresis shows).
    """
    qm, pm = rec.means(rec.q), rec.means(rec.p)
    um = None if rec.u is None else rec.means(rec.u)
    h, h_tau, _ = hysteresis_signature(rec.q, rec.p, arm)
    y, X = _equations(qm, pm, um, arm, _declared_means(rec, rec.q, arm, h))
    E = np.zeros((rec.m, 6, 1))
    E[:, 4:6, 0] = -rec.means(h_tau)
    E = Columns(E)
    approach = np.diff(qm, axis=0, prepend=qm[:1])
    feats = {"t": rec.means(rec.t[:, None])[:, 0], "q": qm, "qd": approach, "p": pm}
    # sensor faults and a torque bias at rest (span 1, no motion); without set values there
    # are no valve equations, so the pressure channels get no columns either
    mt = torque_functions(qm, arm)
    extra = sensor_columns(span=np.ones(rec.m), int_u=um, int_g=np.zeros_like(pm), int_mt=mt,
                           int_pmt=pm * mt, patm=arm.pneumatics.p_atm)
    extra[HYSTERESIS_COLUMNS] = E
    extra[ENCODER_OFFSET_COLUMNS] = encoder_columns(
        lambda q: _equations(rec.means(q), pm, um, arm, _declared_means(rec, q, arm)),
        rec.q, y, X)
    return BlockSystem(y=y, X=X, starts=rec.windows[:, 0], stops=rec.windows[:, 1] - 1,
                       u=np.zeros((rec.m, 4)) if um is None else um, dt=1.0, features=feats,
                       extra=extra)


def _declared_means(rec: StaticRecord, q, arm, h=None):
    """Window means of the torques of the arm's declared column effects along the sample
    angles ``q`` (None when it declares none)."""
    d = declared_torque(q, rec.p, arm, h)
    return None if d is None else rec.means(d)


def static_floor(rec: StaticRecord, arm) -> np.ndarray:
    """Lower bound of the rest-point noise level per channel (:data:`RESOLUTION`).

    Parameters
    ----------
    rec : StaticRecord
    arm : ArmParameters

    Returns
    -------
    numpy.ndarray, shape (6,)
        p1..p4 [Pa/s], tau1, tau2 [N m].
    """
    qm, pm = rec.means(rec.q), rec.means(rec.p)
    ph = np.abs(pm * torque_functions(qm, arm))
    kappa = np.array([1.0 / v.time_constant for v in arm.valves.valves])
    tau = np.sqrt(np.mean(np.stack([ph[:, 0] ** 2 + ph[:, 1] ** 2,
                                    ph[:, 2] ** 2 + ph[:, 3] ** 2], 1), axis=0))
    return np.concatenate([kappa * PRESSURE_RESOLUTION, RESOLUTION * tau])


def static_noise_draws(rec: StaticRecord, arm, noise: dict, *, draws: int = 8,
                       seed: int = 0) -> tuple:
    """Changes of the rest-point balances under extra noise of the window means (Monte Carlo).

    The means get white noise of the sample noise / sqrt(samples in the
    window) (seeded); see :func:`~.residuals.noise_draws`.

    Parameters
    ----------
    rec : StaticRecord
    arm : ArmParameters
    noise : dict
        :func:`static_noise`.
    draws : int, keyword-only
    seed : int, keyword-only

    Returns
    -------
    dY : numpy.ndarray, shape (draws, m, 6)
    dX : numpy.ndarray, shape (draws, m, 6, NMU)
    """
    qm, pm = rec.means(rec.q), rec.means(rec.p)
    um = None if rec.u is None else rec.means(rec.u)
    decl = _declared_means(rec, rec.q, arm)
    y0, X0 = _equations(qm, pm, um, arm, decl)
    s = 1.0 / np.sqrt(rec.counts())[:, None]
    rng = np.random.default_rng(seed)
    dY, dX = [], []
    for _ in range(draws):
        y, X = _equations(qm + rng.normal(size=qm.shape) * noise["q"] * s,
                          pm + rng.normal(size=pm.shape) * noise["p"] * s, um, arm, decl)
        dY.append(y - y0)
        dX.append(X - X0)
    return np.array(dY), np.array(dX)


def force_residuals(rec: StaticRecord, arm, noise: dict, delta=0.0) -> dict | None:
    """The force subsystem of §3.5.1.6: measured minus predicted muscle forces at the rest points.

    Predicted: (3.9) at the measured pressure and contraction (window
    means of the sample-wise forces), times ``1 + delta_k (W_k - W_fit)``: "before" with the
    arm's declared delta (none: the force law alone), "after" with ``delta``.  Also fits
    delta on the forces alone (least squares over the four muscles, one delta).

    Parameters
    ----------
    rec : StaticRecord
    arm : ArmParameters
    noise : dict
        :func:`static_noise` (its ``"F"`` entry).
    delta : float or array_like, shape (4,)
        Hysteresis scale of the "after" model [-] (one value, or one per muscle group).

    Returns
    -------
    dict or None
        None without forces; else ``residual_before``/``residual_after``
        (m, 4) [N], ``sigma`` (4,) [N] (noise of a window mean, at least
        :data:`RESOLUTION` x the RMS force),
        ``rho_before``/``rho_after`` (4,), ``delta_forces`` with its
        ``delta_forces_se`` (standard error) and per-muscle
        ``delta_per_muscle`` [-].
    """
    if rec.F is None:
        return None
    h, _, eps = hysteresis_signature(rec.q, rec.p, arm)
    fm = np.stack([muscle_force(k + 1, eps[:, k], rec.p[:, k], arm) for k in range(4)], 1)
    r_law = rec.means(rec.F - fm)
    sig_cols = rec.means(fm * h)
    sigma = np.maximum(noise["F"] / np.sqrt(np.mean(rec.counts())),
                       RESOLUTION * np.sqrt(np.mean(rec.means(fm) ** 2, axis=0)))
    r0 = r_law - declared_hysteresis(arm)[None, :] * sig_cols
    r1 = r_law - np.broadcast_to(np.asarray(delta, float), (4,))[None, :] * sig_cols
    a = (sig_cols / sigma).ravel()
    b = (r_law / sigma).ravel()
    d_all = float(a @ b / (a @ a)) if a @ a > 0 else 0.0
    res = b - d_all * a
    se = float(np.sqrt(res @ res / max(b.size - 1, 1) / (a @ a))) if a @ a > 0 else np.inf
    per = [float(sig_cols[:, k] @ r_law[:, k] / (sig_cols[:, k] @ sig_cols[:, k]))
           if sig_cols[:, k] @ sig_cols[:, k] > 0 else 0.0 for k in range(4)]
    return {"residual_before": r0, "residual_after": r1, "sigma": sigma,
            "rho_before": np.sqrt(np.mean((r0 / sigma) ** 2, axis=0)),
            "rho_after": np.sqrt(np.mean((r1 / sigma) ** 2, axis=0)),
            "delta_forces": d_all, "delta_forces_se": se, "delta_per_muscle": per}


def static_equilibria(rec: StaticRecord, rows, *, steps: int = CONTINUATION_STEPS) -> tuple:
    """The model's rest angles at every rest point (quasi-static continuation).

    Per plant row: pressures from the set values through the row's static
    valve model p = v1 + v2 u (3.12) (measured pressures when the record
    has no u); then, from the first measured rest angles, every next rest
    point is reached in ``steps`` linear steps of the pressures, each an
    equilibrium ``sum_k p_k m_tau,k(q) (1 + delta_k (W_k - W_fit)) + b = G(q)``
    solved by Newton's method with the Preisach memories peeked, then
    committed (the plant's hysteresis and joint torque bias b when the row has them on).

    Parameters
    ----------
    rec : StaticRecord
    rows : numpy.ndarray, shape (B, NP)
        Packed plant rows.
    steps : int, keyword-only
        Continuation steps between rest points.

    Returns
    -------
    q : numpy.ndarray, shape (B, m, 2)
        Rest angles [rad].
    p : numpy.ndarray, shape (B, m, 4)
        Pressures used [Pa].
    """


    rows = np.atleast_2d(np.asarray(rows, dtype=float))
    qm, pm = rec.means(rec.q), rec.means(rec.p)
    um = None if rec.u is None else rec.means(rec.u)
    B, m = rows.shape[0], rec.m
    Q, Pout = np.zeros((B, m, 2)), np.zeros((B, m, 4))
    mt, dmt, vol = np.empty(4), np.empty(4), np.empty(4)
    for b in range(B):
        P = np.ascontiguousarray(rows[b])
        if um is None:
            pres = pm
        else:
            v1, v2 = lay.PLANT.read(P, "v1"), lay.PLANT.read(P, "v2")
            pres = v1 + v2 * um
        hyst = int(P[lay.HYST_MODE]) == lay.Switch.ON
        z = initial_effect_state(P)[0].copy() if hyst else None
        bias = ((P[lay.TORQUE_BIAS], P[lay.TORQUE_BIAS + 1])
                if int(P[lay.TORQUE_BIAS_MODE]) == lay.Switch.ON else (0.0, 0.0))

        def es_of(q):
            c1, s1 = np.cos(q[0]), np.sin(q[0])
            c12, s12 = np.cos(q[0] + q[1]), np.sin(q[0] + q[1])
            return [scaled_contraction(group_contraction(k, c1, s1, c12, s12, P),
                                       P[lay.HYST_EPS_MAX]) for k in range(4)]

        def balance(q, p):
            torque_kernel(q[0], q[1], P, mt, dmt, vol)
            f = np.ones(4)
            if hyst:
                es = es_of(q)
                for k in range(4):
                    w = preisach_peek(z, es[k], lay.Z_HYST + k * lay.HYST_ROW)
                    f[k] = hysteresis_factor(P[lay.HYST_DELTA + k], w, es[k],
                                             P[lay.HYST_WFIT_SLOPE], P[lay.HYST_WFIT_INTERCEPT])
            g1, g2 = gravity_torque(q[0], q[1], P)
            return np.array([p[0] * mt[0] * f[0] + p[1] * mt[1] * f[1] + bias[0] - g1,
                             p[2] * mt[2] * f[2] + p[3] * mt[3] * f[3] + bias[1] - g2])

        q = qm[0].copy()
        prev = pres[0]
        for i in range(m):
            for s in range(1, steps + 1) if i else (steps,):
                p = prev + (pres[i] - prev) * s / steps if i else pres[0]
                q = fsolve(lambda x: balance(x, p), q, xtol=1e-12)
                if hyst:
                    for k, e in enumerate(es_of(q)):
                        preisach_update(z, e, lay.Z_HYST + k * lay.HYST_ROW)
            prev = pres[i]
            Q[b, i], Pout[b, i] = q, pres[i]
    return Q, Pout


__all__ = ["StaticRecord", "static_record", "static_system", "static_noise",
           "static_noise_draws", "static_floor", "force_residuals", "RESOLUTION",
           "PRESSURE_RESOLUTION", "static_equilibria", "STATIC_CANDIDATES",
           "WINDOW_GAP_FACTOR", "CONTINUATION_STEPS"]
