"""Worst head placement around the tool point.

The thesis (§6.3.2, fig. 6.2) puts the head centre along the TCP velocity at
the impact instant, "in order to obtain the highest possible HIC value".  This
module searches every placement instead, and every instant of an experiment.

**Placement.**  The head (free sphere, mass m_h, radius R, *at rest* at t0 as
in the thesis) touches the tool point with its centre at r_tcp + R u(psi)::

    u(psi) = cos(psi) e_v + sin(psi) e_perp,    e_v = v_tcp/|v_tcp|,
    e_perp = e_v turned +90 deg (counter-clockwise in the base frame),

psi in (-90, 90) deg: the tool can only hit a head towards which it moves,
v_n = v_tcp . u = |v_tcp| cos(psi) > 0.  psi = 0 is the thesis' choice (and
at psi = 0 the case rows are bitwise those of
:func:`~ppamsafety.impact.model.simulate_impacts` with its default
direction).  phi = atan2(u_y, u_x) is the absolute placement angle.

**Predictor (two-body physics).**  During the few-ms contact the joint
springs barely act (§6.3.4), so an impact along u is close to the two-body
impact of the effective mass m_eff(u) = 1/(u^T J H^-1 J^T u) with speed v_n
against the head: reduced mass mu = m_eff m_h/(m_eff + m_h).  Its Hunt-
Crossley solution scales exactly: with delta_m = ((n+1) mu v^2/(2k))^(1/(n+1)),
F_s = k delta_m^n and tau = delta_m/v, the dimensionless penetration obeys
x'' = -(n+1)/2 x^n (1 + (b/k) v x'), so::

    F_max = F_s g(v),      HIC = tau (F_s/(m_h g0))^2.5 h(v)

(if the pulse fits in the HIC window) with g, h functions of (b/k) v only,
tabulated once per head model by the two-body kernel
(:class:`TwoBodyPredictor`).  The predictor over a psi grid costs a few
array operations per instant; on the thesis arm it agrees with the full
engine to 0.1 % near the optimum and lies above it elsewhere (the tangential
sliding of the head lowers the normal closing speed).  The maximising
direction of mu v_n^2 alone (no damping) is u ~ (J H^-1 J^T + I/m_h)^-1 v_tcp,
with the whole "effective kinetic energy" v^T (M + I/m_h)^-1 v: not the
velocity direction unless v_tcp is an eigenvector of M.

**Search.**  Per state and per metric (F_max, HIC36): the predictor's best
psi on a 1-deg grid, then the full engine (fixed-step RK4, the reference
integrator) with a bounded Brent search (:func:`scipy.optimize.minimize_scalar`)
on a bracket around it, widened until the engine value at both ends is below
the middle.  Every evaluated placement is a valid impact, so the reported
maximum is the best engine value seen (never a model value).

**Every instant, and what is rigorous.**  First, instants whose predictor
*envelope* (the prediction at the largest effective mass of the state and the
full tool speed, an upper bound of the prediction over every psi because both
scales grow with mass and speed; g and h by their running maxima) is below a
simulated thesis-placement value by more than ``margin`` are dropped (same
footing as tier 2 below).  The rest are pruned in two tiers:

1. Rigorous: :func:`~ppamsafety.impact.bounds.impact_bounds` bounds F_max and
   HIC of an instant *for every head placement*: its derivation uses only
   the energy at t0 (independent of u), the smallest effective mass over all
   directions and configurations, and, for the HIC, a cone about whichever
   initial normal u the head has.  An instant whose bound is below the best
   engine value found cannot hold the worst case, in any direction.
2. Predictor: an instant is searched only if (1 + ``margin``) times its
   predicted maximum over psi reaches the best engine value.  This is not a
   proof; it is checked at run time: the largest ratio engine/predictor over
   every simulated placement (``rho``) must stay below 1 + margin/2,
   otherwise the margin is doubled past it and the selection is repeated
   (:attr:`WorstDirection.margin` reports the margin used).  Among the
   selected instants, the predicted direction is simulated first and only
   instants within ``search_tol`` of the best are refined by Brent.

The thesis-direction worst over every instant is found by the same two tiers
(engine at psi = 0); it equals
:func:`~ppamsafety.impact.instants.worst_instant` (tested).
"""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..results import Result
from .._validation import (MAX_BYTES, as_float_array, check_bool, check_int, check_range,
                           check_range_array, check_finite_result, check_size)
from ..plant import dynamics as dyn
from ..plant import geometry as geo
from ..plant import packing
from ..plots.impact import plot_direction_optimum, plot_direction_polar
from ..units import G0
from . import engine as eng
from .bounds import impact_bounds
from .instants import impact_states, _check_result
from .model import (BYTES_PER_CASE, ENERGY_TOL, MAX_JOINT_SPEED, check_angles, check_arm,
                    check_pass_through, check_stiffness, resolve_head)
from .twobody import two_body_impact

