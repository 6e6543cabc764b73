"""Motor-side conventions of the impact model (issue 12 item 3; thesis §6.3.4, fig. 6.3).

Frozen equilibrium (default, unchanged), Spong's flexible joint with a motor-side
inertia B, and the rigid arm H + diag(B).  Reference state: the PID step-response
impact of fig. 6.3 (instant of largest TCP speed, rounded), thesis head model.
"""

import math
import warnings

import numpy as np
import pandas as pd
import pytest

from ppamsafety.impact import JointModel
from ppamsafety.impact import engine as eng
from ppamsafety.impact.contact import hunt_crossley_force
from ppamsafety.impact.model import (ENERGY_TOL, effective_mass, flexible_stiffness_limit,
                                     simulate_impacts, stiffness_limit)
from ppamsafety.impact.reference import simulate_impact_scipy
from ppamsafety.impact.twobody import two_body_impact
from ppamsafety.params import thesis_arm
from ppamsafety.impact.head import head_model
from ppamsafety.plant import dynamics as dyn
from ppamsafety.plant import geometry as geo

ARM = thesis_arm()
Q = np.array([0.613593, -1.321503])          # fig. 6.3 impact state [rad]
QD = np.array([-4.425199, -3.994642])        # [rad/s]
DT0 = 2e-5


def _dt(k, B=None):
    """Largest step DT0/2^m whose stiffness limit admits k (as the stiffness study)."""
    if B is None:
        lim = float(stiffness_limit(Q, ARM, eng.FREE_STRIDE * DT0))
    else:
        lim = float(flexible_stiffness_limit(Q, B, ARM, eng.FREE_STRIDE * DT0))
    return DT0 if k <= lim else DT0 / 2 ** math.ceil(math.log2(math.sqrt(k / lim) * 1.0001))


def _run(k, joint_model="frozen-equilibrium", B=None, **kw):
    kw.setdefault("dt", _dt(k, None if joint_model == "frozen-equilibrium" else B))
    extra = {} if B is None else {"motor_inertia": B}
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # no energy-balance or other flag
        return simulate_impacts(ARM, Q, QD, [k, k], joint_model=joint_model, **extra,
                                **kw).summary.iloc[0]


# --- the default is the historical model --------------------------------------------------

def test_default_is_the_frozen_equilibrium_bitwise():
    rng = np.random.default_rng(4)
    q = np.column_stack([rng.uniform(0.5, 1.5, 6), rng.uniform(-1.8, -0.8, 6)])
    qd = rng.normal(scale=2.0, size=(6, 2))
    K = rng.uniform(10, 500, (6, 2))
    a = simulate_impacts(ARM, q, qd, K).summary
    b = simulate_impacts(ARM, q, qd, K, joint_model=JointModel.FROZEN_EQUILIBRIUM).summary
    assert list(a.columns) == list(b.columns) and "joint_model" not in a.columns
    np.testing.assert_array_equal(a[eng.SUMMARY_COLUMNS].to_numpy(),
                                  b[eng.SUMMARY_COLUMNS].to_numpy())
    row = eng.pack_cases(1, q=Q, qd=QD, K=[1.0, 2.0], u=[1.0, 0.0], v_head=0.0)[0]
    assert int(row[eng.C_JM]) == JointModel.FROZEN_EQUILIBRIUM
    assert row[eng.C_B] == row[eng.C_B + 1] == 0.0


def test_new_fields_are_appended_at_the_end_of_the_layouts():
    assert [f.name for f in eng.CASE.fields][-2:] == ["joint_model", "B"]
    assert [f.name for f in eng.STATE.fields][-2:] == ["theta", "theta_d"]
    assert eng.C_ARM < eng.C_JM < eng.C_B and eng.Y_ED < eng.Y_TH < eng.Y_THD


# --- energy balance and limits --------------------------------------------------------------

@pytest.mark.parametrize("k", [1.0, 43.0, 6000.0, 1e5, 1e6])
@pytest.mark.parametrize("joint_model, B", [("frozen-equilibrium", None),
                                            ("flexible-joint", [0.003, 0.003]),
                                            ("flexible-joint", [0.3, 0.05])])
