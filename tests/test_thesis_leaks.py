"""No thesis value in the output of a run for another arm.

The detector (``tests/thesis_leaks.py``) derives the thesis constants from the thesis arm's
parameter sets and the published values of the thesis data modules, in the units and
spellings they are printed in, drops those the arm under test has, and looks for the rest in
every output: printed text, Markdown, CSV (headers and values), JSON and HTML.

The default suite checks the detector on planted leaks (it must be able to fail), every
subcommand for the shipped example arm, a user's variant of it and an arm drawn at random,
and a quick report of a few sections for a random arm; ``-m slow`` builds the whole quick
report, every section included, for the example, the variant and two random arms.
"""

import json
import re

import numpy as np
import pandas as pd
import pytest

import thesis_leaks as tl
from ppamsafety.cli import main
from ppamsafety.impact.thesis_data import STEP_IMPACT_STIFFNESS
from ppamsafety.params import load_arm, thesis_arm
from ppamsafety.params.arm_file import arm_to_toml
from ppamsafety.sections import REGISTRY

ROOT = tl.EXAMPLE.parent.parent.parent
#: Seeds of the random arms (default suite; the slow run adds the second).
SEEDS = (11, 12)


def _arm_file(tmp_path, arm, name="arm.toml"):
    f = tmp_path / name
    f.write_text(arm_to_toml(arm), encoding="utf-8")
    return f


def _leaks_text(leaks):
    return "\n".join(str(x) for x in leaks)


# ----------------------------------------------------------------------------- the detector

def test_the_constants_are_derived_from_the_thesis_data():
    names = {c.name for c in tl.thesis_constants()}
    # the parameter sets (every key of the thesis arm's file) ...
    assert "arm pneumatics.mean_pressure[0]" in names and "arm links.m2" in names
    assert "arm valves.valve1.offset" in names and "arm valves.valve2.time_constant" in names
    # ... and the published values of the data modules, found by their names
    assert any("STEP_IMPACT_STIFFNESS" in n for n in names)
    assert any("THESIS_ARM_MASS" in n for n in names)
    assert any("DELTA_25_FIBRES" in n for n in names)
    assert any("table_6_1() Fmax_step" in n for n in names)
    assert any("table_5_2() thesis_mean_m" in n for n in names)
    # the thesis arm has every one of them: nothing to look for in its own output
    assert tl.constants_for(thesis_arm()) == []


def test_an_arm_does_not_leak_what_it_has():
    example = load_arm(tl.EXAMPLE)
    have = {c.name for c in tl.thesis_constants()} - {c.name for c in tl.constants_for(example)}
    # same pressures and geometry as the thesis arm; its own stiffness at the pose is 43/27
    assert "arm pneumatics.mean_pressure[0]" in have and "arm geometry.L1" in have
    assert any("STEP_IMPACT_STIFFNESS[0]" in n for n in have)
    assert any("DELTA_40_FIBRES" in n for n in have)          # it declares delta = 0.299
    variant = tl.user_variant()
    names = {c.name for c in tl.constants_for(variant)}
    assert any("STEP_IMPACT_STIFFNESS[0]" in n for n in names)  # 37.7 Nm/rad: 43 is a leak
    assert "arm pneumatics.mean_pressure[1]" in names


PLANTED = """# Report

The arm is stiff: K = 43 Nm/rad at the pose, and (43, 27) Nm/rad in the table.
Robot mass M = 2.5 kg (thesis §6.3.5).
`ppamsafety synthesize --effect hysteresis_delta=0.139`
Valve 1 offset 0.0447 bar, forearm m2 = 1.136 kg, mean pressure 1.762 bar.

| label | F_max [N] | K1 [Nm/rad] |
|---|---|---|
| PID | 1524 | 43.0 |
"""

CLEAN = """# Report

Sections 6.3.5 and §3.6.5, eq. (2.18), Table 6.1, fig. 6.3.
The arm's own K = 37.73 Nm/rad; chattering 0.139 bar; F_max 1524.9662 N; HIC36 4.8133.
The 5.90 mm error and a period of 211 ms.

| label | F_max [N] | K1 [Nm/rad] | gap [deg] |
|---|---|---|---|
| PID | 1524.97 | 37.7 | 4.81 |
"""