#: Largest |psi| searched [rad]: 89 deg (v_n = |v_tcp| cos(psi) > 0; at 90 deg the tool grazes).
PSI_LIMIT = math.radians(89.0)
#: Predictor grid over psi: 1-deg spacing from -89 to 89 deg (includes psi = 0 exactly).
PSI_GRID = np.radians(np.arange(-89.0, 89.5, 1.0))
#: Half-width of the first Brent bracket around the predicted best psi [rad].
BRACKET = math.radians(4.0)
#: Default Brent tolerance on psi [rad] (0.057 deg; near their maximum F_max and HIC vary
#: by about 1e-4 relative per deg^2, so by < 1e-6 within it).
XTOL = 1e-3
#: Default predictor margin (see the module docstring, tier 2).
MARGIN = 0.01
#: Default refinement tolerance: instants whose engine value at the predicted direction is
#: more than this fraction below the best are not refined.  Safe if no refinement gains more
#: than this over the predicted direction; the largest gain seen (``refine_gain``, about 1e-3
#: on the thesis experiments) must stay below half of it, else a warning is given.
SEARCH_TOL = 3e-3
#: Speeds of the predictor table: log-spaced, TABLE_POINTS points from TABLE_VMIN [m/s].
TABLE_POINTS = 160
TABLE_VMIN = 1e-3
#: Reduced mass [kg] and RK4 step [s] of the table's two-body impacts (short pulses).
TABLE_MU = 0.1
TABLE_DT = 5e-6
#: Default largest tabulated speed [m/s] (the thesis' impacts stay below 4 m/s).
VMAX_DEFAULT = 8.0


def _check_psi(name, psi):
    n = np.size(psi) if isinstance(psi, np.ndarray) else None
    if n is not None:                       # an array is sized before it is copied
        _check_placements(name, n)
    a = as_float_array(name, psi, ndim=(0, 1))
    _check_placements(name, a.size)
    check_range_array(name, a, -PSI_LIMIT, PSI_LIMIT, unit="rad")
    return a


def _check_placements(name, n):
    check_size(f"{name}: {n:,} head placements", n * BYTES_PER_CASE,
               remedy=f"give at most {MAX_BYTES // BYTES_PER_CASE:,} angles per call")


def _s(mu, v, hm):
    """Two-body scales: (F_s [N], HIC scale [-]) for reduced mass mu [kg] and speed v [m/s]."""
    k, n = hm.stiffness, hm.exponent
    dm = ((n + 1.0) * mu * v * v / (2.0 * k)) ** (1.0 / (n + 1.0))
    fs = k * dm ** n
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = np.where(v > 0, dm / np.where(v > 0, v, 1.0), 0.0)
    return fs, tau * (fs / (hm.mass * G0)) ** 2.5


@dataclass(frozen=True)
class TwoBodyPredictor:
    """Two-body F_max and HIC36 of an impact along a direction (module docstring).

    Attributes
    ----------
    head : HeadContactModel
        Head and contact model.
    speeds : numpy.ndarray
        Table speeds [m/s], log-spaced, increasing.
    g, h : numpy.ndarray
        F_max / F_s and HIC36 / (tau (F_s/(m_h g0))^2.5) at the table speeds [-].
    """

    head: object
    speeds: np.ndarray
    g: np.ndarray
    h: np.ndarray

    def predict(self, mu, v):
        """Predicted (F_max [N], HIC36 [-]) for reduced masses ``mu`` and normal speeds ``v``.

        Parameters
        ----------
        mu : array_like
            Reduced mass m_eff m_h/(m_eff + m_h) [kg], > 0.
        v : array_like
            Normal closing speed [m/s], >= 0 (0 gives 0); broadcast with ``mu``.
            Speeds above the table are extrapolated with the last table value.

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            F_max [N] and HIC36 [-].
        """
        mu = as_float_array("mu", mu)
        v = as_float_array("v", v)
        if np.any(mu <= 0):
            raise ValueError(f"mu = {mu.min():g} kg must be positive")
        if np.any(v < 0):
            raise ValueError(f"v = {v.min():g} m/s must be >= 0")
        return self._predict(mu, v)

    def _envelope(self, mu, v):
        """Upper envelope over psi: prediction at reduced mass ``mu`` and full speed ``v``
        with g, h replaced by their running maxima over the table speeds up to v."""
        lv = np.log(np.clip(v, self.speeds[0], None))
        ls = np.log(self.speeds)
        fs, hs = _s(mu, v, self.head)
        return (fs * np.interp(lv, ls, np.maximum.accumulate(self.g)),
                hs * np.interp(lv, ls, np.maximum.accumulate(self.h)))

    def _predict(self, mu, v):
        lv = np.log(np.clip(v, self.speeds[0], None))
        ls = np.log(self.speeds)
        fs, hs = _s(mu, v, self.head)
        return fs * np.interp(lv, ls, self.g), hs * np.interp(lv, ls, self.h)


@functools.lru_cache(maxsize=16)
def _table(hm, vmax):
    v = np.geomspace(TABLE_VMIN, vmax, TABLE_POINTS)
    arm_mass = 1.0 / (1.0 / TABLE_MU - 1.0 / hm.mass)
    r = two_body_impact(v, arm_mass=arm_mass, head_mass=hm.mass, stiffness=hm.stiffness,
                        exponent=hm.exponent, damping=hm.damping, dt=TABLE_DT, duration=0.05)
    fs, hs = _s(TABLE_MU, v, hm)
    g, h = r["F_max"] / fs, r["HIC36"] / hs
    for a in (v, g, h):
        a.setflags(write=False)
    return TwoBodyPredictor(hm, v, g, h)


def two_body_predictor(head=None, *, vmax: float = VMAX_DEFAULT) -> TwoBodyPredictor:
    """Tabulate the two-body scaling functions g, h of ``head`` up to ``vmax``.

    Parameters
    ----------
    head : HeadContactModel or str, optional
        Head model or its name (default ``"thesis-frontal"``).
    vmax : float
        Largest tabulated speed [m/s], in [0.01, 100].

    Returns
    -------
    TwoBodyPredictor
    """
    hm = resolve_head(head)
    vmax = check_range("vmax", vmax, 0.01, 100.0, unit="m/s")
    return _table(hm, vmax)


