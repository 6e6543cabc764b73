"""Regenerate the report folder from scratch by running every registered section.

Each section is computed, rendered and its artifacts written by
:func:`ppamsafety.sections.run_section`.  Figures are pyplot-free
:class:`matplotlib.figure.Figure` objects (see :mod:`ppamsafety.plots.figure`),
so no matplotlib backend is selected here or anywhere in the package.

The folder is written through :class:`ppamsafety.output.OutputFolder`: a
previous report is replaced only with ``overwrite=True`` and a folder holding
files ppamsafety did not write is never used.

**Parallel sections.**  Sections are independent (each computes, renders and
writes its own artifacts), so with ``processes > 1`` they run in that many
worker processes, longest first (the CPU times of the previous report in the
folder's ``metrics.json``, else each section's ``SECTION.typical_seconds``; sections never timed
before go first), and the report is assembled in the order of the sections (``only``, or
:data:`~ppamsafety.sections.REGISTRY`) whatever the completion order.  A new
section needs nothing to benefit.  For the full report, before the sections
start, the workers compile the large kernels between them
(:mod:`ppamsafety.report.warmup`; a task starts once the tasks whose kernels it
calls are done, and the sections once every task has started), so that a cold
kernel cache is not filled by every worker at once.  Each worker runs one BLAS
thread.  A section that starts worker processes of its own (the safety scan, the lambda
sweep) gets its worker's share of the processes, so the report never runs more than
``processes`` at once (``--processes 1``: everything in this process), and the closed-loop
batches of a section run in threads on every core (:func:`~ppamsafety.experiments.run_batch`),
so that the last sections of a report, when the other workers are idle, still use the whole
machine.  A section's warnings are raised again in the main process, naming the section.
``metrics.json`` records each section's wall and CPU time.

**Which sections.**  The report opens with the safety summary (:data:`LEADING`: the arm's
governing verdict per controller family and experiment, on one screen), then the sections in
the order asked for.  The thesis report runs every section.  The report for another arm leaves
out the sections that do not concern it (:func:`select_sections`: the bench case study, the
fit of the thesis' own measurements, the hysteresis studies of an arm without hysteresis) and
says so in its header; ``include`` / ``exclude`` change that selection, ``only`` replaces it.
"""

from __future__ import annotations

import json
import os
import resource
import time
import warnings
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path

import pandas as pd
from threadpoolctl import threadpool_limits

from .._errors import mark_internal
from .._validation import check_int, did_you_mean
from ..impact.head import head_model, resolve_head
from ..output import OutputFolder
from ..params import ArmParameters, is_thesis_arm, thesis_arm
from ..params.arm_file import arm_fingerprint, arm_to_toml
from ..sections import REGISTRY, concerns, run_section, section_infos
from . import warmup
from .columns import unit_of, with_header_units
from .html import report_page


