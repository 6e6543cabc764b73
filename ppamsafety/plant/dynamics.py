"""Rigid-body dynamics of the two links (thesis §3.2, Appendix B).

    H(q) qdd + C(q, qd) qd + G(q) + tau_f(qd) = tau            (3.1), (3.29)

written in the base parameters theta of (B.5), theta = [m1 L_G1 + m2 L1,
m1 d_G1, I_zO,1 + m2 L1^2, m2 L_G2, m2 d_G2, I_zS,2]::

    a   = L1 (theta4 cos q2 + theta5 sin q2)
    H   = [[theta3 + theta6 + 2a, theta6 + a], [theta6 + a, theta6]]
    hq  = L1 (theta4 sin q2 - theta5 cos q2)
    C   = [[-hq qd2, -hq (qd1 + qd2)], [hq qd1, 0]]            (Christoffel, B.1)
    G   = g [theta1 c1 + theta2 s1 + theta4 c12 + theta5 s12, theta4 c12 + theta5 s12]

Friction (3.30) is Coulomb + viscous; the plant uses a smooth Coulomb term
c tanh(qd / v_s) (see ``ArmParameters.friction_velocity``).  The regressor
:func:`regressor` implements (B.5)/(B.6) independently of these kernels so
the two can be tested against each other.
"""

from __future__ import annotations

import math

import numpy as np
from .._jit import kernel, leaf

from .._validation import as_float_array
from . import layout as lay
from .layout import COUL, GRAV, L1, TH, VFRIC, VISC


@leaf
def mass_matrix_cs(c2, s2, P):
    """Inertia matrix entries (h11, h12, h22) [kg m^2] from cos q2, sin q2."""
    a = P[L1] * (P[TH + 3] * c2 + P[TH + 4] * s2)
    return P[TH + 2] + P[TH + 5] + 2.0 * a, P[TH + 5] + a, P[TH + 5]


@leaf
def coriolis_cs(c2, s2, w1, w2, P):
    """Centrifugal/Coriolis matrix entries (c11, c12, c21, c22) [kg m^2/s]."""
    hq = P[L1] * (P[TH + 3] * s2 - P[TH + 4] * c2)
    return -hq * w2, -hq * (w1 + w2), hq * w1, 0.0


@leaf
def gravity_cs(c1, s1, c12, s12, P):
    """Gravity torques (g1, g2) [N m] from cos/sin of q1 and q1 + q2."""
    g = P[GRAV]
    g2 = g * (P[TH + 3] * c12 + P[TH + 4] * s12)
    return g * (P[TH] * c1 + P[TH + 1] * s1) + g2, g2


@leaf
def gravity_torque(q1, q2, P):
    """Gravity torques (g1, g2) [N m]."""
    return gravity_cs(math.cos(q1), math.sin(q1), math.cos(q1 + q2), math.sin(q1 + q2), P)


@leaf
def friction_torque(w1, w2, P):
    """Joint friction (smooth Coulomb + viscous) [N m]."""
    vs = P[VFRIC]
    return (P[COUL] * math.tanh(w1 / vs) + P[VISC] * w1,
            P[COUL + 1] * math.tanh(w2 / vs) + P[VISC + 1] * w2)


@leaf
def forward_dynamics_cs(c1, s1, c2, s2, c12, s12, w1, w2, tau1, tau2, P):
    """Joint accelerations (qdd1, qdd2) [rad/s^2] for joint torques tau [N m]."""
    h11, h12, h22 = mass_matrix_cs(c2, s2, P)
    c11, c12_, c21, c22 = coriolis_cs(c2, s2, w1, w2, P)
    g1, g2 = gravity_cs(c1, s1, c12, s12, P)
    f1, f2 = friction_torque(w1, w2, P)
    r1 = tau1 - c11 * w1 - c12_ * w2 - g1 - f1
    r2 = tau2 - c21 * w1 - c22 * w2 - g2 - f2
    det = h11 * h22 - h12 * h12
    return (h22 * r1 - h12 * r2) / det, (h11 * r2 - h12 * r1) / det


@leaf
def forward_dynamics(q1, q2, w1, w2, tau1, tau2, P):
    """Joint accelerations (qdd1, qdd2) [rad/s^2] for joint torques tau [N m]."""
    return forward_dynamics_cs(math.cos(q1), math.sin(q1), math.cos(q2), math.sin(q2),
                               math.cos(q1 + q2), math.sin(q1 + q2), w1, w2, tau1, tau2, P)


def _params_vector(arm, params):
    return lay.pack(arm) if params is None else lay.pack(arm, params)


def inertia_matrix(q, arm, *, params=None) -> np.ndarray:
    """H(q) [kg m^2], shape (..., 2, 2).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad].
    arm : ArmParameters
    params : BaseParameters, optional
        Rigid-body parameters; default the physical plant.
    """
    q = as_float_array("q", q, shape_tail=(2,))
    P = _params_vector(arm, params)
    a = P[L1] * (P[TH + 3] * np.cos(q[..., 1]) + P[TH + 4] * np.sin(q[..., 1]))
    H = np.empty(q.shape[:-1] + (2, 2))
    H[..., 0, 0] = P[TH + 2] + P[TH + 5] + 2 * a
    H[..., 0, 1] = H[..., 1, 0] = P[TH + 5] + a
    H[..., 1, 1] = P[TH + 5]
    return H


