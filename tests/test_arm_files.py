"""Arm and head files (issue 21.1): exact round trip, validation by dotted key, units, changes."""

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ppamsafety.impact.head import (CHECK_NAMES, HeadContactModel, head_model, head_model_names,
                                    load_head, resolve_head)
from ppamsafety.design import load_arm
from ppamsafety.params import ArmParameters, is_thesis_arm, thesis_arm
from ppamsafety.params.arm import SOURCE_PARTS
from ppamsafety.params.arm_file import (ARM_FORMAT, TABLES, ArmFileError, apply_arm_changes,
                                        arm_fingerprint, arm_parameter_paths, arm_to_dict,
                                        arm_to_toml, effects_from_dict)
from ppamsafety.params.effects import Effects

ROOT = Path(__file__).parent.parent
EXAMPLE = ROOT / "examples" / "arms" / "forty_fibre_heavy_forearm.toml"


def test_thesis_arm_round_trips_exactly_with_name_and_sources():
    arm = thesis_arm()
    for comments in (True, False):
        text = arm.to_toml(comments=comments)
        back = ArmParameters.from_toml(text)
        assert back == arm and is_thesis_arm(back)
        assert back.name == arm.name and back.sources == arm.sources
        assert back.to_toml(comments=comments) == text          # a fixed point
    assert arm_fingerprint(ArmParameters.from_toml(arm.to_toml())) == arm_fingerprint(arm)


def test_every_table_and_key_of_the_file_is_written():
    data = tomllib.loads(thesis_arm().to_toml(comments=False))
    assert data["format"] == ARM_FORMAT
    for path, keys in TABLES.items():
        if path == "effects":
            continue                                 # only the effects that are on
        table = data
        for part in path.split(".") if path else ():
            table = table[part]
        for k in keys:
            assert k.key in table, f"{path}.{k.key}"
            if k.unit is not None:
                assert table[k.key]["unit"] == k.unit       # explicit SI units


finite = dict(allow_nan=False, allow_infinity=False)


@st.composite
def arms(draw):
    """Arms whose floats take arbitrary bit patterns inside valid ranges (and effects on)."""
    ch = {"links.m2": draw(st.floats(0.8, 1.6, **finite)),
          "links.IG1": draw(st.floats(0.005, 0.05, **finite)),
          "pneumatics.mean_pressure": [draw(st.floats(0.5e5, 2.5e5, **finite)) for _ in "ab"],
          "muscles.group2.l0": draw(st.floats(0.055, 0.065, **finite)),
          "valves.valve3.time_constant": draw(st.one_of(st.just(math.inf),
                                                        st.floats(1e-3, 10.0, **finite))),
          "model.coulomb": [draw(st.floats(0.0, 1.0, **finite)) for _ in "ab"],
          "sensors.dead_band": draw(st.floats(0.0, 1.0, **finite)),
          "gravity": draw(st.floats(0.0, 30.0, **finite))}
    if draw(st.booleans()):
        ch["effects.hysteresis_delta"] = [draw(st.floats(0.0, 1.0, **finite)) for _ in "abcd"]
        ch["effects.hysteresis_initial"] = draw(st.sampled_from(
            ["negative", "positive", [-1.0, 0.25, -0.5]]))
    if draw(st.booleans()):
        ch["effects.valve_dead_time"] = [draw(st.integers(0, 100)) for _ in "abcd"]
        ch["effects.payload_mass"] = draw(st.floats(0.0, 5.0, **finite))
    name = draw(st.text(max_size=20))
    source = draw(st.text(max_size=40))
    return apply_arm_changes(thesis_arm(), ch).replace(
        name=name, sources=(("links", source),) if source else ())


