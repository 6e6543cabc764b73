"""Rigid-body dynamics (Appendix B): structure, energy, regressor."""

import math

import numpy as np
import pytest

from ppamsafety.plant import dynamics as dyn
from ppamsafety.plant import model, torque

RNG = np.random.default_rng(20260101)


def test_inertia_matrix_symmetric_positive_definite(arm, workspace_grid):
    H = dyn.inertia_matrix(workspace_grid, arm)
    np.testing.assert_array_equal(H, np.swapaxes(H, -1, -2))
    assert np.all(np.linalg.eigvalsh(H) > 0)


def test_identified_model_is_not_positive_definite(arm, workspace_grid):
    """SPEC §1.4: the identified Table 3.5 inertias are inconsistent (why the plant has its own)."""
    H = dyn.inertia_matrix(workspace_grid, arm, params=arm.model)
    assert np.any(np.linalg.eigvalsh(H)[:, 0] < 0)


def test_Hdot_minus_2C_is_skew_symmetric(arm, workspace_grid):
    q = workspace_grid
    qd = RNG.normal(size=q.shape)
    h = 1e-6
    Hdot = (dyn.inertia_matrix(q + h * qd, arm) - dyn.inertia_matrix(q - h * qd, arm)) / (2 * h)
    N = Hdot - 2 * dyn.coriolis(q, qd, arm)
    np.testing.assert_allclose(N, -np.swapaxes(N, -1, -2), atol=1e-9)


def test_gravity_is_gradient_of_potential(arm, workspace_grid):
    q = workspace_grid
    h = 1e-6
    for j in range(2):
        e = np.eye(2)[j] * h
        num = (dyn.potential_energy(q + e, arm) - dyn.potential_energy(q - e, arm)) / (2 * h)
        np.testing.assert_allclose(dyn.gravity(q, arm)[:, j], num, rtol=1e-8, atol=1e-9)


@pytest.mark.parametrize("which", ["plant", "model"])
def test_regressor_times_theta_equals_equations_of_motion(arm, which):
    """K(q, qd, qdd) theta = H qdd + C qd + G + c sgn(qd) + b qd  (B.5)-(B.6)."""
    params = arm.plant_base if which == "plant" else arm.model
    n = 200
    q = RNG.uniform([0.3, -2.2], [1.8, -0.5], size=(n, 2))
    qd = RNG.normal(scale=2.0, size=(n, 2))
    qdd = RNG.normal(scale=5.0, size=(n, 2))
    theta = np.concatenate([params.as_vector(), params.coulomb, params.viscous])
    lhs = dyn.regressor(q, qd, qdd, arm) @ theta
    H = dyn.inertia_matrix(q, arm, params=params)
    C = dyn.coriolis(q, qd, arm, params=params)
    rhs = (np.einsum("nij,nj->ni", H, qdd) + np.einsum("nij,nj->ni", C, qd)
           + dyn.gravity(q, arm, params=params) + dyn.friction(qd, arm, params=params,
                                                               smooth=False))
    np.testing.assert_allclose(lhs, rhs, rtol=1e-12, atol=1e-12)


def test_numpy_api_broadcasts_and_equals_the_regressor_oracle(arm):
    """H/C/G/friction of the NumPy API (the kernels) vs the independent regressor (B.5)-(B.6),
    with q, qd, qdd broadcast against each other."""
    q = RNG.uniform([0.3, -2.2], [1.8, -0.5], size=(7, 1, 2))
    qd = RNG.normal(scale=2.0, size=(5, 2))
    qdd = RNG.normal(scale=5.0, size=(2,))
    p = arm.plant_base
    theta = np.concatenate([p.as_vector(), p.coulomb, p.viscous])
    lhs = dyn.regressor(q, qd, qdd, arm) @ theta
    H = dyn.inertia_matrix(q, arm)
    C = dyn.coriolis(q, qd, arm)
    assert H.shape == (7, 1, 2, 2) and C.shape == (7, 5, 2, 2)
    rhs = (H @ qdd + np.einsum("...ij,...j->...i", C, qd) + dyn.gravity(q, arm)
           + dyn.friction(qd, arm, smooth=False))
    np.testing.assert_allclose(lhs, rhs, rtol=1e-12, atol=1e-12)


def test_smooth_friction_is_tanh_coulomb_plus_viscous(arm):
    """(3.30) with the plant's smooth Coulomb term c tanh(qd / v_s)."""
    qd = np.array([[0.0, 0.0], [0.003, -0.02], [1.5, -2.0]])
    c, b = np.array(arm.plant_base.coulomb), np.array(arm.plant_base.viscous)
    expected = c * np.tanh(qd / arm.friction_velocity) + b * qd
    np.testing.assert_allclose(dyn.friction(qd, arm), expected, rtol=1e-14, atol=1e-15)
    np.testing.assert_array_equal(dyn.friction(qd, arm, smooth=False)[0], [0.0, 0.0])
    with pytest.raises(TypeError, match="smooth"):
        dyn.friction(qd, arm, smooth="yes")


def _conservative_arm(arm):
    """No gravity, no friction, all valves closed (sealed polytropic muscles)."""
    links = arm.links.replace(coulomb=(0.0, 0.0), viscous=(0.0, 0.0))
    valves = arm.valves.with_time_constants([math.inf] * 4)
    return arm.replace(gravity=0.0, links=links, valves=valves)


def _total_energy(X, arm):
    """Kinetic + gas energy: sum P V/(n-1) + P_atm V conserved for closed valves."""
    q, qd, p = X[:, :2], X[:, 2:4], X[:, 4:]
    n, patm = arm.pneumatics.polytropic_n, arm.pneumatics.p_atm
    V = torque.group_volumes(q, arm)
    gas = ((patm + p) * V / (n - 1) + patm * V).sum(axis=1)
    return dyn.kinetic_energy(q, qd, arm) + gas, dyn.kinetic_energy(q, qd, arm)


def test_free_motion_conserves_energy(arm):
    """No gravity/friction, closed valves: energy conserved to 1e-6 relative over 2 s."""
    a = _conservative_arm(arm)
    x0, u = model.rest_state(np.radians([50, -80]), arm)
    x0[2:4] = [2.0, -3.0]                       # fling the arm
    X = model.simulate(a, x0, np.tile(u, (2000, 1)), dt=1e-3, substeps=4)
    E, KE = _total_energy(X, a)
    assert KE.max() - KE.min() > 0.2 * KE[0]    # energy really is exchanged with the gas
    assert np.abs(E - E[0]).max() / E[0] < 1e-6
    # the exchanged part (kinetic) is resolved to 1e-6 of the kinetic energy as well
    assert np.abs(E - E[0]).max() / KE[0] < 1e-5
