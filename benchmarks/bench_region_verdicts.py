"""Benchmark: every body region at every contact point, judged from verdict rows or tables.

:func:`ppamsafety.impact.summary.region_point_verdicts` (the whole-person section, bare and
behind the implied covering: 12 regions x the arm's contact points x 20 runs x 4 instants)
judges the worst instant of each run against every criterion of its region and keeps the
governing row.  It used to build a verdict table (:func:`ppamsafety.impact.verdicts.evaluate`)
and slice the summary with pandas per run (1920 small tables); it now reads the rows
(:func:`~ppamsafety.impact.verdicts.verdict_rows`) and numpy slices.  This script runs both in
one process, alternately, on the same closed-loop runs and impacts: the table path is
reproduced here from the public functions (the impacts are simulated once per region and
contact point by both, as the section does).  It prints the process time of each, their ratio,
whether the two tables are the same to the byte (as CSV), and the load average.

Run (from the repository root):
    PYTHONPATH=. python benchmarks/bench_region_verdicts.py [--rounds N]
"""

import argparse
import io
import os
import time

import numpy as np
import pandas as pd
from threadpoolctl import threadpool_limits

from ppamsafety.experiments.catalog import run_thesis_experiment
from ppamsafety.impact.anywhere import simulate_contacts
from ppamsafety.impact.instants import heuristic_instants, impact_states
from ppamsafety.impact.summary import EXPERIMENTS, region_bodies, region_point_verdicts
from ppamsafety.impact.verdicts import criteria_for, evaluate
from ppamsafety.params import thesis_arm
from ppamsafety.params.contact import THESIS_COVERING, arm_contact_points


def table_path(arm, runs, covering=None) -> pd.DataFrame:
    """The same table, one verdict table and one pandas slice per run (the earlier path)."""
    states = []
    for exp in EXPERIMENTS:
        for res in runs[exp]:
            st = impact_states(res, arm)
            sub = st.iloc[list(heuristic_instants(st).values())]
            states.append((exp, res.meta["label"], sub))
    q = np.concatenate([s[["q1", "q2"]].to_numpy() for *_, s in states])
    qd = np.concatenate([s[["qd1", "qd2"]].to_numpy() for *_, s in states])
    K = np.concatenate([s[["K1", "K2"]].to_numpy() for *_, s in states])
    owner = np.repeat(np.arange(len(states)), [len(s) for *_, s in states])
    rows = []
    for reg, body in region_bodies():
        crit = criteria_for(reg)
        for p in arm_contact_points(arm):
            s = simulate_contacts(arm, q, qd, K, point=p, body=body, covering=covering).summary
            best, npass = None, 0
            for j, (exp, label, _) in enumerate(states):
                g = s[owner == j]
                i = g["F_max"].idxmax()
                v = evaluate({"F_max": g.loc[i, "F_max"], "HIC36": g["HIC36"].max()}, crit,
                             contact_point=p.name, region=reg.name)
                gov = v.loc[v["margin_pct"].idxmin()]
                npass += bool(v["passed"].all())
                if best is None or gov["margin_pct"] < best[2]["margin_pct"]:
                    best = (exp, label, gov, g.loc[i, "F_max"], g["HIC36"].max())
            exp, label, gov, fmax, hic = best
            rows.append({"body_region": reg.name, "contact_point": p.name,
                         "covering": (covering or p.covering).name, "experiment": exp,
                         "variant": label, "criterion": gov["criterion"], "value": gov["value"],
                         "limit": gov["limit"], "unit": gov["unit"], "margin": gov["margin"],
                         "margin [%]": gov["margin_pct"], "passed": bool(gov["passed"]),
                         "F_max [N]": fmax, "HIC36": hic, "passing": npass,
                         "impacts": len(states)})
    return pd.DataFrame(rows)


def _csv(df) -> str:
    buf = io.StringIO()
    df.to_csv(buf, index=False)
    return buf.getvalue()


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=1, help="alternating rounds")
    args = p.parse_args(argv)
    threadpool_limits(limits=1)
    arm = thesis_arm()
    runs = {e: run_thesis_experiment(arm, e) for e in EXPERIMENTS}
    region_point_verdicts(arm, runs=runs)                       # kernels loaded
    print(f"load average at start: {os.getloadavg()}")
    paths = {"tables (earlier)": lambda cov: table_path(arm, runs, cov),
             "rows (now)": lambda cov: region_point_verdicts(arm, covering=cov, runs=runs)}
    cpu = {k: [] for k in paths}
    out = {}
    for _ in range(args.rounds):
        for name, f in paths.items():
            t = time.process_time()
            out[name] = pd.concat([f(None), f(THESIS_COVERING)], ignore_index=True)
            cpu[name].append(time.process_time() - t)
    a, b = (min(v) for v in cpu.values())
    print(f"process time, bare and covered (best of {args.rounds}): tables {a:.2f} s, rows "
          f"{b:.2f} s: ratio {a / b:.2f}")
    same = _csv(out["tables (earlier)"]) == _csv(out["rows (now)"])
    print(f"the two tables are the same to the byte: {same}")
    print(f"load average at end: {os.getloadavg()}")
    return {"tables": a, "rows": b, "ratio": a / b, "same": same}


if __name__ == "__main__":
    main()
