"""Command line and report generation."""

import subprocess
import sys

from ppamsafety.cli import main


def test_help_exits_cleanly():
    r = subprocess.run([sys.executable, "-m", "ppamsafety.cli", "--help"], capture_output=True,
                       text=True)
    assert r.returncode == 0
    assert "report" in r.stdout


def test_unknown_study_is_a_clear_error(tmp_path, capsys):
    assert main(["report", "--outdir", str(tmp_path / "r"), "--only", "nonsense"]) == 2
    assert "unknown studies" in capsys.readouterr().err


def test_report_regenerates_from_scratch(tmp_path):
    out = tmp_path / "rep"
    out.mkdir()
    (out / "stale.txt").write_text("old")
    assert main(["report", "--outdir", str(out), "--quick", "--only", "design"]) == 0
    assert not (out / "stale.txt").exists()
    text = (out / "index.md").read_text()
    assert "Table A.1" in text and (out / "design_max_load.png").exists()
