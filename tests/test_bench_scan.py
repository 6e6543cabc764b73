"""Speed of the pruned every-instant scan (issue 11, item 4); slow, `pytest -m slow`.

Measured on this machine (one run, process time): 8.3x over the 20 experiments
(20-50x on the step responses and the fast switch controllers, 2-6x on the slow
switch controllers, whose speed profile is flat so that the a-priori HIC bound,
up to 8x above the simulated HIC, prunes only half of the instants).  The issue's
target of 10x is therefore an expected failure until the bounds are tightened.
"""

import importlib.util
import pathlib

import pytest

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def bench():
    path = pathlib.Path(__file__).resolve().parents[1] / "studies" / "bench_scan.py"
    spec = importlib.util.spec_from_file_location("bench_scan", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.main(every=1, verbose=False)


def test_pruned_scan_finds_the_same_worst_cases_and_is_much_faster(bench):
    assert bench["all_identical"]           # same worst instants and values, all 20 experiments
    assert bench["instants"] > 250_000      # the full every-ms scan of the safety study
    assert bench["simulated"] < 0.2 * bench["instants"]
    assert bench["speedup_cpu"] >= 5.0


@pytest.mark.xfail(reason="issue 11 target not reached: 8.3x measured (HIC bound too loose on "
                          "the slow switch controllers)", strict=False)
def test_pruned_scan_meets_the_10x_target(bench):
    assert bench["speedup_cpu"] >= 10.0
