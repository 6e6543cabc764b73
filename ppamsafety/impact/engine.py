"""Impact of the flexible-joint arm with a free head (thesis §6.3.2).

Model (SPEC §4): the arm is unactuated, in the horizontal plane (no gravity),
with rigid links and torsional joint springs of constant stiffness K
(2.18), unloaded at the impact instant t0.  What holds the springs' far
(motor) side is the case's :class:`JointModel`; by default (frozen
equilibrium) it is frozen at t0::

    H(q) qdd + C(q, qd) qd = -K (q - q0) + J(q)^T f_tool
    m_h x_h'' = f_head,        f_head = -f_tool = F n

The flexible-joint model (Spong 1987; De Luca and Book 2008, reduced model)
gives the motor side an inertia B moving with the link at t0::

    H(q) qdd + C(q, qd) qd = -K (q - theta) + J(q)^T f_tool
    B thetadd = -K (theta - q),    theta(t0) = q0, thetad(t0) = qd0

and its limit K -> infinity, the rigid arm, is the free arm of inertia
H(q) + diag(B).

The head is a free rigid sphere (mass m_h, radius R) whose surface touches the
tool point (TCP) at t0 with its centre along the unit vector u (by default the
TCP velocity direction, the worst case, fig. 6.2).  Penetration
delta = R - |x_h - r_tcp|, normal n = (x_h - r_tcp)/|x_h - r_tcp|, and the
Hunt-Crossley force F(delta, d delta/dt) >= 0 of (6.2).

Integration: classical RK4 with a fixed step (default 10 us) for 50 ms; the
head acceleration |F|/(m_h g) is sampled at every step for the HIC (exact
maximisation, :mod:`ppamsafety.impact.hic`).  The dissipated energy
integral_0^t (F - k delta^n) d(delta)/dt dt is integrated alongside, so the
energy balance can be checked.  Everything is one compiled kernel over a
batch of impact cases.

Data layouts (:mod:`ppamsafety.layouts`), declared here once: :data:`CASE`
(one impact case; the flag ``arm_mode`` holds an :class:`ArmMode` code),
:data:`HEAD` (head contact parameters, :func:`pack_head`), :data:`STATE`
(integrator state y), :data:`SUMMARY` (one summary row;
:data:`SUMMARY_COLUMNS`) and :data:`HIST` (one history sample;
:data:`HIST_COLUMNS`).  The kernels index them only through the offsets
generated from these declarations.
"""

from __future__ import annotations

import math
from enum import IntEnum

import numpy as np

from .._jit import kernel, leaf, step_kernel
from ..layouts import Field, Layout
from ..plant.dynamics import coriolis_cs, mass_matrix_cs
from ..plant.geometry import tcp_kinematics_cs
from ..units import G0
from .contact import hunt_crossley_elastic, hunt_crossley_force, hunt_crossley_potential
from .hic import hic_pair_kernel


class JointModel(IntEnum):
    """What holds the far (motor) side of the joint springs during an impact (field
    ``joint_model`` of :data:`CASE`); thesis §6.3.2 and §6.3.4, De Luca and Book (2008).

    Every convention starts with the springs unloaded at t0 (the arm is unactuated
    during the impact: the motor torque is held at its t0 value, zero at an unloaded
    spring), and differs in what the spring's far end does afterwards.
    """

    #: Frozen equilibrium (default): the motor side is held at q(t0), at rest, for the whole
    #: impact -- H qdd + C qd = -K (q - q0) + J^T f.  This is the PPAM's own physics: with
    #: the valves' pressures held, the antagonistic pair is a gas spring (2.18) anchored to
    #: the link's equilibrium; there is no moving mass behind the gas.  As K -> infinity it
    #: clamps the link to q0 (F_max -> 0): it is not a model of a stiffer actuator.
    FROZEN_EQUILIBRIUM = 0
    #: Flexible joint of Spong (1987) / De Luca and Book (2008), reduced model: a motor-side
    #: inertia B_i [kg m^2] (reflected to the joint) with angle theta_i moves with the link
    #: at t0 (theta = q, thetad = qd) and is coupled to it only by the spring:
    #: H qdd + C qd + K (q - theta) = J^T f,  B thetadd + K (theta - q) = tau_m(t0) = 0.
    #: B_i = 0: no spring load can build up (theta_i follows q_i), the joint is free.
    #: As K -> infinity it tends to the rigid arm with inertia H + diag(B).
    FLEXIBLE_JOINT = 1
    #: The exact limit K -> infinity of FLEXIBLE_JOINT: a free rigid arm of inertia
    #: H(q) + diag(B) (links and motor sides locked together); K is not used.
    RIGID = 2


class ArmMode(IntEnum):
    """How the arm moves during the impact (field ``arm_mode`` of :data:`CASE`)."""

    #: Flexible-joint arm: rigid links on torsional springs about the frozen motor side.
    FLEXIBLE = 0
    #: Rigid, fixed arm: the tool point does not move; only the head does.
    FIXED = 1


