"""Parameter sweeps: grid -> DataFrame, with progress, resume and several processes.

A sweep is a function ``func(**case) -> dict | DataFrame`` evaluated for a list
of cases (dicts of JSON-serialisable parameters).  :func:`run_sweep`

* shows a progress bar (tqdm),
* stores each finished case in ``cache_dir`` as soon as it finishes, so an
  interrupted or partly failed sweep resumes without recomputing finished
  cases (pass the same ``cache_dir``),
* reuses a cached case only if the case, the sweep name, the source code of
  ``func`` and the source of the whole package are unchanged (see
  :func:`case_key`): an edit never returns results of the old code,
* runs cases on ``processes`` worker processes (the compiled kernels are
  cached on disk, so workers do not recompile),
* records a failing case (its parameters, ``status="failed"`` and the error)
  and goes on, or with ``on_error="raise"`` stops with an error that names
  the case, after keeping every finished result,
* returns one DataFrame with the case parameters as leading columns.

Each case should itself be a batched computation (many impacts or variants
per call) so that process overhead is negligible.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import json
import operator
import os
import pickle
import secrets
import sys
import warnings
from collections.abc import Iterable, Mapping
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import pandas as pd

from ._sourcehash import source_hash

_STATUS_COLUMNS = ("status", "error")


class SweepError(RuntimeError):
    """A sweep case failed with ``on_error="raise"``.

    Parameters
    ----------
    message : str
        The exception message.
    index, case, error
        Stored as the attributes below.

    Attributes
    ----------
    index : int
        Position of the failing case in ``cases``.
    case : dict
        Its parameters.
    error : str
        Type and message of the exception it raised (also the ``__cause__``).
    """

    def __init__(self, message: str, index: int, case: dict, error: str):
        super().__init__(message)
        self.index, self.case, self.error = index, case, error


def _code_fingerprint(code) -> str:
    """Bytecode and constants of a code object, recursively, without memory addresses."""
    parts = [code.co_code.hex(), repr(code.co_names)]
    for c in code.co_consts:
        parts.append(_code_fingerprint(c) if inspect.iscode(c) else repr(c))
    return "|".join(parts)


def function_hash(func) -> str:
    """Hash of what ``func`` computes: its source, its bytecode and the package source.

    The source is ``inspect.getsource(func)``; if it is not available, the
    qualified name and the bytes of its module file.  The bytecode of the
    loaded function is included too, so a source file edited without
    reloading its module does not match the loaded code.  Helper functions
    outside the ppamsafety package that ``func`` calls are *not* covered: put
    a version in the sweep ``name`` when you change them.

    Parameters
    ----------
    func : callable
        The case function of a sweep; a :class:`functools.partial` is hashed
        with its bound arguments and the function it wraps.
    """
    h = hashlib.sha1()
    if isinstance(func, functools.partial):
        h.update(repr((func.args, sorted(func.keywords.items()))).encode())
        func = func.func
    h.update(f"{getattr(func, '__module__', '')}.{getattr(func, '__qualname__', '')}".encode())
    try:
        h.update(inspect.getsource(func).encode())
    except (OSError, TypeError):
        mod = sys.modules.get(getattr(func, "__module__", None) or "")
        file = getattr(mod, "__file__", None)
        if file and os.path.isfile(file):
            h.update(Path(file).read_bytes())
        else:
            h.update(repr(func).encode())
    code = getattr(func, "__code__", None)
    if code is not None:
        h.update(_code_fingerprint(code).encode())
    h.update(source_hash().encode())
    return h.hexdigest()[:20]


def case_key(name: str, case: dict, code: str = "") -> str:
    """Stable hash of a sweep name, a case and (optionally) a code hash: the cache file name.

    Parameters
    ----------
    name : str
        Sweep name.
    case : dict
        Case parameters (JSON-serialisable; key order does not matter).
    code : str
        :func:`function_hash` of the case function ("" leaves it out).
    """
    payload = {"sweep": name, "case": case}
    if code:
        payload["code"] = code
    try:
        text = json.dumps(payload, sort_keys=True, default=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"sweep case is not JSON-serialisable: {case!r} ({exc})") from None
    return hashlib.sha1(text.encode()).hexdigest()[:20]


def _available_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def _as_frame(case: dict, out) -> pd.DataFrame:
    if isinstance(out, pd.DataFrame):
        df = out.copy()
    elif isinstance(out, Mapping):
        df = pd.DataFrame([dict(out)])
    else:
        raise TypeError(f"the sweep function must return a dict or a DataFrame, got "
                        f"{type(out).__name__}")
    for i, (k, v) in enumerate(case.items()):
        if k not in df.columns:
            df.insert(i, k, [v] * len(df))
    return df


def _call(func, case):
    return func(**case)


def _error_text(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}"


def _check_cases(cases) -> list[dict]:
    if isinstance(cases, (str, bytes, Mapping)) or not isinstance(cases, Iterable):
        raise TypeError(f"cases must be a sequence of dicts (keyword arguments of func, one dict "
                        f"per case), got {type(cases).__name__} {cases!r:.80}")
    out = []
    for i, c in enumerate(cases):
        if not isinstance(c, Mapping):
            raise TypeError(f"cases[{i}] must be a dict of keyword arguments, got "
                            f"{type(c).__name__} {c!r:.80}")
        bad = [k for k in c if not isinstance(k, str)]
        if bad:
            raise TypeError(f"cases[{i}] has keys that are not str: {bad!r}; keys are the "
                            f"keyword-argument names of func")
        out.append(dict(c))
    return out


def _check_processes(processes) -> int:
    if isinstance(processes, bool):
        raise TypeError(f"processes must be a positive int, got {processes!r}")
    try:
        processes = operator.index(processes)
    except TypeError:
        raise TypeError(f"processes must be a positive int, got {type(processes).__name__} "
                        f"{processes!r}") from None
    if processes < 1:
        raise ValueError(f"processes = {processes} is not allowed: use a positive int (1 = run "
                         f"in this process)")
    cores = _available_cores()
    if processes > cores:
        warnings.warn(f"processes = {processes} exceeds the {cores} available cores; "
                      f"using {cores} worker processes", UserWarning, stacklevel=3)
        processes = cores
    return processes


def run_sweep(func, cases, *, name: str | None = None, cache_dir=None, processes: int = 1,
              progress: bool = True, on_error: str = "record") -> pd.DataFrame:
    """Evaluate ``func(**case)`` for every case and concatenate the results.

    Parameters
    ----------
    func : callable
        Top-level (picklable) function returning a dict (one row) or a DataFrame.
    cases : sequence of dict
        Keyword arguments per case (str keys, JSON-serialisable values).
    name : str, optional
        Sweep name used in the cache key (default ``func.__qualname__``).
    cache_dir : path-like, optional
        Where finished cases are stored (as pickles: only use folders you trust);
        reuse it to resume.  A cached case is reused only if the case, ``name``,
        the source of ``func`` and the package source are unchanged
        (:func:`case_key`, :func:`function_hash`).  An unreadable cache file is
        named in a warning and recomputed.  Failed cases are not cached.
        None: no cache.
    processes : int
        Worker processes (1 = run in this process).  More than the available
        cores gives a warning and is capped at the number of cores.
    progress : bool
        Show a progress bar.
    on_error : {"record", "raise"}
        ``"record"`` (default): a failing case gives one row with its parameters,
        ``status="failed"``, ``error`` (exception type and message) and NaN
        results; the other cases go on, and one warning at the end counts the
        failures.  ``"raise"``: cases not yet started are cancelled, every
        finished result is kept (and cached), then :class:`SweepError` names the
        first failing case (lowest index).

    Returns
    -------
    pandas.DataFrame
        Case parameters followed by the result columns, in case order.  With
        ``on_error="record"``, the columns ``status`` ("ok"/"failed") and ``error``
        ("" when ok) follow the case parameters.
    """
    from tqdm.auto import tqdm

    if not callable(func):
        raise TypeError(f"func must be callable, got {type(func).__name__} {func!r:.80}")
    cases = _check_cases(cases)
    if on_error not in ("record", "raise"):
        raise ValueError(f"on_error = {on_error!r} is not one of 'record', 'raise'")
    if name is not None and (not isinstance(name, str) or not name):
        raise TypeError(f"name must be a non-empty str or None, got {name!r}")
    if cache_dir is not None and (isinstance(cache_dir, bool)
                                  or not isinstance(cache_dir, (str, os.PathLike))):
        raise TypeError(f"cache_dir must be a path (str or os.PathLike) or None, got "
                        f"{type(cache_dir).__name__} {cache_dir!r}")
    processes = _check_processes(processes)
    name = name or getattr(func, "__qualname__", None) or "sweep"
    cache = None if cache_dir is None else Path(cache_dir)
    if cache is not None:
        if cache.exists() and not cache.is_dir():
            raise ValueError(f"cache_dir = '{cache}' exists and is not a folder")
        cache.mkdir(parents=True, exist_ok=True)
    code = function_hash(func)
    keys = [case_key(name, c, code) for c in cases]     # also checks JSON-serialisability
    if processes > 1:
        try:
            pickle.dumps(func)
        except Exception as exc:
            raise TypeError(f"func must be picklable (a top-level function) to run on "
                            f"processes = {processes}: {_error_text(exc)}") from None

    results: dict[int, pd.DataFrame] = {}
    failures: dict[int, BaseException] = {}
    todo = []
    for i, k in enumerate(keys):
        f = None if cache is None else cache / f"{k}.pkl"
        if f is not None and f.exists():
            try:
                with open(f, "rb") as fh:
                    obj = pickle.load(fh)
                if not isinstance(obj, pd.DataFrame):
                    raise TypeError(f"it holds a {type(obj).__name__}, not a DataFrame")
                results[i] = obj
                continue
            except Exception as exc:
                warnings.warn(f"sweep {name!r}: cache file {f} is unreadable "
                              f"({_error_text(exc)}); recomputing case {i}", RuntimeWarning,
                              stacklevel=2)
        todo.append(i)
    bar = tqdm(total=len(cases), initial=len(cases) - len(todo), desc=name, disable=not progress,
               leave=False)

    def finish(i, out=None, exc=None):
        bar.update(1)
        if exc is None:
            try:
                df = _as_frame(cases[i], out)
            except Exception as e:
                exc = e
        if exc is not None:
            failures[i] = exc
            return False
        results[i] = df
        if cache is not None:               # stored as soon as it finishes
            tmp = cache / f"{keys[i]}.{secrets.token_hex(4)}.tmp"
            with open(tmp, "wb") as fh:
                pickle.dump(df, fh)
            os.replace(tmp, cache / f"{keys[i]}.pkl")   # atomic: no half-written results
        return True

    try:
        nproc = min(processes, len(todo))
        if nproc <= 1:
            for i in todo:
                try:
                    out = func(**cases[i])
                except Exception as exc:
                    ok = finish(i, exc=exc)
                else:
                    ok = finish(i, out)
                if not ok and on_error == "raise":
                    break
        else:
            with ProcessPoolExecutor(max_workers=nproc) as pool:
                futures = {pool.submit(_call, func, cases[i]): i for i in todo}
                for fut in as_completed(futures):
                    if fut.cancelled():
                        continue
                    exc = fut.exception()
                    ok = finish(futures[fut], None if exc else fut.result(), exc)
                    if not ok and on_error == "raise":
                        for other in futures:      # not started yet: cancel; running: finish
                            other.cancel()
    finally:
        bar.close()

    if failures and on_error == "raise":
        i = min(failures)
        err = _error_text(failures[i])
        raise SweepError(f"sweep {name!r}: case {i} {cases[i]!r} failed: {err}"
                         f" ({len(results)} finished cases kept"
                         f"{' in ' + str(cache) if cache is not None else ''})",
                         i, cases[i], err) from failures[i]
    if not cases:
        return pd.DataFrame()
    if on_error == "raise":
        return pd.concat([results[i] for i in range(len(cases))], ignore_index=True)

    frames = []
    for i, c in enumerate(cases):
        if i in failures:
            frames.append(pd.DataFrame([{**c, "status": "failed",
                                         "error": _error_text(failures[i])}]))
            continue
        df = results[i].copy()
        clash = [s for s in _STATUS_COLUMNS if s in df.columns]
        if clash:
            raise ValueError(f"sweep {name!r}: case {i} returned the column(s) {clash}, which "
                             f"run_sweep(on_error='record') adds itself; rename them or pass "
                             f"on_error='raise'")
        pos = sum(1 for k in c if k in df.columns)
        df.insert(pos, "status", "ok")
        df.insert(pos + 1, "error", "")
        frames.append(df)
    if failures:
        shown = "; ".join(f"case {i} {cases[i]!r}: {_error_text(failures[i])}"
                          for i in sorted(failures)[:3])
        more = " ..." if len(failures) > 3 else ""
        warnings.warn(f"sweep {name!r}: {len(failures)} of {len(cases)} cases failed (rows with "
                      f"status='failed'): {shown}{more}", RuntimeWarning, stacklevel=2)
    return pd.concat(frames, ignore_index=True)
