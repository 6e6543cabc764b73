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
c tanh(qd / v_s) (see ``ArmParameters.friction_velocity``).  Which
coefficients: the plant-truth row (``packing.pack(arm)``) holds
``arm.links.coulomb/viscous`` (by default the identified Table 3.5 values, so
nominally truth = belief) unless ``arm.effects.friction_coulomb/viscous``
override them; the controllers' rows hold ``arm.model`` (Table 3.5) or
``arm.model_gravity`` friction and never see the override.

Each formula exists once, as a compiled leaf (``mass_matrix_cs``,
``coriolis_cs``, ``gravity_cs``, ``friction_cs``, ``potential_cs``); the
NumPy-level functions (:func:`inertia_matrix`, :func:`coriolis`,
:func:`gravity`, :func:`friction`, :func:`potential_energy`) evaluate those
same leaves in a batched kernel over the configurations.  The exception is
:func:`regressor`, which implements (B.5)/(B.6) deliberately independently
of the kernels, as the test oracle they are checked against.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel, kernel_array, leaf
from .._validation import as_float_array, check_bool, check_range  # noqa: F401
from . import packing
from ._checks import accelerations, angles, check_pressures, checks_arm, speeds, torques  # noqa: F401
from .layout import COUL, GRAV, L1, THETA1, THETA2, THETA3, THETA4, THETA5, THETA6, VFRIC, VISC


@leaf
def mass_matrix_cs(c2, s2, P):
    """Inertia matrix entries (h11, h12, h22) [kg m^2] from cos q2, sin q2.

    H of (3.1) in the base parameters (B.5); symmetric, so h21 = h12.

    Parameters
    ----------
    c2, s2 : float
        cos q2 and sin q2 of the elbow angle q2 [-].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``L1`` [m] and ``theta``.
    """
    a = P[L1] * (P[THETA4] * c2 + P[THETA5] * s2)
    return P[THETA3] + P[THETA6] + 2.0 * a, P[THETA6] + a, P[THETA6]


@leaf
def coriolis_cs(c2, s2, w1, w2, P):
    """Centrifugal/Coriolis matrix entries (c11, c12, c21, c22) [kg m^2/s].

    C(q, qd) of (3.1) from the Christoffel symbols (B.1); C qd is the
    centrifugal/Coriolis torque [N m].

    Parameters
    ----------
    c2, s2 : float
        cos q2 and sin q2 of the elbow angle q2 [-].
    w1, w2 : float
        Joint velocities qd1, qd2 [rad/s].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``L1`` [m] and ``theta``.
    """
    hq = P[L1] * (P[THETA4] * s2 - P[THETA5] * c2)
    return -hq * w2, -hq * (w1 + w2), hq * w1, 0.0


@leaf
def gravity_cs(c1, s1, c12, s12, P):
    """Gravity torques (g1, g2) [N m] from cos/sin of q1 and q1 + q2.

    G(q) of (3.1) in the base parameters (B.5).

    Parameters
    ----------
    c1, s1 : float
        cos q1 and sin q1 of the shoulder angle q1 [-].
    c12, s12 : float
        cos(q1 + q2) and sin(q1 + q2) [-].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``gravity`` [m/s^2] and ``theta``.
    """
    g = P[GRAV]
    g2 = g * (P[THETA4] * c12 + P[THETA5] * s12)
    return g * (P[THETA1] * c1 + P[THETA2] * s1) + g2, g2


@leaf
def potential_cs(c1, s1, c12, s12, P):
    """Gravitational potential energy (B.1) up to a constant [J]; its gradient is G.

    In base parameters: U = g (theta1 s1 - theta2 c1 + theta4 s12 - theta5 c12).

    Parameters
    ----------
    c1, s1 : float
        cos q1 and sin q1 of the shoulder angle q1 [-].
    c12, s12 : float
        cos(q1 + q2) and sin(q1 + q2) [-].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``gravity`` [m/s^2] and ``theta``.
    """
    return P[GRAV] * (P[THETA1] * s1 - P[THETA2] * c1 + P[THETA4] * s12 - P[THETA5] * c12)


@leaf
def gravity_torque(q1, q2, P):
    """Gravity torques (g1, g2) [N m].

    Parameters
    ----------
    q1, q2 : float
        Joint angles (shoulder, elbow) [rad].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``gravity`` [m/s^2] and ``theta``.
    """
    return gravity_cs(math.cos(q1), math.sin(q1), math.cos(q1 + q2), math.sin(q1 + q2), P)


@leaf
def _sign(w):
    return 1.0 if w > 0.0 else (-1.0 if w < 0.0 else 0.0)


