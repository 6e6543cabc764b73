"""The README's main job, side by side with an earlier version: install, report, quick report.

For the git revision ``--baseline REV`` and for the working tree, alternately (``baseline.py``):

* *install*: ``python -m pip install --no-deps --target <temporary folder> <tree>`` (the
  package's own build and install; the dependencies are already installed here, so a fresh
  machine adds their download to both versions alike);
* *cold report*: ``ppamsafety report --outdir <temporary folder>`` with an empty kernel cache
  (``PPAMSAFETY_CACHE_DIR`` a new folder): what a fresh clone pays, compilation included;
* *warm report*: the same again with that cache (the kernels cached); with ``--skip-cold``
  the user's own kernel cache (``~/.cache/ppamsafety``, one folder per kernel-source key, so
  that two versions with the same kernels share it), which a report run before has filled;
* *quick report*: ``ppamsafety report --quick`` with the warm cache.

Each report is the README's main job, ``report --overwrite`` over the version's own
``reports/`` folder (copied), so it orders its sections by the times of that previous report
as a user's run does.

Each is timed (wall) with the CPU time of the process tree (children's rusage); the warm and
cold reports also give every section's wall time (``metrics.json``) and CPU time (where the
version records it).  ``--sections`` instead measures the CPU time of every section of the
full report run alone, one after the other in one process per version (one BLAS thread,
the kernels cached by a first run), the same measurement for both versions.  The cold minus the warm report is the compilation.  Finally the CSVs of
the two versions' warm reports are compared: identical files, and for the others the largest
relative difference per numeric column (a timing column is expected to differ).

Absolute times mean something only on a quiet machine (the load averages are printed before
and after each run); the ratios are measured side by side.

Run:  python benchmarks/bench_report.py --baseline REV [--rounds N] [--skip-cold]
      [--skip-install]
      python benchmarks/bench_report.py --baseline REV --sections
"""

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from baseline import HERE, checkout, load  # noqa: E402  (the bench folder's helper)

#: Runs the command line of the package on PYTHONPATH (the version under test).
CLI = "from ppamsafety.cli import main; raise SystemExit(main())"


