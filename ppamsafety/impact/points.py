"""Impact of any point of the flexible-joint arm with a free body region, through layers in series.

The model of :mod:`ppamsafety.impact.engine` (thesis §6.3.2: unactuated flexible-joint arm in
the horizontal plane, joint springs of constant stiffness K unloaded at t0, motor side frozen
at q(t0)), generalised in two ways:

* the contact is at a *contact point* of the arm: a material point of link 1 or 2 at a distance
  s from its joint along the link (:class:`~ppamsafety.params.contact.ContactPoint`; the tool
  point is link 2 at s = L2).  Its position and Jacobian J_p(q) replace the tool point's::

      H(q) qdd + C(q, qd) qd = -K (q - q0) + J_p(q)^T f,      m_b x_b'' = -f

  so the effective mass the body meets is 1/(u^T J_p H^-1 J_p^T u) (a point of link 1 is moved
  by joint 1 only);
* the body is a free body region of mass m_b (not only the head) and the contact force is the
  shared force of the covering and the body's layers in series (:mod:`ppamsafety.impact.layers`):
  compression delta = R_b - |x_b - p| (R_b the body's radius), normal n = (x_b - p)/|x_b - p|.

The body touches the point at t0 with its centre along u (by default the point's velocity
relative to the body: the worst case, thesis fig. 6.2).  Integration: classical RK4 with a fixed
step (default 20 us) for 50 ms, with the free-flight steps and the exact HIC of the tool-point
engine; the power dissipated by the contact is integrated in total and per layer, so every
impact carries its energy balance (kinetic in = kinetic out + spring + stored + dissipated in
each layer).  With the tool point, bare metal and a one-layer body this is the tool-point
engine's arithmetic step for step (the same summary values, bit for bit; tested).

A *screening* run (``stride`` m > 1) takes its steps in contact with m dt and samples the
force on that coarser grid (the HIC on it, the peak force refined by a parabola through the
largest sample and its neighbours); a long step across which the contact starts or ends is
taken again in :data:`REDO_STEPS` shorter steps (their peak kept), so the onset and the
separation are resolved: a cheap
estimate used by the every-instant scan (:mod:`ppamsafety.impact.anywhere`) to choose the
instants simulated exactly.

Data layouts (declared here): :data:`PCASE` (one case), :data:`PSTATE` (integrator state),
:data:`PSUMMARY` (summary row; :data:`PSUMMARY_COLUMNS`) and :data:`PHIST` (history sample).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel, leaf
from ..layouts import Field, Layout
from ..plant.dynamics import coriolis_cs, mass_matrix_cs
from ..plant.layout import L1
from ..units import G0
from .engine import FREE_GAP, ArmMode
from .hic import hic_pair_kernel
from .layers import NL, NWORK, S_AF, S_LIM, S_M, S_NC, S_R, W_HINT, stack_eval

# ---- declared layouts ------------------------------------------------------------------------
#: One impact case of a contact point: the arm state at t0, the point and the placement.
PCASE = Layout("contact point case", [
    Field("q", 2, "rad", "link angles at the impact instant t0"),
    Field("qd", 2, "rad/s", "link angular velocities at t0 (unused for a fixed arm)"),
    Field("K", 2, "N m/rad", "joint stiffnesses, constant during the impact (2.18)"),
    Field("u", 2, "-", "unit vector from the contact point to the body centre at t0",
          columns=("ux", "uy")),
    Field("v_body", 2, "m/s", "body velocity at t0", columns=("vbx0", "vby0")),
    Field("arm_mode", 1, "code", "ArmMode: flexible-joint (0) or rigid fixed arm (1)",
          default=float(ArmMode.FLEXIBLE)),
    Field("link", 1, "-", "link of the contact point (1 or 2)"),
    Field("position", 1, "m", "distance of the point from its link's joint along the link"),
])
P_Q, P_QD, P_K, P_U, P_VB, P_ARM, P_LINK, P_POS = PCASE.offsets(
    "q", "qd", "K", "u", "v_body", "arm_mode", "link", "position")
NPCASE = PCASE.size

#: Integrator state of one contact-point impact.
PSTATE = Layout("contact point integrator state", [
    Field("q", 2, "rad", "link angles"),
    Field("w", 2, "rad/s", "link angular velocities"),
    Field("x_body", 2, "m", "body centre position", columns=("xb", "yb")),
    Field("v_body", 2, "m/s", "body centre velocity", columns=("vxb", "vyb")),
    Field("E_dissipated", 1, "J", "integral of (F - F_el) d(delta)/dt dt"),
    Field("E_layer", NL, "J", "the same, booked to each layer by its compliance share"),
])
Z_Q, Z_W, Z_XB, Z_VB, Z_ED, Z_EL = PSTATE.offsets(
    "q", "w", "x_body", "v_body", "E_dissipated", "E_layer")
NZ = PSTATE.size

#: One row of the summary of a contact-point impact.
PSUMMARY = Layout("contact point summary", [
    Field("F_max", 1, "N", "peak contact force"),
    Field("t_Fmax", 1, "s", "time of the peak force after t0"),
    Field("HIC36", 1, "-", "HIC over windows of at most 36 ms (exact maximum)"),
    Field("HIC36_window", 2, "s", "start and end of the HIC36 window",
          columns=("HIC36_t1", "HIC36_t2")),
    Field("HIC15", 1, "-", "HIC over windows of at most 15 ms (exact maximum)"),
    Field("HIC15_window", 2, "s", "start and end of the HIC15 window",
          columns=("HIC15_t1", "HIC15_t2")),
    Field("delta_max", 1, "m", "largest total compression of the layers"),
    Field("a_max_g", 1, "g", "peak body acceleration F_max / (m_b g0)"),
    Field("p_max", 1, "Pa", "peak mean contact pressure F / (pi R_e delta)"),
    Field("covering_use", 1, "-", "largest compression of a covering layer over its limit "
          "(1: bottomed out; 0: bare metal)"),
    Field("E_body_final", 1, "J", "body kinetic energy at the end"),
    Field("E_dissipated", 1, "J", "energy dissipated by the contact"),
    Field("E_layer", NL, "J", "energy dissipated in each layer (covering first)",
          columns=tuple(f"E_layer{i + 1}" for i in range(NL))),
    Field("contact_time", 1, "s", "total time with a positive contact force"),
    Field("v_point0", 1, "m/s", "contact point speed |J_p qd| at t0"),
    Field("E_initial", 1, "J", "energy at t0 (kinetic; springs unloaded, no contact)"),
    Field("E_balance_error", 1, "-", "(final energy + dissipated - E_initial) / E_initial"),
])
(U_FMAX, U_TFMAX, U_HIC36, U_W36, U_HIC15, U_W15, U_DMAX, U_AMAX, U_PMAX, U_CUSE, U_EBODY,
 U_EDISS, U_ELAY, U_TCONT, U_VP0, U_E0, U_EBAL) = PSUMMARY.offsets(
    "F_max", "t_Fmax", "HIC36", "HIC36_window", "HIC15", "HIC15_window", "delta_max",
    "a_max_g", "p_max", "covering_use", "E_body_final", "E_dissipated", "E_layer",
    "contact_time", "v_point0", "E_initial", "E_balance_error")
PSUMMARY_COLUMNS = PSUMMARY.columns()
NPSUM = PSUMMARY.size

#: One sample of a recorded contact-point impact.
PHIST = Layout("contact point history row", [
    Field("t", 1, "s", "time after the impact instant t0"),
    Field("F", 1, "N", "contact force (shared by every layer)"),
    Field("delta", 1, "m", "total compression R_b - |x_b - p| (negative: gap)"),
    Field("a_body_g", 1, "g", "body acceleration F / (m_b g0)"),
    Field("pressure", 1, "Pa", "mean contact pressure F / (pi R_e delta)"),
    Field("delta_layer", NL, "m", "compression of each layer (covering first)",
          columns=tuple(f"delta{i + 1}" for i in range(NL))),
    Field("dq", 2, "rad", "joint deflections q - q(t0)"),
    Field("v_body_n", 1, "m/s", "body velocity along the initial direction u"),
    Field("v_point_n", 1, "m/s", "contact point velocity along u"),
    Field("E_total", 1, "J", "kinetic + spring + stored + dissipated energy"),
])
(H_T, H_F, H_DELTA, H_AG, H_P, H_DL, H_DQ, H_VBN, H_VPN, H_E) = PHIST.offsets(
    "t", "F", "delta", "a_body_g", "pressure", "delta_layer", "dq", "v_body_n", "v_point_n",
    "E_total")
PHIST_COLUMNS = PHIST.columns()
NPHIST = PHIST.size


#: A long screening step across which the contact starts or ends is redone in this many
#: steps (of dt at the least).
REDO_STEPS = 8


@kernel
def point_terms(q1, q2, P, link, s):
    """Inertia and the kinematics of a point of the arm at the link angles q1, q2 [rad].

    The point is on link ``link`` (1 or 2) at ``s`` [m] from that link's joint along the link.
    For link 2 at s = L2 the arithmetic is that of the tool point
    (:func:`~ppamsafety.plant.geometry.tcp_kinematics_cs`).

    Parameters
    ----------
    q1, q2 : float
        Link angles [rad].
    P : ndarray of float64
        Packed plant parameter row (reads L1 and the inertia terms).
    link : int
        1 or 2.
    s : float
        Distance of the point from its link's joint [m].

    Returns
    -------
    tuple of float
        ``(cos q2, sin q2, H11, H12, H22, x, y, J11, J12, J21, J22)`` (kg m^2, m, m/rad).
    """
    c1, s1 = math.cos(q1), math.sin(q1)
    c2, s2 = math.cos(q2), math.sin(q2)
    c12, s12 = c1 * c2 - s1 * s2, s1 * c2 + c1 * s2
    h11, h12, h22 = mass_matrix_cs(c2, s2, P)
    if link == 2:
        x, yy = P[L1] * c1 + s * c12, P[L1] * s1 + s * s12
        j11, j12, j21, j22 = -P[L1] * s1 - s * s12, -s * s12, P[L1] * c1 + s * c12, s * c12
    else:
        x, yy = s * c1, s * s1
        j11, j12, j21, j22 = -s * s1, 0.0, s * c1, 0.0
    return c2, s2, h11, h12, h22, x, yy, j11, j12, j21, j22


@kernel
def _terms(y, case, P):
    return point_terms(y[Z_Q], y[Z_Q + 1], P, int(case[P_LINK]), case[P_POS])


def _rhs_py(y, case, P, S, work, dy):
    """Derivative of the state; returns (F, delta, delta_dot, |point velocity|).

    Frozen-equilibrium joint springs (H qdd + C qd = -K (q - q0) + J_p^T f), or a fixed arm;
    the contact force of the stack ``S`` (:func:`~ppamsafety.impact.layers.stack_eval`, which
    also fills ``work``).

    Parameters
    ----------
    y : ndarray of float64, shape (NZ,)
        State, layout :data:`PSTATE` (read).
    case : ndarray of float64, shape (NPCASE,)
        The case, layout :data:`PCASE`.
    P : ndarray of float64
        Packed plant parameter row.
    S : ndarray of float64
        The contact stack (:data:`~ppamsafety.impact.layers.STACK`).
    work : ndarray of float64
        Work array of :func:`~ppamsafety.impact.layers.stack_eval`.
    dy : ndarray of float64, shape (NZ,)
        Output: dy/dt.
    """
    c2, s2, h11, h12, h22, x, yy, j11, j12, j21, j22 = _terms(y, case, P)
    w1, w2 = y[Z_W], y[Z_W + 1]
    fixed = int(case[P_ARM]) == ArmMode.FIXED
    if fixed:
        w1, w2 = 0.0, 0.0
    vx, vy = j11 * w1 + j12 * w2, j21 * w1 + j22 * w2
    dx, dyy = y[Z_XB] - x, y[Z_XB + 1] - yy
    dist = math.sqrt(dx * dx + dyy * dyy)
    nx, ny = dx / dist, dyy / dist
    delta = S[S_R] - dist
    ddelta = -(nx * (y[Z_VB] - vx) + ny * (y[Z_VB + 1] - vy))
    f, fel, _, _ = stack_eval(delta, ddelta, S, work)
    if fixed:
        dy[Z_Q], dy[Z_Q + 1], dy[Z_W], dy[Z_W + 1] = 0.0, 0.0, 0.0, 0.0
    else:
        dy[Z_Q], dy[Z_Q + 1] = w1, w2
        c11, c12, c21, c22 = coriolis_cs(c2, s2, w1, w2, P)
        sp1 = -case[P_K] * (y[Z_Q] - case[P_Q])
        sp2 = -case[P_K + 1] * (y[Z_Q + 1] - case[P_Q + 1])
        t1 = sp1 - (j11 * nx + j21 * ny) * f - c11 * w1 - c12 * w2
        t2 = sp2 - (j12 * nx + j22 * ny) * f - c21 * w1 - c22 * w2
        det = h11 * h22 - h12 * h12
        dy[Z_W] = (h22 * t1 - h12 * t2) / det
        dy[Z_W + 1] = (h11 * t2 - h12 * t1) / det
    dy[Z_XB], dy[Z_XB + 1] = y[Z_VB], y[Z_VB + 1]
    dy[Z_VB] = f * nx / S[S_M]
    dy[Z_VB + 1] = f * ny / S[S_M]
    p = (f - fel) * ddelta if delta > 0.0 else 0.0
    dy[Z_ED] = p
    for i in range(NL):
        dy[Z_EL + i] = p * work[NL + i]
    return f, delta, ddelta, math.sqrt(vx * vx + vy * vy)


#: The derivative compiled once, for calls outside the RK4 step.
point_rhs = kernel(_rhs_py)
#: The same source inlined into :func:`_rk4` (see :mod:`ppamsafety._jit`).
_rhs_inline = leaf(_rhs_py)


@kernel
def _energy(y, case, P, S, work):
    """Kinetic (links, body) + spring + stored contact energy [J] (dissipation not included)."""
    _, _, h11, h12, h22, x, yy, _, _, _, _ = _terms(y, case, P)
    w1, w2 = y[Z_W], y[Z_W + 1]
    e = 0.5 * (h11 * w1 * w1 + 2.0 * h12 * w1 * w2 + h22 * w2 * w2)
    if int(case[P_ARM]) == ArmMode.FIXED:
        e = 0.0
    e += 0.5 * case[P_K] * (y[Z_Q] - case[P_Q]) ** 2 \
        + 0.5 * case[P_K + 1] * (y[Z_Q + 1] - case[P_Q + 1]) ** 2
    e += 0.5 * S[S_M] * (y[Z_VB] * y[Z_VB] + y[Z_VB + 1] * y[Z_VB + 1])
    dx, dyy = y[Z_XB] - x, y[Z_XB + 1] - yy
    delta = S[S_R] - math.sqrt(dx * dx + dyy * dyy)
    if delta > 0.0:
        _, _, _, v = stack_eval(delta, 0.0, S, work)
        e += v
    return e


@kernel
def point_initial_state(case, P, S, y):
    """Arm at q0 with qd0, body centre at p + R_b u with velocity v_b0, nothing dissipated.

    Parameters
    ----------
    case : ndarray of float64, shape (NPCASE,)
        The case, layout :data:`PCASE`.
    P : ndarray of float64
        Packed plant parameter row.
    S : ndarray of float64
        The contact stack (its body radius is read).
    y : ndarray of float64, shape (NZ,)
        Output: the initial state, layout :data:`PSTATE`.
    """
    y[Z_Q], y[Z_Q + 1] = case[P_Q], case[P_Q + 1]
    y[Z_W], y[Z_W + 1] = case[P_QD], case[P_QD + 1]
    _, _, _, _, _, x, yy, _, _, _, _ = _terms(y, case, P)
    y[Z_XB] = x + S[S_R] * case[P_U]
    y[Z_XB + 1] = yy + S[S_R] * case[P_U + 1]
    y[Z_VB], y[Z_VB + 1] = case[P_VB], case[P_VB + 1]
    y[Z_ED] = 0.0
    for i in range(NL):
        y[Z_EL + i] = 0.0


@kernel
def _rk4(y, h, case, P, S, work, k1, k2, k3, k4, yt):
    """One RK4 step of length h; ``k1`` holds the derivative at ``y`` on entry and at the new
    state on return; returns :func:`point_rhs`'s tuple at the new state."""
    for i in range(NZ):
        yt[i] = y[i] + 0.5 * h * k1[i]
    _rhs_inline(yt, case, P, S, work, k2)
    for i in range(NZ):
        yt[i] = y[i] + 0.5 * h * k2[i]
    _rhs_inline(yt, case, P, S, work, k3)
    for i in range(NZ):
        yt[i] = y[i] + h * k3[i]
    _rhs_inline(yt, case, P, S, work, k4)
    for i in range(NZ):
        y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    return _rhs_inline(y, case, P, S, work, k1)


