"""Clamping: the head pinned between the tool and a rigid wall (beyond thesis §6.3.5).

The thesis simulated only free (unconstrained) head impacts and expected the
2.5 kg arm "to be on the safe side" in clamping (§6.3.5).  Two cases:

**Transient clamping** (:func:`simulate_clamping`).  The impact model of
:mod:`ppamsafety.impact.engine` -- unactuated flexible-joint arm, rigid links,
joint springs K (2.18) about the frozen motor side, horizontal plane -- hits a
free rigid head (mass m_h, radius R) whose back already touches a rigid,
frictionless wall: the wall is the plane through the back of the head at t0,
perpendicular to the impact direction u (the worst case: the wall lies
exactly behind the head along the tool's motion).  The head moves in the
plane; the wall pushes back along -u with its own contact law
F_w = k_w d^n_w + b_w d^n_w d' (d = (x_h - x_h0) . u, the head's penetration
into the wall).  Default wall contact: the ``thesis-frontal`` Hunt-Crossley fit,
which is checked against the Hybrid III certification drop of a head onto a
*rigid plate* (49 CFR 572.32) -- the contact of a head with a wall; the
alternative ``iso15066-forehead`` is the linear skull spring of ISO/TS 15066.
State, energies and the tool contact are as in the free-impact engine, plus
the wall force and its dissipation; the energy balance is checked.  A
fixed-step RK4 kernel over a batch (:func:`simulate_clamping`) and the same
right-hand side under :func:`scipy.integrate.solve_ivp`
(:func:`simulate_clamping_scipy`) as a cross-check.

**Quasi-static clamping** (:func:`static_force_bound`).  Upper bound of the
force the actuators can press along u at a configuration: at equilibrium
J^T f_head = tau - G(q), so f_u = (J^-1 u) . (tau - G) is linear in the four
gauge pressures; its maximum over the box 0 <= p_i <= p_max (the hardware
bound) or over the Delta-p approach p = p_m +- Delta-p clipped to the box
(3.7; what the controllers can command) is at a vertex, computed exactly.

Data layouts declared here: :data:`CLAMP_STATE` (integrator state),
:data:`WALL` (wall contact parameters) and :data:`CLAMP_SUMMARY` (one summary
row).  Impact cases are rows of :data:`ppamsafety.impact.engine.CASE`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .._jit import kernel, step_kernel
from .._validation import (as_float_array, check_choice, check_finite_result, check_int,
                           check_range)
from ..layouts import Field, Layout
from ..plant import dynamics as dyn
from ..plant import geometry as geo
from ..plant import packing
from ..plant.dynamics import coriolis_cs
from ..plant.torque import torque_functions
from ..plots.iso import plot_clamping_histories
from . import engine as eng
from .contact import hunt_crossley_elastic, hunt_crossley_force, hunt_crossley_potential
from .engine import C_K, C_Q, C_QD, C_U, HP_B, HP_K, HP_M, HP_N, HP_R, arm_terms
from .model import (MAX_STEPS, check_angles, check_arm, check_pass_through, check_stiffness,
                    resolve_head)

CLAMP_STATE = Layout("clamping integrator state", [
    Field("q", 2, "rad", "link angles"),
    Field("w", 2, "rad/s", "link angular velocities"),
    Field("x_head", 2, "m", "head centre position", columns=("xh", "yh")),
    Field("v_head", 2, "m/s", "head centre velocity", columns=("vxh", "vyh")),
    Field("E_diss_tool", 1, "J", "energy dissipated by the tool-head contact damping"),
    Field("E_diss_wall", 1, "J", "energy dissipated by the head-wall contact damping"),
])
Y_Q, Y_W, Y_XH, Y_VH, Y_ET, Y_EW = CLAMP_STATE.offsets("q", "w", "x_head", "v_head",
                                                       "E_diss_tool", "E_diss_wall")
NY = CLAMP_STATE.size

WALL = Layout("clamping wall parameters", [
    Field("stiffness", 1, "N/m^n", "head-wall contact stiffness k_w"),
    Field("exponent", 1, "-", "head-wall contact exponent n_w"),
    Field("damping", 1, "N s/m^(n+1)", "head-wall Hunt-Crossley damping b_w"),
    Field("offset", 1, "m", "wall plane position along u: u . x_head at t0"),
])
WP_K, WP_N, WP_B, WP_OFF = WALL.offsets("stiffness", "exponent", "damping", "offset")

CLAMP_SUMMARY = Layout("clamping summary", [
    Field("F_max", 1, "N", "peak tool-head contact force"),
    Field("t_Fmax", 1, "s", "time of the peak tool-head force"),
    Field("F_wall_max", 1, "N", "peak head-wall force"),
    Field("delta_max", 1, "m", "largest tool-head penetration"),
    Field("wall_delta_max", 1, "m", "largest head-wall penetration"),
    Field("contact_time", 1, "s", "total time with a positive tool-head force"),
    Field("v_tcp0", 1, "m/s", "tool speed at t0"),
    Field("E_initial", 1, "J", "energy at t0 (kinetic arm energy)"),
    Field("E_dissipated", 1, "J", "energy dissipated by both contacts"),
    Field("E_balance_error", 1, "-", "largest |E(t) + dissipated - E_initial| / E_initial"),
])
(R_FMAX, R_TFMAX, R_FWMAX, R_DMAX, R_DWMAX, R_TCONT, R_V0, R_E0, R_ED,
 R_EBAL) = CLAMP_SUMMARY.offsets("F_max", "t_Fmax", "F_wall_max", "delta_max", "wall_delta_max",
                                 "contact_time", "v_tcp0", "E_initial", "E_dissipated",
                                 "E_balance_error")
NSUM = CLAMP_SUMMARY.size

#: Relative energy-balance error above which a clamping case is flagged (as the free engine).
ENERGY_TOL = 1e-3


@step_kernel
def _terms(y, P):
    """:func:`~ppamsafety.impact.engine.arm_terms` at the link angles of the clamping state."""
    return arm_terms(y[Y_Q], y[Y_Q + 1], P)


@step_kernel
def clamp_rhs(y, case, P, hp, wp, dy):
    """Derivative of the clamping state; returns (F_tool, F_wall, delta, delta_wall, |v_tcp|).

    Parameters
    ----------
    y : ndarray of float64, shape (NY,)
        State, layout :data:`CLAMP_STATE`; only read.
    case : ndarray of float64, shape (engine.NCASE,)
        Impact case, layout :data:`ppamsafety.impact.engine.CASE` (q0, K, u read).
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`).
    hp : ndarray of float64, shape (engine.HEAD.size,)
        Head mass, radius and tool-head contact, layout :data:`ppamsafety.impact.engine.HEAD`.
    wp : ndarray of float64, shape (WALL.size,)
        Wall contact and position, layout :data:`WALL`.
    dy : ndarray of float64, shape (NY,)
        Output, overwritten: dy/dt.
    """
    c2, s2, h11, h12, h22, x, yy, j11, j12, j21, j22 = _terms(y, P)
    w1, w2 = y[Y_W], y[Y_W + 1]
    vx, vy = j11 * w1 + j12 * w2, j21 * w1 + j22 * w2
    dx, dyy = y[Y_XH] - x, y[Y_XH + 1] - yy
    dist = math.sqrt(dx * dx + dyy * dyy)
    nx, ny = dx / dist, dyy / dist
    delta = hp[HP_R] - dist
    ddelta = -(nx * (y[Y_VH] - vx) + ny * (y[Y_VH + 1] - vy))
    f = hunt_crossley_force(delta, ddelta, hp[HP_K], hp[HP_N], hp[HP_B])
    ux, uy = case[C_U], case[C_U + 1]
    dw = y[Y_XH] * ux + y[Y_XH + 1] * uy - wp[WP_OFF]
    dwd = y[Y_VH] * ux + y[Y_VH + 1] * uy
    fw = hunt_crossley_force(dw, dwd, wp[WP_K], wp[WP_N], wp[WP_B])
    dy[Y_Q], dy[Y_Q + 1] = w1, w2
    c11, c12, c21, c22 = coriolis_cs(c2, s2, w1, w2, P)
    t1 = -case[C_K] * (y[Y_Q] - case[C_Q]) - (j11 * nx + j21 * ny) * f - c11 * w1 - c12 * w2
    t2 = -case[C_K + 1] * (y[Y_Q + 1] - case[C_Q + 1]) - (j12 * nx + j22 * ny) * f \
        - c21 * w1 - c22 * w2
    det = h11 * h22 - h12 * h12
    dy[Y_W] = (h22 * t1 - h12 * t2) / det
    dy[Y_W + 1] = (h11 * t2 - h12 * t1) / det
    dy[Y_XH], dy[Y_XH + 1] = y[Y_VH], y[Y_VH + 1]
    dy[Y_VH] = (f * nx - fw * ux) / hp[HP_M]
    dy[Y_VH + 1] = (f * ny - fw * uy) / hp[HP_M]
    dy[Y_ET] = (f - hunt_crossley_elastic(delta, hp[HP_K], hp[HP_N])) * ddelta \
        if delta > 0.0 else 0.0
    dy[Y_EW] = (fw - hunt_crossley_elastic(dw, wp[WP_K], wp[WP_N])) * dwd if dw > 0.0 else 0.0
    return f, fw, delta, dw, math.sqrt(vx * vx + vy * vy)


@step_kernel
def clamp_energy(y, case, P, hp, wp):
    """Kinetic + joint-spring + both contact potentials [J] (dissipation not included).

    Parameters
    ----------
    y : ndarray of float64, shape (NY,)
        State, layout :data:`CLAMP_STATE`.
    case : ndarray of float64, shape (engine.NCASE,)
        Impact case (layout :data:`ppamsafety.impact.engine.CASE`).
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row.
    hp : ndarray of float64, shape (engine.HEAD.size,)
        Head row (layout :data:`ppamsafety.impact.engine.HEAD`).
    wp : ndarray of float64, shape (WALL.size,)
        Wall row (layout :data:`WALL`).
    """
    _, _, h11, h12, h22, x, yy, _, _, _, _ = _terms(y, P)
    w1, w2 = y[Y_W], y[Y_W + 1]
    e = 0.5 * (h11 * w1 * w1 + 2.0 * h12 * w1 * w2 + h22 * w2 * w2)
    e += 0.5 * case[C_K] * (y[Y_Q] - case[C_Q]) ** 2 \
        + 0.5 * case[C_K + 1] * (y[Y_Q + 1] - case[C_Q + 1]) ** 2
    e += 0.5 * hp[HP_M] * (y[Y_VH] * y[Y_VH] + y[Y_VH + 1] * y[Y_VH + 1])
    dx, dyy = y[Y_XH] - x, y[Y_XH + 1] - yy
    e += hunt_crossley_potential(hp[HP_R] - math.sqrt(dx * dx + dyy * dyy), hp[HP_K], hp[HP_N])
    dw = y[Y_XH] * case[C_U] + y[Y_XH + 1] * case[C_U + 1] - wp[WP_OFF]
    e += hunt_crossley_potential(dw, wp[WP_K], wp[WP_N])
    return e


@step_kernel
def clamp_initial_state(case, P, hp, y):
    """Arm at q0 with qd0, head at rest with its surface at the tool and its back at the wall.

    Parameters
    ----------
    case : ndarray of float64, shape (engine.NCASE,)
        Impact case (layout :data:`ppamsafety.impact.engine.CASE`).
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row.
    hp : ndarray of float64, shape (engine.HEAD.size,)
        Head row (the radius is read).
    y : ndarray of float64, shape (NY,)
        Output, overwritten: the initial state.
    """
    y[Y_Q], y[Y_Q + 1] = case[C_Q], case[C_Q + 1]
    y[Y_W], y[Y_W + 1] = case[C_QD], case[C_QD + 1]
    _, _, _, _, _, x, yy, _, _, _, _ = _terms(y, P)
    y[Y_XH] = x + hp[HP_R] * case[C_U]
    y[Y_XH + 1] = yy + hp[HP_R] * case[C_U + 1]
    y[Y_VH], y[Y_VH + 1] = 0.0, 0.0
    y[Y_ET], y[Y_EW] = 0.0, 0.0


@kernel
def clamp_batch(CASES, P, hp, WP, dt, nsteps, every, SUM, HIST):
    """Fixed-step RK4 of every clamping case; fill SUM (N, NSUM) and HIST (N, m, 4).

    Parameters
    ----------
    CASES : ndarray of float64, shape (N, engine.NCASE)
        Impact cases (layout :data:`ppamsafety.impact.engine.CASE`).
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row.
    hp : ndarray of float64, shape (engine.HEAD.size,)
        Head row.
    WP : ndarray of float64, shape (N, WALL.size)
        Wall row per case (the offset depends on the case).
    dt : float
        RK4 step [s].
    nsteps : int
        Number of steps.
    every : int
        History stride [steps]; HIST holds samples 0, every, 2 every, ...
    SUM : ndarray of float64, shape (N, NSUM)
        Output: summary rows (layout :data:`CLAMP_SUMMARY`).
    HIST : ndarray of float64, shape (N, nsteps // every + 1, 4)
        Output: t [s], tool-head force [N], head-wall force [N], tool-head
        penetration [m] per recorded sample.
    """
    y = np.empty(NY)
    yt = np.empty(NY)
    k1, k2, k3, k4 = np.empty(NY), np.empty(NY), np.empty(NY), np.empty(NY)
    for c in range(CASES.shape[0]):
        case = CASES[c]
        wp = WP[c]
        clamp_initial_state(case, P, hp, y)
        e0 = clamp_energy(y, case, P, hp, wp)
        fmax, tmax, fwmax, dmax, dwmax, tcont, v0, ebal = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0
        for s in range(nsteps + 1):
            f, fw, delta, dw, vt = clamp_rhs(y, case, P, hp, wp, k1)
            if v0 < 0.0:
                v0 = vt
            if f > fmax:
                fmax, tmax = f, s * dt
            fwmax = max(fwmax, fw)
            dmax = max(dmax, delta)
            dwmax = max(dwmax, dw)
            if f > 0.0:
                tcont += dt
            err = abs(clamp_energy(y, case, P, hp, wp) + y[Y_ET] + y[Y_EW] - e0)
            ebal = max(ebal, err)
            if s % every == 0:
                r = s // every
                HIST[c, r, 0], HIST[c, r, 1], HIST[c, r, 2], HIST[c, r, 3] = s * dt, f, fw, delta
            if s == nsteps:
                break
            for i in range(NY):
                yt[i] = y[i] + 0.5 * dt * k1[i]
            clamp_rhs(yt, case, P, hp, wp, k2)
            for i in range(NY):
                yt[i] = y[i] + 0.5 * dt * k2[i]
            clamp_rhs(yt, case, P, hp, wp, k3)
            for i in range(NY):
                yt[i] = y[i] + dt * k3[i]
            clamp_rhs(yt, case, P, hp, wp, k4)
            for i in range(NY):
                y[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        row = SUM[c]
        row[R_FMAX], row[R_TFMAX], row[R_FWMAX] = fmax, tmax, fwmax
        row[R_DMAX], row[R_DWMAX], row[R_TCONT], row[R_V0] = dmax, dwmax, tcont, v0
        row[R_E0], row[R_ED] = e0, y[Y_ET] + y[Y_EW]
        row[R_EBAL] = ebal / e0 if e0 > 0.0 else 0.0


def _wall_row(wall, offset: float) -> np.ndarray:
    row = WALL.empty(1)[0]
    row[WP_K], row[WP_N], row[WP_B], row[WP_OFF] = (wall.stiffness, wall.exponent, wall.damping,
                                                    offset)
    return row


def _prepare(arm, q, qd, stiffness, head, wall, dt, duration, step_for_check):
    arm = check_arm(arm)
    q = as_float_array("q", q, ndim=(1, 2), shape_tail=(2,))
    q = np.atleast_2d(q)
    qd = np.atleast_2d(as_float_array("qd", qd, ndim=(1, 2), shape_tail=(2,)))
    K = np.atleast_2d(as_float_array("stiffness", stiffness, ndim=(1, 2), shape_tail=(2,)))
    n = q.shape[0]
    for name, a in (("qd", qd), ("stiffness", K)):
        if a.shape[0] != n:
            raise ValueError(f"{name} has {a.shape[0]} rows, q has {n}: give one per case")
    hm = resolve_head(head)
    wm = resolve_head(wall, "wall")
    dt = check_range("dt", dt, 1e-8, 1e-3, unit="s")
    duration = check_range("duration", duration, 1e-4, 10.0, unit="s")
    if duration < dt or duration / dt > MAX_STEPS:
        raise ValueError(f"duration = {duration:g} s and dt = {dt:g} s: need dt <= duration "
                         f"and duration / dt <= {MAX_STEPS}")
    check_angles("q", q, arm, stacklevel=4)
    if np.any(np.abs(qd) > 1e3):
        raise ValueError(f"qd = {qd.tolist()} rad/s is outside [-1000, 1000] rad/s")
    if np.any(K < 0):
        raise ValueError(f"stiffness = {K.tolist()} N m/rad must be non-negative")
    check_stiffness(K, q, arm, step_for_check, dt)
    J = geo.jacobian(q, arm)
    v = np.einsum("nij,nj->ni", J, qd)
    sp = np.linalg.norm(v, axis=1)
    if np.any(sp == 0.0):
        raise ValueError(f"qd: case(s) {np.nonzero(sp == 0)[0].tolist()} have the tool at rest; "
                         "there is no impact")
    check_pass_through(hm, sp)
    u = v / sp[:, None]
    cases = eng.pack_cases(n, q=q, qd=qd, K=K, u=u, v_head=0.0,
                           arm_mode=int(eng.ArmMode.FLEXIBLE))
    P = np.array(packing.pack(arm))
    hp = eng.pack_head(hm)
    r = geo.forward_kinematics(q, arm)
    offset = np.einsum("ni,ni->n", r + hm.radius * u, u)
    WP = np.stack([_wall_row(wm, float(o)) for o in offset])
    return cases, P, hp, WP, hm, wm, dt, duration


@dataclass
class ClampingResults:
    """Results of :func:`simulate_clamping`.

    Attributes
    ----------
    summary : pandas.DataFrame
        One row per case, columns of :data:`CLAMP_SUMMARY` plus ``energy_ok``
        (balance error below :data:`ENERGY_TOL`).
    t : numpy.ndarray, shape (m,)
        Recorded sample times [s].
    force : numpy.ndarray, shape (N, m)
        Tool-head force [N].
    wall_force : numpy.ndarray, shape (N, m)
        Head-wall force [N].
    penetration : numpy.ndarray, shape (N, m)
        Tool-head penetration [m].
    head : str
        Tool-head contact model name.
    wall : str
        Head-wall contact model name.
    meta : dict
        Free-form annotations (empty by default).
    """

    summary: pd.DataFrame
    t: np.ndarray
    force: np.ndarray
    wall_force: np.ndarray
    penetration: np.ndarray
    head: str = ""
    wall: str = ""
    meta: dict = field(default_factory=dict)

    def to_pandas(self) -> pd.DataFrame:
        """The summary table (a copy)."""
        return self.summary.copy()

    def plot(self):
        """Tool-head force histories of every case (a ``Figure``)."""
        return plot_clamping_histories(self)


def simulate_clamping(arm, q, qd, stiffness, *, head=None, wall="thesis-frontal",
                      dt: float = 1e-5, duration: float = 0.05,
                      record_every: int = 10) -> ClampingResults:
    """Transient clamping: the arm hits a head whose back touches a rigid wall.

    Same arm model and input rules as :func:`ppamsafety.impact.simulate_impacts`
    (impact direction = tool velocity, head at rest); the wall is the plane
    behind the head perpendicular to that direction.

    Parameters
    ----------
    arm : ArmParameters
        Link inertias and kinematics.
    q : array_like, shape (2,) or (N, 2)
        Link angles at the impact instant [rad].
    qd : array_like, shape (2,) or (N, 2)
        Link angular velocities [rad/s] (the tool must move).
    stiffness : array_like, shape (2,) or (N, 2)
        Joint stiffnesses K1, K2 [N m/rad], >= 0, resolvable by the step ``dt``.
    head : HeadContactModel or str, optional
        Head (mass, radius) and tool-head contact (default ``"thesis-frontal"``).
    wall : HeadContactModel or str
        Head-wall contact law (its k, n, b; mass and radius unused); default
        ``"thesis-frontal"`` (Hunt-Crossley fit checked against the Hybrid III
        head drop on a rigid plate).
    dt : float
        RK4 step [s], in [1e-8, 1e-3].
    duration : float
        Simulated time [s], in [1e-4, 10].
    record_every : int
        History stride [steps], >= 1.

    Returns
    -------
    ClampingResults
    """
    record_every = check_int("record_every", record_every, 1, 10 ** 7)
    cases, P, hp, WP, hm, wm, dt, duration = _prepare(arm, q, qd, stiffness, head, wall, dt,
                                                      duration, dt)
    nsteps = int(math.ceil(duration / dt - 1e-9))
    n = cases.shape[0]
    SUM = np.empty((n, NSUM))
    m = nsteps // record_every + 1
    HIST = np.zeros((n, m, 4))
    clamp_batch(cases, P, hp, WP, float(dt), nsteps, record_every, SUM, HIST)
    check_finite_result("simulate_clamping", SUM, f"head {hm.name!r}, wall {wm.name!r}")
    df = pd.DataFrame(SUM, columns=CLAMP_SUMMARY.columns())
    df["energy_ok"] = df["E_balance_error"] < ENERGY_TOL
    return ClampingResults(summary=df, t=HIST[0, :, 0].copy(), force=HIST[:, :, 1].copy(),
                           wall_force=HIST[:, :, 2].copy(), penetration=HIST[:, :, 3].copy(),
                           head=hm.name, wall=wm.name)


#: Integration methods of :func:`scipy.integrate.solve_ivp` accepted by the cross-check.
METHODS = ("RK45", "DOP853", "Radau", "LSODA")


def simulate_clamping_scipy(arm, q, qd, stiffness, *, head=None, wall="thesis-frontal",
                            method: str = "DOP853", rtol: float = 1e-10, atol: float = 1e-12,
                            duration: float = 0.05) -> dict:
    """One transient clamping case by ``solve_ivp`` (the same compiled right-hand side).

    Parameters
    ----------
    arm : ArmParameters
        Link inertias and kinematics.
    q, qd, stiffness : array_like, shape (2,)
        Link angles [rad], velocities [rad/s] and joint stiffnesses [N m/rad].
    head : HeadContactModel or str, optional
        Head and tool-head contact (default ``"thesis-frontal"``).
    wall : HeadContactModel or str
        Head-wall contact law (default ``"thesis-frontal"``).
    method : str
        One of :data:`METHODS`.
    rtol, atol : float
        Tolerances, each in [1e-14, 1e-3].
    duration : float
        Simulated time [s], in [1e-4, 10].

    Returns
    -------
    dict
        ``F_max``, ``F_wall_max`` [N] (maxima over the solver's steps and a
        dense 1 us grid), ``E_balance_error`` (relative, at the end) and ``nfev``.
    """
    from scipy.integrate import solve_ivp

    method = check_choice("method", method, METHODS)
    rtol = check_range("rtol", rtol, 1e-14, 1e-3)
    atol = check_range("atol", atol, 1e-14, 1e-3)
    cases, P, hp, WP, hm, wm, _, duration = _prepare(arm, q, qd, stiffness, head, wall, 1e-6,
                                                     duration, 1e-6)
    if cases.shape[0] != 1:
        raise ValueError(f"q has {cases.shape[0]} rows: simulate_clamping_scipy takes one case")
    case, wp = cases[0], WP[0]
    y0 = np.empty(NY)
    clamp_initial_state(case, P, hp, y0)
    e0 = clamp_energy(y0, case, P, hp, wp)
    dy = np.empty(NY)

    def rhs(t, y):
        clamp_rhs(y, case, P, hp, wp, dy)
        return dy.copy()

    t_eval = np.linspace(0.0, duration, int(round(duration / 1e-6)) + 1)
    sol = solve_ivp(rhs, (0.0, duration), y0, method=method, t_eval=t_eval, rtol=rtol, atol=atol)
    if not sol.success:
        raise ValueError(f"solve_ivp ({method}) failed: {sol.message}")
    F = np.empty(sol.y.shape[1])
    Fw = np.empty(sol.y.shape[1])
    for i in range(sol.y.shape[1]):
        F[i], Fw[i], _, _, _ = clamp_rhs(sol.y[:, i], case, P, hp, wp, dy)
    yend = sol.y[:, -1]
    err = abs(clamp_energy(yend, case, P, hp, wp) + yend[Y_ET] + yend[Y_EW] - e0) / e0
    return {"F_max": float(F.max()), "F_wall_max": float(Fw.max()), "E_balance_error": float(err),
            "nfev": int(sol.nfev)}


MODES = ("hardware", "delta_p")


def static_force_bound(q, direction, arm, *, mode: str = "hardware",
                       with_gravity: bool = True) -> pd.DataFrame:
    """Largest static force [N] the muscles can press the tool along ``direction`` at ``q``.

    At equilibrium with the tool blocked, J^T f = tau(p) - G(q) (f: the force
    the tool exerts on the head, tau (2.17) the muscle torques, G the gravity
    torque of the vertical-plane arm), so f_u = a . (tau - G) with
    a = J^-1 u.  f_u is linear in the gauge pressures; its maximum over the
    admissible pressures is at a vertex and is computed exactly.

    Parameters
    ----------
    q : array_like, shape (2,) or (N, 2)
        Joint angles [rad] of the clamping configurations (|q| <= 2 pi).
    direction : array_like, shape (2,) or (N, 2)
        Direction u of the pushing force (normalised; non-zero), broadcast
        against ``q``.
    arm : ArmParameters
        The arm (torque functions, p_max, p_m, plant gravity).
    mode : {"hardware", "delta_p"}, keyword-only
        ``"hardware"``: each muscle pressure anywhere in [0, p_max] (the
        physical limit).  ``"delta_p"``: the Delta-p approach (3.7) the
        controllers use, p_top = p_m + dp, p_bottom = p_m - dp, clipped to
        [0, p_max], any dp.
    with_gravity : bool
        Subtract the gravity torque (the experiments' vertical plane); False for
        a horizontal arm.

    Returns
    -------
    pandas.DataFrame
        One row per configuration: ``F_u`` [N] (the bound), ``p1``..``p4``
        [Pa] (pressures attaining it), ``tau1``, ``tau2`` [N m].
    """
    arm = check_arm(arm)
    q = np.atleast_2d(as_float_array("q", q, ndim=(1, 2), shape_tail=(2,)))
    d = np.atleast_2d(as_float_array("direction", direction, ndim=(1, 2), shape_tail=(2,)))
    try:
        q, d = np.broadcast_arrays(q, d)
    except ValueError:
        raise ValueError(f"direction (shape {d.shape}) does not broadcast against q "
                         f"(shape {q.shape})") from None
    nd = np.linalg.norm(d, axis=1)
    if not np.all(nd > 0):
        raise ValueError(f"direction must be non-zero vectors; row(s) "
                         f"{np.nonzero(~(nd > 0))[0].tolist()} are zero")
    u = d / nd[:, None]
    mode = check_choice("mode", mode, MODES)
    if not isinstance(with_gravity, bool):
        raise TypeError(f"with_gravity must be a bool, got {with_gravity!r}")
    check_angles("q", q, arm)
    J = geo.jacobian(q, arm)
    det = np.linalg.det(J)
    if np.any(np.abs(det) < 1e-9):
        raise ValueError(f"q: row(s) {np.nonzero(np.abs(det) < 1e-9)[0].tolist()} are singular "
                         "(stretched or folded arm)")
    a = np.linalg.solve(J, u[..., None])[..., 0]         # (N, 2)
    m = torque_functions(q, arm)                          # (N, 4) [N m/Pa]
    G = dyn.gravity(q, arm) if with_gravity else np.zeros_like(q)
    pmax = arm.pneumatics.p_max
    n = q.shape[0]
    p = np.empty((n, 4))
    for j, (top, bot) in enumerate(((0, 1), (2, 3))):
        if mode == "hardware":
            for i in (top, bot):
                p[:, i] = np.where(a[:, j] * m[:, i] > 0, pmax, 0.0)
        else:
            pm = arm.pneumatics.p_mean[j]
            cands = np.array([-pmax, -pm, -(pmax - pm), 0.0, pmax - pm, pm, pmax])
            pt = np.clip(pm + cands, 0.0, pmax)           # (7,)
            pb = np.clip(pm - cands, 0.0, pmax)
            val = a[:, j:j + 1] * (pt[None, :] * m[:, top:top + 1] + pb[None, :] * m[:, bot:bot + 1])
            k = np.argmax(val, axis=1)
            p[:, top], p[:, bot] = pt[k], pb[k]
    tau = np.stack([p[:, 0] * m[:, 0] + p[:, 1] * m[:, 1],
                    p[:, 2] * m[:, 2] + p[:, 3] * m[:, 3]], axis=1)
    F = np.einsum("ni,ni->n", a, tau - G)
    check_finite_result("static_force_bound", F, "these configurations")
    return pd.DataFrame({"F_u": F, "p1": p[:, 0], "p2": p[:, 1], "p3": p[:, 2], "p4": p[:, 3],
                         "tau1": tau[:, 0], "tau2": tau[:, 1]})


__all__ = ["CLAMP_STATE", "WALL", "CLAMP_SUMMARY", "ClampingResults", "simulate_clamping",
           "simulate_clamping_scipy", "static_force_bound", "clamp_rhs", "clamp_energy",
           "clamp_initial_state", "clamp_batch", "ENERGY_TOL", "MODES", "METHODS"]
