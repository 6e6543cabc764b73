"""Speed of the as-built fit (issue 20 part 2): one batched evaluation of many plants.

What is compared
----------------
ours
    :func:`ppamsafety.diagnose.arm.as_built.evaluate_plants` with every plant of the
    sensitivity step (the nominal arm and each candidate at theta = 0.5) in one call: one
    compiled closed-loop batch per experiment (three circles, step, switch, sawtooth) over
    all plants and variants.
straightforward
    The same plants one call each (one batch per experiment and plant), as a loop over
    the plants would do.

Both compute the same numbers (checked: identical values).  Times are wall times after a
warm-up that loads the kernels; the kernels run single-threaded.

Run:  python benchmarks/bench_as_built.py [--quick]
"""

import argparse
import time

import numpy as np

from ppamsafety.diagnose.arm import as_built as ab
from ppamsafety.params import thesis_arm


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="the quick design of the section")
    args = p.parse_args(argv)
    arm = thesis_arm()
    design = ab.Design.quick() if args.quick else ab.Design()
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
    print(f"{len(setups)} plants, design {'quick' if args.quick else 'report'}: batched "
          f"{t1 - t0:.1f} s, one call per plant {t2 - t1:.1f} s, ratio "
          f"{(t2 - t1) / (t1 - t0):.2f}; identical values: {same}")


if __name__ == "__main__":
    main()
