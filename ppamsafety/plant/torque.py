"""Torque functions m_tau,i(q) (2.10), joint torques (2.17) and group volumes.

The torque function of group i is its torque per unit gauge pressure::

    m_tau,i(q) = f_i(eps_i(q)) * h_i(q)          [N m / Pa = m^3]

with f_i the force law (3.9) and h_i = (e_i x OA_i) . 1_z the lever arm
(A.1)-(A.4).  Joint torques are tau = [p1 m1 + p2 m2, p3 m3 + p4 m4] (2.17).
Because dV_group/dq = n_m l0 f de/dq = f h, the torque function is also the
volume derivative: dV_group,i/dq = m_tau,i (virtual work).

The kernel :func:`torque_kernel` returns in one pass everything the plant
needs: m_tau, its derivative along the driven joint, and the group volumes.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel, kernel_array, leaf, step_kernel
from . import packing
from ._checks import accelerations, angles, check_pressures, checks_arm, speeds, torques  # noqa: F401
from .geometry import _flat_q, group_length_lever
from .layout import L0, LCONN, NM
from .muscle import dforce_deps, force_per_pressure, muscle_volume


@step_kernel
def torque_kernel(q1, q2, P, mt, dmt, vol):
    """:func:`torque_kernel_cs` for angles ``q1``, ``q2`` [rad].

    Parameters
    ----------
    q1, q2 : float
        Joint angles (shoulder, elbow) [rad].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`).
    mt, dmt, vol : ndarray of float64, shape (4,)
        Outputs, overwritten, indexed by group 0..3: torque functions
        m_tau [m^3], their derivatives along the driven joint [m^3/rad] and
        group volumes [m^3], as in :func:`torque_kernel_cs`.
    """
    torque_kernel_cs(math.cos(q1), math.sin(q1), math.cos(q1 + q2), math.sin(q1 + q2),
                     P, mt, dmt, vol)


@leaf
def torque_kernel_cs(c1, s1, c12, s12, P, mt, dmt, vol):
    """Fill m_tau (4) [m^3], d m_tau/dq (4) [m^3/rad] and group volumes (4) [m^3].

    The derivative is along the driven joint (q1 for groups 1-2, q2 for
    groups 3-4):  d m_tau/dq = f'(eps) h^2/(n_m l0) + f dh/dq, using
    d eps/dq = h/(n_m l0).

    Parameters
    ----------
    c1, s1 : float
        cos q1 and sin q1 of the shoulder angle q1 [-].
    c12, s12 : float
        cos(q1 + q2) and sin(q1 + q2) [-].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads the geometry, ``lconn``, ``n_muscles``, ``l0``, ``coef``,
        ``eps_f0`` and ``v_c`` fields.
    mt : ndarray of float64, shape (4,)
        Output, overwritten: torque functions m_tau,i = f_i h_i of (2.10) per
        group 0..3 [N m/Pa = m^3].
    dmt : ndarray of float64, shape (4,)
        Output, overwritten: d m_tau,i/dq along the driven joint [m^3/rad].
    vol : ndarray of float64, shape (4,)
        Output, overwritten: group volumes n_m V(eps) [m^3].
    """
    for k in range(4):
        mt[k], dmt[k], vol[k], _ = group_terms(k, c1, s1, c12, s12, P)


@step_kernel
def torque_functions_cs(c1, s1, c12, s12, P, mt):
    """Fill m_tau (4) [m^3] only: :func:`torque_kernel_cs` without the derivatives and volumes.

    The same arithmetic as :func:`group_terms` (bitwise the same m_tau); what a caller
    does not use is left out by the compiler (no logarithm of the volume, no
    derivative of the force law).  Compiled once (not inlined into its callers: the
    gravity compensation, the task PSMC and the SMC model), which keeps their first
    compilation short.

    Parameters
    ----------
    c1, s1 : float
        cos q1 and sin q1 of the shoulder angle q1 [-].
    c12, s12 : float
        cos(q1 + q2) and sin(q1 + q2) [-].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`).
    mt : ndarray of float64, shape (4,)
        Output, overwritten: torque functions m_tau,i of (2.10) per group 0..3 [m^3].
    """
    for k in range(4):
        mt[k] = group_terms(k, c1, s1, c12, s12, P)[0]


@leaf
def group_contraction(k, c1, s1, c12, s12, P):
    """Contraction eps of muscle group ``k`` (dimensionless), from cos/sin of q1, q1 + q2.

    The same arithmetic as :func:`group_terms` (so bitwise the contraction
    the torque kernels use).

    Parameters
    ----------
    k : int
        Muscle group 0..3.
    c1, s1, c12, s12 : float
        cos/sin of q1 and of q1 + q2.
    P : float64[:]
        Plant row.
    """
    d, _, _ = group_length_lever(k, c1, s1, c12, s12, P)
    nl = P[NM + k] * P[L0 + k]
    return (P[LCONN + k] + nl - d) / nl


@leaf
def group_terms(k, c1, s1, c12, s12, P):
    """(m_tau [m^3], d m_tau/dq [m^3/rad], group volume [m^3], contraction eps [-]) of group ``k``.

    One group's share of :func:`torque_kernel_cs`; the contraction is what
    the plant's force hysteresis (3.35) needs.

    Parameters
    ----------
    k : int
        Muscle group 0..3.
    c1, s1, c12, s12 : float
        cos/sin of q1 and of q1 + q2.
    P : float64[:]
        Plant row.
    """
    d, h, dh = group_length_lever(k, c1, s1, c12, s12, P)
    nl = P[NM + k] * P[L0 + k]
    eps = (P[LCONN + k] + nl - d) / nl
    f = force_per_pressure(k, eps, P)
    return (f * h, dforce_deps(k, eps, P) * h * h / nl + f * dh,
            P[NM + k] * muscle_volume(k, eps, P), eps)


@kernel
def _many(q, P, mt, dmt, vol):
    for n in range(q.shape[0]):
        torque_kernel(q[n, 0], q[n, 1], P, mt[n], dmt[n], vol[n])


def _eval(q, P):
    qf, lead = _flat_q(q)
    n = qf.shape[0]
    mt, dmt, vol = np.empty((n, 4)), np.empty((n, 4)), np.empty((n, 4))
    _many(qf, kernel_array(P), mt, dmt, vol)
    shp = lead + (4,)
    return mt.reshape(shp), dmt.reshape(shp), vol.reshape(shp)


@checks_arm
def torque_functions(q, arm, *, with_derivative: bool = False):
    """Torque functions m_tau,i(q) [N m/Pa], shape (..., 4).

    Multiply by 1e5 for the thesis' Nm/bar (fig. 2.11).  With
    ``with_derivative=True`` also returns d m_tau,i/dq along the driven joint.

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi.
    arm : ArmParameters
        The arm.
    with_derivative : bool, keyword-only
        Also return d m_tau,i/dq [N m/(Pa rad)].
    """
    mt, dmt, _ = _eval(q, packing.pack(arm))
    return (mt, dmt) if with_derivative else mt


@checks_arm
def group_volumes(q, arm) -> np.ndarray:
    """Volumes of the four muscle groups at configuration ``q`` [m^3], shape (..., 4).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi.
    arm : ArmParameters
        The arm.
    """
    return _eval(q, packing.pack(arm))[2]


@checks_arm
def joint_torques(q, pressures, arm) -> np.ndarray:
    """Actuator torques (2.17) [N m] for gauge pressures ``pressures`` [Pa] (..., 4).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi.
    pressures : array_like, shape (..., 4)
        Gauge pressures [Pa] in [-1 atm, 100 bar].
    arm : ArmParameters
        The arm.
    """
    p = check_pressures("pressures", pressures)
    mt = torque_functions(q, arm)
    tau = mt * p
    return np.stack([tau[..., 0] + tau[..., 1], tau[..., 2] + tau[..., 3]], axis=-1)
