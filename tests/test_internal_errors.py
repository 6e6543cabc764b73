"""A bug is never reported as the user's error, and the report passes each section only the
options it takes.

``ppamsafety report --arm FILE --head NAME`` once stopped with "ppamsafety: error: got an
unexpected keyword argument 'head'" (exit 2): the head was passed to a section that crashes
into none, and the ``TypeError`` of that call was reported as bad input.
"""

import types

import numpy as np
import pytest

from ppamsafety import sections
from ppamsafety._commandline import (EXIT_FAILURE, EXIT_USAGE, InternalFailure, Parser,
                                     is_internal_error, mark_internal, run_guarded)
from ppamsafety._validation import check_int
from ppamsafety.cli import main
from ppamsafety.sections import Section, SectionInfo
from ppamsafety.sweep import run_sweep


def _run(func):
    return run_guarded(Parser(prog="ppamsafety test"), lambda args: func(), [])


def _takes_a(*, a):
    return a


@pytest.mark.parametrize("bug", [
    lambda: _takes_a(b=1),                          # a call with a wrong keyword
    lambda: 1 + "a",                                # an operation on the wrong type
    lambda: np.zeros(3) + "a",                      # numpy's own TypeError
    lambda: __import__("inspect").signature(_takes_a).bind(head=1),   # inspect: 'head'
])
def test_a_type_error_of_the_interpreter_or_a_library_is_an_internal_failure(bug, capsys):
    assert _run(bug) == EXIT_FAILURE
    err = capsys.readouterr().err
    assert err.startswith("ppamsafety: error: internal failure (") and "TypeError: " in err \
        and "please report" in err


def test_a_wrong_call_inside_the_package_is_an_internal_failure(tmp_path, monkeypatch, capsys):
    # the innermost frame is the package's own call (run_section), not a ``raise``
    _patch_sections(monkeypatch, {"design": _fake_section("design", lambda *, arm=None: 0)})
    assert _run(lambda: sections.run_section("design", tmp_path)) == EXIT_FAILURE
    assert "unexpected keyword argument 'quick'" in capsys.readouterr().err


def test_a_type_error_raised_by_the_library_on_purpose_is_bad_input(capsys):
    assert _run(lambda: check_int("--count", "three", 0, 10)) == EXIT_USAGE
    err = capsys.readouterr().err
    assert "--count" in err and "internal failure" not in err
    with pytest.raises(TypeError) as info:
        check_int("n", None, 0, 1)
    assert not is_internal_error(info.value)


def test_value_errors_stay_bad_input(capsys):
    def bad():
        raise ValueError("--x = 3: must be below 2")
    assert _run(bad) == EXIT_USAGE and "--x = 3" in capsys.readouterr().err


def test_mark_internal_keeps_a_bug_a_bug_across_processes():
    try:
        _takes_a(b=1)
    except TypeError as exc:
        marked = mark_internal(exc, "report section 'x'")
    assert isinstance(marked, InternalFailure) and "report section 'x'" in str(marked)
    assert "unexpected keyword argument 'b'" in str(marked)
    try:
        check_int("n", None, 0, 1)
    except TypeError as exc:
        assert mark_internal(exc, "x") is exc


def _patch_sections(monkeypatch, fakes: dict) -> None:
    """``sections.section_module`` answers the fakes by name, the real modules otherwise."""
    real = sections.section_module
    monkeypatch.setattr(sections, "section_module", lambda name: fakes.get(name) or real(name))


def _fake_section(name, compute):
    def render(study):
        return Section(title=name, markdown=f"{name}: {study}", artifacts=[], metrics={})
    return types.SimpleNamespace(compute=compute, render=render,
                                 SECTION=SectionInfo("a test section", "(new)", 1.0))


@pytest.mark.parametrize("processes", [1, 2])
def test_the_report_passes_a_head_only_to_sections_that_take_one(tmp_path, monkeypatch,
                                                                 processes):
    seen = {}

    def with_head(*, quick=False, arm=None, head=None):
        seen["with_head"] = head.name
        return "with head"

    def without_head(*, quick=False, arm=None):
        return "no head"

    fakes = {"design": _fake_section("design", with_head),
             "cylinder_friction": _fake_section("cylinder_friction", without_head)}
    _patch_sections(monkeypatch, fakes)
    assert sections.section_options("cylinder_friction") == {"quick", "arm"}
    out = tmp_path / "r"
    assert main(["report", "--quick", "--only", "design,cylinder_friction", "--outdir", str(out),
                 "--head", "child-frontal", "--processes", str(processes)]) == 0
    md = (out / "index.md").read_text()
    assert "design: with head" in md and "cylinder_friction: no head" in md
    if processes == 1:
        assert seen == {"with_head": "child-frontal"}


@pytest.mark.parametrize("processes", [1, 2])
def test_a_bug_in_a_section_is_an_internal_failure_not_bad_input(tmp_path, monkeypatch, capsys,
                                                                 processes):
    def buggy(*, quick=False, arm=None, head=None):
        return _takes_a(b=1)

    fakes = {"design": _fake_section("design", buggy),
             "stiffness": _fake_section("stiffness", lambda *, quick=False, arm=None,
                                        head=None: "ok")}
    _patch_sections(monkeypatch, fakes)
    rc = main(["report", "--quick", "--only", "design,stiffness", "--outdir",
               str(tmp_path / "r"), "--processes", str(processes)])
    err = capsys.readouterr().err
    assert rc == EXIT_FAILURE and "internal failure" in err, err
    assert "unexpected keyword argument 'b'" in err
    if processes > 1:
        assert "report section 'design'" in err


def _sweep_case(kind):
    if kind == "bug":
        return _takes_a(b=1)
    if kind == "bad":
        check_int("n", "three", 0, 1)
    return {"x": 1.0}


@pytest.mark.parametrize("processes", [1, 2])
def test_a_sweep_case_that_meets_a_bug_says_so(processes):
    df = run_sweep(_sweep_case, [{"kind": "bug"}, {"kind": "bad"}, {"kind": "ok"}, {"kind": "ok"}],
                   processes=processes, progress=False)
    err = dict(zip(df["kind"], df["error"]))
    assert err["bug"].startswith("InternalFailure: sweep case: TypeError: ") and \
        "unexpected keyword argument 'b'" in err["bug"]
    assert err["bad"].startswith("InvalidTypeError: n must be a")
    assert list(df["status"]) == ["failed", "failed", "ok", "ok"]
