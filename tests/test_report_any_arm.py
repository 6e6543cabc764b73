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
    from ppamsafety.report.build import select_sections

    md = _build(out, "--arm", str(EXAMPLE), "--head", "thesis-frontal")
    names, left = select_sections(load_arm(EXAMPLE))
    assert all(f"*Study `{name}` ran in" in md for name in names)
    assert all(f"`{name}` (" in md.split("##")[0] for name in left)       # said, and why
    _no_thesis_values(out)
    assert (out / "index.html").is_file() and (out / "head.toml").is_file()


# ------------------------------------------------------------ which sections, processes, warnings

def test_the_report_for_another_arm_leaves_out_what_does_not_concern_it():
    from ppamsafety.params.effects import Effects
    from ppamsafety.report.build import select_sections

    arm = load_arm(EXAMPLE)                         # declares hysteresis: its studies run
    names, left = select_sections(arm)
    assert set(left) == {"cylinder_friction", "as_built"}
    assert "effects" in names and "diagnose_sawtooth" in names
    assert "bench case study" in left["cylinder_friction"]
    bare = arm.replace(effects=Effects())
    names, left = select_sections(bare)
    assert {"effects", "diagnose_sawtooth"} <= set(left) and "effects" not in names
    names, left = select_sections(bare, include=["cylinder_friction"], exclude=["smc"])
    assert "cylinder_friction" in names and "smc" not in names and "cylinder_friction" not in left
    assert select_sections(bare, only=["cylinder_friction"]) == (["cylinder_friction"], {})
    assert select_sections(None) == (list(REGISTRY), {})          # the thesis report: all
    assert select_sections(thesis_arm())[1] == {}
    with pytest.raises(ValueError, match="only names every section"):
        select_sections(arm, only=["design"], include=["smc"])
    with pytest.raises(ValueError, match="unknown report sections"):
        select_sections(arm, include=["cylinder"])


def test_the_header_says_what_was_left_out(tmp_path, capsys):
    out = tmp_path / "rep"
    keep = ("head_model", "cylinder_friction", "as_built")      # the last two: left out
    assert main(["report", "--arm", str(EXAMPLE), "--quick", "--outdir", str(out),
                 "--processes", "1", "--exclude", ",".join(n for n in REGISTRY
                                                           if n not in keep)]) == 0
    md = (out / "index.md").read_text()
    assert "Left out, as they do not concern this arm" in md and "`cylinder_friction`" in md
    assert "*Study `head_model` ran in" in md and "*Study `design` ran in" not in md
    assert main(["report", "--quick", "--only", "design", "--include", "smc", "--outdir",
                 str(tmp_path / "x")]) == 2
    assert "--only names every section" in capsys.readouterr().err


@pytest.mark.parametrize("processes, inner", [(1, 1), (2, 2)])
def test_processes_is_honoured_inside_a_section(processes, inner, monkeypatch, tmp_path):
    """--processes 1: the lambda sweep's own sweep runs in this process; one section alone
    gets every process the report has."""
    import ppamsafety.sections.lambda_sweep as ls

    seen = []
    real = ls.run_sweep

    def spy(*args, **kwargs):
        seen.append(kwargs.get("processes"))
        return real(*args, **kwargs)
    monkeypatch.setattr(ls, "run_sweep", spy)
    assert main(["report", "--quick", "--only", "lambda_sweep", "--outdir", str(tmp_path / "r"),
                 "--processes", str(processes)]) == 0
    assert seen == [inner]


def test_a_sections_warning_names_it(monkeypatch, tmp_path, capsys):
    import warnings

    import ppamsafety.sections.head_model as hm

    real = hm.compute

    def warns(**kw):
        warnings.warn("the solver stopped at its iteration limit", RuntimeWarning)
        return real(**kw)
    monkeypatch.setattr(hm, "compute", warns)
    assert main(["report", "--quick", "--only", "head_model", "--outdir", str(tmp_path / "r"),
                 "--processes", "1"]) == 0
    err = capsys.readouterr().err
    assert "ppamsafety: warning: section head_model: the solver stopped at its iteration " \
           "limit" in err


def test_rows_with_nothing_to_score_are_not_failed():
    from ppamsafety.diagnose.scenarios import scores
    from ppamsafety.sections.diagnose_trust import _met_text

    from ppamsafety.diagnose.scenarios import load_results

    rows = load_results()
    some = rows[rows["hidden"].map(len) == 1].head(5)     # no "nothing hidden" scenario
    s = scores(some).set_index("measure")
    empty = s.loc["nothing hidden: something named"]
    assert empty["count"] == 0 and empty["met"] is None
    assert s.loc["'high' names right (precision)", "met"] in (True, False)
    text = _met_text(s.reset_index()).set_index("measure")["met"]
    assert text["nothing hidden: something named"] == "no samples"
    assert set(text) <= {"yes", "no", "no samples", ""}


@pytest.mark.slow
def test_the_hysteresis_studies_asked_for_an_arm_without_hysteresis_state_the_assumption(
        tmp_path):
    from ppamsafety.params.effects import Effects
    from ppamsafety.sections import run_section

    bare = load_arm(EXAMPLE).replace(effects=Effects(), name="no hysteresis declared")
    for name in ("effects", "diagnose_sawtooth"):
        (tmp_path / name).mkdir()
        md = run_section(name, tmp_path / name, quick=True, arm=bare).markdown
        assert "ASSUMED: the arm declares no hysteresis" in md, name
        assert "25-fibre muscles (§3.6.5)" in md, name
