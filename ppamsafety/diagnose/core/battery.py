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


def coverage_entry(effect: str, parameter: str, true: float, d: dict, level: str) -> dict:
    """One right name's parameter scored against its true value (the ``coverage`` rows).

    Parameters
    ----------
    effect, parameter : str
    true : float
        The value the scenario hid (the nominal one for a parameter it did not change).
    d : dict
        The parameter's entry in the diagnosis (``ci_low``/``ci_high`` the reported
        interval, ``ci_low_noise``/``ci_high_noise`` the fit's own).
    level : str
        The name's confidence level.

    Returns
    -------
    dict
        ``covered`` for the reported interval, ``covered_noise`` for the fit's own.
    """
    lo_n, hi_n = d["ci_low_noise"], d["ci_high_noise"]
    return {"effect": effect, "parameter": parameter, "true": float(true),
            "value": d["value"], "ci_low": d["ci_low"], "ci_high": d["ci_high"],
            "covered": bool(d["ci_low"] <= true <= d["ci_high"]),
            "ci_low_noise": lo_n, "ci_high_noise": hi_n,
            "covered_noise": bool(lo_n <= true <= hi_n), "level": level}


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
