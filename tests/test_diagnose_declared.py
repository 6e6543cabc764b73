"""The diagnosis starts from the arm it is given: declared effects, the replay, a forgotten --arm.

The model under test is the arm, its declared ``[effects]`` included: a record made with
nothing hidden names nothing; a candidate is named only where the record asks for a change
from the declared value, and reports the declared value beside the fitted one; the "after"
replay is the fitted model; "unexplained: no" needs that replay at the noise; and a record
that names another arm is refused unless the comparison is asked for.  Every arm here is
one of the test's own (the thesis arm with effects declared), not the shipped example.
"""

import math
from dataclasses import replace

import numpy as np
import pytest

from ppamsafety.cli import main
from ppamsafety.data import load_measured
from ppamsafety.data.measured import MeasuredData
from ppamsafety.diagnose import diagnose, synthesize
from ppamsafety.diagnose.arm.pipeline import REPLAY_RHO, after_row
from ppamsafety.diagnose.arm.residuals import (arm_record, block_system, declared_torque,
                                               model_vector)
from ppamsafety.diagnose.arm.synthesize import plant_with
from ppamsafety.diagnose.core.result import Estimate
from ppamsafety.params import thesis_arm
from ppamsafety.params.arm_file import arm_fingerprint
from ppamsafety.plant import layout as lay
from ppamsafety.plant import packing


def _arm(name, **effects):
    """The thesis arm with ``effects`` declared in its [effects] (an arm of the test's own)."""
    a = thesis_arm()
    return a.replace(effects=replace(a.effects, **effects), name=name)


HYST = _arm("test arm: 40-fibre muscles", hysteresis_delta=(0.25,) * 4)
FRICTION = _arm("test arm: stiff bearings", friction_coulomb=(0.4, 0.25))


def _strip(data):
    """The record without its [arm] metadata (a measured file that names no arm)."""
    return MeasuredData({k: v for k, v in data.meta.items() if k != "arm"}, data.frame,
                        source=data.source)


def _summary(dg):
    return {e.name: {p: (d.value, d.nominal) for p, d in e.parameters.items()}
            for e in dg.effects}


@pytest.fixture(scope="module")
def hyst_record():
    return synthesize("closed-loop", {}, seed=11, duration=6.0, arm=HYST)


def test_declared_hysteresis_with_nothing_hidden_names_nothing(hyst_record):
    dg = diagnose(hyst_record, arm=HYST, seed=11)
    assert dg.names == () and not dg.partial and not dg.confounded, _summary(dg)
    assert not dg.unexplained, dg.unexplained_channels
    # the replay of the model under test (its hysteresis included) is at the noise
    assert max(dg.settings["replay"]["rho"].values()) <= REPLAY_RHO


def test_without_the_declared_line_the_hysteresis_is_named_at_the_declared_delta(hyst_record):
    bare = _arm("test arm: 40-fibre muscles, hysteresis line removed")
    # the record names HYST: the comparison with another arm is asked for on purpose
    dg = diagnose(hyst_record, arm=bare, seed=11, allow_other_arm=True)
    assert dg.names == ("hysteresis",), _summary(dg)
    d = dg.effects[0].parameters["delta"]
    assert d.nominal == 0.0
    assert abs(d.value - 0.25) < 0.01 and d.ci_low <= 0.25 <= d.ci_high, d
    # ... and the mismatch heads the result
    assert dg.warnings and "record came from arm 'test arm: 40-fibre muscles'" in dg.warnings[0]
    assert dg.report_markdown().splitlines()[2].startswith("> **Warning:** the record came")


def test_a_hidden_dead_time_beside_declared_hysteresis_names_only_the_dead_time():
    rec = synthesize("closed-loop", {"valve_dead_time": 0.02}, seed=12, duration=6.0, arm=HYST)
    dg = diagnose(rec, arm=HYST, seed=12)
    assert dg.names == ("valve_dead_time",), _summary(dg)
    d = dg.effects[0].parameters["d"]
    assert d.nominal == 0.0 and abs(d.value - 0.02) <= 0.0025, d


