"""Impact engine: analytic oracles, invariants, convergence, reference integrator."""

import numpy as np
import pytest

from ppamsafety.impact import contact
from ppamsafety.impact.model import effective_mass, simulate_impacts
from ppamsafety.impact.reference import simulate_impact_scipy
from ppamsafety.impact.twobody import two_body_impact
from ppamsafety.impact.head import head_model
from ppamsafety.plant import geometry as geo
from ppamsafety.units import DEG

Q = np.array([50 * DEG, -80 * DEG])
QD = np.array([3.0, -1.0])            # tool speed about 1.2 m/s
K = np.array([43.0, 27.0])


@pytest.mark.parametrize("n, b", [(1.5, 0.0), (1.5, 3.3e6), (1.0, 0.0), (1.0, 2.0e5)])
def test_fixed_arm_matches_marhefka_orin_closed_form(arm, n, b):
    """Rigid fixed arm, head thrown at it: maximum penetration and restitution equal the
    closed-form Hunt-Crossley phase-plane solution (Marhefka & Orin 1999) to 1e-4."""
    head = head_model().replace(exponent=n, damping=b,
                                stiffness=9.3e5 if n == 1.5 else 6.5e4)
    v0 = 1.2
    u = np.array([0.6, 0.8])
    r = simulate_impacts(arm, Q, [0.0, 0.0], K, head=head, direction=u, head_velocity=-v0 * u,
                         fixed_arm=True, dt=1e-6, duration=0.05, history=True)
    h = r.histories[0]
    dmax = contact.max_penetration(head.mass, v0, head.stiffness, n, b)
    assert h["delta"].max() == pytest.approx(dmax, rel=1e-4)
    v_out = h["v_head_n"].iloc[-1]                       # rebound speed along u
    e = contact.exit_velocity(head.mass, v0, head.stiffness, n, b) / v0
    assert v_out / v0 == pytest.approx(e, rel=1e-4)
    assert h["F"].iloc[-1] == 0.0                        # separated at the end


def test_undamped_impact_conserves_energy(arm):
    head = head_model().replace(damping=0.0)
    r = simulate_impacts(arm, Q, QD, K, head=head, dt=1e-5, history=True)
    s = r.summary.iloc[0]
    assert s.E_dissipated == pytest.approx(0.0, abs=1e-12)
    E = r.histories[0]["E_total"].to_numpy()
    assert np.abs(E - E[0]).max() / E[0] < 1e-6
    assert s.E_head_final > 0.1 * s.E_initial              # energy really went to the head


def test_energy_lost_equals_contact_dissipation(arm):
    """Kinetic + spring + contact potential + integral (F - k d^n) d' dt is constant."""
    r = simulate_impacts(arm, Q, QD, K, dt=1e-5, history=True)
    s = r.summary.iloc[0]
    assert s.E_dissipated > 0.1 * s.E_initial
    assert abs(s.E_balance_error) < 1e-6
    E = r.histories[0]["E_total"].to_numpy()
    assert np.abs(E - E[0]).max() / E[0] < 1e-6


def test_contact_force_is_never_negative(arm):
    """Also when the Hunt-Crossley expression goes negative (fast separation, big b)."""
    assert contact.hunt_crossley_force(1e-3, -10.0, 1e6, 1.5, 1e6) == 0.0
    head = head_model().replace(damping=5e7)
    r = simulate_impacts(arm, Q, 3 * QD, K, head=head, dt=1e-5, history=True)
    assert r.histories[0]["F"].min() >= 0.0
    assert r.summary.F_max.iloc[0] > 0


def test_momentum_balance_between_arm_and_head(arm):
    """Head momentum change = contact impulse; the arm's generalized momentum H qd changes by
    the opposite impulse through J^T plus the spring and Coriolis terms (Hdot = C + C^T)."""
    from ppamsafety.plant import dynamics as dyn

    r = simulate_impacts(arm, Q, QD, K, dt=5e-6, history=True)
    h = r.histories[0]
    t = h["t"].to_numpy()
    F = h["F"].to_numpy()
    n = h[["nx", "ny"]].to_numpy()
    m_h = r.head.mass
    vh = h[["vhx", "vhy"]].to_numpy()
    impulse = np.trapezoid(F[:, None] * n, t, axis=0)
    np.testing.assert_allclose(m_h * (vh[-1] - vh[0]), impulse, rtol=1e-5, atol=1e-9)
    q = Q + h[["dq1", "dq2"]].to_numpy()
    qd = h[["qd1", "qd2"]].to_numpy()
    p = np.einsum("nij,nj->ni", dyn.inertia_matrix(q, arm), qd)
    J = geo.jacobian(q, arm)
    C = dyn.coriolis(q, qd, arm)
    gen = (-(q - Q) * K + np.einsum("nji,nj->ni", C, qd)
           + np.einsum("nji,nj->ni", J, -F[:, None] * n))
    np.testing.assert_allclose(p[-1] - p[0], np.trapezoid(gen, t, axis=0), rtol=1e-4,
                               atol=1e-6 * np.abs(p[0]).max())


