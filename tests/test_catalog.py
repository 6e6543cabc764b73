"""Named thesis experiments and variants, and the response metrics."""

import numpy as np
import pytest

from ppamsafety.control import PID, JointPSMC, SensorConfig, TaskPSMC
from ppamsafety.experiments import catalog, metrics
from ppamsafety.units import BAR, DEG


def test_variants_are_table_6_1_in_order_with_si_gains():
    v = catalog.thesis_variants()
    assert all(isinstance(x, catalog.ControllerVariant) for x in v)
    labels = [x.label for x in v]
    assert labels == ["PID",
                      "PSMC joint Ki=2 λ=0.4", "PSMC joint Ki=2 λ=0.8", "PSMC joint Ki=2 λ=1.5",
                      "PSMC joint Ki=12 λ=0.4", "PSMC joint Ki=12 λ=0.8", "PSMC joint Ki=12 λ=1.5",
                      "PSMC task λ=0.4", "PSMC task λ=0.8", "PSMC task λ=1.5"]
    pid = v[0].controller
    assert isinstance(pid, PID)
    assert pid.kp == (2 * BAR, 1.5 * BAR) and pid.ki == (2 * BAR, 2 * BAR)
    assert pid.kd == (0.1 * BAR, 0.1 * BAR)
    for i, (ki, lam) in enumerate([(2, 0.4), (2, 0.8), (2, 1.5), (12, 0.4), (12, 0.8), (12, 1.5)]):
        c = v[1 + i].controller
        assert (v[1 + i].family, v[1 + i].ki_bar, v[1 + i].lambda_s) == (
            catalog.Family.PSMC_JOINT, ki, lam)
        assert isinstance(c, JointPSMC)
        assert c.ki == (ki * BAR, ki * BAR) and c.lam == (lam, lam)
        assert c.kp == (2 * BAR, 1.5 * BAR) and c.kd == (0.1 * BAR, 0.1 * BAR)
        assert c.dp_limit == (0.2 * BAR, 0.2 * BAR)
        assert c.gravity_compensation == "proxy"
    for i, lam in enumerate((0.4, 0.8, 1.5)):
        c = v[7 + i].controller
        assert v[7 + i].family is catalog.Family.PSMC_TASK and v[7 + i].lambda_s == lam
        assert np.isnan(v[7 + i].ki_bar)
        assert isinstance(c, TaskPSMC)
        assert (c.kp, c.ki, c.kd, c.force_limit, c.lam) == (200.0, 100.0, 10.0, 15.0, lam)
    groups = ["PID"] + ["PSMC joint Ki=2"] * 3 + ["PSMC joint Ki=12"] * 3 + ["PSMC task"] * 3
    assert [catalog.variant_family(x.controller) for x in v] == groups
    assert [x.group for x in v] == groups
    assert (v[0].family, v[0].ki_bar) == (catalog.Family.PID, 2.0) and np.isnan(v[0].lambda_s)
    label, ctrl = v[4]                      # old (label, controller) unpacking still works
    assert label == "PSMC joint Ki=12 λ=0.4" and ctrl is v[4].controller


def test_references_of_the_named_experiments(arm):
    for name in catalog.EXPERIMENTS:
        ref = catalog.thesis_reference(arm, name)
        assert ref.duration == pytest.approx(catalog.DEFAULT_DURATIONS[name])
    step = catalog.thesis_reference(arm, "step")
    k = np.searchsorted(step.t, catalog.STEP_TIMES)
    q1_d = step.signal("q1_d")
    np.testing.assert_allclose(q1_d[[k[0] - 1, k[0], k[1]]], np.radians([30, 70, 30]))
    np.testing.assert_allclose(step.signal("q2_d"), -80 * DEG)
    c10 = catalog.thesis_reference(arm, "circle10", duration=10.0)
    r = c10.field("r_d")
    np.testing.assert_allclose(np.hypot(*(r - r.mean(axis=0)).T), 0.10, atol=1e-6)
    with pytest.raises(ValueError, match="unknown thesis experiment"):
        catalog.thesis_reference(arm, "circle7")
    with pytest.raises(ValueError, match="must exceed"):
        catalog.thesis_reference(arm, "switch", duration=5.0)


