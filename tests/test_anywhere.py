"""Contact anywhere on the arm (impact.anywhere, impact.points): the engine, its bounds, the
screening margin and the worst case over contact point x body region x instant."""

import numpy as np
import pytest

from ppamsafety.experiments.catalog import run_thesis_experiment, thesis_variants
from ppamsafety.impact import points as pt
from ppamsafety.impact import simulate_impacts
from ppamsafety.impact.anywhere import (SCREEN_FLOOR, SCREEN_MARGIN, _prepare, _run, _screen,
                                        contact_bounds, min_point_mass, point_effective_mass,
                                        point_jacobian, simulate_contacts, worst_contact)
from ppamsafety.impact.bodies import body_from_head, body_from_region
from ppamsafety.impact.model import effective_mass
from ppamsafety.params import iso_ts_15066 as iso
from ppamsafety.params import thesis_arm
from ppamsafety.params.contact import (BARE, FOREHEAD, THESIS_COVERING, ContactPoint,
                                       arm_contact_points)
from ppamsafety.plant import dynamics as dyn
from ppamsafety.plant.geometry import jacobian
from ppamsafety.units import DEG


@pytest.fixture(scope="module")
def arm():
    return thesis_arm()


def _random_states(arm, n, seed, vmax=3.0):
    rng = np.random.default_rng(seed)
    q = np.stack([rng.uniform(20, 105, n), rng.uniform(-130, -30, n)], 1) * DEG
    qd = rng.normal(scale=rng.choice([0.3, 2.0, 5.0], size=(n, 1)), size=(n, 2))
    v = np.linalg.norm(np.einsum("nij,nj->ni", jacobian(q, arm), qd), axis=1)
    qd = qd * np.minimum(1.0, vmax / np.maximum(v, 1e-12))[:, None]
    K = np.stack([rng.uniform(5, 80, n), rng.uniform(3, 60, n)], 1)
    return q, qd, K


def test_tool_point_with_a_one_layer_body_is_the_tool_engine_bit_for_bit(arm):
    """Bare metal at the tool point with thesis-frontal as a body: the summary of
    simulate_impacts exactly (today's single-layer numbers stay)."""
    q, qd, K = _random_states(arm, 60, 1)
    old = simulate_impacts(arm, q, qd, K, head="thesis-frontal").summary
    new = simulate_contacts(arm, q, qd, K, point="tool point",
                            body="thesis-frontal").summary
    for c in ("F_max", "t_Fmax", "HIC36", "HIC15", "HIC36_t1", "HIC36_t2", "delta_max",
              "a_max_g", "E_dissipated", "E_initial", "E_balance_error", "contact_time"):
        assert np.array_equal(old[c].to_numpy(), new[c].to_numpy()), c
    assert np.array_equal(old["tcp_speed"].to_numpy(), new["point_speed"].to_numpy())
    assert np.array_equal(new["E_layer1"].to_numpy(), new["E_dissipated"].to_numpy())


def test_effective_mass_of_points(arm):
    q = np.array([[50.0, -80.0], [70.0, -40.0], [30.0, -120.0]]) * DEG
    u = np.array([[1.0, 0.3], [-0.2, 1.0], [0.7, 0.7]])
    pts = {p.name: p for p in arm_contact_points(arm)}
    np.testing.assert_allclose(point_effective_mass(q, u, arm, pts["tool point"]),
                               effective_mass(q, u, arm), rtol=1e-12)
    # a point of link 1 at s: m = 1 / (s^2 [H^-1]_11 (u . e_perp)^2)
    Hi = np.linalg.inv(dyn.inertia_matrix(q, arm))
    s = pts["upper arm"].position
    eperp = np.stack([-np.sin(q[:, 0]), np.cos(q[:, 0])], 1)
    un = u / np.linalg.norm(u, axis=1, keepdims=True)
    closed = 1.0 / (s ** 2 * Hi[:, 0, 0] * np.einsum("ni,ni->n", un, eperp) ** 2)
    np.testing.assert_allclose(point_effective_mass(q, u, arm, pts["upper arm"]), closed,
                               rtol=1e-12)
    # the elbow as link 2 at 0 is link 1 at L1
    e1 = ContactPoint("e", 1, arm.geometry.L1, "sphere", 0.03, BARE)
    np.testing.assert_allclose(point_effective_mass(q, u, arm, pts["elbow"]),
                               point_effective_mass(q, u, arm, e1), rtol=1e-12)
    np.testing.assert_allclose(point_jacobian(q, arm, pts["tool point"]), jacobian(q, arm),
                               rtol=1e-13, atol=1e-15)
    # along link 1 a link-1 point cannot move: infinite mass
    along = np.stack([np.cos(q[:, 0]), np.sin(q[:, 0])], 1)
    assert np.all(np.isinf(point_effective_mass(q, along, arm, pts["upper arm"])))