def coriolis(q, qd, arm, *, params=None) -> np.ndarray:
    """C(q, qd) [kg m^2/s], shape (..., 2, 2) (Christoffel form, so Hdot - 2C is skew)."""
    q = as_float_array("q", q, shape_tail=(2,))
    qd = as_float_array("qd", qd, shape_tail=(2,))
    P = _params_vector(arm, params)
    hq = P[L1] * (P[TH + 3] * np.sin(q[..., 1]) - P[TH + 4] * np.cos(q[..., 1]))
    C = np.zeros(np.broadcast_shapes(q.shape, qd.shape)[:-1] + (2, 2))
    C[..., 0, 0] = -hq * qd[..., 1]
    C[..., 0, 1] = -hq * (qd[..., 0] + qd[..., 1])
    C[..., 1, 0] = hq * qd[..., 0]
    return C


def gravity(q, arm, *, params=None) -> np.ndarray:
    """G(q) [N m], shape (..., 2)."""
    q = as_float_array("q", q, shape_tail=(2,))
    P = _params_vector(arm, params)
    g = P[GRAV]
    c12, s12 = np.cos(q[..., 0] + q[..., 1]), np.sin(q[..., 0] + q[..., 1])
    g2 = g * (P[TH + 3] * c12 + P[TH + 4] * s12)
    g1 = g * (P[TH] * np.cos(q[..., 0]) + P[TH + 1] * np.sin(q[..., 0])) + g2
    return np.stack([g1, g2], axis=-1)


def friction(qd, arm, *, params=None, smooth: bool = True) -> np.ndarray:
    """Joint friction (3.30) [N m]; ``smooth=False`` uses the ideal sign function."""
    qd = as_float_array("qd", qd, shape_tail=(2,))
    P = _params_vector(arm, params)
    c, b = P[COUL:COUL + 2], P[VISC:VISC + 2]
    s = np.tanh(qd / P[VFRIC]) if smooth else np.sign(qd)
    return c * s + b * qd


def regressor(q, qd, qdd, arm, *, gravity_acc: float | None = None) -> np.ndarray:
    """Observation matrix K(q, qd, qdd) of (B.5) extended with friction (B.6).

    K @ [theta1..theta6, c1, c2, b1, b2] = H qdd + C qd + G + c sgn(qd) + b qd.

    Returns
    -------
    numpy.ndarray, shape (..., 2, 10)
    """
    q = as_float_array("q", q, shape_tail=(2,))
    qd = as_float_array("qd", qd, shape_tail=(2,))
    qdd = as_float_array("qdd", qdd, shape_tail=(2,))
    g = arm.gravity if gravity_acc is None else gravity_acc
    l1 = arm.geometry.L1
    q1, q2 = q[..., 0], q[..., 1]
    w1, w2 = qd[..., 0], qd[..., 1]
    a1, a2 = qdd[..., 0], qdd[..., 1]
    c1, s1, c2, s2 = np.cos(q1), np.sin(q1), np.cos(q2), np.sin(q2)
    c12, s12 = np.cos(q1 + q2), np.sin(q1 + q2)
    shape = np.broadcast_shapes(q1.shape, w1.shape, a1.shape)
    K = np.zeros(shape + (2, 10))
    K[..., 0, 0] = g * c1
    K[..., 0, 1] = g * s1
    K[..., 0, 2] = a1
    K[..., 0, 3] = g * c12 + (2 * a1 + a2) * c2 * l1 - w2 * (2 * w1 + w2) * s2 * l1
    K[..., 0, 4] = g * s12 + w2 * (2 * w1 + w2) * c2 * l1 + (2 * a1 + a2) * s2 * l1
    K[..., 0, 5] = a1 + a2
    K[..., 1, 3] = g * c12 + a1 * c2 * l1 + w1 ** 2 * s2 * l1
    K[..., 1, 4] = g * s12 - w1 ** 2 * c2 * l1 + a1 * s2 * l1
    K[..., 1, 5] = a1 + a2
    K[..., 0, 6] = np.sign(w1)
    K[..., 1, 7] = np.sign(w2)
    K[..., 0, 8] = w1
    K[..., 1, 9] = w2
    return K


def kinetic_energy(q, qd, arm, *, params=None) -> np.ndarray:
    """Kinetic energy 1/2 qd^T H qd [J]."""
    qd = as_float_array("qd", qd, shape_tail=(2,))
    H = inertia_matrix(q, arm, params=params)
    return 0.5 * np.einsum("...i,...ij,...j->...", qd, H, qd)


def potential_energy(q, arm, *, params=None) -> np.ndarray:
    """Gravitational potential energy (B.1) up to a constant [J].

    In base parameters: P = g (theta1 s1 - theta2 c1 + theta4 s12 - theta5 c12),
    so that dP/dq = G.
    """
    q = as_float_array("q", q, shape_tail=(2,))
    P = _params_vector(arm, params)
    q1, q12 = q[..., 0], q[..., 0] + q[..., 1]
    return P[GRAV] * (P[TH] * np.sin(q1) - P[TH + 1] * np.cos(q1)
                      + P[TH + 3] * np.sin(q12) - P[TH + 4] * np.cos(q12))
