"""A user's arm: its experiments, its noise, its short records and its load, from the arm.

The arms here are written in the test as a new user writes them (the thesis template with a
few keys changed, read through ``load_arm``): a narrower joint 1 (q1_min = 40 deg, outside the
thesis step's 30 deg), noisier sensors (1e-4 rad^2), a declared payload.
"""

import math
import re
import warnings

import numpy as np
import pytest

from ppamsafety.design import arm_summary, load_arm, max_load_map
from ppamsafety.diagnose import diagnose, synthesize
from ppamsafety.diagnose.arm.pipeline import REPLAY_RHO
from ppamsafety.diagnose.arm.replay_limit import REPLAY_CALIBRATED_SECONDS, widened_limit
from ppamsafety.experiments.catalog import thesis_reference
from ppamsafety.experiments.trajectories import (CIRCLE_CENTER, CIRCLE_RADIUS, STEP_HIGH,
                                                 STEP_LOW, STEP_Q2, arm_pose,
                                                 experiment_references)
from ppamsafety.params import thesis_arm
from ppamsafety.params.sensors import TABLE_3_2_ANGLE_VARIANCES
from ppamsafety.plant import geometry as geo
from ppamsafety.sweep_cases import check_case

DEG = math.pi / 180


def _write_arm(tmp_path, name, **edits):
    """The thesis template with ``edits`` {toml key line prefix: new line}, read like a user's."""
    text = thesis_arm().to_toml().replace('name = "thesis arm"', f'name = "{name}"', 1)
    for key, line in edits.items():
        if key.startswith("["):               # append to a table
            text = text.replace(f"{key}\n", f"{key}\n{line}\n", 1)
            continue
        text, n = re.subn(rf"^{re.escape(key)} = .*$", line, text, count=1, flags=re.M)
        assert n == 1, key
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return load_arm(path)


@pytest.fixture(scope="module")
def q40(tmp_path_factory):
    return _write_arm(tmp_path_factory.mktemp("arms"), "q40",
                      q1_min='q1_min = { value = 40, unit = "deg" }')


@pytest.fixture(scope="module")
def noisy(tmp_path_factory):
    return _write_arm(tmp_path_factory.mktemp("arms"), "noisy", angle_noise_variance=(
        'angle_noise_variance = { value = [1e-4, 1e-4], unit = "rad^2" }'))


# --- 1. the experiments derive from the arm ---------------------------------------------

def test_the_thesis_arm_keeps_exactly_its_references():
    r = experiment_references(thesis_arm())
    assert r.thesis and (r.step_low, r.step_high, r.step_q2) == (30 * DEG, 70 * DEG, -80 * DEG)
    assert (r.step_low, r.step_high, r.step_q2) == (STEP_LOW, STEP_HIGH, STEP_Q2)
    assert r.circle_center == CIRCLE_CENTER and r.circle_radius == CIRCLE_RADIUS
    assert "thesis" in r.describe("step") and "30 -> 70 -> 30 deg" in r.describe("step")
    assert np.array_equal(arm_pose(thesis_arm(), np.radians([35.0, -100.0])),
                          np.radians([35.0, -100.0]))