def test_declared_friction_plus_hidden_extra_friction_names_the_extra():
    hidden = (1.2, 0.25)                         # joint 1 three times the declared 0.4 N m
    rec = synthesize("open-loop", {"friction_coulomb_factor": (3.0, 1.0)}, seed=13,
                     duration=8.0, arm=FRICTION)
    assert plant_with(FRICTION, {"friction_coulomb_factor": (3.0, 1.0)})[0] \
        .effects.friction_coulomb == pytest.approx(hidden)
    dg = diagnose(rec, arm=FRICTION, seed=13)
    assert dg.names == ("joint_friction",), _summary(dg)
    p = dg.effects[0].parameters
    # the declared friction is the nominal value; the fit says how much more there is
    assert p["c1"].nominal == pytest.approx(0.4) and p["c2"].nominal == pytest.approx(0.25)
    assert p["c1"].ci_low > 0.4 and abs(p["c1"].value - 1.2) < 0.25, p["c1"]
    # nothing hidden on that arm: nothing named (its own friction is not "missing")
    dg0 = diagnose(synthesize("open-loop", {}, seed=13, duration=8.0, arm=FRICTION),
                   arm=FRICTION, seed=13)
    assert dg0.names == () and not dg0.unexplained, _summary(dg0)


def test_declared_dead_time_and_payload_are_the_nominal_values():
    arm = _arm("test arm: slow valves, a tool", valve_dead_time=(15,) * 4, payload_mass=0.3)
    rec0 = synthesize("closed-loop", {}, seed=14, duration=6.0, arm=arm)
    dg0 = diagnose(rec0, arm=arm, seed=14)
    assert dg0.names == () and not dg0.unexplained, _summary(dg0)
    # a hidden heavier tool and a longer dead time: the change is named, the declared
    # values stated beside the fitted ones
    rec = synthesize("closed-loop", {"payload_mass": 0.6, "valve_dead_time": 0.025}, seed=14,
                     duration=6.0, arm=arm)
    dg = diagnose(rec, arm=arm, seed=14)
    assert set(dg.names) == {"payload", "valve_dead_time"}, _summary(dg)
    s = _summary(dg)
    assert s["payload"]["M"][1] == pytest.approx(0.3)
    assert abs(s["payload"]["M"][0] - 0.6) < 0.05
    assert s["valve_dead_time"]["d"][1] == pytest.approx(0.015)
    assert abs(s["valve_dead_time"]["d"][0] - 0.025) <= 0.0025


def test_declared_valves_and_polytropic_exponent_are_the_model():
    t = tuple(1.5 * v.time_constant for v in thesis_arm().valves.valves)
    arm = _arm("test arm: long tubes", valve_time_constant=t, polytropic_n=1.2,
               valve_offset=(6000.0, 2000.0, 4000.0, 1000.0))
    dg0 = diagnose(synthesize("open-loop", {}, seed=19, duration=8.0, arm=arm), arm=arm,
                   seed=19)
    assert dg0.names == () and not dg0.unexplained, _summary(dg0)
    # the valves are slower still than declared: the lag is named, the declared time
    # constants beside the fitted ones
    rec = synthesize("open-loop", {"valve_time_constant_factor": 1.6}, seed=19, duration=8.0,
                     arm=arm)
    dg = diagnose(rec, arm=arm, seed=19)
    assert dg.names == ("valve_lag",), _summary(dg)
    p = dg.effects[0].parameters
    for i in range(4):
        d = p[f"T_{i + 1}"]
        assert d.nominal == pytest.approx(t[i])
        assert abs(d.value / (1.6 * t[i]) - 1) < 0.1, d


def test_declared_torque_bias_enters_the_equations_and_the_static_replay():
    arm = _arm("test arm: a cable", joint_torque_bias=(0.5, -0.3))
    data = synthesize("static-sawtooth", {}, seed=15, duration=40.0, arm=arm)
    dg = diagnose(data, arm=arm, seed=15)
    assert dg.names == () and not dg.confounded and not dg.unexplained, _summary(dg)
    # the rest angles of the model with the cable's torque reproduce the record
    rr = dg.residual_rms
    assert rr["q1"]["after"] < 0.2 * rr["q1"]["noise"] and rr["q2"]["after"] < 0.2 * \
        rr["q2"]["noise"]
    # the torque the arm declares is that bias (and none without it)
    q = np.zeros((5, 2)) + [0.8, -1.2]
    assert np.allclose(declared_torque(q, np.zeros((5, 4)) + 1e5, arm), [0.5, -0.3])
    assert declared_torque(q, np.zeros((5, 4)) + 1e5, thesis_arm()) is None


