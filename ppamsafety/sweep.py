"""Parameter sweeps: grid -> DataFrame, with progress, resume and several processes.

A sweep is a function ``func(**case) -> dict | DataFrame`` evaluated for a list
of cases (dicts of JSON-serialisable parameters).  :func:`run_sweep`

* shows a progress bar (tqdm),
* stores each finished case in ``cache_dir`` under a hash of the case and the
  sweep name, so an interrupted sweep resumes without recomputing finished
  cases (pass the same ``cache_dir``),
* runs cases on ``processes`` worker processes (the compiled kernels are
  cached on disk, so workers do not recompile),
* returns one DataFrame with the case parameters as leading columns.

Each case should itself be a batched computation (many impacts or variants
per call) so that process overhead is negligible.
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import pandas as pd

from ._validation import check_int


def case_key(name: str, case: dict) -> str:
    """Stable hash of a sweep name and a case (the cache file name)."""
    try:
        text = json.dumps({"sweep": name, "case": case}, sort_keys=True, default=float)
    except TypeError as exc:
        raise ValueError(f"sweep case is not JSON-serialisable: {case!r}") from exc
    return hashlib.sha1(text.encode()).hexdigest()[:20]


def _as_frame(case: dict, out) -> pd.DataFrame:
    df = out.copy() if isinstance(out, pd.DataFrame) else pd.DataFrame([out])
    for i, (k, v) in enumerate(case.items()):
        if k not in df.columns:
            df.insert(i, k, [v] * len(df))
    return df


def _call(func, case):
    return func(**case)


def run_sweep(func, cases, *, name: str | None = None, cache_dir=None, processes: int = 1,
              progress: bool = True) -> pd.DataFrame:
    """Evaluate ``func(**case)`` for every case and concatenate the results.

    Parameters
    ----------
    func : callable
        Top-level (picklable) function returning a dict (one row) or a DataFrame.
    cases : sequence of dict
        Keyword arguments per case (JSON-serialisable values).
    name : str, optional
        Sweep name used in the cache key (default ``func.__qualname__``).
    cache_dir : path-like, optional
        Where finished cases are stored; reuse it to resume.  None: no cache.
    processes : int
        Worker processes (1 = run in this process).
    progress : bool
        Show a progress bar.

    Returns
    -------
    pandas.DataFrame
        Case parameters followed by the result columns, in case order.
    """
    from tqdm.auto import tqdm

    cases = [dict(c) for c in cases]
    processes = check_int("processes", processes, 1, os.cpu_count() or 1024)
    name = name or getattr(func, "__qualname__", "sweep")
    cache = None if cache_dir is None else Path(cache_dir)
    if cache is not None:
        cache.mkdir(parents=True, exist_ok=True)
    keys = [case_key(name, c) for c in cases]
    results: dict[int, pd.DataFrame] = {}
    todo = []
    for i, (c, k) in enumerate(zip(cases, keys)):
        f = None if cache is None else cache / f"{k}.pkl"
        if f is not None and f.exists():
            with open(f, "rb") as fh:
                results[i] = pickle.load(fh)
        else:
            todo.append(i)
    bar = tqdm(total=len(cases), initial=len(cases) - len(todo), desc=name, disable=not progress,
               leave=False)

    def store(i, out):
        df = _as_frame(cases[i], out)
        results[i] = df
        if cache is not None:
            tmp = cache / f"{keys[i]}.tmp"
            with open(tmp, "wb") as fh:
                pickle.dump(df, fh)
            os.replace(tmp, cache / f"{keys[i]}.pkl")   # atomic: no half-written results
        bar.update(1)

    if processes == 1 or len(todo) <= 1:
        for i in todo:
            store(i, func(**cases[i]))
    else:
        with ProcessPoolExecutor(max_workers=processes) as pool:
            futures = {pool.submit(_call, func, cases[i]): i for i in todo}
            for fut in as_completed(futures):
                store(futures[fut], fut.result())
    bar.close()
    if not results:
        return pd.DataFrame()
    return pd.concat([results[i] for i in range(len(cases))], ignore_index=True)
