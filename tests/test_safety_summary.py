"""The safety summary, the whole-person section's computations, and impact --contact/--covering
with covering and contact point files."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from ppamsafety.cli import main
from ppamsafety.design import load_arm
from ppamsafety.impact.anywhere import simulate_contacts
from ppamsafety.impact.summary import (ranking_limit, region_body, region_bodies,
                                       region_point_verdicts, safety_summary)
from ppamsafety.impact.verdicts import criteria_for
from ppamsafety.params import thesis_arm
from ppamsafety.params.arm_file import ArmFileError
from ppamsafety.params.contact import FOREHEAD, THESIS_COVERING, arm_contact_points
from ppamsafety.params.contact_files import (contact_point_to_toml, covering_to_toml,
                                             load_contact_point, load_covering,
                                             resolve_contact_point, resolve_covering)
from ppamsafety.params.iso_ts_15066 import REGIONS, body_region
from ppamsafety.report.build import first_screen

ROOT = Path(__file__).parent.parent
EXAMPLE = ROOT / "examples" / "arms" / "forty_fibre_heavy_forearm.toml"


def test_one_body_per_annex_a_region_the_forehead_validated():
    pairs = region_bodies()
    assert len(pairs) == len(REGIONS) == 12
    assert len({b.name for _, b in pairs}) == 12
    r0, b0 = pairs[0]
    assert r0.name == "skull/forehead" and b0.layers == FOREHEAD.layers
    for r, b in pairs[1:]:                  # the Annex A two-body model of the region
        assert b.mass == r.effective_mass and b.layers[0].stiffness == r.spring_constant
    # the ranking limit is the region's smallest force criterion
    assert ranking_limit("skull/forehead").limit == 130.0
    assert ranking_limit("chest/sternum").limit == pytest.approx(
        min(c.limit for c in criteria_for("chest/sternum") if c.metric == "F_max"))
    assert region_body("face", head="thesis-frontal").layers[0].law == "power"


@pytest.fixture(scope="module")
def quick_summary():
    return safety_summary(every=40)


def test_summary_rows_govern_and_match_a_fresh_simulation(quick_summary):
    s = quick_summary
    assert len(s.cases) == 20 and len(s.table) == 8            # 4 families x 2 experiments
    assert set(s.table.family) == {"PID", "PSMC joint Ki=2", "PSMC joint Ki=12", "PSMC task"}
    arm = thesis_arm()
    for r in s.table.to_dict("records"):
        # the governing criterion has the smallest margin of the region's criteria at that case
        v = s.verdicts[(s.verdicts.experiment == r["experiment"])
                       & (s.verdicts.variant == r["variant"])]
        assert v["margin_pct"].min() == pytest.approx(r["margin [%]"])
        assert r["margin [%]"] == pytest.approx(100 * (r["limit"] - r["value"]) / r["limit"])
        # the family row is its worst variant
        g = s.cases[(s.cases.experiment == r["experiment"]) & (s.cases.family == r["family"])]
        assert r["margin [%]"] == g["margin [%]"].min() and r["variants"] == len(g)
        # the worst case is an impact the engine gives again
        body = dict((b.name, b) for _, b in region_bodies())[r["body_region"]]
        again = simulate_contacts(arm, [r["q1 [rad]"], r["q2 [rad]"]],
                                  [r["qd1 [rad/s]"], r["qd2 [rad/s]"]],
                                  [r["K1 [N m/rad]"], r["K2 [N m/rad]"]],
                                  point=r["contact_point"], body=body).summary.iloc[0]
        assert again.F_max == pytest.approx(r["F_max [N]"], rel=1e-9)
        # the dependence flags say whether the verdict flips
        assert r["depends_on_covering"] == ((r["covered_value"] < r["limit"]) != r["passed"])
    # the PID step is the worst of all, and no variant of the bare thesis arm passes
    assert s.overall["family"] == "PID" and s.metrics["cases_passing"] == 0


def test_summary_section_formats_and_the_report_opens_with_it(quick_summary):
    from ppamsafety.sections import REGISTRY
    from ppamsafety.sections.safety_summary import render

    sec = render(quick_summary)
    assert sec.title == "Safety summary"
    o = quick_summary.overall
    assert f"{o['value']:.4g} N" in sec.markdown and o["criterion"] in sec.markdown
    assert {n for n, _ in sec.artifacts} == {"safety_summary.csv", "safety_summary_cases.csv",
                                             "safety_summary_verdicts.csv",
                                             "safety_summary_worst.png"}
    pts = quick_summary.worst_scan.worst
    assert len(pts) == 4 and pts["margin_pct"].min() == pytest.approx(o["margin [%]"])
    assert REGISTRY[0] == "safety_summary"
    assert first_screen(["design", "safety", "safety_summary"])[0] == "safety_summary"
    assert first_screen(["design", "safety"]) == ["design", "safety"]


def test_summary_for_another_arm_has_its_own_numbers():
    arm = load_arm(EXAMPLE)
    s = safety_summary(arm, experiments=("step",), every=200)
    assert s.arm_name == arm.name and len(s.table) == 4
    assert np.isfinite(s.table["value"]).all()


def test_region_point_verdicts_cover_every_region_and_point():
    arm = thesis_arm()
    t = region_point_verdicts(arm, experiments=("step",))
    assert len(t) == 12 * 4
    assert set(t.contact_point) == {p.name for p in arm_contact_points(arm)}
    assert (t["impacts"] == 10).all() and (t["passing"] <= t["impacts"]).all()
    # softer regions take less force from the same impacts: the chest (25 N/mm, 40 kg) less
    # than the validated head at the tool point
    tp = t[t.contact_point == "tool point"].set_index("body_region")
    assert tp.loc["chest/sternum", "F_max [N]"] < tp.loc["skull/forehead", "F_max [N]"]


# ---------------------------------------------------------------- covering and contact files
def test_covering_file_round_trip_and_units(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text(covering_to_toml(THESIS_COVERING))
    assert load_covering(f) == THESIS_COVERING
    g = tmp_path / "mm.toml"
    g.write_text('format = "ppamsafety-covering/1"\nname = "foam"\n[[layer]]\nname = "PU"\n'
                 'law = "thin-layer"\nmodulus = { value = 1.16, unit = "MPa" }\n'
                 'thickness = { value = 10, unit = "mm" }\nstrain_limit = 0.8\n'
                 'hysteresis = { value = 9.8, unit = "s/m" }\n')
    lay = load_covering(g).layers[0]
    assert lay.modulus == pytest.approx(1.16e6) and lay.thickness == pytest.approx(0.01)
    assert resolve_covering("bare metal").bare


@pytest.mark.parametrize("text, match", [
    ('format = "ppamsafety-region/1"\nname = "x"\n', "format"),
    ('format = "ppamsafety-covering/1"\n', "missing key name"),
    ('format = "ppamsafety-covering/1"\nname = "x"\n[[layer]]\nname = "a"\nlaw = "thin-layer"\n'
     'modulus = 1e6\nthickness = { value = 5, unit = "mm" }\n', "modulus"),
    ('format = "ppamsafety-covering/1"\nname = "x"\n[[layer]]\nname = "a"\nlaw = "thin-layer"\n'
     'modulus = { value = 1, unit = "MPa" }\nthickness = { value = 5, unit = "furlong" }\n',
     "thickness.unit"),
    ('format = "ppamsafety-covering/1"\nname = "x"\n[[layer]]\nname = "a"\nlaw = "rubber"\n',
     "law"),
    ('format = "ppamsafety-covering/1"\nname = "x"\nthicknes = 1\n', "thicknes"),
])
def test_bad_covering_files_name_the_key(tmp_path, text, match):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    with pytest.raises(ArmFileError, match=match):
        load_covering(f)


def test_contact_point_file_with_its_covering_file(tmp_path):
    (tmp_path / "cov.toml").write_text(covering_to_toml(THESIS_COVERING))
    p = tmp_path / "pt.toml"
    p.write_text('format = "ppamsafety-contact/1"\nname = "gripper edge"\nlink = 2\n'
                 'position = { value = 300, unit = "mm" }\nshape = "edge"\n'
                 'radius = { value = 2, unit = "mm" }\ncovering = "cov.toml"\n')
    pt = load_contact_point(p)
    assert (pt.link, pt.position, pt.shape, pt.radius) == (2, pytest.approx(0.3), "edge",
                                                            pytest.approx(2e-3))
    assert pt.covering == THESIS_COVERING
    q = tmp_path / "again.toml"
    q.write_text(contact_point_to_toml(pt, covering_file="cov.toml"))
    assert load_contact_point(q) == pt
    tool = resolve_contact_point("tool point", thesis_arm())
    assert tool == arm_contact_points(thesis_arm())[0]
    with pytest.raises(ValueError, match="did you mean 'elbow'"):
        resolve_contact_point("elbo", thesis_arm())
    bad = tmp_path / "bad.toml"
    bad.write_text('format = "ppamsafety-contact/1"\nname = "x"\nlink = 3\n'
                   'position = { value = 1, unit = "m" }\nshape = "flat"\n')
    with pytest.raises(ArmFileError, match="link = 3"):
        load_contact_point(bad)


# ------------------------------------------------------------------------------ command line
def test_impact_at_a_contact_point_uses_the_regions_limits(tmp_path, capsys):
    (tmp_path / "cov.toml").write_text(covering_to_toml(THESIS_COVERING))
    assert main(["impact", "--q", "50", "-80", "--qd", "2", "0", "--contact", "forearm",
                 "--region", "chest/sternum"]) == 0
    out = capsys.readouterr().out
    chest = body_region("chest/sternum")
    assert f"limit {chest.force_transient:8.4g} N" in out
    assert "contact at the forearm" in out and "Annex A two-body model" in out
    # the printed force is the engine's for that point and region
    arm = thesis_arm()
    from ppamsafety.design import rest_stiffness

    q = np.radians([50.0, -80.0])
    s = simulate_contacts(arm, q, [2.0, 0.0], rest_stiffness(arm, q).stiffness,
                          point="forearm", body=region_body("chest/sternum")).summary.iloc[0]
    assert f"F_max           {s.F_max:.4g} N" in out
    # a covering file: less force than bare at the forehead
    assert main(["impact", "--q", "50", "-80", "--qd", "2", "0", "--covering",
                 str(tmp_path / "cov.toml")]) == 0
    covered = capsys.readouterr().out
    assert main(["impact", "--q", "50", "-80", "--qd", "2", "0", "--contact",
                 "tool point"]) == 0
    bare = capsys.readouterr().out

    def fmax(text):
        return float(next(l for l in text.splitlines() if l.startswith("F_max")).split()[1])

    assert fmax(covered) < fmax(bare)
    assert "validated head" in bare and "iso_ts_15066_qs" in bare


@pytest.mark.parametrize("argv, words", [
    (["--contact", "elbo"], ["--contact elbo", "did you mean 'elbow'", "tool point"]),
    (["--covering", "foam"], ["--covering foam", "bare metal", "thesis-implied"]),
    (["--covering", "missing.toml"], ["--covering missing.toml", "does not exist"]),
    (["--contact", "forearm", "--region", "chst"], ["--region chst", "chest/sternum"]),
])
def test_impact_contact_bad_input_names_the_option(argv, words, capsys):
    rc = main(["impact", "--q", "50", "-80", "--qd", "2", "0", *argv])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("ppamsafety: error: ") and err.count("\n") == 1, err
    for w in words:
        assert w in err, (w, err)


def test_impact_contact_refuses_a_point_that_does_not_move(capsys):
    # the elbow does not move when only joint 2 turns
    rc = main(["impact", "--q", "50", "-80", "--qd", "0", "1", "--contact", "elbow"])
    err = capsys.readouterr().err
    assert rc == 2 and "elbow" in err and "does not move" in err


@pytest.mark.slow
def test_the_whole_person_section_on_the_thesis_arm(tmp_path):
    from ppamsafety.sections import run_section

    res = run_section("person", tmp_path, quick=True)
    m = res.metrics
    assert m["drop_passed"] and 225.0 <= m["drop_peak_g"] <= 275.0
    assert not 225.0 <= m["thesis_frontal_drop_g"] <= 275.0      # the lumped law fails it
    assert m["covering_rms_sigma"] <= 1.0 < m["bare_rms_sigma"]     # Table 6.1 needs a covering
    env = pd.read_csv(tmp_path / "person_envelope.csv")
    assert env.monotone.all()
    assert (env["thinnest safe [mm]"] > env["thickest unsafe [mm]"]).all()
    assert (env["margin [N]"] >= 0).all()
    reg = pd.read_csv(tmp_path / "person_regions.csv")
    assert len(reg) == 2 * 12 * 4 and set(reg.covering) == {"bare metal", "thesis-implied"}


def test_summary_inputs_are_checked():
    with pytest.raises(TypeError, match="experiments"):
        safety_summary(experiments="step")
    with pytest.raises(ValueError, match="circle10"):
        region_point_verdicts(experiments=("circle10",))
    with pytest.raises(TypeError, match="arm"):
        safety_summary("thesis arm")
    with pytest.raises(ValueError, match="covering"):
        safety_summary(covering="foam")


def test_the_report_opens_with_the_summary_whatever_the_order(tmp_path):
    out = tmp_path / "rep"
    assert main(["report", "--quick", "--only", "design,safety_summary", "--outdir", str(out),
                 "--processes", "1"]) == 0
    md = (out / "index.md").read_text()
    titles = [line for line in md.splitlines() if line.startswith("## ")]
    assert titles[0] == "## Safety summary" and len(titles) == 2
    cols = pd.read_csv(out / "columns.csv", keep_default_na=False)
    num = cols[(cols.kind == "number") & (cols.section == "safety_summary")]
    assert len(num) > 10 and (num.unit != "").all(), num[num.unit == ""]