def _check_predictor(predictor, hm, vmax):
    """``predictor`` checked against the head and the largest speed, or a new table."""
    if predictor is None:
        return two_body_predictor(hm, vmax=max(VMAX_DEFAULT, 1.2 * vmax))
    if not isinstance(predictor, TwoBodyPredictor):
        raise TypeError(f"predictor must be a TwoBodyPredictor or None, got "
                        f"{type(predictor).__name__}")
    if predictor.head != hm:
        raise ValueError(f"predictor was tabulated for the head {predictor.head.name!r}, the "
                         f"impacts use {hm.name!r}")
    if predictor.speeds[-1] < vmax:
        raise ValueError(f"predictor covers speeds up to {predictor.speeds[-1]:g} m/s, the tool "
                         f"reaches {vmax:g} m/s")
    return predictor


# ---- per-state geometry and the engine --------------------------------------------------------
def _frame(arm, q, qd):
    """TCP velocity (as simulate_impacts computes it), e_v, e_perp, J H^-1 J^T per state."""
    J = geo.jacobian(q, arm)
    vt = np.einsum("nij,nj->ni", J, qd)
    speed = np.linalg.norm(vt, axis=1)
    e = vt / np.where(speed > 0, speed, 1.0)[:, None]
    ep = np.stack([-e[:, 1], e[:, 0]], axis=1)
    M = J @ np.linalg.inv(dyn.inertia_matrix(q, arm)) @ np.swapaxes(J, -1, -2)
    return vt, speed, e, ep, M


def _placement(e, ep, psi):
    """u(psi) for frames (N, 2) and angles psi (N,) or (N, G): shape (N, 2) or (N, G, 2)."""
    c, s = np.cos(psi), np.sin(psi)
    if np.ndim(psi) == 2:
        return c[..., None] * e[:, None, :] + s[..., None] * ep[:, None, :]
    return c[:, None] * e + s[:, None] * ep


def _mass_speed(M, speed, psi, e, ep, mh):
    """Reduced mass [kg], normal speed [m/s] and m_eff [kg] for placements psi ((N,) or (N, G)).

    u^T M u = c^2 e.Me + 2 c s e.Mp + s^2 p.Mp with c, s = cos, sin psi and p = e_perp.
    """
    a = np.einsum("ni,nij,nj->n", e, M, e)
    b = np.einsum("ni,nij,nj->n", e, M, ep)
    d = np.einsum("ni,nij,nj->n", ep, M, ep)
    c, s = np.cos(psi), np.sin(psi)
    if np.ndim(psi) == 2:
        a, b, d, speed = a[:, None], b[:, None], d[:, None], speed[:, None]
    inv = c * c * a + 2.0 * c * s * b + s * s * d
    return 1.0 / (inv + 1.0 / mh), speed * c, 1.0 / inv


class _Engine:
    """Calls the compiled fixed-step engine (:func:`~.engine.impact_batch`) on raw case rows.

    Same rows, step, duration and HIC windows as :func:`simulate_impacts` with
    ``integrator="fixed"``; the inputs are validated once by the caller.
    """

    def __init__(self, arm, hm, dt, duration):
        self.P = np.array(packing.pack(arm))
        self.hp = eng.pack_head(hm)
        self.dt = float(dt)
        self.nsteps = int(math.ceil(duration / dt - 1e-9))
        self.w36 = int(math.floor(0.036 / dt * (1 + 1e-9)))
        self.w15 = int(math.floor(0.015 / dt * (1 + 1e-9)))
        self.HIST = np.zeros((0, self.nsteps + 1, eng.NHIST))
        self.calls = 0
        self.energy_error = 0.0

    def run(self, q, qd, K, u):
        n = len(u)
        cases = eng.pack_cases(n, q=q, qd=qd, K=K, u=u, v_head=0.0,
                               arm_mode=int(eng.ArmMode.FLEXIBLE))
        out = np.zeros((n, eng.NSUM))
        eng.impact_batch(np.ascontiguousarray(cases), self.P, self.hp, self.dt, self.nsteps,
                         self.w36, self.w15, out, self.HIST, np.full(n, -1, np.int64))
        self.calls += n
        check_finite_result("impact engine", out, "a direction search")
        self.energy_error = max(self.energy_error,
                                float(np.abs(out[:, eng.R_EBAL]).max(initial=0.0)))
        return out


_COL = {"F_max": eng.R_FMAX, "HIC36": eng.R_HIC36}


def _validate_states(arm, q, qd, K, hm, dt, duration, warn_area=True):
    """Shape, range and model-validity checks of impact states (as simulate_impacts)."""
    arm = check_arm(arm)
    q = np.atleast_2d(as_float_array("q", q, shape_tail=(2,), ndim=(1, 2)))
    qd = np.atleast_2d(as_float_array("qd", qd, shape_tail=(2,), ndim=(1, 2)))
    K = np.atleast_2d(as_float_array("stiffness", K, shape_tail=(2,), ndim=(1, 2)))
    n = max(len(q), len(qd), len(K))
    for name, a in (("q", q), ("qd", qd), ("stiffness", K)):
        if len(a) not in (1, n):
            raise ValueError(f"{name} has {len(a)} rows; q, qd and stiffness need 1 or {n} rows")
    q, qd, K = (np.ascontiguousarray(np.broadcast_to(a, (n, 2))) for a in (q, qd, K))
    if warn_area or np.any(np.abs(q) > 2.0 * math.pi):
        check_angles("q", q, arm, stacklevel=4)
    check_range_array("qd", qd, -MAX_JOINT_SPEED, MAX_JOINT_SPEED, unit="rad/s")
    check_range_array("stiffness", K, 0.0, math.inf, unit="N m/rad")
    dt = check_range("dt", dt, 1e-8, 1e-3, unit="s")
    duration = check_range("duration", duration, 1e-4, 10.0, unit="s")
    if duration < dt:
        raise ValueError(f"duration = {duration:g} s is shorter than dt = {dt:g} s")
    if n:
        check_stiffness(K, q, arm, eng.FREE_STRIDE * dt, dt)
    return arm, q, qd, K, dt, duration