# ---- declared layouts (ppamsafety.layouts) ------------------------------------------------
#: One impact case: the arm state at the impact instant t0 and the impact geometry.
CASE = Layout("impact case", [
    Field("q", 2, "rad", "link angles at the impact instant t0"),
    Field("qd", 2, "rad/s", "link angular velocities at t0 (unused for a fixed arm)"),
    Field("K", 2, "N m/rad", "joint stiffnesses, constant during the impact (2.18)"),
    Field("u", 2, "-", "unit vector from the tool point to the head centre at t0",
          columns=("ux", "uy")),
    Field("v_head", 2, "m/s", "head velocity at t0", columns=("vhx0", "vhy0")),
    Field("arm_mode", 1, "code", "ArmMode: flexible-joint (0) or rigid fixed arm (1)",
          default=float(ArmMode.FLEXIBLE)),
    Field("joint_model", 1, "code",
          "JointModel: frozen equilibrium (0), flexible joint (1) or rigid (2)",
          default=float(JointModel.FROZEN_EQUILIBRIUM)),
    Field("B", 2, "kg m^2", "motor-side inertias reflected to the joints (flexible joint, "
          "rigid); unused for the frozen equilibrium", default=0.0),
])
C_Q, C_QD, C_K, C_U, C_VH, C_ARM, C_JM, C_B = CASE.offsets(
    "q", "qd", "K", "u", "v_head", "arm_mode", "joint_model", "B")
NCASE = CASE.size

#: Head and Hunt-Crossley contact parameters (a HeadContactModel as a kernel row).
HEAD = Layout("head contact parameters", [
    Field("mass", 1, "kg", "head mass (thesis §6.3.2: 5 kg)"),
    Field("radius", 1, "m", "radius of the spherical head surface"),
    Field("stiffness", 1, "N/m^n", "Hunt-Crossley k (6.2)"),
    Field("exponent", 1, "-", "Hunt-Crossley n (6.2)"),
    Field("damping", 1, "N s/m^(n+1)", "Hunt-Crossley b (6.2)"),
])
HP_M, HP_R, HP_K, HP_N, HP_B = HEAD.offsets("mass", "radius", "stiffness", "exponent", "damping")

#: Integrator state y of one impact.
STATE = Layout("impact integrator state", [
    Field("q", 2, "rad", "link angles"),
    Field("w", 2, "rad/s", "link angular velocities"),
    Field("x_head", 2, "m", "head centre position", columns=("xh", "yh")),
    Field("v_head", 2, "m/s", "head centre velocity", columns=("vxh", "vyh")),
    Field("E_dissipated", 1, "J", "integral of (F - k delta^n) d(delta)/dt dt"),
    Field("theta", 2, "rad", "motor-side angles (frozen equilibrium: q(t0); a joint with "
          "B = 0 and the rigid model: equal to q)"),
    Field("theta_d", 2, "rad/s", "motor-side angular velocities (frozen equilibrium: 0)"),
])
Y_Q, Y_W, Y_XH, Y_VH, Y_ED, Y_TH, Y_THD = STATE.offsets(
    "q", "w", "x_head", "v_head", "E_dissipated", "theta", "theta_d")
NY = STATE.size

#: One row of the summary of an impact (columns of ImpactResults.summary).
SUMMARY = Layout("impact summary", [
    Field("F_max", 1, "N", "peak contact force"),
    Field("t_Fmax", 1, "s", "time of the peak force after t0"),
    Field("HIC36", 1, "-", "HIC over windows of at most 36 ms (exact maximum)"),
    Field("HIC36_window", 2, "s", "start and end of the HIC36 window",
          columns=("HIC36_t1", "HIC36_t2")),
    Field("HIC15", 1, "-", "HIC over windows of at most 15 ms (exact maximum)"),
    Field("HIC15_window", 2, "s", "start and end of the HIC15 window",
          columns=("HIC15_t1", "HIC15_t2")),
    Field("delta_max", 1, "m", "maximum penetration"),
    Field("a_max_g", 1, "g", "peak head acceleration F_max / (m_h g0)"),
    Field("E_head_final", 1, "J", "head kinetic energy at the end"),
    Field("E_dissipated", 1, "J", "energy dissipated by the contact damping"),
    Field("contact_time", 1, "s", "total time with a positive contact force"),
    Field("v_tcp0", 1, "m/s", "tool point speed |J qd| at t0"),
    Field("E_initial", 1, "J", "energy at t0 (kinetic; springs unloaded, no contact)"),
    Field("E_balance_error", 1, "-",
          "(final energy + dissipated - E_initial) / E_initial"),
])
(R_FMAX, R_TFMAX, R_HIC36, R_W36, R_HIC15, R_W15, R_DMAX, R_AMAX, R_EHEAD, R_EDISS, R_TCONT,
 R_VTCP0, R_E0, R_EBAL) = SUMMARY.offsets(
    "F_max", "t_Fmax", "HIC36", "HIC36_window", "HIC15", "HIC15_window", "delta_max",
    "a_max_g", "E_head_final", "E_dissipated", "contact_time", "v_tcp0", "E_initial",
    "E_balance_error")
SUMMARY_COLUMNS = SUMMARY.columns()
NSUM = SUMMARY.size