def test_the_detector_finds_planted_leaks_and_only_those(tmp_path):
    arm = tl.random_arm(SEEDS[0])
    det = tl.Detector(tl.constants_for(arm))
    hits = det.text(PLANTED, "planted.md")
    found = {h.constant.name for h in hits}
    assert len(hits) >= 10, _leaks_text(hits)
    for what in ("STEP_IMPACT_STIFFNESS[0]", "STEP_IMPACT_STIFFNESS[1]", "THESIS_ARM_MASS",
                 "DELTA_25_FIBRES", "arm valves.valve1.offset", "arm links.m2",
                 "arm pneumatics.mean_pressure[1]", "table_6_1() Fmax_step"):
        assert any(what in n for n in found), (what, found)
    assert det.text(CLEAN, "clean.md") == [], _leaks_text(det.text(CLEAN, "clean.md"))
    # the same in a CSV, an HTML page and a JSON file
    pd.DataFrame({"label": ["PID"], "K1 [Nm/rad]": [43.0], "p_m [bar]": [1.762],
                  "F_max_N": [1524.9662]}).to_csv(tmp_path / "t.csv", index=False)
    csv = det.csv(tmp_path / "t.csv")
    assert {h.constant.value for h in csv} == {43.0, 176200.0}, _leaks_text(csv)
    (tmp_path / "p.html").write_text("<html><body><p>M = 2.5 kg</p><table><tr><th>K1 "
                                     "[Nm/rad]</th></tr><tr><td>27</td></tr></table></body>"
                                     "</html>")
    html = tl.scan_folder(tmp_path, arm)
    assert {h.where.split(":")[0] for h in html} == {"t.csv", "p.html"}
    (tmp_path / "m.json").write_text(json.dumps({"s": {"K1": 43.0, "K2": 23.9}}))
    assert [h.constant.value for h in det.json(tmp_path / "m.json")] == [43.0]


def test_the_detector_catches_the_old_default_stiffness_planted_back(monkeypatch, tmp_path,
                                                                      capsys):
    """A leak nobody listed: ``impact`` given the thesis stiffness instead of the arm's."""
    import ppamsafety.design as design

    arm = tl.user_variant()
    f = _arm_file(tmp_path, arm)
    argv = ["impact", "--arm", str(f), "--q", "50", "-80", "--qd", "2", "0"]
    assert main(argv) == 0
    assert tl.scan_output(capsys.readouterr().out, arm) == []
    det = tl.Detector(tl.constants_for(arm))       # before the plant: it uses the arm's own K
    real = design.rest_stiffness

    def thesis_default(a, q):
        r = real(a, q)
        return design.RestStiffness(r.q, r.pressures, r.holdable, STEP_IMPACT_STIFFNESS)
    monkeypatch.setattr(design, "rest_stiffness", thesis_default)
    assert main(argv) == 0
    out = capsys.readouterr().out
    leaks = det.text(tl.strip_arm_text(out, arm), "stdout")
    assert {lk.constant.value for lk in leaks} == set(STEP_IMPACT_STIFFNESS), out


# ------------------------------------------------------------------------------ subcommands

def _arms():
    return {"example": load_arm(tl.EXAMPLE), "variant": tl.user_variant(),
            f"random {SEEDS[0]}": tl.random_arm(SEEDS[0])}


ENVELOPE = """[study]
name = "speed-envelope"
[envelope]
parameter = "speed"
range = [0.2, 3.0]
limit = "F_max"
tolerance = 0.05
"""


