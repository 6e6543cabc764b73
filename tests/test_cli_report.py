"""Command line and report generation."""

import json
import os
import subprocess
import sys

import pytest

from ppamsafety.cli import _split_multi_value, build_parser, main
from ppamsafety.output import MARKER


def test_help_exits_cleanly():
    r = subprocess.run([sys.executable, "-m", "ppamsafety.cli", "--help"], capture_output=True,
                       text=True)
    assert r.returncode == 0
    assert "report" in r.stdout


def test_unknown_section_is_a_clear_error(tmp_path, capsys):
    assert main(["report", "--outdir", str(tmp_path / "r"), "--only", "nonsense"]) == 2
    assert "unknown report section(s) 'nonsense'" in capsys.readouterr().err


def test_report_regenerates_from_scratch(tmp_path):
    out = tmp_path / "rep"
    assert main(["report", "--outdir", str(out), "--quick", "--only", "design"]) == 0
    (out / "design_stale.png").write_text("old")          # toolkit-written, listed as such
    m = json.loads((out / MARKER).read_text())
    (out / MARKER).write_text(json.dumps({**m, "files": m["files"] + ["design_stale.png"]}))
    assert main(["report", "--outdir", str(out), "--quick", "--only", "design",
                 "--overwrite"]) == 0
    assert not (out / "design_stale.png").exists()
    text = (out / "index.md").read_text()
    assert "Table A.1" in text and (out / "design_max_load.png").exists()
    page = (out / "index.html").read_text(encoding="utf-8")     # the same report as a page
    assert "<table>" in page and 'src="design_max_load.png"' in page
    assert "index.html" in json.loads((out / MARKER).read_text())["files"]


def test_help_documents_exit_codes_and_overwrite():
    r = subprocess.run([sys.executable, "-m", "ppamsafety.cli", "report", "--help"],
                       capture_output=True, text=True)
    assert r.returncode == 0
    for text in ("exit status", "0    success", "2    bad usage", "1    failure", "--overwrite"):
        assert text in r.stdout


def test_user_error_in_a_real_process_has_no_traceback(tmp_path):
    (tmp_path / "mine.txt").write_text("keep")
    r = subprocess.run([sys.executable, "-m", "ppamsafety.cli", "report", "--outdir",
                        str(tmp_path), "--overwrite"], capture_output=True, text=True,
                       env={**os.environ, "PPAMSAFETY_DEBUG": "0"})
    assert r.returncode == 2
    assert r.stderr.startswith("ppamsafety: error:") and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert (tmp_path / "mine.txt").read_text() == "keep"


def test_unexpected_failure_exits_1_without_traceback(monkeypatch, capsys):
    import ppamsafety.cli as cli

    def boom(args):
        raise KeyError("internal")
    monkeypatch.setattr(cli, "_cmd_info", boom)
    monkeypatch.delenv("PPAMSAFETY_DEBUG", raising=False)
    assert main(["info"]) == 1
    err = capsys.readouterr().err
    assert "please report" in err and "KeyError" in err and "Traceback" not in err
    monkeypatch.setenv("PPAMSAFETY_DEBUG", "1")
    assert main(["info"]) == 1
    assert "Traceback" in capsys.readouterr().err


@pytest.mark.parametrize("argv", [
    ["--q", "-1e1", "-80", "--qd", "-3", "-1"],
    ["--q=-1e-3", "-80", "--qd", "-3", "-1"],
    ["--q", "50", "-8E1", "--qd=-3", "-1.5e0", "--stiffness", "4.3e1", "27"],
    ["--q", "-.5", "-80", "--qd", "3", "-1", "--dt", "1e-5"],
])
def test_negative_numbers_parse_as_values(argv):
    args = build_parser().parse_args(_split_multi_value(["impact", *argv]))
    assert len(args.q) == 2 and len(args.qd) == 2
    assert any(v < 0 for v in (*args.q, *args.qd))
    assert all(isinstance(v, float) for v in (*args.q, *args.qd))