def test_run_thesis_experiment_is_one_labelled_batch(arm):
    v = catalog.thesis_variants()[:2] + catalog.thesis_variants()[-1:]
    res = catalog.run_thesis_experiment(arm, "step", v, duration=3.0,
                                        sensors=SensorConfig.ideal())
    assert [r.meta["label"] for r in res] == [x.label for x in v]
    assert [r.meta["family"] for r in res] == ["PID", "PSMC joint Ki=2", "PSMC task"]
    assert [r.meta["controller_family"] for r in res] == ["PID", "PSMC joint", "PSMC task"]
    assert [r.meta["variant"] for r in res] == v
    assert res[1].meta["ki_bar"] == 2.0 and np.isnan(res[2].meta["ki_bar"])
    assert np.isnan(res[0].meta["lambda_s"]) and res[2].meta["lambda_s"] == 1.5
    assert all(r.log.shape[0] == 3000 and not r.diverged for r in res)
    with pytest.raises(ValueError, match="pairs"):
        catalog.run_thesis_experiment(arm, "step", [PID()], duration=3.0)


def test_time_to_within_and_settling_time():
    t = np.arange(0, 10, 0.01)
    err = np.where(t < 2, 1.0, np.exp(-(t - 2)))           # event at t = 2
    err[(t > 6) & (t < 6.5)] = 0.5                          # a later excursion
    assert metrics.time_to_within(t, err, 2.0, 0.1) == pytest.approx(np.log(10), abs=0.011)
    assert metrics.settling_time(t, err, 2.0, 0.1) == pytest.approx(4.5, abs=0.011)
    assert np.isnan(metrics.time_to_within(t, err, 2.0, 1e-9))
    assert np.isnan(metrics.settling_time(t, np.ones_like(t), 2.0, 0.1))
    with pytest.raises(ValueError, match="tol"):
        metrics.time_to_within(t, err, 2.0, 0.0)


def test_chattering_index_measures_only_the_high_frequencies():
    dt = 1e-3
    t = np.arange(0, 4, dt)
    slow = np.stack([np.sin(2 * np.pi * 0.25 * t), np.cos(2 * np.pi * 0.5 * t)], 1)
    fast = np.stack([0.3 * np.sin(2 * np.pi * 50 * t), np.zeros_like(t)], 1)
    assert metrics.chattering_index(slow, dt) < 1e-10
    assert metrics.chattering_index(slow + fast, dt) == pytest.approx(0.3 / np.sqrt(2), rel=1e-6)
    assert metrics.command_increment_rms(np.zeros((10, 2))) == 0.0
    with pytest.raises(ValueError, match="dp"):
        metrics.chattering_index(np.zeros(10), dt)


def test_step_metrics_and_response_table(arm):
    v = [("PID", PID()), ("PSMC joint Ki=2 λ=0.4", JointPSMC())]
    res = catalog.run_thesis_experiment(arm, "step", v, duration=7.0)
    tab = metrics.response_table(res, experiment="step")
    assert list(tab.variant) == ["PID", "PSMC joint Ki=2 λ=0.4"]
    pid, psmc = tab.iloc[0], tab.iloc[1]
    assert pid.overshoot_pct > 10 > psmc.overshoot_pct
    assert pid.peak_tcp_speed_m_s > 2 * psmc.peak_tcp_speed_m_s
    assert pid.t90_s < psmc.t90_s
    sm = metrics.step_metrics(res[0], t_event=2.0, t_end=7.0)
    assert sm["step"] == pytest.approx(40 * DEG)
    with pytest.raises(ValueError, match="does not step"):
        metrics.step_metrics(res[0], t_event=3.0, t_end=7.0)
    with pytest.raises(ValueError, match="experiment"):
        metrics.response_table(res, experiment="circle")


def test_experiment_result_plot_returns_a_figure(arm):
    import matplotlib.figure

    res = catalog.run_thesis_experiment(arm, "step", [("PID", PID())], duration=2.5)
    fig = res[0].plot(t_range=(0.0, 2.5))
    assert isinstance(fig, matplotlib.figure.Figure) and len(fig.axes) == 3
    import matplotlib.pyplot as plt
    plt.close(fig)