# ---- one state ------------------------------------------------------------------------------
@dataclass
class DirectionSweep(Result):
    """F_max and HIC of one impact state for head placements on a grid (:func:`direction_sweep`).

    Attributes
    ----------
    table : pandas.DataFrame
        One row per placement: ``psi_deg`` (from the TCP velocity, counter-
        clockwise) and ``phi_deg`` (absolute, base frame) [deg], ``ux``,
        ``uy``, ``v_n`` [m/s], ``m_eff`` [kg], engine ``F_max`` [N],
        ``HIC36``, ``HIC15``, and the two-body predictions ``F_pred`` [N],
        ``HIC_pred``.
    velocity_deg : float
        Absolute direction of the TCP velocity [deg] (psi = 0).
    tcp_speed : float
        |v_tcp| [m/s].
    label : str
        Free text naming the state (used in plot titles).
    """

    table: pd.DataFrame
    velocity_deg: float
    tcp_speed: float
    label: str = ""

    def to_pandas(self) -> pd.DataFrame:
        """The sweep table (a copy).

        Returns
        -------
        pandas.DataFrame
        """
        return self.table.copy()

    def plot(self, **kwargs):
        """Polar plot of F_max over the placement angle (engine and predictor).

        Parameters
        ----------
        **kwargs
            Passed to :func:`ppamsafety.plots.impact.plot_direction_polar`.

        Returns
        -------
        matplotlib.figure.Figure
        """
        return plot_direction_polar([self], **kwargs)


def direction_sweep(arm, q, qd, stiffness, *, head=None, angles=None, dt: float = 2e-5,
                    duration: float = 0.05, label: str = "",
                    predictor: TwoBodyPredictor | None = None) -> DirectionSweep:
    """Simulate one impact state for every head placement psi in ``angles``.

    Parameters
    ----------
    arm : ArmParameters
        Kinematics and link inertias.
    q, qd : array_like, shape (2,)
        Link angles [rad] and velocities [rad/s] at the impact instant (the
        tool must move: |J qd| > 0).
    stiffness : array_like, shape (2,)
        Joint stiffnesses [N m/rad].
    head : HeadContactModel or str, optional
        Head model (default ``"thesis-frontal"``), at rest at t0.
    angles : array_like, optional
        Placements psi [rad] relative to the TCP velocity, each in
        [-89, 89] deg (default every 2.5 deg from -87.5 to 87.5).
    dt, duration : float
        Engine step and simulated time [s] (as :func:`simulate_impacts`).
    label : str
        Name of the state for plots.
    predictor : TwoBodyPredictor, optional
        Reuse a table (same head, covering the tool speed).

    Returns
    -------
    DirectionSweep
    """
    hm = resolve_head(head)
    psi = np.radians(np.arange(-87.5, 87.6, 2.5)) if angles is None else \
        np.atleast_1d(_check_psi("angles", angles))
    if not isinstance(label, str):
        raise TypeError(f"label must be a str, got {type(label).__name__}")
    arm, q, qd, K, dt, duration = _validate_states(arm, q, qd, stiffness, hm, dt, duration)
    if len(q) != 1:
        raise ValueError(f"q, qd, stiffness must describe one state, got {len(q)} rows")
    vt, speed, e, ep, M = _frame(arm, q, qd)
    if not speed[0] > 0:
        raise ValueError(f"qd = {qd[0].tolist()} rad/s: the tool point is at rest, no head "
                         f"placement gives an impact")
    check_pass_through(hm, speed)
    n = psi.size
    P = np.broadcast_to
    mu, vn, me = _mass_speed(P(M, (n, 2, 2)), P(speed, (n,)), psi, P(e, (n, 2)),
                             P(ep, (n, 2)), hm.mass)
    u = _placement(P(e, (n, 2)), P(ep, (n, 2)), psi)
    en = _Engine(arm, hm, dt, duration)
    out = en.run(P(q, (n, 2)), P(qd, (n, 2)), P(K, (n, 2)), u)
    pr = _check_predictor(predictor, hm, float(speed[0]))
    fp, hpred = pr._predict(mu, vn)
    vdeg = math.degrees(math.atan2(e[0, 1], e[0, 0]))
    tab = pd.DataFrame({"psi_deg": np.degrees(psi),
                        "phi_deg": np.degrees(np.arctan2(u[:, 1], u[:, 0])),
                        "ux": u[:, 0], "uy": u[:, 1], "v_n": vn, "m_eff": me,
                        "F_max": out[:, eng.R_FMAX], "HIC36": out[:, eng.R_HIC36],
                        "HIC15": out[:, eng.R_HIC15], "F_pred": fp, "HIC_pred": hpred})
    return DirectionSweep(tab, vdeg, float(speed[0]), label)