def test_energy_balance_at_every_stiffness(k, joint_model, B):
    """Kinetic (links + motor sides) + springs + contact + dissipated is conserved.

    Stated tolerance ENERGY_TOL = 1e-3; measured max 4e-5 (frozen, 1e6 Nm/rad)."""
    r = _run(k, joint_model, B)
    assert abs(r.E_balance_error) < 1e-4 < ENERGY_TOL
    assert r.F_max > 0 and r.status == "ok"


def test_motor_kinetic_energy_is_in_the_initial_energy():
    B = np.array([0.2, 0.1])
    H = dyn.inertia_matrix(Q, ARM)
    e_links = 0.5 * QD @ H @ QD
    e_motor = 0.5 * B @ QD ** 2
    assert _run(10.0, "flexible-joint", B).E_initial == pytest.approx(e_links + e_motor,
                                                                        rel=1e-12)
    assert _run(10.0, "rigid", B).E_initial == pytest.approx(e_links + e_motor, rel=1e-12)
    assert _run(10.0).E_initial == pytest.approx(e_links, rel=1e-12)


def test_flexible_joint_without_motor_inertia_is_the_free_rigid_links_at_any_stiffness():
    """B = 0: no spring load can build up, so K is irrelevant (and never limits the step)."""
    f = [_run(k, "flexible-joint", [0.0, 0.0], dt=DT0).F_max for k in (1.0, 6000.0, 1e9)]
    rigid = _run(1.0, "rigid", [0.0, 0.0]).F_max
    assert f[0] == f[1] == f[2]
    assert rigid == pytest.approx(f[0], rel=1e-12)


def test_flexible_joint_rises_with_stiffness_like_fig_6_3():
    """Thesis §6.3.4: F_max *rises*, by less than 5 N (0.33 %), from 1 to 6000 Nm/rad."""
    B = [0.1, 0.1]
    ks = [1.0, 10.0, 100.0, 1000.0, 6000.0]
    f = np.array([_run(k, "flexible-joint", B).F_max for k in ks])
    assert np.all(np.diff(f) > 0)
    assert 0.0 < f[-1] - f[0] < 5.0


def test_frozen_equilibrium_falls_with_stiffness_and_clamps_the_link():
    """The frozen spring pulls the link back to q(t0): F_max falls with k (towards 0)."""
    ks = [1.0, 100.0, 6000.0, 1e6]
    f = np.array([_run(k).F_max for k in ks])
    assert np.all(np.diff(f) < 0)
    assert f[0] - f[2] > 5.0          # the thesis' bound is violated, with the wrong sign
    assert f[3] < 0.3 * f[0]


def test_rigid_limit_of_the_flexible_joint():
    """K -> inf: the flexible joint tends to the rigid arm H + diag(B) (never to 0)."""
    B = np.array([0.03, 0.03])
    rigid = _run(1.0, "rigid", B).F_max
    far = _run(1e8, "flexible-joint", B).F_max
    assert far == pytest.approx(rigid, rel=1e-4)
    assert rigid > _run(1.0, "rigid", [0.0, 0.0]).F_max          # B adds inertia
    r_inf = simulate_impacts(ARM, Q, QD, [np.inf, np.inf], joint_model="rigid",
                             motor_inertia=B).summary.F_max.iloc[0]
    assert r_inf == rigid                                         # K unused


@pytest.mark.parametrize("B", [0.0, 0.01, 1.0])
def test_rigid_mode_against_the_two_body_impact(B):
    """The rigid arm's F_max is the two-body value with the effective mass of H + diag(B),
    within the effect of the configuration change during the contact (< 0.3 %)."""
    v = geo.jacobian(Q, ARM) @ QD
    sp = float(np.linalg.norm(v))
    m = float(effective_mass(Q, v / sp, ARM, motor_inertia=[B, B]))
    if B == 0.0:
        assert m == pytest.approx(float(effective_mass(Q, v / sp, ARM)), rel=1e-14)
    hm = head_model()
    tb = two_body_impact([sp], arm_mass=m, head_mass=hm.mass, stiffness=hm.stiffness,
                         exponent=hm.exponent, damping=hm.damping)["F_max"][0]
    assert _run(1.0, "rigid", [B, B]).F_max == pytest.approx(tb, rel=3e-3)


