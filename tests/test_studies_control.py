"""The control studies (quick mode) and the evaluation of the thesis' conclusions."""

import pathlib

import numpy as np
import pandas as pd
import pytest

from ppamsafety.experiments import conclusions as cc
from ppamsafety.sections import REGISTRY, Section, SectionResult, run_section


def test_registry_order():
    assert REGISTRY[:5] == ["safety_summary", "design", "tracking", "responses", "smc"]


@pytest.mark.parametrize("name, files", [
    ("responses", ["responses_step.png", "responses_step_ki12.png", "responses_step_lambda.png",
                   "responses_switch.png", "responses_switch_lambda.png", "responses_step.csv",
                   "responses_switch.csv"]),
    ("tracking", ["tracking_table_5_2.csv", "tracking_table_5_2.png", "tracking_circle_errors.png",
                  "tracking_circle_errors_ki12.png", "tracking_joint_angles.png",
                  "tracking_sensor_ablation.png", "tracking_sensor_ablation.csv",
                  "tracking_gc_ablation.csv", "tracking_conclusions.csv"]),
    ("smc", ["smc_chattering.png", "smc_commands.png", "smc_tuning.csv",
             "smc_chattering_sweep.csv"]),
])
def test_study_runs_quick_and_writes_its_files(tmp_path, name, files):
    res = run_section(name, tmp_path, quick=True)
    assert isinstance(res, SectionResult) and res.title and res.markdown
    for f in files:
        assert (tmp_path / f).exists(), f
        assert f in res.markdown or f.endswith(".csv") or f in " ".join(res.artifacts)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        pathlib.Path(a).name for a in res.artifacts)
    assert all(np.isfinite(v) for v in res.metrics.values() if isinstance(v, float))


def test_responses_in_three_parts_compute_writes_nothing(tmp_path, monkeypatch):
    """compute -> study object (no files, no figures), plot -> Figures, render -> Section."""
    from matplotlib.figure import Figure

    from ppamsafety.sections import responses

    monkeypatch.chdir(tmp_path)
    study = responses.compute(quick=True)
    assert list(tmp_path.iterdir()) == []
    assert isinstance(study, responses.ResponsesFindings)
    table = study.to_pandas()
    assert len(table) == 20 and set(table.experiment) == {"step", "switch"}
    assert np.isfinite(study.oscillation_hz) and study.oscillation_hz > 0
    figs = study.figures()
    assert set(figs) == {"responses_step.png", "responses_step_ki12.png",
                         "responses_step_lambda.png", "responses_switch.png",
                         "responses_switch_lambda.png"}
    assert all(isinstance(f, Figure) for f in figs.values())
    sec = responses.render(study)
    assert isinstance(sec, Section) and "**Step**" in sec.markdown
    names = [n for n, _ in sec.artifacts]
    assert set(figs) | {"responses_step.csv", "responses_switch.csv"} == set(names)
    assert all(n in sec.markdown for n in figs)
    assert sec.metrics["step_pid_overshoot_pct"] == study.metrics["step_pid_overshoot_pct"]
    assert list(tmp_path.iterdir()) == []


def test_study_arguments_are_checked():
    from ppamsafety.sections import lambda_sweep, resolve_arm, safety, section_module, write_artifact

    with pytest.raises(ValueError, match="unknown report section name='nope'"):
        section_module("nope")
    with pytest.raises(TypeError, match="arm must be an ArmParameters"):
        resolve_arm("thesis")
    for mod in (safety, lambda_sweep):           # any arm since issue 21; not a string
        with pytest.raises(TypeError, match="arm must be an ArmParameters"):
            mod.compute(quick=True, arm="thesis")
    with pytest.raises(TypeError, match="expected a matplotlib Figure or a pandas DataFrame"):
        write_artifact("text", "x.txt")


def test_tracking_table_has_thesis_values_and_ratios(tmp_path):
    from ppamsafety.sections import tracking

    th = tracking.thesis_table()
    assert len(th) == 30
    row = th[(th.variant == "PSMC joint Ki=12 λ=0.4") & (th.period_s == 10.0)].iloc[0]
    assert (row.thesis_mean_m, row.thesis_max_m) == (0.0022, 0.0053)       # §5.3.5
    errs = th.rename(columns={"thesis_mean_m": "mean_m", "thesis_max_m": "max_m"})
    cmp = tracking.compare_with_thesis(errs)
    np.testing.assert_allclose(cmp.ratio_mean, 1.0)
    wide = tracking.comparison_markdown(cmp)
    assert wide.shape == (10, 7) and "(1.00)" in wide.iloc[0, 1]


def _thesis_like_tables():
    """Toolkit-format tables built from the thesis' own Table 5.2 and plausible responses."""
    from ppamsafety.experiments import catalog
    from ppamsafety.sections import tracking

    fam = {lab: (catalog.variant_family(c), catalog.variant_lambda(c))
           for lab, c in catalog.thesis_variants()}
    errors = tracking.thesis_table().rename(columns={"thesis_mean_m": "mean_m",
                                                     "thesis_max_m": "max_m"})
    errors["family"] = [fam[v][0] for v in errors.variant]
    errors["lambda_s"] = [fam[v][1] for v in errors.variant]
    rows = []
    for lab, (f, lam) in fam.items():
        pid = f == "PID"
        rows.append({"variant": lab, "family": f, "lambda_s": lam,
                     "peak_tcp_speed_m_s": 3.0 if pid else 0.4 / lam,
                     "peak_qd1_rad_s": 5.0 if pid else 1.0, "peak_qd2_rad_s": 4.0 if pid else 0.5,
                     "overshoot_pct": 40.0 if pid else 1.0,
                     "t_reach_s": 0.2 if pid else (np.nan if lam > 1 else 3 * lam)})
    step = pd.DataFrame(rows)
    switch = step.copy()
    return errors, step, switch


def test_conclusions_on_the_thesis_own_table_hold():
    errors, step, switch = _thesis_like_tables()
    out = cc.evaluate_conclusions(errors, step, switch)
    assert [c.key for c in out] == list("abcdef")
    for c in out:
        assert isinstance(c, cc.Conclusion) and isinstance(c.holds, bool)
        assert c.claim and c.criterion and c.evidence and isinstance(c.numbers, dict)
        assert c.holds, (c.key, c.evidence)
    t = cc.conclusions_table(out)
    assert list(t.verdict) == ["holds"] * 6


def test_conclusions_detect_violations():
    errors, step, switch = _thesis_like_tables()
    bad = errors.copy()
    sel = (bad.variant == "PSMC joint Ki=12 λ=0.4") & (bad.period_s == 20.0)
    bad.loc[sel, "mean_m"] = 0.05                       # Ki=12 worse than task space
    a = cc.task_space_worst(bad)
    assert not a.holds and a.numbers["P20"]["worst_other"] == "PSMC joint Ki=12 λ=0.4"
    assert not cc.high_integral_gain_helps(bad).holds
    assert not cc.lambda_hardly_matters(bad).holds
    slow = step.copy()
    slow.loc[slow.variant == "PSMC task λ=0.8", "t_reach_s"] = 0.1
    assert not cc.lambda_slows_recovery(slow, switch).holds
    calm = step.copy()
    calm.loc[calm.family == "PID", "overshoot_pct"] = 2.0
    assert not cc.pid_violent_psmc_smooth(calm).holds
    with pytest.raises(ValueError, match="lacks columns"):
        cc.task_space_worst(errors.drop(columns="family"))
