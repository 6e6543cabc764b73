"""Speed of the compiled closed loop: one 10 s experiment, a batch of 100 variants.

Setup: the full plant (rigid body, muscles, pneumatics, first-order valves),
1 kHz control with one RK4 step per period, realistic sensors (encoder
quantisation and the inter-pulse-timing velocity board), joint-space PSMC
on the 10 s step experiment (q1_d 30 -> 70 -> 30 deg).  The batch runs 100
different joint-PSMC variants (lambda 0.1-2 s x Ki 2 / 12 bar/(rad s)) in
one ``run_batch`` call.  Everything is compiled by a warm-up call first.

Measured (``--measure single``, in a process pinned to one core): the best wall and CPU
time of one experiment over several repeats, and the same for the pieces of a control
period (plant alone, without gravity compensation, with ideal sensors) to show where the
time goes.  ``--measure batch`` (every core): the best wall time of the batch of 100 in
one ``run_batch`` call, and of the same 100 runs one by one.  Each also prints a hash of
the logs, so that two versions can be checked to compute the same bits.

``--baseline REV`` runs both measurements for the git revision REV and for the working
tree, alternately, ``--rounds`` times (:mod:`baseline`), and prints the ratios (REV /
working tree; above 1 means faster now) with the load average.

Run:  python studies/bench/bench_closed_loop.py [--baseline REV] [--rounds N]
"""

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path

import numpy as np

from ppamsafety.control import JointPSMC, SensorConfig
from ppamsafety.experiments import closed_loop as cl
from ppamsafety.experiments.case import ExperimentCase
from ppamsafety.experiments import trajectories as tr
from ppamsafety.params import thesis_arm
from ppamsafety.plant import model
from ppamsafety.units import BAR

DURATION = 10.0         #: simulated time per experiment [s]
N_BATCH = 100
TARGET_SINGLE = 0.1     #: [s]
TARGET_BATCH = 2.0      #: [s]


def _best(f, repeats, clock=time.perf_counter):
    f()                                     # warm-up: compile / load the cache
    best = np.inf
    for _ in range(repeats):
        t0 = clock()
        f()
        best = min(best, clock() - t0)
    return best


def single_case(arm=None):
    """The one-experiment benchmark case: (arm, controller, reference, sensors)."""
    arm = thesis_arm() if arm is None else arm
    return arm, JointPSMC(), tr.step(arm, duration=DURATION), SensorConfig()