#: One sample of a recorded impact history (columns of ImpactResults.histories[i]).
HIST = Layout("impact history row", [
    Field("t", 1, "s", "time after the impact instant t0"),
    Field("F", 1, "N", "contact force (Hunt-Crossley, 6.2)"),
    Field("delta", 1, "m", "penetration R - |x_head - r_tcp| (negative: gap)"),
    Field("a_head_g", 1, "g", "head acceleration F / (m_h g0)"),
    Field("dq", 2, "rad", "joint deflections q - q(t0)"),
    Field("v_head_n", 1, "m/s", "head velocity along the initial direction u"),
    Field("v_tcp_n", 1, "m/s", "tool point velocity along the initial direction u"),
    Field("E_total", 1, "J", "kinetic + spring + contact potential + dissipated energy"),
    Field("qd", 2, "rad/s", "link angular velocities"),
    Field("n", 2, "-", "contact normal (tool point -> head centre)", columns=("nx", "ny")),
    Field("v_head", 2, "m/s", "head velocity", columns=("vhx", "vhy")),
])
(W_T, W_F, W_DELTA, W_AG, W_DQ, W_VHN, W_VTN, W_E, W_QD, W_N, W_VH) = HIST.offsets(
    "t", "F", "delta", "a_head_g", "dq", "v_head_n", "v_tcp_n", "E_total", "qd", "n", "v_head")
HIST_COLUMNS = HIST.columns()
NHIST = HIST.size


_CASE_FIELDS = tuple((f.name, CASE.slice(f.name), f.length, f.default, f.doc)
                     for f in CASE.fields)


def pack_cases(n: int, **fields) -> np.ndarray:
    """Rows of :data:`CASE` for ``n`` cases, fields given by name.

    Parameters
    ----------
    n : int
        Number of cases.
    **fields
        Field values by name; each broadcasts to ``(n, length)`` (a vector
        field of length 2 takes shape (2,) or (n, 2), a scalar field a number
        or shape (n,)).  Fields with a default (``arm_mode``) may be omitted.

    Returns
    -------
    numpy.ndarray, shape (n, NCASE)

    Raises
    ------
    KeyError
        For a name that is not a field of :data:`CASE`.
    ValueError
        For a missing required field or a value that does not broadcast.
    """
    unknown = [k for k in fields if k not in CASE]
    if unknown:
        raise KeyError(f"layout {CASE.name!r} has no field(s) {unknown}; fields: "
                       f"{', '.join(f[0] for f in _CASE_FIELDS)}")
    rows = np.empty((n, NCASE))
    for name, sl, length, default, doc in _CASE_FIELDS:
        if name in fields:
            v = np.asarray(fields[name], dtype=float)
            if length == 1 and v.ndim:
                v = v[..., None]
        elif default is not None:
            v = default
        else:
            raise ValueError(f"layout {CASE.name!r}: field {name!r} ({doc}) is required")
        try:
            rows[:, sl] = v
        except ValueError:
            raise ValueError(f"case field {name!r} must broadcast to ({n}, {length}), "
                             f"got shape {np.shape(fields[name])}") from None
    return rows


def pack_head(head) -> np.ndarray:
    """The :data:`HEAD` row of a :class:`~ppamsafety.impact.head.HeadContactModel`.

    Parameters
    ----------
    head : HeadContactModel
        Head mass [kg], radius [m] and Hunt-Crossley k [N/m^n], n [-],
        b [N s/m^(n+1)] are copied (not validated again).

    Returns
    -------
    numpy.ndarray, shape (HEAD.size,)
    """
    row = np.empty(HEAD.size)
    row[HP_M], row[HP_R], row[HP_K] = head.mass, head.radius, head.stiffness
    row[HP_N], row[HP_B] = head.exponent, head.damping
    return row


@step_kernel
def arm_terms(q1, q2, P):
    """cos/sin of q2, inertia matrix entries and TCP kinematics at the angles q1, q2 [rad].

    Parameters
    ----------
    q1, q2 : float
        Link angles [rad].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`).

    Returns
    -------
    tuple of float
        ``(cos q2, sin q2, H11, H12, H22, x_tcp, y_tcp, J11, J12, J21, J22)``
        (kg m^2, m, m/rad).
    """
    c1, s1 = math.cos(q1), math.sin(q1)
    c2, s2 = math.cos(q2), math.sin(q2)
    c12, s12 = c1 * c2 - s1 * s2, s1 * c2 + c1 * s2
    h11, h12, h22 = mass_matrix_cs(c2, s2, P)
    x, yy, j11, j12, j21, j22 = tcp_kinematics_cs(c1, s1, c12, s12, P)
    return c2, s2, h11, h12, h22, x, yy, j11, j12, j21, j22


@step_kernel
def _arm_terms(y, P):
    """:func:`arm_terms` at the link angles of the impact state ``y`` (layout :data:`STATE`)."""
    return arm_terms(y[Y_Q], y[Y_Q + 1], P)


