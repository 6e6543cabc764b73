"""Worst head placement around the tool point (ppamsafety.impact.directions, issue 12 item 6)."""

import math
import warnings

import numpy as np
import pytest

from ppamsafety.impact import directions as dr
from ppamsafety.impact.bounds import impact_bounds
from ppamsafety.impact.model import simulate_impacts
from ppamsafety.impact.twobody import two_body_impact
from ppamsafety.params import thesis_arm
from ppamsafety.impact.head import head_model
from ppamsafety.plant import dynamics as dyn
from ppamsafety.plant import geometry as geo

ARM = thesis_arm()
# the PID step response's worst impact state of the thesis arm (t0 = 7.178 s, |v_tcp| = 3.2 m/s)
# is not needed exactly: a fast state of the working area with joint stiffnesses of §6.3.4.
Q = np.radians([60.0, -70.0])
QD = np.array([6.0, 9.0])
K = np.array([43.0, 27.0])


@pytest.fixture(scope="module")
def optimum():
    return dr.worst_direction_state(ARM, Q, QD, K)


def test_thesis_placement_reproduces_simulate_impacts_bitwise():
    sw = dr.direction_sweep(ARM, Q, QD, K, angles=[0.0])
    ref = simulate_impacts(ARM, Q, QD, K).summary.iloc[0]
    for c in ("F_max", "HIC36", "HIC15"):
        assert sw.table[c].iloc[0] == ref[c]
    v = geo.jacobian(Q, ARM) @ QD
    assert math.isclose(sw.velocity_deg, math.degrees(math.atan2(v[1], v[0])), abs_tol=1e-12)


def test_worst_is_at_least_the_thesis_placement(optimum):
    assert optimum.F_max >= optimum.F_along_velocity
    assert optimum.HIC36 >= optimum.HIC_along_velocity
    assert abs(optimum.psi_F) < math.radians(89.0)


def test_optimiser_agrees_with_a_dense_brute_force_grid(optimum):
    """Brute force: the engine every 0.25 deg over the whole half plane (713 impacts).

    Tolerance: the grid's own error at 0.25 deg spacing is < 1e-5 relative (curvature about
    1e-4 per deg^2 at the maximum); the optimiser must reach the grid maximum within 2e-5
    relative and never exceed it by more than that, and find the same angle within 0.25 deg.
    """
    psi = np.radians(np.arange(-89.0, 89.001, 0.25))
    sw = dr.direction_sweep(ARM, Q, QD, K, angles=psi)
    t = sw.table
    for col, val, ang in (("F_max", optimum.F_max, optimum.psi_F),
                          ("HIC36", optimum.HIC36, optimum.psi_HIC)):
        i = int(t[col].idxmax())
        gmax = t[col].iloc[i]
        assert val >= gmax * (1 - 2e-5)
        assert val <= gmax * (1 + 2e-5)
        assert abs(math.degrees(ang) - t["psi_deg"].iloc[i]) <= 0.25 + 1e-9


def test_predictor_is_the_two_body_model_exactly():
    """The scaling law F = F_s g(v), HIC = tau (F_s/(m_h g0))^2.5 h(v) against the two-body
    kernel at reduced masses it was not tabulated for (interpolation error < 2e-3)."""
    hm = head_model()
    pred = dr.two_body_predictor(hm)
    ma = np.array([0.3, 0.9, 1.6, 3.0])
    v = np.array([0.05, 0.7, 2.1, 3.9])
    mu = ma * hm.mass / (ma + hm.mass)
    ref = two_body_impact(v, arm_mass=ma, head_mass=hm.mass, stiffness=hm.stiffness,
                          exponent=hm.exponent, damping=hm.damping, dt=2e-6)
    f, h = pred.predict(mu, v)
    np.testing.assert_allclose(f, ref["F_max"], rtol=2e-3)
    np.testing.assert_allclose(h, ref["HIC36"], rtol=2e-3)


