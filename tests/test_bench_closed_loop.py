"""Speed targets of the closed loop (issue 3): run with ``pytest -m slow``.

A 10 s experiment (full plant, 1 kHz control, realistic sensors, joint PSMC)
in at most 0.1 s of wall time, a batch of 100 variants in at most 2 s, on
one core.  The measurement code is ``benchmarks/bench_closed_loop.py``.
"""

import importlib.util
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
def test_single_experiment_within_target(bench):
    t = bench.bench_single(repeats=5)
    assert t <= bench.TARGET_SINGLE, f"10 s experiment took {t:.3f} s"


@pytest.mark.slow
def test_batch_of_100_within_target(bench):
    t = bench.bench_batch(repeats=3)
    assert t <= bench.TARGET_BATCH, f"batch of 100 took {t:.3f} s"


@pytest.mark.slow
def test_benchmark_cases_are_what_they_claim(bench):
    cases = bench.batch_cases()
    assert len(cases) == bench.N_BATCH
    assert len({(c.controller.lam, c.controller.ki) for c in cases}) == bench.N_BATCH
    arm, c, ref, sens = bench.single_case()
    assert ref.duration == pytest.approx(bench.DURATION)
    assert sens.encoder and sens.velocity == "ipt"
