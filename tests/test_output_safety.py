"""No user file is ever deleted or overwritten by what the toolkit writes (issue 8.1)."""

import json
import os
from pathlib import Path

import pytest

from ppamsafety.cli import main
from ppamsafety.output import (MARKER, OutputError, OutputFolder, atomic_write, read_marker)

REPO = Path(__file__).resolve().parents[1]
QUICK = ["--quick", "--only", "design"]


def _marked(folder, files, kind="report", extra=()):
    folder.mkdir(parents=True, exist_ok=True)
    for f in list(files) + list(extra):
        (folder / f).parent.mkdir(parents=True, exist_ok=True)
        (folder / f).write_text(f"content of {f}")
    (folder / MARKER).write_text(json.dumps({"tool": "ppamsafety", "version": "0", "kind": kind,
                                             "files": list(files)}))


def _write(stage, **files):
    for name, text in files.items():
        (stage / name).write_text(text)


# ---- the output folder rule, without running studies -------------------------------------

def test_missing_folder_is_created_and_marked(tmp_path):
    out = tmp_path / "a" / "b"
    with OutputFolder(out, kind="report") as stage:
        _write(stage, **{"x.csv": "1"})
    assert (out / "x.csv").read_text() == "1"
    assert read_marker(out)["files"] == ["x.csv"] and read_marker(out)["kind"] == "report"
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "x.csv"]     # no staging left


def test_folder_with_user_file_is_refused_and_untouched(tmp_path):
    (tmp_path / "thesis.tex").write_text("years of work")
    for flag in (False, True):
        with pytest.raises(OutputError, match="no marker") as e:
            with OutputFolder(tmp_path, kind="report", overwrite=flag):
                pytest.fail("must not be entered")
        assert str(tmp_path) in str(e.value) and "thesis.tex" in str(e.value)
    assert (tmp_path / "thesis.tex").read_text() == "years of work"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["thesis.tex"]


def test_staging_folder_of_a_killed_run_neither_blocks_nor_is_deleted(tmp_path):
    """A run killed by SIGKILL cannot remove its staging folder; the next run with the flag
    must still work, warn about the leftover and leave it (and its contents) in place."""
    _marked(tmp_path, ["old.csv"])
    stale = tmp_path / ".ppamsafety-staging-dead1234"
    stale.mkdir()
    (stale / "half.png").write_text("partial")
    with pytest.warns(UserWarning, match="interrupted"):
        with OutputFolder(tmp_path, kind="report", overwrite=True) as stage:
            _write(stage, **{"new.csv": "n"})
    assert (tmp_path / "new.csv").read_text() == "n" and not (tmp_path / "old.csv").exists()
    assert (stale / "half.png").read_text() == "partial"
    assert read_marker(tmp_path)["files"] == ["new.csv"]
    # a user file is still refused, leftover or not
    (tmp_path / "mine.txt").write_text("x")
    with pytest.warns(UserWarning), pytest.raises(OutputError, match="mine.txt"):
        with OutputFolder(tmp_path, kind="report", overwrite=True):
            pytest.fail("must not be entered")


def test_marked_folder_needs_the_flag(tmp_path):
    _marked(tmp_path, ["old.csv"])
    with pytest.raises(OutputError, match="--overwrite"):
        with OutputFolder(tmp_path, kind="report"):
            pass
    assert (tmp_path / "old.csv").read_text() == "content of old.csv"


def test_flag_replaces_only_listed_files(tmp_path):
    _marked(tmp_path, ["old.csv", "same.csv", "sub/deep.png"])
    with OutputFolder(tmp_path, kind="report", overwrite=True) as stage:
        _write(stage, **{"same.csv": "new", "fresh.csv": "f"})
    assert not (tmp_path / "old.csv").exists() and not (tmp_path / "sub").exists()
    assert (tmp_path / "same.csv").read_text() == "new"
    assert read_marker(tmp_path)["files"] == ["fresh.csv", "same.csv"]


