"""Study files (TOML) and `ppamsafety sweep` (issue 11.2)."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from ppamsafety.cli import main
from ppamsafety.output import MARKER, OutputError
from ppamsafety.study_files import (STUDY_DATA, StudyFileError, history_format, load_study,
                                    parse_study, run_study_file, shipped_studies)
from ppamsafety.sweep_cases import check_case, safety_case

ROOT = Path(__file__).parent.parent
STUDIES = STUDY_DATA


def test_the_example_study_files_load_and_expand():
    t = load_study(STUDIES / "table_6_1.toml")
    assert len(t.cases) == 20 and t.csv == "table_6_1.csv"           # 10 variants x 2
    assert {c["experiment"] for c in t.cases} == {"step", "switch"}
    labels = {(c["controller"], c.get("ki_bar"), c.get("lam")) for c in t.cases}
    assert len(labels) == 10                                         # Table 6.1's variants
    lk = load_study(STUDIES / "lambda_ki.toml")
    assert len(lk.cases) == 2 * 3 * 7 and lk.name == "lambda-ki"
    # a shipped study is found by its name as well
    assert load_study("lambda_ki").source == lk.source
    assert shipped_studies() == ["lambda_ki", "table_6_1"]


BASE = '[case]\nexperiment = "step"\n'


@pytest.mark.parametrize("text, words", [
    ('[cases]\nx = 1\n', ["unknown table [cases]", "'case'", "'grid'"]),
    (BASE + 'lamda = 0.4\n', ["unknown key case.lamda", "'lam'", "'ki_bar'"]),
    (BASE + '[grid]\nlam = [0.4, -1.0]\n', ["grid.lam[1] = -1.0", ">= 0"]),
    (BASE + '[grid]\nlam = 0.4\n', ["grid.lam = 0.4", "list"]),
    (BASE + '[grid]\nlam = []\n', ["grid.lam", "empty"]),
    (BASE + '[grid]\nexperiment = ["step"]\n', ["grid.experiment", "also set as case.experiment"]),
    (BASE + '[grid]\nstiffness = { logspace = [1, 2, 3] }\n', ["grid.stiffness", "geomspace"]),
    (BASE + '[grid]\nstiffness = { geomspace = [0, 2, 3] }\n', ["grid.stiffness.geomspace",
                                                               "start, stop > 0"]),
    (BASE + 'controller = "LQR"\n', ["case.controller = 'LQR'", "'PID'", "'PSMC task'"]),
    ('[impact]\nhead = "dummy"\n', ["impact.head = 'dummy'", "thesis-frontal"]),
    ('[impact]\ncontroller = "PID"\n', ["unknown key impact.controller", "'instants'"]),
    ('[impact]\ninstants = "worst"\n', ["impact.instants = 'worst'", "'heuristic'", "'all'"]),
    (BASE + 'effects = { valve_delay = 0.01 }\n', ["case.effects", "unknown effect",
                                                   "effects.valve_delay", "hysteresis_delta"]),
    (BASE + 'effects = { payload_mass = -1.0 }\n', ["case.effects", "effects.payload_mass = -1 kg",
                                                    "[0, 5] kg"]),
    (BASE + 'arm.links.m2 = -1.0\n', ["case.arm.links.m2 = -1.0", "arm.links.m2 = -1 kg",
                                      "(0, 100] kg"]),
    (BASE + 'arm.links.m3 = 1.0\n', ["case.arm.links.m3", "unknown arm parameter 'links.m3'"]),
    (BASE + '[grid]\narm.pneumatics.mean_pressure = { linspace = [1, 4, 2], unit = "bar" }\n',
     ["grid.arm.pneumatics.mean_pressure[1] = '4 bar'", "400000 Pa", "[0, 300000] Pa"]),
    (BASE + '[grid]\neffects.hysteresis_delta = [0.1, 2.0]\n',
     ["grid.effects.hysteresis_delta[1] = 2.0", "effects.hysteresis_delta[0] = 2", "[0, 1]"]),
    ('[arm]\nfile = "no_such_arm.toml"\n', ["arm.file = 'no_such_arm.toml'", "does not exist"]),
    ('[arm]\npath = "x.toml"\n', ["unknown key arm.path", "'file'"]),
    ('[envelope]\nparameter = "lam"\nrange = [2.0, 1.0]\n', ["envelope.range", "low < high"]),
    ('[envelope]\nparameter = "colour"\nrange = [1.0, 2.0]\n', ["envelope.parameter = 'colour'"]),
    ('[envelope]\nparameter = "lam"\nrange = [0.1, 2.0]\nlimit = "pain"\n',
     ["envelope.limit = 'pain'", "'iso_ts_15066'"]),
    ('[envelope]\nparameter = "lam"\nrange = [0.1, 2.0]\n[grid]\nki_bar = [2, 12]\n',
     ["[envelope] study searches one parameter"]),
    (BASE + 'lam = 0.4\n', ["case 0", "lam = 0.4", "'PID'"]),
    ('[[variants]]\ncontroller = "PSMC task"\nki_bar = 2\n', ["case 0", "ki_bar",
                                                              "'PSMC task'"]),
    (BASE + '[output]\ncsv = "../x.csv"\n', ["output.csv = '../x.csv'", "file name"]),
    (BASE + '[output]\nformat = "csv"\n', ["unknown key output.format", "'csv'", "'histories'"]),
    (BASE + 'histories = true\n', ["unknown key case.histories", "[output]"]),
    (BASE + '[study]\nname = ""\n', ["study.name", "non-empty"]),
    ('x = [1,\n', ["not valid TOML"]),
])
def test_study_file_errors_name_the_key_and_the_allowed_values(text, words):
    with pytest.raises(StudyFileError) as e:
        parse_study(text, where="s.toml")
    msg = str(e.value)
    assert msg.startswith("s.toml: ") and all(w in msg for w in words), msg


def test_safety_case_parameters_are_checked_by_name():
    with pytest.raises(ValueError, match=r"unknown safety_case parameter\(s\) \['lamda'\]"):
        check_case(lamda=0.4)
    with pytest.raises(ValueError, match=r"every = 5 applies only to instants = 'all'"):
        check_case(every=5)
    with pytest.raises(TypeError, match=r"noise_seed = 1.5 must be an int"):
        check_case(noise_seed=1.5)
    assert check_case(controller="PSMC joint", lam=[0.4, 0.8])["lam"] == [0.4, 0.8]


def test_cli_runs_table_6_1_reduced_and_reproduces_the_safety_study(tmp_path, capsys):
    """Case 0 of the shipped table_6_1 (PID, step) equals Table 6.1 of the safety study."""
    from ppamsafety.experiments.catalog import run_thesis_experiment
    from ppamsafety.impact.instants import evaluate_experiment
    from ppamsafety.params import thesis_arm
    from ppamsafety.impact.head import head_model

    out = tmp_path / "t61"
    def argv(n, *extra):
        return ["sweep", str(STUDIES / "table_6_1.toml"), "--out", str(out), "--max-cases",
                str(n), "--processes", "1", "--no-progress", *extra]

    assert main(argv(1)) == 0
    df = pd.read_csv(out / "table_6_1.csv")
    assert len(df) == 1 and df.status[0] == "ok" and df.label[0] == "PID"
    # what ppamsafety/sections/safety.py::_heuristic_table does for the step experiment
    arm = thesis_arm()
    r = run_thesis_experiment(arm, "step")[0]                  # all ten variants in one batch
    ev = evaluate_experiment(r, arm, head=head_model(), history=True).summary
    assert df["F_max [N]"][0] == ev.F_max.max() and df["HIC36 [-]"][0] == ev.HIC36.max()
    ref = pd.read_csv(ROOT / "reports" / "safety_table_6_1.csv")
    row = ref[(ref.experiment == "step") & (ref.label == "PID")].iloc[0]
    assert df["F_max [N]"][0] == row.F_max and df["HIC36 [-]"][0] == row.HIC36
    marker = json.loads((out / MARKER).read_text())
    assert marker["kind"] == "sweep" and marker["dirs"] == ["cache"]
    assert (out / "study.toml").read_text() == (STUDIES / "table_6_1.toml").read_text()
    cached = {f.name: f.stat().st_mtime_ns for f in (out / "cache").glob("*.pkl")}
    assert len(cached) == 1

    # a previous sweep: plain run refused (naming --resume), --resume adds the next case only
    assert main(argv(2)) == 2
    assert "--resume" in capsys.readouterr().err
    assert main(argv(2, "--resume")) == 0
    df2 = pd.read_csv(out / "table_6_1.csv")
    assert list(df2.experiment) == ["step", "switch"]
    assert df2["F_max [N]"][0] == df["F_max [N]"][0]
    now = {f.name: f.stat().st_mtime_ns for f in (out / "cache").glob("*.pkl")}
    assert len(now) == 2 and all(now[k] == v for k, v in cached.items())   # not recomputed

    # a user's file makes the folder unusable, --resume or not; it is never touched
    (out / "notes.txt").write_text("mine")
    assert main(argv(2, "--resume")) == 2
    assert "notes.txt" in capsys.readouterr().err and (out / "notes.txt").read_text() == "mine"


def test_a_stiffness_override_case_reproduces_the_stiffness_section():
    """A study of the PID step impact at k = 1 Nm/rad: the stiffness section's first row."""
    st = parse_study('[case]\nexperiment = "step"\ncontroller = "PID"\n[impact]\n'
                     'instants = "max TCP speed"\nstiffness = 1.0\n')
    r = safety_case(**st.cases[0])
    ref = pd.read_csv(ROOT / "reports" / "stiffness_sweep.csv")
    assert ref.k[0] == st.cases[0]["stiffness"] == 1.0
    assert r["K1"] == r["K2"] == 1.0 and r["n_impacts"] == 1
    np.testing.assert_allclose(r["F_max"], ref.F_max[0], rtol=1e-12)   # same simulate_impacts call


