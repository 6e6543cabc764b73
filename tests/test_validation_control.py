"""Issue 8 (control, experiments, plant): the issue's examples of implausible input are refused
with a clear message, and divergence is reported with its reason.

Each test asserts the exception type AND that the message names the argument and the rule, so a
regression to a deep traceback or a silent NaN fails.
"""

import math
import warnings

import numpy as np
import pytest

from ppamsafety.control import (PID, GravityCompensation, JointPSMC, SensorConfig,
                                SlidingModeControl, TaskPSMC)
from ppamsafety.experiments import trajectories as tr
from ppamsafety.experiments.case import ExperimentCase
from ppamsafety.experiments.closed_loop import DIVERGENCE_VELOCITY, divergence, LOG, run_batch
from ppamsafety.experiments import metrics
from ppamsafety.params import thesis_arm
from ppamsafety.plant import model
from ppamsafety.units import BAR, DEG


@pytest.fixture(scope="module")
def arm():
    return thesis_arm()


# --- step times in the wrong order, change times -----------------------------------------

def test_step_times_in_wrong_order_are_refused(arm):
    with pytest.raises(ValueError, match=r"t_down = 2 s must come after t_up = 7 s"):
        tr.step(arm, t_up=7, t_down=2)


def test_joint_steps_change_times(arm):
    lv = [[0.6, -1.4], [0.9, -1.4], [0.6, -1.4]]
    with pytest.raises(ValueError, match=r"t_changes must be strictly increasing"):
        tr.joint_steps(arm, q_levels=lv, t_changes=[2.0, 1.0], duration=3.0)
    with pytest.raises(ValueError, match=r"t_changes\[1\] = 5 s is outside \(0, duration\)"):
        tr.joint_steps(arm, q_levels=lv, t_changes=[1.0, 5.0], duration=3.0)
    with pytest.raises(ValueError, match=r"t_changes\[0\] = 0 s"):
        tr.joint_steps(arm, q_levels=lv, t_changes=[0.0, 1.0], duration=3.0)
    with pytest.raises(ValueError, match=r"one more level than change times"):
        tr.joint_steps(arm, q_levels=lv, t_changes=[1.0], duration=3.0)


def test_step_outside_the_record_is_refused(arm):
    # the short duration is what is wrong, so the message names it (issue 22 item 8)
    with pytest.raises(ValueError, match=r"^duration = 1 s is too short: the up-step comes at "
                                         r"t_up = 2 s"):
        tr.step(arm, duration=1.0)
    with pytest.raises(ValueError, match=r"low = high"):
        tr.step(arm, low=0.6, high=0.6)


def test_short_step_keeps_its_old_meaning(arm):
    """A 4 s run of the 12 s experiment: the down-step (7 s) lies beyond the record."""
    ref = tr.step(arm, duration=4.0)
    q1 = ref.signal("q1_d")
    assert ref.n_steps == 4000
    assert q1[0] == pytest.approx(30 * DEG) and q1[-1] == pytest.approx(70 * DEG)


# --- degrees passed as radians ----------------------------------------------------------------

def test_degrees_passed_to_step_get_a_hint(arm):
    with pytest.raises(ValueError, match=r"low = 30 rad .* did you mean np\.radians\(30\)"):
        tr.step(arm, low=30, high=70)
    with pytest.raises(ValueError, match=r"q2 = -80 rad .* did you mean np\.radians\(-80\)"):
        tr.step(arm, q2=-80)


def test_degrees_passed_to_joint_steps_get_a_hint(arm):
    with pytest.raises(ValueError, match=r"q_levels\[0, 0\] = 50 rad .*np\.radians\(50\)"):
        tr.joint_steps(arm, q_levels=[[50, -80]], t_changes=[], duration=1.0)


def test_levels_outside_working_area_without_hint(arm):
    with pytest.raises(ValueError) as e:
        tr.joint_steps(arm, q_levels=[[0.1, -1.0]], t_changes=[], duration=1.0)
    assert "working area of joint 1" in str(e.value) and "did you mean" not in str(e.value)


def test_circle_out_of_reach_or_area_names_center_and_radius(arm):
    with pytest.raises(ValueError, match=r"circle.*center=\(0\.9, 0\.0\).*reach"):
        tr.circle(arm, period=5.0, duration=1.0, center=(0.9, 0.0))
    with pytest.raises(ValueError, match=r"circle.*center=.*working area"):
        tr.circle(arm, period=5.0, duration=1.0, center=(0.05, 0.45), radius=0.1)


# --- gains that cannot work ---------------------------------------------------------------