def _timed(cmd, env, cwd) -> tuple:
    """Run ``cmd``; (wall [s], CPU of the process tree [s], stdout)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({out.returncode}):\n{out.stderr[-3000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, out.stdout


def _report(tree: Path, outdir: Path, cache: Path | None, quick: bool = False) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    env.pop("PPAMSAFETY_CACHE_DIR", None)
    if cache is not None:
        env["PPAMSAFETY_CACHE_DIR"] = str(cache)
    env.pop("NUMBA_CACHE_DIR", None)
    if not outdir.exists() and (tree / "reports" / "metrics.json").exists():
        shutil.copytree(tree / "reports", outdir)     # the main job: over the previous report
    cmd = [sys.executable, "-c", CLI, "report", "--outdir", str(outdir), "--overwrite"]
    if quick:
        cmd.append("--quick")
    la = load()
    wall, cpu, _ = _timed(cmd, env, tree)
    m = json.loads((outdir / "metrics.json").read_text())
    sec = {k: {"wall": v.get("wall_time_s"), "cpu": v.get("cpu_time_s")} for k, v in m.items()
           if isinstance(v, dict)}
    return {"wall": wall, "cpu": cpu, "sections": sec, "load_before": la, "load_after": load()}


def _install(tree: Path, work: Path) -> dict:
    target = work / "site"
    shutil.rmtree(target, ignore_errors=True)
    la = load()
    wall, cpu, _ = _timed([sys.executable, "-m", "pip", "install", "--no-deps", "--quiet",
                           "--target", str(target), str(tree)], dict(os.environ), work)
    return {"wall": wall, "cpu": cpu, "load_before": la}


def compare_csvs(a: Path, b: Path) -> tuple:
    """(identical file names, {file: {column: largest relative difference}})."""
    same, diff = [], {}
    for f in sorted(a.glob("*.csv")):
        g = b / f.name
        if not g.exists():
            diff[f.name] = {"": "missing"}
            continue
        if f.read_bytes() == g.read_bytes():
            same.append(f.name)
            continue
        A, B = pd.read_csv(f), pd.read_csv(g)
        if A.shape != B.shape or list(A.columns) != list(B.columns):
            diff[f.name] = {"": f"shape {A.shape} vs {B.shape}"}
            continue
        cols = {}
        for c in A.columns:
            x, y = A[c], B[c]
            if pd.api.types.is_numeric_dtype(x) and pd.api.types.is_numeric_dtype(y):
                x, y = x.to_numpy(float), y.to_numpy(float)
                with np.errstate(all="ignore"):
                    r = np.abs(x - y) / np.maximum(np.abs(y), 1e-300)
                r = r[~(np.isnan(x) & np.isnan(y))]
                if r.size and np.nanmax(r) > 0:
                    cols[c] = float(np.nanmax(r))
            elif not (x.astype(str) == y.astype(str)).all():
                cols[c] = "text"
        diff[f.name] = cols
    return same, diff


def measure_sections() -> dict:
    """CPU time [s] of each section of the full report, run alone one after the other here."""
    from threadpoolctl import threadpool_limits

    from ppamsafety.sections import REGISTRY, run_section

    def cpu():
        me, kids = (resource.getrusage(resource.RUSAGE_SELF),
                    resource.getrusage(resource.RUSAGE_CHILDREN))
        return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime

    threadpool_limits(limits=1)
    out = {}
    with tempfile.TemporaryDirectory() as d:
        for name in REGISTRY:
            c0 = cpu()
            run_section(name, d)
            out[name] = cpu() - c0
    return out


def sections_side_by_side(trees: dict, work: Path) -> None:
    from baseline import run                              # the bench folder's helper

    me = str(Path(__file__).resolve())
    res = {}
    for name, tree in trees.items():
        cache = work / f"cache-sections-{name}"
        env = {"PPAMSAFETY_CACHE_DIR": str(cache)}
        run(tree, [me, "--measure-sections"], env=env)      # compiles the kernels
        la = load()
        res[name] = run(tree, [me, "--measure-sections"], env=env)
        print(f"{name}: {sum(res[name].values()):.1f} s of CPU (load before {la}, after "
              f"{load()})", flush=True)
    print("\n| section | baseline CPU [s] | now CPU [s] | ratio |\n|---|---|---|---|")
    for s in res["now"]:
        b, n = res["baseline"].get(s), res["now"][s]
        print(f"| {s} | {b:.1f} | {n:.1f} | {b / n:.2f} |" if b else f"| {s} | - | {n:.1f} | |")
    b, n = sum(res["baseline"].values()), sum(res["now"].values())
    print(f"| total | {b:.1f} | {n:.1f} | {b / n:.2f} |")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--baseline", metavar="REV",
                   help="the earlier version (a git revision)")
    p.add_argument("--rounds", type=int, default=1, help="alternating rounds")
    p.add_argument("--skip-cold", action="store_true",
                   help="no cold reports; the warm ones use the user's kernel cache")
    p.add_argument("--skip-install", action="store_true", help="no install step")
    p.add_argument("--keep", metavar="DIR", help="keep the reports in DIR/<version>")
    p.add_argument("--sections", action="store_true",
                   help="CPU time of each section run alone, per version")
    p.add_argument("--measure-sections", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.measure_sections:
        print(json.dumps(measure_sections()))
        return
    if not args.baseline:
        p.error("--baseline REV is required")
    trees = {"baseline": checkout(args.baseline), "now": HERE}
    work = Path(tempfile.mkdtemp(prefix="bench-report-"))
    if args.sections:
        try:
            sections_side_by_side(trees, work)
        finally:
            shutil.rmtree(work, ignore_errors=True)
        return
    res = {k: [] for k in trees}
    print(f"baseline {args.baseline} ({trees['baseline'].name[:12]}) vs the working tree; "
          f"work folder {work}; load {load()}", flush=True)
    try:
        for r in range(args.rounds):
            for name, tree in trees.items():
                cache = None if args.skip_cold else work / f"cache-{name}-{r}"
                out = {} if args.skip_install else {"install": _install(tree, work)}
                if not args.skip_cold:
                    out["cold"] = _report(tree, work / f"cold-{name}", cache)
                out["warm"] = _report(tree, work / f"warm-{name}", cache)
                out["quick"] = _report(tree, work / f"quick-{name}", cache, quick=True)
                res[name].append(out)
                print(f"round {r + 1} {name}: " + ", ".join(
                    f"{k} {v['wall']:.1f} s wall / {v['cpu']:.1f} s CPU (load {v['load_before']})"
                    for k, v in out.items()), flush=True)
        print("\n| step | baseline wall [s] | now wall [s] | ratio | baseline CPU [s] | "
              "now CPU [s] | ratio |")
        print("|---|---|---|---|---|---|---|")
        for k in res["now"][0]:
            b = min(x[k]["wall"] for x in res["baseline"])
            n = min(x[k]["wall"] for x in res["now"])
            bc = min(x[k]["cpu"] for x in res["baseline"])
            nc = min(x[k]["cpu"] for x in res["now"])
            print(f"| {k} | {b:.1f} | {n:.1f} | {b / n:.2f} | {bc:.1f} | {nc:.1f} | "
                  f"{bc / nc:.2f} |")
        if not args.skip_cold:
            print("\ncompilation (cold minus warm report, CPU [s]): baseline "
                  f"{res['baseline'][0]['cold']['cpu'] - res['baseline'][0]['warm']['cpu']:.1f}, "
                  f"now {res['now'][0]['cold']['cpu'] - res['now'][0]['warm']['cpu']:.1f}")
        print("\nSections of the warm report (first round): wall [s] (CPU [s] where recorded)\n")
        print("| section | baseline | now |")
        print("|---|---|---|")
        sb, sn = res["baseline"][0]["warm"]["sections"], res["now"][0]["warm"]["sections"]
        for s in sn:
            def fmt(d):
                if d is None:
                    return "-"
                return f"{d['wall']:.1f}" + (f" ({d['cpu']:.1f})" if d.get("cpu") else "")
            print(f"| {s} | {fmt(sb.get(s))} | {fmt(sn[s])} |")
        same, diff = compare_csvs(work / "warm-baseline", work / "warm-now")
        print(f"\nCSVs of the warm reports: {len(same)} identical, {len(diff)} differ")
        for f, cols in diff.items():
            print(f"  {f}: " + ", ".join(f"{c} {v:.1e}" if isinstance(v, float) else f"{c} {v}"
                                         for c, v in cols.items()))
        print(f"\nload after: {load()}")
        if args.keep:
            for name in trees:
                dest = Path(args.keep) / name
                shutil.rmtree(dest, ignore_errors=True)
                shutil.copytree(work / f"warm-{name}", dest)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
