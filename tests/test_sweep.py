"""Sweep runner: results, resume from cache, several processes, errors."""

import importlib
import re
import sys

import pandas as pd
import pytest

import ppamsafety.sweep as sweep_mod
from ppamsafety.sweep import SweepError, case_key, function_hash, run_sweep

CALLS = []


def square(x, y=1.0):
    CALLS.append(x)
    return {"value": x * x * y}


def rows(n):
    return pd.DataFrame({"i": range(n), "sq": [i * i for i in range(n)]})


def test_sweep_returns_cases_and_results_in_order():
    df = run_sweep(square, [{"x": 3.0}, {"x": 1.0, "y": 2.0}], progress=False)
    assert list(df["x"]) == [3.0, 1.0] and list(df["value"]) == [9.0, 2.0]


def test_sweep_resumes_without_recomputing(tmp_path):
    CALLS.clear()
    cases = [{"x": float(i)} for i in range(4)]
    run_sweep(square, cases[:2], cache_dir=tmp_path, progress=False)
    assert CALLS == [0.0, 1.0]
    df = run_sweep(square, cases, cache_dir=tmp_path, progress=False)
    assert CALLS == [0.0, 1.0, 2.0, 3.0]                  # only the new ones ran
    assert list(df["value"]) == [0.0, 1.0, 4.0, 9.0]


def test_sweep_on_two_processes_equals_serial():
    cases = [{"n": n} for n in (1, 3, 2)]
    a = run_sweep(rows, cases, processes=2, progress=False)
    b = run_sweep(rows, cases, processes=1, progress=False)
    pd.testing.assert_frame_equal(a, b)


def test_case_key_is_stable_and_checks_serialisability():
    assert case_key("s", {"a": 1, "b": 2}) == case_key("s", {"b": 2, "a": 1})
    assert case_key("s", {"a": 1}) != case_key("t", {"a": 1})
    with pytest.raises(ValueError, match="JSON"):
        case_key("s", {"a": object()})


# ---- failures, cache safety, arguments (issues 8.5 and 7.8) ------------------------------

def fails_on_two(x):
    if x == 2:
        raise ValueError(f"x = {x} is bad")
    return {"value": 10 * x}


@pytest.mark.parametrize("processes", [1, 2])
def test_failing_case_is_recorded_and_the_others_kept(tmp_path, processes, monkeypatch):
    monkeypatch.setattr(sweep_mod, "available_cores", lambda: 2)   # really use 2 workers
    cases = [{"x": x} for x in range(4)]
    with pytest.warns(RuntimeWarning, match=r"1 of 4 cases failed.*x = 2 is bad"):
        df = run_sweep(fails_on_two, cases, cache_dir=tmp_path, processes=processes,
                       progress=False)
    assert list(df.columns[:3]) == ["x", "status", "error"]
    assert list(df.status) == ["ok", "ok", "failed", "ok"]
    assert df.error[2] == "ValueError: x = 2 is bad" and df.error[0] == ""
    assert list(df.value[[0, 1, 3]]) == [0, 10, 30] and pd.isna(df.value[2])
    assert len(list(tmp_path.glob("*.pkl"))) == 3                # every success cached


@pytest.mark.parametrize("processes", [1, 2])
def test_on_error_raise_names_the_case_and_keeps_finished_results(tmp_path, processes,
                                                                  monkeypatch):
    monkeypatch.setattr(sweep_mod, "available_cores", lambda: 2)
    cases = [{"x": x} for x in (0, 1, 2)]
    with pytest.raises(SweepError, match=r"case 2 \{'x': 2\} failed: ValueError") as e:
        run_sweep(fails_on_two, cases, cache_dir=tmp_path, processes=processes, progress=False,
                  on_error="raise")
    assert e.value.index == 2 and e.value.case == {"x": 2}
    assert len(list(tmp_path.glob("*.pkl"))) == 2
    CALLS.clear()
    df = run_sweep(square, [{"x": 1.0}], progress=False, on_error="raise")
    assert "status" not in df.columns and list(df.value) == [1.0]


