"""Benchmark of the open-loop plant.

Time to simulate 10 s of open-loop motion at a 1 kHz input rate (one RK4 step
per period, the default), for one state and for a batch of 100 parameter
variants.  Run:  python benchmarks/bench_plant.py
"""

import time

import numpy as np

from ppamsafety.params import thesis_arm
from ppamsafety.plant import model
from ppamsafety.units import BAR, DEG


def main(repeats=3):
    arm = thesis_arm()
    x0, u = model.rest_state(np.array([50, -80]) * DEG, arm)
    U = np.tile(u, (10000, 1))
    U[2000:, 0] += 0.3 * BAR
    variants = [arm.replace(valves=arm.valves.with_time_constants([t] * 4))
                for t in np.linspace(0.03, 0.09, 100)]
    model.simulate(arm, x0, U[:10])                          # compile
    model.simulate(variants[:2], np.tile(x0, (2, 1)), U[:10])
    best1 = best100 = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        model.simulate(arm, x0, U)
        best1 = min(best1, time.perf_counter() - t0)
        t0 = time.perf_counter()
        model.simulate(variants, np.tile(x0, (100, 1)), U)
        best100 = min(best100, time.perf_counter() - t0)
    print(f"10 s open loop, one state:        {best1:.4f} s ({10 / best1:.0f}x real time)")
    print(f"10 s open loop, batch of 100:     {best100:.3f} s ({1000 / best100:.0f}x real time)")
    return best1, best100


if __name__ == "__main__":
    main()
