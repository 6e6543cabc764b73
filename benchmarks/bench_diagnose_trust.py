"""Speed of the trusted diagnosis: a 60 s arm record, full library, every gate.

Target: ``diagnose`` of a 60 s closed-loop record at 1 kHz against the full library (the
sensor faults included) with every gate before "high" (the subset search, the stability
selection of 25 complementary pairs, the HAC intervals, the region-constancy test, the
detection limits) in <= 10 s on 2 cores.

What is compared, on the same record (the closed loop of ``bench_diagnose.py``: joint PSMC
Ki = 2 lambda = 0.4 s on the 10 s circle, 60 s, payload 0.4 kg and a 20 ms dead time hidden):

ours
    :func:`ppamsafety.diagnose.diagnose` (defaults): every model is a small solve on
    per-chunk Gram matrices (``arm/gram.py``), a forward-selection step or a whole subset
    search is one compiled call (``ppamsafety/lstsq.py``), one BLAS thread.
straightforward
    The same selection done the obvious way: every candidate model fitted by least
    squares on the full block design (``selection.fit_model``, the dead time profiled
    over every shift) and cross-validated the same way (``selection.cv_chi2``); the
    stability selection repeats that forward selection on each of the 50 halves.  Only one
    forward selection on the full record and two halves are run and timed; the printed
    total extrapolates the halves to 50, so the ratio is an estimate of the straightforward
    cost of the same gates.

Times are wall times (time.perf_counter) after a warm-up that compiles / loads the kernels.

``--against DIR`` compares two versions of the toolkit instead, side by side in one run:
the record is written once, and each version (``DIR``, a checkout of another revision, and
this one) diagnoses it in child processes, alternately, ``--repeats`` times each; the
medians and their ratio are printed.

Run:  python benchmarks/bench_diagnose_trust.py [--duration SECONDS] [--against DIR]
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from ppamsafety.diagnose import diagnose, synthesize
from ppamsafety.diagnose.arm.candidates import default_candidates
from ppamsafety.diagnose.arm.residuals import (arm_record, block_system, channel_noise,
                                               model_vector, noise_draws)
from ppamsafety.diagnose.arm.selection import (ALPHA, cv_chi2, fit_model, in_bounds,
                                               make_problem, rank_step)
from ppamsafety.diagnose.core.criteria import _chi2_sf
from ppamsafety.params import thesis_arm
from ppamsafety.plant import packing

TARGET_S = 10.0          #: target for a 60 s record [s]
HIDDEN = {"payload_mass": 0.4, "valve_dead_time": 0.02}
PAIRS = 25               #: complementary pairs of the stability selection


def straightforward_selection(prob, names, mask=None):
    """Forward selection with full-design fits; returns the chosen names."""
    selected = []
    current = fit_model(prob, selected, mask=mask)
    cur_cv = cv_chi2(prob, selected) if mask is None else None
    while len(selected) < 5:
        rest = [n for n in names if n not in selected]
        rows, fits = [], {}
        for n in rest:
            f = fit_model(prob, selected + [n], mask=mask)
            fits[n] = f
            cv = cv_chi2(prob, selected + [n])
            d = current.chi2 - f.chi2
            df = max(f.k - current.k, 1)
            rows.append({"name": n, "bic": f.bic, "delta_bic": f.bic - current.bic,
                         "p_value": _chi2_sf(max(d, 0.0), df),
                         "cv_gain": (cur_cv if cur_cv is not None else 0.0) - cv,
                         "in_bounds": in_bounds(prob, f, n)})
        chosen, _ = rank_step(rows, current.bic, alpha=ALPHA, n_candidates=len(rest))
        if chosen is None:
            break
        selected.append(chosen)
        current = fits[chosen]
        cur_cv = cv_chi2(prob, selected)
    return selected


#: The child of ``--against``: diagnose the record (after a warm-up), print the wall time.
CHILD = """
import sys, time
from ppamsafety.data import load_measured
from ppamsafety.diagnose import diagnose, synthesize
diagnose(synthesize(experiment="closed-loop", effects={hidden!r}, seed=3, duration=2.0))
data = load_measured(sys.argv[1])
t0 = time.perf_counter()
dg = diagnose(data)
print(time.perf_counter() - t0, "+".join(dg.names))
"""


def against(other, duration, repeats):
    """Time the diagnosis of one record with the toolkit in ``other`` and with this one."""
    here = Path(__file__).resolve().parents[1]
    trees = {"other": Path(other).resolve(), "this": here}
    times = {k: [] for k in trees}
    with tempfile.TemporaryDirectory() as tmp:
        rec = Path(tmp) / "record.csv"
        synthesize(experiment="closed-loop", effects=HIDDEN, seed=3, duration=duration).save(rec)
        for _ in range(repeats):
            for name, tree in trees.items():
                env = {**os.environ, "PYTHONPATH": str(tree)}
                out = subprocess.run([sys.executable, "-c", CHILD.format(hidden=HIDDEN),
                                      str(rec)], env=env, capture_output=True, text=True,
                                     check=True).stdout.split()
                times[name].append(float(out[0]))
                print(f"{name} ({tree}): {float(out[0]):.2f} s, named {out[1:]}", flush=True)
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"median over {repeats}: this {med['this']:.2f} s, other {med['other']:.2f} s; "
          f"ratio this / other {med['this'] / med['other']:.3f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=60.0)
    ap.add_argument("--against", default=None, metavar="DIR",
                    help="a checkout of another revision: time both, side by side")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    if args.against is not None:
        against(args.against, args.duration, args.repeats)
        return
    arm = thesis_arm()
    data = synthesize(experiment="closed-loop", effects=HIDDEN, seed=3, duration=args.duration)
    diagnose(synthesize(experiment="closed-loop", effects=HIDDEN, seed=3, duration=2.0))  # warm
    t0 = time.perf_counter()
    dg = diagnose(data)
    ours = time.perf_counter() - t0
    print(f"ours: {ours:.2f} s; named {dg.names}, "
          f"levels {[e.confidence_level for e in dg.effects]}; stages "
          f"{ {k: round(v, 2) for k, v in dg.timings.items()} }")
    with threadpool_limits(limits=1, user_api="blas"):
        rec, _ = arm_record(data)
        noise = channel_noise(rec)
        bs = block_system(rec, arm, velocity_noise=noise["qd"])
        mu0 = model_vector(packing.pack(arm))
        prob = make_problem(bs, mu0, noise_draws(rec, arm, noise, velocity_noise=True), arm)
        names = list(default_candidates())
        t0 = time.perf_counter()
        full = straightforward_selection(prob, names)
        t_full = time.perf_counter() - t0
        rng = np.random.default_rng(0)
        t0 = time.perf_counter()
        for _ in range(1):                       # one pair = two halves, timed
            half = rng.random(prob.nchunk) < 0.5
            for h in (half, ~half):
                straightforward_selection(prob, names, mask=h[prob.chunk])
        t_pair = time.perf_counter() - t0
    straight = t_full + PAIRS * t_pair
    print(f"straightforward: forward selection {t_full:.1f} s (chose {full}), one pair of "
          f"halves {t_pair:.1f} s, x {PAIRS} pairs -> about {straight:.0f} s")
    print(f"ratio straightforward / ours: about {straight / ours:.0f}x; ours vs target "
          f"{TARGET_S:g} s: {'met' if ours <= TARGET_S else 'NOT met'}")


if __name__ == "__main__":
    main()