def test_min_point_mass_grid_is_conservative(arm):
    for p in arm_contact_points(arm):
        coarse = min_point_mass(arm, p)
        fine = min_point_mass(arm, p, grid=200001) / 0.99
        assert coarse <= fine


@pytest.mark.parametrize("stack", ["head bare", "head covered", "face spring", "thesis"])
def test_bounds_exceed_simulated_values_at_every_point(arm, stack):
    """400 random impacts per contact point: the a-priori bounds are never below the engine."""
    body, cov = {"head bare": (FOREHEAD, None), "head covered": (FOREHEAD, THESIS_COVERING),
                 "face spring": (body_from_region(iso.FACE, radius=0.08), None),
                 "thesis": (body_from_head("thesis-frontal"), None)}[stack]
    q, qd, K = _random_states(arm, 400, 7)
    for p in arm_contact_points(arm):
        s = simulate_contacts(arm, q, qd, K, point=p, body=body, covering=cov).summary
        fb, hb = contact_bounds(arm, q, qd, point=p, body=body, covering=cov)
        act = s["status"] == "ok"
        assert np.all(fb[act] >= s.F_max[act]), p.name
        assert np.all(hb[act] >= s.HIC36[act]), p.name
        assert s.F_max.max() > 20.0


@pytest.mark.parametrize("stack", ["head bare", "head covered", "thesis"])
def test_screening_values_with_margin_bound_the_exact_ones(arm, stack):
    """The screening run (coarse contact steps) times 1 + SCREEN_MARGIN is never below the
    exact engine, and its shortfall stays under half the margin."""
    body, cov = {"head bare": (FOREHEAD, None), "head covered": (FOREHEAD, THESIS_COVERING),
                 "thesis": (body_from_head("thesis-frontal"), None)}[stack]
    q, qd, K = _random_states(arm, 300, 11, vmax=3.5)
    worst = 0.0
    for p in arm_contact_points(arm):
        prep = _prepare(arm, q, qd, K, point=p, body=body, covering=cov, direction=None,
                        body_velocity=None, fixed_arm=False, dt=2e-5, duration=0.05,
                        history=False, warn_area=False, stacklevel=2)
        ex = _run(prep, prep.sel, 1)
        for crit, col in (("F_max", pt.U_FMAX), ("HIC36", pt.U_HIC36)):
            sc, ok = _screen(prep, prep.sel, crit)
            # the scan uses a screening value only for contacts resolved by its grid, above a
            # floor: nearly every contact that matters is
            assert ok[ex[:, col] >= 10 * SCREEN_FLOOR[crit]].mean() > 0.95
            m = SCREEN_MARGIN[crit]
            assert np.all(sc[ok, col] * (1.0 + m) >= ex[ok, col]), (p.name, crit)
            worst = max(worst, float(np.max(1.0 - sc[ok, col] / ex[ok, col])) / m)
    assert worst < 0.5


def test_energy_balance_of_the_engine_with_a_covering(arm):
    q, qd, K = _random_states(arm, 50, 3)
    for p in arm_contact_points(arm):
        s = simulate_contacts(arm, q, qd, K, point=p, covering=THESIS_COVERING).summary
        assert np.all(np.abs(s.E_balance_error) < 1e-6)
        layers = s[["E_layer1", "E_layer2", "E_layer3"]].sum(axis=1)
        np.testing.assert_allclose(layers, s.E_dissipated, rtol=1e-9, atol=1e-12)
        assert np.all(s.E_layer1 >= s.E_layer2)          # the covering dissipates most
        assert np.all((s.covering_use >= 0) & (s.covering_use <= 1.0 + 1e-12))
        assert np.all(s.p_max > 0)


def test_history_and_result_protocol(arm):
    r = simulate_contacts(arm, np.array([50, -80]) * DEG, [2.0, -1.0], [43, 27],
                          point="forearm", covering=THESIS_COVERING, history=True)
    h = r.history(0)
    assert {"t", "F", "delta", "a_body_g", "pressure", "delta1", "delta2", "delta3"} <= set(h)
    assert h["F"].max() == pytest.approx(r.summary.F_max[0], rel=1e-12)
    np.testing.assert_allclose(h[["delta1", "delta2", "delta3"]].sum(axis=1)[h.delta > 0],
                               h.delta[h.delta > 0], rtol=1e-10)
    assert r.to_pandas().shape[0] == 1 and r.table is r.summary
    fig = r.plot()
    assert fig.axes


