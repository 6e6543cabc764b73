"""The impact studies run end to end in quick mode and write their artifacts."""

import pytest

from ppamsafety.sections import (head_model, lambda_sweep, run_section, stiffness,
                                write_section)


@pytest.fixture(scope="module")
def safety_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("safety")
    return out, run_section("safety", out, quick=True)


def test_safety_study_writes_its_artifacts(safety_run):
    out, res = safety_run
    for f in ["safety_table_6_1.csv", "safety_table_6_1.png", "safety_every_instant.csv",
              "safety_fmax_over_time.png", "safety_worst_histories.png"]:
        assert (out / f).exists(), f
    assert "Table 6.1 reproduced" in res.markdown


def test_safety_study_reproduces_the_thesis_ordering(safety_run):
    """PID is far more dangerous than PSMC on the step, and PID breaks 660 N (§6.3.3)."""
    _, res = safety_run
    assert res.metrics["pid_step_F_max"] > 660.0
    assert res.metrics["conclusions_hold"] >= res.metrics["conclusions"] - 1


@pytest.mark.parametrize("module, files", [
    (stiffness, ["stiffness_sweep.csv", "stiffness_sweep.png", "stiffness_table.csv",
                 "stiffness_fit.csv", "stiffness_rigid.csv"]),
    (head_model, ["head_model_fit.png", "head_model_fits.csv", "head_model_sensitivity.csv"]),
    (lambda_sweep, ["lambda_sweep.csv", "lambda_sweep.png"]),
])
def test_impact_study_quick(tmp_path, module, files):
    study = module.compute(quick=True)
    assert list(tmp_path.iterdir()) == []                  # compute writes nothing
    table = study.to_pandas()
    assert len(table) > 0 and table.select_dtypes("number").notna().all().all()
    res = write_section(module.render(study), tmp_path)
    for f in files:
        assert (tmp_path / f).exists(), f
    assert res.markdown.strip()


def test_worst_direction_study_quick():
    """Issue 12 item 6 in quick mode: the worst head placement is never better than the
    thesis' (along the TCP velocity), lies a few degrees aside, and is measurably worse (the
    effective mass grows faster aside than the normal speed falls); PSMC stays below the
    660 N maxilla tolerance, PID's step does not."""
    from ppamsafety.params.head import MAXILLA_FRACTURE_N
    from ppamsafety.sections import worst_direction as wd

    study = wd.compute(quick=True)
    t = study.to_pandas()
    assert len(t) == 4
    assert (t["ratio_F_max"] >= 1.0).all() and (t["ratio_HIC36"] >= 1.0).all()
    assert (t["ratio_F_max"] > 1.005).all() and (t["ratio_F_max"] < 1.1).all()
    assert (t["psi_F_max_deg"].abs().between(2.0, 30.0)).all()
    assert (t["F_max_worst"] >= t["F_max_same_instant"] - 1e-9).all()
    pid = t[(t.experiment == "step") & (t.label == "PID")].iloc[0]
    assert pid.F_max_worst > MAXILLA_FRACTURE_N
    assert study.metrics["psmc_below_maxilla"]
    assert study.metrics["rho_max"] <= 1.005
    sec = wd.render(study)
    names = [n for n, _ in sec.artifacts]
    assert "worst_direction_polar.png" in names and "worst_direction.csv" in names
    assert "how much worse" in sec.markdown.lower()


def test_stiffness_study_conventions_quick():
    """Fig. 6.3 (§6.3.4): the flexible joint rises by < 5 N from 1 to 6000 Nm/rad, the frozen
    equilibrium falls; the rigid limit is the rigid arm; energy balanced everywhere."""
    m = stiffness.compute(quick=True).metrics
    assert m["dF_frozen_6000_N"] < -5.0                        # wrong sign, beyond the bound
    assert m["F_frozen_1e6_N"] < 0.5 * m["F_k1_N"]             # clamped link
    assert m["dF_flexible_B0_6000_N"] == 0.0                   # PPAM drive: free joint
    assert 0.0 < m["dF_flexible_Bppam_6000_N"] < m["rise_saturation_N"] < 5.0
    assert m["B_ppam_1_kgm2"] < 0.01 and m["B_ppam_2_kgm2"] < 0.01
    assert m["max_abs_energy_error"] < 1e-4
    assert m["max_flex_kmax_rigid_rel"] < 0.01                 # k = 1e6 against rigid
    assert m["max_rigid_two_body_rel"] < 3e-3
