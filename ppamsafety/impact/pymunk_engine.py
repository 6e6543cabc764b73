"""Independent cross-check of the impact model in the pymunk (Chipmunk2D) engine.

The main impact engine (:mod:`ppamsafety.impact.engine`) integrates the
arm's Lagrangian equations in joint coordinates with RK4.  This module builds
the *same* physical system from rigid bodies and joints in pymunk, whose
integrator (semi-implicit Euler) and iterative impulse-based joint solver
share no code with ours, so agreement of the two is evidence that the
equations of motion, the initial conditions and the contact coupling of the
main engine are right.

The pymunk model (horizontal plane: gravity 0, ``space.damping = 1``):

* ``motor``: a kinematic body at rest at O = (0, 0) -- the frozen motor side;
* ``link1``: dynamic body, origin at O, angle q1, centre of gravity at
  (L_G1, -d_G1) in link coordinates (so R(q1) [L_G1, -d_G1] in the world, the
  convention of the potential energy in :mod:`ppamsafety.plant.dynamics`),
  centroidal moment I_G1;
* ``link2``: dynamic body, origin at S = L1 (cos q1, sin q1), angle q1 + q2,
  centre of gravity (L_G2, -d_G2), centroidal moment I_G2; the tool point
  (TCP) is (L2, 0) in link-2 coordinates;
* ``head``: dynamic point mass m_h (infinite moment: it cannot rotate), centre
  at r_tcp(t0) + (R + gap) u, at rest;
* ``PivotJoint(motor, link1)`` at O and ``PivotJoint(link1, link2)`` at S;
* ``DampedRotarySpring(motor, link1, -q1_0, K1, 0)`` and
  ``DampedRotarySpring(link1, link2, -q2_0, K2, 0)``.  Chipmunk's spring torque
  is computed from ``a.angle - b.angle`` (not ``b - a``): the torque on b is
  +K (a.angle - b.angle - rest) and on a the opposite.  With a = link1,
  b = link2 that is -K2 (q2 - q2_0) on link 2, so the rest angle must be
  **-q2_0** (and -q1_0 for the motor spring, whose body a has angle 0).
* no shapes: pymunk's own collision detection never runs.

The Hunt-Crossley force is computed by our code (the compiled contact law of
:mod:`ppamsafety.impact.contact`, the same function the main engine inlines)
in the ``pre_solve`` callback of the first constraint (the pivot at O).
``cpSpaceStep`` first integrates
positions (x_{k+1} = x_k + v_k dt), then calls each constraint's pre_solve and
preStep, then integrates velocities with the accumulated body forces
(v_{k+1} = v_k + M^-1 f dt) and resets the forces, then runs the joint solver.
So a force applied with ``apply_force_at_world_point`` inside pre_solve acts in
the same step, exactly once; it sees the new positions x_{k+1} and the old
velocities v_k (pre_solve of the *first* constraint runs before any spring
preStep has touched the velocities).  The velocity lag makes the coupling
first order in dt; see :func:`simulate_impact_pymunk`.

The same construction serves any contact point of the arm (a point of link 1 or 2 at a
distance from its joint, ``point=``) and layers in series (``contact=``: the covering and the
body's tissue and bone, their compiled law :func:`~ppamsafety.impact.layers.stack_eval`
called from the callback), the cross-check of :mod:`ppamsafety.impact.anywhere`.

pymunk is an optional dependency (``pip install pymunk``); it is imported when
the function is called.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .._validation import as_float_array, check_finite_result, check_int, check_range
from ..layouts import Field, Layout
from ..params.contact import ContactPoint
from ..units import G0
from .contact import hunt_crossley_elastic, hunt_crossley_force
from .engine import HIST as _HIST
from .head import HeadContactModel
from .hic import hic
from .layers import NWORK, SeriesContact, stack_eval
from .model import check_angles, check_arm, check_pass_through, check_stiffness, resolve_head

#: Columns of :attr:`PymunkImpact.history`: the main engine's history fields of the same
#: names and meaning (:data:`ppamsafety.impact.engine.HIST`) and the dissipated energy.
HISTORY_COLUMNS = [c for name in ("t", "F", "delta", "a_head_g", "dq", "v_head_n", "v_tcp_n",
                                  "E_total") for c in _HIST.field(name).column_names()] \
    + ["E_dissipated"]

#: One recorded step of the pymunk bodies (world frame), read back by name.
RECORD = Layout("pymunk impact record", [
    Field("angle", 2, "rad", "body angles of link 1 and link 2 (q1, q1 + q2)"),
    Field("omega", 2, "rad/s", "body angular velocities of link 1 and link 2"),
    Field("v_cog1", 2, "m/s", "velocity of the centre of gravity of link 1"),
    Field("v_cog2", 2, "m/s", "velocity of the centre of gravity of link 2"),
    Field("x_head", 2, "m", "head centre position"),
    Field("v_head", 2, "m/s", "head velocity"),
    Field("x_tcp", 2, "m", "tool point of the link-2 body"),
    Field("v_tcp", 2, "m/s", "velocity of the tool point of the link-2 body"),
])
_ANG, _OM, _VG1, _VG2, _XH, _VH, _XT, _VT = RECORD.offsets(
    "angle", "omega", "v_cog1", "v_cog2", "x_head", "v_head", "x_tcp", "v_tcp")


@dataclass
class PymunkImpact:
    """Result of one impact simulated in pymunk.

    Attributes
    ----------
    F_max : float
        Peak contact force [N].
    t_Fmax : float
        Time of the peak [s].
    HIC36, HIC15 : float
        Exact HIC over windows of at most 36 / 15 ms of the head acceleration
        |F|/(m_h g) sampled every step [-].
    delta_max : float
        Maximum penetration [m].
    E_initial : float
        Kinetic energy at t0 [J] (springs unloaded, no contact).
    E_dissipated : float
        Energy dissipated by the contact damping, integral of (F - k delta^n) d(delta) [J].
    joint_error_max : float
        Largest distance between the TCP of the link-2 body and the forward
        kinematics of the two link angles [m]: how far pymunk's iterative
        solver lets the pivots open.
    history : pandas.DataFrame
        Every step: :data:`HISTORY_COLUMNS` -- t [s], F [N], delta [m],
        a_head_g [g], joint deflections dq1, dq2 [rad], head and TCP velocity
        along the initial impact direction u [m/s], E_total (kinetic + springs +
        contact potential k delta^(n+1)/(n+1)) [J] and E_dissipated [J].
    dt, duration : float
        Step and simulated time [s].
    iterations : int
        Joint solver iterations per step.
    wall_time : float
        Wall-clock time of the simulation [s].
    """

    F_max: float
    t_Fmax: float
    HIC36: float
    HIC15: float
    delta_max: float
    E_initial: float
    E_dissipated: float
    joint_error_max: float
    history: pd.DataFrame = field(repr=False)
    dt: float = 1e-6
    duration: float = 0.05
    iterations: int = 100
    wall_time: float = 0.0


def _tcp(q1, q2, L1, L2):
    """TCP position and the Jacobian rows (own code, independent of plant.geometry)."""
    c1, s1, c12, s12 = math.cos(q1), math.sin(q1), math.cos(q1 + q2), math.sin(q1 + q2)
    pos = (L1 * c1 + L2 * c12, L1 * s1 + L2 * s12)
    jac = ((-L1 * s1 - L2 * s12, -L2 * s12), (L1 * c1 + L2 * c12, L2 * c12))
    return pos, jac


def simulate_impact_pymunk(arm, q, qd, stiffness, *, head: HeadContactModel | str | None = None,
                           direction=None, gap: float = 0.0, dt: float = 1e-6,
                           duration: float = 0.05, iterations: int = 100, point=None,
                           contact=None) -> PymunkImpact:
    """Simulate one arm-head impact (thesis §6.3.2) with pymunk bodies and joints.

    Same physics as :func:`ppamsafety.impact.model.simulate_impacts`: an
    unactuated flexible-joint arm (rigid links ``arm.links``, torsional springs
    K about the frozen motor side), a free head with Hunt-Crossley contact at
    the TCP, horizontal plane, no friction.  See the module docstring for the
    body set-up and pymunk's conventions.

    pymunk integrates with semi-implicit Euler (first order) and enforces the
    pivots with an iterative impulse solver, so it needs a much smaller step
    than the RK4 main engine: with the damped thesis head model, dt = 1e-6 s
    gives F_max and HIC36 within 3e-4 and 5e-4 (relative) of the main engine
    at 1e-5 s, and halving dt halves the difference; undamped contacts agree
    to about 1e-5 already (the position-only forces make the scheme
    effectively second order).  The energy error oscillates within
    (dt/2) max |v . f| (the modified energy of symplectic Euler) and does not
    drift.  One 50 ms impact at 1e-6 s takes about 1 s (50 000 pymunk steps,
    each with a Python callback).

    Parameters
    ----------
    arm : ArmParameters
        Uses ``arm.links`` (masses, centres of gravity, centroidal inertias)
        and ``arm.geometry.L1``, ``L2``.
    q : array_like, shape (2,)
        Link angles [rad] at the impact instant t0 (|q| <= 2 pi; outside the
        working area a ``UserWarning``).
    qd : array_like, shape (2,)
        Link angular velocities [rad/s] at t0, |qd| <= 1000 rad/s.
    stiffness : array_like, shape (2,)
        Joint stiffnesses K1, K2 [N m/rad], >= 0 and at most
        :func:`~ppamsafety.impact.model.stiffness_limit` for the step ``dt``.
    head : HeadContactModel or str, keyword-only
        Head model or its name (default ``"thesis-frontal"``).
    direction : array_like, shape (2,), optional
        Unit vector from the TCP to the head centre; default the TCP velocity
        direction (fig. 6.2).  Required if the TCP is at rest.
    gap : float
        Extra distance between the head surface and the TCP at t0 [m], in
        [0, 10] (0: touching; a large value gives the free motion of the arm).
    dt : float
        Fixed pymunk step [s], in [1e-8, 1e-4].
    duration : float
        Simulated time [s], in [1e-4, 1].
    iterations : int
        Iterations of pymunk's joint solver per step, in [1, 10000].
    point : ContactPoint, optional
        A contact point of the arm (:class:`ppamsafety.params.contact.ContactPoint`: link 1
        or 2 at a distance from its joint) instead of the tool point: the contact force acts
        on that body at that point (the columns ``v_tcp_n`` then hold the point's velocity).
    contact : SeriesContact, optional
        Layers in series (:func:`ppamsafety.impact.layers.series_contact`) instead of the
        head model's law: the body's mass and radius, and the compiled law of the layers
        (:func:`~ppamsafety.impact.layers.stack_eval`), called from the step callback; the
        energy's contact term is the stack's potential.

    Returns
    -------
    PymunkImpact
    """
    try:
        import pymunk
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("simulate_impact_pymunk needs pymunk (pip install pymunk)") from exc


    arm = check_arm(arm)
    q = as_float_array("q", q, shape_tail=(2,))
    qd = as_float_array("qd", qd, shape_tail=(2,))
    K = as_float_array("stiffness", stiffness, shape_tail=(2,))
    if q.ndim != 1 or qd.ndim != 1 or K.ndim != 1:
        raise ValueError(f"q, qd and stiffness must each have shape (2,) (one impact), got "
                         f"shapes {q.shape}, {qd.shape}, {K.shape}")
    hm = resolve_head(head)
    if point is not None and not isinstance(point, ContactPoint):
        raise TypeError(f"point must be a ContactPoint, got {type(point).__name__}")
    if contact is not None and not isinstance(contact, SeriesContact):
        raise TypeError(f"contact must be a SeriesContact, got {type(contact).__name__}")
    if np.any(K < 0):
        raise ValueError(f"stiffness = {K.tolist()} must be non-negative [N m/rad]")
    if np.any(np.abs(qd) > 1e3):
        raise ValueError(f"qd = {qd.tolist()} rad/s is outside [-1000, 1000] rad/s")
    gap = check_range("gap", gap, 0.0, 10.0, unit="m")
    dt = check_range("dt", dt, 1e-8, 1e-4, unit="s")
    duration = check_range("duration", duration, 1e-4, 1.0, unit="s")
    iterations = check_int("iterations", iterations, 1, 10000)
    if duration / dt > 1e7:
        raise ValueError(f"duration / dt = {duration:g} s / {dt:g} s exceeds 1e7 pymunk steps; "
                         f"use a larger dt or a shorter duration")
    check_angles("q", q, arm)
    check_stiffness(K[None, :], q[None, :], arm, dt, dt)

    lk, L1, L2 = arm.links, arm.geometry.L1, arm.geometry.L2
    q1, q2 = float(q[0]), float(q[1])
    w1, w2 = float(qd[0]), float(qd[1])
    K1, K2 = float(K[0]), float(K[1])
    mh, R, kc, nc, bc = hm.mass, hm.radius, hm.stiffness, hm.exponent, hm.damping
    plink, s_pt = (2, L2) if point is None else (point.link, point.position)
    if contact is not None:
        mh, R = contact.body.mass, contact.body.radius

    if plink == 2:
        r_tcp, J = _tcp(q1, q2, L1, s_pt)
    else:                             # a point of link 1: joint 1 only
        c1, s1 = math.cos(q1), math.sin(q1)
        r_tcp, J = (s_pt * c1, s_pt * s1), ((-s_pt * s1, 0.0), (s_pt * c1, 0.0))
    v_tcp = (J[0][0] * w1 + J[0][1] * w2, J[1][0] * w1 + J[1][1] * w2)
    if direction is None:
        sp = math.hypot(*v_tcp)
        if sp == 0.0:
            raise ValueError("the contact point is at rest: give the impact direction "
                             "explicitly")
        u = (v_tcp[0] / sp, v_tcp[1] / sp)
    else:
        d = as_float_array("direction", direction, shape_tail=(2,))
        if d.ndim != 1:
            raise ValueError(f"direction must have shape (2,), got {d.shape}")
        nd = float(np.hypot(d[0], d[1]))
        if nd == 0.0 or not math.isfinite(nd):
            raise ValueError(f"direction = {d.tolist()} must be a non-zero finite vector")
        u = (float(d[0]) / nd, float(d[1]) / nd)
    if contact is None:
        check_pass_through(hm, [max(v_tcp[0] * u[0] + v_tcp[1] * u[1], 0.0)])

    # ---- bodies ---------------------------------------------------------------------------
    space = pymunk.Space()
    space.gravity = (0.0, 0.0)
    space.damping = 1.0
    space.iterations = iterations

    motor = pymunk.Body(body_type=pymunk.Body.KINEMATIC)   # frozen motor side, at rest
    motor.position = (0.0, 0.0)

    def link(mass, moment, cog, angle, origin, omega, origin_velocity):
        b = pymunk.Body(mass, moment)
        b.center_of_gravity = cog   # body-local; set before angle/position (Chipmunk keeps
        b.angle = angle             # the CoG fixed when the angle is set)
        b.position = origin
        ca, sa = math.cos(angle), math.sin(angle)
        rx, ry = ca * cog[0] - sa * cog[1], sa * cog[0] + ca * cog[1]   # origin -> CoG, world
        b.velocity = (origin_velocity[0] - omega * ry, origin_velocity[1] + omega * rx)
        b.angular_velocity = omega
        return b

    S = (L1 * math.cos(q1), L1 * math.sin(q1))
    v_S = (-w1 * S[1], w1 * S[0])
    b1 = link(lk.m1, lk.IG1, (lk.LG1, -lk.dG1), q1, (0.0, 0.0), w1, (0.0, 0.0))
    b2 = link(lk.m2, lk.IG2, (lk.LG2, -lk.dG2), q1 + q2, S, w1 + w2, v_S)
    bh = pymunk.Body(mh, math.inf)
    bh.position = (r_tcp[0] + (R + gap) * u[0], r_tcp[1] + (R + gap) * u[1])
    bh.velocity = (0.0, 0.0)

    # the first constraint added carries the contact callback (see module docstring)
    pivot_o = pymunk.PivotJoint(motor, b1, (0.0, 0.0), (0.0, 0.0))
    pivot_s = pymunk.PivotJoint(b1, b2, (L1, 0.0), (0.0, 0.0))
    spring1 = pymunk.DampedRotarySpring(motor, b1, -q1, K1, 0.0)
    spring2 = pymunk.DampedRotarySpring(b1, b2, -q2, K2, 0.0)
    space.add(motor, b1, b2, bh, pivot_o, pivot_s, spring1, spring2)

    # ---- contact callback ----------------------------------------------------------------
    n = int(math.ceil(duration / dt - 1e-9))
    F = np.zeros(n + 1)
    D = np.zeros(n + 1)
    Ediss = np.zeros(n + 1)
    state = {"k": 0, "diss": 0.0, "delta": 0.0}
    tcp_local = (s_pt, 0.0)
    bp = b2 if plink == 2 else b1         # the body carrying the contact point

    # the contact law is the engine's compiled one (one definition, see impact.contact and
    # impact.layers); bound to locals for the per-step Python callback
    if contact is None:
        hc_force, hc_elastic = hunt_crossley_force, hunt_crossley_elastic
    else:
        work = np.full(NWORK, np.nan)
        row = contact.row

        def hc_force(d, dd, k, n, b):
            return stack_eval(d, dd, row, work)[0]

        def hc_elastic(d, k, n):
            return stack_eval(d, 0.0, row, work)[1]

    def contact_force(constraint, sp):
        k = state["k"] + 1
        p_tcp = bp.local_to_world(tcp_local)
        ph = bh.position
        dx, dy = ph.x - p_tcp.x, ph.y - p_tcp.y
        dist = math.sqrt(dx * dx + dy * dy)
        delta = R - dist
        f = 0.0
        if delta > 0.0:
            nx, ny = dx / dist, dy / dist
            vt = bp.velocity_at_world_point(p_tcp)
            vh = bh.velocity
            ddelta = -(nx * (vh.x - vt.x) + ny * (vh.y - vt.y))
            f = hc_force(delta, ddelta, kc, nc, bc)
            if f > 0.0:
                bh.apply_force_at_world_point((f * nx, f * ny), ph)
                bp.apply_force_at_world_point((-f * nx, -f * ny), p_tcp)
        # dissipation: (F - k delta^n) d(delta), trapezoid over the step
        d_old = state["delta"]
        if delta > 0.0 or d_old > 0.0:
            fel = hc_elastic(delta, kc, nc)
            fel_old = hc_elastic(d_old, kc, nc)
            state["diss"] += 0.5 * ((f - fel) + (F[k - 1] - fel_old)) * (delta - d_old)
        state["delta"] = delta
        F[k], D[k], Ediss[k] = f, delta, state["diss"]
        state["k"] = k

    pivot_o.pre_solve = contact_force

    # ---- run ---------------------------------------------------------------------------
    REC = RECORD.empty(n + 1)   # one RECORD row per step

    def record(i):
        v1, v2, vh, ph = b1.velocity, b2.velocity, bh.velocity, bh.position
        p_tcp = bp.local_to_world(tcp_local)
        vt = bp.velocity_at_world_point(p_tcp)
        REC[i] = (b1.angle, b2.angle, b1.angular_velocity, b2.angular_velocity,   # RECORD order
                  v1.x, v1.y, v2.x, v2.y, ph.x, ph.y, vh.x, vh.y, p_tcp.x, p_tcp.y, vt.x, vt.y)

    t0 = time.perf_counter()
    record(0)
    D[0] = R - math.hypot(REC[0, _XH] - REC[0, _XT], REC[0, _XH + 1] - REC[0, _XT + 1])
    state["delta"] = D[0]
    step = space.step
    for i in range(1, n + 1):
        step(dt)
        record(i)
    wall = time.perf_counter() - t0
    if state["k"] != n:   # pragma: no cover - would mean pymunk skipped the callback
        raise RuntimeError(f"contact callback ran {state['k']} times in {n} steps")

    # ---- outputs -----------------------------------------------------------------------
    # Energy from the state after each step (positions x_k, velocities v_k).
    ang1, ang2 = REC[:, _ANG], REC[:, _ANG + 1]
    xh, yh, vhx, vhy = REC[:, _XH], REC[:, _XH + 1], REC[:, _VH], REC[:, _VH + 1]
    xt, yt, vtx, vty = REC[:, _XT], REC[:, _XT + 1], REC[:, _VT], REC[:, _VT + 1]
    ke = 0.5 * (lk.m1 * (REC[:, _VG1] ** 2 + REC[:, _VG1 + 1] ** 2) + lk.IG1 * REC[:, _OM] ** 2
                + lk.m2 * (REC[:, _VG2] ** 2 + REC[:, _VG2 + 1] ** 2)
                + lk.IG2 * REC[:, _OM + 1] ** 2
                + mh * (vhx ** 2 + vhy ** 2))
    dq1 = ang1 - q1
    dq2 = (ang2 - ang1) - q2
    dist = np.hypot(xh - xt, yh - yt)
    dpos = np.maximum(R - dist, 0.0)
    if contact is None:
        e_con = kc * dpos ** (nc + 1) / (nc + 1)
    else:
        e_con = contact.evaluate(dpos)["V"].to_numpy()
    e_tot = ke + 0.5 * K1 * dq1 ** 2 + 0.5 * K2 * dq2 ** 2 + e_con
    a_g = F / (mh * G0)
    # joint solver check: TCP of the link-2 body vs forward kinematics of the body angles
    # (a pivot that opens by e moves the body TCP by e)
    c1, s1, c12, s12 = np.cos(ang1), np.sin(ang1), np.cos(ang2), np.sin(ang2)
    if plink == 2:
        joint_err = np.hypot(xt - L1 * c1 - s_pt * c12, yt - L1 * s1 - s_pt * s12)
    else:
        joint_err = np.hypot(xt - s_pt * c1, yt - s_pt * s1)
    t = np.arange(n + 1) * dt
    hist = pd.DataFrame({"t": t, "F": F, "delta": D, "a_head_g": a_g, "dq1": dq1, "dq2": dq2,
                         "v_head_n": vhx * u[0] + vhy * u[1],
                         "v_tcp_n": vtx * u[0] + vty * u[1],
                         "E_total": e_tot, "E_dissipated": Ediss}, columns=HISTORY_COLUMNS)
    check_finite_result("the pymunk contact force", F, "these inputs")
    i_max = int(np.argmax(F))
    return PymunkImpact(F_max=float(F[i_max]), t_Fmax=float(t[i_max]),
                        HIC36=float(hic(a_g, dt, window=0.036).value),
                        HIC15=float(hic(a_g, dt, window=0.015).value),
                        delta_max=float(D.max()), E_initial=float(e_tot[0]),
                        E_dissipated=float(Ediss[-1]), joint_error_max=float(joint_err.max()),
                        history=hist, dt=dt,
                        duration=duration, iterations=iterations, wall_time=wall)
