"""Speed target of the pruned every-instant scan (issue 11, item 4); slow, `pytest -m slow`."""

import importlib.util
import pathlib

import pytest

pytestmark = pytest.mark.slow


def _bench():
    path = pathlib.Path(__file__).resolve().parents[1] / "studies" / "bench_scan.py"
    spec = importlib.util.spec_from_file_location("bench_scan", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.main(every=1, verbose=False)


def test_pruned_scan_is_10x_faster_and_finds_the_same_worst_cases():
    r = _bench()
    assert r["all_identical"]                 # same worst instants and values, all 20 experiments
    assert r["instants"] > 250_000            # the full every-ms scan of the safety study
    assert r["speedup_cpu"] >= 10.0
