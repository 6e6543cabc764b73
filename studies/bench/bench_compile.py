"""Cold compilation of the report's kernels, measured on its own, side by side with an earlier
version.

In a fresh process with an empty kernel cache (``PPAMSAFETY_CACHE_DIR`` a new folder), the
report's warm-up tasks (:mod:`ppamsafety.report.warmup`) and then every section in quick
mode run one after the other, while a listener of numba's ``numba:compile`` events records
the CPU time of each compilation (exclusive of the compilations it triggers).  Printed: the
total compilation CPU time, the number of compiled signatures, the kernels that take the
longest, and every kernel compiled for more than one signature (numba compiles a kernel once
per argument type, and once per distinct *constant* int or bool argument at a call site).
The quick sections call the same kernels with the same types as the full report.

``--baseline REV`` measures the git revision REV and the working tree, one after the other
(:mod:`baseline`), and prints the totals side by side.

Run:  python studies/bench/bench_compile.py [--baseline REV] [--top N]
"""

import argparse
import json
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path


def measure() -> dict:
    """Compile events of the warm-up and the quick sections in this process (empty cache)."""
    from numba.core import event

    stack, excl = [], defaultdict(float)

    class Listener(event.Listener):
        def on_start(self, ev):
            stack.append([time.process_time(), 0.0])

        def on_end(self, ev):
            t0, child = stack.pop()
            dt = time.process_time() - t0
            d = ev.data["dispatcher"]
            key = f"{d.py_func.__module__}.{d.py_func.__qualname__}|{ev.data['args']}"
            excl[key] += dt - child
            if stack:
                stack[-1][1] += dt

    event.register("numba:compile", Listener())
    from ppamsafety.report import warmup
    from ppamsafety.sections import REGISTRY, run_section

    c0 = time.process_time()
    for i in range(len(warmup.TASKS)):
        warmup.run_task(i)
    with tempfile.TemporaryDirectory() as out:
        for name in REGISTRY:
            run_section(name, out, quick=True)
    return {"compile": excl, "cpu": time.process_time() - c0}


def summary(res: dict, top: int) -> None:
    ev = res["compile"]
    by = defaultdict(list)
    for k, v in ev.items():
        name, sig = k.split("|", 1)
        by[name].append((sig, v))
    print(f"compilation {sum(ev.values()):.1f} s of CPU (of {res['cpu']:.1f} s for the warm-up "
          f"and the quick sections), {len(ev)} signatures of {len(by)} kernels")
    print("\n| kernel | signatures | compilation CPU [s] |\n|---|---|---|")
    for name, sigs in sorted(by.items(), key=lambda kv: -sum(v for _, v in kv[1]))[:top]:
        print(f"| {name} | {len(sigs)} | {sum(v for _, v in sigs):.2f} |")
    multi = {n: s for n, s in by.items() if len(s) > 1}
    print(f"\nkernels compiled for more than one signature: {len(multi)}")
    for name, sigs in sorted(multi.items()):
        print(f"  {name}: " + "; ".join(f"{s[:110]} ({v:.2f} s)" for s, v in sigs))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--baseline", metavar="REV", help="compare with this git revision")
    p.add_argument("--top", type=int, default=20, help="kernels listed")
    p.add_argument("--measure", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.measure:
        res = measure()
        print(json.dumps({"compile": res["compile"], "cpu": res["cpu"]}))
        return
    from baseline import HERE, checkout, load, run    # the bench folder's helper

    trees = {"now": HERE} if not args.baseline else {"baseline": checkout(args.baseline),
                                                      "now": HERE}
    me = str(Path(__file__).resolve())
    res = {}
    for name, tree in trees.items():
        with tempfile.TemporaryDirectory() as cache:
            la = load()
            res[name] = run(tree, [me, "--measure"], env={"PPAMSAFETY_CACHE_DIR": cache})
        print(f"\n## {name} (load before {la}, after {load()})\n")
        summary(res[name], args.top)
    if args.baseline:
        b, n = (sum(res[k]["compile"].values()) for k in ("baseline", "now"))
        print(f"\ncompilation CPU: baseline {b:.1f} s, now {n:.1f} s (ratio {b / n:.2f}); "
              f"signatures {len(res['baseline']['compile'])} -> {len(res['now']['compile'])}")


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))     # the helper `baseline`
    main()