def test_undamped_worst_direction_has_the_closed_form():
    """Without damping F_max depends on mu v_n^2 only, maximal for
    u ~ (J H^-1 J^T + I/m_h)^-1 v_tcp (a generalised Rayleigh quotient)."""
    hm = head_model("iso15066-forehead")
    assert hm.damping == 0.0
    J = geo.jacobian(Q, ARM)
    M = J @ np.linalg.inv(dyn.inertia_matrix(Q, ARM)) @ J.T
    v = J @ QD
    u = np.linalg.solve(M + np.eye(2) / hm.mass, v)
    e = v / np.linalg.norm(v)
    psi_star = math.atan2(e[0] * u[1] - e[1] * u[0], e @ u)
    psi = np.radians(np.arange(-60.0, 60.0, 0.05))
    sw = dr.direction_sweep(ARM, Q, QD, K, head=hm, angles=psi)
    i = int(sw.table["F_pred"].idxmax())
    assert abs(sw.table["psi_deg"].iloc[i] - math.degrees(psi_star)) <= 0.05
    # and the predicted energy there equals v^T (M + I/m_h)^-1 v / 2 (the whole "effective"
    # kinetic energy), more than along the velocity
    e_best = 0.5 * v @ np.linalg.solve(M + np.eye(2) / hm.mass, v)
    r = sw.table.iloc[i]
    mu = r.m_eff * hm.mass / (r.m_eff + hm.mass)
    assert math.isclose(0.5 * mu * r.v_n ** 2, e_best, rel_tol=1e-6)


def test_engine_close_to_the_two_body_model_near_the_optimum_and_below_it_aside():
    """§6.3.4: the joint springs barely act during the contact, so the two-body model is
    within 1.5 % of the engine for |psi| <= 20 deg and never more than 0.5 % below it (the
    predictor margin of worst_direction, 1 %, needs engine/prediction <= 1.005)."""
    psi = np.radians(np.arange(-80.0, 80.1, 5.0))
    t = dr.direction_sweep(ARM, Q, QD, K, angles=psi).table
    r = t["F_max"] / t["F_pred"]
    near = np.abs(t["psi_deg"]) <= 20
    assert np.all(np.abs(r[near] - 1) < 1.5e-2)
    assert np.all(r <= 1.005)
    assert r[np.abs(t["psi_deg"]) >= 70].max() < 0.9


def test_rigorous_bounds_hold_for_every_placement():
    psi = np.radians(np.arange(-85.0, 85.1, 5.0))
    t = dr.direction_sweep(ARM, Q, QD, K, angles=psi).table
    fb, hb = impact_bounds(ARM, Q, QD, head=head_model())
    assert np.all(t["F_max"] <= fb[0])
    assert np.all(t["HIC36"] <= hb[0])


@pytest.fixture(scope="module")
def pid_step():
    from ppamsafety.experiments.catalog import run_thesis_experiment, thesis_variants
    v = [x for x in thesis_variants() if x.label == "PID"]
    return run_thesis_experiment(ARM, "step", v)[0]


def test_every_instant_thesis_placement_equals_worst_instant(pid_step):
    from ppamsafety.impact.instants import worst_instant
    w = dr.worst_direction(pid_step, ARM, every=20, min_speed=1e-3, sweep=True)
    ref = worst_instant(pid_step, ARM, every=20, min_speed=1e-3)
    s = w.summary
    assert s["F_max_along_velocity"] == ref.worst_F.F_max
    assert s["HIC36_along_velocity"] == ref.worst_HIC.HIC36
    assert s["t0_F_max_along_velocity"] == ref.worst_F.t0
    assert s["ratio_F_max"] >= 1.0 and s["ratio_HIC36"] >= 1.0
    assert s["ratio_F_max"] >= s["ratio_F_max_same_instant"] - 1e-12
    assert w.rho <= 1 + w.margin / 2
    assert w.counts["bound_pruned"] + w.counts["simulated_instants"] <= w.counts["instants"]
    df = w.to_pandas()
    assert df["F_max_worst"].iloc[0] == s["F_max_worst"]
    # the polar sweep's best grid point cannot beat the optimum by more than the grid error
    assert w.sweep.table["F_max"].max() <= s["F_max_worst"] * (1 + 1e-5)
    fig = w.plot()
    assert len(fig.axes) == 1


