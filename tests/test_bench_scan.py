"""Speed of the pruned every-instant scan (issue 11, item 4); slow, `pytest -m slow`.

Measured on the shared 2-core machine (one run, process time): 24.9x over the
20 experiments (50-90x on the step responses and the fast switch controllers, 6-17x on the slow
switch controllers, whose flat speed profile leaves thousands of instants whose a-priori bounds
reach the worst value; those are screened with the dense-output integrator, about 3x cheaper
than the fixed-step engine, and only a few dozen are simulated exactly).
"""

import importlib.util
import pathlib

import pytest

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def bench():
    path = pathlib.Path(__file__).resolve().parents[1] / "benchmarks" / "bench_scan.py"
    spec = importlib.util.spec_from_file_location("bench_scan", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.main(every=1, verbose=False)


def test_pruned_scan_finds_the_same_worst_cases_and_is_much_faster(bench):
    assert bench["all_identical"]           # same worst instants and values, all 20 experiments
    assert bench["instants"] > 250_000      # the full every-ms scan of the safety study
    assert bench["simulated"] < 0.2 * bench["instants"]
    assert bench["speedup_cpu"] >= 5.0


def test_pruned_scan_meets_the_10x_target(bench):
    assert bench["speedup_cpu"] >= 10.0
    assert bench["simulated"] < 0.01 * bench["instants"]      # exact simulations: a few per run
