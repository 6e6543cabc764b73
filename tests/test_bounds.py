"""Rigorous impact bounds (impact.bounds) and the pruned every-instant scan (instants.worst_instant)."""

import dataclasses

import numpy as np
import pytest

from ppamsafety.experiments.catalog import run_thesis_experiment, thesis_variants
from ppamsafety.impact.engine import DENSE_FREE_STRIDE, FREE_STRIDE
from ppamsafety.impact.bounds import MASS_GRID, _min_eig_mass, impact_bounds, min_effective_mass
from ppamsafety.impact.instants import SCREEN_MARGIN, evaluate_experiment, worst_instant
from ppamsafety.impact.model import effective_mass, simulate_impacts
from ppamsafety.params import thesis_arm
from ppamsafety.impact.head import head_model
from ppamsafety.plant.geometry import jacobian
from ppamsafety.units import DEG


@pytest.fixture(scope="module")
def arm():
    return thesis_arm()


def _random_cases(n, seed):
    rng = np.random.default_rng(seed)
    q = np.stack([rng.uniform(-180, 180, n), rng.uniform(-170, 170, n)], 1) * DEG
    qd = rng.normal(scale=rng.choice([0.3, 2.0, 6.0], size=(n, 1)), size=(n, 2))
    # tool speeds up to 6 m/s: faster impacts would pass through the softer test heads,
    # which simulate_impacts refuses as implausible (issue 8)
    v = np.linalg.norm(np.einsum("nij,nj->ni", jacobian(q, thesis_arm()), qd), axis=1)
    qd = qd * np.minimum(1.0, 6.0 / np.maximum(v, 1e-12))[:, None]
    K = np.stack([rng.uniform(5, 120, n), rng.uniform(3, 80, n)], 1)
    return q, qd, K


@pytest.mark.parametrize("head_kw", [{}, {"stiffness": 2e5, "damping": 0.0},
                                     {"exponent": 1.0, "stiffness": 3e4, "damping": 2e4},
                                     {"mass": 1.0, "radius": 0.03}])
def test_bounds_exceed_simulated_values_on_random_impacts(arm, head_kw):
    """1500 random impacts per head: the a-priori bounds are never below the simulation."""
    head = dataclasses.replace(head_model(), **head_kw)
    q, qd, K = _random_cases(1500, seed=len(head_kw))
    s = simulate_impacts(arm, q, qd, K, head=head).summary
    fb, hb = impact_bounds(arm, q, qd, head=head)
    _, h15 = impact_bounds(arm, q, qd, head=head, window=0.015)
    assert np.all(fb >= s.F_max) and np.all(hb >= s.HIC36) and np.all(h15 >= s.HIC15)
    assert np.all(np.isfinite(fb)) and s.F_max.max() > 10.0      # the cases do hit hard
    # and they are bounds worth having: within a factor 10 for F_max at the median
    assert np.median(fb / np.maximum(s.F_max, 1e-12)) < 10.0
    # the screening of worst_instant: dense-output values x (1 + margin) bound the exact ones
    d = simulate_impacts(arm, q, qd, K, head=head, integrator="dense").summary
    for c in ("F_max", "HIC36"):
        assert np.all(d[c] * (1.0 + SCREEN_MARGIN) >= s[c]), c


@pytest.mark.parametrize("speed", [1e-3, 2e-2, 0.3])
def test_screening_bounds_slow_and_stiff_impacts(arm, speed):
    """Adversarial states for the screening margin: slow tools (long, soft contacts), joint
    stiffness at the engine's limit, arm near the stretched/folded singularities."""
    from ppamsafety.impact.model import stiffness_limit
    rng = np.random.default_rng(int(speed * 1e3))
    n = 400
    q = np.stack([rng.uniform(-np.pi, np.pi, n),
                  rng.choice([0.05, 3.09, -0.05, -3.09, -1.2], n) + rng.normal(0, 0.02, n)], 1)
    qd = rng.normal(size=(n, 2))
    v = np.linalg.norm(np.einsum("nij,nj->ni", jacobian(q, arm), qd), axis=1)
    qd *= (speed / np.maximum(v, 1e-12))[:, None]
    # half at the dense integrator's own limit (its free-flight step), half beyond it up to
    # the fixed engine's (those take the fixed engine: identical values)
    lim = np.where(np.arange(n) % 2 == 0, stiffness_limit(q, arm, DENSE_FREE_STRIDE * 2e-5),
                   stiffness_limit(q, arm, FREE_STRIDE * 2e-5))
    K = lim[:, None] * rng.uniform(0.05, 0.999, (n, 2))
    with pytest.warns(UserWarning):            # outside the working area
        s = simulate_impacts(arm, q, qd, K).summary
    with pytest.warns(UserWarning):
        d = simulate_impacts(arm, q, qd, K, integrator="dense").summary
    hit = s.F_max > 0
    assert hit.sum() > n / 2
    for c in ("F_max", "HIC36", "HIC15"):
        assert np.all(d[c] * (1.0 + SCREEN_MARGIN) >= s[c]), c
        # the margin is generous: the largest deviation is far below it
        assert np.max(np.abs(d[c][hit] / s[c][hit] - 1.0)) < SCREEN_MARGIN / 10
    stiff = (K.max(axis=1) > stiffness_limit(q, arm, DENSE_FREE_STRIDE * 2e-5))
    assert stiff.sum() > n / 3
    np.testing.assert_array_equal(d.F_max[stiff], s.F_max[stiff])


