"""Contact anywhere on the arm: impacts of any contact point with any body region, and the worst.

* :func:`simulate_contacts` -- impacts of one contact point of the arm (tool point, elbow,
  forearm, upper arm, or any :class:`~ppamsafety.params.contact.ContactPoint`) with one body
  region (:class:`~ppamsafety.params.contact.BodyContact`) through the point's covering and the
  body's layers in series (engine: :mod:`ppamsafety.impact.points`); a result per case with the
  force, the pressure, the HIC and the energies;
* :func:`point_effective_mass` -- the arm's apparent mass at a contact point along a direction,
  1 / (u^T J_p H^-1 J_p^T u) (J_p the point's Jacobian; a point of link 1 moves with joint 1
  only);
* :func:`contact_bounds` -- rigorous a-priori bounds on F_max and HIC of such impacts
  (:mod:`ppamsafety.impact.bounds` generalised from the tool point and one Hunt-Crossley law
  to any point and any stack);
* :func:`worst_contact` -- the worst case over contact point x body region x instant of an
  experiment, found the way :func:`~ppamsafety.impact.instants.worst_instant` finds it for the
  tool: rigorous bounds, a screening run with a margin, exact simulation of the candidates
  that can still win.

**Bounds.**  The derivation of :mod:`ppamsafety.impact.bounds` holds for a contact point p:
with E0 the kinetic energy at t0, the stack's potential V (:mod:`ppamsafety.impact.layers`,
a conservative elastic part and non-negative dissipation) and m_min,p the smallest effective
mass of the arm at p over every configuration and direction, every impact obeys
(1/2) mu delta_dot^2 + V(delta) <= E0 (mu = m_b m_min,p / (m_b + m_min,p)).  So delta <=
delta_m with V(delta_m) = E0, and on each cell of a grid of delta the force is at most
F_el(right end) (1 + alpha_max V_rel sqrt(1 - V(left end) / E0))
(:func:`~ppamsafety.impact.layers.stack_force_bound`; the grid is conservative: the first
grid point with V >= E0 stands for delta_m).  The HIC bound is that of the tool point (the
body's acceleration F / m_b, its impulse, the cone about the initial normal with the body's
radius).  Both are multiplied by :data:`~ppamsafety.impact.bounds.MARGIN` (integration error).

**Screening.**  The engine run with longer contact steps (:data:`SCREEN_STRIDE` x dt for the
HIC; for the force and pressure about :data:`SCREEN_SAMPLES_PER_CONTACT` steps per contact;
force sampled on that grid, peak refined by a parabola; free flight in steps of 100 dt where they
resolve the joint springs, as the tool point's dense integrator): its F_max and HIC36 times
1 + :data:`SCREEN_MARGIN` stand in for the bounds; tests/test_anywhere.py checks screen x
(1 + margin) >= exact on random and scan states.
"""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..results import Result, layout_units
from .._validation import (as_float_array, check_bool, check_choice, check_instance, check_int,
                           check_nonnegative, check_range, check_range_array, describe)
from ..params.contact import (BARE, FOREHEAD, BodyContact, ContactPoint, Covering,
                              arm_contact_points, check_point_on_arm)
from ..plant import dynamics as dyn
from ..plant import packing
from ..plots.contacts import plot_contact_history, plot_contact_margins
from ..units import G0
from . import engine as eng
from . import points as pt
from .bodies import body_from_head
from .bounds import MARGIN, MASS_GRID, MASS_GRID_FACTOR
from .head import HeadContactModel
from .instants import _check_result, impact_states
from .layers import (NL, S_ALPHA, S_NL, SeriesContact, series_contact, stack_batch,
                     stack_force_bound)
from .model import (DT_RANGE, ENERGY_TOL, MAX_JOINT_SPEED, MAX_SPEED, PLAUSIBLE_SPEED,
                    STEPS_PER_PERIOD, _fmt_cases, _history_indices, _rows, _unit, check_angles,
                    check_arm, check_stiffness)

#: Contact steps of a screening run, in units of dt, by criterion: the HIC (coarser window
#: ends) is within 0.5 % of the exact engine's at 4 dt (tests/test_anywhere.py).  For the
#: force and the pressure these are the shortest steps: a longer contact gets longer steps,
#: about
#: :data:`SCREEN_SAMPLES_PER_CONTACT` per contact (a power of 2 times dt, at most
#: :data:`SCREEN_MAX_STRIDE`).
SCREEN_STRIDE = {"F_max": 4, "HIC36": 4, "p_max": 4}
#: Samples per contact of an adaptive screening run, from the contact time of the undamped
#: two-body impact, 2.8 delta*/v with V(delta*) = mu v^2 / 2 (2.94 for Hertz, pi for a linear
#: spring, 2.80 for a thin layer), divided by 1 + alpha_max v for the sharper peak of a damped
#: contact: an estimate that only sets the step.
SCREEN_SAMPLES_PER_CONTACT = 24
#: Longest screening step [dt].
SCREEN_MAX_STRIDE = 64
#: A screening value stands in for the bound only if the contact lasted at least this many
#: long steps (shorter, negligible contacts fall between the screening grid's samples).
SCREEN_MIN_SAMPLES = 8
#: Relative margin on the screening values, by criterion (tests/test_anywhere.py: the largest
#: shortfall of a screening value below the exact one, over random states at every contact
#: point, stays under half of it).
SCREEN_MARGIN = {"F_max": 0.001, "HIC36": 0.01, "p_max": 0.001}
#: Screening values below these floors are not used (the candidate keeps its bound):
#: negligible contacts the screening grid need not resolve.
SCREEN_FLOOR = {"F_max": 1.0, "HIC36": 1e-4, "p_max": 1e3}
#: Criteria :func:`worst_contact` can rank by: summary column -> unit.
CRITERIA = {"F_max": "N", "HIC36": "-", "p_max": "Pa"}


# ---- inputs -------------------------------------------------------------------------------
def resolve_point(point, arm, covering=None) -> ContactPoint:
    """A contact point from a name of :func:`~ppamsafety.params.contact.arm_contact_points`
    or a :class:`ContactPoint`; ``covering`` (a Covering) replaces its covering.

    Parameters
    ----------
    point : str or ContactPoint
        ``"tool point"``, ``"elbow"``, ``"forearm"``, ``"upper arm"`` or a point.
    arm : ArmParameters
        The arm whose default points are meant.
    covering : Covering, optional
        A covering for the point.
    """
    if isinstance(point, str):
        pts = {p.name: p for p in arm_contact_points(arm)}
        check_choice("point", point, tuple(pts))
        point = pts[point]
    elif not isinstance(point, ContactPoint):
        raise TypeError(f"point must be a contact point name or a ContactPoint, got "
                        f"{describe(point)}")
    else:
        check_point_on_arm(point, arm)
    if covering is not None:
        point = point.replace(covering=check_instance("covering", covering, Covering))
    return point


