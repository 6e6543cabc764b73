"""Speed of the as-built fit: the cost of evaluating plants, and the fit to convergence.

What is measured
----------------
evaluation
    :func:`ppamsafety.thesis_fits.as_built.evaluate_plants` of the sensitivity step (the
    nominal arm and each candidate at theta = 0.5) in one call, and of one plant alone (the
    plant the report's fit converges near: valve time constant theta -0.2, Coulomb friction
    theta 1, hysteresis theta 0.65), wall and CPU time after a warm-up that loads the
    kernels.  The values are checked to be the same bits in both versions.
batched vs one call per plant (``--per-plant``)
    The same plants one call each, as a loop over the plants would do.
the fit (``--fit``)
    :func:`~ppamsafety.thesis_fits.as_built.fit_as_built` of the report (every candidate,
    the full design) to convergence: its steps, Jacobians, criterion, chi2 and CPU time.

``--baseline REV`` measures the evaluation in the git revision REV and in the working tree,
alternately (``baseline.py``), and prints the ratios (REV / now; above 1: faster now).

Run:  python benchmarks/bench_as_built.py [--baseline REV] [--rounds N] [--quick]
      [--per-plant] [--fit]
"""

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path

import numpy as np

from ppamsafety.thesis_fits import as_built as ab
from ppamsafety.params import thesis_arm

#: The plant near the report's converged fit, for the one-plant evaluation.
NEAR_FIT = {"valve_time_constant_factor": -0.2, "friction_coulomb_factor": 1.0,
            "hysteresis_delta": 0.65}


def _digest(evs) -> str:
    h = hashlib.sha256()
    for e in evs:
        h.update(e.values.sort_index().to_numpy(float).tobytes())
    return h.hexdigest()[:16]


def measure(quick: bool) -> dict:
    """Wall and CPU time of the sensitivity batch and of one plant near the fit."""
    arm = thesis_arm()
    design = ab.Design.quick() if quick else ab.Design()
    pts = [{}] + [{n: ab.STEP} for n in ab.CANDIDATES]
    setups = [ab.as_built_setup(arm, q) for q in pts]
    ab.evaluate_plants(arm, setups[:2], ab.Design.quick())            # warm-up
    out = {}
    for label, s, q in (("sensitivities", setups, pts),
                        ("one plant", [ab.as_built_setup(arm, NEAR_FIT)], [NEAR_FIT])):
        t0, c0 = time.perf_counter(), time.process_time()
        evs = ab.evaluate_plants(arm, s, design, thetas=q)
        out[label] = {"wall": time.perf_counter() - t0, "cpu": time.process_time() - c0,
                      "plants": len(s), "digest": _digest(evs)}
    return out


def per_plant(quick: bool) -> None:
    arm = thesis_arm()
    design = ab.Design.quick() if quick else ab.Design()
    pts = [{}] + [{n: ab.STEP} for n in ab.CANDIDATES]
    setups = [ab.as_built_setup(arm, q) for q in pts]
    ab.evaluate_plants(arm, setups[:2], ab.Design.quick())            # warm-up
    t0 = time.perf_counter()
    batched = ab.evaluate_plants(arm, setups, design, thetas=pts)
    t1 = time.perf_counter()
    single = [ab.evaluate_plants(arm, [s], design, thetas=[q])[0] for s, q in zip(setups, pts)]
    t2 = time.perf_counter()
    same = all(np.allclose(a.values.to_numpy(), b.values.reindex(a.values.index).to_numpy(),
                           rtol=1e-12, equal_nan=True) for a, b in zip(batched, single))
    print(f"{len(setups)} plants, design {'quick' if quick else 'report'}: batched "
          f"{t1 - t0:.1f} s, one call per plant {t2 - t1:.1f} s, ratio "
          f"{(t2 - t1) / (t1 - t0):.2f}; identical values: {same}")


def fit() -> None:
    c0, t0 = time.process_time(), time.perf_counter()
    f = ab.fit_as_built(thesis_arm(), design=ab.Design())
    m = f.metrics
    h = f.path.history
    print(f"fit: {m['evaluations']} plants ({1 + len(f.candidates)} sensitivities, "
          f"{m['fit_steps']} steps ({int(h[h.kind == 'step'].accepted.sum())} accepted), "
          f"{m['fit_jacobians']} Jacobians); converged: {m['fit_converged']} "
          f"({m['fit_convergence']}); projected gradient x probe {m['fit_gradient_max']:.3g} "
          f"(tolerance {ab.GTOL:g}), Gauss-Newton step {m['fit_gauss_newton_step_max']:.3g} "
          f"(tolerance {ab.XTOL:g}); chi2 {m['chi2_nominal']:.1f} -> {m['chi2_as_built']:.1f}; "
          f"{time.perf_counter() - t0:.1f} s wall, {time.process_time() - c0:.1f} s CPU")
    print(f.effects[["candidate", "fitted", "theta", "value", "interval_low",
                     "interval_high"]].to_string(index=False))


def side_by_side(rev: str, rounds: int, quick: bool) -> None:
    from baseline import HERE, checkout, load, run    # the bench folder's helper

    trees = {"baseline": checkout(rev), "now": HERE}
    me = str(Path(__file__).resolve())
    res = {k: [] for k in trees}
    print(f"baseline {rev} ({trees['baseline'].name[:12]}) vs the working tree; "
          f"load before: {load()}")
    for r in range(rounds):
        for name, tree in trees.items():
            res[name].append(run(tree, [me, "--measure"] + (["--quick"] if quick else [])))
        print(f"round {r + 1}: load {load()}", flush=True)
    same = all(len({m[k]["digest"] for v in res.values() for m in v}) == 1
               for k in res["now"][0])
    print(f"\nbest of {rounds} rounds, design {'quick' if quick else 'report'}; same values "
          f"in both versions: {same}\n")
    print("| evaluation | plants | baseline wall [s] | now wall [s] | ratio | baseline CPU [s] "
          "| now CPU [s] | ratio |")
    print("|---|---|---|---|---|---|---|---|")
    for k in res["now"][0]:
        b = min(m[k]["wall"] for m in res["baseline"])
        n = min(m[k]["wall"] for m in res["now"])
        bc = min(m[k]["cpu"] for m in res["baseline"])
        nc = min(m[k]["cpu"] for m in res["now"])
        print(f"| {k} | {res['now'][0][k]['plants']} | {b:.2f} | {n:.2f} | {b / n:.2f} | "
              f"{bc:.2f} | {nc:.2f} | {bc / nc:.2f} |")
    print(f"\nload after: {load()}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="the quick design of the section")
    p.add_argument("--baseline", metavar="REV", help="compare with this git revision")
    p.add_argument("--rounds", type=int, default=2, help="alternating rounds (--baseline)")
    p.add_argument("--per-plant", action="store_true", help="batched vs one call per plant")
    p.add_argument("--fit", action="store_true", help="the report's fit to convergence")
    p.add_argument("--measure", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.measure:
        print(json.dumps(measure(args.quick)))
        return
    if args.baseline:
        side_by_side(args.baseline, args.rounds, args.quick)
    if args.per_plant:
        per_plant(args.quick)
    if args.fit:
        fit()
    if not (args.baseline or args.per_plant or args.fit):
        print(json.dumps(measure(args.quick), indent=1))


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))     # the helper `baseline`
    main()
