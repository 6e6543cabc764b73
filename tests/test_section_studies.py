"""The report's sweep sections and their TOML studies are one definition.

The sections ``lambda_sweep`` and ``safety`` run the cases of the studies shipped with the
package (``ppamsafety/study_data``), the files ``ppamsafety sweep NAME`` runs; the report's
CSVs are what those studies give.
"""

import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from ppamsafety.cli import main
from ppamsafety.experiments.catalog import CIRCLE_EVAL, CIRCLE_WARMUP, thesis_variants
from ppamsafety.sections import lambda_sweep, safety
from ppamsafety.study_files import (STUDY_DATA, StudyFileError, load_study, shipped_study,
                                    study_path)
from ppamsafety.sweep_cases import safety_case

ROOT = Path(__file__).parent.parent
REPORTS = ROOT / "reports"


def test_the_shipped_studies_are_package_data():
    """A pip install carries the studies the report runs (the top-level studies/ is not
    installed)."""
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())
    patterns = cfg["tool"]["setuptools"]["package-data"]["ppamsafety"]
    files = sorted(STUDY_DATA.glob("*.toml"))
    assert files and all(any(f.relative_to(ROOT / "ppamsafety").match(p) for p in patterns)
                         for f in files)
    # one definition: no copy of a shipped study elsewhere in the repository
    for f in files:
        assert not (ROOT / "studies" / f.name).exists(), f.name


def test_lambda_sweep_runs_the_cases_of_its_study():
    study = load_study(shipped_study(lambda_sweep.STUDY))
    assert lambda_sweep.study_cases() == list(study.cases)
    ref = pd.read_csv(REPORTS / "lambda_sweep.csv")
    grid = study.cases.axes
    assert [(r.Ki_bar, r.lam) for r in ref.itertuples()] == \
        [(k, lam) for k in grid["ki_bar"] for lam in grid["lam"]]
    # the circle of the study is the thesis': 5 s warm-up and the 40 s of measurement of
    # Table 5.2 (its caption: "a dataset representing 40 seconds of measurements")
    assert CIRCLE_EVAL == 40.0 and CIRCLE_WARMUP == 5.0
    circle = [c for c in study.cases if c["experiment"] == "circle10"]
    assert all(lambda_sweep._duration(c) == CIRCLE_WARMUP + CIRCLE_EVAL for c in circle)
    assert (ref.circle_duration == CIRCLE_WARMUP + CIRCLE_EVAL).all()
    # quick: a subset of the study's cases, shorter circles
    quick = lambda_sweep.study_cases(quick=True)
    assert len(quick) == 2 * len(lambda_sweep.QUICK_LAMBDAS) * len(lambda_sweep.QUICK_KIS)
    assert all({k: v for k, v in c.items() if k != "duration"} in study.cases for c in quick)


def test_the_study_gives_the_numbers_of_the_report(tmp_path):
    """`ppamsafety sweep lambda_ki` gives the report's numbers: its first step case by the
    command line, its first circle case by the sweep engine's case."""
    ref = pd.read_csv(REPORTS / "lambda_sweep.csv").iloc[0]
    out = tmp_path / "lk"
    assert main(["sweep", "lambda_ki", "--out", str(out), "--max-cases", "1",
                 "--processes", "1", "--no-progress"]) == 0
    row = pd.read_csv(out / "lambda_ki.csv").iloc[0]
    assert (row["lam [s]"], row["ki_bar [bar/(rad s)]"]) == (ref.lam, ref.Ki_bar)
    assert row["F_max [N]"] == ref.F_max and row["HIC36 [-]"] == ref.HIC36
    study = load_study("lambda_ki")
    circle = next(c for c in study.cases if c["experiment"] == "circle10")
    assert (circle["lam"], circle["ki_bar"]) == (ref.lam, ref.Ki_bar)
    r = safety_case(**circle)
    assert r["track_mean"] == ref.circle_err_mean and r["track_max"] == ref.circle_err_max


def test_safety_runs_the_variants_of_table_6_1():
    experiments, variants = safety.table_6_1_definition()
    assert experiments == ("step", "switch")
    # the study's variants are the thesis' (labels and controllers)
    assert [v.label for v in variants] == [v.label for v in thesis_variants()]
    for a, b in zip(variants, thesis_variants()):
        assert type(a.controller) is type(b.controller)
        assert vars(a.controller).keys() == vars(b.controller).keys()
        for k, v in vars(a.controller).items():
            np.testing.assert_equal(v, vars(b.controller)[k], err_msg=f"{a.label}: {k}")
    ref = pd.read_csv(REPORTS / "safety_table_6_1.csv")
    for exp in experiments:
        assert list(ref[ref.experiment == exp].label) == [v.label for v in variants]


@pytest.mark.parametrize("arg, words", [
    ("lambda_kj", ["lambda_kj", "not a shipped study", "lambda_ki", "did you mean"]),
    ("nothing", ["no such file", "table_6_1"]),
])
def test_an_unknown_study_name_lists_the_shipped_ones(arg, words, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(StudyFileError) as e:
        study_path(arg)
    assert all(w in str(e.value) for w in words), str(e.value)
    assert main(["sweep", arg, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ppamsafety: error:") and arg in err
    assert not (tmp_path / "o").exists()


def test_a_file_of_a_shipped_name_in_the_working_folder_wins(tmp_path, monkeypatch):
    """A path is a path: a file called like a shipped study is read, not the shipped one."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "lambda_ki").write_text('[case]\nexperiment = "step"\n')
    assert study_path("lambda_ki") == Path("lambda_ki")
    assert len(load_study("lambda_ki").cases) == 1
    assert np.isfinite(len(load_study(STUDY_DATA / "lambda_ki.toml").cases))