@kernel
def _covering_use(S, work):
    """Largest compression of a covering layer over its limit, from the last evaluation."""
    use = 0.0
    for i in range(int(S[S_NC])):
        u = work[i] / S[S_LIM + i]
        if u > use:
            use = u
    return use


@kernel
def _write_history(h, t, f, delta, a, y, case, P, S, work, e):
    h[H_T], h[H_F], h[H_DELTA], h[H_AG] = t, f, delta, a
    h[H_P] = f / (S[S_AF] * delta) if delta > 0.0 else 0.0
    for i in range(NL):
        h[H_DL + i] = work[i] if delta > 0.0 else 0.0
    h[H_DQ], h[H_DQ + 1] = y[Z_Q] - case[P_Q], y[Z_Q + 1] - case[P_Q + 1]
    h[H_VBN] = y[Z_VB] * case[P_U] + y[Z_VB + 1] * case[P_U + 1]
    _, _, _, _, _, _, _, j11, j12, j21, j22 = _terms(y, case, P)
    h[H_VPN] = ((j11 * y[Z_W] + j12 * y[Z_W + 1]) * case[P_U]
                + (j21 * y[Z_W] + j22 * y[Z_W + 1]) * case[P_U + 1])
    h[H_E] = e + y[Z_ED]


@kernel
def point_batch(CASES, P, S, dt, nsteps, w36, w15, stride, free, SUM, HIST, hist_of):
    """Simulate every case; fill SUM (N, NPSUM) and HIST[hist_of[c]] where hist_of[c] >= 0.

    In contact (and near it) the RK4 step is ``stride`` x dt and the force is sampled once per
    step; while the point and the body are apart and cannot touch within a long step (gap >
    FREE_GAP + 2 x closing speed x step), steps of (``free`` // ``stride``) x ``stride`` x dt.
    ``stride`` = 1 is the exact engine (every step dt, HIC by branch and bound, as the
    tool-point engine); ``stride`` > 1 a screening run (module docstring; no histories).
    ``nsteps`` must be a multiple of ``stride``; ``w36``, ``w15`` are the HIC windows in
    samples of ``stride`` x dt.

    Parameters
    ----------
    CASES : ndarray of float64, shape (N, NPCASE)
        Rows of :data:`PCASE`.
    P : ndarray of float64
        Packed plant parameter row (reads L1, the inertia terms).
    S : ndarray of float64, shape (NSTACK,)
        The contact stack (:func:`~ppamsafety.impact.layers.pack_stack`).
    dt : float
        Grid step [s].
    nsteps : int
        Grid steps simulated.
    w36, w15 : int
        HIC window limits in samples.
    stride, free : int
        Contact and free-flight steps in units of dt.
    SUM : ndarray of float64, shape (N, NPSUM)
        Output.
    HIST : ndarray of float64, shape (H, nsteps + 1, NPHIST)
        Output histories (``stride`` = 1 only).
    hist_of : ndarray of int64, shape (N,)
        History row of each case, or -1.
    """
    y = np.empty(NZ)
    ys = np.empty(NZ)
    yt = np.empty(NZ)
    k1, k2, k3, k4 = np.empty(NZ), np.empty(NZ), np.empty(NZ), np.empty(NZ)
    work = np.empty(NWORK)
    nsamp = nsteps // stride
    acc = np.empty(nsamp + 1)
    h = stride * dt
    mg = S[S_M] * G0
    for c in range(CASES.shape[0]):
        case = CASES[c]
        work[W_HINT] = np.nan
        point_initial_state(case, P, S, y)
        e0 = _energy(y, case, P, S, work)
        fmax, tmax, dmax, tcont, v0, pmax, cuse = 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0
        imax = 0
        ffine, tfine = 0.0, 0.0
        hrow = hist_of[c]
        s = 0
        f, delta, ddelta, vt = point_rhs(y, case, P, S, work, k1)
        while True:
            if v0 < 0.0:
                v0 = vt
            acc[s] = f / mg
            if f > fmax:
                fmax, tmax, imax = f, s * h, s
            dmax = max(dmax, delta)
            if delta > 0.0:
                if f / (S[S_AF] * delta) > pmax:
                    pmax = f / (S[S_AF] * delta)
                cu = _covering_use(S, work)
                if cu > cuse:
                    cuse = cu
            if f > 0.0:
                tcont += h
            if hrow >= 0:
                _write_history(HIST[hrow, s], s * h, f, delta, acc[s], y, case, P, S, work,
                               _energy(y, case, P, S, work))
            if s == nsamp:
                break
            m = free // stride
            if (hrow < 0 and f == 0.0 and s + m <= nsamp
                    and -delta > FREE_GAP + 2.0 * max(ddelta, 0.0) * m * h):
                f, delta, ddelta, vt = _rk4(y, m * h, case, P, S, work, k1, k2, k3, k4, yt)
                for i in range(1, m):
                    acc[s + i] = 0.0
                s += m
            elif stride == 1:
                f, delta, ddelta, vt = _rk4(y, h, case, P, S, work, k1, k2, k3, k4, yt)
                s += 1
            else:
                for i in range(NZ):
                    ys[i] = y[i]
                f1, d1, dd1, vt1 = _rk4(y, h, case, P, S, work, k1, k2, k3, k4, yt)
                if (f1 > 0.0) == (f > 0.0):
                    f, delta, ddelta, vt = f1, d1, dd1, vt1
                else:
                    # the contact starts or ends inside the long step: redo it in REDO_STEPS
                    # shorter steps (of dt at the least), keeping their peak (onset and
                    # separation are not smooth)
                    for i in range(NZ):
                        y[i] = ys[i]
                    point_rhs(y, case, P, S, work, k1)
                    sub = max(stride // REDO_STEPS, 1)
                    for j in range(stride // sub):
                        f, delta, ddelta, vt = _rk4(y, sub * dt, case, P, S, work, k1, k2, k3,
                                                    k4, yt)
                        if f > ffine:
                            ffine, tfine = f, s * h + (j + 1) * sub * dt
                        dmax = max(dmax, delta)
                        if delta > 0.0 and f / (S[S_AF] * delta) > pmax:
                            pmax = f / (S[S_AF] * delta)
                s += 1
        r = SUM[c]
        if stride > 1:
            if 0 < imax < nsamp:
                # screening: the peak between samples, from the parabola through three samples
                fa, fb, fc = acc[imax - 1] * mg, acc[imax] * mg, acc[imax + 1] * mg
                den = fa - 2.0 * fb + fc
                if den < 0.0:
                    x = 0.5 * (fa - fc) / den
                    fmax = fb - 0.25 * (fa - fc) * x
                    tmax = (imax + x) * h
            if ffine > fmax:
                fmax, tmax = ffine, tfine
        r[U_FMAX], r[U_TFMAX] = fmax, tmax
        r[U_HIC36], i1, i2, r[U_HIC15], j1, j2 = hic_pair_kernel(acc, h, w36, w15, stride == 1)
        r[U_W36], r[U_W36 + 1] = i1 * h, i2 * h
        r[U_W15], r[U_W15 + 1] = j1 * h, j2 * h
        r[U_DMAX], r[U_AMAX], r[U_PMAX], r[U_CUSE] = dmax, fmax / mg, pmax, cuse
        r[U_EBODY] = 0.5 * S[S_M] * (y[Z_VB] * y[Z_VB] + y[Z_VB + 1] * y[Z_VB + 1])
        r[U_EDISS] = y[Z_ED]
        for i in range(NL):
            r[U_ELAY + i] = y[Z_EL + i]
        r[U_TCONT], r[U_VP0], r[U_E0] = tcont, v0, e0
        r[U_EBAL] = (_energy(y, case, P, S, work) + y[Z_ED] - e0) / max(e0, 1e-300)
