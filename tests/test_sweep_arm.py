"""Sweeps over arms, effects and design parameters; sweep summaries; envelopes (issue 21.3)."""

import functools
import math
from pathlib import Path

import pandas as pd
import numpy as np
import pytest

from ppamsafety.envelope import LIMITS, safety_envelope
from ppamsafety.impact.head import head_model
from ppamsafety.design import load_arm
from ppamsafety.params import thesis_arm
from ppamsafety.params.arm_file import apply_arm_changes
from ppamsafety.study_files import load_study, parse_study, run_study_file
from ppamsafety.sweep import function_hash
from ppamsafety.sweep_cases import (case_arm, case_function, check_case, impact_case,
                                    safety_case)

ROOT = Path(__file__).parent.parent
EXAMPLE = ROOT / "examples" / "arms" / "forty_fibre_heavy_forearm.toml"


def test_dotted_parameters_and_effects_reach_the_arm_of_a_case():
    a = case_arm(None, effects={"hysteresis_delta": 0.299},
                 changes={"arm.pneumatics.mean_pressure": 1.5e5, "effects.payload_mass": 0.4,
                          "arm.muscles.group1.count": 5, "arm.links.m2": 1.3})
    assert a.effects.hysteresis_delta == (0.299,) * 4 and a.effects.payload_mass == 0.4
    assert a.pneumatics.p_mean == (1.5e5, 1.5e5) and a.muscles.groups[0].n_muscles == 5
    assert a.links.m2 == 1.3
    assert case_arm(None) is thesis_arm()
    with pytest.raises(ValueError, match="set it in one place"):
        case_arm(None, effects={"payload_mass": 0.1}, changes={"effects.payload_mass": 0.2})


@pytest.mark.parametrize("case, words", [
    ({"effects": {"payload": 1.0}}, ["unknown effect effects.payload"]),
    ({"effects": {"payload_mass": 9.0}}, ["effects.payload_mass = 9 kg", "[0, 5] kg"]),
    ({"effects.hysteresis_delta": 2.0}, ["effects.hysteresis_delta[0] = 2", "[0, 1]"]),
    ({"arm.links.m2": -1.0}, ["arm.links.m2 = -1 kg", "(0, 100] kg"]),
    ({"arm.muscles.group1.count": 0.5}, ["arm.muscles.group1.count = 0.5", "integer"]),
    ({"arm.wheels": 4}, ["unknown arm parameter 'wheels'"]),
    ({"colour": 1}, ["unknown safety_case parameter(s) ['colour']", "arm.<key"]),
])
def test_case_parameters_are_validated_like_the_file(case, words):
    with pytest.raises((TypeError, ValueError)) as e:
        check_case(**case)
    assert all(w in str(e.value) for w in words), str(e.value)


def test_a_dotted_parameter_at_its_thesis_value_changes_nothing():
    base = safety_case("step", "PSMC joint", lam=0.8)
    same = safety_case("step", "PSMC joint", lam=0.8, effects={},
                       **{"arm.links.m2": thesis_arm().links.m2,
                          "arm.pneumatics.mean_pressure": list(thesis_arm().pneumatics.p_mean)})
    assert same == base                              # bitwise: the same arm
    hyst = safety_case("step", "PSMC joint", lam=0.8, effects={"hysteresis_delta": 0.299})
    assert hyst["F_max"] != base["F_max"]            # the plant effect acts
    stiff = safety_case("step", "PSMC joint", lam=0.8, **{"arm.pneumatics.mean_pressure": 2.0e5})
    assert stiff["K1"] > base["K1"] and stiff["K2"] > base["K2"]   # stiffness (2.18) rises


def test_the_case_function_carries_the_arm_and_head_into_the_cache_key():
    arm = apply_arm_changes(thesis_arm(), {"links.m2": 1.3})
    f = case_function(arm, head_model("iso15066-face"))
    assert isinstance(f, functools.partial) and f.keywords["arm"] is arm
    assert case_function() is safety_case and case_function(kind="impact") is impact_case
    assert function_hash(f) != function_hash(case_function(thesis_arm()))
    assert function_hash(case_function(arm)) != function_hash(
        case_function(apply_arm_changes(thesis_arm(), {"links.m2": 1.31})))


def test_a_study_file_takes_an_arm_file_dotted_keys_units_and_effect_axes(tmp_path):
    (tmp_path / "arms").mkdir()
    (tmp_path / "arms" / "mine.toml").write_text(EXAMPLE.read_text())
    text = """
[study]
name = "mine"
[arm]
file = "arms/mine.toml"
[case]
experiment = "step"
controller = "PSMC joint"
arm.links.m1 = { value = 1300, unit = "g" }
[grid]
arm.pneumatics.mean_pressure = { linspace = [1.4, 1.8, 2], unit = "bar" }
effects.payload_mass = [0.0, 0.5]
"""
    (tmp_path / "s.toml").write_text(text)
    st = load_study(tmp_path / "s.toml")
    assert st.arm == load_arm(EXAMPLE) and len(st.cases) == 4
    assert {c["arm.pneumatics.mean_pressure"] for c in st.cases} == {1.4e5, 1.8e5}
    assert all(c["arm.links.m1"] == pytest.approx(1.3) for c in st.cases)
    assert st.swept == ["arm.pneumatics.mean_pressure", "effects.payload_mass"]
    # --arm replaces the file's arm; the cases are checked against it
    st2 = load_study(tmp_path / "s.toml", arm=thesis_arm())
    assert st2.arm is thesis_arm()
    with pytest.raises(ValueError, match=r"\[head\] file \(or --head\) both set the head"):
        parse_study('[impact]\nhead = "iso15066-face"\n', head=head_model())