def _brute(res, arm, pts, bodies, every, crit, limits=None):
    from ppamsafety.impact.instants import impact_states

    st = impact_states(res, arm).iloc[::every]
    q, qd, K = (st[["q1", "q2"]].to_numpy(), st[["qd1", "qd2"]].to_numpy(),
                st[["K1", "K2"]].to_numpy())
    out = {}
    for p in pts:
        best = (-np.inf, None)
        for b in bodies:
            s = simulate_contacts(arm, q, qd, K, point=p, body=b).summary
            v = s[crit].to_numpy() / (limits[b.name] if limits else 1.0)
            i = int(np.argmax(v))
            if v[i] > best[0]:
                best = (v[i], (b.name, float(st["t"].iloc[i]), float(s[crit].iloc[i])))
        out[p.name] = best[1]
    return out


@pytest.mark.parametrize("crit, limits", [("F_max", {"forehead": 260.0, "face": 130.0}),
                                          ("F_max", None), ("HIC36", None)])
def test_worst_contact_equals_simulating_every_candidate(arm, crit, limits):
    res = run_thesis_experiment(arm, "step", [thesis_variants()[1]])[0]
    bodies = [FOREHEAD.replace(name="forehead"), body_from_region(iso.FACE, radius=0.08)]
    pts = arm_contact_points(arm)
    w = worst_contact(res, arm, bodies=bodies, limits=limits, criterion=crit, every=50)
    ref = _brute(res, arm, pts, bodies, 50, crit, limits)
    for _, r in w.worst.iterrows():
        name, t0, value = ref[r["point"]]
        assert (r["body"], r["t0"], r["value"]) == (name, t0, value), r["point"]
    assert w.n_simulated < w.n_candidates / 4           # the pruning prunes
    if limits:
        assert np.allclose(w.worst["utilisation"], w.worst["value"] / w.worst["limit"])
        fig = w.plot(arm)
        assert fig.axes


def test_worst_contact_inputs(arm):
    res = run_thesis_experiment(arm, "step", [thesis_variants()[1]])[0]
    with pytest.raises(ValueError, match="no entry"):
        worst_contact(res, arm, limits={"face": 130.0}, every=200)
    with pytest.raises(ValueError, match="criterion"):
        worst_contact(res, arm, criterion="force", every=200)
    with pytest.raises(ValueError, match="point"):
        simulate_contacts(arm, [0.9, -1.4], [1.0, 0.0], [40, 30], point="knee")
    with pytest.raises(TypeError, match="body"):
        simulate_contacts(arm, [0.9, -1.4], [1.0, 0.0], [40, 30], body=3.0)


@pytest.mark.parametrize("point, stack", [("upper arm", "head bare"),
                                          ("forearm", "head covered"),
                                          ("elbow", "face spring")])
def test_pymunk_builds_the_same_contact_point_impact(arm, point, stack):
    """The same impact from pymunk bodies, pivots and rotary springs (an independent
    integrator and joint solver; the contact force of the layers applied at the point of the
    link body): F_max and HIC36 within 1 % of the engine, as for the tool point."""
    pytest.importorskip("pymunk")
    from ppamsafety.impact.layers import series_contact
    from ppamsafety.impact.pymunk_engine import simulate_impact_pymunk

    body, cov = {"head bare": (FOREHEAD, None), "head covered": (FOREHEAD, THESIS_COVERING),
                 "face spring": (body_from_region(iso.FACE, radius=0.08), None)}[stack]
    p = {c.name: c for c in arm_contact_points(arm)}[point]
    if cov is not None:
        p = p.replace(covering=cov)
    q, qd, K = np.array([60.0, -75.0]) * DEG, np.array([2.5, -1.5]), np.array([43.0, 27.0])
    ref = simulate_contacts(arm, q, qd, K, point=p, body=body, dt=1e-5).summary.iloc[0]
    pm = simulate_impact_pymunk(arm, q, qd, K, point=p, contact=series_contact(body=body,
                                                                             point=p),
                                dt=1e-6, duration=0.03)
    assert pm.F_max == pytest.approx(ref.F_max, rel=0.01)
    assert pm.HIC36 == pytest.approx(ref.HIC36, rel=0.01)
    assert pm.joint_error_max < 1e-5