@dataclass
class DirectionOptimum(Result):
    """Worst head placement of one impact state (:func:`worst_direction_state`).

    Attributes
    ----------
    psi_F, psi_HIC : float
        Placements [rad from the TCP velocity] maximising F_max and HIC36.
    F_max, HIC36 : float
        Their engine values [N], [-].
    F_along_velocity, HIC_along_velocity : float
        Engine values at psi = 0, the head along the TCP velocity (the thesis' placement)
        [N], [-].
    velocity_deg : float
        Absolute direction of the TCP velocity [deg].
    evaluations : int
        Engine runs used.
    evaluated : pandas.DataFrame
        Every placement the search simulated: ``psi`` [rad], ``F_max`` [N], ``HIC36`` [-].
    """

    psi_F: float
    psi_HIC: float
    F_max: float
    HIC36: float
    F_along_velocity: float
    HIC_along_velocity: float
    velocity_deg: float
    evaluations: int
    evaluated: pd.DataFrame = field(default=None, repr=False)

    def to_pandas(self) -> pd.DataFrame:
        """One row: the fields above, angles also in degrees (``psi_F_deg``, ``psi_HIC_deg``).

        Returns
        -------
        pandas.DataFrame
        """
        d = {k: v for k, v in self.__dict__.items() if k != "evaluated"}
        d["psi_F_deg"], d["psi_HIC_deg"] = math.degrees(self.psi_F), math.degrees(self.psi_HIC)
        return pd.DataFrame([d])

    def plot(self, *, title: str = ""):
        """F_max and HIC36 at every placement the search simulated, the worst starred.

        The search samples the placements near the optima; the whole polar curve is
        :func:`direction_sweep` (its ``plot``).

        Parameters
        ----------
        title : str, keyword-only
            Figure title.
        """
        if self.evaluated is None:
            raise ValueError("this DirectionOptimum holds no evaluations to draw: make it "
                             "with worst_direction_state()")
        return plot_direction_optimum(self.evaluated, psi_F=self.psi_F, psi_HIC=self.psi_HIC,
                                      title=title)


def _search(en, q, qd, K, e, ep, psi0, col, xtol, seen):
    """Bounded Brent search of the engine value ``col`` over psi around psi0 (one state).

    ``seen`` (dict psi -> summary row) collects every evaluation.  Returns (psi, value).
    """
    from scipy.optimize import minimize_scalar

    def val(p):
        p = float(min(max(p, -PSI_LIMIT), PSI_LIMIT))
        if p not in seen:
            u = _placement(e, ep, np.array([p]))
            seen[p] = en.run(q, qd, K, u)[0]
        return seen[p][col]

    w = BRACKET
    a, b = psi0 - w, psi0 + w
    for _ in range(64):                  # widen / shift until the ends are below the middle
        a, b = max(a, -PSI_LIMIT), min(b, PSI_LIMIT)
        m = 0.5 * (a + b)
        va, vm, vb = val(a), val(m), val(b)
        if va > vm and a > -PSI_LIMIT:
            a, b = a - w, m
        elif vb > vm and b < PSI_LIMIT:
            a, b = m, b + w
        else:
            break
        w *= 2.0
    minimize_scalar(lambda p: -val(p), bounds=(a, b), method="bounded",
                    options={"xatol": xtol})
    best = max(seen, key=lambda p: seen[p][col])
    return best, float(seen[best][col])


def worst_direction_state(arm, q, qd, stiffness, *, head=None, dt: float = 2e-5,
                          duration: float = 0.05, xtol: float = XTOL) -> DirectionOptimum:
    """Head placement maximising F_max, and the one maximising HIC36, for one impact state.

    Parameters
    ----------
    arm : ArmParameters
        Kinematics and link inertias.
    q, qd : array_like, shape (2,)
        Link angles [rad] and velocities [rad/s] at the impact instant (moving tool).
    stiffness : array_like, shape (2,)
        Joint stiffnesses [N m/rad].
    head : HeadContactModel or str, optional
        Head model (default ``"thesis-frontal"``), at rest at t0.
    dt, duration : float
        Engine step and simulated time [s].
    xtol : float
        Brent tolerance on psi [rad], in [1e-8, 0.1].

    Returns
    -------
    DirectionOptimum
    """
    hm = resolve_head(head)
    xtol = check_range("xtol", xtol, 1e-8, 0.1, unit="rad")
    arm, q, qd, K, dt, duration = _validate_states(arm, q, qd, stiffness, hm, dt, duration)
    if len(q) != 1:
        raise ValueError(f"q, qd, stiffness must describe one state, got {len(q)} rows")
    vt, speed, e, ep, M = _frame(arm, q, qd)
    if not speed[0] > 0:
        raise ValueError(f"qd = {qd[0].tolist()} rad/s: the tool point is at rest, no head "
                         f"placement gives an impact")
    check_pass_through(hm, speed)
    pred = _check_predictor(None, hm, float(speed[0]))
    psi = PSI_GRID[None, :]
    mu, vn, _ = _mass_speed(M, speed, psi, e, ep, hm.mass)
    fp, hpd = pred._predict(mu, vn)
    en = _Engine(arm, hm, dt, duration)
    seen = {}
    seen[0.0] = en.run(q, qd, K, e)[0]
    pf, F = _search(en, q, qd, K, e, ep, float(PSI_GRID[np.argmax(fp[0])]), eng.R_FMAX, xtol,
                    seen)
    ph, H = _search(en, q, qd, K, e, ep, float(PSI_GRID[np.argmax(hpd[0])]), eng.R_HIC36, xtol,
                    seen)
    return DirectionOptimum(pf, ph, F, H, float(seen[0.0][eng.R_FMAX]),
                            float(seen[0.0][eng.R_HIC36]),
                            math.degrees(math.atan2(e[0, 1], e[0, 0])), en.calls,
                            pd.DataFrame({"psi": list(seen),
                                          "F_max": [float(r[eng.R_FMAX]) for r in seen.values()],
                                          "HIC36": [float(r[eng.R_HIC36])
                                                    for r in seen.values()]}))


