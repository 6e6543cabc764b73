"""Benchmark of the every-instant impact scan.

For each of the 20 Table 6.1 experiments (step and switch, 10 controller
variants each), interleaved in one run: the straightforward scan
(``evaluate_experiment(..., instants="all")``: every instant simulated) and the
pruned scan (:func:`ppamsafety.impact.instants.worst_instant`: rigorous
F_max/HIC bounds, then a dense-output screening with a margin, only instants
that can be the worst are simulated exactly).  Checks
that both give the same worst instant and the same F_max/HIC36 (exact float
equality) and prints the process (CPU) and wall times with their ratios.
Both run on one process here (the safety study spreads experiments over 2).

Run (from the repository root):  PYTHONPATH=. python benchmarks/bench_scan.py [--every N] [--experiments K]
"""

import argparse
import time

import numpy as np

from ppamsafety.experiments.catalog import run_thesis_experiment, thesis_variants
from ppamsafety.impact.instants import evaluate_experiment, worst_instant
from ppamsafety.params import thesis_arm
from ppamsafety.sections.safety import MIN_SPEED, table_6_1_definition


def _timed(f):
    w, p = time.perf_counter(), time.process_time()
    out = f()
    return out, time.perf_counter() - w, time.process_time() - p


def main(every=1, experiments=None, repeats=1, verbose=True):
    """Run the comparison; returns a dict of totals and ``all_identical``.

    Parameters
    ----------
    every : int
        Instant stride [ms] (1 = the safety study's full scan).
    experiments : int, optional
        Only the first ``experiments`` of the 20 (default all).
    repeats : int
        Timings per experiment and method (best of); old and new alternate.
    verbose : bool
        Print one line per experiment.
    """
    arm = thesis_arm()
    runs = [(e, i) for e in table_6_1_definition()[0] for i in range(len(thesis_variants()))]
    runs = runs[:experiments] if experiments else runs
    # compile both paths on a short scan first
    r0 = run_thesis_experiment(arm, "step", [thesis_variants()[0]])[0]
    evaluate_experiment(r0, arm, instants="all", every=500, min_speed=MIN_SPEED)
    worst_instant(r0, arm, every=500, min_speed=MIN_SPEED)
    tot = {"old_cpu": 0.0, "old_wall": 0.0, "new_cpu": 0.0, "new_wall": 0.0}
    n_all = n_sim = n_scr = 0
    identical = True
    if verbose:
        print(f"{'experiment':<34s} {'instants':>8s} {'screened':>8s} {'simulated':>9s} {'old cpu s':>9s} "
              f"{'new cpu s':>9s} {'ratio':>7s}  same worst")
    for exp, i in runs:
        label, ctrl = thesis_variants()[i]
        res = run_thesis_experiment(arm, exp, [(label, ctrl)])[0]
        best = {"old_cpu": np.inf, "old_wall": np.inf, "new_cpu": np.inf, "new_wall": np.inf}
        for _ in range(repeats):
            old, w, p = _timed(lambda: evaluate_experiment(res, arm, instants="all", every=every,
                                                           min_speed=MIN_SPEED).summary)
            best["old_cpu"], best["old_wall"] = min(best["old_cpu"], p), min(best["old_wall"], w)
            new, w, p = _timed(lambda: worst_instant(res, arm, every=every, min_speed=MIN_SPEED))
            best["new_cpu"], best["new_wall"] = min(best["new_cpu"], p), min(best["new_wall"], w)
        for k in tot:
            tot[k] += best[k]
        same = bool(old.F_max.max() == new.worst_F.F_max
                    and old.loc[old.F_max.idxmax(), "t0"] == new.worst_F.t0
                    and old.HIC36.max() == new.worst_HIC.HIC36
                    and old.loc[old.HIC36.idxmax(), "t0"] == new.worst_HIC.t0
                    and old.loc[old.HIC36.idxmax(), "HIC15"] == new.worst_HIC.HIC15)
        identical &= same
        n_all += len(old)
        n_sim += new.n_simulated
        n_scr += new.n_screened
        if verbose:
            print(f"{exp + ': ' + label:<34s} {len(old):8d} {new.n_screened:8d} {new.n_simulated:9d} "
                  f"{best['old_cpu']:9.2f} {best['new_cpu']:9.2f} "
                  f"{best['old_cpu'] / max(best['new_cpu'], 1e-9):6.1f}x  {same}")
    out = {**tot, "instants": n_all, "simulated": n_sim, "screened": n_scr,
           "all_identical": identical,
           "speedup_cpu": tot["old_cpu"] / tot["new_cpu"],
           "speedup_wall": tot["old_wall"] / tot["new_wall"]}
    if verbose:
        print(f"\n{'total (' + str(len(runs)) + ' experiments, every ' + str(every) + ' ms)':<34s} "
              f"{n_all:8d} {n_scr:8d} {n_sim:9d} {tot['old_cpu']:9.2f} {tot['new_cpu']:9.2f}")
        print(f"speed-up, process time: {out['speedup_cpu']:.1f}x   wall time: "
              f"{out['speedup_wall']:.1f}x   (target >= 10x)   same worst cases: {identical}")
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--every", type=int, default=1)
    ap.add_argument("--experiments", type=int, default=None)
    ap.add_argument("--repeats", type=int, default=1)
    a = ap.parse_args()
    main(every=a.every, experiments=a.experiments, repeats=a.repeats)
