"""Speed of the exact branch-and-bound HIC against the numba brute force.

Realistic impact records: 50 ms, one contact pulse of 1-15 ms embedded in
zeros, sampled at dt = 10 us (the impact integration rate) and 1 us; HIC36.
Both kernels are compiled (warm-up call) before timing; times are the best
of several repeats (time.perf_counter).  Also checks that both agree.

Run:  python benchmarks/bench_hic.py
"""

import time

import numpy as np

from ppamsafety.impact.hic import hic_bruteforce_kernel, hic_kernel

RECORD = 0.050  # record length [s]
WINDOW = 0.036  # HIC36 [s]
START = 0.012  # pulse onset [s]


def pulse(shape: str, dt: float) -> np.ndarray:
    """Acceleration magnitude [g] of the named pulse on a 50 ms record."""
    t = np.arange(round(RECORD / dt) + 1) * dt - START

    def half_sine(amp, dur, t0=0.0):
        x = (t - t0) / dur
        return np.where((x >= 0) & (x <= 1), amp * np.sin(np.pi * np.clip(x, 0, 1)), 0.0)

    if shape == "half-sine 1 ms":
        return half_sine(80.0, 0.001)
    if shape == "half-sine 5 ms":
        return half_sine(60.0, 0.005)
    if shape == "half-sine 15 ms":
        return half_sine(40.0, 0.015)
    if shape == "asymmetric 8 ms":  # quarter-sine rise in 1.5 ms, quarter-cosine fall in 6.5 ms
        rise = np.sin(0.5 * np.pi * np.clip(t / 0.0015, 0, 1))
        fall = np.cos(0.5 * np.pi * np.clip((t - 0.0015) / 0.0065, 0, 1))
        return np.where(t < 0, 0.0, 70.0 * np.where(t < 0.0015, rise, fall))
    if shape == "10 ms + 2nd bump":
        return half_sine(50.0, 0.010) + half_sine(8.0, 0.004, 0.013)
    raise ValueError(shape)


SHAPES = ["half-sine 1 ms", "half-sine 5 ms", "half-sine 15 ms", "asymmetric 8 ms",
          "10 ms + 2nd bump"]


def best_time(f, a, dt, wn, repeats):
    f(a, dt, wn)  # warm-up / compile
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = f(a, dt, wn)
        best = min(best, time.perf_counter() - t0)
    return best, res


def main():
    print("| pulse | dt [us] | N | W [samples] | HIC36 | brute force [ms] | fast [ms] | speed-up |")
    print("|---|---|---|---|---|---|---|---|")
    for dt in (1e-5, 1e-6):
        wn = int(round(WINDOW / dt))
        for shape in SHAPES:
            a = pulse(shape, dt)
            tb, rb = best_time(hic_bruteforce_kernel, a, dt, wn, 3 if dt > 5e-6 else 1)
            tf, rf = best_time(hic_kernel, a, dt, wn, 20)
            assert abs(rf[0] - rb[0]) <= 1e-12 * rb[0], (shape, rf, rb)
            print(f"| {shape} | {dt * 1e6:g} | {a.size} | {wn} | {rf[0]:.1f} | {tb * 1e3:.1f} "
                  f"| {tf * 1e3:.3f} | {tb / tf:.0f}x |")


if __name__ == "__main__":
    main()