def _run_subcommands(tmp_path, arm, capsys):
    """Every subcommand for ``arm``; the leaks of what each printed and wrote."""
    f = _arm_file(tmp_path, arm)
    leaks = []

    def run(argv, folder=None):
        rc = main(argv)
        out = capsys.readouterr()
        assert rc == 0, (argv, out.err)
        leaks.extend(tl.scan_output(out.out + out.err, arm, argv[0]))
        if folder is not None:
            leaks.extend(tl.scan_folder(folder, arm))

    run(["arm", "check", str(f)])
    run(["info", "--arm", str(f)])
    run(["impact", "--arm", str(f), "--q", "50", "-80", "--qd", "2", "0"])
    run(["impact", "--arm", str(f), "--q", "70", "-60", "--qd", "1", "-1"])
    rec = tmp_path / "rec.csv"
    run(["synthesize", "--arm", str(f), "--duration", "3", "--seed", "1", "--out", str(rec)])
    run(["diagnose", str(rec), "--arm", str(f), "--out", str(tmp_path / "dg"), "--bootstrap",
         "0"], tmp_path / "dg")
    run(["identify", str(rec), "--kind", "dynamic", "--arm", str(f), "--out",
         str(tmp_path / "id")], tmp_path / "id")
    run(["sweep", str(ROOT / "studies" / "mean_pressure.toml"), "--arm", str(f), "--out",
         str(tmp_path / "sw"), "--max-cases", "2", "--processes", "1", "--no-progress"],
        tmp_path / "sw")
    env = tmp_path / "env.toml"
    env.write_text(ENVELOPE)
    run(["sweep", str(env), "--arm", str(f), "--out", str(tmp_path / "env"), "--processes", "1",
         "--no-progress"], tmp_path / "env")
    return leaks


@pytest.mark.parametrize("which", ["example", "variant", f"random {SEEDS[0]}"])
def test_every_subcommand_shows_the_arms_own_values(which, tmp_path, capsys):
    arm = _arms()[which]
    leaks = _run_subcommands(tmp_path, arm, capsys)
    assert leaks == [], _leaks_text(leaks)


# ------------------------------------------------------------------------------ the report

#: Sections of the default suite's report: fast, and where the leaks were.
QUICK_SECTIONS = ("safety_summary", "design", "stiffness", "diagnose_sawtooth", "iso_15066",
                  "head_model")


def _report(tmp_path, arm, *extra, processes=2):
    f = _arm_file(tmp_path, arm)
    out = tmp_path / "rep"
    assert main(["report", "--arm", str(f), "--quick", "--outdir", str(out), "--processes",
                 str(processes), *extra]) == 0
    return out


def test_a_quick_report_of_a_random_arm_has_no_thesis_value(tmp_path, capsys):
    arm = tl.random_arm(SEEDS[0])
    out = _report(tmp_path, arm, "--only", ",".join(QUICK_SECTIONS))
    leaks = tl.scan_folder(out, arm)
    assert leaks == [], _leaks_text(leaks)
    assert tl.scan_output(capsys.readouterr().out, arm) == []


@pytest.mark.slow
@pytest.mark.parametrize("which", ["example", "variant", "random 11", "random 12"])
def test_the_whole_quick_report_for_another_arm_has_no_thesis_value(which, tmp_path):
    arm = (load_arm(tl.EXAMPLE) if which == "example" else tl.user_variant()
           if which == "variant" else tl.random_arm(int(which.split()[1])))
    out = _report(tmp_path, arm, "--include", "as_built,cylinder_friction,person")
    md = (out / "index.md").read_text()
    assert all(f"*Section `{name}` ran in" in md for name in REGISTRY)
    leaks = tl.scan_folder(out, arm)
    assert leaks == [], _leaks_text(leaks)
    cols = pd.read_csv(out / "columns.csv", keep_default_na=False)    # and every unit declared
    num = cols[cols.kind == "number"]
    assert (num.unit != "").all(), num[num.unit == ""].to_dict("records")


def test_random_arms_are_valid_not_the_thesis_arm_and_reproducible():
    a, b = tl.random_arm(SEEDS[0]), tl.random_arm(SEEDS[0])
    assert a == b and a != tl.random_arm(SEEDS[1])
    for arm in (a, tl.user_variant()):
        assert not arm == thesis_arm()
        assert arm.effects.hysteresis_delta is not None
        assert re.search(r"\S", arm.name)
    assert np.isfinite(tl.own_values(a)[-1][0])
