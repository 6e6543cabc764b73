"""Body regions of ISO/TS 15066 Annex A, injury criteria and one verdict everywhere.

Oracles: the two-body closed form of Annex A (peak force F = v sqrt(mu K), the permissible
speed v = F / sqrt(mu K)) against the two-body engine for every body region; the NHTSA
lognormal AIS curves against scipy's lognormal distribution with the published
coefficients; envelopes on curves whose crossings are known exactly.
"""

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.stats import lognorm

from ppamsafety.cli import main
from ppamsafety.envelope import LIMITS, safety_envelope, search_envelope
from ppamsafety.impact.head import head_model
from ppamsafety.impact.pfl import linear_peak_force, max_relative_speed, reduced_mass
from ppamsafety.impact.twobody import two_body_impact
from ppamsafety.impact.verdicts import (ais_risk, annex_a_head, criteria_for, criterion,
                                        criterion_names, evaluate, impact_verdicts)
from ppamsafety.params import thesis_arm
from ppamsafety.params.arm_file import ArmFileError
from ppamsafety.params.injury import AIS_RISK, FRACTURE_FORCES
from ppamsafety.params.iso_ts_15066 import (LOCATIONS, REGIONS, BodyRegion, PainThreshold,
                                            body_region, body_region_names, load_region,
                                            resolve_region)
from ppamsafety.study_files import StudyFileError, parse_study
from ppamsafety.sweep_cases import safety_sweep

# ---- the body model: 29 locations in 12 regions, each value cited -------------------------


def test_every_annex_a_location_is_there_with_its_region_values_and_sources():
    names = body_region_names()
    assert len(names) == 29 and len(REGIONS) == 12
    assert [body_region(i).name for i in range(1, 30)] == names
    for name in names:
        r = body_region(name)
        short, F, K, m, in_ts, head, *_ = REGIONS[r.region]
        # Table A.2 force per region, A.3 K [N/mm] and m_H [kg], in SI
        assert (r.force_quasi_static, r.spring_constant, r.effective_mass) == (F, K * 1e3, m)
        assert r.force_transient == 2 * F and r.head == head and r.transient_in_ts == in_ts
        for f in ("force_quasi_static", "pressure_quasi_static", "spring_constant",
                  "effective_mass", "transient_factor"):
            assert r.source_of(f).strip()
        # only the head's transient multiplier is unconfirmed: the TS gives none
        assert r.confirmed("transient_factor") == in_ts
        assert all(r.confirmed(f) for f in ("force_quasi_static", "pressure_quasi_static",
                                            "spring_constant", "effective_mass"))
    # spot values of Table A.2 as the public transcriptions print them [N/cm^2]
    assert body_region("skull/forehead").pressure_quasi_static == 130e4
    assert body_region("hand/forefinger pad D").pressure_quasi_static == 300e4
    assert body_region("hand/back ND").pressure_quasi_static == 190e4
    assert body_region("lower leg/calf muscle").pressure_quasi_static == 210e4
    assert sum(loc[1] == "hands and fingers" for loc in LOCATIONS) == 9


@pytest.mark.parametrize("name", [loc[3] for loc in LOCATIONS])
def test_annex_a_two_body_closed_form_for_every_region(name):
    """Peak force v sqrt(mu K) and the permissible speed F_T / sqrt(mu K), against the engine.

    The two-body engine (RK4, linear undamped spring = Hunt-Crossley with n = 1, b = 0)
    must give the closed form within 0.5 % (its step is 1 us here; the contact lasts
    pi sqrt(mu/K), at least 0.5 ms for every region), and at the Annex A speed the force
    is the transient limit.
    """
    r = body_region(name)
    m_r = 1.25                                           # Annex A.4: M/2, M = 2.5 kg
    mu = reduced_mass(r.effective_mass, m_r)
    v_max = max_relative_speed(r.force_transient, r.spring_constant, mu)
    assert v_max == pytest.approx(r.force_transient / math.sqrt(mu * r.spring_constant))
    speeds = np.array([0.25 * v_max, v_max])
    dur = 2.0 * math.pi * math.sqrt(mu / r.spring_constant)
    F = two_body_impact(speeds, arm_mass=m_r, head_mass=r.effective_mass,
                        stiffness=r.spring_constant, exponent=1.0, damping=0.0, dt=1e-6,
                        duration=dur)["F_max"]
    assert F == pytest.approx(linear_peak_force(speeds, r.spring_constant, mu), rel=5e-3)
    assert F[1] == pytest.approx(r.force_transient, rel=5e-3)
    # the Annex A body model of the region gives the same force in the two-body engine
    h = annex_a_head(r)
    assert (h.mass, h.stiffness, h.exponent, h.damping) == (r.effective_mass,
                                                             r.spring_constant, 1.0, 0.0)