@pytest.mark.parametrize("garbage", [b"", b"not a pickle at all", b"\x80\x04\x95"])
def test_corrupt_cache_file_is_named_and_recomputed(tmp_path, garbage):
    CALLS.clear()
    run_sweep(square, [{"x": 3.0}], cache_dir=tmp_path, progress=False)
    (f,) = tmp_path.glob("*.pkl")
    f.write_bytes(garbage)
    with pytest.warns(RuntimeWarning, match=re.escape(str(f))):
        df = run_sweep(square, [{"x": 3.0}], cache_dir=tmp_path, progress=False)
    assert CALLS == [3.0, 3.0] and list(df.value) == [9.0]
    CALLS.clear()
    run_sweep(square, [{"x": 3.0}], cache_dir=tmp_path, progress=False)     # repaired
    assert CALLS == []


def test_more_processes_than_cores_warns_and_caps(monkeypatch):
    monkeypatch.setattr(sweep_mod, "available_cores", lambda: 1)
    CALLS.clear()
    with pytest.warns(UserWarning, match="processes = 3 exceeds the 1 available cores; using 1"):
        df = run_sweep(square, [{"x": 1.0}, {"x": 2.0}], processes=3, progress=False)
    assert CALLS == [1.0, 2.0]                  # capped to 1: ran in this process
    assert list(df.value) == [1.0, 4.0]


MODULE_V1 = "def case(x):\n    return {'y': x + 1}\n"
MODULE_V2 = "def case(x):\n    # edited: the model changed\n    return {'y': x + 1000}\n"


def test_editing_the_function_invalidates_the_cache(tmp_path, monkeypatch):
    src = tmp_path / "src"
    src.mkdir()
    mod_file = src / "edited_sweep_case.py"
    mod_file.write_text(MODULE_V1)
    monkeypatch.syspath_prepend(str(src))
    mod = importlib.import_module("edited_sweep_case")
    cache = tmp_path / "cache"
    try:
        a = run_sweep(mod.case, [{"x": 1}], cache_dir=cache, progress=False)
        assert list(a.y) == [2]
        assert list(run_sweep(mod.case, [{"x": 1}], cache_dir=cache, progress=False).y) == [2]
        assert len(list(cache.glob("*.pkl"))) == 1                  # reused, not recomputed
        mod_file.write_text(MODULE_V2)
        mod = importlib.reload(mod)
        b = run_sweep(mod.case, [{"x": 1}], cache_dir=cache, progress=False)
        assert list(b.y) == [1001]
        assert len(list(cache.glob("*.pkl"))) == 2
    finally:
        sys.modules.pop("edited_sweep_case", None)


def test_function_hash_follows_code_and_package_source(monkeypatch):
    h = function_hash(square)
    assert h == function_hash(square) and h != function_hash(rows)
    monkeypatch.setattr(sweep_mod, "source_hash", lambda: "other-package-source")
    assert function_hash(square) != h


@pytest.mark.parametrize("kwargs, exc, words", [
    ({"func": 3}, TypeError, ["func", "callable", "int"]),
    ({"cases": "x=1"}, TypeError, ["cases", "sequence of dicts", "str"]),
    ({"cases": {"x": 1}}, TypeError, ["cases", "sequence of dicts"]),
    ({"cases": [{"x": 1}, 5]}, TypeError, ["cases[1]", "dict", "int 5"]),
    ({"cases": [{1: 2}]}, TypeError, ["cases[0]", "not str", "[1]"]),
    ({"cases": [{"x": object()}]}, ValueError, ["JSON"]),
    ({"processes": 0}, ValueError, ["processes = 0", "positive"]),
    ({"processes": 1.5}, TypeError, ["processes", "1.5"]),
    ({"processes": True}, TypeError, ["processes", "True"]),
    ({"cache_dir": 3}, TypeError, ["cache_dir", "int 3"]),
    ({"on_error": "ignore"}, ValueError, ["on_error", "'ignore'", "'record'", "'raise'"]),
])
def test_bad_arguments_are_named(kwargs, exc, words):
    args = {"func": square, "cases": [{"x": 1.0}], "progress": False, **kwargs}
    with pytest.raises(exc) as e:
        run_sweep(args.pop("func"), args.pop("cases"), **args)
    assert all(w in str(e.value) for w in words), str(e.value)


def test_cache_dir_that_is_a_file_is_refused(tmp_path):
    f = tmp_path / "file"
    f.write_text("user")
    with pytest.raises(ValueError, match="cache_dir.*not a folder"):
        run_sweep(square, [{"x": 1.0}], cache_dir=f, progress=False)
    assert f.read_text() == "user"


def test_unpicklable_function_on_processes_is_refused():
    with pytest.raises(TypeError, match="picklable"):
        run_sweep(lambda x: {"v": x}, [{"x": 1}, {"x": 2}], processes=2, progress=False)