def test_histories_are_written_per_case_when_asked(tmp_path, monkeypatch):
    import importlib.util

    text = ('[case]\nexperiment = "step"\nduration = 3.0\ncontroller = "PSMC task"\n'
            '[grid]\nlam = [0.4, 0.8]\n[output]\ncsv = "r.csv"\nhistories = true\n')
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda n, *a: None if n in ("pyarrow", "fastparquet") else real(n, *a))
    assert history_format() == "csv"
    df = run_study_file(parse_study(text), tmp_path / "h", processes=1, progress=False).table
    assert "histories" not in df.columns and len(df) == 2
    files = sorted(p.name for p in (tmp_path / "h" / "histories").iterdir())
    assert files == ["case00000_closed_loop.csv", "case00000_impact.csv",
                     "case00001_closed_loop.csv", "case00001_impact.csv"]
    cl = pd.read_csv(tmp_path / "h" / "histories" / "case00000_closed_loop.csv")
    assert len(cl) == 3000 and "q1" in cl.columns                 # 3 s at 1 kHz
    imp = pd.read_csv(tmp_path / "h" / "histories" / "case00001_impact.csv")
    assert imp.filter(like="F").max().max() == pytest.approx(df.F_max[1], rel=1e-9)
    with pytest.raises(OutputError, match="--resume"):
        run_study_file(parse_study(text), tmp_path / "h", processes=1, progress=False).table
