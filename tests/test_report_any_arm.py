"""The report for any arm (issue 21.4): the example arm's quick report, thesis values only for
the thesis arm.

The default suite builds the example arm's quick report for a subset of the sections (about a
minute on 2 cores); ``-m slow`` builds all of it, as CI's slow job does.
"""

import json
from pathlib import Path

import pandas as pd
import pytest

from ppamsafety.cli import main
from ppamsafety.design import load_arm
from ppamsafety.params import thesis_arm
from ppamsafety.sections import REGISTRY

ROOT = Path(__file__).parent.parent
EXAMPLE = ROOT / "examples" / "arms" / "forty_fibre_heavy_forearm.toml"
#: Columns that hold values printed in the thesis (or ratios to them): never for another arm.
THESIS_COLUMNS = ("thesis Table A.1 [mm]", "HIC_thesis", "Fmax_thesis", "HIC_ratio",
                  "Fmax_ratio", "thesis_mean_m", "thesis_max_m", "ratio_mean", "Fmax_table_6_1",
                  "HIC_table_6_1", "Fmax_thesis_free", "F/F_thesis", "delta_thesis")
QUICK_SUBSET = ("design", "head_model", "stiffness", "lambda_sweep")


def _no_thesis_values(out: Path):
    for f in out.glob("*.csv"):
        cols = set(pd.read_csv(f).columns)
        assert not cols & set(THESIS_COLUMNS), (f.name, cols & set(THESIS_COLUMNS))


def _build(out, *extra, processes=2):
    assert main(["report", "--outdir", str(out), "--quick", "--processes", str(processes),
                 *extra]) == 0
    return (out / "index.md").read_text()


def test_the_example_arm_quick_report_subset(tmp_path):
    out = tmp_path / "rep"
    md = _build(out, "--arm", str(EXAMPLE), "--only", ",".join(QUICK_SUBSET))
    assert "**40-fibre muscles, heavier forearm**" in md
    assert "thesis values and ratios belong to the thesis arm" in md
    assert md.count("*Computed for arm `40-fibre muscles, heavier forearm`") == len(QUICK_SUBSET)
    assert load_arm(out / "arm.toml") == load_arm(EXAMPLE)
    _no_thesis_values(out)
    a1 = pd.read_csv(out / "design_table_A1.csv")
    assert list(a1.columns) == ["quantity", "computed [mm]"]
    # its numbers are its own: the heavier forearm's head impacts differ from the thesis arm's
    sens = pd.read_csv(out / "head_model_sensitivity.csv").set_index("head model")
    m = json.loads((out / "metrics.json").read_text())
    assert m["head_model"]["F_max_N"] == sens.loc["thesis-frontal", "F_max [N]"]


def test_the_thesis_arm_from_a_file_gives_the_thesis_report(tmp_path):
    arm_file = tmp_path / "thesis.toml"
    arm_file.write_text(thesis_arm().to_toml())
    _build(tmp_path / "a", "--only", "design", processes=1)
    md = _build(tmp_path / "b", "--arm", str(arm_file), "--only", "design", processes=1)
    assert "It has the thesis arm's parameters" in md
    for name in ("design_table_A1.csv",):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    assert "thesis Table A.1 [mm]" in pd.read_csv(tmp_path / "b" / "design_table_A1.csv")


@pytest.mark.slow
def test_the_example_arm_full_quick_report(tmp_path):
    out = tmp_path / "rep"
    md = _build(out, "--arm", str(EXAMPLE), "--head", "thesis-frontal")
    assert all(f"*Study `{name}` ran in" in md for name in REGISTRY)
    _no_thesis_values(out)
    assert (out / "index.html").is_file() and (out / "head.toml").is_file()