def test_all_zero_psmc_gains_are_refused():
    with pytest.raises(ValueError, match=r"JointPSMC\.kp\[0\] = JointPSMC\.ki\[0\] = "
                                         r"JointPSMC\.kd\[0\] = 0.*divides by A"):
        JointPSMC(kp=0, ki=0, kd=0, lam=0)
    with pytest.raises(ValueError, match=r"TaskPSMC\.kp = TaskPSMC\.ki = TaskPSMC\.kd = 0"):
        TaskPSMC(kp=0, ki=0, kd=0)


def test_psmc_without_position_feedback_is_refused():
    with pytest.raises(ValueError, match=r"JointPSMC\.kp\[1\] = 0 and JointPSMC\.ki\[1\] = 0.*"
                                         r"no position feedback"):
        JointPSMC(kp=(2e5, 0.0), ki=(2e5, 0.0))
    with pytest.raises(ValueError, match=r"TaskPSMC\.kp = 0 and TaskPSMC\.ki = 0"):
        TaskPSMC(kp=0, ki=0, kd=10)
    with pytest.raises(ValueError, match=r"pure integrator"):
        JointPSMC(kp=0, kd=0, lam=0, ki=2e5)


def test_pid_without_feedback_is_refused():
    with pytest.raises(ValueError, match=r"PID\.kp\[0\] = 0 and PID\.ki\[0\] = 0.*no feedback"):
        PID(kp=0, ki=0, kd=0)


@pytest.mark.parametrize("cls, kw, match", [
    (PID, {"kp": -1.0}, r"PID\.kp = -1 Pa/rad is outside \[0, 1e\+09\]"),
    (PID, {"ki": (1.0, math.nan)}, r"PID\.ki\[1\] = nan"),
    (PID, {"kd": "0.1"}, r"PID\.kd must be a real number or a pair"),
    (PID, {"kp": [1, 2, 3]}, r"PID\.kp must have 2 entries"),
    (JointPSMC, {"lam": -0.4}, r"JointPSMC\.lam = -0\.4 s is outside"),
    (JointPSMC, {"dp_limit": 0.0}, r"JointPSMC\.dp_limit = 0 Pa is outside \(0"),
    (TaskPSMC, {"force_limit": 0.0}, r"TaskPSMC\.force_limit = 0 N"),
    (SlidingModeControl, {"poles": 0.0}, r"SlidingModeControl\.poles = 0 1/s is outside \(0"),
    (SlidingModeControl, {"boundary_layer": -1.0}, r"SlidingModeControl\.boundary_layer"),
    (SlidingModeControl, {"model_time_constants": [1e-4] * 4},
     r"SlidingModeControl\.model_time_constants\[0\] = 0\.0001 s is outside \[0\.001, 10\]"),
    (SlidingModeControl, {"model_links": "cad"}, r"SlidingModeControl\.model_links must be"),
    (GravityCompensation, {"at": "proxy"}, r"GravityCompensation\.at = 'proxy'"),
    (SensorConfig, {"encoder": 1}, r"SensorConfig\.encoder must be True or False"),
    (SensorConfig, {"noise_variances": (1, 2)}, r"SensorConfig\.noise_variances must have 4"),
])
def test_controller_fields_are_named(cls, kw, match):
    with pytest.raises((TypeError, ValueError), match=match):
        cls(**kw)


def test_valid_gains_unchanged():
    c = JointPSMC(lam=0.8, ki=12 * BAR)
    assert c.ki == (12 * BAR, 12 * BAR) and type(c.ki[0]) is float
    assert PID(kp=(1.0, 2.0)).kp == (1.0, 2.0)
    assert JointPSMC(lam=0.0, dp_limit=math.inf).dp_limit == (math.inf, math.inf)   # the PID limit
    with pytest.raises(ValueError, match=r"JointPSMC.dp_limit = 1e\+300 Pa is outside"):
        JointPSMC(dp_limit=1e300)                     # a limit beyond any pressure


def test_controller_step_input(arm):
    c = PID()
    ref = np.zeros(12)
    ref[:2] = (0.6, -1.4)
    with pytest.raises(ValueError, match=r"q_meas must have shape \(2,\)"):
        c.step(arm, np.zeros((3, 2)), np.zeros(2), np.zeros(4), ref)
    with pytest.raises(ValueError, match=r"qd_meas\[0\] = 1e\+300 rad/s"):
        c.step(arm, [0.6, -1.4], [1e300, 0.0], np.zeros(4), ref)
    with pytest.raises(TypeError, match=r"arm must be a"):
        c.step(None, [0.6, -1.4], [0.0, 0.0], np.zeros(4), ref)
    assert np.all(np.isfinite(c.step(arm, [0.6, -1.4], [0.0, 0.0], np.full(4, 1.5e5), ref)))


# --- valve time constant shorter than the integration step -------------------------------

