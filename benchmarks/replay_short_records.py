"""False "unexplained" on clean records against the record's length (a measurement).

Synthesizes records with nothing hidden (the arm's own declared noise) of several lengths on
the thesis arm and on other arms, diagnoses each against the arm it came from, and counts the
records called unexplained: by a replay channel with the calibrated limit
(``arm.pipeline.REPLAY_RHO``, recomputed from the stored statistic), with the limit the
diagnosis used (widened below ``arm.replay_limit.REPLAY_CALIBRATED_SECONDS``), and by a block
channel.  One JSON line per record goes to ``--out``; the summary is printed.

    nice python benchmarks/replay_short_records.py --seeds 60000 60020 \\
        --lengths 0.5,1,2,5 --arm my_arm.toml --out rows.jsonl
    nice python benchmarks/replay_short_records.py --experiment closed-loop \\
        --seeds 61000 61010 --lengths 0.5,2 --arm my_arm.toml --out rows_cl.jsonl

Seeds used for ``docs/diagnose.md``: 60000-60019 (open loop), 61000-61009 (closed loop),
never used to set anything; 50000-50019 were looked at with the calibrated limit only,
before the widening was written.
"""

from __future__ import annotations

import argparse
import collections
import json
import warnings

from ppamsafety.design import load_arm
from ppamsafety.diagnose import diagnose, synthesize
from ppamsafety.diagnose.arm.pipeline import REPLAY_RHO
from ppamsafety.params import thesis_arm


def measure(arms: dict, experiment: str, seeds, lengths, out) -> list:
    rows = []
    for name, arm in arms.items():
        for d in lengths:
            for s in seeds:
                try:
                    r = diagnose(synthesize(experiment, seed=s, duration=d, arm=arm), arm=arm)
                    rp = r.settings["replay"]
                    row = dict(arm=name, experiment=experiment, duration=d, seed=s,
                               channels=list(r.unexplained_channels), rho=rp["rho"],
                               limits=rp["limits"], named=list(r.names))
                except ValueError as exc:          # e.g. an excitation with no static start
                    row = dict(arm=name, experiment=experiment, duration=d, seed=s,
                               error=str(exc)[:200])
                rows.append(row)
                out.write(json.dumps(row) + "\n")
                out.flush()
    return rows


def summary(rows) -> list:
    g = collections.defaultdict(list)
    for r in rows:
        if "error" not in r:
            g[(r["arm"], r["experiment"], r["duration"])].append(r)
    lines = []
    for k, v in sorted(g.items()):
        old = sum(any(x > REPLAY_RHO for x in r["rho"].values()) for r in v)
        new = sum(any(r["rho"][c] > r["limits"][c] for c in r["rho"]) for r in v)
        blk = sum(any(not c.startswith("replay") for c in r["channels"]) for r in v)
        lines.append(f"{k[0]:>10} {k[1]:>11} {k[2]:5g} s: {len(v):3d} records; replay flagged "
                     f"with the calibrated limit {REPLAY_RHO:g}: {old}, with the limit used: "
                     f"{new}; a block channel: {blk}")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--experiment", default="open-loop", choices=("open-loop", "closed-loop"))
    ap.add_argument("--seeds", nargs=2, type=int, default=(60000, 60020))
    ap.add_argument("--lengths", default="0.5,1,2,5")
    ap.add_argument("--arm", action="append", default=[], help="arm file (repeatable)")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    warnings.simplefilter("ignore")
    arms = {"thesis": thesis_arm(), **{p: load_arm(p) for p in a.arm}}
    with open(a.out, "a") as out:
        rows = measure(arms, a.experiment, range(*a.seeds),
                       [float(x) for x in a.lengths.split(",")], out)
    print("\n".join(summary(rows)))


if __name__ == "__main__":
    main()