@leaf
def friction_cs(w1, w2, smooth, P):
    """Joint friction (3.30) [N m]: Coulomb c s(qd) + viscous b qd.

    ``smooth=True``: s = tanh(qd / v_s) (the plant); ``False``: the ideal
    sign function.

    Parameters
    ----------
    w1, w2 : float
        Joint velocities qd1, qd2 [rad/s].
    smooth : bool
        Smooth Coulomb term tanh(qd / v_s) if true, sign(qd) if false.
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``coulomb`` [N m], ``viscous`` [N m s/rad] and
        ``v_friction`` [rad/s].
    """
    if smooth:
        vs = P[VFRIC]
        s1 = math.tanh(w1 / vs)
        s2 = math.tanh(w2 / vs)
    else:
        s1 = _sign(w1)
        s2 = _sign(w2)
    return P[COUL] * s1 + P[VISC] * w1, P[COUL + 1] * s2 + P[VISC + 1] * w2


@leaf
def friction_torque(w1, w2, P):
    """Joint friction (smooth Coulomb + viscous) [N m].

    :func:`friction_cs` with ``smooth=True``.

    Parameters
    ----------
    w1, w2 : float
        Joint velocities qd1, qd2 [rad/s].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``coulomb``, ``viscous`` and ``v_friction``.
    """
    return friction_cs(w1, w2, True, P)


@leaf
def forward_dynamics_cs(c1, s1, c2, s2, c12, s12, w1, w2, tau1, tau2, P):
    """Joint accelerations (qdd1, qdd2) [rad/s^2] for joint torques tau [N m].

    Solves H qdd = tau - C qd - G - tau_f of (3.1)/(3.29) with the smooth
    friction of :func:`friction_torque`.

    Parameters
    ----------
    c1, s1 : float
        cos q1 and sin q1 of the shoulder angle q1 [-].
    c2, s2 : float
        cos q2 and sin q2 of the elbow angle q2 [-].
    c12, s12 : float
        cos(q1 + q2) and sin(q1 + q2) [-].
    w1, w2 : float
        Joint velocities qd1, qd2 [rad/s].
    tau1, tau2 : float
        Joint torques [N m].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``L1``, ``theta``, ``gravity`` and the friction fields.
    """
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
    """Joint accelerations (qdd1, qdd2) [rad/s^2] for joint torques tau [N m].

    :func:`forward_dynamics_cs` for angles ``q1``, ``q2``.

    Parameters
    ----------
    q1, q2 : float
        Joint angles (shoulder, elbow) [rad].
    w1, w2 : float
        Joint velocities qd1, qd2 [rad/s].
    tau1, tau2 : float
        Joint torques [N m].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``L1``, ``theta``, ``gravity`` and the friction fields.
    """
    return forward_dynamics_cs(math.cos(q1), math.sin(q1), math.cos(q2), math.sin(q2),
                               math.cos(q1 + q2), math.sin(q1 + q2), w1, w2, tau1, tau2, P)


def _params_vector(arm, params):
    return packing.pack(arm) if params is None else packing.pack(arm, params)


@kernel
def _dyn_many(kind, q, qd, P, out):
    """Batched evaluation of the leaves above (kind 0 H, 1 C, 2 G, 3/4 friction, 5 U)."""
    for n in range(q.shape[0]):
        c1, s1 = math.cos(q[n, 0]), math.sin(q[n, 0])
        c2, s2 = math.cos(q[n, 1]), math.sin(q[n, 1])
        c12, s12 = math.cos(q[n, 0] + q[n, 1]), math.sin(q[n, 0] + q[n, 1])
        o = out[n]
        if kind == 0:
            o[0], o[1], o[3] = mass_matrix_cs(c2, s2, P)
            o[2] = o[1]
        elif kind == 1:
            o[0], o[1], o[2], o[3] = coriolis_cs(c2, s2, qd[n, 0], qd[n, 1], P)
        elif kind == 2:
            o[0], o[1] = gravity_cs(c1, s1, c12, s12, P)
        elif kind == 3 or kind == 4:
            o[0], o[1] = friction_cs(qd[n, 0], qd[n, 1], kind == 3, P)
        else:
            o[0] = potential_cs(c1, s1, c12, s12, P)


_WIDTH = (4, 4, 2, 2, 2, 1)


def _evaluate(kind, q, qd, arm, params):
    """Broadcast q, qd (..., 2), run :func:`_dyn_many`; returns (out (n, w), lead shape)."""
    lead = np.broadcast_shapes(q.shape[:-1], qd.shape[:-1])
    qf = np.ascontiguousarray(np.broadcast_to(q, lead + (2,)).reshape(-1, 2))
    qdf = np.ascontiguousarray(np.broadcast_to(qd, lead + (2,)).reshape(-1, 2))
    out = np.empty((qf.shape[0], _WIDTH[kind]))
    _dyn_many(kind, kernel_array(qf), kernel_array(qdf), kernel_array(_params_vector(arm, params)),
              out)
    return out, lead