def _impact_rhs_py(y, case, P, hp, dy):
    """Derivative of the impact state; returns (F, delta, delta_dot, |tcp velocity|).

    Contact force F [N], penetration delta [m], its rate [m/s] and the tool
    point speed [m/s] at state ``y``.  For a fixed arm (``arm_mode`` =
    :attr:`ArmMode.FIXED`) the arm derivatives are zero.  The joint torques
    and the motor-side states follow the case's :class:`JointModel`.

    Parameters
    ----------
    y : ndarray of float64, shape (NY,)
        Integrator state, layout :data:`STATE`; only read.
    case : ndarray of float64, shape (NCASE,)
        The impact case, layout :data:`CASE` (q0, K, arm_mode, joint_model, B
        are read).
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``L1``, ``L2`` and ``theta``.
    hp : ndarray of float64, shape (HEAD.size,)
        Head contact parameters, layout :data:`HEAD` (:func:`pack_head`).
    dy : ndarray of float64, shape (NY,)
        Output, overwritten: dy/dt in the layout :data:`STATE`.
    """
    c2, s2, h11, h12, h22, x, yy, j11, j12, j21, j22 = _arm_terms(y, P)
    w1, w2 = y[Y_W], y[Y_W + 1]
    fixed = int(case[C_ARM]) == ArmMode.FIXED
    if fixed:
        w1, w2 = 0.0, 0.0
    vx, vy = j11 * w1 + j12 * w2, j21 * w1 + j22 * w2
    dx, dyy = y[Y_XH] - x, y[Y_XH + 1] - yy
    dist = math.sqrt(dx * dx + dyy * dyy)
    nx, ny = dx / dist, dyy / dist
    delta = hp[HP_R] - dist
    ddelta = -(nx * (y[Y_VH] - vx) + ny * (y[Y_VH + 1] - vy))
    f = hunt_crossley_force(delta, ddelta, hp[HP_K], hp[HP_N], hp[HP_B])
    if fixed:            # rigid, fixed arm: the tool point does not move
        dy[Y_Q], dy[Y_Q + 1], dy[Y_W], dy[Y_W + 1] = 0.0, 0.0, 0.0, 0.0
        dy[Y_TH], dy[Y_TH + 1], dy[Y_THD], dy[Y_THD + 1] = 0.0, 0.0, 0.0, 0.0
    else:
        dy[Y_Q], dy[Y_Q + 1] = w1, w2
        c11, c12, c21, c22 = coriolis_cs(c2, s2, w1, w2, P)
        jm = int(case[C_JM])
        if jm == JointModel.FROZEN_EQUILIBRIUM:
            sp1 = -case[C_K] * (y[Y_Q] - case[C_Q])
            sp2 = -case[C_K + 1] * (y[Y_Q + 1] - case[C_Q + 1])
        elif jm == JointModel.FLEXIBLE_JOINT:
            sp1 = -case[C_K] * (y[Y_Q] - y[Y_TH]) if case[C_B] > 0.0 else 0.0
            sp2 = -case[C_K + 1] * (y[Y_Q + 1] - y[Y_TH + 1]) if case[C_B + 1] > 0.0 else 0.0
        else:            # rigid: the motor sides are locked to the links
            sp1, sp2 = 0.0, 0.0
            h11 += case[C_B]
            h22 += case[C_B + 1]
        t1 = sp1 - (j11 * nx + j21 * ny) * f - c11 * w1 - c12 * w2
        t2 = sp2 - (j12 * nx + j22 * ny) * f - c21 * w1 - c22 * w2
        det = h11 * h22 - h12 * h12
        dy[Y_W] = (h22 * t1 - h12 * t2) / det
        dy[Y_W + 1] = (h11 * t2 - h12 * t1) / det
        if jm == JointModel.FROZEN_EQUILIBRIUM:
            dy[Y_TH], dy[Y_TH + 1], dy[Y_THD], dy[Y_THD + 1] = 0.0, 0.0, 0.0, 0.0
        else:
            for i in range(2):
                if jm == JointModel.FLEXIBLE_JOINT and case[C_B + i] > 0.0:
                    dy[Y_TH + i] = y[Y_THD + i]
                    dy[Y_THD + i] = case[C_K + i] * (y[Y_Q + i] - y[Y_TH + i]) / case[C_B + i]
                else:    # motor side moves with the link (no spring load can build up)
                    dy[Y_TH + i] = dy[Y_Q + i]
                    dy[Y_THD + i] = dy[Y_W + i]
    dy[Y_XH], dy[Y_XH + 1] = y[Y_VH], y[Y_VH + 1]
    dy[Y_VH] = f * nx / hp[HP_M]
    dy[Y_VH + 1] = f * ny / hp[HP_M]
    dy[Y_ED] = (f - hunt_crossley_elastic(delta, hp[HP_K], hp[HP_N])) * ddelta \
        if delta > 0.0 else 0.0
    return f, delta, ddelta, math.sqrt(vx * vx + vy * vy)


#: The derivative compiled once, for the engines' calls outside the RK4 step.
impact_rhs = step_kernel(_impact_rhs_py)
#: The same source inlined into :func:`_rk4`, where it is hot (see :mod:`ppamsafety._jit`).
_impact_rhs_inline = leaf(_impact_rhs_py)