def test_valve_faster_than_the_step_is_refused(arm):
    from ppamsafety.params.effects import Effects
    fast = arm.replace(effects=Effects(valve_time_constant=(2e-3,) * 4))
    case = ExperimentCase(fast, PID(), tr.step(arm, t_up=0.02, t_down=0.04, duration=0.05, dt=5e-3))
    with pytest.raises(ValueError, match=r"substeps = 1 .*h = dt/substeps = 0\.005 s.*"
                                         r"0\.002 s; use substeps >= 3"):
        run_batch([case], dt=5e-3, substeps=1)
    x0 = model.rest_state([0.6, -1.4], fast)[0]
    with pytest.raises(ValueError, match=r"valve 1 time constant 0\.002 s is below"):
        model.simulate(fast, x0, np.zeros((3, 4)), dt=5e-3, substeps=1)


# --- divergence is reported with its reason ----------------------------------------------

def test_divergence_reason_from_log():
    n = 10
    log = np.zeros((n, LOG.size))
    log[:, 0] = np.arange(n) * 1e-3
    log[6, LOG.offset("qd") + 1] = 800.0
    log[7:] = np.nan
    div, reason, t = divergence(log, True, 1e-3)
    assert div and t == pytest.approx(7e-3)
    assert f"{DIVERGENCE_VELOCITY:g} rad/s" in reason and "|qd2| = 800" in reason
    assert "t = 0.006 s and t = 0.007 s" in reason
    ok = np.zeros((n, LOG.size))
    assert divergence(ok, False, 1e-3) == (False, "", pytest.approx(np.nan, nan_ok=True))
    ok[3, LOG.offset("dp")] = np.inf          # a bad signal the kernel did not stop on
    div, reason, t = divergence(ok, False, 1e-3)
    assert div and "non-finite dp1 at t = 0.003 s" in reason and t == pytest.approx(3e-3)


def test_diverging_run_is_flagged_warned_and_tabulated(arm):
    """Allowed but unstable: huge PID gains with a 50 ms control period (RK4 blows up)."""
    from ppamsafety.params.effects import Effects
    slow = arm.replace(effects=Effects(valve_time_constant=(0.05,) * 4))
    ref = tr.step(arm, t_up=0.5, t_down=1.0, duration=3.0, dt=0.05)
    wild = PID(kp=1e9, ki=1e9, kd=1e7)
    with pytest.warns(UserWarning, match=r"case 0 'wild' diverged: joint speed reached 1000"):
        res = run_batch([ExperimentCase(slow, wild, ref, name="wild",
                                        sensors=SensorConfig.ideal())], dt=0.05)[0]
    assert res.diverged and "rad/s" in res.divergence_reason
    assert 0.5 < res.diverged_at < 3.0 and np.isnan(res.signal("q1")[-1])
    stats = metrics.tracking_stats(res)
    assert stats["diverged"] and math.isnan(stats["mean"]) and stats["divergence_reason"]


def test_valid_run_is_not_flagged(arm):
    ref = tr.step(arm, t_up=0.1, t_down=0.4, duration=0.5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = run_batch([ExperimentCase(arm, PID(), ref)])[0]
    assert not res.diverged and res.divergence_reason == "" and math.isnan(res.diverged_at)
    tab = metrics.response_table([res], experiment="step", step_times=(0.1, 0.4))
    assert list(tab.diverged) == [False] and list(tab.divergence_reason) == [""]


# --- experiment case, run_batch, metrics --------------------------------------------------

def test_case_x0_ranges(arm):
    ref = tr.step(arm, t_up=0.05, t_down=0.08, duration=0.1)
    x0 = np.r_[0.6, -1.4, 0.0, 0.0, 1e5, 1e5, 1e5, 1e5]
    x0[4] = 1e7
    with pytest.raises(ValueError, match=r"ExperimentCase\.x0\[4:8\] \(p1\.\.p4\)\[0\] = 1e\+07 Pa"):
        ExperimentCase(arm, PID(), ref, x0=x0)


def test_run_batch_arguments(arm):
    ref = tr.step(arm, t_up=0.05, t_down=0.08, duration=0.1)
    with pytest.raises(TypeError, match=r"cases must be a sequence"):
        run_batch(ExperimentCase(arm, PID(), ref))
    with pytest.raises(ValueError, match=r"substeps = 0 is outside"):
        run_batch([ExperimentCase(arm, PID(), ref)], substeps=0)
    with pytest.raises(ValueError, match=r"reference sampled at 0\.001 s but dt = 0\.002 s"):
        run_batch([ExperimentCase(arm, PID(), ref)], dt=2e-3)


def test_metric_arguments():
    t = np.arange(10) * 0.1
    with pytest.raises(ValueError, match=r"err has 3 samples, t has 10"):
        metrics.time_to_within(t, [1, 2, 3], 0.0, 0.1)
    with pytest.raises(ValueError, match=r"tol = 0 is outside"):
        metrics.settling_time(t, t, 0.0, 0.0)
    with pytest.raises(TypeError, match=r"result must be a"):
        metrics.tracking_stats("run")
