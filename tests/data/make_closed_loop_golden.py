"""Record the closed-loop logs of the nominal plant as a bitwise reference.

Run once on a known-good commit (this file was first run on 4530509, before the
declared layouts and the effect-state extension): it writes
``closed_loop_golden.npz`` beside itself with, for every run of the Table 6.1
experiments (step and switch, ten thesis variants each) and of one circle
(P = 10 s, all ten variants, 15 s), the SHA-256 of the log bytes and every
100th log row.  ``tests/test_golden.py`` re-runs the same experiments and
requires bitwise equality (issue 7: with every effect off, results are
bitwise identical to those before the refactoring).

Run:  python tests/data/make_closed_loop_golden.py
"""

import hashlib
from pathlib import Path

import numpy as np

from ppamsafety.experiments.catalog import run_thesis_experiment
from ppamsafety.params import thesis_arm

CASES = (("step", None), ("switch", None), ("circle10", 15.0))
STRIDE = 100


def logs():
    """(experiment, label, log array) for every golden run, in a fixed order."""
    arm = thesis_arm()
    out = []
    for name, duration in CASES:
        for r in run_thesis_experiment(arm, name, duration=duration):
            out.append((name, r.meta["label"], np.ascontiguousarray(r.log)))
    return out


def main():
    keys, hashes, rows = [], [], []
    for name, label, log in logs():
        keys.append(f"{name}|{label}")
        hashes.append(hashlib.sha256(log.tobytes()).hexdigest())
        rows.append(log[::STRIDE])
    path = Path(__file__).with_name("closed_loop_golden.npz")
    lengths = np.array([r.shape[0] for r in rows])
    np.savez_compressed(path, keys=np.array(keys), hashes=np.array(hashes),
                        rows=np.concatenate(rows), lengths=lengths, stride=STRIDE)
    print(f"wrote {path} ({len(keys)} runs)")


if __name__ == "__main__":
    main()