def test_another_arm_gets_the_thesis_fractions_of_its_own_range(q40):
    g, t = q40.geometry, thesis_arm().geometry
    r = experiment_references(q40)
    assert not r.thesis
    # the thesis step sits at 10/85 and 50/85 of q1's range, q2 at the middle of q2's
    frac = lambda v, lo, hi: (v - lo) / (hi - lo)   # noqa: E731
    assert frac(r.step_low, g.q1_min, g.q1_max) == pytest.approx(
        frac(30 * DEG, t.q1_min, t.q1_max), abs=1e-12)
    assert frac(r.step_high, g.q1_min, g.q1_max) == pytest.approx(50 / 85, abs=1e-12)
    assert frac(r.step_q2, g.q2_min, g.q2_max) == pytest.approx(0.5, abs=1e-12)
    assert g.q1_min < r.step_low < r.step_high < g.q1_max
    # the sawtooth inside the working area too, and the circle placed by the arm's own kinematics
    assert min(r.sawtooth_q1) > g.q1_min and max(r.sawtooth_q1) < g.q1_max
    assert "derived from the arm's working area" in r.describe()
    # every catalogue experiment builds (the thesis' 30 deg is outside this arm)
    for name in ("step", "switch", "circle5"):
        ref = thesis_reference(q40, name, duration=8.0 if name != "switch" else 8.0)
        q = ref.signal("q1_d")
        assert q.min() >= g.q1_min - 1e-9 and q.max() <= g.q1_max + 1e-9, name
    step = thesis_reference(q40, "step", duration=3.0)
    assert set(np.round(step.signal("q1_d"), 12)) == {round(r.step_low, 12),
                                                       round(r.step_high, 12)}
    assert np.allclose(step.signal("q2_d"), r.step_q2)


def test_the_study_keys_move_the_step_and_an_impossible_one_names_the_arms_keys(q40):
    c = check_case(experiment="step", step_low_deg=45.0, step_q2_deg=-70.0, arm=q40)
    assert c["step_low_deg"] == 45.0
    with pytest.raises(ValueError, match=r"step_low_deg = 30 deg is outside the working area "
                                         r"of joint 1 of the arm \(geometry\.q1_min = 40 deg, "
                                         r"geometry\.q1_max = 105 deg\)"):
        check_case(experiment="step", step_low_deg=30.0, arm=q40)
    with pytest.raises(ValueError, match=r"step_high_deg.*apply only to experiment = 'step'"):
        check_case(experiment="circle10", step_high_deg=60.0, arm=q40)
    # the thesis arm still takes the thesis step, and no 'low' of an internal call appears
    check_case(experiment="step", arm=thesis_arm())


def test_a_sweep_case_and_a_closed_loop_record_run_on_the_arm(q40):
    """The trial's failures: sweep and synthesize --experiment closed-loop on q1_min = 40 deg."""
    from ppamsafety.sweep_cases import safety_case
    row = safety_case("step", "PSMC joint", duration=3.0, arm=q40)
    assert row["F_max"] > 0 and not row["diverged"]
    r = experiment_references(q40)
    rec = synthesize("closed-loop", seed=1, duration=3.0, arm=q40, reference="step").frame
    late = rec[rec.t > 2.5]
    # the PSMC leaves the low level toward the high one after the up-step at 2 s
    assert late.q1.mean() > r.step_low + 0.1 * (r.step_high - r.step_low)
    assert rec[rec.t < 1.9].q1.sub(r.step_low).abs().max() < 5 * DEG


def test_an_arm_whose_area_cannot_hold_the_circle_is_told_with_its_keys(tmp_path):
    narrow = _write_arm(tmp_path, "narrow",
                        q1_min='q1_min = { value = 46, unit = "deg" }',
                        q1_max='q1_max = { value = 54, unit = "deg" }',
                        q2_min='q2_min = { value = -86, unit = "deg" }',
                        q2_max='q2_max = { value = -76, unit = "deg" }',
                        max_pressure='max_pressure = { value = 6, unit = "bar" }')
    thesis_reference(narrow, "step", duration=3.0)           # the step fits any range
    with pytest.raises(ValueError) as e:
        thesis_reference(narrow, "circle10", duration=2.0)
    msg = str(e.value)
    assert "geometry.q1_min = 46 deg" in msg and "geometry.q2_max = -76 deg" in msg
    assert "cannot hold this circle" in msg and "low =" not in msg


def test_the_interaction_poses_follow_the_arm(q40):
    from ppamsafety.sections.interaction import Q_A, Q_B, Q_C
    for q in (Q_A, Q_B, Q_C):
        p = arm_pose(q40, q)
        assert bool(geo.in_working_area(p, q40)), np.degrees(p)