def test_flag_does_not_remove_a_foreign_file_in_a_marked_folder(tmp_path):
    _marked(tmp_path, ["old.csv"], extra=["notes.txt", "sub/mine.dat"])
    with pytest.raises(OutputError, match="did not write") as e:
        with OutputFolder(tmp_path, kind="report", overwrite=True):
            pass
    assert "notes.txt" in str(e.value) and "sub/mine.dat" in str(e.value)
    assert (tmp_path / "notes.txt").exists() and (tmp_path / "sub" / "mine.dat").exists()
    assert (tmp_path / "old.csv").exists()


@pytest.mark.parametrize("marker", ["not json", json.dumps([1, 2]),
                                    json.dumps({"tool": "other", "kind": "report", "files": []}),
                                    json.dumps({"tool": "ppamsafety", "kind": "report",
                                                "files": ["../escape.txt"]})])
def test_invalid_marker_is_not_ours(tmp_path, marker):
    (tmp_path / "data.csv").write_text("user")
    (tmp_path / MARKER).write_text(marker)
    with pytest.raises(OutputError, match="not valid"):
        with OutputFolder(tmp_path, kind="report", overwrite=True):
            pass
    assert (tmp_path / "data.csv").read_text() == "user"


def test_a_failed_run_leaves_the_previous_output_untouched(tmp_path):
    _marked(tmp_path, ["old.csv"])
    with pytest.raises(RuntimeError, match="study broke"):
        with OutputFolder(tmp_path, kind="report", overwrite=True) as stage:
            _write(stage, **{"old.csv": "half"})
            raise RuntimeError("study broke")
    assert (tmp_path / "old.csv").read_text() == "content of old.csv"
    assert sorted(p.name for p in tmp_path.iterdir()) == [MARKER, "old.csv"]


def test_file_added_during_the_run_is_kept_and_blocks_the_commit(tmp_path):
    out = tmp_path / "r"
    with pytest.raises(OutputError, match="late.txt"):
        with OutputFolder(out, kind="report") as stage:
            _write(stage, **{"x.csv": "1"})
            (out / "late.txt").write_text("user wrote this meanwhile")
    assert (out / "late.txt").read_text() == "user wrote this meanwhile"
    assert not (out / "x.csv").exists()


def test_study_mode_adds_to_a_previous_output(tmp_path):
    _marked(tmp_path, ["index.md", "a.csv"])
    with pytest.raises(OutputError, match="not a study"):     # only the kinds it may update
        OutputFolder(tmp_path, kind="study", overwrite=True, clean=False).__enter__()
    with OutputFolder(tmp_path, kind="study", overwrite=True, clean=False,
                      kinds=("study", "report")) as stage:
        _write(stage, **{"a.csv": "new", "b.csv": "b"})
    assert (tmp_path / "index.md").exists() and (tmp_path / "a.csv").read_text() == "new"
    m = read_marker(tmp_path)
    assert m["files"] == ["a.csv", "b.csv", "index.md"] and m["kind"] == "report"


def test_outdir_that_is_a_file_or_not_a_path(tmp_path):
    f = tmp_path / "f.txt"
    f.write_text("keep")
    with pytest.raises(OutputError, match="not a folder"):
        OutputFolder(f, kind="report").__enter__()
    with pytest.raises(TypeError, match="outdir"):
        OutputFolder(3, kind="report")
    assert f.read_text() == "keep"


def test_atomic_write_never_overwrites_without_the_flag(tmp_path):
    f = tmp_path / "h.csv"
    f.write_text("user")
    with pytest.raises(OutputError, match="already exists"):
        atomic_write(f, lambda t: t.write_text("new"))
    assert f.read_text() == "user"
    atomic_write(f, lambda t: t.write_text("new"), overwrite=True)
    assert f.read_text() == "new"
    g = atomic_write(tmp_path / "g.csv", lambda t: t.write_text("g"))
    assert g.read_text() == "g" and sorted(p.name for p in tmp_path.iterdir()) == ["g.csv",
                                                                                   "h.csv"]
    with pytest.raises(OutputError, match="does not exist"):
        atomic_write(tmp_path / "nope" / "x.csv", lambda t: t.write_text("x"))