def resolve_body(body) -> BodyContact:
    """A body region's contact model: a :class:`BodyContact`, or a head model (its name, a head
    file or a :class:`HeadContactModel`, as a one-layer body); ``None``: the validated head.

    Parameters
    ----------
    body : BodyContact, str, path-like, HeadContactModel or None
    """
    if body is None:
        return FOREHEAD
    if isinstance(body, BodyContact):
        return body
    if isinstance(body, (str, HeadContactModel)) or hasattr(body, "__fspath__"):
        return body_from_head(body)
    raise TypeError(f"body must be a BodyContact, a head model (name, file or model) or None, "
                    f"got {describe(body)}")


def point_jacobian(q, arm, point: ContactPoint) -> np.ndarray:
    """Jacobian of a contact point's position w.r.t. the joint angles, shape (..., 2, 2) [m/rad].

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad].
    arm : ArmParameters
        Link lengths.
    point : ContactPoint
        The point (link and position).
    """
    q = np.asarray(q, dtype=float)
    s = point.position
    c1, s1 = np.cos(q[..., 0]), np.sin(q[..., 0])
    c12, s12 = np.cos(q[..., 0] + q[..., 1]), np.sin(q[..., 0] + q[..., 1])
    J = np.zeros(q.shape[:-1] + (2, 2))
    if point.link == 2:
        L1 = arm.geometry.L1
        J[..., 0, 0], J[..., 0, 1] = -L1 * s1 - s * s12, -s * s12
        J[..., 1, 0], J[..., 1, 1] = L1 * c1 + s * c12, s * c12
    else:
        J[..., 0, 0], J[..., 1, 0] = -s * s1, s * c1
    return J


def point_position(q, arm, point: ContactPoint) -> np.ndarray:
    """Position of a contact point [m], shape (..., 2).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad].
    arm : ArmParameters
        Link lengths.
    point : ContactPoint
        The point (link and position).
    """
    q = np.asarray(q, dtype=float)
    s = point.position
    p1 = np.stack([np.cos(q[..., 0]), np.sin(q[..., 0])], axis=-1)
    if point.link == 1:
        return s * p1
    p12 = np.stack([np.cos(q[..., 0] + q[..., 1]), np.sin(q[..., 0] + q[..., 1])], axis=-1)
    return arm.geometry.L1 * p1 + s * p12


def point_effective_mass(q, direction, arm, point) -> np.ndarray:
    """Apparent mass of the arm at a contact point along ``direction`` [kg].

    m_eff = 1 / (u^T J_p H^-1 J_p^T u); ``inf`` where the point cannot move along u (a point
    of link 1 along its link, a point at the shoulder).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad].
    direction : array_like, shape (..., 2)
        Direction (normalised here; non-zero), broadcast against ``q``.
    arm : ArmParameters
        The arm.
    point : str or ContactPoint
        The contact point.

    Returns
    -------
    numpy.ndarray
        Effective mass [kg], shape of ``q`` and ``direction`` broadcast without the last axis.
    """
    arm = check_arm(arm)
    point = resolve_point(point, arm)
    q = as_float_array("q", q, shape_tail=(2,))
    check_angles("q", q, arm)
    u = _unit(as_float_array("direction", direction, shape_tail=(2,)), "direction")
    q, u = np.broadcast_arrays(q, u)
    J = point_jacobian(q, arm, point)
    M = J @ np.linalg.inv(dyn.inertia_matrix(q, arm)) @ np.swapaxes(J, -1, -2)
    inv = np.einsum("...i,...ij,...j->...", u, M, u)
    scale = np.maximum(np.linalg.eigvalsh(M)[..., -1], 1e-300)
    with np.errstate(divide="ignore"):
        return np.where(inv > 1e-12 * scale, 1.0 / np.where(inv > 0, inv, 1.0), np.inf)


@functools.lru_cache(maxsize=32)
def _min_point_mass(arm, link, position, grid):
    q2 = np.linspace(-np.pi, np.pi, grid)
    q = np.stack([np.zeros_like(q2), q2], axis=-1)
    pnt = ContactPoint("p", link, position, "flat", math.inf, BARE)
    J = point_jacobian(q, arm, pnt)
    M = J @ np.linalg.inv(dyn.inertia_matrix(q, arm)) @ np.swapaxes(J, -1, -2)
    lam = np.linalg.eigvalsh(M)[..., -1]
    if not np.all(lam > 0):
        return math.inf                           # a point at the shoulder never moves
    return float((1.0 / lam).min())


def min_point_mass(arm, point, *, grid: int = MASS_GRID) -> float:
    """Smallest effective mass of the arm at a contact point over every q2 and direction [kg].

    min over q2 of 1/lambda_max(J_p H^-1 J_p^T) (independent of q1) on a grid of ``grid``
    points, times :data:`~ppamsafety.impact.bounds.MASS_GRID_FACTOR` (as for the tool point).

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    point : str or ContactPoint
        The contact point.
    grid : int
        Grid points over q2 (>= 101).
    """
    arm = check_arm(arm)
    point = resolve_point(point, arm)
    grid = check_int("grid", grid, 101, 10 ** 7)
    try:
        m = _min_point_mass(arm, point.link, point.position, grid)
    except TypeError:                               # an unhashable arm
        m = _min_point_mass.__wrapped__(arm, point.link, point.position, grid)
    return m * MASS_GRID_FACTOR


@dataclass
class _Table:
    """The stack's law on a log grid of compressions (for the bounds and the pass-through)."""

    D: np.ndarray
    F: np.ndarray
    V: np.ndarray
    alpha_max: float

    def delta_at(self, e):
        """Conservative compression [m] at the energies ``e`` [J]: the first grid point whose
        potential reaches e (``inf`` beyond the grid)."""
        e = np.asarray(e, dtype=float)
        j = np.searchsorted(self.V, e, side="left")
        return np.where(j < self.D.size, self.D[np.minimum(j, self.D.size - 1)], np.inf)


