"""Sweep runner: results, resume from cache, several processes, errors."""

import pandas as pd
import pytest

from ppamsafety.sweep import case_key, run_sweep

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