def test_dense_integrator_matches_fixed_for_the_flexible_joint():
    B = [0.05, 0.02]
    for k in (43.0, 2000.0):
        dt = _dt(k, B) / 5           # dense free flight takes 100 dt steps
        a = _run(k, "flexible-joint", B, dt=dt)
        b = _run(k, "flexible-joint", B, dt=dt, integrator="dense")
        assert b.F_max == pytest.approx(a.F_max, rel=2e-4)
        assert b.HIC36 == pytest.approx(a.HIC36, rel=2e-4)


def test_dense_integrator_hands_springs_its_free_flight_step_cannot_resolve_to_fixed():
    """A stiffness the fixed engine resolves but the dense free-flight step (DENSE_FREE_STRIDE
    x dt) does not: ``integrator="dense"`` runs that case on the fixed engine (bitwise equal),
    never with unresolved springs."""
    k = 0.5 * float(stiffness_limit(Q, ARM, eng.FREE_STRIDE * DT0))
    assert k > float(stiffness_limit(Q, ARM, eng.DENSE_FREE_STRIDE * DT0))
    a = simulate_impacts(ARM, Q, QD, [k, k], dt=DT0).summary
    b = simulate_impacts(ARM, Q, QD, [k, k], dt=DT0, integrator="dense").summary
    pd.testing.assert_frame_equal(a, b)


def test_fixed_step_matches_solve_ivp_for_the_flexible_joint():
    B = [0.05, 0.02]
    k = 2000.0
    a = _run(k, "flexible-joint", B, duration=0.015)
    ref = simulate_impact_scipy(ARM, Q, QD, [k, k], joint_model="flexible-joint",
                                motor_inertia=B, rtol=1e-10, atol=1e-13, duration=0.015)
    assert a.F_max == pytest.approx(ref["F_max"], rel=2e-4)
    assert abs(ref["E_balance_error"]) < 1e-6


# --- independent oracle: the flexible-joint equations written out here -------------------

def _oracle_rhs(arm, case_q0, K, B, hm, u):
    """Spong's reduced model in numpy (Christoffel symbols from central differences of the
    public H(q)); contact with the public Hunt-Crossley law.  Shares no code with impact_rhs."""
    def H(q):
        return dyn.inertia_matrix(q, arm)

    def dH(q, i, h=1e-6):
        e = np.zeros(2)
        e[i] = h
        return (H(q + e) - H(q - e)) / (2 * h)

    def rhs(t, y):
        q, w, xh, vh, th, thd = y[0:2], y[2:4], y[4:6], y[6:8], y[8:10], y[10:12]
        D = [dH(q, 0), dH(q, 1)]
        # C(q, w) w from the Christoffel symbols of H
        cw = np.array([sum(0.5 * (D[k][i, j] + D[j][i, k] - D[i][j, k]) * w[j] * w[k]
                           for j in range(2) for k in range(2)) for i in range(2)])
        r = geo.forward_kinematics(q, arm)
        J = geo.jacobian(q, arm)
        d = xh - r
        dist = np.linalg.norm(d)
        n = d / dist
        delta = hm.radius - dist
        ddelta = -(n @ (vh - J @ w))
        f = hunt_crossley_force(delta, ddelta, hm.stiffness, hm.exponent, hm.damping)
        tau = -K * (q - th) - J.T @ (n * f) - cw
        qdd = np.linalg.solve(H(q), tau)
        return np.concatenate([w, qdd, vh, n * f / hm.mass, thd, K * (q - th) / B])
    return rhs


def test_flexible_joint_against_an_independent_oracle():
    from scipy.integrate import solve_ivp

    hm = head_model()
    K, B = np.array([3000.0, 3000.0]), np.array([0.05, 0.02])
    v = geo.jacobian(Q, ARM) @ QD
    u = v / np.linalg.norm(v)
    r0 = geo.forward_kinematics(Q, ARM)
    y0 = np.concatenate([Q, QD, r0 + hm.radius * u, [0, 0], Q, QD])
    T, dt = 0.012, 2e-5
    t = np.arange(int(round(T / dt)) + 1) * dt
    rhs = _oracle_rhs(ARM, Q, K, B, hm, u)
    sol = solve_ivp(rhs, (0, T), y0, t_eval=t, rtol=1e-10, atol=1e-12, method="DOP853")
    assert sol.success
    F = []
    for y in sol.y.T:
        r = geo.forward_kinematics(y[0:2], ARM)
        J = geo.jacobian(y[0:2], ARM)
        d = y[4:6] - r
        n = d / np.linalg.norm(d)
        F.append(hunt_crossley_force(hm.radius - np.linalg.norm(d), -(n @ (y[6:8] - J @ y[2:4])),
                                     hm.stiffness, hm.exponent, hm.damping))
    F = np.array(F)
    a = _run(3000.0, "flexible-joint", B, duration=T, dt=dt)
    assert a.F_max == pytest.approx(F.max(), rel=2e-4)
    assert a.t_Fmax == pytest.approx(t[np.argmax(F)], abs=2 * dt)


