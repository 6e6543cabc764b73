"""Benchmark: the safety summary's scan against the tool-only scan, side by side.

For the 20 Table 6.1 experiments, interleaved in one process: today's tool-only scan
(:func:`ppamsafety.impact.instants.worst_instant`: the tool point, the thesis' head) and the
scan of the safety summary (:func:`ppamsafety.impact.anywhere.worst_contact` over the arm's four
contact points x the 12 ISO/TS 15066 Annex A body regions of
:func:`ppamsafety.impact.summary.region_bodies`, ranked by the force over each region's smallest
force limit), every instant.  Prints the process time of each, their ratio (the target of the
scan over contact points and regions: at most 3x) and the load average.

Run (from the repository root):
    PYTHONPATH=. python benchmarks/bench_summary.py
"""

import os
import time

from ppamsafety.experiments.catalog import run_thesis_experiment
from ppamsafety.impact.anywhere import worst_contact
from ppamsafety.impact.instants import worst_instant
from ppamsafety.impact.summary import EXPERIMENTS, MIN_SPEED, ranking_limit, region_bodies
from ppamsafety.params import thesis_arm


def _cpu(f):
    t = time.process_time()
    out = f()
    return out, time.process_time() - t


def main(verbose=True):
    """Run the comparison; returns a dict with the totals [s] and the ratio."""
    arm = thesis_arm()
    pairs = region_bodies()
    bodies = [b for _, b in pairs]
    limits = {b.name: ranking_limit(r).limit for r, b in pairs}
    runs = {e: run_thesis_experiment(arm, e) for e in EXPERIMENTS}
    r0 = runs["step"][0]
    worst_instant(r0, arm, every=500, min_speed=MIN_SPEED)                # compile both
    worst_contact(r0, arm, bodies=bodies, limits=limits, every=500, min_speed=MIN_SPEED)
    if verbose:
        print(f"load average at start: {os.getloadavg()[0]:.2f}")
    tot = {"tool": 0.0, "summary": 0.0}
    for exp in EXPERIMENTS:
        for res in runs[exp]:
            _, a = _cpu(lambda: worst_instant(res, arm, min_speed=MIN_SPEED))
            _, b = _cpu(lambda: worst_contact(res, arm, bodies=bodies, limits=limits,
                                               min_speed=MIN_SPEED))
            tot["tool"] += a
            tot["summary"] += b
            if verbose:
                print(f"{exp:7s} {res.meta['label']:28s} tool {a:6.2f} s   4 points x "
                      f"{len(bodies)} regions {b:6.2f} s   ratio {b / a:5.2f}")
    ratio = tot["summary"] / tot["tool"]
    if verbose:
        print(f"\ntotal process time: tool-only {tot['tool']:.2f} s, the summary's scan "
              f"{tot['summary']:.2f} s: ratio {ratio:.2f} (target <= 3)")
        print(f"load average at end: {os.getloadavg()[0]:.2f}")
    return {**tot, "ratio": ratio}


if __name__ == "__main__":
    main()