def batch_cases(arm=None, n=N_BATCH):
    """``n`` joint-PSMC variants (lambda x Ki) on the same step reference."""
    arm = thesis_arm() if arm is None else arm
    ref = tr.step(arm, duration=DURATION)
    lams = np.linspace(0.1, 2.0, (n + 1) // 2)
    ctrls = [JointPSMC(lam=float(lam), ki=ki * BAR) for ki in (2.0, 12.0) for lam in lams][:n]
    return [ExperimentCase(arm, c, ref, sensors=SensorConfig()) for c in ctrls]


def bench_single(repeats=10, clock=time.perf_counter) -> float:
    """Best time [s] of one 10 s closed-loop experiment (wall time by default)."""
    arm, c, ref, sens = single_case()
    return _best(lambda: cl.run(arm, c, ref, sensors=sens), repeats, clock)


def bench_batch(repeats=3) -> float:
    """Best wall time [s] of a batch of 100 variants (one run_batch call)."""
    cases = batch_cases()
    return _best(lambda: cl.run_batch(cases), repeats)


def breakdown(repeats=10, clock=time.perf_counter) -> list:
    """(label, best time [s]) of the pieces of a 10 s closed-loop run."""
    arm, c, ref, sens = single_case()
    x0, u = model.rest_state(ref.field("q_d")[0], arm)
    U = np.tile(u, (ref.n_steps, 1))
    rows = [("plant alone (10 000 RK4 steps, open loop)",
             _best(lambda: model.simulate(arm, x0, U, substeps=1), repeats, clock)),
            ("closed loop, ideal sensors",
             _best(lambda: cl.run(arm, c, ref, sensors=SensorConfig.ideal()), repeats, clock)),
            ("closed loop, realistic sensors, no gravity compensation",
             _best(lambda: cl.run(arm, JointPSMC(gravity_compensation="off"), ref, sensors=sens),
                   repeats, clock)),
            ("closed loop, realistic sensors (benchmark case)",
             _best(lambda: cl.run(arm, c, ref, sensors=sens), repeats, clock))]
    return rows


def _digest(logs) -> str:
    h = hashlib.sha256()
    for log in logs:
        h.update(np.ascontiguousarray(log).tobytes())
    return h.hexdigest()[:16]


def measure_single(repeats: int) -> dict:
    """One experiment and the pieces (wall and CPU time, best of ``repeats``)."""
    arm, c, ref, sens = single_case()
    run = lambda: cl.run(arm, c, ref, sensors=sens)          # noqa: E731
    out = {"single_wall": _best(run, repeats), "single_cpu": _best(run, repeats,
                                                                   time.process_time),
           "breakdown_cpu": dict(breakdown(repeats, time.process_time)),
           "digest": _digest([run().log])}
    return out


def measure_batch(repeats: int) -> dict:
    """The batch of 100 in one call and the same runs one by one (wall time)."""
    cases = batch_cases()
    batch = _best(lambda: cl.run_batch(cases), repeats)
    one_by_one = _best(lambda: [cl.run_batch([c]) for c in cases], 1)
    return {"batch_wall": batch, "one_by_one_wall": one_by_one,
            "digest": _digest(r.log for r in cl.run_batch(cases))}


def side_by_side(rev: str, rounds: int, repeats: int) -> None:
    """Measure ``rev`` and the working tree alternately; print the ratios."""
    from baseline import HERE, checkout, load, run    # the bench folder's helper

    trees = {"baseline": checkout(rev), "now": HERE}
    me = str(Path(__file__).resolve())
    res = {k: [] for k in trees}
    print(f"baseline {rev} ({trees['baseline'].name[:12]}) vs the working tree; "
          f"load before: {load()}")
    for r in range(rounds):
        for name, tree in trees.items():
            single = run(tree, [me, "--measure", "single", "--repeats", str(repeats)],
                         cpus={0})
            batch = run(tree, [me, "--measure", "batch", "--repeats", "3"])
            res[name].append({**single, **batch, "digest": (single["digest"],
                                                              batch["digest"])})
        print(f"round {r + 1}: load {load()}", flush=True)
    best = {k: {f: min(m[f] for m in v) for f in ("single_wall", "single_cpu", "batch_wall",
                                                  "one_by_one_wall")}
            for k, v in res.items()}
    same = len({m["digest"] for v in res.values() for m in v}) == 1
    b, n = best["baseline"], best["now"]
    print(f"\nbest of {rounds} rounds; same bits in every log: {same}")
    print("| measurement | baseline | now | ratio |")
    print("|---|---|---|---|")
    for f, label in (("single_wall", "one 10 s experiment, wall, one core [ms]"),
                     ("single_cpu", "one 10 s experiment, CPU [ms]"),
                     ("batch_wall", f"batch of {N_BATCH} in one run_batch, wall [s]"),
                     ("one_by_one_wall", f"the same {N_BATCH} runs one by one, wall [s]")):
        k = 1e3 if "[ms]" in label else 1.0
        print(f"| {label} | {k * b[f]:.4g} | {k * n[f]:.4g} | {b[f] / n[f]:.2f} |")
    print(f"| now: batch vs one by one (>= 1: the batch is not slower) | | | "
          f"{n['one_by_one_wall'] / n['batch_wall']:.2f} |")
    print("\nWhere the time goes (CPU [ms] per 10 s experiment, best of the rounds):\n")
    print("| piece | baseline | now | ratio |")
    print("|---|---|---|---|")
    for label in res["now"][0]["breakdown_cpu"]:
        bb = min(m["breakdown_cpu"][label] for m in res["baseline"])
        nn = min(m["breakdown_cpu"][label] for m in res["now"])
        print(f"| {label} | {1e3 * bb:.2f} | {1e3 * nn:.2f} | {bb / nn:.2f} |")
    print(f"\nload after: {load()}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--baseline", metavar="REV", help="compare with this git revision")
    p.add_argument("--rounds", type=int, default=3, help="alternating rounds (--baseline)")
    p.add_argument("--repeats", type=int, default=20, help="repeats of one experiment")
    p.add_argument("--measure", choices=("single", "batch"), help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.measure:
        f = measure_single if args.measure == "single" else measure_batch
        print(json.dumps(f(args.repeats)))
        return
    if args.baseline:
        side_by_side(args.baseline, args.rounds, args.repeats)
        return
    t1 = bench_single()
    tb = bench_batch()
    print("| case | simulated | wall time [s] | real-time factor | target [s] | met |")
    print("|---|---|---|---|---|---|")
    print(f"| one experiment | {DURATION:g} s | {t1:.4f} | {DURATION / t1:.0f}x | {TARGET_SINGLE:g} "
          f"| {'yes' if t1 <= TARGET_SINGLE else 'NO'} |")
    print(f"| batch of {N_BATCH} variants | {N_BATCH} x {DURATION:g} s | {tb:.3f} | "
          f"{N_BATCH * DURATION / tb:.0f}x | {TARGET_BATCH:g} | "
          f"{'yes' if tb <= TARGET_BATCH else 'NO'} |")
    print()
    print("| piece | wall time [ms] per 10 s |")
    print("|---|---|")
    for label, t in breakdown():
        print(f"| {label} | {1e3 * t:.2f} |")


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))     # the helper `baseline`
    main()