def _cpu_seconds() -> float:
    """CPU time [s] of this process (all its threads) and of its children waited for."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(
        resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def _timed_section(name: str, stage, quick: bool, arm=None, head=None, processes=None):
    """Run one section into ``stage``; (SectionResult, wall time [s], CPU time [s], warnings).

    The CPU time counts every thread of the process that ran the section and the worker
    processes the section started and ended.  The warnings are (message, category) pairs
    naming the section, raised again by the report in the main process (a worker's own
    warnings would print unformatted).  A bug (:func:`ppamsafety._errors.is_internal_error`,
    read from the traceback, which a worker's exception loses on its way to the parent) is
    raised as an ``InternalFailure`` naming the section, so that it is never reported as bad
    input.  Top level: picklable.
    """
    t0, c0 = time.perf_counter(), _cpu_seconds()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            res = run_section(name, stage, quick=quick, arm=arm, head=head,  # compute,
                              processes=processes)                          # render, write
        except TypeError as exc:
            marked = mark_internal(exc, f"report section {name!r}")
            if marked is exc:
                raise
            raise marked from exc
    return (res, time.perf_counter() - t0, _cpu_seconds() - c0,
            [(str(w.message), w.category) for w in caught])


def _run_in_pool(pool, processes: int, order, stage, quick: bool, warm: bool, report,
                 arm=None, head=None, inner=None) -> None:
    """Run the warm-up tasks (if ``warm``) and the sections ``order`` in ``pool``.

    At most ``processes`` jobs run at a time, so that every job submitted starts
    at once.  A free worker takes the first warm-up task of
    :data:`warmup.TASKS <ppamsafety.report.warmup.TASKS>` whose
    :attr:`~ppamsafety.report.warmup.Task.after` tasks have finished; once every
    task has started, it takes the next section of ``order``.  A warm-up task is
    only an optimisation: one that fails is reported as a warning and the
    sections compile what they need themselves.  A section's error is raised here
    (``report(name, result, seconds, cpu_seconds)`` is called for each section that
    finished).
    """
    tasks = warmup.TASKS if warm else ()
    subject = (arm, head)
    finished_tasks, started_tasks = set(), set()
    queue = list(order)
    running = {}                 # future -> ("task", index) or ("section", name)
    while queue or running or len(started_tasks) < len(tasks):
        while len(running) < processes:
            ready = [i for i, t in enumerate(tasks) if t.name not in started_tasks
                     and all(a in finished_tasks for a in t.after)]
            if ready:
                started_tasks.add(tasks[ready[0]].name)
                running[pool.submit(warmup.run_task, ready[0])] = ("task", ready[0])
            elif len(started_tasks) == len(tasks) and queue:
                name = queue.pop(0)
                running[pool.submit(_timed_section, name, stage, quick, *subject,
                                    processes=inner)] = ("section", name)
            else:
                break
        if not running:          # tasks waiting for tasks that never run: a bad TASKS table
            stuck = sorted({t.name for t in tasks} - started_tasks)
            raise RuntimeError(f"report warm-up: tasks {stuck} wait for tasks that are not in "
                               "warmup.TASKS")
        finished, _ = wait(running, return_when=FIRST_COMPLETED)
        for f in finished:
            kind, key = running.pop(f)
            if kind == "section":
                report(key, *f.result())                    # re-raises a section's error
                continue
            finished_tasks.add(tasks[key].name)
            exc = f.exception()
            if exc is not None:
                warnings.warn(f"report warm-up task {tasks[key].name} failed "
                              f"({type(exc).__name__}: {exc}); the sections compile their "
                              "kernels themselves", RuntimeWarning, stacklevel=3)


def _one_blas_thread() -> None:
    """Worker initializer: one BLAS thread per report worker (``threadpoolctl``).

    The workers already keep every core busy; a BLAS thread pool of their own
    only spins on the small matrices of the sections and takes CPU time from
    the other workers (the diagnosis section: 19.1 s of CPU for 16.9 s of wall
    time with OpenBLAS's default two threads, 16.6 s for 16.6 s with one).
    """
    threadpool_limits(limits=1)



def _previous_times(out: Path) -> dict:
    """Section times [s] of the previous report in ``out`` (empty if none or unreadable).

    The CPU time where it was recorded, else the wall time: the CPU time is the section's
    work, whatever else ran on the machine (on a loaded machine a section's wall time was
    measured at 2.3 x its CPU time, and the sections' order by wall time was the load's).
    """
    try:
        prev = json.loads((out / "metrics.json").read_text())
        return {k: float(v.get("cpu_time_s", v["wall_time_s"])) for k, v in prev.items()
                if isinstance(v, dict) and "wall_time_s" in v}
    except (OSError, ValueError, TypeError, KeyError, AttributeError):
        return {}


def _subject_header(quick: bool, arm, head) -> str:
    """The report's first paragraph for a given arm or head: which one, and whether thesis
    values are shown."""
    a = arm or thesis_arm()
    h = head or head_model()
    thesis = is_thesis_arm(a) and h == head_model()
    opts = " ".join(x for x in ("--arm FILE" if arm is not None else "",
                                "--head " + h.name if head is not None else "",
                                "--quick" if quick else "") if x)
    return ("# ppamsafety report\n\n"
            f"Generated by `ppamsafety report {opts}` for the arm **{a.name or 'unnamed arm'}** "
            f"(sha256 {arm_fingerprint(a)[:16]}; its file is `arm.toml`) and the head model "
            f"**{h.name}**{' (`head.toml`)' if head is not None else ''}. Every number below was "
            f"computed by the code in this repository for this arm"
            + (". It has the thesis arm's parameters, so thesis values are quoted for "
               "comparison with their table or equation.\n\n" if thesis else
               "; thesis values and ratios belong to the thesis arm and head and are not "
               "shown.\n\n"))


#: Sections the report opens with, whatever the order asked for: the safety verdict of the arm
#: on one screen.
LEADING = ("safety_summary",)


def first_screen(names) -> list:
    """The sections in report order: :data:`LEADING` first, the others in the order given.

    Parameters
    ----------
    names : list of str
        The sections run.
    """
    return [n for n in LEADING if n in names] + [n for n in names if n not in LEADING]


#: The report's data dictionary: every column of every CSV it wrote, with its unit.
COLUMNS_FILE = "columns.csv"


def column_table(names, results) -> pd.DataFrame:
    """Every column of the CSV files the sections wrote, with its unit and kind.

    Parameters
    ----------
    names : list of str
        The sections, in report order.
    results : dict
        Section -> :class:`~ppamsafety.sections.SectionResult` (its written artifacts).

    Returns
    -------
    pandas.DataFrame
        ``section``, ``file``, ``column``, ``kind`` (``number``, ``text`` or ``flag``) and
        ``unit`` (``-`` dimensionless; empty for text and flags, and where no unit is
        declared: :mod:`ppamsafety.report.columns`).
    """
    rows = []
    for name in names:
        for path in results[name].artifacts:
            if not str(path).endswith(".csv"):
                continue
            try:
                df = pd.read_csv(path)
            except pd.errors.EmptyDataError:       # a table with no rows and no columns
                continue
            for col in df.columns:
                s = df[col]
                kind = ("flag" if pd.api.types.is_bool_dtype(s) else "number"
                        if pd.api.types.is_numeric_dtype(s) and s.notna().any() else "text")
                unit = unit_of(col, name) if kind == "number" else None
                rows.append({"section": name, "file": Path(path).name, "column": col,
                             "kind": kind, "unit": unit or ""})
    return pd.DataFrame(rows, columns=["section", "file", "column", "kind", "unit"])


def _names(option: str, names) -> list:
    """A checked list of section names given to ``option`` (None: [])."""
    if names is None:
        return []
    if isinstance(names, str):
        raise TypeError(f"{option} must be a list of section names, got the str {names!r}")
    names = list(names)
    bad = [n for n in names if not isinstance(n, str)]
    if bad:
        raise TypeError(f"{option} must hold section names (str), got {bad[0]!r}")
    unknown = [n for n in names if n not in REGISTRY]
    if unknown:
        raise ValueError(f"unknown report sections {unknown}"
                         f"{did_you_mean(unknown[0], list(REGISTRY))}; choose from {REGISTRY}")
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ValueError(f"{option} = {names!r} names {twice} more than once; name each "
                         f"section once")
    return names


def select_sections(arm=None, *, only=None, include=None, exclude=None) -> tuple:
    """The sections a report runs for an arm, and those it leaves out with the reason.

    Without ``only``: every section that concerns the arm (:func:`ppamsafety.sections.
    concerns`: all of them for the thesis arm; for another arm not the bench case study, nor
    the fit of the thesis' own measurements, nor the hysteresis studies of an arm without
    hysteresis), plus ``include``, minus ``exclude``, in report order.  ``only`` runs exactly
    the sections it names (whether they concern the arm or not).

    Parameters
    ----------
    arm : ArmParameters, optional
        The arm (None: the thesis arm).
    only, include, exclude : list of str, optional, keyword-only
        Section names (:data:`~ppamsafety.sections.REGISTRY`); ``only`` excludes the others.

    Returns
    -------
    (list of str, dict)
        The sections to run; section -> why it was left out (not asked for).
    """
    if only is not None and (include is not None or exclude is not None):
        raise ValueError("only names every section to run; give include/exclude without it")
    if only is not None:
        names = _names("only", only)
        if not names:
            raise ValueError(f"only = {only!r} names no report section; choose from {REGISTRY}")
        return names, {}
    include, exclude = _names("include", include), _names("exclude", exclude)
    both = sorted(set(include) & set(exclude))
    if both:
        raise ValueError(f"{both} both included and excluded; name each section once")
    names, left = [], {}
    for name in REGISTRY:
        ok, why = concerns(name, arm)
        if name in exclude:
            continue
        if ok or name in include:
            names.append(name)
        else:
            left[name] = why
    if not names:
        raise ValueError(f"exclude = {exclude!r} leaves no report section to run")
    return names, left


def build_report(outdir="reports", *, quick: bool = False, only=None, progress: bool = True,
                 overwrite: bool = False, processes: int | None = None, arm=None,
                 head=None, replace_kind: bool = False, include=None, exclude=None) -> Path:
    """Run the sections and write ``outdir/index.md``, ``index.html``, figures and tables.

    ``index.html`` is the same report as one page with section navigation
    (:func:`ppamsafety.report.html.report_page`).

    Parameters
    ----------
    outdir : path-like
        Report folder.  Created if missing; an existing non-empty folder must be a
        previous ppamsafety output (marker file ``.ppamsafety-output``) holding
        only files ppamsafety wrote, and is replaced only with ``overwrite=True``.
    quick : bool
        Coarser grids and shorter sweeps (for smoke tests).
    only : iterable of str, optional
        Run only these section names (see :data:`ppamsafety.sections.REGISTRY`), whether
        they concern the arm or not.
    progress : bool
        Print one line per section.
    overwrite : bool
        Replace a previous ppamsafety output in ``outdir`` (its toolkit-written
        files only).  If a section fails, the previous report is left untouched.
    processes : int, optional
        Worker processes of the report (default: the CPU count).  Sections run at the same
        time, each in its own worker, at most one per section; a section that runs a sweep
        of its own (the every-instant scan, the lambda sweep) gets the share of the
        processes its worker has (``processes // workers``, at least 1), so that the report
        never runs more than ``processes`` at once.  1 runs the sections one after the other
        in this process.  The report is the same either way.
    arm : ArmParameters, optional
        The arm of every section (default the thesis arm): any valid arm, e.g. from an
        arm file (:func:`ppamsafety.design.load_arm`).  Thesis values and
        ratios appear only for the thesis arm; the sections that do not concern the arm
        are left out unless asked for (:func:`select_sections`).
    head : HeadContactModel, str or path-like, optional
        The head model of the impacts (default ``thesis-frontal``): a model, a name or
        a head file.
    replace_kind : bool
        Allow replacing a previous ppamsafety output of another kind than a report or a
        section (e.g. a sweep folder); refused by default, even with ``overwrite``.
    include, exclude : iterable of str, optional
        Sections added to or removed from the arm's default selection (not with ``only``).

    Returns
    -------
    pathlib.Path
        Path of the written ``index.md``.
    """
    if arm is not None and not isinstance(arm, ArmParameters):
        raise TypeError(f"arm must be an ArmParameters or None, got {type(arm).__name__}")
    names, left_out = select_sections(arm, only=only, include=include, exclude=exclude)
    if processes is None:
        processes = os.cpu_count() or 1
    budget = check_int("processes", processes, 1, 1024)
    processes = min(budget, len(names))
    inner = max(1, budget // processes)     # a section's own sweep: its worker's share
    head = None if head is None else resolve_head(head)
    out = Path(outdir)
    previous = _previous_times(out)
    with OutputFolder(outdir, kind="report", overwrite=overwrite, kinds=("report", "section"),
                      replace_kind=replace_kind) as stage:
        done = {}

        def report(name, res, dt, cpu, caught=()):
            done[name] = (res, dt, cpu)
            for message, category in caught:     # a section's warnings, named (in this process)
                warnings.warn(message, category, stacklevel=2)
            if progress:
                print(f"[report] {name}: {dt:.1f} s ({cpu:.1f} s of CPU), "
                      f"{len(res.artifacts)} artifacts", flush=True)

        if processes == 1:
            for name in names:
                report(name, *_timed_section(name, stage, quick, arm, head, processes=inner))
        else:
            # longest first (never timed: first), so the last to finish is a short one;
            # without a previous report, by the typical times
            times = previous or {n: i.typical_seconds for n, i in section_infos().items()}
            order = sorted(names, key=lambda n: -times.get(n, float("inf")))
            pool = ProcessPoolExecutor(max_workers=processes, initializer=_one_blas_thread)
            try:
                # the full report first compiles the large kernels once, split between the
                # workers (report.warmup)
                _run_in_pool(pool, processes, order, stage, quick, only is None, report,
                             arm, head, inner)
            except BaseException:
                # Ctrl-C or a failed section: stop the other sections now instead of waiting
                # for them (the previous report is left untouched either way)
                workers = list((getattr(pool, "_processes", None) or {}).values())
                pool.shutdown(wait=False, cancel_futures=True)
                for w in workers:
                    if w.is_alive():
                        w.terminate()
                raise
            pool.shutdown(wait=True)
        sections, metrics = [], {}
        for name in first_screen(names):     # the order asked for, the summary first
            res, dt, cpu = done[name]
            metrics[name] = {**res.metrics, "wall_time_s": round(dt, 2),
                             "cpu_time_s": round(cpu, 2)}
            body = with_header_units(res.markdown.strip(), name)
            sections.append(f"## {res.title}\n\n{body}\n\n*Section `{name}` ran in "
                            f"{dt:.1f} s.*\n")
        column_table(names, {n: done[n][0] for n in names}).to_csv(stage / COLUMNS_FILE,
                                                                    index=False)
        header = ("# ppamsafety report\n\nGenerated by `ppamsafety report`"
                  f"{' --quick' if quick else ''}. Every number below was computed by the code in "
                  "this repository; thesis values are quoted for comparison with their table or "
                  "equation.\n\n")
        if arm is not None or head is not None:
            header = _subject_header(quick, arm, head)
            (stage / "arm.toml").write_text(arm_to_toml(arm or thesis_arm()), encoding="utf-8")
            if head is not None:
                (stage / "head.toml").write_text(head.to_toml(), encoding="utf-8")
        if left_out:
            header += ("Left out, as they do not concern this arm (run them with `--include "
                       "NAMES`): " + "; ".join(f"`{n}` ({why})" for n, why in left_out.items())
                       + ".\n\n")
        md = header + "\n".join(sections)
        (stage / "index.md").write_text(md)
        (stage / "index.html").write_text(report_page(md), encoding="utf-8")
        (stage / "metrics.json").write_text(json.dumps(metrics, indent=2, default=float))
    return out / "index.md"