# --- 2. the noise is the arm's ------------------------------------------------------------

def test_the_default_noise_is_the_arms_declared_sensor_noise(noisy):
    clean = synthesize("open-loop", seed=5, duration=4.0, arm=noisy, noise="none").frame
    rec = synthesize("open-loop", seed=5, duration=4.0, arm=noisy).frame
    var = np.var(rec[["q1", "q2"]].to_numpy() - clean[["q1", "q2"]].to_numpy(), axis=0)
    # 4000 samples: the sample variance is within 10 % of 1e-4 rad^2 (sd 2.2 %)
    assert np.allclose(var, 1e-4, rtol=0.1), var
    with pytest.warns(UserWarning, match=r"noise = 'table-3.2': the thesis' Table 3.2 .*not "
                                         r"the arm's declared \[sensors\] \(q \[0.0001, 0.0001\]"):
        thesis_noise = synthesize("open-loop", seed=5, duration=4.0, arm=noisy,
                                  noise="table-3.2").frame
    var = np.var(thesis_noise[["q1", "q2"]].to_numpy() - clean[["q1", "q2"]].to_numpy(), axis=0)
    assert np.allclose(var, TABLE_3_2_ANGLE_VARIANCES, rtol=0.1), var


def test_the_closed_loop_feeds_back_the_arms_noise(noisy):
    from ppamsafety.diagnose.arm.synthesize import closed_loop_case
    case = closed_loop_case(noisy, noisy, duration=1.0, noise=True)
    assert case.sensors.noise_variances[:2] == (1e-4, 1e-4)
    case = closed_loop_case(noisy, noisy, duration=1.0, noise="table-3.2")
    assert case.sensors.noise_variances[:2] == TABLE_3_2_ANGLE_VARIANCES


def test_the_identification_record_carries_the_arms_declared_noise(noisy):
    from ppamsafety.data.synthetic import synthetic_excitation

    clean = synthetic_excitation(noisy, periods=0.4, seed=3, noise=False).frame
    rec = synthetic_excitation(noisy, periods=0.4, seed=3).frame
    d = rec[["q1", "q2", "qd1", "qd2"]].to_numpy() - clean[["q1", "q2", "qd1", "qd2"]].to_numpy()
    # 4000 samples: each sample variance within 10 % of the arm's declared one (sd 2.2 %)
    assert np.allclose(np.var(d[:, :2], axis=0), 1e-4, rtol=0.1)
    assert np.allclose(np.var(d[:, 2:], axis=0), noisy.sensors.velocity_noise_variances,
                       rtol=0.1)


def test_the_thesis_arm_records_are_unchanged_by_the_arm_noise():
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # the thesis arm declares Table 3.2: no warning
        a = synthesize("open-loop", seed=2, duration=1.0).frame
        b = synthesize("open-loop", seed=2, duration=1.0, noise="table-3.2").frame
    assert a.equals(b)


# --- 3. clean short records are explained ---------------------------------------------------

def test_the_widened_limit_is_the_calibrated_one_from_the_calibrated_length():
    assert widened_limit(REPLAY_RHO, 50.0, REPLAY_CALIBRATED_SECONDS) == REPLAY_RHO
    assert widened_limit(REPLAY_RHO, 50.0, 20.0) == REPLAY_RHO
    assert widened_limit(REPLAY_RHO, 50.0, 4.0) == pytest.approx(math.sqrt(4.0 + 25.0))
    assert widened_limit(REPLAY_RHO, 0.0, 0.5) == REPLAY_RHO


def test_the_calibrated_length_is_the_batteries_shortest_record():
    from ppamsafety.diagnose.scenarios import random_scenario
    shortest = min(sc.duration for sc in (random_scenario(s) for s in range(200))
                   if sc.duration is not None and sc.kind != "static-sawtooth")
    assert REPLAY_CALIBRATED_SECONDS <= shortest < REPLAY_CALIBRATED_SECONDS + 1.0