def test_results_converge_when_the_step_is_halved(arm):
    a = simulate_impacts(arm, Q, QD, K, dt=2e-5).summary.iloc[0]
    b = simulate_impacts(arm, Q, QD, K, dt=1e-5).summary.iloc[0]
    for key in ("F_max", "HIC36", "HIC15", "delta_max"):
        assert a[key] == pytest.approx(b[key], rel=2e-4)


def test_matches_adaptive_scipy_reference(arm):
    ref = simulate_impact_scipy(arm, Q, QD, K)
    s = simulate_impacts(arm, Q, QD, K).summary.iloc[0]
    assert s.F_max == pytest.approx(ref["F_max"], rel=1e-5)
    assert s.HIC36 == pytest.approx(ref["HIC36"], rel=1e-5)


def test_two_body_model_with_effective_mass_reproduces_the_full_model(arm):
    """The force is decided by the links' effective mass at the tool (thesis §6.3.4)."""
    h = head_model()
    v = geo.jacobian(Q, arm) @ QD
    me = effective_mass(Q, v, arm)
    tb = two_body_impact([np.linalg.norm(v)], arm_mass=me, stiffness=h.stiffness,
                         exponent=h.exponent, damping=h.damping)
    full = simulate_impacts(arm, Q, QD, [1.0, 1.0]).summary.iloc[0]
    assert full.F_max == pytest.approx(tb["F_max"][0], rel=0.01)
    assert full.HIC36 == pytest.approx(tb["HIC36"][0], rel=0.03)


def test_effective_mass_of_a_single_pendulum_direction(arm):
    """Along the tool velocity of joint 2 alone, with joint 1 free, m_eff < I_S2 / L2^2."""
    J = geo.jacobian(Q, arm)
    m = effective_mass(Q, J[:, 1], arm)
    assert 0.0 < m < arm.plant_base.IS2 / arm.geometry.L2 ** 2 * 1.000001


def test_arm_at_rest_gives_no_impact(arm):
    r = simulate_impacts(arm, np.stack([Q, Q]), [[0.0, 0.0], QD], K)
    assert r.summary.F_max.iloc[0] == 0.0 and r.summary.HIC36.iloc[0] == 0.0
    assert r.summary.F_max.iloc[1] > 0


def test_invalid_inputs(arm):
    with pytest.raises(ValueError, match="stiffness"):
        simulate_impacts(arm, Q, QD, [-1.0, 2.0])
    with pytest.raises(ValueError, match="unknown head model"):
        simulate_impacts(arm, Q, QD, K, head="martian")
    with pytest.raises(ValueError, match="dt"):
        simulate_impacts(arm, Q, QD, K, dt=0.1)


