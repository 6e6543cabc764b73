"""`ppamsafety arm export/check`, and `--arm`/`--head` on every command (issue 21.1-2)."""

from pathlib import Path

import pytest

from ppamsafety.cli import build_parser, main
from ppamsafety.data import load_measured, read_metadata
from ppamsafety.impact.head import head_model
from ppamsafety.design import load_arm
from ppamsafety.params import thesis_arm
from ppamsafety.params.arm_file import arm_fingerprint

ROOT = Path(__file__).parent.parent
EXAMPLE = ROOT / "examples" / "arms" / "forty_fibre_heavy_forearm.toml"
COMMANDS = {"report": [], "identify": ["d.csv", "--kind", "static", "--out", "o"],
            "sweep": ["s.toml", "--out", "o"], "diagnose": ["d.csv", "--out", "o"],
            "synthesize": ["--out", "o.csv"], "impact": ["--q", "50", "-80", "--qd", "1", "0"],
            "info": []}


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_command_takes_arm_and_head(command):
    args = build_parser().parse_args([command, *COMMANDS[command], "--arm", "a.toml",
                                      "--head", "h.toml"])
    assert args.arm == "a.toml" and args.head == "h.toml"


def test_export_writes_a_commented_template_that_reads_back(tmp_path, capsys):
    out = tmp_path / "my_arm.toml"
    assert main(["arm", "export", "--out", str(out)]) == 0
    text = out.read_text()
    assert text.count("\n#") > 20 and "# payload_mass = " in text       # commented, effects off
    assert load_arm(out) == thesis_arm()
    assert main(["arm", "export", "--out", str(out)]) == 2              # never overwritten ...
    assert "--overwrite" in capsys.readouterr().err
    assert main(["arm", "export", "--out", str(out), "--arm", str(EXAMPLE), "--overwrite"]) == 0
    assert load_arm(out) == load_arm(EXAMPLE)                           # ... unless asked


def test_check_prints_the_summary_or_names_the_bad_key(tmp_path, capsys):
    assert main(["arm", "check", str(EXAMPLE)]) == 0
    text = capsys.readouterr().out
    for words in ("valid arm file", "40-fibre muscles", "joint stiffness K1 at the pose",
                  "maximum load", "TCP workspace area", "hysteresis_delta"):
        assert words in text, words
    bad = tmp_path / "bad.toml"
    bad.write_text(EXAMPLE.read_text().replace('l0 = { value = 0.06, unit = "m" }',
                                               'l0 = { value = -0.1, unit = "m" }', 1))
    assert main(["arm", "check", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("ppamsafety: error: ")
    assert "muscles.group1.l0 = -0.1 m: must be in (0, 1] m" in err[0]
    assert main(["arm", "check", str(EXAMPLE), "--q", "10", "-80"]) == 2    # outside the area
    assert "outside the working area" in capsys.readouterr().err


def test_info_and_impact_use_the_given_arm_and_head(tmp_path, capsys):
    head = tmp_path / "face.toml"
    head.write_text(head_model("iso15066-face").to_toml().replace('"iso15066-face"', '"my face"'))
    assert main(["info", "--arm", str(EXAMPLE), "--head", str(head)]) == 0
    out = capsys.readouterr().out
    assert "40-fibre muscles, heavier forearm" in out and arm_fingerprint(load_arm(EXAMPLE)) in out
    assert "'my face'" in out and "check iso_ts_15066" in out and "claimed met" in out
    assert main(["impact", "--q", "50", "-80", "--qd", "1", "0", "--arm", str(EXAMPLE),
                 "--head", str(head)]) == 0
    out = capsys.readouterr().out
    assert "40-fibre muscles" in out and "my face" in out
    assert main(["impact", "--q", "50", "-80", "--qd", "1", "0", "--head", "nobody"]) == 2


def test_a_synthesized_record_names_its_arm_and_diagnose_refuses_another(tmp_path, capsys):
    rec = tmp_path / "rec.csv"
    assert main(["synthesize", "--arm", str(EXAMPLE), "--duration", "2", "--seed", "3",
                 "--out", str(rec)]) == 0
    meta = read_metadata(rec)
    fp = arm_fingerprint(load_arm(EXAMPLE))
    assert meta["arm"] == {"name": "40-fibre muscles, heavier forearm", "sha256": fp}
    assert load_measured(rec).meta["arm"]["sha256"] == meta["arm"]["sha256"]
    # the forgotten --arm: refused before computing, the record's arm named
    assert main(["diagnose", str(rec), "--out", str(tmp_path / "dg"), "--bootstrap", "0",
                 "--head", "thesis-frontal"]) == 2
    err = capsys.readouterr().err
    assert "--head has no effect on diagnose" in err
    line = err.strip().splitlines()[-1]
    assert line.startswith("ppamsafety: error: ")
    assert "the record came from arm '40-fibre muscles, heavier forearm'" in line
    assert fp[:16] in line and "--arm FILE" in line and "diagnosed against arm 'thesis arm'" in line
    assert not (tmp_path / "dg").exists()
    assert main(["diagnose", str(rec), "--out", str(tmp_path / "dg"), "--arm", str(EXAMPLE)]) == 0