@pytest.mark.parametrize("which,seed", [("q40", 1), ("q40", 3), ("q40", 4), ("thesis", 3)])
def test_clean_records_of_the_minimum_length_are_explained(q40, which, seed):
    """0.5 s, nothing hidden: the trial's false 'unexplained' (replay qd2 2.08 > 2)."""
    arm = q40 if which == "q40" else thesis_arm()
    d = diagnose(synthesize("open-loop", seed=seed, duration=0.5, arm=arm), arm=arm)
    rp = d.settings["replay"]
    assert not any(c.startswith("replay") for c in d.unexplained_channels), rp
    assert rp["start_spread"] is not None and rp["calibrated_seconds"] == 8.0
    assert all(rp["limits"][c] > REPLAY_RHO for c in ("q2", "qd2"))


def test_a_record_of_the_calibrated_length_keeps_the_calibrated_limit(q40):
    d = diagnose(synthesize("open-loop", seed=1, duration=8.0, arm=q40), arm=q40)
    rp = d.settings["replay"]
    assert rp["start_spread"] is None and set(rp["limits"].values()) == {REPLAY_RHO}


def test_a_short_record_still_shows_what_the_replay_exists_for():
    """A velocity sensor reading 20 % low leaves the block channels at the noise; the replay
    of a 2 s record still calls it unexplained."""
    d = diagnose(synthesize("open-loop", {"velocity_sensor_gain": -0.2}, seed=62000,
                            duration=2.0))
    assert d.unexplained and any(c.startswith("replay qd") for c in d.unexplained_channels)


# --- 4. the maximum load says what it counts ------------------------------------------------

def test_the_maximum_load_says_it_counts_the_declared_payload(tmp_path):
    paid = _write_arm(tmp_path, "paid", **{"[effects]": 'payload_mass = { value = 250, unit = '
                                                         '"g" }'})
    table = arm_summary(paid, n=9).to_pandas().set_index("quantity")["value"]
    total = table["maximum load at A_L, min over the working area"]
    assert total == pytest.approx(max_load_map(paid, n1=18, n2=18).minimum)
    assert table["  of which the declared payload_mass"] == pytest.approx(0.25)
    assert table["  left beyond the declared payload (min)"] == pytest.approx(total - 0.25)
    bare = arm_summary(thesis_arm(), n=9).to_pandas().set_index("quantity")["value"]
    assert bare["  of which a declared payload"] == "none declared"
    # the payload is a point mass at A_L: the map (links only) is the same with or without it
    assert bare["maximum load at A_L, min over the working area"] == pytest.approx(total)


# --- the default impact and summary pose ----------------------------------------------------

def test_the_default_impact_pose_follows_the_arm(tmp_path):
    from ppamsafety.sweep_cases import IMPACT_POSE_DEG, impact_case, impact_pose_deg

    assert impact_pose_deg() == IMPACT_POSE_DEG == (50.0, -80.0)   # thesis §6.3.3, exactly
    arm = _write_arm(tmp_path, "q55", q1_min='q1_min = { value = 55, unit = "deg" }')
    pose = impact_pose_deg(arm)
    # q1 at the thesis fraction (50 - 20) / (105 - 20) of the arm's range [55, 105] deg
    assert pose[0] == pytest.approx(55.0 + (50.0 - 20.0) / 85.0 * 50.0, abs=1e-9)
    assert pose[1] == pytest.approx(-80.0, abs=1e-9)
    # the thesis pose (50 deg) lies outside this arm's area: the default still runs
    row = impact_case(1.0, arm=arm)
    assert row["F_max"] > 0.0 and row["tcp_speed"] == pytest.approx(1.0, rel=1e-6)
    with pytest.raises(ValueError, match="outside the arm's working area"):
        impact_case(1.0, q1_deg=50.0, q2_deg=-80.0, arm=arm)
    assert arm_summary(arm, n=11).pose[0] == pytest.approx(pose[0] * DEG, abs=1e-9)