def test_bounds_hold_with_a_moving_head(arm):
    head = head_model()
    q, qd, K = _random_cases(800, seed=7)
    vh = np.random.default_rng(8).normal(scale=1.0, size=(800, 2))
    s = simulate_impacts(arm, q, qd, K, head=head, head_velocity=vh).summary
    fb, hb = impact_bounds(arm, q, qd, head=head, head_velocity=vh)
    assert np.all(fb >= s.F_max) and np.all(hb >= s.HIC36)


def test_min_effective_mass_is_below_a_finer_grid_and_every_direction(arm):
    m = min_effective_mass(arm)
    fine = _min_eig_mass(np.linspace(-np.pi, np.pi, 10 * MASS_GRID + 7), arm).min()
    assert m <= fine
    rng = np.random.default_rng(3)
    q = rng.uniform(-np.pi, np.pi, size=(2000, 2))
    u = rng.normal(size=(2000, 2))
    assert np.all(effective_mass(q, u, arm) >= m)


def test_bounds_grow_with_speed_and_validate_inputs(arm):
    head = head_model()
    q = np.array([[0.8, -1.2]] * 3)
    fb, hb = impact_bounds(arm, q, np.array([[0.5, 0.5], [1.0, 1.0], [2.0, 2.0]]), head=head)
    assert np.all(np.diff(fb) > 0) and np.all(np.diff(hb) > 0)
    with pytest.raises(ValueError, match="duration"):
        impact_bounds(arm, q, q, head=head, duration=-1.0)
    with pytest.raises(ValueError, match="window"):
        impact_bounds(arm, q, q, head=head, window=0.0)
    with pytest.raises(ValueError, match="grid"):
        min_effective_mass(arm, grid=5)


def test_worst_instant_finds_the_same_worst_cases_as_the_full_scan(arm):
    label, ctrl = thesis_variants()[0]
    res = run_thesis_experiment(arm, "step", [(label, ctrl)])[0]
    full = evaluate_experiment(res, arm, instants="all", every=3, min_speed=1e-3).summary
    w = worst_instant(res, arm, every=3, min_speed=1e-3)
    assert len(w.table) == len(full)
    assert w.n_simulated + w.n_pruned == len(full) and w.n_simulated < len(full) / 4
    for metric, row in (("F_max", w.worst_F), ("HIC36", w.worst_HIC)):
        i = full[metric].idxmax()
        assert row[metric] == full.loc[i, metric] and row.t0 == full.loc[i, "t0"]
        assert row.HIC15 == full.loc[i, "HIC15"]
    t = w.table
    sim = t.simulated.to_numpy()
    np.testing.assert_array_equal(t.F_max[sim], full.F_max[sim])    # simulated rows: same values
    assert t.F_max[~sim].isna().all()
    # every pruned instant has a bound (or a screening value with its margin) below the best:
    # it cannot be the worst
    scr = t.screened.to_numpy()
    assert w.n_screened == scr.sum() and w.n_screened < len(full) / 4
    up_f = np.where(scr, t.F_screen * (1 + SCREEN_MARGIN), t.F_bound)
    up_h = np.where(scr, t.HIC36_screen * (1 + SCREEN_MARGIN), t.HIC36_bound)
    assert np.all((up_f[~sim] < w.worst_F.F_max) & (up_h[~sim] < w.worst_HIC.HIC36))
    assert np.all(t.F_bound >= full.F_max) and np.all(t.HIC36_bound >= full.HIC36)
    assert np.all(up_f[scr] >= full.F_max[scr]) and np.all(up_h[scr] >= full.HIC36[scr])
    # without screening: the same worst rows
    w2 = worst_instant(res, arm, every=3, min_speed=1e-3, screen=False)
    assert w2.n_screened == 0 and w2.worst_F.equals(w.worst_F) and w2.worst_HIC.equals(w.worst_HIC)


def test_worst_instant_rejects_bad_arguments(arm):
    label, ctrl = thesis_variants()[0]
    res = run_thesis_experiment(arm, "step", [(label, ctrl)])[0]
    with pytest.raises(ValueError, match="chunk"):
        worst_instant(res, arm, chunk=0)
    with pytest.raises(TypeError, match="head"):
        worst_instant(res, arm, head=3.0)
    with pytest.raises(TypeError, match="screen"):
        worst_instant(res, arm, screen="yes")