@step_kernel
def _energy(y, case, P, hp):
    """Kinetic (links, motor sides) + spring + contact potential energy [J].

    Dissipation is not included.  The spring energy follows the case's
    :class:`JointModel`: 1/2 K (q - q0)^2 (frozen equilibrium), 1/2 K (q -
    theta)^2 plus the motor-side kinetic energy 1/2 B thetad^2 (flexible
    joint), or none and 1/2 B qd^2 added to the links' (rigid).
    """
    _, _, h11, h12, h22, x, yy, _, _, _, _ = _arm_terms(y, P)
    w1, w2 = y[Y_W], y[Y_W + 1]
    e = 0.5 * (h11 * w1 * w1 + 2.0 * h12 * w1 * w2 + h22 * w2 * w2)
    if int(case[C_ARM]) == ArmMode.FIXED:
        e = 0.0
    jm = int(case[C_JM])
    if jm == JointModel.FROZEN_EQUILIBRIUM:
        e += 0.5 * case[C_K] * (y[Y_Q] - case[C_Q]) ** 2 \
            + 0.5 * case[C_K + 1] * (y[Y_Q + 1] - case[C_Q + 1]) ** 2
    elif jm == JointModel.FLEXIBLE_JOINT:
        for i in range(2):
            if case[C_B + i] > 0.0:
                e += 0.5 * case[C_B + i] * y[Y_THD + i] * y[Y_THD + i] \
                    + 0.5 * case[C_K + i] * (y[Y_Q + i] - y[Y_TH + i]) ** 2
    elif int(case[C_ARM]) != ArmMode.FIXED:    # rigid: motor sides move with the links
        e += 0.5 * (case[C_B] * w1 * w1 + case[C_B + 1] * w2 * w2)
    e += 0.5 * hp[HP_M] * (y[Y_VH] * y[Y_VH] + y[Y_VH + 1] * y[Y_VH + 1])
    dx, dyy = y[Y_XH] - x, y[Y_XH + 1] - yy
    delta = hp[HP_R] - math.sqrt(dx * dx + dyy * dyy)
    if delta > 0.0:
        e += hunt_crossley_potential(delta, hp[HP_K], hp[HP_N])
    return e


@step_kernel
def initial_state(case, P, hp, y):
    """Arm at q0 with qd0, head centre at r_tcp + R u, head velocity v_h0.

    Parameters
    ----------
    case : ndarray of float64, shape (NCASE,)
        The impact case, layout :data:`CASE`.
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``L1``, ``L2`` and ``theta``.
    hp : ndarray of float64, shape (HEAD.size,)
        Head contact parameters, layout :data:`HEAD` (the radius R is read).
    y : ndarray of float64, shape (NY,)
        Output, overwritten: the initial state, layout :data:`STATE`
        (dissipated energy 0; motor side at theta = q0 with thetad = qd0, or at
        rest for the frozen equilibrium).
    """
    y[Y_Q], y[Y_Q + 1] = case[C_Q], case[C_Q + 1]
    y[Y_W], y[Y_W + 1] = case[C_QD], case[C_QD + 1]
    _, _, _, _, _, x, yy, _, _, _, _ = _arm_terms(y, P)
    y[Y_XH] = x + hp[HP_R] * case[C_U]
    y[Y_XH + 1] = yy + hp[HP_R] * case[C_U + 1]
    y[Y_VH], y[Y_VH + 1] = case[C_VH], case[C_VH + 1]
    y[Y_ED] = 0.0
    y[Y_TH], y[Y_TH + 1] = case[C_Q], case[C_Q + 1]
    if int(case[C_JM]) == JointModel.FROZEN_EQUILIBRIUM:
        y[Y_THD], y[Y_THD + 1] = 0.0, 0.0
    else:
        y[Y_THD], y[Y_THD + 1] = case[C_QD], case[C_QD + 1]


@step_kernel
def _rk4(y, h, case, P, hp, k1, k2, k3, k4, yt):
    """One RK4 step of length h, then the derivative at the new state.

    ``k1`` must hold the derivative at ``y`` on entry; on return ``y`` is the
    new state, ``k1`` its derivative and the result is :func:`impact_rhs`'s
    (F, delta, delta_dot, |tcp velocity|) there.  Every evaluation of the
    derivative inside a step is inlined here (four copies of one source,
    :data:`_impact_rhs_inline`), and this is the one compiled function both
    engines call per step: inlining the derivative at every call site of the
    engines instead made their first compilation take 70 s (measured), and
    calling a non-inlined derivative inside the step made them 11 % slower.
    """
    for i in range(NY):
        yt[i] = y[i] + 0.5 * h * k1[i]
    _impact_rhs_inline(yt, case, P, hp, k2)
    for i in range(NY):
        yt[i] = y[i] + 0.5 * h * k2[i]
    _impact_rhs_inline(yt, case, P, hp, k3)
    for i in range(NY):
        yt[i] = y[i] + h * k3[i]
    _impact_rhs_inline(yt, case, P, hp, k4)
    for i in range(NY):
        y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    return _impact_rhs_inline(y, case, P, hp, k1)


