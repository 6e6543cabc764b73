"""What a new user certifying their own arm reads after a slip: implausible contact point and
covering files refused or noted, error messages that name the argument, its value and what
is allowed, and units in what a person reads.

The inputs are those a new user wrote in a trial (a contact point 3200 mm out on a 400 mm
forearm, a foam modulus of 800 Pa meant as kPa, ...), rebuilt here on the thesis arm.
"""

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from ppamsafety.cli import main
from ppamsafety.experiments.catalog import run_thesis_experiment, thesis_variants
from ppamsafety.impact.anywhere import simulate_contacts, worst_contact
from ppamsafety.params import thesis_arm
from ppamsafety.params.arm_file import ArmFileError
from ppamsafety.params.contact import (POINT_EXTENT_FACTOR, SOFT_LAYER_MODULUS, THESIS_COVERING,
                                       ContactPoint, Covering, Layer, check_point_on_arm,
                                       covering_notes)
from ppamsafety.params.contact_files import load_covering, resolve_contact_point

ARM = thesis_arm()
L2 = ARM.geometry.L2


def _point_file(path, position_mm, link=2, covering='"bare metal"'):
    path.write_text('format = "ppamsafety-contact/1"\nname = "gripper bracket"\n'
                    f'link = {link}\nposition = {{ value = {position_mm}, unit = "mm" }}\n'
                    'shape = "cylinder"\nradius = { value = 25, unit = "mm" }\n'
                    f'covering = {covering}\nsource = "CAD"\n')
    return path


def _covering_file(path, modulus, unit):
    path.write_text('format = "ppamsafety-covering/1"\nname = "15 mm EVA foam sleeve"\n'
                    '[[layer]]\nname = "EVA foam"\nlaw = "thin-layer"\n'
                    f'modulus = {{ value = {modulus}, unit = "{unit}" }}\n'
                    'thickness = { value = 15, unit = "mm" }\nstrain_limit = 0.7\n'
                    'hysteresis = { value = 4.0, unit = "s/m" }\n')
    return path


# ---- 1. implausible contact point and covering files -----------------------------------------
def test_a_contact_point_beyond_its_link_is_refused_naming_key_value_length_and_range(tmp_path):
    f = _point_file(tmp_path / "far.toml", 10 * 1e3 * L2)      # 10 forearm lengths out
    with pytest.raises(ArmFileError) as e:
        resolve_contact_point(f, ARM)
    msg = str(e.value)
    for part in ("position", f"{1e4 * L2:.4g} mm", f"L2 = {L2:.4g} m",
                 f"[0, {POINT_EXTENT_FACTOR * L2:.4g}] m", "gripper bracket", "far.toml"):
        assert part in msg, msg
    # the same point as an object, through the Python API of the contact engine
    pt = ContactPoint("bracket", 2, 10 * L2, "sphere", 0.02, Covering("bare metal"))
    with pytest.raises(ValueError, match=r"position = .* allowed \[0, "):
        simulate_contacts(ARM, [0.8, -1.4], [2.0, 0.0], [85.0, 54.0], point=pt)
    with pytest.raises(ValueError, match="L1 = "):
        check_point_on_arm(pt.replace(link=1, position=5 * ARM.geometry.L1), ARM)


def test_a_contact_point_within_the_tool_margin_is_accepted(tmp_path):
    at_margin = _point_file(tmp_path / "tool.toml", 1e3 * POINT_EXTENT_FACTOR * L2 * 0.999)
    assert resolve_contact_point(at_margin, ARM).position == pytest.approx(
        POINT_EXTENT_FACTOR * L2 * 0.999)
    just_out = _point_file(tmp_path / "out.toml", 1e3 * POINT_EXTENT_FACTOR * L2 * 1.01)
    with pytest.raises(ValueError, match="position"):
        resolve_contact_point(just_out, ARM)


