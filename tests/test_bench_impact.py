"""Speed of the impact engine, as ratios measured in one run; slow, run with `pytest -m slow`.

The absolute times are printed by ``benchmarks/bench_impact.py``."""

import importlib.util
import pathlib

import pytest

pytestmark = pytest.mark.slow


def _bench():
    path = pathlib.Path(__file__).resolve().parents[1] / "benchmarks" / "bench_impact.py"
    spec = importlib.util.spec_from_file_location("bench_impact", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.main(n_batch=5000, n_scipy=20)


def test_impact_speed_targets():
    r = _bench()
    assert r["speed-up batched vs solve_ivp"] >= 20.0
    assert r["speed-up exact vs brute force"] >= 100.0
    assert r["max rel. deviation dense vs fixed (F_max, HIC36, HIC15)"] <= 2e-4
    # 5000 impacts >= 5x faster than the fixed-step reference engine (5.7x on a quiet 2-core
    # machine)
    assert r["speed-up dense vs fixed step (process time)"] >= 5.0
