"""Speed of the discrepancy diagnosis: a 60 s closed-loop record at 1 kHz.

Target: ``diagnose`` of a 60 s closed-loop record sampled at 1 kHz against the
whole candidate library in <= 60 s on 2 cores.

Record: :func:`ppamsafety.diagnose.synthesize` (closed loop, joint PSMC Ki = 2
lambda = 0.4 s on the 10 s circle, 60 s, Table 3.2 noise fed back) with a
hidden payload of 0.4 kg and a valve dead time of 20 ms.

What is compared
----------------
ours
    :func:`ppamsafety.diagnose.diagnose`: every candidate is fitted by
    linear regression on the block-integral residuals (no simulation inside
    the selection; the dead time is profiled on the regression), and the
    full simulation is one batched rollout (nominal and fitted model in one
    ``plant.model.simulate`` call).
straightforward (output error)
    The same forward selection done the obvious way: each candidate's
    parameters are fitted by nonlinear least squares on the replay error
    (whitened q, qd, p of the full simulation against the record),
    ``scipy.optimize.least_squares`` with a finite-difference Jacobian, so
    **one simulation of the record per candidate per residual/Jacobian
    evaluation**; the dead time is profiled with one simulation per grid
    step (1..60 ms).  Only the *first* selection step (every candidate
    against the nominal model) is run and timed -- a complete selection
    needs at least one more step for the second effect -- so the printed
    ratio is a **lower bound**.  Each least-squares fit is capped at
    ``MAX_NFEV`` evaluations (a cap that favours the straightforward
    approach).

Times are wall times (time.perf_counter) after a warm-up that compiles /
loads the kernels; the kernels run single-threaded.

Run:  python benchmarks/bench_diagnose.py [--duration SECONDS]
"""

import argparse
import time

import numpy as np
from scipy.optimize import least_squares

from ppamsafety.diagnose import diagnose, synthesize
from ppamsafety.diagnose.arm.candidates import library
from ppamsafety.diagnose.arm.residuals import (arm_record, channel_noise, model_vector, replay,
                                               row_from_mu)
from ppamsafety.params import thesis_arm
from ppamsafety.plant import packing

TARGET_S = 60.0          #: issue target for a 60 s record [s]
HIDDEN = {"payload_mass": 0.4, "valve_dead_time": 0.02}
MAX_NFEV = 8             #: cap of each output-error fit (residual evaluations)
DEAD_GRID_S = 0.06       #: dead-time grid of the straightforward profile [s]


def straightforward_step(rec, arm):
    """First forward-selection step by output error; returns (seconds, simulations, table)."""
    row0 = packing.pack(arm)
    mu0 = model_vector(row0)
    noise = channel_noise(rec)
    sig = np.concatenate([noise["q"], noise["qd"], noise["p"]])
    meas = np.concatenate([rec.q, rec.qd, rec.p], axis=1)
    count = [0]

    def err(row, shift=0):
        count[0] += 1
        X = replay(rec, row[None], shifts=[shift])[0]
        return ((X - meas) / sig).ravel()

    t0 = time.perf_counter()
    base = err(row0)
    table = [("nominal", float(base @ base), 1)]
    for c in library():
        n0 = count[0]
        if c.grid:
            best = min(float(np.sum(err(row0, s) ** 2))
                       for s in range(1, int(round(DEAD_GRID_S / rec.dt)) + 1))
        else:
            D = c.directions(mu0, arm)
            scale = np.maximum(np.abs(D.T @ np.abs(mu0)), 1e-6) * 0.05

            def res(z, D=D, scale=scale):
                try:
                    return err(row_from_mu(row0, mu0 + D @ (z * scale)))
                except ValueError:           # an infeasible row (1/T <= 0): a large residual
                    return np.full(base.size, 1e3)

            sol = least_squares(res, np.zeros(D.shape[1]), max_nfev=MAX_NFEV, method="trf")
            best = float(sol.fun @ sol.fun)
        table.append((c.name, best, count[0] - n0))
    return time.perf_counter() - t0, count[0], table


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--duration", type=float, default=60.0, help="record length [s] (60)")
    p.add_argument("--skip-straightforward", action="store_true")
    a = p.parse_args(argv)
    arm = thesis_arm()
    short = synthesize("closed-loop", HIDDEN, seed=1, duration=2.0)
    diagnose(short)                                       # warm-up: compile / load kernels
    rec_data = synthesize("closed-loop", HIDDEN, seed=1, duration=a.duration)
    t0 = time.perf_counter()
    dg = diagnose(rec_data)
    ours = time.perf_counter() - t0
    print(f"record: closed loop, {a.duration:g} s at 1 kHz ({len(rec_data)} samples), hidden "
          f"{HIDDEN}")
    print(f"ours: diagnose {ours:.1f} s (target <= {TARGET_S:g} s: "
          f"{'met' if ours <= TARGET_S else 'NOT met'}); stages "
          + ", ".join(f"{k} {v:.1f} s" for k, v in dg.timings.items()))
    print(f"      named {list(dg.names)}, unexplained {dg.unexplained}")
    if a.skip_straightforward:
        return 0
    rec, _ = arm_record(rec_data)
    tsf, nsim, table = straightforward_step(rec, arm)
    print(f"straightforward (output error, one simulation per candidate per evaluation), "
          f"first selection step only: {tsf:.1f} s, {nsim} simulations of the record "
          f"({tsf / nsim:.2f} s each)")
    for name, chi2, n in table:
        print(f"      {name:<20} replay chi2 {chi2:.4g} ({n} simulations)")
    print(f"ratio straightforward / ours >= {tsf / ours:.1f} (lower bound: one of >= 2 steps)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