# ---- region files ------------------------------------------------------------------------

def test_region_files_round_trip_and_carry_measured_pain_thresholds(tmp_path):
    for name in body_region_names():
        r = body_region(name)
        assert BodyRegion.from_toml(r.to_toml()) == r
    mine = replace(body_region("lower arm/forearm muscle"), name="my forearm",
                   pain=(PainThreshold("lab2026", "force", "transient",
                                       ((25.0, 180.0), (50.0, 230.0), (75.0, 290.0)),
                                       "our own measurement, 2026"),))
    f = tmp_path / "forearm.toml"
    f.write_text(mine.to_toml())
    back = load_region(f)
    assert back == mine and resolve_region(str(f)) == mine
    names = [c.name for c in criteria_for(back)]
    assert names == ["iso_ts_15066", "iso_ts_15066_p", "pain_lab2026_p25", "pain_lab2026_p50", "pain_lab2026_p75"]
    # a user's unit: N/mm and N/cm^2 are converted
    text = mine.to_toml().replace('value = 40000.0, unit = "N/m"', 'value = 40.0, unit = "N/mm"')
    assert BodyRegion.from_toml(text).spring_constant == 40e3


@pytest.mark.parametrize("change, key", [
    (("format = \"ppamsafety-region/1\"", "format = \"ppamsafety-head/1\""), "format"),
    (("name = \"skull/forehead\"\n", ""), "missing key name"),
    (("spring_constant = { value = 150000.0, unit = \"N/m\"",
      "spring_constant = { value = 150000.0, unit = \"N/s\""), "spring_constant.unit"),
    (("effective_mass = { value = 4.4,", "effective_mass = { value = -4.4,"),
     "effective_mass.value = -4.4"),
    (("location = 1\n", "location = 31\n"), "location = 31"),
    (("head = true", "head = \"yes\""), "head = 'yes'"),
    (("head = true", "head = true\ncolour = \"red\""), "unknown key 'colour'"),
    (("force_quasi_static = { value = 130.0, unit = \"N\",",
      "force_quasi_static = { value = 130.0, units = \"N\","), "force_quasi_static: unknown key"),
    (("force_quasi_static = { value = 130.0", "force_quasi_static = { value = \"130\""),
     "force_quasi_static.value"),
])
def test_bad_region_files_name_the_key(change, key):
    text = body_region("skull/forehead").to_toml()
    assert change[0] in text
    with pytest.raises(ArmFileError) as exc:
        BodyRegion.from_toml(text.replace(change[0], change[1]), where="r.toml")
    assert str(exc.value).startswith("r.toml: ") and key in str(exc.value)


def test_bad_pain_thresholds_name_the_entry():
    base = body_region("face").to_toml()
    bad = base + ('\n[[pain]]\nstudy = "x"\nquantity = "force"\ncontact = "transient"\n'
                  'unit = "N"\npercentiles = [[75.0, 100.0], [25.0, 80.0]]\n')
    with pytest.raises(ArmFileError, match=r"pain\[0\].*percentiles must increase"):
        BodyRegion.from_toml(bad)
    bad = base + ('\n[[pain]]\nstudy = "x"\nquantity = "force"\ncontact = "impact"\n'
                  'unit = "N"\npercentiles = [[25.0, 80.0]]\n')
    with pytest.raises(ArmFileError, match=r"pain\[0\].*contact = 'impact'"):
        BodyRegion.from_toml(bad)
    with pytest.raises(ValueError, match="did you mean 'chest/sternum'"):
        body_region("chest/sternm")


# ---- criteria, verdicts and injury risk ----------------------------------------------------

