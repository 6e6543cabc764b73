"""Benchmark of the impact engine.

Prints the wall time of one impact with its HIC, of a batch of 5000 impacts
(the fixed-step reference engine and the
dense-output engine with the single-pulse HIC path),
of the same impacts with one scipy.integrate.solve_ivp call each (measured on
a sample and extrapolated), and of the exact HIC against brute force on a
50 ms record.  Run:  python benchmarks/bench_impact.py
"""

import time

import numpy as np

from ppamsafety.impact.hic import (_hic_branch_and_bound, _unimodal_peak, hic, hic_bruteforce,
                                  hic_kernel)
from ppamsafety.impact.model import simulate_impacts
from ppamsafety.impact.reference import simulate_impact_scipy
from ppamsafety.params import thesis_arm
from ppamsafety.units import DEG


def best_of(f, repeats=3):
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t0)
    return best, out


def cases(n, seed=0):
    """n impact cases spread over the working area, tool speeds 0.1-3 m/s."""
    rng = np.random.default_rng(seed)
    q = np.stack([rng.uniform(30, 95, n), rng.uniform(-120, -40, n)], 1) * DEG
    qd = rng.normal(scale=2.0, size=(n, 2))
    K = np.stack([rng.uniform(30, 60, n), rng.uniform(15, 35, n)], 1)
    return q, qd, K


def main(n_batch=5000, n_scipy=40):
    arm = thesis_arm()
    q, qd, K = cases(n_batch)
    simulate_impacts(arm, q[:2], qd[:2], K[:2])                    # compile
    t_one, _ = best_of(lambda: simulate_impacts(arm, q[0], qd[0], K[0]), 10)
    simulate_impacts(arm, q[:2], qd[:2], K[:2], integrator="dense")  # compile
    t_batch, t_dense = np.inf, np.inf
    c_batch, c_dense = np.inf, np.inf
    for _ in range(3):                         # interleaved: old (fixed) and new (dense)
        p0 = time.process_time()
        t, res = best_of(lambda: simulate_impacts(arm, q, qd, K), 1)
        t_batch, c_batch = min(t_batch, t), min(c_batch, time.process_time() - p0)
        p0 = time.process_time()
        t, res_d = best_of(lambda: simulate_impacts(arm, q, qd, K, integrator="dense"), 1)
        t_dense, c_dense = min(t_dense, t), min(c_dense, time.process_time() - p0)
    hit = res.summary.F_max > 1.0
    dev = max(float(np.max(np.abs(res_d.summary[c][hit] / res.summary[c][hit] - 1)))
              for c in ("F_max", "HIC36", "HIC15"))
    simulate_impact_scipy(arm, q[0], qd[0], K[0])                  # compile the rhs
    t0 = time.perf_counter()
    for i in range(n_scipy):
        simulate_impact_scipy(arm, q[i], qd[i], K[i])
    t_scipy = (time.perf_counter() - t0) / n_scipy * n_batch
    s = res.summary
    a = np.zeros(2501)
    h = s.loc[s.HIC36.idxmax()]
    r = simulate_impacts(arm, q[s.HIC36.idxmax()], qd[s.HIC36.idxmax()], K[s.HIC36.idxmax()],
                         dt=2e-5, history=True)
    a = r.histories[0]["a_head_g"].to_numpy()
    hic(a, 2e-5), hic_bruteforce(a, 2e-5)
    t_hic, _ = best_of(lambda: hic(a, 2e-5), 20)
    t_bf, _ = best_of(lambda: hic_bruteforce(a, 2e-5), 3)
    wn = int(0.036 / 2e-5 + 1e-9)
    _hic_branch_and_bound(a, 2e-5, wn)
    t_bb, _ = best_of(lambda: _hic_branch_and_bound(a, 2e-5, wn), 20)
    hic_kernel(a, 2e-5, wn)
    t_k, _ = best_of(lambda: hic_kernel(a, 2e-5, wn), 20)
    pulse = "single pulse" if _unimodal_peak(a) >= 0 else "not a single pulse"
    rows = [("one impact + HIC36/HIC15", t_one, "<= 0.010 s"),
            (f"{n_batch} impacts (batched kernel)", t_batch, "<= 10 s"),
            (f"{n_batch} impacts, one solve_ivp each (extrapolated from {n_scipy})", t_scipy, ""),
            ("speed-up batched vs solve_ivp", t_scipy / t_batch, ">= 20x"),
            (f"{n_batch} impacts, dense-output integrator (wall)", t_dense, ""),
            (f"{n_batch} impacts, fixed step, process time", c_batch, ""),
            (f"{n_batch} impacts, dense-output, process time", c_dense, ""),
            ("speed-up dense vs fixed step (process time)", c_batch / c_dense, ">= 5x"),
            ("speed-up dense vs solve_ivp", t_scipy / t_dense, ""),
            ("max rel. deviation dense vs fixed (F_max, HIC36, HIC15)", dev, "<= 2e-4"),
            (f"exact HIC, 50 ms at 20 us (worst case, HIC {h.HIC36:.2f})", t_hic, ""),
            ("brute-force HIC, same record", t_bf, ""),
            ("speed-up exact vs brute force", t_bf / t_hic, ">= 100x"),
            (f"exact HIC kernel, same record ({pulse}), no validation", t_k, ""),
            ("exact HIC kernel by branch and bound only, same record", t_bb, ""),
            ("speed-up hic_kernel vs branch and bound", t_bb / t_k, "")]
    print(f"{'quantity':<70s} {'value':>12s}  target")
    for name, v, target in rows:
        unit = "x" if "speed-up" in name else ("" if "deviation" in name else "s")
        print(f"{name:<70s} {v:12.4g}{unit}  {target}")
    return dict((name, v) for name, v, _ in rows)


if __name__ == "__main__":
    main()
