"""Impact of the flexible-joint arm with a free head (thesis §6.3.2).

Model (SPEC §4): the arm is unactuated, in the horizontal plane (no gravity),
with rigid links and torsional joint springs of constant stiffness K
(2.18) whose motor side is frozen at the impact instant t0::

    H(q) qdd + C(q, qd) qd = -K (q - q0) + J(q)^T f_tool
    m_h x_h'' = f_head,        f_head = -f_tool = F n

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
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel, leaf
from ..plant.dynamics import coriolis_cs, mass_matrix_cs
from ..plant.geometry import tcp_kinematics_cs
from ..units import G0
from .contact import hunt_crossley_force
from .hic import hic_kernel

NY = 9          # q1, q2, w1, w2, xh, yh, vxh, vyh, dissipated energy
# case columns
C_Q, C_QD, C_K, C_U, C_VH, C_FIXED = 0, 2, 4, 6, 8, 10
NCASE = 11
# head parameter vector
H_M, H_R, H_K, H_N, H_B = 0, 1, 2, 3, 4
# summary columns
SUMMARY_COLUMNS = ["F_max", "t_Fmax", "HIC36", "HIC36_t1", "HIC36_t2", "HIC15", "HIC15_t1",
                   "HIC15_t2", "delta_max", "a_max_g", "E_head_final", "E_dissipated",
                   "contact_time", "v_tcp0", "E_initial", "E_balance_error"]
NSUM = len(SUMMARY_COLUMNS)
HIST_COLUMNS = ["t", "F", "delta", "a_head_g", "dq1", "dq2", "v_head_n", "v_tcp_n", "E_total",
                "qd1", "qd2", "nx", "ny", "vhx", "vhy"]
NHIST = len(HIST_COLUMNS)


@leaf
def _arm_terms(y, P):
    """cos/sin of q2, inertia matrix entries and TCP kinematics at state ``y``."""
    c1, s1 = math.cos(y[0]), math.sin(y[0])
    c2, s2 = math.cos(y[1]), math.sin(y[1])
    c12, s12 = c1 * c2 - s1 * s2, s1 * c2 + c1 * s2
    h11, h12, h22 = mass_matrix_cs(c2, s2, P)
    x, yy, j11, j12, j21, j22 = tcp_kinematics_cs(c1, s1, c12, s12, P)
    return c2, s2, h11, h12, h22, x, yy, j11, j12, j21, j22


@leaf
def impact_rhs(y, case, P, hp, dy):
    """Derivative of the impact state; returns (F, delta, delta_dot, |tcp velocity|)."""
    c2, s2, h11, h12, h22, x, yy, j11, j12, j21, j22 = _arm_terms(y, P)
    w1, w2 = y[2], y[3]
    if case[C_FIXED] > 0.5:
        w1, w2 = 0.0, 0.0
    vx, vy = j11 * w1 + j12 * w2, j21 * w1 + j22 * w2
    dx, dyy = y[4] - x, y[5] - yy
    dist = math.sqrt(dx * dx + dyy * dyy)
    nx, ny = dx / dist, dyy / dist
    delta = hp[H_R] - dist
    ddelta = -(nx * (y[6] - vx) + ny * (y[7] - vy))
    f = hunt_crossley_force(delta, ddelta, hp[H_K], hp[H_N], hp[H_B])
    if case[C_FIXED] > 0.5:            # rigid, fixed arm: the tool point does not move
        dy[0], dy[1], dy[2], dy[3] = 0.0, 0.0, 0.0, 0.0
    else:
        dy[0], dy[1] = w1, w2
        c11, c12, c21, c22 = coriolis_cs(c2, s2, w1, w2, P)
        t1 = -case[C_K] * (y[0] - case[C_Q]) - (j11 * nx + j21 * ny) * f - c11 * w1 - c12 * w2
        t2 = -case[C_K + 1] * (y[1] - case[C_Q + 1]) - (j12 * nx + j22 * ny) * f \
            - c21 * w1 - c22 * w2
        det = h11 * h22 - h12 * h12
        dy[2] = (h22 * t1 - h12 * t2) / det
        dy[3] = (h11 * t2 - h12 * t1) / det
    dy[4], dy[5] = y[6], y[7]
    dy[6] = f * nx / hp[H_M]
    dy[7] = f * ny / hp[H_M]
    dy[8] = (f - hp[H_K] * max(delta, 0.0) ** hp[H_N]) * ddelta if delta > 0.0 else 0.0
    return f, delta, ddelta, math.sqrt(vx * vx + vy * vy)


@leaf
def _energy(y, case, P, hp):
    """Kinetic + spring + contact potential energy [J] (dissipation not included)."""
    _, _, h11, h12, h22, x, yy, _, _, _, _ = _arm_terms(y, P)
    w1, w2 = y[2], y[3]
    e = 0.5 * (h11 * w1 * w1 + 2.0 * h12 * w1 * w2 + h22 * w2 * w2)
    if case[C_FIXED] > 0.5:
        e = 0.0
    e += 0.5 * case[C_K] * (y[0] - case[C_Q]) ** 2 + 0.5 * case[C_K + 1] * (y[1] - case[C_Q + 1]) ** 2
    e += 0.5 * hp[H_M] * (y[6] * y[6] + y[7] * y[7])
    dx, dyy = y[4] - x, y[5] - yy
    delta = hp[H_R] - math.sqrt(dx * dx + dyy * dyy)
    if delta > 0.0:
        e += hp[H_K] * delta ** (hp[H_N] + 1.0) / (hp[H_N] + 1.0)
    return e


@leaf
def initial_state(case, P, hp, y):
    """Arm at q0 with qd0, head centre at r_tcp + R u, head velocity v_h0."""
    y[0], y[1] = case[C_Q], case[C_Q + 1]
    y[2], y[3] = case[C_QD], case[C_QD + 1]
    _, _, _, _, _, x, yy, _, _, _, _ = _arm_terms(y, P)
    y[4] = x + hp[H_R] * case[C_U]
    y[5] = yy + hp[H_R] * case[C_U + 1]
    y[6], y[7] = case[C_VH], case[C_VH + 1]
    y[8] = 0.0


@leaf
def _rk4(y, h, case, P, hp, k1, k2, k3, k4, yt):
    """One RK4 step of length h; ``k1`` must already hold the derivative at y."""
    for i in range(NY):
        yt[i] = y[i] + 0.5 * h * k1[i]
    impact_rhs(yt, case, P, hp, k2)
    for i in range(NY):
        yt[i] = y[i] + 0.5 * h * k2[i]
    impact_rhs(yt, case, P, hp, k3)
    for i in range(NY):
        yt[i] = y[i] + h * k3[i]
    impact_rhs(yt, case, P, hp, k4)
    for i in range(NY):
        y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


#: Free-flight steps are FREE_STRIDE times the contact step ...
FREE_STRIDE = 20
#: ... and are only taken while the gap exceeds this [m] plus twice the closing distance.
FREE_GAP = 5e-4


@kernel
def impact_batch(CASES, P, hp, dt, nsteps, w36, w15, SUM, HIST, hist_of):
    """Simulate every case; fill SUM (N, NSUM) and HIST[hist_of[c]] where hist_of[c] >= 0.

    While head and tool are apart and cannot touch within a long step (gap >
    FREE_GAP + 2 x closing speed x step), the integrator takes steps of
    FREE_STRIDE x dt (the force and head acceleration are exactly zero
    there); in contact, near contact and for recorded histories it uses dt.
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
        while True:
            f, delta, ddelta, vt = impact_rhs(y, case, P, hp, k1)
            if v0 < 0.0:
                v0 = vt
            acc[s] = f / (hp[H_M] * G0)
            if f > fmax:
                fmax, tmax = f, s * dt
            dmax = max(dmax, delta)
            if f > 0.0:
                tcont += dt
            if hrow >= 0:
                h = HIST[hrow, s]
                h[0], h[1], h[2], h[3] = s * dt, f, delta, acc[s]
                h[4], h[5] = y[0] - case[C_Q], y[1] - case[C_Q + 1]
                h[6] = y[6] * case[C_U] + y[7] * case[C_U + 1]
                _, _, _, _, _, x, yy, j11, j12, j21, j22 = _arm_terms(y, P)
                h[7] = ((j11 * y[2] + j12 * y[3]) * case[C_U]
                        + (j21 * y[2] + j22 * y[3]) * case[C_U + 1])
                h[8] = _energy(y, case, P, hp) + y[8]
                h[9], h[10] = y[2], y[3]
                dist = math.sqrt((y[4] - x) ** 2 + (y[5] - yy) ** 2)
                h[11], h[12] = (y[4] - x) / dist, (y[5] - yy) / dist
                h[13], h[14] = y[6], y[7]
            if s == nsteps:
                break
            m = FREE_STRIDE
            if (hrow < 0 and f == 0.0 and s + m <= nsteps
                    and -delta > FREE_GAP + 2.0 * max(ddelta, 0.0) * m * dt):
                _rk4(y, m * dt, case, P, hp, k1, k2, k3, k4, yt)
                for i in range(1, m):
                    acc[s + i] = 0.0
                s += m
            else:
                _rk4(y, dt, case, P, hp, k1, k2, k3, k4, yt)
                s += 1
        r = SUM[c]
        r[0], r[1] = fmax, tmax
        r[2], i1, i2 = hic_kernel(acc, dt, w36)
        r[3], r[4] = i1 * dt, i2 * dt
        if i2 - i1 > w15:      # else the HIC36 window is admissible for HIC15, so they are equal
            r[5], i1, i2 = hic_kernel(acc, dt, w15)
        else:
            r[5] = r[2]
        r[6], r[7] = i1 * dt, i2 * dt
        r[8], r[9] = dmax, fmax / (hp[H_M] * G0)
        r[10] = 0.5 * hp[H_M] * (y[6] * y[6] + y[7] * y[7])
        r[11] = y[8]
        r[12], r[13], r[14] = tcont, v0, e0
        r[15] = (_energy(y, case, P, hp) + y[8] - e0) / max(e0, 1e-300)