def test_the_fitted_model_is_the_replayed_model(hyst_record):
    # a change of the declared hysteresis: the replay's row holds the declared arm changed
    # by the fit, i.e. exactly the model vector and delta whose residuals were judged
    rec = synthesize("closed-loop", {"hysteresis_delta": 0.15, "payload_mass": 0.3}, seed=16,
                     duration=6.0, arm=HYST)
    dg = diagnose(rec, arm=HYST, seed=16)
    assert set(dg.names) == {"hysteresis", "payload"}, _summary(dg)
    delta = dg.effects[dg.names.index("hysteresis")].parameters["delta"]
    assert delta.nominal == pytest.approx(0.25) and abs(delta.value - 0.15) < 0.01
    assert max(dg.settings["replay"]["rho"].values()) <= REPLAY_RHO and not dg.unexplained


def test_after_row_carries_the_declared_effects_changed_by_the_fit():
    arm = _arm("test arm: row", hysteresis_delta=(0.2, 0.3, 0.2, 0.3), valve_dead_time=(10,) * 4,
               joint_torque_bias=(0.1, 0.0))

    class Fit:                               # a fit of a hysteresis change and a dead time
        names = ("hysteresis", "valve_dead_time")
        shift = -4
        mu = model_vector(packing.pack(arm))

    delta = Estimate(value=0.3, unit="-", ci_low=0.29, ci_high=0.31, std_error=0.005,
                     nominal=0.25)
    row = after_row(arm, Fit, {"hysteresis": {"delta": delta}})
    # the common change +0.05 from the declared mean 0.25 on every group's own delta
    assert np.allclose(lay.PLANT.read(row, "hysteresis_delta"), [0.25, 0.35, 0.25, 0.35])
    assert np.array_equal(lay.PLANT.read(row, "dead_time"), [6, 6, 6, 6])
    assert np.allclose(lay.PLANT.read(row, "torque_bias"), [0.1, 0.0])
    assert np.allclose(model_vector(row), Fit.mu)


def test_synthesize_keeps_the_declared_effects_under_hidden_ones():
    plant, dead, _ = plant_with(HYST, {"payload_mass": 0.35})
    assert plant.effects.hysteresis_delta == (0.25,) * 4 and plant.effects.payload_mass == 0.35
    plant, _, _ = plant_with(HYST, {"hysteresis_delta": 0.1})        # a hidden change of it
    assert plant.effects.hysteresis_delta == (0.1,) * 4
    arm = _arm("test arm: dead time", valve_dead_time=(15,) * 4)
    plant, dead, _ = plant_with(arm, {"valve_dead_time": 0.03})     # replaces the declared
    assert plant.effects.valve_dead_time is None and dead == 0.03
    plant, dead, _ = plant_with(arm, {"payload_mass": 0.2})
    assert plant.effects.valve_dead_time == (15,) * 4 and dead == 0.0


def test_block_equations_hold_the_declared_hysteresis():
    # noise-free record of the declared arm: its block residual is zero only when the
    # declared hysteresis is in the model under test
    data = synthesize("open-loop", {}, seed=17, duration=3.0, arm=HYST, noise="none")
    rec, _ = arm_record(data)
    bare = _arm("bare")
    r = {}
    for name, a in (("declared", HYST), ("bare", bare)):
        bs = block_system(rec, a)
        r[name] = np.abs(bs.y - bs.X @ model_vector(packing.pack(a)))[:, 4:].max()
    assert r["declared"] < 0.02 * r["bare"], r