# ---- every instant of an experiment -----------------------------------------------------------
@dataclass
class WorstDirection(Result):
    """Worst head placement over every instant of an experiment (:func:`worst_direction`).

    Attributes
    ----------
    label : str
        Name of the experiment (``result.name``).
    summary : dict
        Per metric m in ("F_max", "HIC36"): ``m + "_along_velocity"`` (worst over
        instants at psi = 0: the head along the TCP velocity, the thesis' placement) with
        ``t0_...``; ``m + "_worst"`` (worst over
        instants and placements), ``psi_...`` [deg], ``phi_...`` [deg, base
        frame], ``t0_...`` [s]; ``m + "_same_instant"`` (worst placement at
        the thesis' worst instant) with its ``psi``; ratios
        ``ratio_...`` = worst / along the velocity and ``ratio_..._same_instant``.
    candidates : pandas.DataFrame
        Instants simulated: ``t0`` [s], ``tcp_speed`` [m/s], predictions,
        bounds and engine values (NaN where not simulated) at psi = 0 and at
        the best psi found.
    sweep : DirectionSweep or None
        Engine and predictor over psi at the instant of the worst F_max
        (None with ``sweep=False``).
    counts : dict
        ``instants`` (candidates), ``bound_pruned`` (instants whose rigorous
        bounds lie below the worst values found for both metrics: provably
        not the worst in any placement), ``envelope_pruned`` (dropped by the
        predictor envelope before the psi grid), ``simulated_instants``,
        ``searched`` (Brent-refined instants), ``engine_runs``.
    margin : float
        Predictor margin finally used.
    rho : float
        Largest engine / predictor ratio over every simulated placement
        (F_max or HIC36); below 1 + margin/2 by construction.
    refine_gain : float
        Largest relative gain of the Brent refinement over the predicted
        direction (F_max or HIC36) on the refined instants.
    energy_error : float
        Largest |energy balance error| of the simulated impacts [-].
    """

    label: str
    summary: dict
    candidates: pd.DataFrame
    sweep: DirectionSweep | None
    counts: dict
    margin: float
    rho: float
    refine_gain: float
    energy_error: float

    def to_pandas(self) -> pd.DataFrame:
        """One row: label, the summary values, counts and checks.

        Returns
        -------
        pandas.DataFrame
        """
        return pd.DataFrame([{"label": self.label, **self.summary, **self.counts,
                              "margin": self.margin, "rho": self.rho,
                              "refine_gain": self.refine_gain,
                              "energy_error": self.energy_error}])

    def plot(self, **kwargs):
        """Polar plot of F_max over the placement at the worst instant.

        Parameters
        ----------
        **kwargs
            Passed to :func:`ppamsafety.plots.impact.plot_direction_polar`.

        Returns
        -------
        matplotlib.figure.Figure
        """
        if self.sweep is None:
            raise ValueError("no polar sweep was simulated (worst_direction(..., sweep=False))")
        return self.sweep.plot(**kwargs)


def _states(result, arm, every, min_speed):
    st = impact_states(result, arm)
    idx = np.arange(0, len(st), every)
    idx = idx[st["tcp_speed"].to_numpy()[idx] >= min_speed] if min_speed > 0 else idx
    if idx.size == 0:
        raise ValueError(f"result {result.name!r}: no instant with a tool speed >= "
                         f"min_speed = {min_speed:g} m/s")
    return st.iloc[idx].reset_index(drop=True)


def _tiered(en, predictor, hm, sel, q, qd, K, e, ep, M, speed, bound_all, margin, search_tol,
            xtol):
    """Tiers 1-2 and the refinement on the instants ``sel`` (indices local to ``sel``)."""
    q, qd, K, e, ep, M, speed = (np.ascontiguousarray(a[sel])
                                 for a in (q, qd, K, e, ep, M, speed))
    n = len(sel)
    mu, vn, _ = _mass_speed(M, speed, np.broadcast_to(PSI_GRID, (n, PSI_GRID.size)), e, ep,
                            hm.mass)
    pred = dict(zip(("F_max", "HIC36"), predictor._predict(mu, vn)))
    i0 = int(np.argmin(np.abs(PSI_GRID)))
    bound = {m: b[sel] for m, b in bound_all.items()}

    def engine(idx, psi):
        idx = np.atleast_1d(idx)
        psi = np.broadcast_to(psi, idx.shape)
        u = np.where((psi == 0.0)[:, None], e[idx], _placement(e[idx], ep[idx], psi))
        return en.run(q[idx], qd[idx], K[idx], u)

    rho = 0.0
    thesis, worst, cand_rows, searched, gain, refined = {}, {}, {}, set(), 0.0, {}
    for m, col in _COL.items():
        # thesis placement (psi = 0)
        p0 = pred[m][:, i0]
        top = int(np.argmax(p0))
        best0 = engine(top, 0.0)[0, col]
        c = np.union1d(np.nonzero(((1 + margin) * p0 >= best0) & (bound[m] >= best0))[0], [top])
        out0 = engine(c, 0.0)
        rho = max(rho, float(np.max(out0[:, col] / np.maximum(p0[c], 1e-300))))
        j = int(np.argmax(out0[:, col]))     # first maximum = earliest instant on ties
        thesis[m] = (int(c[j]), float(out0[j, col]))
        for ci, r in zip(c, out0):
            cand_rows.setdefault(int(ci), {})[f"{m}@thesis"] = r
        # every placement: predicted direction first
        pm = pred[m].max(axis=1)
        gi = pred[m].argmax(axis=1)
        top = int(np.argmax(pm))
        best = engine(top, PSI_GRID[gi[top]])[0, col]
        c = np.union1d(np.nonzero(((1 + margin) * pm >= best) & (bound[m] >= best))[0], [top])
        outp = engine(c, PSI_GRID[gi[c]])
        rho = max(rho, float(np.max(outp[:, col] / np.maximum(pm[c], 1e-300))))
        vals = outp[:, col]
        best = max(best, float(vals.max()))
        res = {int(ci): (float(PSI_GRID[gi[ci]]), float(v)) for ci, v in zip(c, vals)}
        for k in np.argsort(-vals, kind="stable"):
            ci = int(c[k])
            if vals[k] * (1 + search_tol) < best:
                break
            if (1 + margin) * pm[ci] < best or bound[m][ci] < best:
                continue
            seen = {float(PSI_GRID[gi[ci]]): outp[k]}
            ps, v = _search(en, q[ci:ci + 1], qd[ci:ci + 1], K[ci:ci + 1], e[ci:ci + 1],
                            ep[ci:ci + 1], float(PSI_GRID[gi[ci]]), col, xtol, seen)
            gain = max(gain, v / vals[k] - 1.0)
            searched.add(ci)
            refined.setdefault(m, {})[ci] = (ps, v)
            res[ci] = (ps, v)
            best = max(best, v)
        kbest = max(res, key=lambda i: (res[i][1], -i))
        worst[m] = (kbest, res[kbest][0], res[kbest][1])
        for ci, (ps, v) in res.items():
            cand_rows.setdefault(ci, {})[f"{m}@worst"] = (ps, v)
    return {"pred": pred, "bound": bound, "thesis": thesis, "worst": worst,
            "cand_rows": cand_rows, "searched": searched, "gain": gain, "rho": rho,
            "refined": refined}