def test_the_cli_refuses_a_far_contact_point_with_one_line(tmp_path, capsys):
    f = _point_file(tmp_path / "far.toml", 3200)
    assert main(["impact", "--q", "50", "-80", "--qd", "2", "0", "--contact", str(f)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ppamsafety: error: --contact") and err.count("\n") == 1, err
    assert "3200 mm" in err and f"L2 = {L2:.4g} m" in err, err


def test_a_foam_modulus_in_pa_meant_as_kpa_gets_a_note_naming_the_slip(tmp_path):
    cov = load_covering(_covering_file(tmp_path / "pa.toml", 800, "Pa"))
    notes = covering_notes(cov)
    assert len(notes) == 1 and "layer[0].modulus = 800 Pa" in notes[0], notes
    assert "did you mean 800 kPa" in notes[0], notes
    # MPa given in Pa: the note names MPa
    cov = load_covering(_covering_file(tmp_path / "mpa.toml", 1.2, "Pa"))
    assert "did you mean 1.2 MPa" in covering_notes(cov)[0]
    # plausible coverings have no note
    assert covering_notes(load_covering(_covering_file(tmp_path / "ok.toml", 800, "kPa"))) == ()
    assert covering_notes(THESIS_COVERING) == ()
    assert SOFT_LAYER_MODULUS <= 55e3                # a silicone gel is not noted


def test_impact_notes_the_slip_and_says_the_covering_bottoms_out(tmp_path, capsys):
    f = _covering_file(tmp_path / "pa.toml", 800, "Pa")
    hist = tmp_path / "h.csv"
    assert main(["impact", "--q", "50", "-80", "--qd", "2", "0", "--covering", str(f),
                 "--history", str(hist)]) == 0
    out, err = capsys.readouterr()
    assert "ppamsafety: note:" in err and "did you mean 800 kPa" in err, err
    line = next(ln for ln in out.splitlines() if ln.startswith("covering use"))
    assert "1.00" in line and "BOTTOMS OUT" in line, line
    h = pd.read_csv(hist)
    use = next(c for c in h.columns if c.startswith("covering_use"))
    assert h[use].max() == pytest.approx(1.0, abs=1e-6)
    # a covering well within its limit: the line says its use, no bottoming out
    ok = _covering_file(tmp_path / "ok.toml", 800, "kPa")
    assert main(["impact", "--q", "50", "-80", "--qd", "0.3", "0", "--covering", str(ok)]) == 0
    out, err = capsys.readouterr()
    line = next(ln for ln in out.splitlines() if ln.startswith("covering use"))
    assert "BOTTOMS OUT" not in line and float(line.split()[2]) < 1.0, line
    assert "note:" not in err


def test_worst_contact_covering_use_is_zero_for_bare_points_never_nan():
    res = _step_record()
    cov = THESIS_COVERING
    pts = ["tool point", ContactPoint("covered forearm", 2, 0.5 * L2, "cylinder", 0.03, cov)]
    w = worst_contact(res, ARM, points=pts, every=50)
    assert w.worst["covering_use"].notna().all(), w.worst
    bare = w.worst.set_index("point").loc["tool point", "covering_use"]
    assert bare == 0.0
    assert 0.0 < w.worst.set_index("point").loc["covered forearm", "covering_use"] <= 1.0


def _step_record():
    return run_thesis_experiment(ARM, "step", [thesis_variants()[1]])[0]


# ---- 2. error messages name the argument, its value and what is allowed ----------------------
def _cli_error(argv, capsys) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("ppamsafety: error:") and err.count("\n") == 1, err
    return err


@pytest.mark.parametrize("value", ["0", "-3", "abc"])
def test_max_cases_names_option_value_and_range(value, capsys):
    err = _cli_error(["sweep", "s.toml", "--out", "o", "--max-cases", value], capsys)
    assert "--max-cases" in err and value in err and "integer >= 1" in err, err
    assert "processes" not in err, err


STUDY = '[case]\nexperiment = "step"\ncontroller = "PID"\n'


@pytest.mark.parametrize("text, words", [
    ('[grid]\nlam = { linspace = [200, 400, 2], unit = "ms" }\n',
     ["grid.lam", "'ms'", "only the dotted keys", "in s", "lam = { linspace = [0.2, 0.4, 2] }"]),
    ('[grid]\nlam = { values = [200, 400], unit = "ms" }\n',
     ["grid.lam", "only the dotted keys", "lam = [0.2, 0.4]"]),
    ('[grid]\nstiffness = { values = [20, 85], unit = "N mm/deg" }\n',
     ["grid.stiffness", "'N mm/deg'", "only the dotted keys", "N m/rad"]),
    ('lam = { value = 300, unit = "ms" }\n',
     ["case.lam", "only the dotted keys", "in s", "lam = 0.3"]),
    ('[grid]\nkp_bar = { values = [1, 3], unit = "mbar/rad" }\n',
     ["grid.kp_bar", "only the dotted keys", "bar/rad"]),
])
def test_a_unit_on_a_key_that_takes_plain_numbers_says_the_rule_and_the_si_value(text, words):
    from ppamsafety.study_files import StudyFileError, parse_study

    text = STUDY + text if text.startswith("[") else STUDY.replace(
        'controller = "PID"\n', 'controller = "PID"\n' + text)
    with pytest.raises(StudyFileError) as e:
        parse_study(text)
    assert all(w in str(e.value) for w in words), str(e.value)
    # a dotted key takes its unit, so the rule holds
    ok = STUDY + '[grid]\narm.links.m2 = { values = [900, 1200], unit = "g" }\n'
    assert [c["arm.links.m2"] for c in parse_study(ok).cases] == [0.9, 1.2]
    # ... and so does a covering key
    ok = STUDY.replace('controller = "PID"\n', 'controller = "PID"\n'
                       'covering_thickness = { value = 15, unit = "mm" }\n')
    assert parse_study(ok).cases[0]["covering_thickness"] == pytest.approx(0.015)


def test_a_missing_arm_file_of_a_study_says_where_relative_paths_are_read(tmp_path):
    from ppamsafety.study_files import StudyFileError, load_study

    sub = tmp_path / "studies"
    sub.mkdir()
    (sub / "s.toml").write_text('[arm]\nfile = "my_arms.toml"\n' + STUDY)
    with pytest.raises(StudyFileError) as e:
        load_study(sub / "s.toml")
    msg = str(e.value)
    assert "arm.file = 'my_arms.toml'" in msg and str((sub / "my_arms.toml").resolve()) in msg
    assert "relative to the study file's folder" in msg, msg


def test_effect_errors_name_the_option_and_the_unit(tmp_path, capsys):
    out = str(tmp_path / "r.csv")
    err = _cli_error(["synthesize", "--out", out, "--effect", "bogus=1"], capsys)
    assert "--effect bogus=1" in err and "unknown effect 'bogus'" in err, err
    err = _cli_error(["synthesize", "--out", out, "--effect", "payload_mass=abc"], capsys)
    assert "--effect payload_mass=abc" in err and "in kg" in err, err
    err = _cli_error(["synthesize", "--out", out, "--effect", "payload_mass=400furlong"], capsys)
    assert "--effect payload_mass=400furlong" in err and "'g'" in err, err
    err = _cli_error(["synthesize", "--out", out, "--effect", "valve_gain_factor=0.8g"], capsys)
    assert "--effect valve_gain_factor=0.8g" in err and "plain number" in err, err
    err = _cli_error(["synthesize", "--kind", "actuator", "--out", out, "--effect", "bogus=1"],
                     capsys)
    assert "--effect bogus=1" in err and "kind='actuator'" in err, err
    assert not (tmp_path / "r.csv").exists()


@pytest.mark.parametrize("text, si", [("400g", "0.4"), ("400 g", "0.4"), ("0.4", "0.4"),
                                      ("0.4kg", "0.4")])
def test_effect_values_with_a_unit_are_converted_to_si(text, si):
    from ppamsafety.cli import _effect_value

    assert float(_effect_value("arm", "payload_mass", text)) == pytest.approx(float(si))
    assert float(_effect_value("arm", "valve_dead_time", "20ms")) == pytest.approx(0.02)
    assert [float(x) for x in _effect_value("arm", "valve_offset_delta",
                                            "10,20,0,0 kPa").split(",")] == [1e4, 2e4, 0, 0]


def test_region_numbers_on_the_command_line_and_their_range(capsys):
    from ppamsafety.params.iso_ts_15066 import body_region

    assert body_region("8") == body_region(8) == body_region("chest/sternum")
    err = _cli_error(["impact", "--q", "50", "-80", "--qd", "1", "0", "--region", "30"], capsys)
    assert "--region 30" in err and "1-29" in err, err
    err = _cli_error(["impact", "--q", "50", "-80", "--qd", "1", "0", "--region", "chst"],
                     capsys)
    assert "--region chst" in err and "1-29" in err and "chest/sternum" in err, err


def test_impact_q_in_radians_gets_the_looks_like_radians_hint_with_the_value(capsys):
    assert main(["impact", "--q", "0.87", "-1.4", "--qd", "1", "0"]) == 0
    err = capsys.readouterr().err
    warn = [ln for ln in err.splitlines() if "warning" in ln]
    assert len(warn) == 1, err                          # said once, in the user's degrees
    assert "--q 0.87 -1.4 deg" in warn[0] and "looks like radians" in warn[0], warn
    assert f"--q {math.degrees(0.87):.4g} {math.degrees(-1.4):.4g}" in warn[0], warn
    # outside the working area but not radians: the warning without the hint
    assert main(["impact", "--q", "0", "-80", "--qd", "1", "0"]) == 0
    err = capsys.readouterr().err
    assert "--q 0 -80 deg lies outside" in err and "radians" not in err, err


def test_dt_help_and_error_give_the_allowed_range(capsys):
    from ppamsafety.cli import _DT_RANGE
    from ppamsafety.impact.model import DT_RANGE

    assert _DT_RANGE == DT_RANGE
    assert main(["impact", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "--dt DT integration step [s], in [1e-08, 0.001] s" in out, out
    err = _cli_error(["impact", "--q", "50", "-80", "--qd", "1", "0", "--dt", "0.01"], capsys)
    assert "--dt" in err and "0.01 s" in err and "[1e-08, 0.001] s" in err, err


# ---- 3. units in what a person reads ---------------------------------------------------------
def _unit_of_every_numeric_column(csv) -> list:
    """Numeric columns of a CSV file whose name carries no ``[unit]``."""
    df = pd.read_csv(csv)
    return [c for c in df.columns
            if pd.api.types.is_numeric_dtype(df[c]) and not pd.api.types.is_bool_dtype(df[c])
            and df[c].notna().any() and not c.rstrip().endswith("]")]


def test_impact_history_csv_names_its_units(tmp_path, capsys):
    h = tmp_path / "h.csv"
    assert main(["impact", "--q", "50", "-80", "--qd", "1", "0", "--history", str(h)]) == 0
    cols = list(pd.read_csv(h).columns)
    assert cols[:3] == ["t [s]", "F [N]", "delta [m]"], cols
    assert _unit_of_every_numeric_column(h) == []
    h2 = tmp_path / "h2.csv"
    assert main(["impact", "--q", "50", "-80", "--qd", "1", "0", "--contact", "forearm",
                 "--covering", "thesis-implied", "--history", str(h2)]) == 0
    cols = list(pd.read_csv(h2).columns)
    assert "pressure [Pa]" in cols and "covering_use [-]" in cols, cols
    assert _unit_of_every_numeric_column(h2) == []


def test_result_tables_are_written_with_units(tmp_path):
    from ppamsafety.impact.instants import worst_instant
    from ppamsafety.results import strip_unit
    from ppamsafety.sweep import SweepResult

    run = _step_record()
    run.write(tmp_path / "run")
    csv = tmp_path / "run" / "table.csv"
    assert _unit_of_every_numeric_column(csv) == []
    cols = list(pd.read_csv(csv).columns)
    assert {"t [s]", "q1 [rad]", "p1 [Pa]", "x_d [m]"} <= set(cols), cols
    assert [strip_unit(c)[0] for c in cols] == list(run.to_pandas().columns)   # same order
    wi = worst_instant(run, ARM, every=50)
    wi.write(tmp_path / "wi")
    assert _unit_of_every_numeric_column(tmp_path / "wi" / "table.csv") == []
    assert "F_max [N]" in pd.read_csv(tmp_path / "wi" / "table.csv").columns
    pts = ["tool point", ContactPoint("covered forearm", 2, 0.5 * L2, "cylinder", 0.03,
                                      THESIS_COVERING)]
    wc = worst_contact(run, ARM, points=pts, every=50, limits={"head (forehead)": 260.0})
    wc.write(tmp_path / "wc")
    for name in ("table", "worst", "candidates"):
        assert _unit_of_every_numeric_column(tmp_path / "wc" / f"{name}.csv") == [], name
    worst = pd.read_csv(tmp_path / "wc" / "worst.csv")
    assert {"value [N]", "limit [N]", "p_max [Pa]", "covering_use [-]"} <= set(worst.columns)
    # a generic sweep knows no units; a sweep with units writes them
    sw = SweepResult(pd.DataFrame({"lam": [0.2, 0.4], "F_max": [1.0, 2.0]}),
                     units={"lam": "s", "F_max": "N"})
    sw.write(tmp_path / "sw")
    assert list(pd.read_csv(tmp_path / "sw" / "table.csv").columns) == ["lam [s]", "F_max [N]"]
    with pytest.raises(TypeError, match="units must be a dict"):
        SweepResult(pd.DataFrame({"x": [1]}), units=["s"])


def test_sweep_figure_legend_and_axes_show_units_and_the_contact_points_speed():
    from ppamsafety.plots.sweep import plot_sweep

    df = pd.DataFrame({"arm.pneumatics.mean_pressure": [140.0, 140.0, 200.0, 200.0],
                       "lam": [0.2, 0.4, 0.2, 0.4], "status": ["ok"] * 4,
                       "F_max": [100.0, 90.0, 120.0, 110.0], "tcp_speed": [1.0, 0.9, 1.2, 1.1],
                       "p_max": [10.0, 9.0, 12.0, 11.0], "contact_point": ["forearm"] * 4})
    fig = plot_sweep(df, ["lam", "arm.pneumatics.mean_pressure"],
                     units={"arm.pneumatics.mean_pressure": "kPa", "lam": "s",
                            "p_max": "N/cm^2"})
    legends = [t for ax in fig.axes for t in ax.get_legend_handles_labels()[1]]
    assert "arm.pneumatics.mean_pressure = 140 kPa" in legends, legends
    assert "lam = 0.2 s" in legends, legends
    ylabels = {ax.get_ylabel() for ax in fig.axes}
    assert "forearm speed at impact [m/s]" in ylabels, ylabels
    assert "peak contact pressure [N/cm^2]" in ylabels, ylabels
    assert not any("TCP speed" in y for y in ylabels)
    # at the tool point the axis stays the TCP speed
    fig = plot_sweep(df.assign(contact_point="tool point"), ["lam"])
    assert "TCP speed at impact [m/s]" in {ax.get_ylabel() for ax in fig.axes}


def test_a_study_shows_p_max_in_n_per_cm2_as_impact_does():
    from ppamsafety.study_files import display_table, parse_study

    st = parse_study(STUDY)
    t = display_table(st, pd.DataFrame({"p_max": [1.837e6], "F_max": [100.0]}))
    assert list(t.columns) == ["p_max [N/cm^2]", "F_max [N]"]
    assert t.iloc[0, 0] == pytest.approx(183.7)


# ---- 4. docs ---------------------------------------------------------------------------------
def _side(point, joint, along) -> float:
    """> 0 when ``point`` lies left of the link (counter-clockwise side), < 0 right."""
    r = np.asarray(point) - np.asarray(joint)
    return float(along[0] * r[1] - along[1] * r[0])


def test_the_documented_sides_of_the_perpendicular_offsets_hold_in_the_code():
    """docs/arm_files.md: positive d12, d32, d33 left of their link; d22, d42, d43, dL, dG1,
    dG2 right (looking from the joint along the link)."""
    from ppamsafety.plant import dynamics as dyn
    from ppamsafety.plant import packing
    from ppamsafety.plant.geometry import attachment_points, load_point

    doc = (Path(__file__).resolve().parents[1] / "docs" / "arm_files.md").read_text()
    assert "a positive `d12`, `d32` and `d33` lies on the **left**" in doc
    g = ARM.geometry.replace(d12=0.02, d22=0.02, d32=0.02, d42=0.02, d33=0.02, d43=0.02,
                             dL=0.02)
    arm = ARM.replace(geometry=g)
    q = np.array([0.7, -1.2])
    e1 = np.array([math.cos(q[0]), math.sin(q[0])])
    e2 = np.array([math.cos(q.sum()), math.sin(q.sum())])
    O, S = np.zeros(2), ARM.geometry.L1 * e1
    A = attachment_points(q, arm)          # A11, A12, A21, A22, A32, A33, A42, A43
    assert _side(A[1], O, e1) > 0 and _side(A[4], O, e1) > 0 and _side(A[5], S, e2) > 0
    assert _side(A[3], O, e1) < 0 and _side(A[6], O, e1) < 0 and _side(A[7], S, e2) < 0
    assert _side(load_point(q[0], q[1], packing.pack(arm)), S, e2) < 0
    # centres of gravity: a positive dG raises the gravity torque of a link pointing along +x
    # only if it lies below the link, i.e. on its right (G = theta1 c1 + theta2 s1 + ...)
    links = ARM.links.replace(dG1=0.05, dG2=0.05)
    flat = np.array([0.0, 0.0])
    g_pos = dyn.gravity(flat, ARM.replace(links=links))
    g_zero = dyn.gravity(flat, ARM.replace(links=ARM.links.replace(dG1=0.0, dG2=0.0)))
    assert np.allclose(g_pos, g_zero)      # along x, a perpendicular offset has no moment
    up = np.array([math.pi / 2, 0.0])      # links pointing up (+y): right is +x
    g_pos = dyn.gravity(up, ARM.replace(links=links))
    g_zero = dyn.gravity(up, ARM.replace(links=ARM.links.replace(dG1=0.0, dG2=0.0)))
    assert np.all(g_pos > g_zero)          # mass to the right (+x) of an upright link: +torque


def test_a_record_without_arm_metadata_says_which_arm_it_is_diagnosed_against(tmp_path,
                                                                               capsys):
    from ppamsafety.data.measured import MeasuredData
    from ppamsafety.diagnose import synthesize

    rec = synthesize("open-loop", {}, noise="table-3.2", seed=3, duration=0.5)
    meta = {k: v for k, v in rec.meta.items() if k != "arm"}
    f = MeasuredData(meta, rec.frame).save(tmp_path / "rec.csv")
    assert main(["diagnose", str(f), "--out", str(tmp_path / "d")]) in (0, 1)
    out, err = capsys.readouterr()
    note = [ln for ln in err.splitlines() if "names no arm" in ln]
    assert len(note) == 1 and "'thesis arm' (sha256 " in note[0] and "--arm FILE" in note[0]
    md = (tmp_path / "d" / "diagnosis.md").read_text()
    assert "the record names no arm" in md and "'thesis arm'" in md


def test_confidence_is_printed_as_a_probability_and_a_level_in_words():
    from ppamsafety.diagnose import Effect

    e = Effect(name="valve_lag", subsystem="valves", parameters={}, evidence={},
               confidence=1.0, confidence_level="low",
               gates={"weight": True, "stable": True, "consistent": False})
    text = e.confidence_text()
    assert text == "inclusion probability 1.000; confidence low (gates not passed: consistent)"
    e = Effect(name="valve_lag", subsystem="valves", parameters={}, evidence={},
               confidence=0.99, confidence_level="high", gates={"weight": True})
    assert e.confidence_text() == "inclusion probability 0.990; confidence high"
