"""Speed of the compiled closed loop (issue targets: 10 s experiment <= 0.1 s, 100 variants <= 2 s).

Setup: the full plant (rigid body, muscles, pneumatics, first-order valves),
1 kHz control with one RK4 step per period, realistic sensors (encoder
quantisation and the inter-pulse-timing velocity board), joint-space PSMC
on the 10 s step experiment (q1_d 30 -> 70 -> 30 deg).  The batch runs 100
different joint-PSMC variants (lambda 0.1-2 s x Ki 2 / 12 bar/(rad s)) in
one ``run_batch`` call.  Everything is compiled by a warm-up call first;
times are the best of several repeats (time.perf_counter), single thread.

``--breakdown`` also times the pieces of one control period (plant alone,
without gravity compensation, with ideal sensors) to show where the time
goes.

Run:  python benchmarks/bench_closed_loop.py [--breakdown]
"""

import sys
import time

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


def _best(f, repeats):
    f()                                     # warm-up: compile / load the cache
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
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


def bench_single(repeats=10) -> float:
    """Best wall time [s] of one 10 s closed-loop experiment."""
    arm, c, ref, sens = single_case()
    return _best(lambda: cl.run(arm, c, ref, sensors=sens), repeats)


def bench_batch(repeats=3) -> float:
    """Best wall time [s] of a batch of 100 variants (one run_batch call)."""
    cases = batch_cases()
    return _best(lambda: cl.run_batch(cases), repeats)


def breakdown(repeats=10) -> list:
    """(label, best wall time [s]) of the pieces of a 10 s closed-loop run."""
    arm, c, ref, sens = single_case()
    x0, u = model.rest_state(ref.field("q_d")[0], arm)
    U = np.tile(u, (ref.n_steps, 1))
    rows = [("plant alone (10 000 RK4 steps, open loop)",
             _best(lambda: model.simulate(arm, x0, U, substeps=1), repeats)),
            ("closed loop, ideal sensors",
             _best(lambda: cl.run(arm, c, ref, sensors=SensorConfig.ideal()), repeats)),
            ("closed loop, realistic sensors, no gravity compensation",
             _best(lambda: cl.run(arm, JointPSMC(gravity_compensation="off"), ref, sensors=sens),
                   repeats)),
            ("closed loop, realistic sensors (benchmark case)",
             _best(lambda: cl.run(arm, c, ref, sensors=sens), repeats))]
    return rows


def main():
    t1 = bench_single()
    tb = bench_batch()
    print("| case | simulated | wall time [s] | real-time factor | target [s] | met |")
    print("|---|---|---|---|---|---|")
    print(f"| one experiment | {DURATION:g} s | {t1:.4f} | {DURATION / t1:.0f}x | {TARGET_SINGLE:g} "
          f"| {'yes' if t1 <= TARGET_SINGLE else 'NO'} |")
    print(f"| batch of {N_BATCH} variants | {N_BATCH} x {DURATION:g} s | {tb:.3f} | "
          f"{N_BATCH * DURATION / tb:.0f}x | {TARGET_BATCH:g} | "
          f"{'yes' if tb <= TARGET_BATCH else 'NO'} |")
    if "--breakdown" in sys.argv:
        print()
        print("| piece | wall time [ms] per 10 s |")
        print("|---|---|")
        for label, t in breakdown():
            print(f"| {label} | {1e3 * t:.2f} |")


if __name__ == "__main__":
    main()