def test_head_criteria_carry_iso_fracture_and_hic_limits_with_sources():
    crit = {c.name: c for c in criteria_for()}
    assert list(crit) == ["iso_ts_15066", "iso_ts_15066_qs", "iso_ts_15066_p",
                          "iso_ts_15066_p_qs", "maxilla", "mandible", "frontal_bone", "HIC36"]
    assert crit["iso_ts_15066"].limit == 260.0 and not crit["iso_ts_15066"].confirmed
    assert crit["iso_ts_15066_qs"].limit == 130.0 and crit["iso_ts_15066_qs"].confirmed
    assert (crit["maxilla"].limit, crit["mandible"].limit, crit["frontal_bone"].limit) == (
        660.0, 1780.0, 4000.0)
    assert crit["HIC36"].limit == 650.0 and crit["HIC36"].metric == "HIC36"
    assert all(c.source for c in crit.values())
    assert FRACTURE_FORCES["maxilla"].confirmed and not FRACTURE_FORCES["mandible"].confirmed
    # a region of the body below the head: its ISO transient limit only
    assert [c.name for c in criteria_for("chest/sternum")] == ["iso_ts_15066", "iso_ts_15066_p"]
    assert criterion("iso_ts_15066", "chest/sternum").limit == 280.0
    assert criterion("F_max") == crit["maxilla"] and "F_max" in criterion_names()
    t = evaluate({"F_max": 250.0, "HIC36": 0.1}, criteria_for())
    row = t.set_index("criterion").loc["iso_ts_15066"]
    assert row.margin == 10.0 and row.margin_pct == pytest.approx(100 * 10 / 260) and row.passed
    assert not t.set_index("criterion").loc["iso_ts_15066_qs", "passed"]
    assert not evaluate({"F_max": 260.0}, criteria_for()).iloc[0].passed     # strict


@pytest.mark.parametrize("hic", [50.0, 250.0, 500.0, 700.0, 1000.0, 1500.0, 3000.0])
def test_ais_curves_against_the_published_lognormal_coefficients(hic):
    """P(AIS >= n) = Phi((ln HIC - mu) / sigma) with NHTSA's (mu, sigma) (Kleinberger et al.
    1998, §2.3): scipy's lognormal distribution (shape sigma, scale e^mu) is the oracle."""
    published = {2: (6.96352, 0.84664), 3: (7.45231, 0.73998), 4: (7.65605, 0.60580)}
    assert AIS_RISK == published
    for level, (mu, sigma) in published.items():
        assert ais_risk(hic, level) == pytest.approx(
            lognorm.cdf(hic, s=sigma, scale=math.exp(mu)), rel=1e-9, abs=1e-15)
    # the median of each curve is e^mu: HIC 1058 (AIS 2+), 1723 (AIS 3+), 2114 (AIS 4+)
    assert ais_risk(math.exp(7.45231), 3) == pytest.approx(0.5, abs=1e-12)
    assert ais_risk(hic, 2) >= ais_risk(hic, 3) >= ais_risk(hic, 4)
    assert ais_risk(0.0, 3) == 0.0
    with pytest.raises(ValueError, match="level = 5"):
        ais_risk(hic, 5)


def test_impact_verdicts_give_both_heads_side_by_side_with_the_reason():
    v = impact_verdicts(thesis_arm(), np.radians([50.0, -80.0]), [2.0, 0.0], [43.0, 27.0])
    heads = list(dict.fromkeys(v.table.head_model))
    assert heads == ["thesis-frontal", "iso15066-skull-4.4kg"]
    t = v.table.set_index(["head_model", "criterion"])
    assert t.loc[("thesis-frontal", "iso_ts_15066"), "passed"]           # 253 N < 260 N
    assert not t.loc[("iso15066-skull-4.4kg", "iso_ts_15066"), "passed"]  # 336 N
    assert "disagree on iso_ts_15066" in v.reason and "linear spring 150 N/mm" in v.reason
    assert v.governing().criterion == "iso_ts_15066_qs"
    assert set(v.risk.level) == {"AIS 2+", "AIS 3+", "AIS 4+"}


