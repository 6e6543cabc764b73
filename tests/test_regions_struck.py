"""A body region is struck on that region's body, and every path gives one answer.

The arm is a user's arm, not the thesis': a heavier forearm and a lower mean pressure than the
thesis arm (``USER_ARM``).  The same case -- arm, pose, speed, region, contact point -- goes
through ``ppamsafety impact``, the sweep engine (``impact_case``) and the safety envelope;
the three forces must be equal.  References: the ISO/TS 15066 Annex A two-body model
(F = v sqrt(mu K), Table A.3 K and m_H of the region) and the Table A.2 pressure limits.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
import pytest

from ppamsafety.cli import main
from ppamsafety.envelope import safety_envelope
from ppamsafety.impact.anywhere import point_jacobian, simulate_contacts
from ppamsafety.impact.head import head_model
from ppamsafety.impact.summary import body_model_name, region_body
from ppamsafety.impact.verdicts import (annex_a_head, criteria_for, impact_verdicts,
                                        region_head)
from ppamsafety.params import is_thesis_arm
from ppamsafety.params.contact import BARE, ContactPoint, arm_contact_points
from ppamsafety.params.iso_ts_15066 import FACE, SKULL_FOREHEAD, body_region
from ppamsafety.sweep import run_sweep
from ppamsafety.sweep_cases import add_verdicts, case_arm, case_function, impact_case, safety_case
from ppamsafety.units import DEG

#: A user's arm: forearm 35 % heavier, mean pressure 1.4/1.5 bar (the thesis: 1 kg, 2 bar).
USER_ARM = case_arm(changes={"arm.links.m2": 1.35,
                             "arm.pneumatics.mean_pressure": {"value": [1.4, 1.5],
                                                             "unit": "bar"}})
POSE_DEG = (50.0, -80.0)
DIRECTION = (1.0, 0.0)
STIFFNESS = (60.0, 40.0)
SPEED = 1.0


def _arm_file(tmp_path):
    f = tmp_path / "user_arm.toml"
    f.write_text(USER_ARM.to_toml())
    return f


def _qd(point=None):
    """Joint speeds [rad/s] moving the point (default the tool point) at SPEED along DIRECTION."""
    q = np.radians(POSE_DEG)
    pts = {c.name: c for c in arm_contact_points(USER_ARM)}
    J = point_jacobian(q, USER_ARM, pts[point or "tool point"])
    d = np.array(DIRECTION)
    return d * SPEED / float(np.hypot(*(J @ d)))


def _cli_force(capsys, tmp_path, *extra):
    qd = _qd(extra[extra.index("--contact") + 1] if "--contact" in extra else None)
    args = ["impact", "--arm", str(_arm_file(tmp_path)), "--q", *map(str, POSE_DEG),
            "--qd", *(repr(float(v)) for v in qd), "--stiffness", *map(str, STIFFNESS),
            *extra]
    assert main(args) == 0
    out = capsys.readouterr().out
    return float(re.search(r"^F_max\s+(\S+) N", out, re.M).group(1)), out


def test_the_user_arm_is_not_the_thesis_arm():
    assert not is_thesis_arm(USER_ARM) and USER_ARM.links.m2 == 1.35


@pytest.mark.parametrize("contact", [None, "forearm"])
def test_impact_sweep_and_envelope_give_one_force_for_the_chest(capsys, tmp_path, contact):
    region = "chest/sternum"
    extra = ["--region", region] + ([] if contact is None else ["--contact", contact])
    f_cli, out = _cli_force(capsys, tmp_path, *extra)
    case = {"q1_deg": POSE_DEG[0], "q2_deg": POSE_DEG[1], "direction": list(DIRECTION),
            "stiffness": list(STIFFNESS), "region": region,
            **({} if contact is None else {"contact": contact})}
    one = impact_case(SPEED, arm=USER_ARM, **case)
    swept = run_sweep(case_function(USER_ARM, kind="impact"), [{"speed": SPEED, **case}],
                      progress=False).table.iloc[0]
    env = safety_envelope("speed", (0.5, 1.5), limit="iso_ts_15066", region=region,
                          case={k: v for k, v in case.items() if k != "region"}, arm=USER_ARM,
                          scan=3, max_rounds=1)
    ev = env.evaluations.set_index("value")
    # the three paths: bit for bit (same engine, same inputs); the CLI prints 4 digits
    assert one["F_max"] == swept["F_max"] == ev.loc[SPEED, "F_max"]
    assert f_cli == pytest.approx(one["F_max"], rel=6e-4)
    # the chest's own body: the Annex A two-body model, Table A.3 chest K = 25 N/mm,
    # m_H = 40 kg -- F = v sqrt(mu K) within 3 % through the flexible-joint arm
    # (docs/impact_models.md), and never the 5 kg thesis head
    chest = body_region(region)
    assert one["body_model"] == env.head == annex_a_head(chest).name == "iso15066-chest-40kg"
    pts = {c.name: c for c in arm_contact_points(USER_ARM)}
    s = simulate_contacts(USER_ARM, np.radians(POSE_DEG), _qd(contact), STIFFNESS,
                          point=pts[contact or "tool point"],
                          body=region_body(region)).summary.iloc[0]
    mu = 1.0 / (1.0 / chest.effective_mass + 1.0 / s.m_eff)
    assert one["F_max"] == pytest.approx(SPEED * math.sqrt(mu * chest.spring_constant),
                                         rel=0.03)
    assert "iso15066-chest-40kg" in out and "thesis-frontal" not in out
    # HIC and the AIS risk are head criteria: not judged for the chest
    assert "injury risk" not in out and "P(AIS" not in out and "HIC36   " not in out
    assert "not judged for chest/sternum" in out


def test_the_tool_point_engine_and_the_contact_engine_strike_the_same_chest(capsys, tmp_path):
    f_tool, _ = _cli_force(capsys, tmp_path, "--region", "chest/sternum")
    f_point, _ = _cli_force(capsys, tmp_path, "--region", "chest/sternum", "--contact",
                            "tool point")
    assert f_point == pytest.approx(f_tool, rel=1e-3)


def test_a_head_model_for_a_region_that_is_not_the_head_is_refused(capsys, tmp_path):
    msg = r"head model 'thesis-frontal' with body region 'chest/sternum'"
    with pytest.raises(ValueError, match=msg):
        region_body("chest/sternum", head="thesis-frontal")
    with pytest.raises(ValueError, match=msg):
        region_head("chest/sternum", head_model())
    with pytest.raises(ValueError, match=r"'iso15066-face' with body region 'lower leg"):
        impact_case(SPEED, region="lower leg/middle of shin", head="iso15066-face",
                    arm=USER_ARM)
    with pytest.raises(ValueError, match=r"'iso15066-face' with body region 'abdomen'"):
        safety_case("step", "PSMC joint", region="abdomen", head="iso15066-face",
                    arm=USER_ARM)
    with pytest.raises(ValueError, match=r"region sets the body struck"):
        safety_case("step", region="chest/sternum", contact="forearm",
                    body="head (forehead)", arm=USER_ARM)
    args = ["impact", "--arm", str(_arm_file(tmp_path)), "--q", "50", "-80", "--qd", "2",
            "0", "--region", "chest/sternum", "--head", "thesis-frontal"]
    assert main(args) == 2
    err = [e for e in capsys.readouterr().err.strip().splitlines()
           if not e.startswith("ppamsafety: note:")]       # the arm file's own note
    assert len(err) == 1 and err[0].startswith("ppamsafety: error: --head thesis-frontal "
                                               "--region chest/sternum")
    assert "'thesis-frontal'" in err[0] and "'chest/sternum'" in err[0]
    # a head region takes a head model: the face on the Annex A face spring
    assert region_head("face", "iso15066-face").name == "iso15066-face"
    assert body_model_name("face", head="iso15066-face") == "iso15066-face"


def test_non_head_verdicts_have_no_head_criteria():
    v = impact_verdicts(USER_ARM, np.radians(POSE_DEG), [2.0, 0.0], STIFFNESS,
                        region="chest/sternum")
    assert set(v.table["head_model"]) == {"iso15066-chest-40kg"}
    assert set(v.table["criterion"]) == {"iso_ts_15066"} and v.risk.empty
    assert not any("HIC" in c.name or c.kind == "fracture"
                   for c in criteria_for("chest/sternum"))
    h = impact_verdicts(USER_ARM, np.radians(POSE_DEG), [2.0, 0.0], STIFFNESS)
    assert list(dict.fromkeys(h.table["head_model"])) == ["thesis-frontal",
                                                          "iso15066-skull-4.4kg"]
    assert set(h.risk["level"]) == {"AIS 2+", "AIS 3+", "AIS 4+"}


def test_the_default_head_is_named_as_the_thesis_arms_fit(capsys, tmp_path):
    _, out = _cli_force(capsys, tmp_path)
    assert "head model      thesis-frontal" in out
    assert "fitted to the thesis arm's Table 6.1 impacts" in out and "not to this arm" in out


def test_safety_case_strikes_and_names_the_region_body():
    kw = dict(lam=0.8, arm=USER_ARM)
    tool = safety_case("step", "PSMC joint", region="chest/sternum", **kw)
    point = safety_case("step", "PSMC joint", region="chest/sternum", contact="tool point",
                        **kw)
    head = safety_case("step", "PSMC joint", **kw)
    covered = safety_case("step", "PSMC joint", contact="forearm", **kw)
    assert tool["body_model"] == point["body_model"] == "iso15066-chest-40kg"
    assert point["body_region"] == "chest/sternum"
    assert tool["F_max"] == pytest.approx(point["F_max"], rel=1e-3)
    assert head["body_model"] == "thesis-frontal"
    assert covered["body_model"] == "validated head"
    # the chest's soft spring (25 N/mm) gives less force than the head (the thesis' fit)
    assert tool["F_max"] < 0.9 * head["F_max"]
    df = add_verdicts(pd.DataFrame([{**tool, "region": "chest/sternum", "status": "ok"},
                                    {**covered, "status": "ok"},
                                    {**head, "status": "ok"}]))
    assert list(df["head_model"]) == ["iso15066-chest-40kg", "validated head",
                                      "thesis-frontal"]
    # the chest row is judged on the chest's 280 N, the others on the forehead's criteria
    assert df.loc[0, "iso_ts_15066_margin"] == pytest.approx(280.0 - tool["F_max"])
    assert pd.isna(df.loc[0, "maxilla_margin"]) and not pd.isna(df.loc[2, "maxilla_margin"])
    # the contact-point case has a pressure; it is judged (Table A.2 forehead 130 N/cm^2)
    assert df.loc[1, "iso_ts_15066_p_qs_margin"] == pytest.approx(1.3e6 - covered["p_max"])
    assert pd.isna(df.loc[2, "iso_ts_15066_p_qs_margin"])


def test_contact_pressure_is_judged_against_table_a2(capsys, tmp_path):
    # a 2 mm edge (the radius of the probe of the TS's pressure study) on the forearm at
    # 320 mm, slowly into the forehead: the force is far below 130 N, the pressure is not
    edge = tmp_path / "edge.toml"
    edge.write_text('format = "ppamsafety-contact/1"\nname = "sharp edge"\nlink = 2\n'
                    'position = { value = 320, unit = "mm" }\nshape = "edge"\n'
                    'radius = { value = 2, unit = "mm" }\ncovering = "bare metal"\n')
    args = ["impact", "--arm", str(_arm_file(tmp_path)), "--q", "50", "-80", "--qd", "0.3",
            "0", "--contact", str(edge), "--region", "skull/forehead"]
    assert main(args) == 0
    out = capsys.readouterr().out
    p = float(re.search(r"^p_max\s+(\S+) N/cm\^2", out, re.M).group(1))
    f = float(re.search(r"^F_max\s+(\S+) N", out, re.M).group(1))
    assert f < 130.0 and p > SKULL_FOREHEAD.pressure_quasi_static / 1e4 == 130.0
    assert "FAIL, governed by iso_ts_15066_p_qs" in out
    assert re.search(r"FAIL  iso_ts_15066_p_qs p_max\s+\S+ N/cm\^2 vs limit\s+130 N/cm\^2", out)


def test_the_linear_annex_a_spring_gives_one_pressure_at_every_speed():
    # F = K delta, A = pi R_e delta: p = K / (pi R_e) whatever the speed (docs/impact_models.md)
    point = ContactPoint(name="edge", link=2, position=0.3, shape="edge", radius=0.002,
                         covering=BARE)
    chest = body_region("chest/sternum")
    body = region_body(chest)
    r1 = 1.0 / (1.0 / body.radius + 1.0 / point.radius)
    r_e = math.sqrt(r1 * body.radius)
    for w in (0.3, 1.0, 3.0):
        s = simulate_contacts(USER_ARM, np.radians(POSE_DEG), [w, 0.0], STIFFNESS, point=point,
                              body=body).summary.iloc[0]
        assert s.p_max == pytest.approx(chest.spring_constant / (math.pi * r_e), rel=1e-9)


def test_annex_a_head_models_carry_the_annex_a_mass():
    # ISO/TS 15066 Annex A Table A.3: skull/forehead and face m_H = 4.4 kg, K = 150 and 75
    # N/mm (params.iso_ts_15066); the thesis' own head is 5 kg (thesis §6.3.2)
    fh, fa = head_model("iso15066-forehead"), head_model("iso15066-face")
    assert (fh.mass, fh.stiffness) == (SKULL_FOREHEAD.effective_mass, 150e3) == (4.4, 150e3)
    assert (fa.mass, fa.stiffness) == (FACE.effective_mass, 75e3) == (4.4, 75e3)
    assert "Table A.3" in fh.source and "4.4 kg" in fa.source
    assert head_model("thesis-frontal").mass == 5.0
    # the named Annex A head and the region's Annex A body model are one model
    a = annex_a_head(SKULL_FOREHEAD)
    assert (a.mass, a.stiffness, a.exponent, a.damping) == (fh.mass, fh.stiffness, 1.0, 0.0)


def test_the_sweep_page_and_figure_show_the_limit_that_decides(tmp_path):
    from ppamsafety.study_files import parse_study, run_study_file

    # the user's arm, a joint PSMC step (lambda 0.4 s), the forearm into the forehead (the
    # validated head), bare and behind the implied covering: the quasi-static 130 N
    # (Table A.2, the TS reading for a head region) governs both; the bare case fails it and
    # the forehead's 130 N/cm^2 pressure too
    text = """[study]
