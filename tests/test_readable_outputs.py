"""Outputs a person can read: units on every column and axis, swept values in the unit the study
file used, labelled limit lines, marked exceedances, titles that fit."""

import re
from pathlib import Path

import pandas as pd
import pytest

from ppamsafety.cli import main
from ppamsafety.plots.figure import fit_titles, new_figure, save
from ppamsafety.plots.sweep import ABOVE, plot_envelope, plot_sweep
from ppamsafety.report.columns import PER_ROW, unit_in_name, unit_of, with_header_units
from ppamsafety.sections import REGISTRY
from ppamsafety.study_files import display_table, parse_study, run_study_file
from ppamsafety.sweep_cases import RESULT_COLUMNS, column_unit

ROOT = Path(__file__).resolve().parents[1]

BAR_STUDY = """[study]
name = "p-bar"
[case]
experiment = "step"
controller = "PID"
duration = 3.0
[impact]
instants = "max TCP speed"
[grid]
arm.pneumatics.mean_pressure = { values = [1.2, 1.5], unit = "bar" }
"""


# --------------------------------------------------------------------------------- sweeps

@pytest.fixture(scope="module")
def bar_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("sw") / "out"
    st = parse_study(BAR_STUDY)
    df = run_study_file(st, out, processes=1, progress=False).table
    return st, df, out


def test_a_bar_study_is_shown_in_bar(bar_sweep):
    st, df, out = bar_sweep
    assert list(df["arm.pneumatics.mean_pressure"]) == [1.2e5, 1.5e5]    # SI inside
    csv = pd.read_csv(out / "results.csv")
    assert list(csv["arm.pneumatics.mean_pressure [bar]"]) == [1.2, 1.5]
    page = (out / "summary.html").read_text()
    assert "<th>arm.pneumatics.mean_pressure [bar]</th>" in page
    assert "arm.pneumatics.mean_pressure [bar]" in page.split("<th>swept</th>")[1][:200]
    assert "120000" not in page


def test_every_sweep_column_has_its_unit_or_is_text(bar_sweep):
    st, df, out = bar_sweep
    csv = pd.read_csv(out / "results.csv")
    for col in csv.columns:
        if pd.api.types.is_numeric_dtype(csv[col]) and not pd.api.types.is_bool_dtype(csv[col]) \
                and csv[col].notna().any():
            assert re.search(r"\[[^\]]+\]$", col), col
    for col in RESULT_COLUMNS:                   # every result declared: unit, [-] or text
        assert col in ("label", "instant_HIC36", "diverged") or column_unit(col), col


def test_the_sweep_figure_has_units_labelled_limits_and_marks_above(bar_sweep):
    st, df, out = bar_sweep
    shown = df.assign(**{"arm.pneumatics.mean_pressure": df["arm.pneumatics.mean_pressure"] / 1e5})
    fig = plot_sweep(shown, ["arm.pneumatics.mean_pressure"], title="x " * 200,
                     units={"arm.pneumatics.mean_pressure": "bar"})
    ax_f = fig.axes[0]
    assert ax_f.get_xlabel() == "arm.pneumatics.mean_pressure [bar]"
    assert ax_f.get_ylabel() == "F_max [N]"
    labels = ax_f.get_legend_handles_labels()[1]
    assert any("660 N" in t for t in labels) and any("260 N" in t for t in labels)
    assert (df.F_max > 260).all() and "above a limit" in labels       # the PID step is above
    for ax in fig.axes:                                                 # every limit labelled
        lines = [ln for ln in ax.get_lines() if ln.get_linestyle() in ("--", ":")]
        if lines:
            assert ax.get_legend() is not None
            texts = [t.get_text() for t in ax.get_legend().get_texts()]
            assert all(ln.get_label() in texts for ln in lines), ax.get_ylabel()
    assert all("[" in ax.get_ylabel() for ax in fig.axes)
    save(fig, out / "check.png")
    sup = fig._suptitle
    assert "\n" in sup.get_text()
    r = fig.canvas.get_renderer()
    assert sup.get_window_extent(r).width <= fig.get_figwidth() * fig.dpi


def test_an_envelope_figure_has_units_and_marks_above():
    from types import SimpleNamespace

    ev = pd.DataFrame({"value": [0.5, 1.0, 2.0], "F_max": [300.0, 600.0, 900.0],
                       "status": ["ok"] * 3})
    env = SimpleNamespace(evaluations=ev, parameter="speed", metric="F_max",
                          limit_value=660.0, limit_label="maxilla fracture 660 N",
                          safe_value=1.0, description="speed envelope")
    fig = plot_envelope(env, unit="m/s")
    ax = fig.axes[0]
    assert ax.get_xlabel() == "speed [m/s]" and ax.get_ylabel() == "F_max [N]"
    labels = ax.get_legend_handles_labels()[1]
    assert "above the limit" in labels and "maxilla fracture 660 N" in labels
    ring = [ln for ln in ax.get_lines() if ln.get_label() == "above the limit"][0]
    assert list(ring.get_xdata()) == [2.0] and ring.get_markeredgecolor() == ABOVE["mec"]


def test_a_long_axes_title_is_wrapped_not_cut(tmp_path):
    fig, ax = new_figure(figsize=(3, 2))
    ax.set_title("a title much longer than the narrow axes it belongs to, " * 3)
    save(fig, tmp_path / "t.png")
    r = fig.canvas.get_renderer()
    assert "\n" in ax.title.get_text()
    assert ax.title.get_window_extent(r).width <= fig.get_figwidth() * fig.dpi
    fig2, ax2 = new_figure(figsize=(6, 2))
    ax2.set_title("short")
    fit_titles(fig2)
    assert ax2.title.get_text() == "short"


