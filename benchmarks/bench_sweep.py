"""Per-case overhead of the sweep engine: 1000 trivial cases, locally and on Dask.

The case function does no work (it returns ``{"y": x * x}``), so the wall time
divided by the number of cases is the engine's overhead per case.  Every
variant is compared with the straightforward approach, a plain
``concurrent.futures.ProcessPoolExecutor.map`` over the same function with the
same number of worker processes (ratio = variant / plain pool; > 1 is slower).

Variants:

* ``run_sweep`` local, no cache: case checks, keys (JSON + SHA-1), one future
  per case, progress bookkeeping, one DataFrame per case, final concat;
* ``run_sweep`` local with a cache folder: + one pickle file per case;
* ``run_sweep`` dask, LocalCluster started for the sweep (``scheduler=None``):
  + cluster start and stop;
* ``run_sweep`` dask on a running LocalCluster (a ``Client``): the steady
  per-case cost of the scheduler round trip; next to it, the plain
  ``Client.map`` + ``gather`` of the same function (dask's own cost).

A physics case (:func:`ppamsafety.sweep_cases.safety_case`, one 12 s
closed-loop experiment and four impacts) takes about 0.05-0.1 s of compiled
work on one core, so the engine's overhead matters only for trivial cases.

Physics cases with an arm of their own (``--physics N``): the per-case cost of
:func:`~ppamsafety.sweep_cases.safety_case` of the thesis arm against the same cases
with a plant effect and dotted-path arm parameters (``effects={"payload_mass": ...}``,
``"arm.links.m2"``, ``"arm.pneumatics.mean_pressure"``), whose values differ per case by
1e-12 relative so that every case builds, validates and packs a new arm (no cache hit), on the
same physics.  Both run in this process through ``run_sweep``, interleaved in rounds (A, B,
A, B ...) so that the load of a shared machine hits both alike; ratio = with / without.

Run:  python benchmarks/bench_sweep.py [--cases 1000] [--processes 2] [--physics 40]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor


def trivial(x):
    """The no-work case."""
    return {"y": x * x}


def _timed(f):
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


def main(argv=None) -> int:
    """Run the benchmark and print a table (seconds, ms per case, ratio to the plain pool)."""
    from ppamsafety.sweep import run_sweep

    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--cases", type=int, default=1000)
    p.add_argument("--processes", type=int, default=2)
    p.add_argument("--physics", type=int, default=40,
                   help="safety cases per variant and round of the arm comparison (0: skip)")
    a = p.parse_args(argv)
    n, procs = a.cases, a.processes
    cases = [{"x": i} for i in range(n)]
    rows = []

    def plain():
        with ProcessPoolExecutor(procs) as pool:
            out = list(pool.map(trivial, range(n)))
        assert len(out) == n

    base = _timed(plain)
    rows.append(("plain ProcessPoolExecutor.map", base))
    rows.append(("run_sweep local, no cache", _timed(
        lambda: run_sweep(trivial, cases, processes=procs, progress=False).table)))
    with tempfile.TemporaryDirectory() as d:
        rows.append(("run_sweep local, cache folder", _timed(
            lambda: run_sweep(trivial, cases, processes=procs, cache_dir=d, progress=False).table)))
        rows.append(("  (rerun: all cached)", _timed(
            lambda: run_sweep(trivial, cases, processes=procs, cache_dir=d, progress=False).table)))
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        print("dask.distributed not installed (pip install 'ppamsafety[cluster]'): dask skipped")
    else:
        rows.append(("run_sweep dask, LocalCluster started", _timed(
            lambda: run_sweep(trivial, cases, backend="dask", processes=procs, progress=False).table)))
        with LocalCluster(n_workers=procs, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            client.run(lambda: None)                      # workers up

            def plain_dask():
                futs = client.map(trivial, range(n), pure=False)
                assert len(client.gather(futs)) == n
            rows.append(("  (plain dask Client.map + gather)", _timed(plain_dask)))
            rows.append(("run_sweep dask, running LocalCluster", _timed(
                lambda: run_sweep(trivial, cases, backend="dask", scheduler=client,
                                  progress=False).table)))
    print(f"{n} trivial cases on {procs} worker processes")
    print(f"{'variant':40s} {'wall [s]':>9s} {'per case [ms]':>14s} {'vs plain pool':>14s}")
    for name, t in rows:
        print(f"{name:40s} {t:9.2f} {1e3 * t / n:14.3f} {t / base:13.1f}x")
    if a.physics:
        physics(a.physics)
    return 0


def physics(n: int, rounds: int = 4) -> tuple:
    """Per-case cost of safety cases on the thesis arm vs with effects and dotted parameters.

    Parameters
    ----------
    n : int
        Cases per variant and round.
    rounds : int
        Interleaved rounds.

    Returns
    -------
    tuple of float
        Seconds per case without and with, summed over the rounds.
    """
    from ppamsafety.params import thesis_arm
    from ppamsafety.sweep import run_sweep
    from ppamsafety.sweep_cases import safety_case

    arm = thesis_arm()
    m2, pm = arm.links.m2, arm.pneumatics.p_mean[0]
    lams = [0.4 + 0.01 * i for i in range(n)]
    plain = [{"controller": "PSMC joint", "lam": lam} for lam in lams]

    def dotted(r):
        return [{"controller": "PSMC joint", "lam": lam,
                 "effects": {"payload_mass": 1e-9 * (1 + r)},
                 "arm.links.m2": m2 * (1 + 1e-12 * (i + n * r)),
                 "arm.pneumatics.mean_pressure": pm * (1 + 1e-12 * (i + n * r))}
                for i, lam in enumerate(lams)]

    run_sweep(safety_case, plain[:1] + dotted(-1)[:1], progress=False).table     # compile, warm
    t_a = t_b = 0.0
    for r in range(rounds):
        t_a += _timed(lambda: run_sweep(safety_case, plain, progress=False).table)
        t_b += _timed(lambda: run_sweep(safety_case, dotted(r), progress=False).table)
    k = n * rounds
    print(f"\n{k} safety cases per variant (step, joint PSMC), in this process, "
          f"{rounds} interleaved rounds")
    print(f"{'variant':52s} {'per case [ms]':>14s}")
    print(f"{'today: the thesis arm':52s} {1e3 * t_a / k:14.2f}")
    print(f"{'effects + dotted arm parameters (a new arm per case)':52s} {1e3 * t_b / k:14.2f}")
    print(f"ratio with / without: {t_b / t_a:.3f}")
    return t_a / k, t_b / k


if __name__ == "__main__":
    raise SystemExit(main())
