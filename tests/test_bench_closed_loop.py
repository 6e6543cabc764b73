"""Speed of the closed loop, as ratios measured in one run: run with ``pytest -m slow``.

A 10 s experiment (full plant, 1 kHz control, realistic sensors, joint PSMC) runs at least
100x faster than real time in CPU time, and a batch of 100 variants in one ``run_batch`` call
is never slower than the same runs one by one.  The measurement code is
``benchmarks/bench_closed_loop.py``, which also prints the absolute times.
"""

import importlib.util
import time
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_closed_loop.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_closed_loop", _PATH)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.slow
def test_single_experiment_runs_100x_faster_than_real_time(bench):
    t = bench.bench_single(repeats=5, clock=time.process_time)     # CPU time: load-proof
    assert bench.DURATION / t >= 100, f"10 s experiment took {t:.3f} s of CPU"


@pytest.mark.slow
def test_batch_is_never_slower_than_one_by_one(bench):
    m = [bench.measure_batch(repeats=2) for _ in range(2)]          # alternated, best of each
    batch = min(r["batch_wall"] for r in m)
    one_by_one = min(r["one_by_one_wall"] for r in m)
    assert batch <= 1.05 * one_by_one, f"batch {batch:.3f} s vs one by one {one_by_one:.3f} s"


@pytest.mark.slow
def test_benchmark_cases_are_what_they_claim(bench):
    cases = bench.batch_cases()
    assert len(cases) == bench.N_BATCH
    assert len({(c.controller.lam, c.controller.ki) for c in cases}) == bench.N_BATCH
    arm, c, ref, sens = bench.single_case()
    assert ref.duration == pytest.approx(bench.DURATION)
    assert sens.encoder and sens.velocity == "ipt"