def test_display_table_declares_every_unit():
    st = parse_study(BAR_STUDY)
    df = pd.DataFrame({"arm.pneumatics.mean_pressure": [1.2e5], "F_max": [100.0],
                       "HIC36": [0.1], "label": ["PID"], "status": ["ok"]})
    t = display_table(st, df)
    assert list(t.columns) == ["arm.pneumatics.mean_pressure [bar]", "F_max [N]", "HIC36 [-]",
                               "label", "status"]
    assert t.iloc[0, 0] == pytest.approx(1.2)


# --------------------------------------------------------------------------------- report

#: Report CSV file -> its section, by the file names the sections write.
PREFIXES = (("design_", "design"), ("tracking_", "tracking"), ("responses_", "responses"),
            ("smc_", "smc"), ("head_model_", "head_model"),
            ("safety_summary", "safety_summary"), ("safety_", "safety"), ("person_", "person"),
            ("worst_direction", "worst_direction"), ("stiffness_", "stiffness"),
            ("lambda_sweep", "lambda_sweep"), ("effects_", "effects"),
            ("interaction_", "interaction"), ("iso_", "iso_15066"), ("reaction_", "reaction"),
            ("diagnose_sawtooth", "diagnose_sawtooth"), ("diagnose_trust", "diagnose_trust"),
            ("diagnose_", "diagnose_cases"), ("as_built", "as_built"),
            ("bench_", "cylinder_friction"))


def _section_of(name: str) -> str:
    return next(s for p, s in PREFIXES if name.startswith(p))


def _undeclared(folder: Path, section_of) -> list:
    missing = []
    for f in sorted(folder.glob("*.csv")):
        if f.name == "columns.csv":
            continue
        try:
            df = pd.read_csv(f)
        except pd.errors.EmptyDataError:
            continue
        sec = section_of(f.name)
        for col in df.columns:
            s = df[col]
            if not (pd.api.types.is_numeric_dtype(s) and not pd.api.types.is_bool_dtype(s)
                    and s.notna().any()):
                continue                                  # text and flags need no unit
            if unit_of(col, sec) is None:
                missing.append(f"{f.name}: {col} ({sec})")
            elif unit_of(col, sec) == PER_ROW:
                assert "unit" in df.columns, (f.name, col)
    return missing


def test_every_column_of_the_thesis_report_has_a_unit():
    """The committed report's CSV files: every numeric column states or declares its unit."""
    assert {s for _, s in PREFIXES} == set(REGISTRY)
    missing = _undeclared(ROOT / "reports", _section_of)
    # the renamed head-placement columns of worst_direction are declared under their new names
    missing = [m for m in missing if "_thesis (worst_direction)" not in m]
    assert missing == [], missing


def test_the_report_writes_its_data_dictionary_and_units_in_its_tables(tmp_path):
    out = tmp_path / "r"
    only = "design,head_model,stiffness"
    assert main(["report", "--quick", "--only", only, "--outdir", str(out), "--processes",
                 "2"]) == 0
    cols = pd.read_csv(out / "columns.csv", keep_default_na=False)
    assert set(cols.section) == set(only.split(","))
    num = cols[cols.kind == "number"]
    assert len(num) > 20 and (num.unit != "").all(), num[num.unit == ""]
    of = dict(zip(cols.file, cols.section))
    assert _undeclared(out, of.get) == []
    md = (out / "index.md").read_text()
    assert "| k [N m/rad] |" in md or "| k [N m/rad]" in md      # stiffness sweep table
    assert "F_max [N]" in md


def test_header_units_are_added_only_where_missing():
    md = ("text | not a table\n\n| label | F_max | t0_s | HIC36 [-] | odd |\n|---|---|---|---|---|\n"
          "| PID | 1 | 2 | 3 | 4 |\n")
    out = with_header_units(md, "safety")
    assert "| label | F_max [N] | t0_s | HIC36 [-] | odd |" in out
    assert out.startswith("text | not a table")
    assert unit_in_name("q1_deg") == "deg" and unit_in_name("F [N]") == "N"
    assert unit_of("k", "head_model") != unit_of("k", "stiffness")


def _unlabelled_axes(fig) -> list:
    """Axis labels of a figure without a unit ([...]) on an axis of numbers."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()
    bad = []
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            label = axis.get_label_text()
            if not label or re.search(r"\[[^\]]*\]", label):
                continue
            ticks = [t.get_text().replace("−", "-") for t in axis.get_ticklabels()
                     if t.get_text()]
            numeric = all(re.fullmatch(r"[-+]?[\d.]+(e[-+]?\d+)?|\$.*\$", t) for t in ticks)
            if ticks and numeric:
                bad.append(label)
    return bad


@pytest.mark.parametrize("name", ["design", "head_model", "stiffness", "diagnose_sawtooth"])
def test_every_axis_of_numbers_in_a_section_figure_has_a_unit(name):
    from ppamsafety.sections import section_module

    mod = section_module(name)
    sec = mod.render(mod.compute(quick=True))
    figs = [(f, obj) for f, obj in sec.artifacts if hasattr(obj, "savefig")]
    assert figs
    fig, ax = new_figure()                        # the check can fail
    ax.plot([1, 2], [3, 4])
    ax.set_ylabel("HIC36")
    assert _unlabelled_axes(fig) == ["HIC36"]
    bad = {f: _unlabelled_axes(obj) for f, obj in figs}
    assert not any(bad.values()), bad
