"""Controllers: PSMC/PID equivalence, limits, the discrete PSMC equations, SMC cancellation."""

import math

import numpy as np
import pytest

from ppamsafety.control import (PID, GravityCompensation, JointPSMC, SensorConfig,
                                SlidingModeControl, TaskPSMC)
from ppamsafety.control.reference import NREF
from ppamsafety.experiments import closed_loop as cl
from ppamsafety.experiments.case import ExperimentCase
from ppamsafety.experiments import trajectories as tr
from ppamsafety.units import BAR, DEG

T = 1e-3


def _random_inputs(n=3000, seed=3):
    """Measurement/reference sequences for open-loop controller comparisons."""
    rng = np.random.default_rng(seed)
    q = np.radians([50, -80]) + np.cumsum(rng.normal(scale=2e-3, size=(n, 2)), axis=0)
    qd = rng.normal(scale=0.5, size=(n, 2))
    p = np.tile([1.7e5, 1.5e5, 1.3e5, 2.1e5], (n, 1))
    ref = np.zeros((n, NREF))
    ref[:, 0:2] = np.radians([55, -75]) + 0.1 * np.sin(np.arange(n)[:, None] * 2e-3)
    ref[:, 2:4] = 0.2 * np.cos(np.arange(n)[:, None] * 2e-3)
    return q, qd, p, ref


def test_default_gains_are_table_5_1_in_si():
    assert PID().kp == (2.0 * BAR, 1.5 * BAR) and PID().kd == (0.1 * BAR, 0.1 * BAR)
    j = JointPSMC()
    assert j.lam == (0.4, 0.4) and j.dp_limit == (0.2 * BAR, 0.2 * BAR) and j.ki == (2e5, 2e5)
    t = TaskPSMC()
    assert (t.kp, t.ki, t.kd, t.force_limit, t.lam) == (200.0, 100.0, 10.0, 15.0, 0.4)


def test_psmc_with_zero_lambda_and_infinite_limit_is_discrete_pid(arm):
    """§5.2.6.4 (Kikuuwe & Fujimoto 2006): lambda = 0, F -> inf gives discrete PID
    (backward-Euler integral, backward-difference derivative), step for step."""
    q, qd, p, ref = _random_inputs()
    psmc = JointPSMC(lam=0.0, dp_limit=math.inf)
    pid = PID(derivative="difference")
    for k in range(q.shape[0]):
        a = psmc.step(arm, q[k], qd[k], p[k], ref[k])
        b = pid.step(arm, q[k], qd[k], p[k], ref[k])
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-6)     # Pa


def test_psmc_zero_lambda_closed_loop_equals_pid(arm):
    ref = tr.step(arm, duration=4.0)
    runs = cl.run_batch([ExperimentCase(arm, c, ref, sensors=SensorConfig.ideal())
                         for c in (JointPSMC(lam=0.0, dp_limit=math.inf),
                                   PID(derivative="difference"))])
    state = ("q1", "q2", "qd1", "qd2", "p1", "p2", "p3", "p4")
    np.testing.assert_allclose(runs[0].signals(*state), runs[1].signals(*state), rtol=1e-7,
                               atol=1e-7)


@pytest.mark.parametrize("controller, saturates", [(JointPSMC(), True),
                                                   (JointPSMC(ki=12 * BAR, lam=1.5), False)])
def test_joint_psmc_output_never_exceeds_limit_and_satisfies_5_19_5_20(arm, controller,
                                                                       saturates):
    """|Delta p_psmc| <= Delta p_lm, and (5.19)-(5.20) hold at every step."""
    ref = tr.step(arm)
    res = cl.run(arm, controller, ref)
    df = res.to_pandas()
    lim = np.array(controller.dp_limit)
    for j in range(2):
        f = df[f"dp_psmc{j + 1}"].to_numpy()
        a = df[f"a{j + 1}"].to_numpy()
        assert np.all(np.abs(f) <= lim[j] * (1 + 1e-12))
        if j == 0 and saturates:                                    # the q1 step saturates
            assert np.any(np.abs(f) >= lim[j] * (1 - 1e-12))
        kp, ki, kd, lam = (controller.kp[j], controller.ki[j], controller.kd[j],
                           controller.lam[j])
        ap = np.concatenate([[0.0, 0.0], a])
        da = ap[2:] - ap[1:-1]
        d2a = ap[2:] - 2 * ap[1:-1] + ap[:-2]
        # (5.20): f = Kp Na/T + Ki a + Kd N^2 a / T^2
        np.testing.assert_allclose(kp * da / T + ki * a + kd * d2a / T ** 2, f,
                                   rtol=1e-6, atol=1e-6 * lim[j])
        # (5.19): f = F sgn(s) with s = sigma - Na/T - lambda N^2 a/T^2
        q, qd = df[f"q{j + 1}_meas"].to_numpy(), df[f"qd{j + 1}_meas"].to_numpy()
        sigma = (df[f"q{j + 1}_d"] - q) + lam * (df[f"qd{j + 1}_d"] - qd)
        s = sigma.to_numpy() - da / T - lam * d2a / T ** 2
        inside = np.abs(f) < lim[j] * (1 - 1e-9)
        assert np.abs(s[inside]).max() < 1e-7
        assert np.all(s[~inside] * f[~inside] >= -1e-12)
        assert inside.mean() > 0.5


