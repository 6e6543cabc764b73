"""The dense-output impact integrator (engine.impact_batch_dense, integrator="dense").

Accuracy criterion: F_max, HIC36 and HIC15 within 2e-4 relative of the fixed-step
reference engine and of solve_ivp (RK45, rtol 1e-10, atol 1e-13, sampled on the same
20 us grid) -- the same criterion the fixed-step engine meets against solve_ivp.
"""

import sys
import pathlib

import numpy as np
import pytest

from ppamsafety.impact.model import simulate_impacts
from ppamsafety.impact.reference import simulate_impact_scipy
from ppamsafety.params import thesis_arm

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "benchmarks"))
from bench_impact import cases  # noqa: E402


@pytest.fixture(scope="module")
def arm():
    return thesis_arm()


def test_dense_matches_the_fixed_step_engine_on_random_impacts(arm):
    q, qd, K = cases(600, seed=11)
    a = simulate_impacts(arm, q, qd, K).summary
    b = simulate_impacts(arm, q, qd, K, integrator="dense").summary
    hit = a.F_max > 1.0
    assert hit.sum() > 500
    for c in ("F_max", "HIC36", "HIC15", "delta_max"):
        np.testing.assert_allclose(b[c][hit], a[c][hit], rtol=2e-4, atol=0)
    np.testing.assert_allclose(b.E_balance_error, 0.0, atol=1e-4)    # energy still balances
    assert np.all(b.F_max >= 0) and np.all(np.isfinite(b.select_dtypes("number").to_numpy()))
    assert set(b.status) <= {"ok", "at rest"}


def test_dense_matches_solve_ivp_at_tight_tolerance(arm):
    q, qd, K = cases(8, seed=5)
    b = simulate_impacts(arm, q, qd, K, integrator="dense").summary
    for i in range(len(q)):
        ref = simulate_impact_scipy(arm, q[i], qd[i], K[i], rtol=1e-10, atol=1e-13)
        for c in ("F_max", "HIC36", "HIC15"):
            assert b[c][i] == pytest.approx(ref[c], rel=2e-4)


def test_dense_with_history_uses_the_fixed_engine(arm):
    q, qd, K = cases(3, seed=2)
    a = simulate_impacts(arm, q, qd, K, history=[1])
    b = simulate_impacts(arm, q, qd, K, history=[1], integrator="dense")
    assert b.summary.loc[1].equals(a.summary.loc[1])         # recorded case: bitwise the same
    np.testing.assert_array_equal(b.signal("F", 1), a.signal("F", 1))


def test_integrator_is_validated(arm):
    with pytest.raises(ValueError, match="integrator"):
        simulate_impacts(arm, [0.5, -1.0], [1.0, 1.0], [40.0, 20.0], integrator="rk45")
