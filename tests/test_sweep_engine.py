"""The sweep engine: grids, resume after SIGKILL, the dask back end (issue 11.1)."""

import os
import pickle
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

import sweep_helpers as h
from ppamsafety.sweep import grid_cases, run_sweep

TESTS = Path(__file__).parent
ROOT = TESTS.parent


def test_grid_cases_are_every_combination_first_key_slowest():
    cases = grid_cases({"lam": [0.4, 0.8], "ki_bar": [2, 12, 6]}, base={"x": 1, "lam": 9})
    assert len(cases) == 6
    assert cases[0] == {"x": 1, "lam": 0.4, "ki_bar": 2}
    assert cases[3] == {"x": 1, "lam": 0.8, "ki_bar": 2}


@pytest.mark.parametrize("grid, exc, words", [
    ({"lam": []}, ValueError, ["grid['lam']", "empty"]),
    ({"lam": 0.4}, TypeError, ["grid['lam']", "list", "0.4"]),
    ({"lam": "0.4"}, TypeError, ["grid['lam']", "list"]),
    ([("lam", [1])], TypeError, ["grid", "dict"]),
])
def test_bad_grids_are_named(grid, exc, words):
    with pytest.raises(exc) as e:
        grid_cases(grid)
    assert all(w in str(e.value) for w in words), str(e.value)


def test_run_sweep_combines_cases_with_a_grid(tmp_path):
    calls = tmp_path / "calls"
    calls.mkdir()
    df = run_sweep(h.counted, [{"calls_dir": str(calls)}], grid={"x": [0, 1, 2]}, progress=False)
    assert list(df.x) == [0, 1, 2] and list(df.y) == [1, 2, 3]
    assert h.calls_of(calls) == {0: 1, 1: 1, 2: 1}


def _pids(calls):
    """x -> pid of the process that computed it (one marker file per computation)."""
    return {int(f.split("-")[0][1:]): int(f.split("-")[1][3:]) for f in os.listdir(calls)}


def test_first_case_runs_in_this_process_the_rest_in_workers(tmp_path, monkeypatch):
    """With more cases than workers the first case runs here (its compiled kernels are then
    inherited by the forked workers instead of compiled by each), the others in workers;
    a failing case is still recorded and the sweep goes on."""
    import ppamsafety.sweep as sweep_mod

    monkeypatch.setattr(sweep_mod, "available_cores", lambda: 2)   # really use 2 workers
    calls = tmp_path / "calls"
    calls.mkdir()
    df = run_sweep(h.counted, [{"calls_dir": str(calls)}], grid={"x": [0, 1, 2, 3, 4, 5]},
                   processes=2, on_error="record", progress=False)
    pids = _pids(calls)
    assert pids[0] == os.getpid()
    assert all(pids[x] != os.getpid() for x in range(1, 6))
    assert h.calls_of(calls) == {x: 1 for x in range(6)}
    assert list(df.status) == ["ok", "ok", "ok", "failed", "ok", "ok"]


def test_no_more_cases_than_workers_all_run_in_workers(tmp_path, monkeypatch):
    """Two cases on two workers: running one here first would only serialise them."""
    import ppamsafety.sweep as sweep_mod

    monkeypatch.setattr(sweep_mod, "available_cores", lambda: 2)
    calls = tmp_path / "calls"
    calls.mkdir()
    run_sweep(h.counted, [{"calls_dir": str(calls)}], grid={"x": [0, 1]}, processes=2,
              progress=False)
    assert all(pid != os.getpid() for pid in _pids(calls).values())


def test_first_case_failing_with_raise_starts_no_workers(tmp_path, monkeypatch):
    """on_error="raise": the first case fails in this process, no other case is computed."""
    import ppamsafety.sweep as sweep_mod
    from ppamsafety.sweep import SweepError

    monkeypatch.setattr(sweep_mod, "available_cores", lambda: 2)
    calls = tmp_path / "calls"
    calls.mkdir()
    with pytest.raises(SweepError, match=r"case 0 .*'x': 3.* failed: ValueError"):
        run_sweep(h.counted, [{"calls_dir": str(calls)}], grid={"x": [3, 0, 1, 2]},
                  processes=2, on_error="raise", progress=False)
    assert h.calls_of(calls) == {3: 1}


@pytest.mark.parametrize("kwargs, exc, words", [
    ({"backend": "slurm"}, ValueError, ["backend = 'slurm'", "'local'", "'dask'"]),
    ({"scheduler": "tcp://127.0.0.1:1"}, ValueError, ["scheduler", "backend='dask'"]),
    ({"cases": None}, TypeError, ["cases", "grid"]),
])
def test_bad_backend_arguments_are_named(kwargs, exc, words):
    args = {"cases": [{"x": 1, "calls_dir": "."}], "progress": False, **kwargs}
    with pytest.raises(exc) as e:
        run_sweep(h.counted, args.pop("cases"), **args)
    assert all(w in str(e.value) for w in words), str(e.value)


def _cached_xs(cache: Path) -> dict:
    out = {}
    for f in cache.glob("*.pkl"):
        with open(f, "rb") as fh:
            row = pickle.load(fh)                           # a dict result is cached as a row
            out[int(row["x"])] = (f.name, f.stat().st_mtime_ns)
    return out