def _stack_table(contact: SeriesContact) -> _Table:
    key = contact.row.tobytes()
    hit = _TABLES.get(key)
    if hit is not None:
        return hit
    D = np.geomspace(1e-9, 2.0 * contact.body.radius, 4000)
    out = np.empty((D.size, 4))
    parts = np.empty((D.size, NL))
    stack_batch(D, np.zeros_like(D), contact.row, out, parts)
    nl = int(contact.row[S_NL])
    t = _Table(D, out[:, 1].copy(), out[:, 3].copy(),
               float(contact.row[S_ALPHA:S_ALPHA + nl].max()))
    if len(_TABLES) > 64:
        _TABLES.clear()
    _TABLES[key] = t
    return t


#: Tables of the stacks met in this process (by the bytes of their rows).
_TABLES: dict = {}


# ---- simulation ------------------------------------------------------------------------------
@dataclass
class ContactResult(Result):
    """Results of a batch of contact-point impacts (:func:`simulate_contacts`).

    Attributes
    ----------
    summary : pandas.DataFrame
        One row per case: inputs (q1, q2 [rad], qd1, qd2 [rad/s], K1, K2 [N m/rad], ux, uy,
        ``point_speed`` [m/s], ``m_eff`` [kg] along u), the columns of
        :data:`~ppamsafety.impact.points.PSUMMARY_COLUMNS` (F_max [N], HIC36, HIC15,
        delta_max [m], a_max_g [g], p_max [Pa], covering_use, energies [J] in total and per
        layer ``E_layer1..4``, covering first), ``energy_ok`` and ``status``.
    histories : dict
        Case index -> DataFrame of :data:`~ppamsafety.impact.points.PHIST_COLUMNS`.
    point : ContactPoint
        The contact point (with its covering).
    contact : SeriesContact
        The stack (covering and body layers at the point's geometry).
    dt, duration : float
        Step and simulated time [s].
    """

    summary: pd.DataFrame
    histories: dict = field(default_factory=dict)
    point: ContactPoint | None = None
    contact: SeriesContact | None = None
    dt: float = 2e-5
    duration: float = 0.05

    def to_pandas(self) -> pd.DataFrame:
        """A copy of :attr:`summary`."""
        return self.summary.copy()

    def column_units(self) -> dict:
        """The units of :attr:`summary`."""
        return {**_INPUT_UNITS, **layout_units(pt.PSUMMARY)}

    @property
    def table(self) -> pd.DataFrame:
        """The summary table."""
        return self.summary

    def __len__(self) -> int:
        return len(self.summary)

    def history(self, index: int) -> pd.DataFrame:
        """Time history of case ``index`` (recorded with ``history=``).

        Parameters
        ----------
        index : int
            Case index (row of :attr:`summary`) whose history was recorded.
        """
        i = check_int("index", index)
        if i not in self.histories:
            raise KeyError(f"index = {i}: no history recorded for this case; recorded: "
                           f"{sorted(self.histories)}")
        return self.histories[i]

    def plot(self, index=None, **kwargs):
        """The force, body acceleration and compression of a recorded case (a Figure).

        Parameters
        ----------
        index : int, optional
            Case whose history is plotted (default the first recorded).
        **kwargs
            Passed to :func:`ppamsafety.plots.contacts.plot_contact_history`.
        """
        if index is None:
            if not self.histories:
                raise KeyError("no history was recorded (pass history=True)")
            index = next(iter(self.histories))
        return plot_contact_history(self.history(index), point=self.point.name,
                                    body=self.contact.body.name, **kwargs)


@dataclass
class _PointPrep:
    q: np.ndarray
    qd: np.ndarray
    K: np.ndarray
    u: np.ndarray
    speed: np.ndarray
    meff: np.ndarray
    cases: np.ndarray
    sel: np.ndarray
    hist_idx: np.ndarray
    hist_of: np.ndarray
    P: np.ndarray
    S: np.ndarray
    point: ContactPoint
    contact: SeriesContact
    dt: float
    duration: float
    nsteps: int
    fixed_arm: bool
    arm: object = None
    free_steps: np.ndarray | None = None


#: Free-flight steps of a screening run [dt], longest first: each case takes the longest that
#: resolves its joint springs (:func:`~ppamsafety.impact.model.stiffness_limit`), else the
#: exact engine's (100 dt: the tool point's dense integrator's; 200 dt measured no faster).
SCREEN_FREE_STEPS = (100,)


def _free_steps(K, lam_min, dt) -> np.ndarray:
    """The screening free-flight step of each case [dt] (:data:`SCREEN_FREE_STEPS`), from the
    joint stiffnesses ``K`` [N m/rad] and the smallest eigenvalue of H(q) [kg m^2]."""
    out = np.full(len(K), eng.FREE_STRIDE, dtype=np.int64)
    kmax = np.asarray(K).max(axis=1)
    for f in SCREEN_FREE_STEPS[::-1]:
        ok = kmax <= lam_min * (2.0 * math.pi / (STEPS_PER_PERIOD * f * dt)) ** 2
        out[ok] = f
    return out


def _with_body(prep: _PointPrep, body: BodyContact) -> _PointPrep:
    """The same cases against another body region (the arm's checks are not repeated)."""
    contact = series_contact(body=body, point=prep.point)
    vclose = prep.speed                        # body at rest, placed along the velocity
    _check_through(contact, vclose)
    return _PointPrep(**{**prep.__dict__, "S": contact.row, "contact": contact})


def _check_through(contact: SeriesContact, v_close) -> None:
    """Refuse a case whose closing speed would drive the point through the body's centre
    (the stack cannot store the kinetic energy of the body on a rigid arm before it)."""
    body = contact.body
    v = np.maximum(np.asarray(v_close, dtype=float), 0.0)
    tab = _stack_table(contact)
    # the reach grows with the speed: if the fastest case stops short, every case does
    if v.size == 0 or tab.delta_at(0.5 * body.mass * v.max() ** 2) < body.radius:
        return
    reach = tab.delta_at(0.5 * body.mass * v ** 2)
    bad = np.nonzero(reach >= body.radius)[0]
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"case {i}: at the closing speed {v_close[i]:.4g} m/s the contact "
                         f"would pass through the body {body.name!r} (its layers store the "
                         f"energy only beyond its radius {body.radius:g} m)")