def test_task_psmc_force_never_exceeds_limit(arm):
    ref = tr.trajectory_switch(arm, duration=10.0)
    c = TaskPSMC(lam=0.05)             # small lambda: the 20 cm jump needs more than F
    df = cl.run(arm, c, ref).to_pandas()
    fn = np.hypot(df.fx, df.fy)
    assert fn.max() <= c.force_limit * (1 + 1e-12)
    assert fn.max() >= c.force_limit * (1 - 1e-9)           # the switch saturates it
    off = df.on_surface < 0.5
    assert np.all(np.abs(df.f_star_norm[off]) > c.force_limit)


def test_psmc_recovers_slower_with_larger_lambda(arm):
    """Large errors recover at the rate set by lambda (§5.2.6.3)."""
    ref = tr.step(arm, duration=7.0)
    runs = cl.run_batch([ExperimentCase(arm, JointPSMC(lam=lam), ref) for lam in (0.4, 0.8, 1.5)])
    t_reach = []
    for r in runs:
        df = r.to_pandas()
        reached = df.t[(df.t > 2.0) & (df.q1 > 60 * DEG)]
        t_reach.append(reached.iloc[0] - 2.0)
    assert t_reach[0] < t_reach[1] < t_reach[2]


def test_reset_restores_initial_state(arm):
    q, qd, p, ref = _random_inputs(200)
    c = JointPSMC()
    first = [c.step(arm, q[k], qd[k], p[k], ref[k]) for k in range(200)]
    assert np.any(c.state != 0)
    c.reset()
    assert np.all(c.state == 0)
    again = [c.step(arm, q[k], qd[k], p[k], ref[k]) for k in range(200)]
    np.testing.assert_array_equal(first, again)


def test_gravity_compensation_alone_settles_near_the_set_angles(arm):
    """Static gravity compensation (3.18)-(3.19) with the identified model (Table 3.1) as
    feedforward at the set angles: the arm settles close to them (the thesis' sawtooth
    validation, fig. 3.1, had RMS errors of 2.47 and 2.06 deg on the real arm)."""
    ref = tr.joint_steps(arm, q_levels=[[50 * DEG, -80 * DEG]], t_changes=[], duration=3.0)
    df = cl.run(arm, GravityCompensation(), ref).to_pandas()
    err = np.degrees(np.abs(df[["q1", "q2"]].to_numpy() - [50 * DEG, -80 * DEG]))
    assert np.all(err[-500:] < 5.0)
    assert np.all(np.abs(np.degrees(df[["qd1", "qd2"]].to_numpy()[-500:])) < 0.5)


def test_smc_cancels_the_modelled_dynamics(arm):
    """MIMO feedback linearisation on the exact nominal model, ideal sensors:
    ds/dt = -K sat(s/Gamma), i.e. reaching at rate K, then exponential decay
    with rate K/Gamma inside the boundary layer (eqs. (4.35)-(4.41))."""
    K, G = 20.0, 2.0
    smc = SlidingModeControl(poles=8.0, gain=K, boundary_layer=G, coupling="mimo")
    q_goal = np.array([55 * DEG, -75 * DEG])
    ref = tr.joint_steps(arm, q_levels=[q_goal], t_changes=[], duration=2.0)
    from ppamsafety.plant.model import rest_state
    x0 = rest_state(np.radians([53, -77]), arm)[0]
    df = cl.run(arm, smc, ref, sensors=SensorConfig.ideal(), x0=x0).to_pandas()
    t = df.t.to_numpy()
    for j in (1, 2):
        s = df[f"s{j}"].to_numpy()
        s0 = s[0]
        assert abs(s0) > G                               # starts outside the layer
        t_in = (abs(s0) - G) / K                         # reaching time at rate K
        k_in = np.argmax(np.abs(s) <= G)
        assert t[k_in] == pytest.approx(t_in, abs=0.02)
        later = (t > t[k_in]) & (t < t[k_in] + 0.3)
        predicted = s[k_in] * np.exp(-K / G * (t[later] - t[k_in]))
        np.testing.assert_allclose(s[later], predicted, atol=0.03 * G)


def test_controller_parameter_validation():
    with pytest.raises(ValueError, match="JointPSMC.lam"):
        JointPSMC(lam=-1.0)
    with pytest.raises(ValueError, match="TaskPSMC.force_limit"):
        TaskPSMC(force_limit=0.0)
    with pytest.raises(ValueError, match="derivative"):
        PID(derivative="both")
    with pytest.raises(ValueError, match="coupling"):
        SlidingModeControl(coupling="none")
    with pytest.raises(ValueError, match="boundary_layer"):
        SlidingModeControl(boundary_layer=0.0)