def test_negative_scientific_angle_gives_a_clear_error(capsys):
    assert main(["impact", "--q", "-1e5", "-80", "--qd", "-3", "-1"]) == 2
    err = capsys.readouterr().err
    assert "--q" in err and "-100000 deg" in err and "[-360, 360]" in err


@pytest.mark.parametrize("argv, words", [
    (["--q", "nan", "0", "--qd", "0", "0"], ["--q", "'nan'", "finite"]),
    (["--q", "0", "0", "--qd", "inf", "0"], ["--qd", "'inf'", "finite"]),
    (["--q", "0", "0", "--qd", "0", "0", "--dt", "-1e-5"],
     ["--dt", "-1e-05", "[1e-08, 0.001] s"]),
    (["--q", "0", "0", "--qd", "0", "0", "--stiffness", "-1", "27"], ["--stiffness", ">= 0"]),
    (["--q", "abc", "0", "--qd", "0", "0"], ["--q", "'abc'", "not a number"]),
])
def test_bad_impact_values_are_refused(argv, words, capsys):
    assert main(["impact", *argv]) == 2
    err = capsys.readouterr().err
    assert all(w in err for w in words), err


@pytest.mark.parametrize("only", ["", ",", " , "])
def test_empty_only_is_an_error_not_everything(only, tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["report", "--outdir", str(out), "--only", only]) == 2
    assert "names no report section" in capsys.readouterr().err
    assert not out.exists()


def test_build_report_checks_only(tmp_path):
    from ppamsafety.report.build import build_report

    with pytest.raises(ValueError, match="names no report section"):
        build_report(tmp_path / "r", only=[])
    with pytest.raises(TypeError, match="list of section names"):
        build_report(tmp_path / "r", only="design")
    assert not (tmp_path / "r").exists()


def test_a_reader_that_leaves_early_is_not_an_error():
    """`ppamsafety impact ... | head -1`: the closed pipe gives exit 0 and no message."""
    p = subprocess.Popen([sys.executable, "-m", "ppamsafety.cli", "impact", "--q", "50", "-80",
                          "--qd", "3", "-1"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    p.stdout.close()                                   # the reader is gone before any output
    err = p.stderr.read().decode()
    assert p.wait(timeout=300) == 0
    assert "Traceback" not in err and "error" not in err


def test_report_in_worker_processes_equals_the_serial_report(tmp_path):
    """Sections run in parallel worker processes; the report is assembled in the order asked
    for and its text is that of the serial run (up to the measured run times)."""
    import re

    from ppamsafety.report.build import build_report

    only = ["stiffness", "design"]                         # not in registry order
    a = build_report(tmp_path / "a", quick=True, only=only, progress=False, processes=2)
    b = build_report(tmp_path / "b", quick=True, only=only, progress=False, processes=1)
    strip = lambda t: re.sub(r"ran in [0-9.]+ s", "ran in - s", t)     # noqa: E731
    ta, tb = strip(a.read_text()), strip(b.read_text())
    assert ta == tb and ta.index("Section `stiffness`") < ta.index("Section `design`")
    assert sorted(p.name for p in a.parent.glob("*.png")) == \
        sorted(p.name for p in b.parent.glob("*.png"))
    # a second run schedules by the recorded times and still writes the same report
    a2 = build_report(tmp_path / "a", quick=True, only=only, progress=False, processes=2,
                      overwrite=True)
    assert strip(a2.read_text()) == tb
    with pytest.raises(ValueError, match="processes"):
        build_report(tmp_path / "c", quick=True, only=only, processes=0)


def test_report_processes_option_is_validated(tmp_path, capsys):
    assert main(["report", "--outdir", str(tmp_path / "r"), "--processes", "0"]) == 2
    assert "not positive" in capsys.readouterr().err