def _prepare(arm, q, qd, stiffness, *, point, body, covering, direction, body_velocity,
             fixed_arm, dt, duration, history, warn_area, stacklevel, Hinv=None,
             checked=False):
    """Validate and pack the cases (:func:`simulate_contacts`).  ``Hinv`` (H(q)^-1 of the
    cases) and ``checked`` (the stiffnesses already checked for these q) spare a scan over
    several points the work it has done once."""
    arm = check_arm(arm)
    point = resolve_point(point, arm, covering)
    body = resolve_body(body)
    contact = series_contact(body=body, point=point)
    q = as_float_array("q", q, shape_tail=(2,), ndim=(1, 2))
    qd = as_float_array("qd", qd, shape_tail=(2,), ndim=(1, 2))
    K = as_float_array("stiffness", stiffness, shape_tail=(2,), ndim=(1, 2))
    d = None if direction is None else as_float_array("direction", direction, shape_tail=(2,),
                                                      ndim=(1, 2))
    vb = None if body_velocity is None else as_float_array(
        "body_velocity", body_velocity, shape_tail=(2,), ndim=(1, 2))
    fixed_arm = check_bool("fixed_arm", fixed_arm)
    dt = check_range("dt", dt, *DT_RANGE, unit="s")
    duration = check_range("duration", duration, 1e-4, 10.0, unit="s")
    if duration < dt:
        raise ValueError(f"duration = {duration:g} s is shorter than dt = {dt:g} s")
    nsteps = int(math.ceil(duration / dt - 1e-9))
    if nsteps > 10 ** 7:
        raise ValueError(f"duration / dt = {nsteps} steps exceeds 1e7; use a larger dt")
    named = [(nm, a) for nm, a in (("q", q), ("qd", qd), ("stiffness", K), ("direction", d),
                                     ("body_velocity", vb)) if a is not None]
    n = max(a.shape[0] if a.ndim == 2 else 1 for _, a in named)
    if q.ndim == 2 and q.shape[0] == 0:
        n = 0
    ref = next(nm for nm, a in named if (a.shape[0] if a.ndim == 2 else 1) == n)
    q, qd, K = _rows("q", q, n, ref), _rows("qd", qd, n, ref), _rows("stiffness", K, n, ref)
    vb = np.zeros((n, 2)) if vb is None else _rows("body_velocity", vb, n, ref)
    if warn_area:
        check_angles("q", q, arm, stacklevel=stacklevel)
    elif np.any(np.abs(q) > 2 * math.pi):
        check_angles("q", q, arm)
    check_range_array("qd", qd, -MAX_JOINT_SPEED, MAX_JOINT_SPEED, unit="rad/s")
    check_range_array("stiffness", K, 0.0, math.inf, unit="N m/rad")
    check_range_array("body_velocity", vb, -1e3, 1e3, unit="m/s")
    if not fixed_arm and n and not checked:
        check_stiffness(K, q, arm, eng.FREE_STRIDE * dt, dt)
    J = point_jacobian(q, arm, point)
    vp = np.einsum("nij,nj->ni", J, qd)
    speed = np.linalg.norm(vp, axis=1)
    if d is None:
        rel = (0.0 if fixed_arm else vp) - vb
        nrm = np.linalg.norm(rel, axis=1)
        u = np.where(nrm[:, None] > 0, rel / np.where(nrm > 0, nrm, 1.0)[:, None], [1.0, 0.0])
    else:
        u = _rows("direction", _unit(d, "direction"), n, ref)
    for nm, sp in (("qd", speed), ("body_velocity", np.linalg.norm(vb, axis=1))):
        bad = np.nonzero(sp > MAX_SPEED)[0]
        if bad.size:
            raise ValueError(f"{nm}: case(s) {_fmt_cases(bad)} give a speed of "
                             f"{sp[bad[0]]:.4g} m/s at the {point.name}, physically impossible "
                             f"(at most {MAX_SPEED:g} m/s; plausible below {PLAUSIBLE_SPEED:g})")
    v_close = np.einsum("ni,ni->n", (0.0 if fixed_arm else vp) - vb, u)
    _check_through(contact, v_close)
    with np.errstate(divide="ignore", invalid="ignore"):
        Hi = np.linalg.inv(dyn.inertia_matrix(q, arm)) if Hinv is None else Hinv
        w = np.einsum("nji,nj->ni", J, u)                     # J^T u
        inv = np.einsum("ni,nij,nj->n", w, Hi, w)
        meff = np.where(inv > 0, 1.0 / np.where(inv > 0, inv, 1.0), np.inf)
    active = (np.linalg.norm((0.0 if fixed_arm else vp) - vb, axis=1) > 0)
    cases = np.zeros((n, pt.NPCASE))
    cases[:, pt.P_Q:pt.P_Q + 2] = q
    cases[:, pt.P_QD:pt.P_QD + 2] = 0.0 if fixed_arm else qd
    cases[:, pt.P_K:pt.P_K + 2] = K
    cases[:, pt.P_U:pt.P_U + 2] = u
    cases[:, pt.P_VB:pt.P_VB + 2] = vb
    cases[:, pt.P_ARM] = float(eng.ArmMode.FIXED if fixed_arm else eng.ArmMode.FLEXIBLE)
    cases[:, pt.P_LINK] = point.link
    cases[:, pt.P_POS] = point.position
    hist_idx = _history_indices(history, n)
    hist_of = np.full(n, -1, dtype=np.int64)
    hist_of[hist_idx] = np.arange(hist_idx.size)
    return _PointPrep(q, qd, K, u, speed, meff, cases, np.nonzero(active)[0], hist_idx, hist_of,
                      np.array(packing.pack(arm)), contact.row, point, contact, float(dt),
                      float(duration), nsteps, fixed_arm, arm)