@step_kernel
def _write_history(h, s, dt, f, delta, a, y, case, P, hp):
    """Fill the :data:`HIST` row ``h`` of step ``s`` from the state ``y``."""
    h[W_T], h[W_F], h[W_DELTA], h[W_AG] = s * dt, f, delta, a
    h[W_DQ], h[W_DQ + 1] = y[Y_Q] - case[C_Q], y[Y_Q + 1] - case[C_Q + 1]
    h[W_VHN] = y[Y_VH] * case[C_U] + y[Y_VH + 1] * case[C_U + 1]
    _, _, _, _, _, x, yy, j11, j12, j21, j22 = _arm_terms(y, P)
    h[W_VTN] = ((j11 * y[Y_W] + j12 * y[Y_W + 1]) * case[C_U]
                + (j21 * y[Y_W] + j22 * y[Y_W + 1]) * case[C_U + 1])
    h[W_E] = _energy(y, case, P, hp) + y[Y_ED]
    h[W_QD], h[W_QD + 1] = y[Y_W], y[Y_W + 1]
    dist = math.sqrt((y[Y_XH] - x) ** 2 + (y[Y_XH + 1] - yy) ** 2)
    h[W_N], h[W_N + 1] = (y[Y_XH] - x) / dist, (y[Y_XH + 1] - yy) / dist
    h[W_VH], h[W_VH + 1] = y[Y_VH], y[Y_VH + 1]


@kernel
def _summarize(r, acc, dt, w36, w15, general, fmax, tmax, dmax, tcont, v0, e0, y, case, P, hp):
    """Fill the :data:`SUMMARY` row ``r`` of one impact from its head acceleration ``acc`` [g]
    and final state ``y``; shared by both engines (``general``: HIC by branch and bound only,
    see :func:`~.hic.hic_pair_kernel`)."""
    r[R_FMAX], r[R_TFMAX] = fmax, tmax
    r[R_HIC36], i1, i2, r[R_HIC15], j1, j2 = hic_pair_kernel(acc, dt, w36, w15, general)
    r[R_W36], r[R_W36 + 1] = i1 * dt, i2 * dt
    r[R_W15], r[R_W15 + 1] = j1 * dt, j2 * dt
    r[R_DMAX], r[R_AMAX] = dmax, fmax / (hp[HP_M] * G0)
    r[R_EHEAD] = 0.5 * hp[HP_M] * (y[Y_VH] * y[Y_VH] + y[Y_VH + 1] * y[Y_VH + 1])
    r[R_EDISS] = y[Y_ED]
    r[R_TCONT], r[R_VTCP0], r[R_E0] = tcont, v0, e0
    r[R_EBAL] = (_energy(y, case, P, hp) + y[Y_ED] - e0) / max(e0, 1e-300)


#: Free-flight steps are FREE_STRIDE times the contact step ...
FREE_STRIDE = 20
#: ... and are only taken while the gap exceeds this [m] plus twice the closing distance.
FREE_GAP = 5e-4


@kernel
def impact_batch(CASES, P, hp, dt, nsteps, w36, w15, SUM, HIST, hist_of):
    """Simulate every case; fill SUM (N, NSUM) and HIST[hist_of[c]] where hist_of[c] >= 0.

    CASES rows follow :data:`CASE`, ``hp`` is a :data:`HEAD` row, SUM rows
    follow :data:`SUMMARY` and HIST[j, s] rows :data:`HIST`.

    While head and tool are apart and cannot touch within a long step (gap >
    FREE_GAP + 2 x closing speed x step), the integrator takes steps of
    FREE_STRIDE x dt (the force and head acceleration are exactly zero
    there); in contact, near contact and for recorded histories it uses dt.

    Parameters
    ----------
    CASES : ndarray of float64, shape (N, NCASE), C-contiguous
        The impact cases, one :data:`CASE` row each.
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``L1``, ``L2`` and ``theta``.
    hp : ndarray of float64, shape (HEAD.size,)
        Head contact parameters, layout :data:`HEAD` (:func:`pack_head`).
    dt : float
        RK4 step in contact [s]; also the HIC sample spacing.
    nsteps : int
        Number of steps of ``dt`` simulated (duration ``nsteps * dt``).
    w36, w15 : int
        HIC36 / HIC15 window limits in whole sample intervals
        (0.036 s / dt and 0.015 s / dt rounded down).
    SUM : ndarray of float64, shape (N, NSUM)
        Output, overwritten: one :data:`SUMMARY` row per case.
    HIST : ndarray of float64, shape (H, nsteps + 1, NHIST)
        Output: for a recorded case c, ``HIST[hist_of[c], s]`` is filled with
        the :data:`HIST` row of step s (every step is taken with ``dt``).
    hist_of : ndarray of int64, shape (N,)
        Per case, its index into the first axis of ``HIST``, or -1 for no
        history.
    """
    y = np.empty(NY)
    yt = np.empty(NY)
    k1, k2, k3, k4 = np.empty(NY), np.empty(NY), np.empty(NY), np.empty(NY)
    acc = np.empty(nsteps + 1)
    for c in range(CASES.shape[0]):
        case = CASES[c]
        initial_state(case, P, hp, y)
        e0 = _energy(y, case, P, hp)
        fmax, tmax, dmax, tcont, v0 = 0.0, 0.0, 0.0, 0.0, -1.0
        hrow = hist_of[c]
        s = 0
        f, delta, ddelta, vt = impact_rhs(y, case, P, hp, k1)
        while True:
            if v0 < 0.0:
                v0 = vt
            acc[s] = f / (hp[HP_M] * G0)
            if f > fmax:
                fmax, tmax = f, s * dt
            dmax = max(dmax, delta)
            if f > 0.0:
                tcont += dt
            if hrow >= 0:
                _write_history(HIST[hrow, s], s, dt, f, delta, acc[s], y, case, P, hp)
            if s == nsteps:
                break
            m = FREE_STRIDE
            if (hrow < 0 and f == 0.0 and s + m <= nsteps
                    and -delta > FREE_GAP + 2.0 * max(ddelta, 0.0) * m * dt):
                f, delta, ddelta, vt = _rk4(y, m * dt, case, P, hp, k1, k2, k3, k4, yt)
                for i in range(1, m):
                    acc[s + i] = 0.0
                s += m
            else:
                f, delta, ddelta, vt = _rk4(y, dt, case, P, hp, k1, k2, k3, k4, yt)
                s += 1
        # the reference engine keeps the general branch and bound, so that comparing it with
        # the dense engine (single-pulse HIC path) also cross-checks the two HIC algorithms
        _summarize(SUM[c], acc, dt, w36, w15, True, fmax, tmax, dmax, tcont, v0, e0, y, case,
                   P, hp)