def test_impact_prints_verdicts_with_margins(capsys):
    assert main(["impact", "--q", "50", "-80", "--qd", "2", "0", "--stiffness", "43",
                 "27"]) == 0
    out = capsys.readouterr().out
    assert "verdicts with head model thesis-frontal (body region skull/forehead" in out
    assert "verdicts with head model iso15066-skull-4.4kg" in out
    assert "margin +6.66 N" in out and "limit      260 N" in out and "FAIL" in out
    assert "injury risk from HIC15" in out and "P(AIS 3+)" in out
    assert "note: the head models disagree" in out
    assert main(["impact", "--q", "50", "-80", "--qd", "2", "0", "--region", "chest/sternum"]) == 0
    out = capsys.readouterr().out
    assert "body region chest/sternum" in out and "iso15066-chest-40kg" in out
    assert main(["impact", "--q", "50", "-80", "--qd", "2", "0", "--region", "chin"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("ppamsafety: error: --region chin")


# ---- envelopes: brackets, crossings, margins ------------------------------------------------

def test_an_envelope_on_a_plateau_reports_the_narrow_margin():
    env = search_envelope(lambda x: 259.5 + 0.2 * x, (0.0, 1.0), limit_value=260.0)
    assert env.direction == "all safe" and env.min_margin == pytest.approx(0.3)
    assert any(line.startswith("NARROW") for line in env.lines())
    # a crossing on a plateau: bracketed, flagged flat, the margin at the boundary stated
    env = search_envelope(lambda x: 262.0 - 4.0 * x, (0.0, 1.0), limit_value=260.0, scan=5,
                          tolerance=1e-3)
    (c,) = env.crossings
    assert c["unsafe_value"] <= 0.5 < c["safe_value"] <= 0.5 * (1 + 1e-3) + 1e-12
    assert c["flat"] and c["spread"] == pytest.approx(1.0) and env.flat
    assert env.margin == pytest.approx(260.0 - (262.0 - 4.0 * c["safe_value"]))
    assert "FLAT" in "\n".join(env.lines())


def test_a_non_monotone_curve_reports_every_crossing():
    # F = 200 + 40 (x - 1.5)^2 crosses 260 at x = 1.5 -+ sqrt(1.5) = 0.2753, 2.7247
    env = search_envelope(lambda x: 200.0 + 40.0 * (x - 1.5) ** 2, (0.0, 3.0),
                          limit_value=260.0, scan=13, tolerance=1e-4)
    assert not env.monotone and env.direction == "inside" and len(env.crossings) == 2
    x1, x2 = 1.5 - math.sqrt(1.5), 1.5 + math.sqrt(1.5)
    (a, b), = env.safe_ranges
    assert a == pytest.approx(x1, rel=2e-4) and b == pytest.approx(x2, rel=2e-4)
    for c, x in zip(env.crossings, (x1, x2)):
        lo, hi = sorted((c["safe_value"], c["unsafe_value"]))
        assert lo <= x <= hi
    assert "crossed 2 times" in "\n".join(env.lines())
    # two evaluations only (scan = 2) would have called the whole range unsafe
    assert search_envelope(lambda x: 200.0 + 40.0 * (x - 1.5) ** 2, (0.0, 3.0),
                           limit_value=260.0, scan=2).direction == "none safe"


def test_the_limit_value_can_be_chosen_and_is_named():
    iso = safety_envelope("speed", (0.2, 3.0), limit="iso_ts_15066", tolerance=0.02)
    own = safety_envelope("speed", (0.2, 3.0), limit="iso_ts_15066", limit_value=200.0,
                          tolerance=0.02)
    assert own.limit_value == 200.0 and own.safe_value < iso.safe_value
    assert own.limit_label.startswith("200 N (chosen, in place of ISO/TS 15066") and "head model thesis-frontal" in own.description
    assert set(LIMITS) >= {"F_max", "HIC36", "iso_ts_15066", "iso_ts_15066_qs"}
    with pytest.raises(ValueError, match="limit_value"):
        safety_envelope("speed", (0.2, 3.0), limit_value=-1.0)


ENV = '[impact]\nstiffness = [43.0, 27.0]\n[envelope]\nparameter = "speed"\n'


def test_an_envelope_pose_in_the_wrong_unit_is_blamed_on_the_pose():
    with pytest.raises(StudyFileError, match=r"envelope\.pose = \[0\.87, -1\.4\] \[deg\].*"
                                             r"looks like radians \(\[49\.8, -80\.2\] deg\)"):
        parse_study(ENV + "range = [0.2, 3.0]\npose = [0.87, -1.4]\n")
    with pytest.raises(StudyFileError, match=r"envelope\.direction = \[0\.0, 0\.0\]"):
        parse_study(ENV + "range = [0.2, 3.0]\ndirection = [0.0, 0.0]\n")


def test_an_envelope_range_takes_units():
    st = parse_study(ENV + 'range = { values = [200, 3000], unit = "mm/s" }\n')
    assert st.envelope["bounds"] == pytest.approx((0.2, 3.0))
    st = parse_study('[case]\ncontroller = "PID"\n[envelope]\n'
                     'parameter = "arm.pneumatics.mean_pressure"\n'
                     'range = { values = [1.2, 2.0], unit = "bar" }\nlimit = "iso_ts_15066"\n'
                     'limit_value = { value = 0.2, unit = "kN" }\nscan = 5\n')
    e = st.envelope
    assert e["bounds"] == pytest.approx((1.2e5, 2.0e5)) and e["limit_value"] == 200.0
    assert e["scan"] == 5
    with pytest.raises(StudyFileError, match=r"envelope\.range .*unit = 'kg'"):
        parse_study(ENV + 'range = { values = [0.2, 3.0], unit = "kg" }\n')
    with pytest.raises(StudyFileError, match=r"envelope\.limit = 'pain'"):
        parse_study(ENV + 'range = [0.2, 3.0]\nlimit = "pain"\n')


# ---- the same question, answered identically everywhere ----------------------------------

def test_the_same_question_gets_the_same_answer_from_envelope_sweep_and_report():
    """PSMC joint (Ki = 2) against the 260 N forehead limit, step experiment, both heads."""
    from ppamsafety.sections import iso_15066

    study = iso_15066.compute(quick=True)
    q = study.question
    q = q[(q.experiment == "step") & (q.family == "PSMC joint Ki=2")
          & (q.criterion == "iso_ts_15066") & (q.region == "skull/forehead")]
    case = {"experiment": "step", "controller": "PSMC joint", "ki_bar": 2}
    for head in (head_model("thesis-frontal"), annex_a_head("skull/forehead")):
        sweep = safety_sweep([case], grid={"lam": [0.4, 0.8]}, processes=1, progress=False,
                             head=head).table
        env = safety_envelope("lam", (0.4, 0.8), limit="iso_ts_15066", scan=3, head=head,
                              case={k: v for k, v in case.items()}, tolerance=0.01)
        ev = env.to_pandas().set_index("value")
        sec = q[q.head_model == head.name].set_index("lambda")
        assert env.head == head.name and head.name in env.description
        for lam in (0.4, 0.8):
            s = sweep.set_index("lam").loc[lam]
            assert s.head_model == head.name
            assert s.F_max == ev.loc[lam, "F_max"] == sec.loc[lam, "F_max"]
            assert s.iso_ts_15066_margin == ev.loc[lam, "margin"] == sec.loc[lam, "margin"]
            assert bool(s.iso_ts_15066_pass) == bool(ev.loc[lam, "safe"]) == bool(
                sec.loc[lam, "passed"])
        # the envelope's bracket agrees with the grid verdicts of the section
        p04, p08 = bool(sec.loc[0.4, "passed"]), bool(sec.loc[0.8, "passed"])
        if p04 == p08:
            assert not env.crossings
        else:
            (c,) = env.crossings
            assert 0.4 <= min(c["safe_value"], c["unsafe_value"]) <= 0.8
    # the two heads answer differently at lambda = 0.4 s, and the report says so
    at = q[q["lambda"] == 0.4].set_index("head_model")["passed"]
    assert bool(at["thesis-frontal"]) and not bool(at["iso15066-skull-4.4kg"])
    md = iso_15066.render(study).markdown
    assert "The same question with two head models" in md and "iso15066-skull-4.4kg" in md
    lt = study.lambda_table
    row = lt[(lt.family == "PSMC joint Ki=2") & (lt.factor == 2.0)
             & (lt.region == "skull/forehead")].iloc[0]
    assert row.head_model == "iso15066-skull-4.4kg" and row.hc_head_model == "thesis-frontal"
    assert row.lambda_min_force_hc < row.lambda_min_force


def test_the_docs_list_every_region_value_with_its_source():
    from pathlib import Path
    from ppamsafety.params.iso_ts_15066 import annex_a_table

    doc = (Path(__file__).parent.parent / "docs" / "body_regions.md").read_text()
    assert annex_a_table() in doc
    for c in criteria_for():
        assert f"`{c.name}`" in doc