def test_atomic_write_failure_leaves_no_temp_file(tmp_path):
    def broken(t):
        t.write_text("partial")
        raise RuntimeError("disk full")
    with pytest.raises(RuntimeError):
        atomic_write(tmp_path / "x.csv", broken)
    assert list(tmp_path.iterdir()) == []


def test_shipped_reports_marker_lists_every_file():
    """`ppamsafety report --overwrite` on a fresh clone must accept the shipped reports/."""
    m = read_marker(REPO / "reports")
    assert m is not None and m["kind"] == "report"
    on_disk = sorted(p.relative_to(REPO / "reports").as_posix()
                     for p in (REPO / "reports").rglob("*") if p.is_file() and p.name != MARKER)
    assert sorted(m["files"]) == on_disk


# ---- the commands ------------------------------------------------------------------------

def test_report_into_folder_with_user_file_is_an_error(tmp_path, capsys):
    (tmp_path / "mine.txt").write_text("precious")
    for extra in ([], ["--overwrite"]):
        assert main(["report", "--outdir", str(tmp_path), *QUICK, *extra]) == 2
        err = capsys.readouterr().err
        assert "ppamsafety: error:" in err and str(tmp_path) in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.txt"]
    assert (tmp_path / "mine.txt").read_text() == "precious"


def test_report_into_the_current_folder_is_refused(tmp_path, monkeypatch, capsys):
    (tmp_path / "setup.py").write_text("code")
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "a.py").write_text("more code")
    monkeypatch.chdir(tmp_path)
    assert main(["report", "--outdir", ".", *QUICK, "--overwrite"]) == 2
    assert "not a ppamsafety output" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["setup.py", "src"]


def test_report_replaces_its_own_folder_only_with_the_flag(tmp_path, capsys):
    out = tmp_path / "rep"
    assert main(["report", "--outdir", str(out), *QUICK]) == 0
    first = read_marker(out)["files"]
    assert "index.md" in first and "design_max_load.png" in first
    assert main(["report", "--outdir", str(out), *QUICK]) == 2
    assert "--overwrite" in capsys.readouterr().err
    (out / "index.md").write_text("stale")
    assert main(["report", "--outdir", str(out), *QUICK, "--overwrite"]) == 0
    assert "Table A.1" in (out / "index.md").read_text()
    assert read_marker(out)["files"] == first
    (out / "my_notes.md").write_text("mine")                   # now a foreign file
    assert main(["report", "--outdir", str(out), *QUICK, "--overwrite"]) == 2
    assert "my_notes.md" in capsys.readouterr().err
    assert (out / "my_notes.md").read_text() == "mine" and (out / "index.md").exists()


def test_one_section_alone_uses_the_same_rules(tmp_path, capsys):
    (tmp_path / "mine.txt").write_text("precious")
    one = ["report", "--only", "design", "--quick"]
    assert main([*one, "--outdir", str(tmp_path), "--overwrite"]) == 2
    assert "mine.txt" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.txt"]
    out = tmp_path / "s"
    assert main([*one, "--outdir", str(out)]) == 0
    assert "design_table_A1.csv" in read_marker(out)["files"]
    assert main([*one, "--outdir", str(out)]) == 2


def test_history_onto_an_existing_file_is_an_error(tmp_path, capsys):
    h = tmp_path / "h.csv"
    h.write_text("user data")
    args = ["impact", "--q", "50", "-80", "--qd", "3", "-1", "--history", str(h)]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "already exists" in err and str(h) in err
    assert h.read_text() == "user data"
    assert main(args + ["--overwrite"]) == 0
    assert h.read_text().startswith("t")                       # a CSV header, written atomically
    assert sorted(os.listdir(tmp_path)) == ["h.csv"]
