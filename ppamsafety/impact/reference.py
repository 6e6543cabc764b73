"""Reference impact solution with scipy's adaptive integrator (one call per impact).

Same model as :mod:`ppamsafety.impact.engine` (its compiled right-hand side),
integrated by :func:`scipy.integrate.solve_ivp` with tight tolerances and
sampled on the same uniform grid for the HIC.  Used to cross-check the fixed
step integrator and as the baseline of the batch-speed benchmark.
"""

from __future__ import annotations

import math

import numpy as np

from .._validation import (as_float_array, check_choice, check_finite_result, check_range,
                           check_range_array)
from ..plant import geometry as geo
from ..plant import packing
from ..units import G0
from . import engine as eng
from .hic import hic
from .model import (MAX_MOTOR_INERTIA, MAX_STEPS, check_angles, check_arm,
                    check_flexible_stiffness, check_pass_through, check_stiffness, resolve_head,
                    resolve_joint_model)

#: Integration methods of :func:`scipy.integrate.solve_ivp` accepted.
METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")


def simulate_impact_scipy(arm, q, qd, stiffness, *, head=None, method: str = "RK45",
                          rtol: float = 1e-9, atol: float = 1e-12, dt: float = 2e-5,
                          duration: float = 0.05, joint_model="frozen-equilibrium",
                          motor_inertia=None) -> dict:
    """One impact by ``solve_ivp`` (tool velocity direction, head at rest).

    Same model and input checks as :func:`ppamsafety.impact.model.simulate_impacts`
    for a single case.

    Parameters
    ----------
    arm : ArmParameters
        Link inertias and kinematics.
    q : array_like, shape (2,)
        Link angles [rad] at the impact instant (|q| <= 2 pi; outside the
        working area a ``UserWarning``).
    qd : array_like, shape (2,)
        Link angular velocities [rad/s], not both zero (the tool must move).
    stiffness : array_like, shape (2,)
        Joint stiffnesses K1, K2 [N m/rad], >= 0 and at most
        :func:`~ppamsafety.impact.model.stiffness_limit` for the step ``dt``.
    head : HeadContactModel or str, optional
        Head model or its name (default ``"thesis-frontal"``).
    method : str
        One of :data:`METHODS`.
    rtol : float
        Relative tolerance of ``solve_ivp``, in [1e-14, 1e-2].
    atol : float
        Absolute tolerance of ``solve_ivp``, in [1e-20, 1e-2].
    dt : float
        Output grid step [s] in [1e-8, 1e-3] (HIC sampling).
    duration : float
        Simulated time [s] in [1e-4, 10], at least dt.
    joint_model : str or JointModel
        Motor-side convention, as in
        :func:`~ppamsafety.impact.model.simulate_impacts`.
    motor_inertia : array_like, shape (2,), optional
        Motor-side inertias [kg m^2] (flexible joint, rigid), each in
        [0, :data:`~ppamsafety.impact.model.MAX_MOTOR_INERTIA`]; default 0.

    Returns
    -------
    dict
        ``F_max`` [N], ``HIC36``, ``HIC15``, ``delta_max`` [m], ``nfev``
        (right-hand side evaluations), ``E_balance_error`` [-] (as in the
        engine's summary).
    """
    from scipy.integrate import solve_ivp

    arm = check_arm(arm)
    q = as_float_array("q", q, ndim=1, shape_tail=(2,))
    qd = as_float_array("qd", qd, ndim=1, shape_tail=(2,))
    jm = resolve_joint_model(joint_model)
    K = as_float_array("stiffness", stiffness, ndim=1, shape_tail=(2,),
                       allow_nonfinite=jm == eng.JointModel.RIGID)
    if np.any(np.isnan(K)):
        raise ValueError(f"stiffness = {K.tolist()} N m/rad contains NaN")
    B = np.zeros(2) if motor_inertia is None else as_float_array(
        "motor_inertia", motor_inertia, ndim=1, shape_tail=(2,))
    check_range_array("motor_inertia", B, 0.0, MAX_MOTOR_INERTIA, unit="kg m^2")
    if jm == eng.JointModel.FROZEN_EQUILIBRIUM and motor_inertia is not None:
        raise ValueError("motor_inertia is only used by joint_model 'flexible-joint' or 'rigid'")
    hm = resolve_head(head)
    method = check_choice("method", method, METHODS)
    rtol = check_range("rtol", rtol, 1e-14, 1e-2)
    atol = check_range("atol", atol, 1e-20, 1e-2)
    dt = check_range("dt", dt, 1e-8, 1e-3, unit="s")
    duration = check_range("duration", duration, 1e-4, 10.0, unit="s")
    if duration < dt or duration / dt > MAX_STEPS:
        raise ValueError(f"duration = {duration:g} s and dt = {dt:g} s: need dt <= duration "
                         f"and duration / dt <= {MAX_STEPS}")
    check_angles("q", q, arm)
    if np.any(np.abs(qd) > 1e3):
        raise ValueError(f"qd = {qd.tolist()} rad/s is outside [-1000, 1000] rad/s")
    if np.any(K < 0):
        raise ValueError(f"stiffness = {K.tolist()} N m/rad must be non-negative")
    if jm == eng.JointModel.FROZEN_EQUILIBRIUM:
        check_stiffness(K[None, :], q[None, :], arm, dt, dt)
    elif jm == eng.JointModel.FLEXIBLE_JOINT:
        check_flexible_stiffness(K[None, :], q[None, :], B[None, :], arm, dt, dt)
    v = geo.jacobian(q, arm) @ qd
    sp = float(np.linalg.norm(v))
    if sp == 0.0:
        raise ValueError(f"qd = {qd.tolist()}: the tool is at rest, there is no impact")
    check_pass_through(hm, [sp])
    case = eng.pack_cases(1, q=q, qd=qd, K=K, u=v / sp,
                          v_head=0.0, arm_mode=int(eng.ArmMode.FLEXIBLE),
                          joint_model=int(jm), B=B)[0]
    P = np.array(packing.pack(arm))
    hp = eng.pack_head(hm)
    y0 = np.empty(eng.NY)
    eng.initial_state(case, P, hp, y0)
    dy = np.empty(eng.NY)

    def rhs(t, y):
        eng.impact_rhs(y, case, P, hp, dy)
        return dy.copy()

    n = int(math.ceil(duration / dt - 1e-9))
    t = np.arange(n + 1) * dt
    sol = solve_ivp(rhs, (0.0, t[-1]), y0, method=method, t_eval=t, rtol=rtol, atol=atol)
    if not sol.success:
        raise ValueError(f"solve_ivp ({method}, rtol = {rtol:g}, atol = {atol:g}) failed: "
                         f"{sol.message}")
    F = np.empty(n + 1)
    delta = np.empty(n + 1)
    for i in range(n + 1):
        F[i], delta[i], _, _ = eng.impact_rhs(sol.y[:, i], case, P, hp, dy)
    check_finite_result("the scipy impact solution", F, "these inputs")
    a = F / (hm.mass * G0)
    e0 = eng._energy(y0, case, P, hp)
    e1 = eng._energy(sol.y[:, -1], case, P, hp) + sol.y[eng.Y_ED, -1]
    return {"F_max": float(F.max()), "HIC36": hic(a, dt).value,
            "HIC15": hic(a, dt, window=0.015).value, "delta_max": float(delta.max()),
            "nfev": int(sol.nfev), "E_balance_error": float((e1 - e0) / e0)}
