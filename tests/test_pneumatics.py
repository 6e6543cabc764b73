"""Valves, Delta-p approach, stiffness (2.18) and the mean-pressure calibration."""

import numpy as np
import pytest

from ppamsafety.params.pneumatics import CALIBRATED_P_MEAN
from ppamsafety.plant import pneumatics as pn
from ppamsafety.plant import torque
from ppamsafety.units import BAR


def _closed_valve_torque(q, q0, p0, arm):
    """Joint torques with every valve closed: P V^n = const per group (3.3)."""
    n = arm.pneumatics.polytropic_n
    patm = arm.pneumatics.p_atm
    v0 = torque.group_volumes(q0, arm)
    v = torque.group_volumes(q, arm)
    p = (patm + p0) * (v0 / v) ** n - patm
    mt = torque.torque_functions(q, arm)
    return np.stack([p[..., 0] * mt[..., 0] + p[..., 1] * mt[..., 1],
                     p[..., 2] * mt[..., 2] + p[..., 3] * mt[..., 3]], axis=-1)


@pytest.mark.parametrize("q0_deg", [(50, -80), (30, -80), (70, -80), (95, -40), (25, -120)])
def test_stiffness_equals_finite_difference_of_closed_valve_torque(arm, q0_deg):
    """K_j of (2.18) with dp/dq of (3.4) equals -d tau_j/dq_j under closed valves."""
    q0 = np.radians(q0_deg)
    p0 = pn.static_pressures(q0, arm)
    K = pn.joint_stiffness(q0, p0, arm)
    h = 1e-4
    for j in range(2):
        e = np.eye(2)[j] * h
        tp = _closed_valve_torque(q0 + e, q0, p0, arm)[j]
        tm = _closed_valve_torque(q0 - e, q0, p0, arm)[j]
        assert K[j] == pytest.approx(-(tp - tm) / (2 * h), rel=1e-6)


def test_stiffness_includes_the_polytropic_term(arm, step_config):
    """Without the dp/dq terms the stiffness is much lower (closed valves stiffen)."""
    p = pn.static_pressures(step_config, arm)
    K = pn.joint_stiffness(step_config, p, arm)
    mt, dmt = torque.torque_functions(step_config, arm, with_derivative=True)
    k_geometric = np.array([-(p[0] * dmt[0] + p[1] * dmt[1]), -(p[2] * dmt[2] + p[3] * dmt[3])])
    assert np.all(K > 1.3 * k_geometric)


def test_calibrated_mean_pressures_reproduce_the_thesis_stiffness(arm, step_config):
    """§6.3.3: K1 ~ 43, K2 ~ 27 Nm/rad at the step-response impact instant."""
    K = pn.joint_stiffness(step_config, pn.static_pressures(step_config, arm), arm)
    np.testing.assert_allclose(K, [43.0, 27.0], rtol=0.01)
    pm = pn.calibrate_mean_pressures(arm)
    np.testing.assert_allclose(pm, CALIBRATED_P_MEAN, atol=0.002 * BAR)


def test_static_valve_model_round_trip(arm):
    p = np.array([0.5, 1.0, 1.5, 2.5]) * BAR
    u = pn.valve_set_values(p, arm)
    np.testing.assert_allclose(pn.valve_pressure(u, arm), p, rtol=1e-12)
    # (3.12) with Table B.2: a set value of 1 bar on valve 1 gives 0.0447 + 0.9933 bar
    assert pn.valve_pressure(np.full(4, BAR), arm)[0] == pytest.approx(1.038 * BAR)


def test_commanded_pressures_are_clipped(arm):
    u = pn.valve_set_values(np.array([-1.0, 0.5, 3.5, 10.0]) * BAR, arm)
    assert u.min() >= 0 and u.max() <= arm.pneumatics.p_max
    p = pn.delta_p_pressures(np.array([5 * BAR, -5 * BAR]), arm)
    assert p.min() == 0.0 and p.max() == arm.pneumatics.p_max


def test_gravity_compensation_balances_gravity(arm, workspace_grid):
    """(3.18)-(3.19): with exact parameters the Delta-p pressures cancel G(q)."""
    from ppamsafety.plant import dynamics

    q = workspace_grid
    p = pn.static_pressures(q, arm)
    mt = torque.torque_functions(q, arm)
    tau = np.stack([p[:, 0] * mt[:, 0] + p[:, 1] * mt[:, 1],
                    p[:, 2] * mt[:, 2] + p[:, 3] * mt[:, 3]], -1)
    np.testing.assert_allclose(tau, dynamics.gravity(q, arm), rtol=1e-10, atol=1e-10)


def test_calibration_rejects_unreachable_targets(arm):
    with pytest.raises(ValueError, match="not reachable"):
        pn.calibrate_mean_pressures(arm, target_stiffness=(5000.0, 27.0))