@settings(max_examples=40, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(arm=arms())
def test_any_arm_round_trips_exactly(arm):
    text = arm_to_toml(arm)
    back = ArmParameters.from_toml(text)
    assert back == arm
    assert back.name == arm.name and back.sources == arm.sources
    assert back.effects.hysteresis_initial == arm.effects.hysteresis_initial
    assert arm_to_toml(back) == text


def _edit(old, new):
    text = thesis_arm().to_toml()
    assert old in text, old
    return text.replace(old, new, 1)


@pytest.mark.parametrize("old, new, words", [
    ('l0 = { value = 0.06, unit = "m" }', 'l0 = { value = -0.1, unit = "m" }',
     ["muscles.group1.l0 = -0.1 m", "must be in (0, 1] m"]),
    ("count = 3", "count = 0", ["muscles.group2.count = 0", "[1, 20]"]),
    ("count = 4", "count = 4.5", ["muscles.group1.count = 4.5", "integer"]),
    ("count = 4", "cnt = 4", ["unknown key muscles.group1.cnt", "'count'"]),
    ("[sensors]", "[sensor]", ["unknown key or table 'sensor'", "'sensors'"]),
    ('gravity = { value = 9.81, unit = "m/s^2" }', 'gravity = { value = 99, unit = "m/s^2" }',
     ["gravity = 99 m/s^2", "[0, 30]"]),
    ('l0 = { value = 0.06, unit = "m" }', "l0 = 0.06",
     ["muscles.group1.l0 = 0.06", "with its unit", 'unit = "m"']),
    ('l0 = { value = 0.06, unit = "m" }', 'l0 = { value = 6, unit = "inch" }',
     ["muscles.group1.l0 unit = 'inch'", "'m'", "'mm'"]),
    ("mean_pressure = { value = [165800.0, 176200.0], unit = \"Pa\" }",
     "mean_pressure = { value = [1.6, 4.0], unit = \"bar\" }",
     ["pneumatics.mean_pressure[1] = 400000 Pa", "[0, 300000] Pa"]),
    ('L22 = { value = 0.2175, unit = "m" }', 'L22 = { value = 0.0, unit = "m" }',
     ["muscle group 2", "geometry.L22", "muscles.group2.count/l0"]),
    ("eps_max = 0.3", "eps_max = 0.04", ["muscles:", "eps_min", "eps_max = 0.04"]),
    ("format = \"ppamsafety-arm/1\"", "format = \"ppamsafety-head/1\"", ["a head file"]),
    ("# hysteresis_delta = [0.139", "hysteresis_delta = [1.5",
     ["effects.hysteresis_delta[0] = 1.5", "[0, 1]"]),
    ("[model_gravity]", "[model_gravity_x]", ["unknown key or table 'model_gravity_x'"]),
    ("counter_bits = 16", "counter_bits = true", ["sensors.counter_bits", "integer"]),
])
def test_validation_names_the_dotted_key_its_value_and_the_range(old, new, words):
    with pytest.raises(ArmFileError) as e:
        ArmParameters.from_toml(_edit(old, new), where="my_arm.toml")
    msg = str(e.value)
    assert msg.startswith("my_arm.toml: ") and all(w in msg for w in words), msg


def test_a_missing_key_or_table_is_named_with_its_unit():
    text = thesis_arm().to_toml(comments=False)
    lines = [ln for ln in text.splitlines() if not ln.startswith("IG2 =")]
    with pytest.raises(ArmFileError, match=r"missing key links.IG2 \[kg m\^2\]"):
        ArmParameters.from_toml("\n".join(lines))
    with pytest.raises(ArmFileError, match=r"missing table \[valves.valve4\]"):
        ArmParameters.from_toml(text.split("[valves.valve4]")[0] + "[pneumatics]"
                                + text.split("[pneumatics]")[1])


def test_other_units_convert_to_si():
    text = _edit('l0 = { value = 0.06, unit = "m" }', 'l0 = { value = 60, unit = "mm" }')
    text = text.replace("q1_max = { value = 1.8325957145940461, unit = \"rad\" }",
                        "q1_max = { value = 105, unit = \"deg\" }")
    text = text.replace("max_pressure = { value = 300000.0, unit = \"Pa\" }",
                        "max_pressure = { value = 3, unit = \"bar\" }")
    arm = ArmParameters.from_toml(text)
    assert arm.muscles.groups[0].l0 == pytest.approx(0.06, rel=1e-15)
    assert arm.geometry.q1_max == pytest.approx(np.radians(105.0), rel=1e-15)
    assert arm.pneumatics.p_max == 3e5
    # Table B.1 in N/bar, as printed
    t2 = _edit("force_law = { value = [8.16906e-05, 0.00295069, -0.0158659, 0.036231, "
               "-0.0572879], unit = \"N/Pa\" }",
               "force_law = { value = [8.16906, 295.069, -1586.59, 3623.1, -5728.79], "
               "unit = \"N/bar\" }")
    g = ArmParameters.from_toml(t2).muscles.groups[0]
    np.testing.assert_allclose(g.coefficients, thesis_arm().muscles.groups[0].coefficients,
                               rtol=1e-14)


def test_sources_are_kept_in_order_and_checked():
    arm = thesis_arm()
    assert [p for p, _ in arm.sources] == [p for p in SOURCE_PARTS if arm.source(p)]
    assert "Table B.1" in arm.source("muscles.group1")
    with pytest.raises(ValueError, match="unknown part 'wheels'"):
        arm.replace(sources=(("wheels", "x"),))
    with pytest.raises(TypeError, match=r"sources\[0\] must be a \(part, text\) pair"):
        arm.replace(sources=(("links",),))


def test_changes_by_dotted_key_broadcast_index_and_name_the_key():
    a = apply_arm_changes(thesis_arm(), {"arm.pneumatics.mean_pressure": 2e5,
                                         "muscles.group1.count": 5, "links.m2": 1.5,
                                         "effects.hysteresis_delta": 0.3,
                                         "links.coulomb[1]": {"value": 0.2, "unit": "N m"}})
    assert a.pneumatics.p_mean == (2e5, 2e5) and a.muscles.groups[0].n_muscles == 5
    assert a.links.m2 == 1.5 and a.effects.hysteresis_delta == (0.3,) * 4
    assert a.links.coulomb == (thesis_arm().links.coulomb[0], 0.2)
    assert apply_arm_changes(thesis_arm(), {}) is thesis_arm()
    for ch, words in [({"arm.links.m3": 1.0}, ["unknown arm parameter 'links.m3'"]),
                      ({"arm.muscles.group1.count": 0}, ["arm.muscles.group1.count = 0",
                                                         "[1, 20]"]),
                      ({"links.coulomb[2]": 1.0}, ["index 2 outside [0, 1]"]),
                      ({"geometry.L22": 0.0}, ["arm.geometry.L22 = 0:", "muscle group 2"]),
                      ({"effects.valve_dead_time[1]": 2}, ["effects.valve_dead_time[1]",
                                                           "whole list"])]:
        with pytest.raises(ArmFileError) as e:
            apply_arm_changes(thesis_arm(), ch)
        assert all(w in str(e.value) for w in words), str(e.value)
    assert "pneumatics.mean_pressure" in arm_parameter_paths()


def test_effects_from_a_table_are_validated_like_the_file():
    e = effects_from_dict({"hysteresis_delta": 0.299, "payload_mass": {"value": 500, "unit": "g"},
                           "valve_dead_time": 2})
    assert e.hysteresis_delta == (0.299,) * 4 and e.payload_mass == 0.5
    assert e.valve_dead_time == (2,) * 4
    for bad, words in [({"payload_mass": -1}, ["effects.payload_mass = -1 kg", "[0, 5]"]),
                       ({"valve_delay": 1}, ["unknown effect effects.valve_delay"]),
                       ({"hysteresis_delta": [0.1, 0.2]}, ["must have 4 entries"])]:
        with pytest.raises(ArmFileError) as err:
            effects_from_dict(bad)
        assert all(w in str(err.value) for w in words), str(err.value)
    assert effects_from_dict({}) == Effects()


def test_fingerprint_changes_with_any_parameter():
    a = thesis_arm()
    assert len(arm_fingerprint(a)) == 64
    assert arm_fingerprint(apply_arm_changes(a, {"links.m2": a.links.m2 * (1 + 1e-15)})) != \
        arm_fingerprint(a)


def test_the_example_arm_loads_and_states_its_reason():
    arm = load_arm(EXAMPLE)
    assert not is_thesis_arm(arm)
    assert arm.effects.hysteresis_delta == (0.299,) * 4         # 40 fibres, thesis §3.6.5
    assert arm.links.m2 == 1.6 > thesis_arm().links.m2
    assert "40 fibre" in arm.source("arm") and "3.6.5" in arm.source("effects")
    assert arm_to_dict(arm)["effects"]["hysteresis_delta"] == [0.299] * 4
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_arm(ROOT / "no_such_arm.toml")


# ------------------------------------------------------------------------------- heads
def test_head_files_round_trip_and_the_shipped_heads_state_provenance_and_checks():
    for name in head_model_names():
        m = head_model(name)
        back = HeadContactModel.from_toml(m.to_toml())
        assert back == m and back.source == m.source and back.checks == m.checks
        assert m.source and {c[0] for c in m.checks} == set(CHECK_NAMES)


def test_head_file_units_and_errors(tmp_path):
    face = head_model("iso15066-face")
    text = face.to_toml().replace('unit = "N/m^n"', 'unit = "N/mm"').replace("75000.0", "75")
    assert HeadContactModel.from_toml(text) == face
    p = tmp_path / "h.toml"
    p.write_text(text.replace('mass = { value = 4.4, unit = "kg" }',     # Annex A m_H
                              'mass = { value = -5.0, unit = "kg" }'))
    with pytest.raises(ArmFileError, match=r"h.toml: mass = -5 kg: must be in \(0, 100\] kg"):
        load_head(p)
    p.write_text("colour = 1\n" + text)
    with pytest.raises(ArmFileError, match="unknown key 'colour'"):
        load_head(p)
    p.write_text(thesis_arm().to_toml())
    with pytest.raises(ArmFileError, match="an arm file"):
        load_head(p)
    p.write_text(face.to_toml())
    assert resolve_head(str(p)) == face and resolve_head(None) == head_model()
    with pytest.raises(ValueError, match="unknown head model"):
        resolve_head("nobody")


def test_the_file_format_doc_lists_every_key():
    doc = (ROOT / "docs" / "arm_files.md").read_text()
    for path, keys in TABLES.items():
        for k in keys:
            assert f"| `{k.key}` |" in doc, f"{path}.{k.key} missing from docs/arm_files.md"