def test_the_replay_gate_flags_an_error_the_block_residuals_miss():
    # a velocity sensor reading 20 % low is outside the library; the block equations absorb
    # it (every block channel at the noise) but the replay of qd2 is far above it
    rec = synthesize("open-loop", {"velocity_sensor_gain": -0.2}, seed=5, duration=6.0)
    dg = diagnose(rec, seed=5)
    blocks = [v["after"] for k, v in dg.residual_rms.items() if k.startswith("block_")]
    assert max(blocks) < 1.5
    assert dg.unexplained and "replay qd2" in dg.unexplained_channels
    assert dg.settings["replay"]["rho"]["qd2"] > 5 * REPLAY_RHO
    assert not any(e.confidence_level == "high" for e in dg.effects)
    assert any("replay of the fitted model" in n for n in dg.notes)


def test_a_record_of_another_arm_is_refused_in_python():
    data = synthesize("open-loop", {}, seed=18, duration=2.0, arm=FRICTION)
    with pytest.raises(ValueError) as exc:
        diagnose(data)
    msg = str(exc.value)
    fp = arm_fingerprint(FRICTION)
    assert "'test arm: stiff bearings'" in msg and fp[:16] in msg
    assert "'thesis arm'" in msg and arm_fingerprint(thesis_arm())[:16] in msg
    assert "allow_other_arm=True" in msg
    with pytest.raises(TypeError, match="allow_other_arm"):
        diagnose(data, arm=FRICTION, allow_other_arm="yes")
    # the same record without the arm it names: nothing to check
    assert diagnose(_strip(data)).warnings == ()


def test_forgotten_arm_on_the_command_line(tmp_path, capsys):
    arm_file = tmp_path / "my_arm.toml"
    arm_file.write_text(HYST.to_toml())
    rec = tmp_path / "rec.csv"
    assert main(["synthesize", "--arm", str(arm_file), "--duration", "2", "--seed", "3",
                 "--out", str(rec)]) == 0
    capsys.readouterr()
    out = tmp_path / "dg"
    assert main(["diagnose", str(rec), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("ppamsafety: error: ")
    fp = arm_fingerprint(HYST)
    assert "'test arm: 40-fibre muscles'" in err[0] and fp[:16] in err[0]
    assert "--arm FILE" in err[0] and "--allow-other-arm" in err[0]
    assert not out.exists()
    # on purpose: the mismatch stands first, in the summary and in diagnosis.md
    assert main(["diagnose", str(rec), "--out", str(out), "--allow-other-arm"]) == 0
    cap = capsys.readouterr()
    assert cap.out.splitlines()[0].startswith("WARNING: the record came from arm 'test arm: "
                                              "40-fibre muscles'")
    md = (out / "diagnosis.md").read_text().splitlines()
    assert md[2].startswith("> **Warning:** the record came from arm")
    # with the right arm: no warning, nothing named (the declared hysteresis is the model)
    assert main(["diagnose", str(rec), "--out", str(tmp_path / "dg2"), "--arm",
                 str(arm_file)]) == 0
    cap = capsys.readouterr()
    assert "WARNING" not in cap.out and "no effect named" in cap.out
    # --allow-other-arm where the arms agree changes nothing: refused
    assert main(["diagnose", str(rec), "--out", str(tmp_path / "dg3"), "--arm", str(arm_file),
                 "--allow-other-arm"]) == 2
    assert "--allow-other-arm" in capsys.readouterr().err
    assert load_measured(rec).meta["arm"]["sha256"] == fp


def test_reported_parameters_state_the_declared_value(tmp_path, capsys):
    arm_file = tmp_path / "a.toml"
    arm_file.write_text(HYST.to_toml())
    rec = tmp_path / "rec.csv"
    assert main(["synthesize", "--arm", str(arm_file), "--duration", "4", "--seed", "4",
                 "--effect", "hysteresis_delta=0.1", "--out", str(rec)]) == 0
    assert main(["diagnose", str(rec), "--out", str(tmp_path / "dg"), "--arm",
                 str(arm_file)]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("effect hysteresis"))
    assert "(declared 0.25)" in line
    assert math.isclose(float(line.split("delta = ")[1].split()[0]), 0.1, abs_tol=0.015)