def test_a_sweep_folder_holds_the_table_a_figure_a_page_and_the_arm(tmp_path):
    text = """
[study]
name = "mp"
description = "mean pressure"
[case]
experiment = "step"
controller = "PSMC joint"
[impact]
instants = "max TCP speed"
[grid]
arm.pneumatics.mean_pressure = [1.4e5, 1.8e5]
"""
    st = parse_study(text, arm=load_arm(EXAMPLE))
    df = run_study_file(st, tmp_path / "out", processes=1, progress=False).table
    out = tmp_path / "out"
    assert list(df["status"]) == ["ok", "ok"]
    for name in ("results.csv", "summary.png", "summary.html", "arm.toml", "study.toml"):
        assert (out / name).is_file(), name
    page = (out / "summary.html").read_text()
    assert "40-fibre muscles, heavier forearm" in page and 'src="summary.png"' in page
    assert "limits that decide the verdicts" in page and "ISO/TS 15066" in page
    assert load_arm(out / "arm.toml") == load_arm(EXAMPLE)
    back = pd.read_csv(out / "results.csv")           # SI values: the file gave no unit
    assert list(back["arm.pneumatics.mean_pressure [Pa]"]) == [1.4e5, 1.8e5]


def test_a_speed_envelope_brackets_the_maxilla_limit():
    env = safety_envelope("speed", (0.2, 3.0), limit="F_max", tolerance=0.02)
    assert env.direction == "largest" and env.monotone
    ev = env.to_pandas().set_index("value")
    assert ev.loc[env.safe_value, "F_max"] < 660.0 <= ev.loc[env.unsafe_value, "F_max"]
    assert env.unsafe_value - env.safe_value <= 0.02 * env.unsafe_value
    assert env.limit_value == LIMITS["F_max"].value
    # ISO/TS 15066's transient forehead limit is lower: a lower speed
    iso = safety_envelope("speed", (0.2, 3.0), limit="iso_ts_15066", tolerance=0.02)
    assert iso.safe_value < env.safe_value
    assert "speed <=" in env.description and env.plot() is not None


def test_an_envelope_over_the_whole_range_and_bad_arguments():
    env = safety_envelope("speed", (0.1, 0.3), limit="HIC36")        # far below HIC 650
    assert env.direction == "all safe" and env.safe_value == 0.3 and env.unsafe_value is None
    with pytest.raises(ValueError, match="low must be smaller"):
        safety_envelope("speed", (2.0, 1.0))
    with pytest.raises(ValueError, match="limit = 'pain'"):
        safety_envelope("speed", (0.1, 1.0), limit="pain")
    with pytest.raises(ValueError, match="cannot be searched"):
        safety_envelope("experiment", (0.1, 1.0))
    with pytest.raises(ValueError, match=r"bounds\[1\] = 20: speed = 20 is not allowed .*"
                                         r"\(0, 10\] m/s"):      # refused before anything runs
        safety_envelope("speed", (0.1, 20.0))                          # speed above 10 m/s
    assert math.isfinite(impact_case(1.0)["F_max"])


def test_the_shipped_mean_pressure_study_loads():
    st = load_study(ROOT / "studies" / "mean_pressure.toml")
    ps = sorted({c["arm.pneumatics.mean_pressure"] for c in st.cases})
    assert len(ps) >= 5 and ps[0] >= 1.0e5 and ps[-1] <= 2.1e5
    assert "arm.pneumatics.mean_pressure" in st.swept


def test_an_envelope_study_file_writes_its_search(tmp_path):
    (tmp_path / "env.toml").write_text("""
[study]
name = "speed-envelope"
[impact]
stiffness = [43.0, 27.0]
[envelope]
parameter = "speed"
range = [0.2, 3.0]
limit = "F_max"
tolerance = 0.05
pose = [50.0, -80.0]
""")
    df = run_study_file(tmp_path / "env.toml", tmp_path / "out", progress=False,
                        head=head_model("thesis-frontal")).table
    assert set(df["status"]) == {"ok"} and df["safe"].any() and not df["safe"].all()
    page = (tmp_path / "out" / "summary.html").read_text()
    assert "safe for speed &lt;=" in page and (tmp_path / "out" / "head.toml").is_file()
    with pytest.raises(ValueError, match="speed' is one impact at a pose"):
        parse_study('[case]\ncontroller = "PID"\n[envelope]\nparameter = "speed"\n'
                    'range = [0.2, 3.0]\n')


def test_a_mean_pressure_envelope_searches_the_arm_parameter():
    pid = safety_envelope("arm.pneumatics.mean_pressure", (1.2e5, 2.0e5), limit="F_max",
                          case={"controller": "PID", "instants": "max TCP speed"})
    assert pid.direction == "none safe" and pid.safe_value is None      # PID: > 660 N always
    # the scan (9 values, ends included) sees no safe value: no bisection
    assert sorted(pid.evaluations["value"]) == pytest.approx(np.linspace(1.2e5, 2.0e5, 9))
    assert (pid.evaluations["F_max"] > 660.0).all() and pid.crossings == []
    with pytest.raises(ValueError, match="case sets 'lam'"):
        safety_envelope("lam", (0.1, 1.0), case={"lam": 0.4})
