"""The assembled plant: one ODE for arm, muscles and valves.

State (8,): ``x = [q1, q2, qd1, qd2, p1, p2, p3, p4]`` (rad, rad/s, Pa gauge).
Input (4,): valve set values ``u = [p_s1 .. p_s4]`` (Pa), optional external
joint torques ``tau_ext`` (2,) (N m).

    qdd = H^-1 (sum_i p_i m_tau,i + tau_ext - C qd - G - tau_f)       (3.1), (2.17)
    pd_i = (v1_i + v2_i u_i - p_i)/T_i - n (P_atm + p_i) m_tau,i qd_j / V_i    (3.6), (3.12)

Integration is a fixed-step classical Runge-Kutta 4 (:func:`rk4_step`) with
the input held constant over the step (zero-order hold), the natural scheme
for a 1 kHz digital control loop: one control period is ``substeps`` RK4
steps.  Everything is a numba kernel; :func:`simulate` also accepts a leading
batch axis (one row of parameters, initial state and inputs per variant).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel, leaf

from .._validation import as_float_array, check_int, check_range
from . import layout as lay
from .dynamics import forward_dynamics_cs
from .pneumatics import pressure_rates
from .torque import torque_kernel_cs

NX = 8          #: state dimension
NU = 4          #: input dimension
#: scratch length needed by rk4_step (5 state vectors + 3 x 4 torque buffers)
NWORK = 5 * NX + 12


@kernel
def plant_rhs(x, u, tau_ext, P, dx, work):
    """State derivative of the plant; writes ``dx`` (8,).  ``work`` >= 12 floats."""
    mt = work[0:4]
    dmt = work[4:8]
    vol = work[8:12]
    c1, s1 = math.cos(x[0]), math.sin(x[0])
    c2, s2 = math.cos(x[1]), math.sin(x[1])
    c12, s12 = c1 * c2 - s1 * s2, s1 * c2 + c1 * s2
    torque_kernel_cs(c1, s1, c12, s12, P, mt, dmt, vol)
    tau1 = x[4] * mt[0] + x[5] * mt[1] + tau_ext[0]
    tau2 = x[6] * mt[2] + x[7] * mt[3] + tau_ext[1]
    a1, a2 = forward_dynamics_cs(c1, s1, c2, s2, c12, s12, x[2], x[3], tau1, tau2, P)
    dx[0] = x[2]
    dx[1] = x[3]
    dx[2] = a1
    dx[3] = a2
    pressure_rates(x[4:8], u, x[2], x[3], mt, vol, P, dx[4:8])


@kernel
def rk4_step(x, u, tau_ext, h, P, work):
    """Advance ``x`` in place by one RK4 step of length ``h`` [s] (inputs held)."""
    k1 = work[0:8]
    k2 = work[8:16]
    k3 = work[16:24]
    k4 = work[24:32]
    xt = work[32:40]
    buf = work[40:52]
    plant_rhs(x, u, tau_ext, P, k1, buf)
    for i in range(NX):
        xt[i] = x[i] + 0.5 * h * k1[i]
    plant_rhs(xt, u, tau_ext, P, k2, buf)
    for i in range(NX):
        xt[i] = x[i] + 0.5 * h * k2[i]
    plant_rhs(xt, u, tau_ext, P, k3, buf)
    for i in range(NX):
        xt[i] = x[i] + h * k3[i]
    plant_rhs(xt, u, tau_ext, P, k4, buf)
    for i in range(NX):
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@kernel
def _simulate_batch(X0, U, TAU, dt, substeps, P, out):
    nb = X0.shape[0]
    nsteps = U.shape[1]
    work = np.empty(NWORK)
    x = np.empty(NX)
    h = dt / substeps
    u = np.empty(NU)
    tau = np.empty(2)
    for b in range(nb):
        x[:] = X0[b]
        Pb = P[b].copy()
        out[b, 0] = x
        for k in range(nsteps):
            u[:] = U[b, k]
            tau[:] = TAU[b, k]
            for _ in range(substeps):
                rk4_step(x, u, tau, h, Pb, work)
            out[b, k + 1] = x


def simulate(arm, x0, set_values, *, dt: float = 1e-3, substeps: int = 2,
             tau_ext=None, params=None) -> np.ndarray:
    """Simulate the plant with piecewise-constant valve set values.

    Parameters
    ----------
    arm : ArmParameters or sequence of ArmParameters
        The arm.  A sequence (one per batch row) runs parameter variants.
    x0 : array_like, shape (8,) or (B, 8)
        Initial state [q1, q2, qd1, qd2, p1..p4] (rad, rad/s, Pa).
    set_values : array_like, shape (N, 4) or (B, N, 4)
        Valve set values held over each interval of length ``dt`` [Pa].
    dt : float, keyword-only
        Input (control) period [s]; default 1 ms.
    substeps : int, keyword-only
        RK4 steps per ``dt``.
    tau_ext : array_like, shape (N, 2) or (B, N, 2), optional
        External joint torques [N m].
    params : numpy.ndarray, shape (NP,) or (B, NP), optional
        Pre-packed parameter rows (overrides ``arm``; for sweeps).

    Returns
    -------
    numpy.ndarray, shape (N + 1, 8) or (B, N + 1, 8)
        States at t = 0, dt, ..., N dt.
    """
    check_range("dt", dt, 1e-6, 1.0, unit="s")
    substeps = check_int("substeps", substeps, 1, 10000)
    x0 = as_float_array("x0", x0, shape_tail=(NX,))
    U = as_float_array("set_values", set_values, shape_tail=(NU,))
    batched = x0.ndim == 2 or U.ndim == 3
    X0 = np.atleast_2d(x0)
    if U.ndim == 2:
        U = U[None]
    B = max(X0.shape[0], U.shape[0])
    if params is None:
        arms = list(arm) if isinstance(arm, (list, tuple)) else [arm]
        rows = np.array([lay.pack(a) for a in arms])
    else:
        rows = np.atleast_2d(as_float_array("params", params, shape_tail=(lay.NP,)))
    B = max(B, rows.shape[0])
    X0 = np.array(np.broadcast_to(X0, (B, NX)))          # writable C copies: one
    U = np.array(np.broadcast_to(U, (B,) + U.shape[1:]))  # numba signature for all
    rows = np.array(np.broadcast_to(rows, (B, lay.NP)))
    if tau_ext is None:
        T = np.zeros((B, U.shape[1], 2))
    else:
        T = as_float_array("tau_ext", tau_ext, shape_tail=(2,))
        T = np.array(np.broadcast_to(T if T.ndim == 3 else T[None], (B, U.shape[1], 2)))
    out = np.empty((B, U.shape[1] + 1, NX))
    _simulate_batch(X0, U, T, float(dt), substeps, rows, out)
    return out if batched or B > 1 else out[0]


def state_derivative(x, set_values, arm, *, tau_ext=None) -> np.ndarray:
    """Plant state derivative for states ``x`` (..., 8) and inputs (..., 4)."""
    x = as_float_array("x", x, shape_tail=(NX,))
    u = as_float_array("set_values", set_values, shape_tail=(NU,))
    shape = np.broadcast_shapes(x.shape[:-1], u.shape[:-1])
    xf = np.ascontiguousarray(np.broadcast_to(x, shape + (NX,)).reshape(-1, NX))
    uf = np.ascontiguousarray(np.broadcast_to(u, shape + (NU,)).reshape(-1, NU))
    tf = np.zeros((xf.shape[0], 2)) if tau_ext is None else np.ascontiguousarray(
        np.broadcast_to(as_float_array("tau_ext", tau_ext, shape_tail=(2,)), shape + (2,)).reshape(-1, 2))
    out = np.empty_like(xf)
    _rhs_many(xf, uf, tf, lay.pack(arm), out)
    return out.reshape(shape + (NX,))


@kernel
def _rhs_many(X, U, T, P, out):
    work = np.empty(12)
    for n in range(X.shape[0]):
        plant_rhs(X[n], U[n], T[n], P, out[n], work)


def rest_state(q, arm) -> tuple[np.ndarray, np.ndarray]:
    """A state at rest in ``q`` and the constant set values that hold it there.

    The pressures are the plant's exact static gravity-compensation pressures
    (Delta-p approach with the arm's mean pressures), so the state is an
    equilibrium of the ODE.

    Returns
    -------
    x0 : numpy.ndarray, shape (8,)
    set_values : numpy.ndarray, shape (4,)
    """
    from .pneumatics import static_pressures

    q = as_float_array("q", q, shape_tail=(2,))
    if q.shape != (2,):
        raise ValueError("rest_state expects a single configuration q of shape (2,)")
    p = static_pressures(q, arm)
    if np.any(p < 0) or np.any(p > arm.pneumatics.p_max):
        raise ValueError(f"rest_state: configuration q = {q} needs pressures {p} Pa outside "
                         f"[0, {arm.pneumatics.p_max:g}] Pa")
    v1 = np.array([v.v1 for v in arm.valves.valves])
    v2 = np.array([v.v2 for v in arm.valves.valves])
    return np.concatenate([q, [0.0, 0.0], p]), (p - v1) / v2