#: Step of the dense-output integrator, in grid intervals dt (see :func:`impact_batch_dense`).
DENSE_STRIDE = 8
#: Its free-flight step while the gap exceeds FREE_GAP plus twice the closing distance [dt].
DENSE_FREE_STRIDE = 100


@step_kernel
def _delta_rates(y, case, P, hp, dy):
    """(d2 delta/dt2, dF/dt) at state ``y`` whose derivative ``dy`` is given.

    delta = R - |x|, x = x_head - r_tcp: delta'' = -(|x'|^2 - (n.x')^2)/|x| - n.x''
    with x'' = a_head - (J qdd + Jdot qd); for the planar 2R chain
    Jdot qd = -w1^2 p1 - (w1 + w2)^2 p2 (p1: base to elbow = (j21 - j22, j12 - j11),
    p2: elbow to tool = (j22, -j12)).  dF/dt = n delta^(n-1) delta' (k + b delta')
    + b delta^n delta'' where F > 0, else 0.
    """
    _, _, _, _, _, x, yy, j11, j12, j21, j22 = _arm_terms(y, P)
    w1, w2, a1, a2 = y[Y_W], y[Y_W + 1], dy[Y_W], dy[Y_W + 1]
    if int(case[C_ARM]) == ArmMode.FIXED:
        w1, w2, a1, a2 = 0.0, 0.0, 0.0, 0.0
    vx, vy = j11 * w1 + j12 * w2, j21 * w1 + j22 * w2
    w12 = w1 + w2
    atx = j11 * a1 + j12 * a2 - w1 * w1 * (j21 - j22) - w12 * w12 * j22
    aty = j21 * a1 + j22 * a2 - w1 * w1 * (j12 - j11) + w12 * w12 * j12
    dx, dyy = y[Y_XH] - x, y[Y_XH + 1] - yy
    dist = math.sqrt(dx * dx + dyy * dyy)
    nx, ny = dx / dist, dyy / dist
    ex, ey = y[Y_VH] - vx, y[Y_VH + 1] - vy
    en = nx * ex + ny * ey
    ddd = -((ex * ex + ey * ey - en * en) / dist + nx * (dy[Y_VH] - atx) + ny * (dy[Y_VH + 1] - aty))
    delta, dd = hp[HP_R] - dist, -en
    if delta <= 0.0:
        return ddd, 0.0
    g = hp[HP_K] + hp[HP_B] * dd
    if g <= 0.0:
        return ddd, 0.0
    dn = delta ** hp[HP_N]
    return ddd, hp[HP_N] * dn / delta * dd * g + hp[HP_B] * dn * ddd


@step_kernel
def _hermite(v0, d0, v1, d1, h, s):
    """Cubic Hermite interpolant at fraction s of [0, h] from values and derivatives at both ends."""
    s2 = s * s
    s3 = s2 * s
    return ((2.0 * s3 - 3.0 * s2 + 1.0) * v0 + (s3 - 2.0 * s2 + s) * h * d0
            + (3.0 * s2 - 2.0 * s3) * v1 + (s3 - s2) * h * d1)


