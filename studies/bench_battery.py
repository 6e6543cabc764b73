"""The randomized battery of muscle test-bench records (issue 19): scores on a seed range.

``python studies/bench_battery.py FIRST STOP [--progress]`` runs
:func:`ppamsafety.diagnose.bench.scenarios.run_battery` on seeds FIRST..STOP-1
in this process and prints the arm battery's scores
(:func:`ppamsafety.diagnose.scenarios.scores`), the calibration table, what
became of every single hidden effect
(:func:`~ppamsafety.diagnose.bench.scenarios.single_effect_outcomes`) and the
seconds per scenario.  Tuning seeds 0-199; measurement seeds 1000-1299 (never
used to set a gate).
"""

import argparse

import pandas as pd

from ppamsafety.diagnose.bench.scenarios import run_battery, single_effect_outcomes
from ppamsafety.diagnose.scenarios import calibration_table, scores


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python studies/bench_battery.py")
    ap.add_argument("first", type=int)
    ap.add_argument("stop", type=int)
    ap.add_argument("--progress", action="store_true")
    a = ap.parse_args(argv)
    if not 0 <= a.first < a.stop:
        ap.error(f"first, stop = {a.first}, {a.stop}: need 0 <= first < stop")
    res = run_battery(range(a.first, a.stop), progress=a.progress)
    with pd.option_context("display.width", 200, "display.max_colwidth", 90):
        print(f"seeds {a.first}-{a.stop - 1}: {len(res)} scenarios, "
              f"{int((res['error'].fillna('') != '').sum())} errors")
        print(scores(res).to_string())
        print(calibration_table(res).to_string())
        print(single_effect_outcomes(res).to_string())
    sec = res["seconds"].astype(float)
    print(f"seconds per scenario: mean {sec.mean():.2f}, median {sec.median():.2f}, "
          f"max {sec.max():.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
