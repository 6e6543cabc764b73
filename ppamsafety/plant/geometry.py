"""Arm geometry: attachment points, muscle lengths, lever arms, kinematics.

Implements thesis Appendix A: attachment points (A.13)-(A.22), muscle group
lengths (A.31)-(A.34), connection lengths (A.35)-(A.42), and the lever arm
of each group about its joint, (e_i x OA_i2) . 1_z as in (A.1)-(A.4).  Also
the forward kinematics and Jacobian of the tool centre point (TCP, end of
link 2) and the elbow-up inverse kinematics.

The low-level functions are ``numba.njit`` kernels working on scalars and the
packed parameter vector of :mod:`ppamsafety.plant.layout`; the public
functions accept arrays of configurations ``q`` with shape (..., 2) [rad]
and an :class:`~ppamsafety.params.ArmParameters`.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from .._jit import kernel, kernel_array, leaf
from .._validation import as_float_array
from . import layout as lay
from ._checks import accelerations, angles, check_pressures, checks_arm, speeds, torques  # noqa: F401
from .layout import (D12, D22, D32, D33, D42, D43, DL, L1, L2, L12, L22, L32, L33, L42, L43,
                     LL, X11, X21, Y11, Y21)


@leaf
def group_points(k, c1, s1, c12, s12, P):
    """Attachment points of muscle group ``k`` (0..3) and the pivot it turns.

    Returns ``(ax, ay, bx, by, px, py)``: the proximal point A (base for
    groups 1-2, upper arm for 3-4), the distal point B and the pivot P of the
    joint that moves B relative to A (O for groups 1-2, S for 3-4) [m].
    Eqs. (A.13)-(A.20); ``c1 = cos q1``, ``c12 = cos(q1 + q2)`` etc.

    Parameters
    ----------
    k : int
        Muscle group index 0..3 (thesis groups 1..4; 0, 1 act on joint 1,
        2, 3 on joint 2).  Any other value is treated as 3.
    c1, s1 : float
        cos q1 and sin q1 of the shoulder angle q1 [-].
    c12, s12 : float
        cos(q1 + q2) and sin(q1 + q2) [-].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads the geometry fields (``X11`` .. ``d43``, ``L1``) [m].
    """
    sx = P[L1] * c1
    sy = P[L1] * s1
    if k == 0:
        return (-P[X11], P[Y11], c1 * P[L12] - s1 * P[D12], s1 * P[L12] + c1 * P[D12], 0.0, 0.0)
    if k == 1:
        return (P[X21], -P[Y21], c1 * P[L22] + s1 * P[D22], s1 * P[L22] - c1 * P[D22], 0.0, 0.0)
    if k == 2:
        return (c1 * P[L32] - s1 * P[D32], s1 * P[L32] + c1 * P[D32],
                sx + c12 * P[L33] - s12 * P[D33], sy + s12 * P[L33] + c12 * P[D33], sx, sy)
    return (c1 * P[L42] + s1 * P[D42], s1 * P[L42] - c1 * P[D42],
            sx + c12 * P[L43] + s12 * P[D43], sy + s12 * P[L43] - c12 * P[D43], sx, sy)


@leaf
def group_length_lever(k, c1, s1, c12, s12, P):
    """Length d, lever arm h and dh/dq of muscle group ``k``.

    ``h = (e x r) . 1_z`` with ``e`` the unit vector from A to B and ``r`` the
    vector from the pivot to B: the torque about the joint per newton of
    muscle pull, (A.1)-(A.4).  By virtual work ``h = -dd/dq``; with
    ``d'' = (|r|^2 - u.r - d'^2)/d`` (u = B - A) we get ``dh/dq = -d''``.
    Units: m, m, m/rad.  The derivative is along the joint the group drives
    (q1 for groups 1-2, q2 for groups 3-4).

    Parameters
    ----------
    k : int
        Muscle group index 0..3 (thesis groups 1..4).
    c1, s1 : float
        cos q1 and sin q1 of the shoulder angle q1 [-].
    c12, s12 : float
        cos(q1 + q2) and sin(q1 + q2) [-].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads the geometry fields [m].
    """
    ax, ay, bx, by, px, py = group_points(k, c1, s1, c12, s12, P)
    ux = bx - ax
    uy = by - ay
    rx = bx - px
    ry = by - py
    d = math.sqrt(ux * ux + uy * uy)
    h = (ux * ry - uy * rx) / d
    dd = -h
    ddd = (rx * rx + ry * ry - (ux * rx + uy * ry) - dd * dd) / d
    return d, h, -ddd


@leaf
def tcp_kinematics_cs(c1, s1, c12, s12, P):
    """TCP position and Jacobian from cos/sin of q1 and q1 + q2.

    Returns ``(x, y, j11, j12, j21, j22)``: the TCP (end of link 2) position
    [m] and the entries of its Jacobian d(x, y)/d(q1, q2) [m/rad].

    Parameters
    ----------
    c1, s1 : float
        cos q1 and sin q1 of the shoulder angle q1 [-].
    c12, s12 : float
        cos(q1 + q2) and sin(q1 + q2) [-].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads the link lengths ``L1``, ``L2`` [m].
    """
    return (P[L1] * c1 + P[L2] * c12, P[L1] * s1 + P[L2] * s12,
            -P[L1] * s1 - P[L2] * s12, -P[L2] * s12, P[L1] * c1 + P[L2] * c12, P[L2] * c12)


@leaf
def tcp_position(q1, q2, P):
    """TCP (end of link 2) position (x, y) [m].

    Parameters
    ----------
    q1, q2 : float
        Joint angles (shoulder, elbow) [rad].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads the link lengths ``L1``, ``L2`` [m].
    """
    k = tcp_kinematics_cs(math.cos(q1), math.sin(q1), math.cos(q1 + q2), math.sin(q1 + q2), P)
    return k[0], k[1]


@leaf
def tcp_jacobian(q1, q2, P):
    """TCP Jacobian entries (j11, j12, j21, j22) [m/rad].

    Parameters
    ----------
    q1, q2 : float
        Joint angles (shoulder, elbow) [rad].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads the link lengths ``L1``, ``L2`` [m].
    """
    k = tcp_kinematics_cs(math.cos(q1), math.sin(q1), math.cos(q1 + q2), math.sin(q1 + q2), P)
    return k[2], k[3], k[4], k[5]


@leaf
def load_point(q1, q2, P):
    """Load point A_L (A.21): position (x, y) [m].

    Parameters
    ----------
    q1, q2 : float
        Joint angles (shoulder, elbow) [rad].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``L1``, ``LL`` and ``dL`` [m].
    """
    c1, s1 = math.cos(q1), math.sin(q1)
    c12, s12 = math.cos(q1 + q2), math.sin(q1 + q2)
    return (P[L1] * c1 + c12 * P[LL] + s12 * P[DL], P[L1] * s1 + s12 * P[LL] - c12 * P[DL])


@leaf
def inverse_kinematics_elbow_up(x, y, P):
    """Elbow-up (q2 < 0) inverse kinematics of the TCP: (q1, q2, reachable).

    Returns the joint angles [rad] and ``True``, or ``(0.0, 0.0, False)``
    when the point lies outside the annulus the two links can reach.

    Parameters
    ----------
    x, y : float
        Target TCP position in the base frame [m].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads the link lengths ``L1``, ``L2`` [m].
    """
    a, b = P[L1], P[L2]
    c2 = (x * x + y * y - a * a - b * b) / (2.0 * a * b)
    if c2 > 1.0 or c2 < -1.0:
        return 0.0, 0.0, False
    q2 = -math.acos(c2)
    q1 = math.atan2(y, x) - math.atan2(b * math.sin(q2), a + b * math.cos(q2))
    return q1, q2, True


@kernel
def _lengths_many(q, P, d, h, dh):
    for n in range(q.shape[0]):
        c1, s1 = math.cos(q[n, 0]), math.sin(q[n, 0])
        c12, s12 = math.cos(q[n, 0] + q[n, 1]), math.sin(q[n, 0] + q[n, 1])
        for k in range(4):
            d[n, k], h[n, k], dh[n, k] = group_length_lever(k, c1, s1, c12, s12, P)


@kernel
def _points_many(q, P, out):
    for n in range(q.shape[0]):
        c1, s1 = math.cos(q[n, 0]), math.sin(q[n, 0])
        c12, s12 = math.cos(q[n, 0] + q[n, 1]), math.sin(q[n, 0] + q[n, 1])
        for k in range(4):
            ax, ay, bx, by, _, _ = group_points(k, c1, s1, c12, s12, P)
            out[n, 2 * k, 0], out[n, 2 * k, 1] = ax, ay
            out[n, 2 * k + 1, 0], out[n, 2 * k + 1, 1] = bx, by


def _flat_q(q):
    q = angles("q", q)
    return kernel_array(q.reshape(-1, 2)), q.shape[:-1]


@checks_arm
def attachment_points(q, arm) -> np.ndarray:
    """Muscle attachment points for configurations ``q`` [rad], shape (..., 2).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi.
    arm : ArmParameters
        The arm.

    Returns
    -------
    numpy.ndarray, shape (..., 8, 2)
        Points in the order A11, A12, A21, A22, A32, A33, A42, A43 [m].
    """
    qf, lead = _flat_q(q)
    out = np.empty((qf.shape[0], 8, 2))
    _points_many(qf, kernel_array(geometry_row(arm.geometry, arm.muscles)), out)
    return out.reshape(lead + (8, 2))


@checks_arm
def muscle_lengths(q, arm, *, with_derivatives: bool = False):
    """Muscle group lengths d_i(q) (A.31)-(A.34) [m], shape (..., 4).

    With ``with_derivatives=True`` also returns the lever arms h_i = -dd_i/dq
    [m] and dh_i/dq [m/rad] (derivative with respect to the joint the group
    drives: q1 for groups 1-2, q2 for groups 3-4).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi.
    arm : ArmParameters
        The arm.
    with_derivatives : bool, keyword-only
        Also return the lever arms and their derivatives.
    """
    qf, lead = _flat_q(q)
    n = qf.shape[0]
    d, h, dh = np.empty((n, 4)), np.empty((n, 4)), np.empty((n, 4))
    _lengths_many(qf, kernel_array(geometry_row(arm.geometry, arm.muscles)), d, h, dh)
    shp = lead + (4,)
    if with_derivatives:
        return d.reshape(shp), h.reshape(shp), dh.reshape(shp)
    return d.reshape(shp)


@checks_arm
def lever_arms(q, arm) -> np.ndarray:
    """Lever arms (e_i x OA_i) . 1_z of the four groups [m], shape (..., 4).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi.
    arm : ArmParameters
        The arm.
    """
    return muscle_lengths(q, arm, with_derivatives=True)[1]


def design_connection_lengths(P, geometry, eps_min: float, eps_max: float) -> np.ndarray:
    """Connection lengths L_conn,i of (A.35)-(A.38) [m].

    Groups 1 and 3 reach ``eps_min`` at their longest length in the working
    area, groups 2 and 4 reach ``eps_max`` at their shortest.  The extremes
    (A.39)-(A.42) are found on a dense grid refined by a bounded scalar
    search.  Lengths of groups 1-2 depend on q1 only, of 3-4 on q2 only.

    Parameters
    ----------
    P : numpy.ndarray, shape (NP,)
        Plant row (layout ``PLANT`` of :mod:`ppamsafety.plant.layout`) with
        at least the geometry fields, ``n_muscles`` and ``l0`` set (the
        connection lengths themselves are not read).
    geometry : ArmGeometry
        The geometry packed in ``P``; its joint ranges q1_min .. q2_max
        [rad] bound the working area searched.
    eps_min, eps_max : float
        Smallest and largest contraction allowed in the working area [-]
        (``MuscleSet.eps_min``, ``eps_max``).

    Returns
    -------
    numpy.ndarray, shape (4,)
        L_conn of the four muscle groups [m].
    """
    from scipy.optimize import minimize_scalar

    g = geometry
    out = np.empty(4)
    for k, (lo, hi, sign, eps) in enumerate((
            (g.q1_min, g.q1_max, -1.0, eps_min), (g.q1_min, g.q1_max, 1.0, eps_max),
            (g.q2_min, g.q2_max, -1.0, eps_min), (g.q2_min, g.q2_max, 1.0, eps_max))):
        joint = 0 if k < 2 else 1
        other = 0.5 * (g.q2_min + g.q2_max) if joint == 0 else 0.5 * (g.q1_min + g.q1_max)

        def lengths(x, k=k, joint=joint, other=other):
            x = np.atleast_1d(np.asarray(x, dtype=float))
            q = np.empty((x.size, 2))
            q[:, joint], q[:, 1 - joint] = x, other
            d, h, dh = np.empty((x.size, 4)), np.empty((x.size, 4)), np.empty((x.size, 4))
            _lengths_many(q, kernel_array(P), d, h, dh)
            return sign * d[:, k]

        grid = np.linspace(lo, hi, 2001)
        vals = lengths(grid)
        j = int(np.argmin(vals))
        a, b = grid[max(j - 1, 0)], grid[min(j + 1, grid.size - 1)]
        res = minimize_scalar(lambda x: float(lengths(x)[0]), bounds=(a, b), method="bounded",
                              options={"xatol": 1e-12})
        extreme = min(vals[j], res.fun) * sign
        nm, l0 = P[lay.NM + k], P[lay.L0 + k]
        out[k] = extreme - nm * l0 * (1.0 - eps)
    return out


@lru_cache(maxsize=128)
def geometry_row(geometry, muscles=None) -> np.ndarray:
    """The plant row with the fields the kinematics kernels read; every other slot 0.

    The same values as in :func:`ppamsafety.plant.packing.pack`, so kinematics
    need no full packed row.

    Parameters
    ----------
    geometry : ArmGeometry
        Attachment points, link lengths and working area [m, rad].
    muscles : MuscleSet, optional
        With it, the row also holds ``n_muscles``, ``l0`` and the connection
        lengths of :func:`design_connection_lengths` (what the muscle-length and
        contraction kernels read).

    Returns
    -------
    numpy.ndarray, shape (NP,)
        Read-only row (layout :data:`~ppamsafety.plant.layout.PLANT`).
    """
    values = lay.geometry_values(geometry)
    if muscles is not None:
        groups = muscles.groups
        values.update(n_muscles=[g.n_muscles for g in groups], l0=[g.l0 for g in groups])
        P = lay.partial_row(values)
        P[lay.LCONN:lay.LCONN + 4] = design_connection_lengths(P, geometry, muscles.eps_min,
                                                               muscles.eps_max)
    else:
        P = lay.partial_row(values)
    P.setflags(write=False)
    return P


@checks_arm
def connection_lengths(arm) -> np.ndarray:
    """Connection lengths L_conn,i of the arm (Table A.1) [m], shape (4,).

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    """
    return np.array(geometry_row(arm.geometry, arm.muscles)[lay.LCONN:lay.LCONN + 4])


@checks_arm
def contractions(q, arm) -> np.ndarray:
    """Contraction of one muscle in each group, eq. (2.12), shape (..., 4) [-].

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi.
    arm : ArmParameters
        The arm.
    """
    P = geometry_row(arm.geometry, arm.muscles)
    d = muscle_lengths(q, arm)
    nm, l0, lc = P[lay.NM:lay.NM + 4], P[lay.L0:lay.L0 + 4], P[lay.LCONN:lay.LCONN + 4]
    return (lc + nm * l0 - d) / (nm * l0)


@kernel
def _fk_many(q, P, out, jac):
    for n in range(q.shape[0]):
        out[n, 0], out[n, 1] = tcp_position(q[n, 0], q[n, 1], P)
        jac[n, 0, 0], jac[n, 0, 1], jac[n, 1, 0], jac[n, 1, 1] = tcp_jacobian(q[n, 0], q[n, 1], P)


@checks_arm
def forward_kinematics(q, arm) -> np.ndarray:
    """TCP position for configurations ``q`` [rad], shape (..., 2) [m].

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi.
    arm : ArmParameters
        The arm.
    """
    qf, lead = _flat_q(q)
    out, jac = np.empty((qf.shape[0], 2)), np.empty((qf.shape[0], 2, 2))
    _fk_many(qf, kernel_array(geometry_row(arm.geometry, arm.muscles)), out, jac)
    return out.reshape(lead + (2,))


@checks_arm
def jacobian(q, arm) -> np.ndarray:
    """TCP Jacobian dr/dq for configurations ``q``, shape (..., 2, 2) [m/rad].

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi.
    arm : ArmParameters
        The arm.
    """
    qf, lead = _flat_q(q)
    out, jac = np.empty((qf.shape[0], 2)), np.empty((qf.shape[0], 2, 2))
    _fk_many(qf, kernel_array(geometry_row(arm.geometry, arm.muscles)), out, jac)
    return jac.reshape(lead + (2, 2))


@checks_arm
def inverse_kinematics(r, arm) -> np.ndarray:
    """Elbow-up (q2 < 0) inverse kinematics of the TCP.

    Parameters
    ----------
    r : array_like, shape (..., 2)
        TCP positions [m].
    arm : ArmParameters

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        Joint angles [rad] with q2 in (-pi, 0).

    Raises
    ------
    ValueError
        If a point is out of reach (|r| > L1 + L2 or < |L1 - L2|).
    """
    r = as_float_array("r", r, shape_tail=(2,))
    a, b = arm.geometry.L1, arm.geometry.L2
    x, y = r[..., 0], r[..., 1]
    c2 = (x ** 2 + y ** 2 - a ** 2 - b ** 2) / (2 * a * b)
    if np.any(np.abs(c2) > 1.0):
        raise ValueError("inverse_kinematics: a target point is out of reach of the arm "
                         f"(distance from O must be in [{abs(a - b):g}, {a + b:g}] m)")
    # the inverse trigonometric functions run in a compiled loop on the C library's scalar
    # functions: numpy's vectorised arccos/arctan2 differ in the last bit between CPUs
    # (AVX-512 has its own implementations), and a reference that depends on the CPU makes
    # a closed loop's log depend on it too
    q = np.empty(x.shape + (2,))
    _inverse_kinematics_many(np.ascontiguousarray(x, dtype=float).reshape(-1),
                             np.ascontiguousarray(y, dtype=float).reshape(-1),
                             np.ascontiguousarray(c2, dtype=float).reshape(-1), float(a),
                             float(b), q.reshape(-1, 2))
    return q


@kernel
def _inverse_kinematics_many(x, y, c2, a, b, q):
    """Elbow-up inverse kinematics of many reachable TCP positions ``x, y`` [m] with the
    elbow cosines ``c2`` into ``q`` (n, 2) [rad] (the arithmetic of
    :func:`inverse_kinematics`, with the C library's acos and atan2); ``a, b`` are the link
    lengths L1, L2 [m]."""
    for n in range(x.shape[0]):
        q2 = -math.acos(c2[n])
        q[n, 0] = math.atan2(y[n], x[n]) - math.atan2(b * math.sin(q2), a + b * math.cos(q2))
        q[n, 1] = q2


@checks_arm
def in_working_area(q, arm) -> np.ndarray:
    """True where q lies inside the working area (2.6)-(2.7).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi.
    arm : ArmParameters
        The arm.
    """
    q = as_float_array("q", q, shape_tail=(2,))
    g = arm.geometry
    return ((q[..., 0] >= g.q1_min) & (q[..., 0] <= g.q1_max)
            & (q[..., 1] >= g.q2_min) & (q[..., 1] <= g.q2_max))