def test_invalid_inputs():
    with pytest.raises(ValueError, match="angles"):
        dr.direction_sweep(ARM, Q, QD, K, angles=[math.radians(95.0)])
    with pytest.raises(ValueError, match="at rest"):
        dr.worst_direction_state(ARM, Q, [0.0, 0.0], K)
    with pytest.raises(ValueError, match="xtol"):
        dr.worst_direction_state(ARM, Q, QD, K, xtol=0.0)
    with pytest.raises(ValueError, match="one state"):
        dr.direction_sweep(ARM, np.stack([Q, Q]), QD, K)
    with pytest.raises(ValueError, match="qd"):
        dr.worst_direction_state(ARM, Q, [np.nan, 1.0], K)
    with pytest.raises(ValueError, match="vmax"):
        dr.two_body_predictor(vmax=-1.0)
    with pytest.raises(ValueError, match="mu"):
        dr.two_body_predictor().predict(-1.0, 1.0)
    with pytest.raises(TypeError, match="predictor"):
        dr.direction_sweep(ARM, Q, QD, K, predictor="table")
    with pytest.raises(ValueError, match="head"):
        dr.direction_sweep(ARM, Q, QD, K, predictor=dr.two_body_predictor("iso15066-face"))


def test_invalid_experiment_arguments(pid_step):
    with pytest.raises(ValueError, match="margin"):
        dr.worst_direction(pid_step, ARM, margin=-0.1)
    with pytest.raises(ValueError, match="min_speed"):
        dr.worst_direction(pid_step, ARM, min_speed=0.0)
    with pytest.raises(ValueError, match="min_speed"):
        dr.worst_direction(pid_step, ARM, min_speed=50.0)
    with pytest.raises(TypeError):
        dr.worst_direction("not a result", ARM)
    with pytest.raises(ValueError, match="every"):
        dr.worst_direction(pid_step, ARM, every=0)


@pytest.mark.slow
def test_predictor_pruning_misses_nothing_on_a_brute_force_scan(pid_step):
    """Every instant of the PID step the rigorous bounds leave (841 of 10224), each at 21
    placements (psi = -40..40 deg by 4 deg; the optimum lies at 8-14 deg), simulated by the
    engine: none beats the tiered search (measured: F 1498.16 N vs 1498.18 N, HIC 5.418 vs
    5.424).  The grid cannot be finer than its spacing allows, so the search may only exceed it."""
    from ppamsafety.impact.instants import impact_states
    hm = head_model()
    w = dr.worst_direction(pid_step, ARM, sweep=False)
    st = impact_states(pid_step, ARM)
    st = st[st["tcp_speed"] >= 1e-3]
    q, qd, K = (st[["q1", "q2"]].to_numpy(), st[["qd1", "qd2"]].to_numpy(),
                st[["K1", "K2"]].to_numpy())
    fb, hb = impact_bounds(ARM, q, qd, head=hm)
    s = w.summary
    live = np.nonzero((fb >= s["F_max_worst"]) | (hb >= s["HIC36_worst"]))[0]
    assert 0 < len(live) < len(st)
    best_f = best_h = 0.0
    for p in np.radians(np.arange(-40.0, 40.1, 4.0)):
        v = geo.jacobian(q[live], ARM) @ qd[live][..., None]
        e = v[..., 0] / np.linalg.norm(v[..., 0], axis=1, keepdims=True)
        u = math.cos(p) * e + math.sin(p) * np.stack([-e[:, 1], e[:, 0]], axis=1)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = simulate_impacts(ARM, q[live], qd[live], K[live], direction=u).summary
        best_f, best_h = max(best_f, r["F_max"].max()), max(best_h, r["HIC36"].max())
    assert best_f <= s["F_max_worst"] * (1 + 1e-9)
    assert best_h <= s["HIC36_worst"] * (1 + 1e-9)