name = "decides"
[case]
experiment = "step"
controller = "PSMC joint"
contact = "forearm"
lam = 0.4
duration = 3.0
[impact]
instants = "max TCP speed"
[grid]
covering = ["bare metal", "thesis-implied"]
"""
    st = parse_study(text, arm=USER_ARM)
    out = tmp_path / "out"
    df = run_study_file(st, out, processes=1, progress=False).table
    assert list(df["head_model"]) == ["validated head"] * 2           # the body simulated
    assert list(df["governing"]) == ["iso_ts_15066_qs"] * 2
    fails = df["verdict"] == "fail"
    assert list(fails) == [True, False]
    assert df.loc[0, "p_max"] > 1.3e6 > df.loc[1, "p_max"]            # 130 N/cm^2
    page = (out / "summary.html").read_text()
    assert "validated head (2 cases)" in page and "default thesis-frontal" not in page
    decided = page.split("limits that decide the verdicts</th><td>")[1].split("</td>")[0]
    assert "quasi-static force, the TS reading for a head region 130 N: governs 2" in decided
    assert "(Annex A)" not in page
    if (df["F_max"] > 260).any():        # the transient 260 N is not in the TS: said so
        assert "260 N (2 x 130 N; not in the TS for this region) [unconfirmed" in decided
    assert page.count('title="fails: ') == 2                # the bare case's F_max and p_max
    assert '<span class="above">fail</span>' in page
    # the figure draws the deciding line and rings the failing cases
    from ppamsafety.plots.sweep import ABOVE
    from ppamsafety.study_files import sweep_figure
    fig = sweep_figure(st, df, ["covering"])
    ax = fig.axes[0]
    labels = ax.get_legend_handles_labels()[1]
    assert any("skull/forehead iso_ts_15066_qs 130 N (governs 2, fails 1)" in t
               for t in labels)
    assert "fails its verdict" in labels
    ringed = [ln for ln in ax.get_lines() if ln.get_marker() == ABOVE["marker"]
              and ln.get_markerfacecolor() == "none" and len(ln.get_xdata())]
    assert len(ringed) == 1 and list(ringed[0].get_xdata()) == [0]      # the bare case
    assert any("iso_ts_15066_p_qs 1.3e+06 Pa (governs 0, fails 1)" in t for t in
               sum((a.get_legend_handles_labels()[1] for a in fig.axes), []))