# --- validation -----------------------------------------------------------------------------

@pytest.mark.parametrize("kw, exc, match", [
    ({"joint_model": "spong"}, ValueError, "joint_model"),
    ({"joint_model": 1}, TypeError, "joint_model"),
    ({"joint_model": "flexible-joint", "motor_inertia": [-0.1, 0.0]}, ValueError,
     "motor_inertia"),
    ({"joint_model": "flexible-joint", "motor_inertia": [np.nan, 0.0]}, ValueError,
     "motor_inertia"),
    ({"joint_model": "flexible-joint", "motor_inertia": [1e3, 0.0]}, ValueError,
     "motor_inertia"),
    ({"joint_model": "rigid", "motor_inertia": [0.1, 0.1, 0.1]}, ValueError, "motor_inertia"),
    ({"motor_inertia": [0.1, 0.1]}, ValueError, "motor_inertia"),
    ({"joint_model": "flexible-joint", "fixed_arm": True}, ValueError, "fixed_arm"),
])
def test_invalid_joint_model_inputs_are_refused(kw, exc, match):
    with pytest.raises(exc, match=match):
        simulate_impacts(ARM, Q, QD, [43.0, 27.0], **kw)


def test_motor_inertia_rows_must_match_the_cases():
    with pytest.raises(ValueError, match="motor_inertia"):
        simulate_impacts(ARM, np.stack([Q, Q]), QD, [43.0, 27.0], joint_model="rigid",
                         motor_inertia=[[0.1, 0.1]] * 3)


def test_infinite_stiffness_only_for_the_rigid_model():
    with pytest.raises(ValueError, match="stiffness"):
        simulate_impacts(ARM, Q, QD, [np.inf, 27.0])
    with pytest.raises(ValueError, match="stiffness"):
        simulate_impacts(ARM, Q, QD, [np.inf, 27.0], joint_model="flexible-joint",
                         motor_inertia=[0.1, 0.1])
    with pytest.raises(ValueError, match="stiffness"):
        simulate_impacts(ARM, Q, QD, [np.nan, 27.0], joint_model="rigid")


def test_unresolvable_flexible_stiffness_points_to_the_rigid_model():
    with pytest.raises(ValueError, match="rigid"):
        simulate_impacts(ARM, Q, QD, [1e8, 1e8], joint_model="flexible-joint",
                         motor_inertia=[0.1, 0.1])


def test_flexible_stiffness_limit_validates_and_bounds_the_frequency():
    with pytest.raises(ValueError, match="motor_inertia"):
        flexible_stiffness_limit(Q, [-1.0, 0.0], ARM, 1e-4)
    with pytest.raises(ValueError, match="step"):
        flexible_stiffness_limit(Q, [0.1, 0.1], ARM, 0.0)
    assert flexible_stiffness_limit(Q, [0.0, 0.0], ARM, 1e-4) == np.inf
    # the exact highest frequency of the coupled system lies below the bound's
    B, step = np.array([0.05, 0.02]), 1e-4
    k = float(flexible_stiffness_limit(Q, B, ARM, step))
    M = np.zeros((4, 4))
    M[:2, :2] = dyn.inertia_matrix(Q, ARM)
    M[2, 2], M[3, 3] = B
    Kf = k * np.block([[np.eye(2), -np.eye(2)], [-np.eye(2), np.eye(2)]])
    w2 = np.max(np.real(np.linalg.eigvals(np.linalg.solve(M, Kf))))
    assert 2 * math.pi / math.sqrt(w2) >= 20 * step * (1 - 1e-12)
    with pytest.raises(ValueError, match="motor_inertia"):
        effective_mass(Q, [1.0, 0.0], ARM, motor_inertia=[-1.0, 0.0])
