"""Running a scenario battery: one result row per seed, here or in a pool of workers.

The arm's battery (:mod:`ppamsafety.diagnose.scenarios`) and the muscle bench's
(:mod:`ppamsafety.diagnose.bench.scenarios`) draw, synthesize and score their scenarios
differently but run them the same way, through :func:`run_seeds`.
"""

from __future__ import annotations

import multiprocessing

import pandas as pd

#: Scenarios a worker runs before it is replaced (bounds what a long battery can leak).
TASKS_PER_WORKER = 50


def progress_line(row: dict) -> str:
    """One line on a finished scenario: seed, kind, hidden, perturbation, claims, time, error.

    Parameters
    ----------
    row : dict
        A battery row (its missing keys print as None).
    """
    r = row
    return (f"seed {r.get('seed')}: {r.get('kind')} hidden={r.get('hidden')} "
            f"pert={r.get('perturbation') or '-'} named={r.get('named')} high={r.get('high')} "
            f"conf={r.get('confounded')} unexpl={r.get('unexplained')} "
            f"{r.get('seconds', 0):.1f}s {r.get('error') or ''}")


def run_seeds(work, seeds, *, processes: int, progress: bool = False) -> pd.DataFrame:
    """``work(seed)`` for every seed, in this process (``processes == 1``) or in a pool.

    Parameters
    ----------
    work : callable
        Picklable; ``work(seed)`` returns the scenario's row (a dict with ``seed``); a
        failure must be returned as a row, not raised.
    seeds : sequence of int
        Checked by the caller.
    processes : int, keyword-only
        Worker processes (forked; checked by the caller).
    progress : bool, keyword-only
        Print :func:`progress_line` of every finished scenario.

    Returns
    -------
    pandas.DataFrame
        One row per seed, sorted by seed.
    """
    rows = []

    def done(r):
        rows.append(r)
        if progress:
            print(progress_line(r), flush=True)

    if processes == 1:
        for s in seeds:
            done(work(s))
    else:
        with multiprocessing.get_context("fork").Pool(
                processes, maxtasksperchild=TASKS_PER_WORKER) as pool:
            for r in pool.imap_unordered(work, seeds):
                done(r)
    return pd.DataFrame(rows).sort_values("seed").reset_index(drop=True)


__all__ = ["run_seeds", "progress_line", "TASKS_PER_WORKER"]
