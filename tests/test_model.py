"""The assembled plant ODE: equilibrium, batching, integrator convergence."""

import numpy as np
import pytest

from ppamsafety.plant import model, packing
from ppamsafety.units import BAR


def test_rest_state_is_an_equilibrium(arm, workspace_grid):
    from ppamsafety.plant.pneumatics import static_pressures

    p = static_pressures(workspace_grid, arm)
    feasible = np.all((p >= 0) & (p <= arm.pneumatics.p_max), axis=1)
    assert feasible.sum() > 0.4 * len(feasible)
    for q in workspace_grid[feasible][::11]:
        x0, u = model.rest_state(q, arm)
        dx = model.state_derivative(x0, u, arm)
        np.testing.assert_allclose(dx, 0.0, atol=1e-9)


def _step_inputs(arm, n=3000):
    x0, u = model.rest_state(np.radians([50, -80]), arm)
    U = np.tile(u, (n, 1))
    U[500:, 0] += 0.4 * BAR
    U[500:, 3] -= 0.3 * BAR
    return x0, U


def test_batch_rows_equal_single_runs(arm):
    x0, U = _step_inputs(arm)
    slow = arm.replace(valves=arm.valves.with_time_constants([0.1, 0.1, 0.1, 0.1]))
    single = [model.simulate(a, x0, U) for a in (arm, slow)]
    batch = model.simulate([arm, slow], np.stack([x0, x0]), U)
    assert batch.shape == (2, U.shape[0] + 1, 8)
    np.testing.assert_array_equal(batch[0], single[0])
    np.testing.assert_array_equal(batch[1], single[1])
    assert np.abs(single[0] - single[1]).max() > 1e-3      # variants differ


def test_fixed_step_rk4_converges(arm):
    """1 kHz with one RK4 step per period agrees with 16 sub-steps to < 1e-6 rad."""
    x0, U = _step_inputs(arm)
    coarse = model.simulate(arm, x0, U, substeps=1)
    fine = model.simulate(arm, x0, U, substeps=16)
    assert np.abs(coarse[:, :2] - fine[:, :2]).max() < 1e-6
    assert np.abs(coarse[:, 4:] - fine[:, 4:]).max() < 1.0          # Pa
    assert np.abs(fine[-1, :2] - x0[:2]).max() > 0.05                # it moved


def test_state_derivative_broadcasts(arm):
    x0, U = _step_inputs(arm)
    X = np.stack([x0, x0 + 0.01])
    dx = model.state_derivative(X, U[0], arm)
    assert dx.shape == (2, 8)


def test_rest_state_rejects_unreachable_configuration(arm):
    weak = arm.replace(pneumatics=arm.pneumatics.replace(p_max=0.1 * BAR,
                                                         p_mean=(0.05 * BAR, 0.05 * BAR)))
    with pytest.raises(ValueError, match="outside"):
        model.rest_state(np.radians([30, -80]), weak)


def test_simulate_validates_inputs(arm):
    x0, U = _step_inputs(arm, 10)
    with pytest.raises(ValueError, match="set_values"):
        model.simulate(arm, x0, U[:, :3])
    with pytest.raises(ValueError, match="dt"):
        model.simulate(arm, x0, U, dt=-1.0)
    bad = U.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        model.simulate(arm, x0, bad)


# --- effect state z (issue 7, item 2) ------------------------------------------------------

def test_explicit_zero_effect_state_equals_the_default(arm):
    x0, U = _step_inputs(arm, 400)
    default = model.simulate(arm, x0, U)
    X, z = model.simulate(arm, x0, U, effect_state=np.zeros(0), return_effect_state=True)
    np.testing.assert_array_equal(X, default)
    assert z.shape == (0,)                       # every effect off: empty effect state


def test_effect_state_is_sized_per_row_and_untouched_with_effects_off(arm):
    """Rows may ask for different z lengths; with no effect on, z and x are unaffected."""
    x0, U = _step_inputs(arm, 400)
    default = model.simulate(arm, x0, U)
    rows = np.stack([packing.with_effects(packing.pack(arm), effect_state_length=3),
                     packing.with_effects(packing.pack(arm), effect_state_length=1)])
    np.testing.assert_array_equal(packing.effect_state_lengths(rows), [3, 1])
    z0 = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    X, z = model.simulate(None, np.stack([x0, x0]), U, params=rows, effect_state=z0,
                          return_effect_state=True)
    np.testing.assert_array_equal(X[0], default)
    np.testing.assert_array_equal(X[1], default)
    np.testing.assert_array_equal(z, z0)
    with pytest.raises(ValueError, match="effect_state"):
        model.simulate(None, x0, U, params=rows[0], effect_state=np.zeros(2))


def test_effect_parameters_are_validated(arm):
    from ppamsafety.plant import layout as lay

    P = packing.pack(arm)
    assert lay.PLANT.read(P, "effect_state_length") == 0.0           # all effects off
    for bad in (-1, 2.5, True, "3"):
        with pytest.raises(ValueError, match="effect_state_length"):
            packing.with_effects(P, effect_state_length=bad)
    with pytest.raises(KeyError, match="no field"):
        packing.with_effects(P, hysteresis=1)
    row = np.array(P)
    row[lay.NZ] = 0.5
    x0, U = _step_inputs(arm, 10)
    with pytest.raises(ValueError, match="effect_state_length"):
        model.simulate(None, x0, U, params=row)