@kernel
def impact_batch_dense(CASES, P, hp, dt, nsteps, w36, w15, SUM):
    """:func:`impact_batch` without histories, RK4 steps of DENSE_STRIDE x dt in contact.

    The head acceleration is still sampled on the grid k dt (for the HIC and
    F_max): between the ends of a long step, where the force is positive at
    both ends, F(t) and delta(t) are cubic Hermite interpolants of their values
    and rates at the ends (dF/dt and delta'' from :func:`_delta_rates`;
    F clipped at 0).  A long step across which the force switches between zero
    and positive (contact onset, where F ~ t^(3/2) is not smooth, and
    separation) is repeated with DENSE_STRIDE steps of dt, as is any step while
    head and tool approach each other with a gap too small for a long step
    (while they separate, a contact cannot start inside a long step, and if the
    force becomes positive at its end the step is repeated finely); free flight
    as in :func:`impact_batch`, with steps of DENSE_FREE_STRIDE x dt while the
    gap exceeds FREE_GAP plus twice the closing distance of such a step.
    Accuracy against solve_ivp: tests/test_impact_dense.py.

    Parameters
    ----------
    CASES : numpy.ndarray, shape (N, NCASE)
        Impact cases, rows of :data:`CASE`.
    P : numpy.ndarray
        Arm parameter vector (:func:`ppamsafety.plant.packing.pack`).
    hp : numpy.ndarray
        Head row (:data:`HEAD`).
    dt : float
        Grid step of the force samples and of the fine RK4 steps [s].
    nsteps : int
        Grid intervals simulated (duration / dt).
    w36, w15 : int
        HIC window limits in grid intervals.
    SUM : numpy.ndarray, shape (N, NSUM)
        Output, rows of :data:`SUMMARY`.
    """
    y = np.empty(NY)
    ys = np.empty(NY)
    yt = np.empty(NY)
    k1, k2, k3, k4 = np.empty(NY), np.empty(NY), np.empty(NY), np.empty(NY)
    acc = np.empty(nsteps + 1)
    mg = hp[HP_M] * G0
    for c in range(CASES.shape[0]):
        case = CASES[c]
        initial_state(case, P, hp, y)
        e0 = _energy(y, case, P, hp)
        f0, delta0, dd0, v0 = impact_rhs(y, case, P, hp, k1)
        ddd0, fd0 = _delta_rates(y, case, P, hp, k1)
        acc[0] = f0 / mg
        fmax, tmax, dmax = f0, 0.0, max(delta0, 0.0)
        tcont = dt if f0 > 0.0 else 0.0
        s = 0
        while s < nsteps:
            m = DENSE_FREE_STRIDE
            if not (s + m <= nsteps and -delta0 > FREE_GAP + 2.0 * max(dd0, 0.0) * m * dt):
                m = FREE_STRIDE
            if (f0 == 0.0 and s + m <= nsteps
                    and -delta0 > FREE_GAP + 2.0 * max(dd0, 0.0) * m * dt):
                f0, delta0, dd0, _ = _rk4(y, m * dt, case, P, hp, k1, k2, k3, k4, yt)
                for i in range(1, m):
                    acc[s + i] = 0.0
                s += m
                ddd0, fd0 = _delta_rates(y, case, P, hp, k1)
                acc[s] = f0 / mg
                if f0 > fmax:
                    fmax, tmax = f0, s * dt
                dmax = max(dmax, delta0)
                if f0 > 0.0:
                    tcont += dt
                continue
            m = min(DENSE_STRIDE, nsteps - s)
            fine = m == 1 or (f0 == 0.0 and dd0 > 0.0 and -delta0 <= FREE_GAP * DENSE_STRIDE
                              / FREE_STRIDE + 2.0 * dd0 * m * dt)
            if not fine:
                for i in range(NY):
                    ys[i] = y[i]
                f1, delta1, dd1, _ = _rk4(y, m * dt, case, P, hp, k1, k2, k3, k4, yt)
                if (f1 > 0.0) != (f0 > 0.0):         # contact switches inside: redo finely
                    for i in range(NY):
                        y[i] = ys[i]
                    impact_rhs(y, case, P, hp, k1)
                    fine = True
                else:
                    ddd1, fd1 = _delta_rates(y, case, P, hp, k1)
                    h = m * dt
                    for i in range(1, m):
                        fr = i / m
                        fi = 0.0
                        if f0 > 0.0:
                            fi = max(_hermite(f0, fd0, f1, fd1, h, fr), 0.0)
                        di = _hermite(delta0, dd0, delta1, dd1, h, fr)
                        acc[s + i] = fi / mg
                        if fi > fmax:
                            fmax, tmax = fi, (s + i) * dt
                        dmax = max(dmax, di)
                        if fi > 0.0:
                            tcont += dt
                    s += m
                    f0, delta0, dd0, ddd0, fd0 = f1, delta1, dd1, ddd1, fd1
            if fine:
                for i in range(m):
                    f0, delta0, dd0, _ = _rk4(y, dt, case, P, hp, k1, k2, k3, k4, yt)
                    s += 1
                    acc[s] = f0 / mg
                    if f0 > fmax:
                        fmax, tmax = f0, s * dt
                    dmax = max(dmax, delta0)
                    if f0 > 0.0:
                        tcont += dt
                ddd0, fd0 = _delta_rates(y, case, P, hp, k1)
            else:
                acc[s] = f0 / mg
                if f0 > fmax:
                    fmax, tmax = f0, s * dt
                dmax = max(dmax, delta0)
                if f0 > 0.0:
                    tcont += dt
        _summarize(SUM[c], acc, dt, w36, w15, False, fmax, tmax, dmax, tcont, v0, e0, y, case,
                   P, hp)
