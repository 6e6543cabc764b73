"""The cost model of a sweep case beside the measured cost (a sweep estimates before it runs).

``ppamsafety sweep`` estimates the time and memory of a study before anything runs
(:func:`ppamsafety.study_files.estimate_cases`, constants
:data:`ppamsafety.study_files.COST`) and refuses long runs without ``--yes``.  This script
runs a few representative :func:`ppamsafety.sweep_cases.safety_case` cases (kernels
compiled first, one process) and prints, per case, the measured seconds beside the model's,
as a ratio (model / measured; > 1: the estimate is on the safe side).

Run:  python benchmarks/bench_case_cost.py [--repeat 2]
"""

from __future__ import annotations

import argparse
import time


CASES = [{"experiment": "step"},
         {"experiment": "step", "controller": "PSMC joint", "lam": 0.4},
         {"experiment": "switch"},
         {"experiment": "circle10", "controller": "PSMC task"},
         {"experiment": "step", "instants": "max TCP speed"},
         {"experiment": "step", "instants": "all", "every": 50},
         {"experiment": "step", "duration": 60.0},
         {"experiment": "step", "histories": True}]


def main(argv=None) -> int:
    """Measure each case (best of ``--repeat``) and print model / measured."""
    from ppamsafety.study_files import _case_cost
    from ppamsafety.sweep_cases import safety_case

    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--repeat", type=int, default=2)
    a = p.parse_args(argv)
    safety_case(**CASES[0])                                   # compile the kernels once
    print(f"{'case':70s} {'measured s':>10s} {'model s':>8s} {'ratio':>6s}")
    for c in CASES:
        best = min(_timed(lambda: safety_case(**c)) for _ in range(a.repeat))
        model = _case_cost(c)[0]
        print(f"{str(c):70s} {best:10.3f} {model:8.3f} {model / best:6.2f}")
    return 0


def _timed(f) -> float:
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


if __name__ == "__main__":
    raise SystemExit(main())