def test_history_and_summary_columns_mean_what_their_names_say(arm):
    """Writer/column drift check: every named column of a recorded history and of the summary
    is recomputed from the recorded state with independent NumPy code (issue 7)."""
    from ppamsafety.impact import engine as eng
    from ppamsafety.impact.hic import hic
    from ppamsafety.plant import dynamics as dyn
    from ppamsafety.units import G0

    dt = 1e-5
    r = simulate_impacts(arm, Q, QD, K, dt=dt, duration=0.02, history=[0])
    h, s, head = r.history(0), r.summary.iloc[0], r.head
    assert list(h.columns) == eng.HIST_COLUMNS == eng.HIST.columns()
    assert list(r.summary.columns[-eng.NSUM - 2:-2]) == eng.SUMMARY_COLUMNS   # + energy_ok, status
    t, F, delta = r.signal("t", 0), r.signal("F", 0), r.signal("delta", 0)
    q = Q + r.signals("dq1", "dq2", index=0)
    qd = r.signals("qd1", "qd2", index=0)
    n = r.signals("nx", "ny", index=0)
    vh = r.signals("vhx", "vhy", index=0)
    u = np.array([s.ux, s.uy])
    J = geo.jacobian(q, arm)
    v_tcp = np.einsum("nij,nj->ni", J, qd)
    # time grid, initial state
    np.testing.assert_array_equal(t, np.arange(t.size) * dt)
    np.testing.assert_array_equal(q[0], Q)
    np.testing.assert_array_equal(qd[0], QD)
    np.testing.assert_allclose(np.hypot(n[:, 0], n[:, 1]), 1.0, rtol=1e-14)
    # F is the contact law at the recorded penetration and its rate
    delta_dot = -np.einsum("ni,ni->n", n, vh - v_tcp)
    np.testing.assert_allclose(F, head.force(delta, delta_dot), rtol=1e-9,
                               atol=1e-9 * F.max())
    assert F.max() > 100.0 and np.count_nonzero(F) > 10          # a real contact was recorded
    np.testing.assert_allclose(r.signal("a_head_g", 0), F / (head.mass * G0), rtol=1e-15)
    np.testing.assert_allclose(r.signal("v_head_n", 0), vh @ u, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(r.signal("v_tcp_n", 0), v_tcp @ u, rtol=1e-12, atol=1e-15)
    # E_total: kinetic + springs + contact potential + dissipated
    H = dyn.inertia_matrix(q, arm)
    e_arm = 0.5 * np.einsum("ni,nij,nj->n", qd, H, qd)
    e_spring = 0.5 * ((q - Q) ** 2 @ K)
    e_head = 0.5 * head.mass * (vh ** 2).sum(axis=1)
    dpos = np.maximum(delta, 0.0)
    e_contact = head.stiffness * dpos ** (head.exponent + 1) / (head.exponent + 1)
    e_mech = e_arm + e_spring + e_head + e_contact
    np.testing.assert_allclose(r.signal("E_total", 0)[-1] - s.E_dissipated, e_mech[-1],
                               rtol=1e-12)
    # summary columns against the history
    i = int(np.argmax(F))
    assert s.F_max == F[i] and s.t_Fmax == t[i]
    assert s.delta_max == max(delta.max(), 0.0)
    assert s.a_max_g == pytest.approx(s.F_max / (head.mass * G0), rel=1e-15)
    assert s.contact_time == pytest.approx(dt * np.count_nonzero(F > 0), rel=1e-12)
    assert s.E_initial == pytest.approx(0.5 * QD @ dyn.inertia_matrix(Q, arm) @ QD, rel=1e-12)
    assert s.E_initial == pytest.approx(e_mech[0], rel=1e-12)
    assert s.v_tcp0 == pytest.approx(np.linalg.norm(geo.jacobian(Q, arm) @ QD), rel=1e-12)
    assert s.v_tcp0 == pytest.approx(r.signal("v_tcp_n", 0)[0], rel=1e-12)   # u = tool direction
    assert s.E_head_final == pytest.approx(e_head[-1], rel=1e-12)
    assert s.E_balance_error == pytest.approx(
        (r.signal("E_total", 0)[-1] - s.E_initial) / s.E_initial, rel=1e-6, abs=1e-15)
    for w, col in ((0.036, "HIC36"), (0.015, "HIC15")):
        ref = hic(r.signal("a_head_g", 0), dt, window=w)
        assert s[col] == pytest.approx(ref.value, rel=1e-12)
        assert (s[col + "_t1"], s[col + "_t2"]) == pytest.approx((ref.t1, ref.t2), abs=1e-12)
    with pytest.raises(KeyError, match="not a history signal"):
        r.signal("F_max", 0)
    with pytest.raises(KeyError, match="no history recorded"):
        simulate_impacts(arm, Q, QD, K, dt=dt, duration=0.002).history(0)


def test_case_rows_are_packed_by_name_and_the_arm_mode_is_exact(arm):
    from ppamsafety.impact import engine as eng

    rows = eng.pack_cases(3, q=Q, qd=QD, K=K, u=[1.0, 0.0], v_head=0.0,
                          arm_mode=eng.ArmMode.FIXED)
    assert rows.shape == (3, eng.NCASE)
    np.testing.assert_array_equal(eng.CASE.read(rows, "K"), np.tile(K, (3, 1)))
    np.testing.assert_array_equal(eng.CASE.read(rows, "arm_mode"), [1.0, 1.0, 1.0])
    assert eng.CASE.read(eng.pack_cases(1, q=Q, qd=QD, K=K, u=[1, 0], v_head=0)[0],
                         "arm_mode") == eng.ArmMode.FLEXIBLE
    with pytest.raises(ValueError, match="'K' must broadcast"):
        eng.pack_cases(3, q=Q, qd=QD, K=[1.0, 2.0, 3.0], u=[1, 0], v_head=0)
    with pytest.raises(ValueError, match="'u'.*required"):
        eng.pack_cases(3, q=Q, qd=QD, K=K, v_head=0)
    # fixed arm: the tool point never moves
    u = np.array([0.6, 0.8])
    r = simulate_impacts(arm, Q, QD, K, direction=u, head_velocity=-u, fixed_arm=True,
                         dt=1e-5, duration=0.01, history=True)
    assert r.summary.F_max.iloc[0] > 0
    assert np.all(r.signals("dq1", "dq2", "qd1", "qd2", "v_tcp_n", index=0) == 0.0)
    with pytest.raises(TypeError, match="fixed_arm"):
        simulate_impacts(arm, Q, QD, K, fixed_arm=0.7)
