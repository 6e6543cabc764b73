"""Parameter sweeps: grid -> DataFrame, with progress, resume and several processes.

A sweep is a function ``func(**case) -> dict | DataFrame`` evaluated for a list
of cases (dicts of JSON-serialisable parameters).  :func:`run_sweep`

* shows a progress bar (tqdm),
* stores each finished case in ``cache_dir`` as soon as it finishes, so an
  interrupted or partly failed sweep resumes without recomputing finished
  cases (pass the same ``cache_dir``),
* reuses a cached case only if the case, the sweep name, the source code of
  ``func`` and the source of the whole package are unchanged (see
  :func:`case_key`): an edit never returns results of the old code.  The
  package part is :func:`ppamsafety._sourcehash.source_hash`, every file, not
  the compiled-kernel key (which ignores studies, figures and the command
  line): a result also depends on the Python code around the kernels,
* runs cases on ``processes`` worker processes (the compiled kernels are
  cached on disk, so workers do not recompile),
* records a failing case (its parameters, ``status="failed"`` and the error)
  and goes on, or with ``on_error="raise"`` stops with an error that names
  the case, after keeping every finished result,
* returns one DataFrame with the case parameters as leading columns,
* takes the cases as a list of dicts, a grid (:func:`grid_cases`: every
  combination of the values of each key) or both,
* runs locally (``backend="local"``: this process or a process pool) or on a
  Dask cluster (``backend="dask"``: a ``dask.distributed`` scheduler address
  or ``Client``, or a ``LocalCluster`` started and closed for the sweep), with
  the same caching and failure semantics: every case is stored as soon as its
  future completes.

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
import re
import secrets
import signal
import sys
import itertools
import math
import multiprocessing
import warnings
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path

import pandas as pd
from tqdm.auto import tqdm

from ._interrupt import deferred as interrupt_deferred
from ._interrupt import requested as interrupt_requested
from ._jit import available_cores
from ._sourcehash import source_hash
from ._errors import mark_internal
from .plots.sweep import plot_sweep
from .results import Result

_STATUS_COLUMNS = ("status", "error")
#: How often [s] a pooled sweep looks for Ctrl-C while its cases run.
_POLL_S = 0.2
#: Default largest number of cases of one :func:`run_sweep` call.
MAX_CASES = 10 ** 6
#: Memory one case holds until the table is assembled (key, result row) [bytes], estimated.
BYTES_PER_CASE = 4000
#: Execution back ends of :func:`run_sweep`.
BACKENDS = ("local", "dask")


class SweepError(RuntimeError):
    """A sweep case failed with ``on_error="raise"``.

    Parameters
    ----------
    message : str
        The error message.
    index, case, error
        See Attributes.

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

    The package source is :func:`ppamsafety._sourcehash.source_hash` (every
    ``*.py`` of the package), not the narrower key of the compiled-kernel cache.

    The source is ``inspect.getsource(func)``; if it is not available, the
    qualified name and the bytes of its module file.  The bytecode of the
    loaded function is included too, so a source file edited without
    reloading its module does not match the loaded code.  Helper functions
    outside the ppamsafety package that ``func`` calls are *not* covered: put
    a version in the sweep ``name`` when you change them.

    Parameters
    ----------
    func : callable or functools.partial
        The case function (a partial's bound arguments are hashed too).

    Returns
    -------
    str
        20 hex digits.
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


def _as_result(case: dict, out):
    """A dict result as one row (case parameters first, then the results), else a DataFrame.

    Rows are kept as dicts (cheaper than one-row DataFrames) and assembled
    into one DataFrame at the end of the sweep.
    """
    clash = sorted(k for k in (out.columns if isinstance(out, pd.DataFrame) else
                               out if isinstance(out, Mapping) else ()) if k in case)
    if clash:
        raise ResultColumnError(f"the result column(s) {clash} have the name of a case "
                                f"parameter, whose value they would replace in the table; "
                                f"rename them in the sweep function")
    if isinstance(out, Mapping) and not isinstance(out, pd.DataFrame):
        row = dict(case)
        row.update(out)
        return row
    return _as_frame(case, out)


def _assemble(cases, results, failures, on_error, name) -> pd.DataFrame:
    """One DataFrame of every result row (fast path: every result is a dict row)."""
    if on_error == "raise":
        return pd.DataFrame([results[i] for i in range(len(cases))])
    rows = []
    for i, c in enumerate(cases):
        if i in failures:
            rows.append({**c, "status": "failed", "error": _error_text(failures[i])})
            continue
        r = results[i]
        clash = [k for k in _STATUS_COLUMNS if k in r]
        if clash:
            raise ValueError(f"sweep {name!r}: case {i} returned the column(s) {clash}, which "
                             f"run_sweep(on_error='record') adds itself; rename them or pass "
                             f"on_error='raise'")
        row = {k: r[k] for k in c}
        row["status"], row["error"] = "ok", ""
        row.update((k, v) for k, v in r.items() if k not in row)
        rows.append(row)
    return pd.DataFrame(rows)


def _call(func, case):
    """``func(**case)``; a bug's ``TypeError`` is raised as an ``InternalFailure`` (read from
    the traceback, which a worker's exception loses: ``_errors.is_internal_error``), so
    that a failed case is never put down to bad input."""
    try:
        return func(**case)
    except TypeError as exc:
        marked = mark_internal(exc, "sweep case")
        if marked is exc:
            raise
        raise marked from exc


def _ignore_interrupt():
    """Worker initializer: Ctrl-C is the parent's to handle (it terminates the workers);
    a worker that died of it would break the pool and its cases would read as failures."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _error_text(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}"


def grid_cases(grid: Mapping, base: Mapping | None = None, *, _check_only: bool = False):
    """Every combination of the values of a grid, as a list of cases.

    Parameters
    ----------
    grid : mapping of str to sequence
        Parameter name -> the values it takes (a non-empty list or tuple).
        The first key varies slowest.
    base : mapping, optional
        Parameters common to every case (a grid key of the same name wins).
    _check_only : bool, keyword-only
        Internal: only check the grid and return None (:func:`run_sweep` generates the
        points on demand instead of building this list).

    Returns
    -------
    list of dict
        ``len = prod(len(values))`` cases, ``{**base, **point}``.

    Examples
    --------
    >>> grid_cases({"lam": [0.4, 0.8], "ki_bar": [2, 12]})[:2]
    [{'lam': 0.4, 'ki_bar': 2}, {'lam': 0.4, 'ki_bar': 12}]
    """
    if not isinstance(grid, Mapping):
        raise TypeError(f"grid must be a dict of parameter name -> list of values, got "
                        f"{type(grid).__name__} {grid!r:.80}")
    if base is not None and not isinstance(base, Mapping):
        raise TypeError(f"base must be a dict of parameters or None, got {type(base).__name__}")
    keys = list(grid)
    if not keys:
        raise ValueError("grid = {} has no parameter: give at least one key and its values "
                         "(e.g. {'lam': [0.4, 0.8]}), or pass cases instead")
    values = []
    for k in keys:
        if not isinstance(k, str):
            raise TypeError(f"grid keys must be str parameter names, got {k!r}")
        v = grid[k]
        if isinstance(v, (str, bytes, Mapping)) or not isinstance(v, Sequence):
            raise TypeError(f"grid[{k!r}] must be a list of values, got {type(v).__name__} "
                            f"{v!r:.80}")
        if len(v) == 0:
            raise ValueError(f"grid[{k!r}] is an empty list: give at least one value")
        values.append(list(v))
    if _check_only:
        return None
    return [{**(base or {}), **dict(zip(keys, point))} for point in itertools.product(*values)]


def _check_cases(cases) -> Sequence:
    """The cases, checked; a sequence is kept as it is (a lazy grid is not materialised)."""
    if isinstance(cases, (str, bytes, Mapping)) or not isinstance(cases, Iterable):
        raise TypeError(f"cases must be a sequence of dicts (keyword arguments of func, one dict "
                        f"per case), got {type(cases).__name__} {cases!r:.80}")
    lazy = isinstance(cases, Sequence) and not isinstance(cases, (list, tuple))
    out = []
    for i, c in enumerate(cases):
        if not isinstance(c, Mapping):
            raise TypeError(f"cases[{i}] must be a dict of keyword arguments, got "
                            f"{type(c).__name__} {c!r:.80}")
        bad = [k for k in c if not isinstance(k, str)]
        if bad:
            raise TypeError(f"cases[{i}] has keys that are not str: {bad!r}; keys are the "
                            f"keyword-argument names of func")
        if not lazy:
            out.append(dict(c))
    return cases if lazy else out


class _Combined(Sequence):
    """Every case combined with every point of a grid, generated on demand."""

    def __init__(self, cases: Sequence, grid: Mapping):
        self.cases, self.keys = cases, list(grid)
        self.values = [list(grid[k]) for k in self.keys]
        self.points = math.prod(len(v) for v in self.values)

    def __len__(self) -> int:
        return len(self.cases) * self.points

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        j, k = divmod(range(len(self))[i], self.points)
        point = {}
        for key, vals in zip(reversed(self.keys), reversed(self.values)):
            k, m = divmod(k, len(vals))
            point[key] = vals[m]
        return {**self.cases[j], **{key: point[key] for key in self.keys}}


#: Names of the files :func:`run_sweep` writes into ``cache_dir`` (a case key, ``.pkl``; and
#: the temporary file of an atomic write).
_CACHE_FILE = re.compile(r"^[0-9a-f]{20}(\.[0-9a-f]{8}\.tmp|\.pkl)$")


class ResultColumnError(ValueError):
    """A case function returned a column named like a case parameter (it would replace it)."""


def _check_processes(processes) -> int:
    if processes is None:
        return available_cores()
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
    cores = available_cores()
    if processes > cores:
        warnings.warn(f"processes = {processes} exceeds the {cores} available cores; "
                      f"using {cores} worker processes", UserWarning, stacklevel=4)
        processes = cores
    return processes


def _dask_client(scheduler, processes: int):
    """(client, cleanup) for :func:`run_sweep`'s dask back end."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise ImportError("backend='dask' needs dask.distributed: pip install "
                          "'ppamsafety[cluster]' (or 'dask[distributed]')") from None
    if isinstance(scheduler, Client):
        return scheduler, lambda: None
    if scheduler is None:
        cluster = LocalCluster(n_workers=processes, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        try:
            client = Client(cluster)
        except BaseException:
            cluster.close()
            raise

        def close():
            client.close()
            cluster.close()
        return client, close
    if isinstance(scheduler, str) and scheduler:
        try:
            client = Client(scheduler, timeout="30s")
        except (OSError, ValueError, TypeError) as exc:      # unreachable, or not an address
            raise OSError(f"scheduler = {scheduler!r}: cannot connect to the dask scheduler "
                          f"({_error_text(exc)}); give its address, e.g. "
                          f"'tcp://10.0.0.5:8786'") from None
        return client, client.close
    raise TypeError(f"scheduler must be None, a scheduler address str (e.g. "
                    f"'tcp://host:8786') or a dask.distributed.Client, got "
                    f"{type(scheduler).__name__} {scheduler!r:.80}")


def _run_dask(func, cases, todo, keys, name, scheduler, processes, finish, on_error):
    """Submit the cases ``todo`` to dask and ``finish`` each as its future completes.

    The cases are submitted in one ``Client.map`` call; finished futures are
    taken in batches (``as_completed(...).batches()``) and their results
    fetched with one ``gather`` per batch, so the per-case cost is one task on
    the scheduler, not one round trip per result.
    """
    from dask.distributed import as_completed as dask_completed

    client, close = _dask_client(scheduler, processes)
    try:
        run = secrets.token_hex(4)
        futs = client.map(functools.partial(_call, func), [cases[i] for i in todo],
                          key=[f"{name}-{keys[i]}-{run}" for i in todo], pure=False)
        index = {f.key: i for f, i in zip(futs, todo)}
        stop = False
        for batch in dask_completed(futs).batches():
            done = [f for f in batch if f.status == "finished"]
            values = client.gather(done) if done else []
            for f, v in zip(done, values):
                if not finish(index[f.key], v) and on_error == "raise":
                    stop = True
            for f in batch:
                if f.status == "error":
                    if not finish(index[f.key], exc=f.exception()) and on_error == "raise":
                        stop = True
            for f in batch:
                f.release()
            if stop:
                client.cancel([f for f in futs if not f.done()])
                break
    finally:
        close()


def _stop_pool(pool, before=()) -> None:
    """Stop a process pool at once: cancel its queued cases and end its workers.

    The workers' current cases are abandoned (the finished ones are in the cache); else the
    interpreter waits for them at exit (concurrent.futures and multiprocessing join their
    workers) and Ctrl-C would take as long as the longest running case.  ``before``: the
    child processes that existed before the pool; every other live child is one of its
    workers, including one forked in the instant before an interrupt that the pool had not
    registered yet (it would hold the output pipes open after this process exits).
    """
    workers = list((getattr(pool, "_processes", None) or {}).values())
    known = {id(w) for w in workers}
    workers += [c for c in multiprocessing.active_children()
                if c not in before and id(c) not in known]
    pool.shutdown(wait=False, cancel_futures=True)
    for w in workers:
        if w.is_alive():
            w.terminate()
    for w in workers:
        w.join(timeout=5.0)
        if w.is_alive():
            w.kill()
            w.join(timeout=5.0)


def _run_pool(func, cases, todo, nproc, finish, on_error) -> None:
    """Run the cases ``todo`` in ``nproc`` worker processes, handing each result to ``finish``.

    An interrupt (Ctrl-C) or any other exception here cancels the cases not yet started
    instead of waiting for them (a worker that was interrupted too reports it as the
    case's result and would otherwise take the next case); finished cases are kept.
    """
    # Ctrl-C is held back while the workers are forked (see _interrupt.deferred): raised in
    # the middle, it would leave a worker the pool does not know of
    before = set(multiprocessing.active_children())
    pool = None
    try:
        with interrupt_deferred():
            pool = ProcessPoolExecutor(max_workers=nproc, initializer=_ignore_interrupt)
            futures = {pool.submit(_call, func, cases[i]): i for i in todo}
        pending = set(futures)
        while pending:
            # a short timeout, not a blocking as_completed: the kernel may deliver Ctrl-C to
            # another thread (the pool's, tqdm's), and then the main thread would see it only
            # when the next case finishes, which can be minutes away
            done, pending = wait(pending, timeout=_POLL_S, return_when=FIRST_COMPLETED)
            if interrupt_requested():           # an interrupt the interpreter swallowed
                raise KeyboardInterrupt
            for fut in done:
                if fut.cancelled():
                    continue
                exc = fut.exception()
                if isinstance(exc, KeyboardInterrupt):   # the worker was interrupted with us
                    raise KeyboardInterrupt
                ok = finish(futures[fut], None if exc else fut.result(), exc)
                if not ok and on_error == "raise":
                    for other in futures:      # not started yet: cancel; running: finish
                        other.cancel()
    except BaseException:
        if pool is not None:
            _stop_pool(pool, before)
        raise
    pool.shutdown(wait=True)


class SweepResult(Result):
    """The result of a sweep (:func:`run_sweep`, :func:`ppamsafety.sweep_cases.safety_sweep`).

    Parameters
    ----------
    table : pandas.DataFrame
        One row per case (or per row a case returned): the case parameters, ``status`` and
        ``error`` (with ``on_error="record"``), then the results.
    name : str
        The sweep's name.
    swept : sequence of str, optional
        The case parameters that vary (default: the leading columns before ``status``
        that take more than one value).
    units : dict, optional
        ``{column: unit}`` of the table's columns (:meth:`column_units`; ``write()`` names
        the CSV columns ``"column [unit]"``); a generic sweep knows none.
    """

    def __init__(self, table: pd.DataFrame, *, name: str = "sweep", swept=None, units=None):
        if not isinstance(table, pd.DataFrame):
            raise TypeError(f"table must be a pandas DataFrame, got {type(table).__name__}")
        if units is not None and not isinstance(units, dict):
            raise TypeError(f"units must be a dict {{column: unit}} or None, got "
                            f"{type(units).__name__}")
        self._table = table
        self.name = str(name)
        self.units = {} if units is None else {str(k): v for k, v in units.items() if v}
        if swept is None:
            cols = list(table.columns)
            lead = cols[:cols.index("status")] if "status" in cols else []
            swept = [c for c in lead if table[c].map(repr).nunique() > 1]
        self.swept = tuple(swept)

    def to_pandas(self) -> pd.DataFrame:
        """The sweep's table."""
        return self._table

    def tables(self) -> dict:
        return {"table": self._table}

    def column_units(self) -> dict:
        """``{column: unit}`` given at construction (a safety sweep's columns)."""
        return dict(self.units)

    def plot(self, **kwargs):
        """Each result against each swept parameter, with the safety limits; a matplotlib
        Figure.

        Parameters
        ----------
        **kwargs
            Passed to :func:`ppamsafety.plots.sweep.plot_sweep` (``title``, ``units``,
            ``region_limits``).
        """
        if not self.swept:
            raise ValueError(f"sweep {self.name!r}: no case parameter varies, nothing to plot "
                             f"against")
        return plot_sweep(self._table, list(self.swept), **kwargs)

    def __len__(self) -> int:
        return len(self._table)

    def __repr__(self) -> str:
        return (f"SweepResult(name={self.name!r}, rows={len(self._table)}, "
                f"swept={list(self.swept)})")


def run_sweep(func, cases=None, *, name: str | None = None, cache_dir=None,
              processes: int | None = 1, progress: bool = True, on_error: str = "record",
              grid: Mapping | None = None, backend: str = "local",
              scheduler=None, limit: int = MAX_CASES) -> SweepResult:
    """Evaluate ``func(**case)`` for every case and concatenate the results.

    Parameters
    ----------
    func : callable
        Top-level (picklable) function returning a dict (one row) or a DataFrame.
    cases : sequence of dict, optional
        Keyword arguments per case (str keys, JSON-serialisable values).
        With ``grid``, each case is combined with every grid point (default
        one empty case).  One of ``cases`` and ``grid`` is required.
    name : str, optional
        Sweep name used in the cache key (default ``func.__qualname__``).
    cache_dir : path-like, optional
        Where finished cases are stored (as pickles: only use folders you trust);
        reuse it to resume.  A cached case is reused only if the case, ``name``,
        the source of ``func`` and the package source are unchanged
        (:func:`case_key`, :func:`function_hash`).  An unreadable cache file is
        named in a warning and recomputed.  Failed cases are not cached.
        None: no cache (an empty path ``""`` is refused: it would mean the current folder;
        so is a folder that holds other files than the cache's: give the cache a folder of
        its own).
    processes : int or None
        Worker processes (1 = run in this process; None = every available
        core).  More than the available cores gives a warning and is capped at
        the number of cores.  With the local backend and more cases than
        workers, the first case runs in this process before the workers
        start, so that the kernels it compiles are inherited by them instead
        of compiled by each on a cold cache.  With ``backend="dask"`` and no
        ``scheduler``: the number of workers of the ``LocalCluster`` (ignored
        with a scheduler).
    progress : bool
        Show a progress bar.
    on_error : {"record", "raise"}
        ``"record"`` (default): a failing case gives one row with its parameters,
        ``status="failed"``, ``error`` (exception type and message) and NaN
        results; the other cases go on, and one warning at the end counts the
        failures.  ``"raise"``: cases not yet started are cancelled, every
        finished result is kept (and cached), then :class:`SweepError` names the
        first failing case (lowest index).
    grid : mapping of str to list, optional
        Parameter grid (:func:`grid_cases`); the cases are every combination,
        each merged into every entry of ``cases``.
    backend : {"local", "dask"}
        ``"local"``: this process or a ``ProcessPoolExecutor``.  ``"dask"``:
        ``dask.distributed`` (optional extra ``ppamsafety[cluster]``); the
        cases are submitted as futures and stored as they complete
        (``as_completed``), so a sweep interrupted on a cluster resumes from
        ``cache_dir`` too.  The cache must be on a file system this process
        can write (the results come back to this process, which writes them).
    scheduler : None, str or dask.distributed.Client
        Dask only.  None: a ``LocalCluster(n_workers=processes,
        threads_per_worker=1, processes=True)`` is started for the sweep and
        closed after it.  A scheduler address such as
        ``"tcp://10.0.0.5:8786"`` (e.g. of a dask-jobqueue ``SLURMCluster``):
        a client is connected and closed afterwards, the cluster is left
        running.  A ``Client``: used as it is and left open.
    limit : int
        Largest number of cases accepted (default :data:`MAX_CASES`): the keys and result
        rows of every case are held in memory until the table is assembled (about
        :data:`BYTES_PER_CASE` each), so a larger sweep is refused with its size before
        anything runs.  Raise it if this machine holds it, or split the sweep.

    Returns
    -------
    SweepResult
        Its table (``.table``, ``.to_pandas()``): case parameters followed by the result
        columns, in case order.  With ``on_error="record"``, the columns ``status``
        ("ok"/"failed") and ``error`` ("" when ok) follow the case parameters.  A result
        column with the name of a case parameter raises :class:`ResultColumnError` (it would
        replace the parameter).

    Notes
    -----
    ``cases`` may be a lazy sequence (e.g. a study's
    :class:`~ppamsafety.study_files.CaseGrid`) and a ``grid`` is combined on demand: the
    cases are generated as they run, never stored as one list.
    """
    table = _sweep_table(func, cases, name=name, cache_dir=cache_dir, processes=processes,
                         progress=progress, on_error=on_error, grid=grid, backend=backend,
                         scheduler=scheduler, limit=limit)
    return SweepResult(table, name=name or getattr(func, "__qualname__", None) or "sweep")


def _sweep_table(func, cases, *, name, cache_dir, processes, progress, on_error, grid, backend,
                 scheduler, limit) -> pd.DataFrame:
    if not callable(func):
        raise TypeError(f"func must be callable, got {type(func).__name__} {func!r:.80}")
    if cases is None and grid is None:
        raise TypeError("run_sweep needs cases (a list of dicts) or grid (a dict of lists)")
    if isinstance(limit, bool) or not isinstance(limit, int) or limit < 1:
        raise TypeError(f"limit must be a positive int, got {limit!r}")
    if grid is not None:
        grid_cases(grid, _check_only=True)
    n_base = len(cases) if isinstance(cases, Sequence) and not isinstance(cases, (str, bytes)) \
        else (1 if cases is None else None)
    if n_base is not None:                 # counted before a single case is generated
        shape = [n_base] + ([len(v) for v in grid.values()] if grid is not None else [])
        n = math.prod(shape)
        if n > limit:
            raise ValueError(
                f"run_sweep: {n:,} cases ({' x '.join(map(str, shape))} = cases x grid) "
                f"would hold about {n * BYTES_PER_CASE / 1e9:.3g} GB of keys and result rows "
                f"in memory; at most limit = {limit:,} cases are run at once: split the sweep "
                f"(a part of the grid per call), or pass a larger limit")
    cases = _check_cases([{}] if cases is None else cases)
    if grid is not None:
        cases = _Combined(cases, grid)
    if len(cases) > limit:
        raise ValueError(f"run_sweep: {len(cases):,} cases would hold about "
                         f"{len(cases) * BYTES_PER_CASE / 1e9:.3g} GB of keys and result rows in "
                         f"memory; at most limit = {limit:,} cases are run at once: split the "
                         f"sweep, or pass a larger limit")
    if backend not in BACKENDS:
        raise ValueError(f"backend = {backend!r} is not one of {', '.join(map(repr, BACKENDS))}")
    if scheduler is not None and backend != "dask":
        raise ValueError(f"scheduler = {scheduler!r} is given but backend = {backend!r}; a "
                         f"scheduler is used only with backend='dask'")
    if on_error not in ("record", "raise"):
        raise ValueError(f"on_error = {on_error!r} is not one of 'record', 'raise'")
    if name is not None and (not isinstance(name, str) or not name):
        raise TypeError(f"name must be a non-empty str or None, got {name!r}")
    if cache_dir is not None and (isinstance(cache_dir, bool)
                                  or not isinstance(cache_dir, (str, os.PathLike))):
        raise TypeError(f"cache_dir must be a path (str or os.PathLike) or None, got "
                        f"{type(cache_dir).__name__} {cache_dir!r}")
    if cache_dir is not None and not str(os.fspath(cache_dir)).strip():
        raise ValueError(f"cache_dir = {cache_dir!r} is an empty path (it would fill the "
                         f"current folder with cache files); give a folder, or None for no "
                         f"cache")
    processes = _check_processes(processes)
    name = name or getattr(func, "__qualname__", None) or "sweep"
    cache = None if cache_dir is None else Path(cache_dir)
    if cache is not None:
        if cache.exists() and not cache.is_dir():
            raise ValueError(f"cache_dir = '{cache}' exists and is not a folder")
        if cache.is_dir():
            other = sorted(e.name for e in cache.iterdir() if not _CACHE_FILE.match(e.name))
            if other:
                raise ValueError(f"cache_dir = '{cache}' holds {len(other)} file(s) that are not "
                                 f"sweep cache files (e.g. {other[0]!r}); the cache needs a "
                                 f"folder of its own (e.g. '{cache / '.sweep_cache'}'), so "
                                 f"that its files never mix with yours")
        try:
            cache.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OSError(f"cache_dir = '{cache}' cannot be created ({exc.strerror or exc})") \
                from None
    code = function_hash(func)
    keys = [case_key(name, c, code) for c in cases]     # also checks JSON-serialisability
    if processes > 1 and backend == "local":
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
                if not isinstance(obj, (pd.DataFrame, dict)):
                    raise TypeError(f"it holds a {type(obj).__name__}, not a DataFrame or a "
                                    f"dict (one result row)")
                results[i] = obj
                continue
            except Exception as exc:
                warnings.warn(f"sweep {name!r}: cache file {f} is unreadable "
                              f"({_error_text(exc)}); recomputing case {i}", RuntimeWarning,
                              stacklevel=3)
        todo.append(i)
    bar = tqdm(total=len(cases), initial=len(cases) - len(todo), desc=name, disable=not progress,
               leave=False)

    def finish(i, out=None, exc=None):
        bar.update(1)
        if exc is None:
            try:
                df = _as_result(cases[i], out)
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
        if backend == "dask":
            if todo:
                _run_dask(func, cases, todo, keys, name, scheduler, processes, finish, on_error)
        else:
            # With more cases than workers the first case runs in this process before the
            # pool starts: the kernels it compiles are then inherited by the forked workers
            # (or found in the on-disk cache) instead of compiled by every worker at once on
            # a cold cache.  With at most one case per worker that would only serialise.
            if nproc <= 1:
                here, pooled = list(todo), []
            elif len(todo) > nproc:
                here, pooled = list(todo[:1]), list(todo[1:])
            else:
                here, pooled = [], list(todo)
            stop = False
            for i in here:
                if interrupt_requested():
                    raise KeyboardInterrupt
                try:
                    out = _call(func, cases[i])
                except Exception as exc:
                    ok = finish(i, exc=exc)
                else:
                    ok = finish(i, out)
                if not ok and on_error == "raise":
                    stop = True
                    break
            if pooled and not stop:
                _run_pool(func, cases, pooled, min(nproc, len(pooled)), finish, on_error)
            if interrupt_requested():
                raise KeyboardInterrupt
    finally:
        bar.close()

    clash = sorted(i for i, e in failures.items() if isinstance(e, ResultColumnError))
    if clash:                          # the function's contract, not a case failure
        i = clash[0]
        raise ResultColumnError(f"sweep {name!r}: case {i} {cases[i]!r}: {failures[i]}")
    if failures and on_error == "raise":
        i = min(failures)
        err = _error_text(failures[i])
        raise SweepError(f"sweep {name!r}: case {i} {cases[i]!r} failed: {err}"
                         f" ({len(results)} finished cases kept"
                         f"{' in ' + str(cache) if cache is not None else ''})",
                         i, cases[i], err) from failures[i]
    if not cases:
        return pd.DataFrame()
    if all(isinstance(r, dict) for r in results.values()):
        out = _assemble(cases, results, failures, on_error, name)
        _warn_failures(cases, failures, name)
        return out
    results = {i: pd.DataFrame([r]) if isinstance(r, dict) else r for i, r in results.items()}
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
    _warn_failures(cases, failures, name)
    return pd.concat(frames, ignore_index=True)


def _warn_failures(cases, failures, name) -> None:
    if failures:
        shown = "; ".join(f"case {i} {cases[i]!r}: {_error_text(failures[i])}"
                          for i in sorted(failures)[:3])
        more = " ..." if len(failures) > 3 else ""
        warnings.warn(f"sweep {name!r}: {len(failures)} of {len(cases)} cases failed (rows with "
                      f"status='failed'): {shown}{more}", RuntimeWarning, stacklevel=4)