def test_sigkill_mid_sweep_then_resume_loses_and_repeats_nothing(tmp_path):
    """A sweep killed with SIGKILL resumes: no finished case lost or recomputed."""
    cache, calls = tmp_path / "cache", tmp_path / "calls"
    calls.mkdir()
    n = 12
    cases = [{"x": i, "calls_dir": str(calls)} for i in range(n)]
    script = (f"import sys; sys.path.insert(0, {str(TESTS)!r}); import sweep_helpers as h; "
              f"from ppamsafety.sweep import run_sweep; "
              f"run_sweep(h.slow_square, {cases!r}, cache_dir={str(cache)!r}, processes=2, "
              f"progress=False)")
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    proc = subprocess.Popen([sys.executable, "-c", script], cwd=ROOT, env=env,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while len(list(cache.glob("*.pkl"))) < 3:          # some cases finished
            assert proc.poll() is None, "the sweep ended before it could be killed"
            assert time.monotonic() < deadline, "no case finished within 120 s"
            time.sleep(0.02)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)                 # the sweep and its workers
        proc.wait()
    finished = _cached_xs(cache)
    assert 3 <= len(finished) < n, f"{len(finished)} of {n} finished: not killed mid-run"
    before = h.calls_of(calls)
    assert all(before[x] == 1 for x in finished)

    df = run_sweep(h.slow_square, cases, cache_dir=cache, processes=2, progress=False)

    after = h.calls_of(calls)
    for x in finished:                                      # not recomputed, file untouched
        assert after[x] == 1
        assert _cached_xs(cache)[x] == finished[x]
    assert set(after) == set(range(n))                       # nothing lost
    assert all(after[x] == before.get(x, 0) + 1 for x in range(n) if x not in finished)
    assert len(list(cache.glob("*.pkl"))) == n
    assert not list(cache.glob("*.tmp"))                     # no half-written result is kept
    expected = pd.DataFrame({"x": range(n), "calls_dir": str(calls), "status": "ok",
                             "error": "", "y": [x * x for x in range(n)]})
    pd.testing.assert_frame_equal(df, expected)


# ---- dask ------------------------------------------------------------------------------

dask_distributed = pytest.importorskip("dask.distributed", reason="needs ppamsafety[cluster]")


def test_dask_local_cluster_records_failures_caches_and_resumes(tmp_path):
    """backend='dask' with no scheduler: a LocalCluster of 2 worker processes for the sweep."""
    cache, calls = tmp_path / "cache", tmp_path / "calls"
    calls.mkdir()
    cases = [{"x": i, "calls_dir": str(calls)} for i in range(6)]
    with pytest.warns(RuntimeWarning, match=r"1 of 6 cases failed.*x = 3 is refused"):
        df = run_sweep(h.counted, cases, cache_dir=cache, backend="dask", processes=2,
                       progress=False)
    assert list(df.status) == ["ok"] * 3 + ["failed"] + ["ok"] * 2
    assert df.error[3] == "ValueError: x = 3 is refused"
    assert list(df.y[df.status == "ok"]) == [1, 2, 3, 5, 6]
    assert len(list(cache.glob("*.pkl"))) == 5               # stored as futures completed
    pids = {f.split("pid")[1].split("-")[0] for f in os.listdir(calls)}
    assert str(os.getpid()) not in pids                      # ran on the workers
    with pytest.warns(RuntimeWarning, match="1 of 6 cases failed"):
        local = run_sweep(h.counted, cases, cache_dir=tmp_path / "local", progress=False)
    pd.testing.assert_frame_equal(df, local)                 # same table as the local back end
    n_before = sum(h.calls_of(calls).values())
    again = run_sweep(h.counted, cases[:3], cache_dir=cache, backend="dask", processes=1,
                      progress=False)
    assert sum(h.calls_of(calls).values()) == n_before       # all cached: nothing submitted
    pd.testing.assert_frame_equal(again, df.iloc[:3], check_dtype=False)   # no NaN: int y


@pytest.mark.slow
def test_dask_with_a_client_and_an_address(tmp_path):
    """A running LocalCluster(2 workers, processes): by Client and by scheduler address."""
    from dask.distributed import Client, LocalCluster

    from ppamsafety.sweep import SweepError

    calls = tmp_path / "calls"
    calls.mkdir()
    cases = [{"x": i, "calls_dir": str(calls)} for i in (0, 1, 2, 4)]
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        a = run_sweep(h.counted, cases, backend="dask", scheduler=client, progress=False)
        assert client.status == "running"                    # a given Client is left open
        b = run_sweep(h.counted, cases, backend="dask", scheduler=cluster.scheduler_address,
                      cache_dir=tmp_path / "c", progress=False)
        pd.testing.assert_frame_equal(a, b)
        with pytest.raises(SweepError, match=r"case 1 \{'x': 3"):
            run_sweep(h.counted, [cases[0], {"x": 3, "calls_dir": str(calls)}], backend="dask",
                      scheduler=client, progress=False, on_error="raise")


def test_dask_scheduler_of_a_wrong_type_is_named():
    with pytest.raises(TypeError, match=r"scheduler must be None, a scheduler address.*int 5"):
        run_sweep(h.counted, [{"x": 1, "calls_dir": "."}], backend="dask", scheduler=5,
                  progress=False)
