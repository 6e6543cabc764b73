"""Benchmark: the every-instant scan over contact points and body regions against the tool-only scan.

For Table 6.1 experiments (step and switch, the thesis' controller variants), interleaved in
one run on one process: today's tool-only scan
(:func:`ppamsafety.impact.instants.worst_instant`: the tool point, the thesis' head, worst
F_max and HIC36) and the scan over the arm's four contact points (tool point, elbow, forearm,
upper arm, bare metal) x the body regions ISO/TS 15066 Annex A gives limits for today (the
skull/forehead as the head that passes the Hybrid III drop, the face as its Annex A two-body
model), ranked by the force over each region's transient limit
(:func:`ppamsafety.impact.anywhere.worst_contact`).  Prints the process time of each and
their ratio (target: at most 3x), and the load average.

Run (from the repository root):
    PYTHONPATH=. python benchmarks/bench_anywhere.py [--experiments K] [--repeats R]
"""

import argparse
import os
import time

import numpy as np

from ppamsafety.experiments.catalog import run_thesis_experiment, thesis_variants
from ppamsafety.impact.anywhere import worst_contact
from ppamsafety.impact.bodies import body_from_region
from ppamsafety.impact.instants import worst_instant
from ppamsafety.params import iso_ts_15066 as iso
from ppamsafety.params import thesis_arm
from ppamsafety.params.contact import FOREHEAD
from ppamsafety.sections.safety import MIN_SPEED, table_6_1_definition


def _cpu(f):
    t = time.process_time()
    out = f()
    return out, time.process_time() - t


def main(experiments=None, repeats=1, verbose=True):
    """Run the comparison; returns a dict with the totals and the ratio.

    Parameters
    ----------
    experiments : int, optional
        Only the first ``experiments`` of the 20 (default all).
    repeats : int
        Timings per experiment and method (best of); the two alternate.
    verbose : bool
        Print one line per experiment.
    """
    arm = thesis_arm()
    bodies = [FOREHEAD.replace(name=iso.SKULL_FOREHEAD.name),
              body_from_region(iso.FACE, radius=0.08)]
    limits = {iso.SKULL_FOREHEAD.name: iso.SKULL_FOREHEAD.force_transient,
              iso.FACE.name: iso.FACE.force_transient}
    runs = [(e, i) for e in table_6_1_definition()[0] for i in range(len(thesis_variants()))]
    runs = runs[:experiments] if experiments else runs
    r0 = run_thesis_experiment(arm, "step", [thesis_variants()[0]])[0]
    worst_instant(r0, arm, every=500, min_speed=MIN_SPEED)                 # compile both
    worst_contact(r0, arm, bodies=bodies, limits=limits, every=500, min_speed=MIN_SPEED)
    tot = {"tool": 0.0, "anywhere": 0.0}
    if verbose:
        print(f"load average at start: {os.getloadavg()[0]:.2f}")
        print(f"{'experiment':<34s} {'tool s':>7s} {'anyw s':>7s} {'ratio':>6s} "
              f"{'cands':>7s} {'screen':>6s} {'exact':>5s}  worst point / region")
    for exp, i in runs:
        res = run_thesis_experiment(arm, exp, [thesis_variants()[i]])[0]
        best = {"tool": np.inf, "anywhere": np.inf}
        for _ in range(repeats):
            _, t = _cpu(lambda: worst_instant(res, arm, min_speed=MIN_SPEED))
            best["tool"] = min(best["tool"], t)
            w, t = _cpu(lambda: worst_contact(res, arm, bodies=bodies, limits=limits,
                                               min_speed=MIN_SPEED))
            best["anywhere"] = min(best["anywhere"], t)
        for k in tot:
            tot[k] += best[k]
        if verbose:
            o = w.overall
            print(f"{exp + ': ' + str(thesis_variants()[i].label):<34.34s} {best['tool']:7.3f} "
                  f"{best['anywhere']:7.3f} {best['anywhere'] / best['tool']:6.2f} "
                  f"{w.n_candidates:7d} {w.n_screened:6d} {w.n_simulated:5d}  "
                  f"{o['point']} / {o['body']} ({o['value']:.0f} N, limit {o['limit']:.0f} N)")
    ratio = tot["anywhere"] / tot["tool"]
    if verbose:
        print(f"\ntotal process time: tool-only {tot['tool']:.2f} s, every contact point and "
              f"region {tot['anywhere']:.2f} s: ratio {ratio:.2f} (target <= 3)")
        print(f"load average at end: {os.getloadavg()[0]:.2f}")
    return {**tot, "ratio": ratio}


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--experiments", type=int, default=None)
    ap.add_argument("--repeats", type=int, default=1)
    a = ap.parse_args()
    main(experiments=a.experiments, repeats=a.repeats)