def worst_direction(result, arm, *, every: int = 1, head=None, dt: float = 2e-5,
                    duration: float = 0.05, min_speed: float = 1e-3, margin: float = MARGIN,
                    search_tol: float = SEARCH_TOL, xtol: float = XTOL,
                    predictor: TwoBodyPredictor | None = None,
                    sweep: bool = True) -> WorstDirection:
    """Worst F_max and HIC36 over every instant and every head placement of an experiment.

    Method and what is proven: module docstring.  The head is at rest at t0.

    Parameters
    ----------
    result : ExperimentResult
        The closed-loop record.
    arm : ArmParameters
        The arm.
    every : int, keyword-only
        Instant stride [samples of the record] (1 = every control period).
    head : HeadContactModel or str, optional
        Head model (default ``"thesis-frontal"``).
    dt, duration : float
        Engine step and simulated time [s] (as :func:`simulate_impacts`).
    min_speed : float
        Instants whose tool speed is below this [m/s] are not candidates (> 0).
    margin : float
        Predictor margin in [0, 1] (tier 2 of the module docstring).
    search_tol : float
        Refinement tolerance in [0, 1].
    xtol : float
        Brent tolerance on psi [rad], in [1e-8, 0.1].
    predictor : TwoBodyPredictor, optional
        Reuse a table (must be for the same head and cover the speeds).
    sweep : bool
        Also simulate the polar sweep at the worst-F_max instant (for plots).

    Returns
    -------
    WorstDirection
    """
    result = _check_result(result)
    arm = check_arm(arm)
    every = check_int("every", every, 1, 10 ** 6)
    hm = resolve_head(head)
    min_speed = check_range("min_speed", min_speed, 0.0, 100.0, lo_open=True, unit="m/s")
    margin = check_range("margin", margin, 0.0, 1.0)
    search_tol = check_range("search_tol", search_tol, 0.0, 1.0)
    xtol = check_range("xtol", xtol, 1e-8, 0.1, unit="rad")
    st = _states(result, arm, every, min_speed)
    q, qd, K = (st[["q1", "q2"]].to_numpy(), st[["qd1", "qd2"]].to_numpy(),
                st[["K1", "K2"]].to_numpy())
    arm, q, qd, K, dt, duration = _validate_states(arm, q, qd, K, hm, dt, duration,
                                                   warn_area=False)
    vt, speed, e, ep, M = _frame(arm, q, qd)
    check_pass_through(hm, [speed.max()])   # the penetration grows with the speed
    predictor = _check_predictor(predictor, hm, float(speed.max()))
    n_all = len(st)
    en = _Engine(arm, hm, dt, duration)
    # tier 1: rigorous bounds, valid for every head placement (module docstring)
    bound_all = dict(zip(("F_max", "HIC36"), impact_bounds(arm, q, qd, head=hm,
                                                           duration=duration)))
    # tier 0 (predictor envelope): max over psi of the prediction <= prediction at the largest
    # effective mass and the full speed (both scales grow with mu and v; g, h by their running
    # maxima); instants whose envelope is below a simulated thesis-placement value by more than
    # the margin are dropped before the psi grid is evaluated.
    mmax = 1.0 / np.linalg.eigvalsh(M)[:, 0]
    env = predictor._envelope(mmax * hm.mass / (mmax + hm.mass), speed)
    mu0, vn0, _ = _mass_speed(M, speed, np.zeros(n_all), e, ep, hm.mass)
    p0_all = predictor._predict(mu0, vn0)
    keep = np.zeros(n_all, bool)
    seeds = {}
    for j, (m, col) in enumerate(_COL.items()):
        top = int(np.argmax(p0_all[j]))
        seeds[m] = float(en.run(q[top:top + 1], qd[top:top + 1], K[top:top + 1],
                                e[top:top + 1])[0, col])
    for _attempt in range(4):
        keep[:] = False
        for j, m in enumerate(_COL):
            keep |= (1 + margin) * env[j] >= seeds[m]
        sel = np.nonzero(keep)[0]
        res_ = _tiered(en, predictor, hm, sel, q, qd, K, e, ep, M, speed, bound_all, margin,
                       search_tol, xtol)
        if res_["rho"] <= 1 + margin / 2:
            break
        margin = 2.0 * (res_["rho"] - 1.0) + 1e-3
    else:
        warnings.warn(f"worst_direction({result.name!r}): the two-body predictor underestimates "
                      f"the engine by {res_['rho'] - 1:.3g} (margin {margin:.3g}); the search may "
                      f"miss the worst instant", UserWarning, stacklevel=2)
    st = st.iloc[sel].reset_index(drop=True)
    q, qd, K, e, ep, M, speed = (a[sel] for a in (q, qd, K, e, ep, M, speed))
    pred, bound, thesis, worst, cand_rows, searched, gain, rho, refined = (
        res_[k] for k in ("pred", "bound", "thesis", "worst", "cand_rows", "searched", "gain",
                          "rho", "refined"))
    i0 = int(np.argmin(np.abs(PSI_GRID)))

    # same instant: worst placement at the thesis' worst instants
    summary = {}
    for m, col in _COL.items():
        ti, tv = thesis[m]
        wi, wpsi, wv = worst[m]
        if ti in refined.get(m, {}):      # already refined in the tiered search
            ps, sv = refined[m][ti]
        else:
            ps, sv = _search(en, q[ti:ti + 1], qd[ti:ti + 1], K[ti:ti + 1], e[ti:ti + 1],
                             ep[ti:ti + 1], float(PSI_GRID[np.argmax(pred[m][ti])]), col, xtol,
                             {})
        if sv > wv:          # the thesis' instant refined beats the tiered search: keep it
            wi, wpsi, wv = ti, ps, sv
        u = _placement(e[wi:wi + 1], ep[wi:wi + 1], np.array([wpsi]))[0]
        summary.update({
            f"{m}_along_velocity": tv, f"t0_{m}_along_velocity": float(st["t"].iloc[ti]),
            f"{m}_worst": wv, f"psi_{m}_deg": math.degrees(wpsi),
            f"phi_{m}_deg": math.degrees(math.atan2(u[1], u[0])),
            f"t0_{m}_worst": float(st["t"].iloc[wi]), f"ratio_{m}": wv / tv,
            f"{m}_same_instant": sv, f"psi_{m}_same_instant_deg": math.degrees(ps),
            f"ratio_{m}_same_instant": sv / tv})
        worst[m] = (wi, wpsi, wv)
    wi = worst["F_max"][0]
    polar = None
    if check_bool("sweep", sweep):
        polar = direction_sweep(arm, q[wi], qd[wi], K[wi], head=hm, dt=dt, duration=duration,
                                predictor=predictor,
                                label=f"{result.name}, t0 = {st['t'].iloc[wi]:.3f} s")
        en.calls += len(polar.table)
    if gain > search_tol / 2:
        warnings.warn(f"worst_direction({result.name!r}): the refinement gained {gain:.3g} over "
                      f"the predicted direction, more than search_tol/2 = {search_tol / 2:g}; "
                      f"use a larger search_tol", UserWarning, stacklevel=2)
    rows = []
    for ci in sorted(cand_rows):
        d = cand_rows[ci]
        row = {"t0": float(st["t"].iloc[ci]), "tcp_speed": float(speed[ci]),
               "F_bound": float(bound["F_max"][ci]), "HIC36_bound": float(bound["HIC36"][ci]),
               "F_pred_along_velocity": float(pred["F_max"][ci, i0]),
               "F_pred_worst": float(pred["F_max"][ci].max()),
               "HIC_pred_along_velocity": float(pred["HIC36"][ci, i0]),
               "HIC_pred_worst": float(pred["HIC36"][ci].max()),
               "searched": ci in searched}
        for m, col in _COL.items():
            r = d.get(f"{m}@thesis")
            row[f"{m}_along_velocity"] = float(r[col]) if r is not None else np.nan
            w = d.get(f"{m}@worst")
            row[f"{m}_worst"] = w[1] if w is not None else np.nan
            row[f"psi_{m}_deg"] = math.degrees(w[0]) if w is not None else np.nan
        rows.append(row)
    cand = pd.DataFrame(rows)
    prune = ((bound_all["F_max"] < summary["F_max_worst"])
             & (bound_all["HIC36"] < summary["HIC36_worst"]))
    counts = {"instants": n_all, "bound_pruned": int(prune.sum()),
              "envelope_pruned": int(n_all - len(sel)), "simulated_instants": len(cand),
              "searched": len(searched), "engine_runs": en.calls}
    if en.energy_error > ENERGY_TOL:
        warnings.warn(f"worst_direction({result.name!r}): energy balance error "
                      f"{en.energy_error:.3g} > {ENERGY_TOL:g} in a simulated impact",
                      UserWarning, stacklevel=2)
    return WorstDirection(result.name, summary, cand, polar, counts, margin, rho, gain,
                          en.energy_error)


__all__ = ["TwoBodyPredictor", "two_body_predictor", "DirectionSweep", "direction_sweep",
           "DirectionOptimum", "worst_direction_state", "WorstDirection", "worst_direction",
           "PSI_GRID", "PSI_LIMIT"]
