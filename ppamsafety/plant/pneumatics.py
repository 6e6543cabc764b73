"""Valves, pressure dynamics, the Delta-p approach and joint stiffness.

* Valve (3.2) with static error (3.12): the delivered pressure settles at
  v1 + v2 p_s for a set value p_s, with first-order time constant T.
* Polytropic volume coupling (3.3)-(3.6), n = 1.4, P_atm::

      dp_i/dt = (v1_i + v2_i p_s,i - p_i)/T_i - n (P_atm + p_i)/V_i dV_i/dq qd

  with dV_i/dq = m_tau,i (see :mod:`ppamsafety.plant.torque`).
* Delta-p approach (3.7): p_1,3 = p_m + Delta p, p_2,4 = p_m - Delta p.
* Static gravity compensation (3.18)-(3.19).
* Joint stiffness (2.18) including dp/dq of (3.4): the stiffness a fast
  disturbance feels before the valves react::

      K_j = sum_i [ n (P_atm + p_i) m_tau,i^2 / V_i - p_i d m_tau,i/dq_j ]
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel, step_kernel, kernel_array, leaf
from .._validation import as_float_array, check_range, check_range_array
from ..units import DEG
from . import packing
from ._checks import (PRESSURE_MAX, accelerations, angles, check_pressures,  # noqa: F401
                      checks_arm, speeds, torques)
from .dynamics import gravity_cs
from .layout import NPOLY, PATM, PM1, PM2, PMAX, TV, V1, V2, TORQUE_BIAS, TORQUE_BIAS_MODE, Switch
from .torque import torque_functions_cs, torque_kernel


@leaf
def pressure_rates(p, u, qd1, qd2, mt, vol, P, out):
    """Gauge-pressure derivatives of (3.6) with the static valve model [Pa/s].

    dp_i/dt = (v1_i + v2_i u_i - p_i)/T_i - n (P_atm + p_i) m_tau,i qd_j / V_i,
    with j the joint group i drives.

    Parameters
    ----------
    p : ndarray of float64, shape (4,)
        Gauge pressures of the four groups [Pa].
    u : ndarray of float64, shape (4,)
        Valve set values of the four groups [Pa].
    qd1, qd2 : float
        Joint velocities (shoulder, elbow) [rad/s].
    mt : ndarray of float64, shape (4,)
        Torque functions m_tau,i = dV_i/dq [m^3], from
        :func:`~ppamsafety.plant.torque.torque_kernel`.
    vol : ndarray of float64, shape (4,)
        Group volumes V_i [m^3], from the same kernel.
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``n_poly``, ``p_atm``, ``v1``, ``v2`` and ``tv``.
    out : ndarray of float64, shape (4,)
        Output, overwritten: dp_i/dt [Pa/s].
    """
    pressure_rates_at(p, 0, u, qd1, qd2, mt, 0, vol, 0, P, out, 0)


@leaf
def pressure_rates_at(p, po, u, qd1, qd2, mt, mo, vol, vo, P, out, oo):
    """:func:`pressure_rates` on ``p[po:po + 4]``, ``mt[mo:mo + 4]``, ``vol[vo:vo + 4]`` into
    ``out[oo:oo + 4]``: offsets instead of views, for the plant's derivative (a view costs two
    atomic reference-count updates in compiled code).

    Parameters
    ----------
    p : ndarray of float64
        Holds the gauge pressures of the four groups [Pa] from ``po``.
    po : int
        Offset of the pressures in ``p``.
    u : ndarray of float64, shape (4,)
        Valve set values of the four groups [Pa].
    qd1, qd2 : float
        Joint velocities (shoulder, elbow) [rad/s].
    mt, vol : ndarray of float64
        Hold the torque functions [m^3] from ``mo`` and the group volumes [m^3] from
        ``vo`` (the same array may hold both).
    mo, vo : int
        Their offsets.
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row.
    out : ndarray of float64
        Receives dp_i/dt [Pa/s] from ``oo``.
    oo : int
        Offset of the output.
    """
    n = P[NPOLY]
    for i in range(4):
        w = qd1 if i < 2 else qd2
        out[oo + i] = ((P[V1 + i] + P[V2 + i] * u[i] - p[po + i]) / P[TV + i]
                       - n * (P[PATM] + p[po + i]) * mt[mo + i] * w / vol[vo + i])


@leaf
def stiffness_from(p, mt, dmt, vol, P):
    """Joint stiffnesses (K1, K2) of (2.18) [N m/rad] from torque-kernel outputs.

    K_j = sum over the groups of joint j of
    n (P_atm + p_i) m_tau,i^2 / V_i - p_i d m_tau,i/dq_j.

    Parameters
    ----------
    p : ndarray of float64, shape (4,)
        Gauge pressures of the four groups [Pa].
    mt : ndarray of float64, shape (4,)
        Torque functions m_tau,i [m^3], from
        :func:`~ppamsafety.plant.torque.torque_kernel`.
    dmt : ndarray of float64, shape (4,)
        Their derivatives along the driven joint [m^3/rad].
    vol : ndarray of float64, shape (4,)
        Group volumes V_i [m^3].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``n_poly`` and ``p_atm``.
    """
    n = P[NPOLY]
    k1 = 0.0
    k2 = 0.0
    for i in range(4):
        ki = n * (P[PATM] + p[i]) * mt[i] * mt[i] / vol[i] - p[i] * dmt[i]
        if i < 2:
            k1 += ki
        else:
            k2 += ki
    return k1, k2


@leaf
def set_value(i, p_desired, P):
    """Valve set value giving ``p_desired`` by inverting (3.12), clipped to [0, p_max].

    Returns (p_desired - v1_i) / v2_i clipped to [0, p_max] [Pa].

    Parameters
    ----------
    i : int
        Valve (muscle group) index 0..3.
    p_desired : float
        Desired steady-state gauge pressure [Pa].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``v1``, ``v2`` and ``p_max``.
    """
    ps = (p_desired - P[V1 + i]) / P[V2 + i]
    return min(max(ps, 0.0), P[PMAX])


@step_kernel
def delta_p_to_set_values(dp1, dp2, P, out):
    """Delta-p approach (3.7): desired pressures p_m +- dp, clipped, then set values.

    Groups 0, 2 (thesis 1, 3) get p_m + dp, groups 1, 3 get p_m - dp; the
    desired pressures are clipped to [0, p_max] and converted with
    :func:`set_value`.

    Parameters
    ----------
    dp1, dp2 : float
        Pressure differences Delta p of joints 1 and 2 [Pa].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads ``p_mean``, ``p_max``, ``v1`` and ``v2``.
    out : ndarray of float64, shape (4,)
        Output, overwritten: valve set values of the four groups [Pa].
    """
    pmax = P[PMAX]
    for i in range(4):
        pm = P[PM1] if i < 2 else P[PM2]
        dp = dp1 if i < 2 else dp2
        pd = pm + dp if i % 2 == 0 else pm - dp
        out[i] = set_value(i, min(max(pd, 0.0), pmax), P)


@step_kernel
def gravity_compensation_dp(q1, q2, Pc, mt):
    """Delta-p for static gravity compensation (3.18)-(3.19) [Pa].

    ``Pc`` is the controller's packed view (identified gravity terms, see
    :func:`ppamsafety.plant.packing.controller_view`).  The scratch array
    ``mt`` of length 4 is overwritten.  Returns ``(dp1, dp2)``.

    Parameters
    ----------
    q1, q2 : float
        Joint angles (shoulder, elbow) [rad].
    Pc : ndarray of float64, shape (NP,)
        Packed parameter row (layout :data:`ppamsafety.plant.layout.PLANT`)
        the compensation believes in; reads the torque-function fields,
        ``theta``, ``gravity``, ``p_mean`` and, in a plant-truth row with the
        torque bias on, the bias (the controllers' rows never carry it).
    mt : ndarray of float64, shape (4,)
        Scratch, overwritten with the torque functions m_tau [m^3] at (q1, q2)
        (:func:`~ppamsafety.plant.torque.torque_functions_cs`).
    """
    c1, s1, c12, s12 = math.cos(q1), math.sin(q1), math.cos(q1 + q2), math.sin(q1 + q2)
    torque_functions_cs(c1, s1, c12, s12, Pc, mt)
    g1, g2 = gravity_cs(c1, s1, c12, s12, Pc)
    if int(Pc[TORQUE_BIAS_MODE]) == Switch.ON:     # the muscles hold what the bias does not
        g1 -= Pc[TORQUE_BIAS]
        g2 -= Pc[TORQUE_BIAS + 1]
    dp1 = (g1 - Pc[PM1] * (mt[0] + mt[1])) / (mt[0] - mt[1])
    dp2 = (g2 - Pc[PM2] * (mt[2] + mt[3])) / (mt[2] - mt[3])
    return dp1, dp2


@kernel
def _stiffness_many(q, p, P, out):
    mt, dmt, vol = np.empty(4), np.empty(4), np.empty(4)
    for n in range(q.shape[0]):
        torque_kernel(q[n, 0], q[n, 1], P, mt, dmt, vol)
        out[n, 0], out[n, 1] = stiffness_from(p[n], mt, dmt, vol, P)


@kernel
def _gc_many(q, Pc, out):
    mt = np.empty(4)
    for n in range(q.shape[0]):
        out[n, 0], out[n, 1] = gravity_compensation_dp(q[n, 0], q[n, 1], Pc, mt)


@checks_arm
def joint_stiffness(q, pressures, arm) -> np.ndarray:
    """Joint stiffness (2.18) incl. the closed-valve dp/dq terms [N m/rad].

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad].
    pressures : array_like, shape (..., 4)
        Gauge pressures of groups 1..4 [Pa].
    arm : ArmParameters

    Returns
    -------
    numpy.ndarray, shape (..., 2)
    """
    q = angles("q", q)
    p = check_pressures("pressures", pressures)
    shape = np.broadcast_shapes(q.shape[:-1], p.shape[:-1])
    qf = np.ascontiguousarray(np.broadcast_to(q, shape + (2,)).reshape(-1, 2))
    pf = np.ascontiguousarray(np.broadcast_to(p, shape + (4,)).reshape(-1, 4))
    out = np.empty((qf.shape[0], 2))
    _stiffness_many(kernel_array(qf), kernel_array(pf), kernel_array(packing.pack(arm)), out)
    return out.reshape(shape + (2,))


@checks_arm
def gravity_compensation(q, arm, *, params=None) -> np.ndarray:
    """Delta-p of the static gravity compensation (3.18)-(3.19) [Pa], shape (..., 2).

    ``params`` are the rigid-body parameters the compensation believes in;
    default the identified static gravity terms (Table 3.1).  Pass
    ``arm.plant_base`` for an exact compensation of the nominal plant links
    (without the payload of ``arm.effects``; :func:`static_pressures`
    compensates the plant truth including it).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi.
    arm : ArmParameters
        The arm.
    params : BaseParameters, optional
        Rigid-body parameters the compensation believes in.
    """
    q = angles("q", q)
    return _gravity_compensation_row(q, packing.pack(arm, arm.model_gravity if params is None
                                                 else params))


def _gravity_compensation_row(q, Pc) -> np.ndarray:
    """:func:`gravity_compensation` for a packed row ``Pc``."""
    qf = kernel_array(q.reshape(-1, 2))
    out = np.empty((qf.shape[0], 2))
    _gc_many(qf, kernel_array(Pc), out)
    return out.reshape(q.shape[:-1] + (2,))


@checks_arm
def delta_p_pressures(dp, arm, *, clip: bool = True) -> np.ndarray:
    """Desired pressures [p_m1 + dp1, p_m1 - dp1, p_m2 + dp2, p_m2 - dp2] [Pa] (3.7).

    Parameters
    ----------
    dp : array_like, shape (..., 2)
        Pressure differences per joint [Pa].
    arm : ArmParameters
        The arm (mean pressures, p_max).
    clip : bool, keyword-only
        Clip to [0, p_max].
    """
    dp = check_range_array("dp", as_float_array("dp", dp, shape_tail=(2,)), -PRESSURE_MAX,
                           PRESSURE_MAX, unit="Pa")
    pm = arm.pneumatics.p_mean
    p = np.stack([pm[0] + dp[..., 0], pm[0] - dp[..., 0], pm[1] + dp[..., 1],
                  pm[1] - dp[..., 1]], axis=-1)
    return np.clip(p, 0.0, arm.pneumatics.p_max) if clip else p


@checks_arm
def valve_pressure(set_values, arm) -> np.ndarray:
    """Static delivered pressure p = v1 + v2 p_s (3.12) [Pa], shape (..., 4).

    Parameters
    ----------
    set_values : array_like, shape (..., 4)
        Valve set values [Pa].
    arm : ArmParameters
        The arm (valve characteristics).
    """
    u = check_pressures("set_values", set_values)
    v1 = np.array([v.v1 for v in arm.valves.valves])
    v2 = np.array([v.v2 for v in arm.valves.valves])
    return v1 + v2 * u


@checks_arm
def valve_set_values(pressures, arm) -> np.ndarray:
    """Set values that deliver ``pressures`` by inverting (3.12), clipped to [0, p_max] [Pa].

    Parameters
    ----------
    pressures : array_like, shape (..., 4)
        Desired gauge pressures [Pa].
    arm : ArmParameters
        The arm (valve characteristics).
    """
    p = check_pressures("pressures", pressures)
    v1 = np.array([v.v1 for v in arm.valves.valves])
    v2 = np.array([v.v2 for v in arm.valves.valves])
    return np.clip((p - v1) / v2, 0.0, arm.pneumatics.p_max)


@checks_arm
def static_pressures(q, arm, *, params=None) -> np.ndarray:
    """Gauge pressures holding ``q`` in static equilibrium with the Delta-p approach [Pa].

    Uses (3.18)-(3.19) with ``params`` (default: the *plant truth* row
    ``packing.pack(arm)``, including the payload of ``arm.effects``, so the
    result is a true equilibrium of the simulated arm).  Not clipped, so that
    an infeasible configuration shows up as a pressure outside [0, p_max].

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi.
    arm : ArmParameters
        The arm.
    params : BaseParameters, optional
        Rigid-body parameters (default: the plant truth).
    """
    if params is None:
        q = angles("q", q)
        dp = _gravity_compensation_row(q, packing.pack(arm))
    else:
        dp = gravity_compensation(q, arm, params=params)
    return delta_p_pressures(dp, arm, clip=False)


@checks_arm
def calibrate_mean_pressures(arm, *, q=(50.0 * DEG, -80.0 * DEG),
                             target_stiffness=(43.0, 27.0)) -> tuple:
    """Mean pressures p_m (per joint) giving a target joint stiffness.

    Solves K_j(q, p(p_m)) = target_j for p_m,j, with p the static
    gravity-compensation pressures of the plant at ``q`` (thesis §6.3.3:
    K1 = 43, K2 = 27 Nm/rad at the step-response impact instant).

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    q : pair of float, keyword-only
        Configuration [rad] (default 50 deg, -80 deg).
    target_stiffness : pair of float, keyword-only
        Target joint stiffnesses [N m/rad], each in (0, 1e4].

    Returns
    -------
    tuple of 2 float
        (p_m1, p_m2) [Pa].
    """
    from scipy.optimize import brentq

    q = np.asarray(q, dtype=float)
    for j, k in enumerate(target_stiffness):
        check_range(f"target_stiffness[{j}]", k, 0.0, 1e4, lo_open=True, unit="N m/rad")
    pm = list(arm.pneumatics.p_mean)
    pmax = arm.pneumatics.p_max

    def stiffness(j, value):
        trial = list(pm)
        trial[j] = value
        a = arm.replace(pneumatics=arm.pneumatics.replace(p_mean=tuple(trial)))
        return joint_stiffness(q, static_pressures(q, a), a)[j]

    out = []
    for j in range(2):
        f = lambda v, j=j: stiffness(j, v) - target_stiffness[j]  # noqa: E731
        lo, hi = 0.05 * pmax, pmax
        if f(lo) * f(hi) > 0:
            raise ValueError(f"calibrate_mean_pressures: stiffness {target_stiffness[j]} N m/rad "
                             f"of joint {j + 1} is not reachable with p_m in [{lo:g}, {hi:g}] Pa")
        out.append(brentq(f, lo, hi, xtol=1.0))
        pm[j] = out[-1]
    return tuple(out)
