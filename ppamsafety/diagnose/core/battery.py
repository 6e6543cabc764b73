"""Running a scenario battery: one result row per seed, here or in a pool of workers.

Every record kind's battery -- the arm's (:mod:`ppamsafety.diagnose.scenarios`), the muscle
bench's (:mod:`ppamsafety.diagnose.bench.scenarios`), the cylinder campaign's
(:mod:`ppamsafety.diagnose.bench.calibration`) -- keeps only its draws: a :class:`Battery`
names its seeds and the function turning one seed into a row.  They run through one
:func:`run_battery` and share the draw helpers (:func:`logu`, :func:`sgn`), the required
precision of "high" (:data:`HIGH_PRECISION`) and its Wilson bound (:func:`wilson_low`).
"""

from __future__ import annotations

import math
import multiprocessing
import os
import traceback
from dataclasses import dataclass, field
from functools import partial

import pandas as pd

from ..._validation import check_int

#: Scenarios a worker runs before it is replaced (bounds what a long battery can leak).
TASKS_PER_WORKER = 50
#: Required precision of "high", every record kind: of all effects named "high", at least
#: this fraction are really there (measured on seeds never used to set the gates).
HIGH_PRECISION = 0.97
#: Probabilities of 0, 1, 2, 3 hidden library effects in a scenario (the arm's and the
#: muscle bench's batteries).
P_COUNT = (0.2, 0.4, 0.28, 0.12)
#: Probability of an out-of-library perturbation in a scenario.
P_PERTURBATION = 0.3


def logu(rng, lo: float, hi: float) -> float:
    """A log-uniform draw in [lo, hi] (a magnitude over decades).

    Parameters
    ----------
    rng : numpy.random.Generator
    lo, hi : float
        Bounds (> 0).
    """
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def sgn(rng) -> float:
    """A random sign, -1.0 or 1.0.

    Parameters
    ----------
    rng : numpy.random.Generator
    """
    return float(rng.choice([-1.0, 1.0]))


def wilson_low(k: int, n: int, z: float = 1.96) -> float:
    """Lower bound of the Wilson score interval of a proportion k / n (nan when n = 0).

    Parameters
    ----------
    k, n : int
        Successes and trials.
    z : float
        Normal quantile of the interval (1.96: 95 %).
    """
    if n == 0:
        return math.nan
    p = k / n
    den = 1 + z * z / n
    centre = p + z * z / (2 * n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return max((centre - half) / den, 0.0)           # 0 of n: exactly 0, not -3e-18


@dataclass(frozen=True)
class Battery:
    """A record kind's battery: its seeds and how one seed becomes a result row.

    Attributes
    ----------
    kind : str
        The record kind (the ``kind`` of a failed scenario's row when ``error_row`` has
        none).
    tuning : range
        Seeds the gates were set on (never used to measure them).
    measure : range
        Seeds of the measurement.
    run : callable
        ``run(seed, **options) -> dict``: draw, synthesize, diagnose and score one scenario
        (module level, so that worker processes can run it).
    error_row : dict
        Keys of the row of a scenario that raised (besides ``seed``, ``error``,
        ``traceback``).
    processes : int or None
        Default worker processes (None: every core).
    """

    kind: str
    tuning: range
    measure: range
    run: object
    error_row: dict = field(default_factory=dict)
    processes: int | None = 1


def _scenario(seed, battery, options):
    try:
        return battery.run(seed, **options)
    except Exception as exc:                     # a failure is a result of the battery
        return {"seed": seed, **battery.error_row, "error": f"{type(exc).__name__}: {exc}",
                "traceback": traceback.format_exc()}


def run_battery(battery: Battery, seeds, *, processes: int | None = None,
                progress: bool = False, **options) -> pd.DataFrame:
    """One row per seed of a record kind's battery (a failed scenario is an error row).

    Parameters
    ----------
    battery : Battery
    seeds : iterable of int
    processes : int, optional, keyword-only
        Worker processes (default ``battery.processes``; 1: in this process).
    progress : bool, keyword-only
        Print one line per finished scenario.
    **options
        Keyword options of ``battery.run`` (the arm's ``arm``, ``declared``).

    Returns
    -------
    pandas.DataFrame
        One row per scenario, sorted by seed.
    """
    if not isinstance(battery, Battery):
        raise TypeError(f"battery: {battery!r} is not a Battery (the kinds' ARM_BATTERY, "
                        f"MUSCLE_BATTERY)")
    seeds = [check_int("seed", s, 0) for s in seeds]
    if processes is None:
        processes = battery.processes
    processes = (os.cpu_count() or 1) if processes is None else \
        check_int("processes", processes, 1, 256)
    return run_seeds(partial(_scenario, battery=battery, options=options), seeds,
                     processes=processes, progress=progress)


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
    d : Estimate
        The parameter's estimate in the diagnosis (``ci_low``/``ci_high`` the reported
        interval, ``ci_low_noise``/``ci_high_noise`` the fit's own).
    level : str
        The name's confidence level.

    Returns
    -------
    dict
        ``covered`` for the reported interval, ``covered_noise`` for the fit's own.
    """
    lo_n, hi_n = d.ci_low_noise, d.ci_high_noise
    return {"effect": effect, "parameter": parameter, "true": float(true),
            "value": d.value, "ci_low": d.ci_low, "ci_high": d.ci_high,
            "covered": bool(d.ci_low <= true <= d.ci_high),
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


__all__ = ["Battery", "run_battery", "run_seeds", "progress_line", "coverage_entry", "logu", "sgn",
           "wilson_low", "HIGH_PRECISION", "P_COUNT", "P_PERTURBATION", "TASKS_PER_WORKER"]