_NO_Q = np.zeros(2)


@checks_arm
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
    q = angles("q", q)
    out, lead = _evaluate(0, q, _NO_Q, arm, params)
    return out.reshape(lead + (2, 2))


@checks_arm
def coriolis(q, qd, arm, *, params=None) -> np.ndarray:
    """C(q, qd) [kg m^2/s], shape (..., 2, 2) (Christoffel form, so Hdot - 2C is skew).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad].
    qd : array_like, shape (..., 2)
        Joint velocities [rad/s] (broadcast against ``q``).
    arm : ArmParameters
    params : BaseParameters, optional
        Rigid-body parameters; default the physical plant.
    """
    q = angles("q", q)
    qd = speeds("qd", qd)
    out, lead = _evaluate(1, q, qd, arm, params)
    return out.reshape(lead + (2, 2))


@checks_arm
def gravity(q, arm, *, params=None) -> np.ndarray:
    """G(q) [N m], shape (..., 2).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad].
    arm : ArmParameters
    params : BaseParameters, optional
        Rigid-body parameters; default the physical plant.
    """
    q = angles("q", q)
    out, lead = _evaluate(2, q, _NO_Q, arm, params)
    return out.reshape(lead + (2,))


@checks_arm
def friction(qd, arm, *, params=None, smooth: bool = True) -> np.ndarray:
    """Joint friction (3.30) [N m], shape (..., 2).

    Parameters
    ----------
    qd : array_like, shape (..., 2)
        Joint velocities [rad/s].
    arm : ArmParameters
    params : BaseParameters, optional
        Rigid-body parameters; default the physical plant.
    smooth : bool, keyword-only
        True (default): smooth Coulomb term c tanh(qd / v_s) as in the plant;
        False: the ideal sign function of (3.30).
    """
    qd = speeds("qd", qd)
    smooth = check_bool("smooth", smooth)
    out, lead = _evaluate(3 if smooth else 4, _NO_Q, qd, arm, params)
    return out.reshape(lead + (2,))


@checks_arm
def regressor(q, qd, qdd, arm, *, gravity_acc: float | None = None) -> np.ndarray:
    """Observation matrix K(q, qd, qdd) of (B.5) extended with friction (B.6).

    K @ [theta1..theta6, c1, c2, b1, b2] = H qdd + C qd + G + c sgn(qd) + b qd.

    Written out from (B.5)/(B.6) in NumPy, deliberately independent of the
    compiled leaves (``mass_matrix_cs`` ...): it is the test oracle those
    kernels are checked against (``tests/test_dynamics.py``), so do not
    rewrite it in terms of them.

    Parameters
    ----------
    q, qd, qdd : array_like, shape (..., 2)
        Joint angles [rad], velocities [rad/s], accelerations [rad/s^2].
    arm : ArmParameters
        Supplies L1 and the gravitational acceleration.
    gravity_acc : float, optional
        Gravitational acceleration [m/s^2]; default ``arm.gravity``.

    Returns
    -------
    numpy.ndarray, shape (..., 2, 10)
    """
    q = angles("q", q)
    qd = speeds("qd", qd)
    qdd = accelerations("qdd", qdd)
    g = arm.gravity if gravity_acc is None else check_range("gravity_acc", gravity_acc, 0.0, 100.0,
                                                            unit="m/s^2")
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


@checks_arm
def kinetic_energy(q, qd, arm, *, params=None) -> np.ndarray:
    """Kinetic energy 1/2 qd^T H qd [J].

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad].
    qd : array_like, shape (..., 2)
        Joint velocities [rad/s], |qd| <= 1000.
    arm : ArmParameters
        The arm.
    params : BaseParameters, optional
        Rigid-body parameters; default the physical plant.
    """
    qd = speeds("qd", qd)
    H = inertia_matrix(q, arm, params=params)
    return 0.5 * np.einsum("...i,...ij,...j->...", qd, H, qd)


@checks_arm
def potential_energy(q, arm, *, params=None) -> np.ndarray:
    """Gravitational potential energy (B.1) up to a constant [J], shape (...).

    In base parameters: U = g (theta1 s1 - theta2 c1 + theta4 s12 - theta5 c12),
    so that dU/dq = G.

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad].
    arm : ArmParameters
    params : BaseParameters, optional
        Rigid-body parameters; default the physical plant.
    """
    q = angles("q", q)
    out, lead = _evaluate(5, q, _NO_Q, arm, params)
    return out.reshape(lead)