def _run(prep: _PointPrep, idx, stride: int = 1, HIST=None) -> np.ndarray:
    """Summary rows of the cases ``idx`` (stride 1: exact; > 1: screening, with the longest
    free-flight steps of :data:`SCREEN_FREE_STEPS` that resolve the joint springs)."""
    idx = np.asarray(idx, dtype=np.int64)
    out = np.zeros((idx.size, pt.NPSUM))
    if idx.size == 0:
        return out
    nst = prep.nsteps
    if stride > 1:                          # whole long steps, covering the duration
        nst = -(-nst // stride) * stride
    h = stride * prep.dt
    w36 = int(math.floor(0.036 / h * (1 + 1e-9)))
    w15 = int(math.floor(0.015 / h * (1 + 1e-9)))
    hist_of = prep.hist_of[idx] if (HIST is not None and stride == 1) else \
        np.full(idx.size, -1, dtype=np.int64)
    if HIST is None:
        HIST = np.zeros((0, nst + 1, pt.NPHIST))
    groups = [(np.ones(idx.size, bool), eng.FREE_STRIDE)]
    if stride > 1 and not prep.fixed_arm:
        if prep.free_steps is None:          # once per set of cases
            prep.free_steps = _free_steps(prep.K, np.linalg.eigvalsh(
                dyn.inertia_matrix(prep.q, prep.arm))[..., 0], prep.dt)
        fs = prep.free_steps[idx]
        groups = [(fs == f, int(f)) for f in np.unique(fs)]
    for sel, free in groups:
        if not sel.any():
            continue
        o = np.zeros((int(sel.sum()), pt.NPSUM))
        pt.point_batch(np.ascontiguousarray(prep.cases[idx[sel]]), prep.P, prep.S, prep.dt, nst,
                       w36, w15, int(stride), int(free), o, HIST,
                       np.ascontiguousarray(hist_of[sel]))
        out[sel] = o
    return out


def _screen_strides(prep: _PointPrep, idx, criterion: str) -> np.ndarray:
    """The screening step of each case [dt]: :data:`SCREEN_STRIDE` for the HIC, and for the
    force and pressure the step that puts about :data:`SCREEN_SAMPLES_PER_CONTACT` samples in
    the contact (never shorter than :data:`SCREEN_STRIDE`)."""
    base = SCREEN_STRIDE[criterion]
    idx = np.asarray(idx, dtype=np.int64)
    if criterion == "HIC36":
        return np.full(idx.size, base, dtype=np.int64)
    mb = prep.contact.body.mass
    me = prep.meff[idx]
    mu = np.where(np.isfinite(me), mb * me / (mb + np.where(np.isfinite(me), me, 1.0)), mb)
    v = np.maximum(prep.speed[idx], 1e-12)
    tab = _stack_table(prep.contact)
    dstar = tab.delta_at(0.5 * mu * v * v)
    # a Hunt-Crossley damped pulse peaks earlier and sharper: shorten the scale with alpha v
    tc = 2.8 * np.minimum(dstar, 1.0) / v / (1.0 + tab.alpha_max * v)
    st = tc / (SCREEN_SAMPLES_PER_CONTACT * prep.dt)
    p2 = 2 ** np.floor(np.log2(np.maximum(st, 1.0)))
    return np.clip(p2, base, SCREEN_MAX_STRIDE).astype(np.int64)


def _screen(prep: _PointPrep, idx, criterion: str) -> tuple:
    """Screening rows of the cases ``idx``, and whether each is usable (its contact spans at
    least :data:`SCREEN_MIN_SAMPLES` long steps and its value reaches
    :data:`SCREEN_FLOOR`)."""
    idx = np.asarray(idx, dtype=np.int64)
    strides = _screen_strides(prep, idx, criterion)
    out = np.zeros((idx.size, pt.NPSUM))
    for st in np.unique(strides):
        sel = strides == st
        out[sel] = _run(prep, idx[sel], int(st))
    col = {"F_max": pt.U_FMAX, "HIC36": pt.U_HIC36, "p_max": pt.U_PMAX}[criterion]
    ok = ((out[:, pt.U_TCONT] >= SCREEN_MIN_SAMPLES * strides * prep.dt)
          & (out[:, col] >= SCREEN_FLOOR[criterion]))
    return out, ok


_INPUTS = ["q1", "q2", "qd1", "qd2", "K1", "K2", "ux", "uy", "point_speed", "m_eff"]
_INPUT_UNITS = {"q1": "rad", "q2": "rad", "qd1": "rad/s", "qd2": "rad/s", "K1": "N m/rad",
                "K2": "N m/rad", "ux": "-", "uy": "-", "point_speed": "m/s", "m_eff": "kg"}


def _frame(prep: _PointPrep, rows, SUM, *, stacklevel) -> pd.DataFrame:
    rows = np.asarray(rows, dtype=np.int64)
    data = np.column_stack([prep.q[rows], prep.qd[rows], prep.K[rows], prep.u[rows],
                            prep.speed[rows], prep.meff[rows], SUM])
    nl = len(prep.contact.layers)
    drop = {f"E_layer{i + 1}" for i in range(nl, NL)}
    if prep.contact.covering.bare:
        drop.add("covering_use")
    cols = _INPUTS + list(pt.PSUMMARY_COLUMNS)
    keep = [j for j, c in enumerate(cols) if c not in drop]
    df = pd.DataFrame(data[:, keep], columns=[cols[j] for j in keep])
    if not math.isfinite(prep.contact.effective_radius):
        df["p_max"] = np.nan
    active = np.zeros(prep.cases.shape[0], dtype=bool)
    active[prep.sel] = True
    act = active[rows]
    vals = SUM
    nonfinite = ~np.isfinite(vals[:, [pt.U_FMAX, pt.U_HIC36, pt.U_EBAL]]) & act[:, None]
    through = act & ~(vals[:, pt.U_DMAX] < prep.contact.body.radius)
    err = vals[:, pt.U_EBAL]
    energy_ok = ~act | (np.abs(err) <= ENERGY_TOL)
    status = np.where(act, "ok", "at rest").astype(object)
    flagged = np.nonzero(nonfinite.any(axis=1) | through | ~energy_ok)[0]
    for i in flagged:
        why = []
        if nonfinite[i].any():
            why.append("non-finite results")
        if through[i]:
            why.append("the point reached the body centre")
        if not energy_ok[i]:
            why.append(f"energy balance error {err[i]:.3g}")
        status[i] = "; ".join(why)
    df["energy_ok"] = energy_ok
    df["status"] = status
    if flagged.size:
        i = int(flagged[0])
        warnings.warn(f"contact results flagged for case(s) {_fmt_cases(flagged)}: {status[i]} "
                      f"(see the summary columns 'status' and 'energy_ok')", UserWarning,
                      stacklevel=stacklevel)
    return df


def simulate_contacts(arm, q, qd, stiffness, *, point="tool point", body=None, covering=None,
                      direction=None, body_velocity=None, fixed_arm: bool = False,
                      dt: float = 2e-5, duration: float = 0.05, history=False) -> ContactResult:
    """Impacts of a contact point of the flexible-joint arm with a free body region.

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    q, qd, stiffness : array_like, shape (N, 2) or (2,)
        Link angles [rad], velocities [rad/s] and joint stiffnesses [N m/rad] at the impact
        instant (as :func:`~ppamsafety.impact.simulate_impacts`).
    point : str or ContactPoint, keyword-only
        ``"tool point"`` (default), ``"elbow"``, ``"forearm"``, ``"upper arm"`` (the arm's
        default points, :func:`~ppamsafety.params.contact.arm_contact_points`) or a
        :class:`ContactPoint`.
    body : BodyContact, str or HeadContactModel, optional
        The body region (default the validated head,
        :data:`~ppamsafety.params.contact.FOREHEAD`; a head model name such as
        ``"thesis-frontal"`` is its one-layer body).
    covering : Covering, optional
        Replaces the point's covering (the default points are bare metal).
    direction : array_like, shape (N, 2) or (2,), optional
        From the point to the body centre (default: the point's velocity relative to the body,
        the worst case).
    body_velocity : array_like, shape (N, 2) or (2,), optional
        Initial body velocity [m/s] (default at rest).
    fixed_arm : bool
        The arm held still (the body moves into the point; e.g. a drop test).
    dt : float
        RK4 step [s], in [1e-8, 1e-3].
    duration : float
        Simulated time [s].
    history : bool or sequence of int
        Record time histories (all cases, or the given indices).

    Returns
    -------
    ContactResult
    """
    prep = _prepare(arm, q, qd, stiffness, point=point, body=body, covering=covering,
                    direction=direction, body_velocity=body_velocity, fixed_arm=fixed_arm,
                    dt=dt, duration=duration, history=history, warn_area=True, stacklevel=4)
    n = prep.cases.shape[0]
    SUM = np.zeros((n, pt.NPSUM))
    HIST = np.zeros((prep.hist_idx.size, prep.nsteps + 1, pt.NPHIST))
    SUM[prep.sel] = _run(prep, prep.sel, 1, HIST)
    df = _frame(prep, np.arange(n), SUM, stacklevel=3)
    nl = len(prep.contact.layers)
    keep = [c for c in pt.PHIST_COLUMNS if not (c.startswith("delta") and c[5:].isdigit()
                                                 and int(c[5:]) > nl)]
    hists = {int(i): pt.PHIST.frame(HIST[j])[keep] for j, i in enumerate(prep.hist_idx)}
    return ContactResult(df, hists, prep.point, prep.contact, prep.dt, prep.duration)


# ---- bounds ------------------------------------------------------------------------------------
def contact_bounds(arm, q, qd, *, point, body=None, covering=None, body_velocity=None,
                   duration: float = 0.05, window: float = 0.036) -> tuple:
    """Rigorous upper bounds on F_max [N] and HIC of contact-point impacts (module docstring).

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    q, qd : array_like, shape (N, 2) or (2,)
        Link angles [rad] and velocities [rad/s] at the impact instant.
    point, body, covering
        As :func:`simulate_contacts`.
    body_velocity : array_like, optional
        Initial body velocity [m/s] (default at rest).
    duration : float
        Simulated time T [s].
    window : float
        HIC window limit W [s].

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        F_max bound [N] and HIC bound, shape (N,); ``inf`` where no finite bound follows.
    """
    arm = check_arm(arm)
    point = resolve_point(point, arm, covering)
    contact = series_contact(body=resolve_body(body), point=point)
    q = np.atleast_2d(as_float_array("q", q, shape_tail=(2,), ndim=(1, 2)))
    qd = np.broadcast_to(as_float_array("qd", qd, shape_tail=(2,), ndim=(1, 2)), q.shape)
    vb = np.zeros(q.shape) if body_velocity is None else np.broadcast_to(
        as_float_array("body_velocity", body_velocity, shape_tail=(2,), ndim=(1, 2)), q.shape)
    duration = check_range("duration", duration, 1e-4, 10.0, unit="s")
    window = check_range("window", window, 1e-9, math.inf, unit="s")
    H = dyn.inertia_matrix(q, arm)
    e0 = 0.5 * np.einsum("ni,nij,nj->n", qd, H, qd)
    return _bounds(arm, point, contact, e0, vb, duration, window)


def _bounds(arm, point, contact, e0_arm, vb, duration, window):
    """The bounds from the arm's kinetic energies ``e0_arm`` [J] (contact_bounds)."""
    mb, R = contact.body.mass, contact.body.radius
    e0 = e0_arm + 0.5 * mb * np.einsum("ni,ni->n", vb, vb)
    mmin = min_point_mass(arm, point)
    mu = mb if not math.isfinite(mmin) else mb * mmin / (mb + mmin)
    V = np.sqrt(2.0 * e0 / mu)
    tab = _stack_table(contact)
    fb = np.empty(e0.size)
    stack_force_bound(np.ascontiguousarray(e0), np.ascontiguousarray(V), tab.alpha_max, tab.D,
                      tab.F, tab.V, fb)
    fb = fb * MARGIN
    dm = tab.delta_at(e0)
    am = fb / (mb * G0)
    hic = window * am ** 2.5
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.minimum(V * duration / np.maximum(R - dm, 1e-300), 2.0)
    ok = (s < 1.0) & (R > dm)
    c = np.sqrt(np.clip(1.0 - s * s, 1e-300, None))
    imp = (np.sqrt(2.0 * mb * e0) + mb * np.linalg.norm(vb, axis=1)) / c / (mb * G0)
    hic = np.where(ok, np.minimum(hic, am ** 1.5 * imp * MARGIN), hic)
    return fb, hic


# ---- the worst case over contact point x body region x instant ----------------------------
@dataclass
class WorstContact(Result):
    """Result of :func:`worst_contact`.

    Attributes
    ----------
    candidates : pandas.DataFrame
        One row per candidate (contact point x body region x instant): ``point``, ``body``,
        ``t0`` [s], ``point_speed`` [m/s], ``bound`` (rigorous bound of the criterion),
        ``screened`` with ``screen`` (screening value, NaN where not screened),
        ``simulated`` with ``value`` (exact, NaN where pruned), ``limit`` (NaN without
        limits) and ``objective`` (value / limit, or the value; NaN where pruned).
    worst : pandas.DataFrame
        One row per contact point: its worst body region and instant (exact, the engine's
        summary row plus ``point``, ``body``, ``t0``, ``criterion``, ``value``, ``limit``,
        ``utilisation`` = value / limit, ``margin`` = limit - value, ``margin_pct`` =
        100 (limit - value) / limit; NaN without limits); ``covering_use`` is 0 for a bare
        point (no covering is compressed).
    criterion : str
        What was ranked (:data:`CRITERIA`).
    limits : dict or None
        The limits used, body region name -> limit.
    n_candidates, n_screened, n_simulated : int
        Candidates, screened and exactly simulated.
    points : tuple of ContactPoint
        The contact points compared.
    arm : ArmParameters or None
        The arm of the scan (drawn by :meth:`plot`).
    """

    candidates: pd.DataFrame
    worst: pd.DataFrame
    criterion: str
    limits: dict | None
    n_candidates: int
    n_screened: int
    n_simulated: int
    points: tuple = ()
    arm: object = None

    def to_pandas(self) -> pd.DataFrame:
        """The worst case of each contact point (:attr:`worst`)."""
        return self.worst.copy()

    def column_units(self) -> dict:
        """The units of :attr:`worst` and :attr:`candidates` (``value``, ``limit``, ``margin``
        and the bounds in the criterion's unit)."""
        unit = CRITERIA[self.criterion]
        return {**_INPUT_UNITS, **layout_units(pt.PSUMMARY), "t0": "s", "value": unit,
                "limit": unit, "margin": unit, "margin_pct": "%", "utilisation": "-",
                "bound": unit, "screen": unit,
                "objective": "-" if self.limits else unit}

    @property
    def overall(self) -> pd.Series:
        """The worst case over every contact point (largest utilisation, or value)."""
        key = "utilisation" if self.limits else "value"
        return self.worst.loc[self.worst[key].idxmax()]

    def plot(self, arm=None, **kwargs):
        """The arm at the overall worst instant, each contact point with its worst body region
        and margin (:func:`ppamsafety.plots.contacts.plot_contact_margins`).

        Parameters
        ----------
        arm : ArmParameters, optional
            The arm drawn (default: the arm of the scan, :attr:`arm`).
        **kwargs
            Passed to :func:`ppamsafety.plots.contacts.plot_contact_margins`.
        """
        arm = self.arm if arm is None else arm
        if arm is None:
            raise ValueError("arm: this result holds no arm; pass the arm of the scan")
        return plot_contact_margins(_arm_drawing(arm, self), **kwargs)


def _arm_drawing(arm, w: WorstContact) -> dict:
    """The data the arm figure needs: link polyline at the overall worst pose, points, labels."""
    o = w.overall
    q = np.array([o["q1"], o["q2"]])
    pts_all = {p.name: p for p in w.points}
    g = arm.geometry
    elbow = g.L1 * np.array([math.cos(q[0]), math.sin(q[0])])
    tool = elbow + g.L2 * np.array([math.cos(q[0] + q[1]), math.sin(q[0] + q[1])])
    rows = []
    for _, r in w.worst.iterrows():
        p = pts_all[r["point"]]
        xy = point_position(q, arm, p)
        rows.append({"point": r["point"], "x": float(xy[0]), "y": float(xy[1]),
                     "body": r["body"], "value": r["value"], "limit": r["limit"],
                     "margin_pct": r["margin_pct"], "t0": r["t0"]})
    return {"links": np.array([[0.0, 0.0], elbow, tool]), "points": pd.DataFrame(rows),
            "criterion": w.criterion, "unit": CRITERIA[w.criterion]}


def worst_contact(result, arm, *, points=None, bodies=None, limits=None,
                  criterion: str = "F_max", every: int = 1, dt: float = 2e-5,
                  duration: float = 0.05, min_speed: float = 0.0, chunk: int = 256,
                  screen: bool = True) -> WorstContact:
    """The worst impact over contact point x body region x instant of an experiment.

    For each contact point, the largest ``criterion`` (or criterion / limit of the body region
    when ``limits`` are given) over every body region and every instant (every ``every``-th
    sample of the record), each impact with the body placed along the point's velocity (the
    worst placement, as for the tool point).  Same answer as simulating every candidate (the
    winners are simulated by the exact engine), but only the candidates that can still win are
    simulated: (1) rigorous bounds of every candidate (:func:`contact_bounds`); (2) with
    ``screen``, candidates whose bound reaches the best exact value so far are screened in
    batches of ``chunk`` (longer contact steps, :func:`_screen_strides`; the value x
    (1 + :data:`SCREEN_MARGIN`) replaces the bound); (3) candidates whose bound or screening value still reaches it are simulated
    exactly.  A candidate is dropped only when strictly below an exact value.

    Parameters
    ----------
    result : ExperimentResult
        The closed-loop record.
    arm : ArmParameters
        The arm.
    points : sequence of str or ContactPoint, optional
        Contact points (default the arm's four, bare metal).
    bodies : sequence of BodyContact (or head model names), optional
        Body regions (default the validated head).
    limits : dict, optional
        Body region name -> limit of the criterion (its unit: N, -, Pa); every body needs one.
        With limits the ranking is by utilisation value / limit.
    criterion : {"F_max", "HIC36", "p_max"}
        What is ranked.
    every : int
        Sample stride of the instants (1 = every control period).
    dt, duration : float
        Integration step and length of each impact [s].
    min_speed : float
        Instants whose point speed is below this [m/s] are not candidates of that point.
    chunk : int
        Candidates screened (or simulated without ``screen``) per compiled call.
    screen : bool
        Screen before simulating exactly.

    Returns
    -------
    WorstContact
    """
    result = _check_result(result)
    arm = check_arm(arm)
    check_choice("criterion", criterion, tuple(CRITERIA))
    every = check_int("every", every, 1, 10 ** 6)
    chunk = check_int("chunk", chunk, 1, 10 ** 6)
    screen = check_bool("screen", screen)
    min_speed = check_nonnegative("min_speed", min_speed, unit="m/s")
    pts = list(arm_contact_points(arm)) if points is None else \
        [resolve_point(p, arm) for p in points]
    bds = [FOREHEAD] if bodies is None else [resolve_body(b) for b in bodies]
    if not pts or not bds:
        raise ValueError("points and bodies must not be empty")
    names = [b.name for b in bds]
    if len(set(names)) != len(names):
        raise ValueError(f"bodies: two body regions share a name ({names}); give each its own")
    if limits is not None:
        if not isinstance(limits, dict):
            raise TypeError(f"limits must be a dict body region name -> limit, got "
                            f"{describe(limits)}")
        missing = [n for n in names if n not in limits]
        if missing:
            raise ValueError(f"limits has no entry for the body region(s) {missing}; "
                             f"given: {sorted(limits)}")
        lim = {n: check_range(f"limits[{n!r}]", limits[n], 0.0, math.inf, lo_open=True,
                              unit=CRITERIA[criterion]) for n in names}
    else:
        lim = None
    st = impact_states(result, arm)
    idx = np.arange(0, len(st), every)
    sub = st.iloc[idx].reset_index(drop=True)
    q, qd, K = (sub[["q1", "q2"]].to_numpy(), sub[["qd1", "qd2"]].to_numpy(),
                sub[["K1", "K2"]].to_numpy())
    Hq = dyn.inertia_matrix(q, arm)
    e0_arm = 0.5 * np.einsum("ni,nij,nj->n", qd, Hq, qd)
    Hinv = np.linalg.inv(Hq)
    if len(q):
        check_stiffness(K, q, arm, eng.FREE_STRIDE * dt, dt)
    # the screening's free-flight steps the joint springs allow (stiffness_limit, once)
    free_steps = _free_steps(K, np.linalg.eigvalsh(Hq)[..., 0], dt)
    col = {"F_max": pt.U_FMAX, "HIC36": pt.U_HIC36, "p_max": pt.U_PMAX}[criterion]
    tables, worst_rows = [], []
    n_scr = n_sim = n_cand = 0
    for p in pts:
        J = point_jacobian(q, arm, p)
        sp = np.linalg.norm(np.einsum("nij,nj->ni", J, qd), axis=1)
        keep = np.nonzero(sp >= max(min_speed, 1e-300))[0]
        if keep.size == 0:
            continue
        preps, ups, scale = [], [], []
        base = _prepare(arm, q[keep], qd[keep], K[keep], point=p, body=bds[0], covering=None,
                        direction=None, body_velocity=None, fixed_arm=False, dt=dt,
                        duration=duration, history=False, warn_area=False, stacklevel=3,
                        Hinv=Hinv[keep], checked=True)
        base.free_steps = free_steps[keep]
        for bi, b in enumerate(bds):
            prep = base if bi == 0 else _with_body(base, b)
            fb, hb = _bounds(arm, p, prep.contact, e0_arm[keep], np.zeros((keep.size, 2)),
                             duration, 0.036)
            if criterion == "F_max":
                bound = fb
            elif criterion == "HIC36":
                bound = hb
            else:
                bound = np.full(keep.size, np.inf)  # no a-priori pressure bound
            s = 1.0 / lim[b.name] if lim else 1.0
            preps.append(prep)
            ups.append(bound * s)
            scale.append(s)
        nb, nk = len(bds), keep.size
        up = np.concatenate(ups)                    # candidate c = body * nk + instant
        n = up.size
        n_cand += n
        simulated = np.zeros(n, bool)
        screened = np.zeros(n, bool)
        scr = np.full(n, np.nan)
        exact = np.full(n, np.nan)
        rows = {}
        best = -np.inf
        order = np.argsort(-up, kind="stable")

        def _split(take):
            for bi in range(nb):
                sel = take[(take >= bi * nk) & (take < (bi + 1) * nk)]
                if sel.size:
                    yield bi, sel, sel - bi * nk

        while True:
            open_ = ~simulated & (up >= best)
            if not open_.any():
                break
            ready = open_ & (screened | (not screen))
            if screen and ready.any():
                cand = np.nonzero(ready)[0]
                if not np.isfinite(best):
                    cand = cand[[int(np.argmax(up[cand]))]]
                take = cand
                stride = 1
            else:
                take = order[open_[order]][:chunk]
                take = np.sort(take)
                stride = 1 if not screen else 2
            for bi, sel, inst in _split(take):
                prep = preps[bi]
                if stride == 1:
                    out = _run(prep, inst, 1)
                else:
                    out, ok = _screen(prep, inst, criterion)
                vals = out[:, col] * scale[bi]
                if stride == 1:
                    simulated[sel] = True
                    exact[sel] = vals
                    up[sel] = vals
                    for j, c in enumerate(sel):
                        rows[int(c)] = out[j]
                    best = max(best, float(vals.max()))
                else:
                    # a contact shorter than SCREEN_MIN_SAMPLES long steps is not resolved
                    # by the screening grid: such a candidate keeps its bound
                    screened[sel] = True
                    scr[sel] = np.where(ok, vals, np.nan)
                    up[sel] = np.where(ok, vals * (1.0 + SCREEN_MARGIN[criterion]), up[sel])
        n_scr += int(screened.sum())
        n_sim += int(simulated.sum())
        inst_all = np.tile(keep, nb)
        sc = np.repeat(scale, nk)
        tables.append({"point": np.full(n, len(tables)), "body": np.repeat(np.arange(nb), nk),
                       "t0": sub["t"].to_numpy()[inst_all], "point_speed": np.tile(sp[keep], nb),
                       "bound": np.concatenate(ups) / sc, "screened": screened,
                       "screen": scr / sc, "simulated": simulated, "value": exact / sc,
                       "limit": np.repeat([lim[n] if lim else np.nan for n in names], nk),
                       "objective": exact, "_name": p.name})
        done = np.nonzero(simulated)[0]
        cw = int(done[np.argmax(exact[done])])          # the earliest on ties (sorted)
        bi, ii = divmod(cw, nk)
        fr = _frame(preps[bi], np.array([ii]), rows[cw][None, :], stacklevel=3).iloc[0]
        value = float(rows[cw][col])
        li = lim[names[bi]] if lim else np.nan
        head = {"point": p.name, "body": names[bi], "t0": float(sub["t"].to_numpy()[keep[ii]]),
                "criterion": criterion, "value": value, "limit": li,
                "utilisation": value / li if lim else np.nan,
                "margin": li - value if lim else np.nan,
                "margin_pct": 100.0 * (li - value) / li if lim else np.nan}
        # covering_use of a bare point is 0 (no covering is compressed), as in the layout
        worst_rows.append({**head, "covering_use": 0.0, **fr.to_dict()})
    if not worst_rows:
        raise ValueError("no contact point moves faster than min_speed at any instant")
    cols = {c: np.concatenate([t[c] for t in tables]) for c in tables[0] if c != "_name"}
    cols["point"] = pd.Categorical.from_codes(cols["point"], [t["_name"] for t in tables])
    cols["body"] = pd.Categorical.from_codes(cols["body"], names)
    return WorstContact(pd.DataFrame(cols), pd.DataFrame(worst_rows), criterion, lim, n_cand,
                        n_scr, n_sim, tuple(pts), arm)


__all__ = ["simulate_contacts", "ContactResult", "point_effective_mass", "point_jacobian",
           "point_position", "min_point_mass", "contact_bounds", "worst_contact",
           "WorstContact", "resolve_point", "resolve_body", "SCREEN_STRIDE", "SCREEN_MARGIN",
           "CRITERIA"]
