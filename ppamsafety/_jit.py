"""The two decorators used for every compiled kernel, and where they are cached.

* :data:`kernel` -- ``numba.njit`` with on-disk caching (compiled once per
  machine, reused by later processes and by sweep workers) and numpy's
  floating-point error model (division by zero gives inf/nan instead of
  raising; kernels validate their inputs instead).
* :data:`nogil_kernel` -- a :data:`kernel` that releases the GIL, for the batch
  kernels that :func:`run_threaded` runs in several threads at once (the closed-loop
  batch of :func:`~ppamsafety.experiments.run_batch`): each thread runs a contiguous
  range of the batch's rows, and every row writes only its own outputs, so the result
  is bitwise the same for any number of threads.
* :data:`leaf` -- the same as :data:`kernel`, additionally inlined into every caller at the
  numba IR level.  Each call site is then typed and lowered again, which is
  what makes first compilations slow (the dense impact engine took 45 s with
  its derivative inlined at 14 call sites).  A plain kernel called from
  another kernel is compiled once, and LLVM still inlines it when it is small
  (measured: a scalar helper with array arguments runs as fast either way),
  but not when it is large: with every leaf a plain kernel, 10 s of open-loop
  plant took 0.040 s instead of 0.023 s and the SMC study 80 % longer, and a
  non-inlined impact derivative in the RK4 step cost 11 %.  So: ``leaf`` for
  the plant and controller helpers inside the RK4 step and the controller
  step, ``kernel`` for the rest (the sensor models, the once-per-period
  effect helpers, the impact, collision, clamping and HIC helpers);
  where a large function is hot in one place only, compile one source both
  ways (``engine._impact_rhs_inline`` inside the RK4 step, ``impact_rhs``
  elsewhere).

Cache location.  numba invalidates a cached function only when *its own*
source file changes, not when a kernel it calls in another module does (nor a
module constant it reads from there, such as a layout offset), so a stale
cache could silently run old physics after an edit.  The cache therefore
lives in a folder named after :func:`~ppamsafety._sourcehash.kernel_source_hash`
(``~/.cache/ppamsafety/numba-<key>``, or ``$PPAMSAFETY_CACHE_DIR/numba-<key>``):
a hash of the files compiled code depends on (the explicit list
:data:`~ppamsafety._sourcehash.KERNEL_FILES`; both decorators refuse a function
defined in a file outside it), of the Python, numba, llvmlite and numpy versions,
and of the numba settings that change machine code (``NUMBA_BOUNDSCHECK``,
``NUMBA_OPT`` ...).  An edit of any of those files gives a fresh folder, and
every kernel compiles again; an edit of a plot, a report section, the report,
the command line, the sweeps or the docs keeps the folder.

Each process holds a shared lock on its folder (``.ppamsafety-in-use``) and
touches it, and then deletes the folders of other keys beyond the
:data:`KEEP_CACHES` most recently used (:func:`_prune_caches`): only
``numba-<16 hex digits>`` folders holding nothing but numba cache files, not
used for :data:`MIN_AGE`, and only when no running process holds their lock
(a failed deletion is a warning, never an error).  Without ``fcntl``
(Windows) nothing is deleted.  An explicit ``NUMBA_CACHE_DIR`` set by the
user is respected (no key, no pruning).

Set ``NUMBA_DISABLE_JIT=1`` to run the kernels as plain Python for debugging.
"""

import os
import re
import shutil
import threading
import time
import warnings
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait

import numba
import numpy as np
from numba import njit

from ._sourcehash import check_kernel_file, kernel_source_hash

try:
    import fcntl
except ImportError:          # Windows: no advisory locks, so old caches are never deleted
    fcntl = None

#: Kernel cache folders kept under the cache root (the current one included): the most
#: recently used, e.g. the current branch, another worktree and the previous edit.
KEEP_CACHES = 3
#: Kernel cache folders used less than this long ago are never deleted [s]: protects a
#: process that does not hold the folder's lock (an older version, a file system without
#: locks) while it runs.
MIN_AGE = 3600.0
#: Names of the kernel cache folders (the key is 16 hex digits).
_CACHE_NAME = re.compile(r"numba-[0-9a-f]{16}")
#: Files numba writes into a cache folder: index, data, and their temporary files.
_NUMBA_FILE = re.compile(r".+\.nb[ic](\.tmp\.[0-9a-f]+)?")
#: Lock file of a cache folder: shared by each process using the folder.
_IN_USE = ".ppamsafety-in-use"
#: Open descriptor of the lock file of this process' folder (held until the process exits).
_held_lock = None


def _cache_root() -> str:
    """Folder of the kernel cache folders: ``$PPAMSAFETY_CACHE_DIR`` or ``~/.cache/ppamsafety``."""
    return os.environ.get("PPAMSAFETY_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "ppamsafety")


def _configure_cache() -> None:
    """Point numba's cache at ``<cache root>/numba-<key>`` and delete old folders of other keys."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    base = _cache_root()
    try:
        os.makedirs(base, exist_ok=True)
    except OSError:          # read-only home: fall back to numba's default locations
        return
    key = kernel_source_hash()
    path = os.path.join(base, f"numba-{key}")
    try:
        _use_folder(path)
    except OSError:          # not writable: fall back to numba's default locations
        return
    numba.config.CACHE_DIR = path
    _prune_caches(base, path)


def _same_file(fd: int, path: str) -> bool:
    """Whether ``path`` still names the open file ``fd`` (False once its folder was deleted)."""
    try:
        a, b = os.fstat(fd), os.stat(path)
    except FileNotFoundError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def _use_folder(path: str) -> None:
    """Create the cache folder ``path`` if needed, hold its shared lock, and touch it.

    A process pruning old folders deletes one only while holding its lock
    exclusively; if it deleted ``path`` between this process creating it and
    taking the lock, the folder is created again.

    Parameters
    ----------
    path : str
        The cache folder.
    """
    global _held_lock
    for _ in range(10):
        os.makedirs(path, exist_ok=True)
        if fcntl is None:
            break
        lock = os.path.join(path, _IN_USE)
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        except FileNotFoundError:        # deleted by a pruner since makedirs: again
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_SH)   # waits only while a pruner deletes the folder
        except OSError:      # no locks on this file system: unprotected, but nobody prunes it
            os.close(fd)
            break
        if _same_file(fd, lock):
            if _held_lock is not None:
                os.close(_held_lock)
            _held_lock = fd
            break
        os.close(fd)                     # deleted while this process waited: again
    else:
        warnings.warn(f"kernel cache {path}: could not lock it (deleted 10 times while "
                      "locking); using it unprotected", RuntimeWarning, stacklevel=2)
    try:
        os.utime(path)                   # most recently used: kept by every pruner
    except OSError as exc:
        warnings.warn(f"kernel cache {path}: could not mark it used ({exc}); it may be "
                      "deleted by another process", RuntimeWarning, stacklevel=2)


def _holds_only_numba_files(path: str) -> bool:
    """Whether every entry under ``path`` is a numba cache file, our lock file or a folder.

    Symbolic links and any other file make it False: such a folder was not
    made by this module and is never deleted.
    """
    def fail(exc):
        raise exc

    for dirpath, dirnames, filenames in os.walk(path, onerror=fail):
        for name in dirnames + filenames:
            if os.path.islink(os.path.join(dirpath, name)):
                return False
        if not all(f == _IN_USE or _NUMBA_FILE.fullmatch(f) for f in filenames):
            return False
    return True


def _remove_if_unused(path: str) -> bool:
    """Delete the cache folder ``path`` unless a process holds its lock or it holds other files.

    Parameters
    ----------
    path : str
        A ``numba-<key>`` folder.

    Returns
    -------
    bool
        Whether it was deleted.
    """
    try:
        if not _holds_only_numba_files(path):
            return False
        lock = os.path.join(path, _IN_USE)
        fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
    except FileNotFoundError:            # deleted by another process meanwhile
        return False
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False                 # in use by a running process
        if not _same_file(fd, lock):     # deleted by another pruner meanwhile
            return False
        shutil.rmtree(path)
        return True
    finally:
        os.close(fd)


def _last_used(path: str) -> float:
    """Latest modification time [s since the epoch] of the folder ``path`` and its subfolders.

    A process touches its folder when it starts (:func:`_use_folder`), and
    numba writes its files into subfolders (one per source folder), whose
    times therefore also follow processes that do not touch the folder.
    """
    t = os.stat(path, follow_symlinks=False).st_mtime
    with os.scandir(path) as it:
        for e in it:
            if e.is_dir(follow_symlinks=False):
                t = max(t, e.stat(follow_symlinks=False).st_mtime)
    return t


def _prune_caches(base: str, current: str, keep: int = KEEP_CACHES,
                  min_age: float = MIN_AGE) -> list:
    """Delete the kernel cache folders under ``base`` but ``current`` and the most recently used.

    Only folders named ``numba-<16 hex digits>`` (not symbolic links) holding
    nothing but numba cache files are candidates.  Of them the ``keep - 1``
    most recently used (:func:`_last_used`) are kept besides ``current``, and
    so is every folder used less than ``min_age`` ago or whose lock a running
    process holds.  Never raises for a file system error: a folder that cannot
    be read or deleted is a ``RuntimeWarning``.  Without ``fcntl`` nothing is
    deleted.

    Parameters
    ----------
    base : str
        The cache root.
    current : str
        This process' folder (kept).
    keep : int
        Folders kept, ``current`` included (>= 1).
    min_age : float
        Folders used less than this long ago are kept [s] (>= 0).

    Returns
    -------
    list of str
        The deleted folders.
    """
    if isinstance(keep, bool) or not isinstance(keep, int) or keep < 1:
        raise ValueError(f"keep must be an int >= 1, got {keep!r}")
    if not (isinstance(min_age, (int, float)) and min_age >= 0):
        raise ValueError(f"min_age must be a number >= 0 [s], got {min_age!r}")
    if fcntl is None:
        return []
    candidates = []
    try:
        with os.scandir(base) as it:
            entries = [e for e in it if _CACHE_NAME.fullmatch(e.name)
                       and e.name != os.path.basename(current)
                       and e.is_dir(follow_symlinks=False)]
    except OSError as exc:
        warnings.warn(f"could not list the kernel caches in {base}: {exc}", RuntimeWarning,
                      stacklevel=2)
        return []
    for e in entries:
        try:
            candidates.append((-_last_used(e.path), e.name, e.path))
        except FileNotFoundError:        # deleted by another process meanwhile
            continue
        except OSError as exc:
            warnings.warn(f"could not read the kernel cache {e.path}: {exc}", RuntimeWarning,
                          stacklevel=2)
    removed, now = [], time.time()
    for minus_t, _, path in sorted(candidates)[keep - 1:]:
        if now + minus_t < min_age:
            continue
        try:
            if _remove_if_unused(path):
                removed.append(path)
        except OSError as exc:
            warnings.warn(f"could not delete the old kernel cache {path}: {exc}",
                          RuntimeWarning, stacklevel=2)
    return removed


_configure_cache()

_compile = njit(cache=True, error_model="numpy")
_compile_inline = njit(cache=True, error_model="numpy", inline="always")
_compile_nogil = njit(cache=True, error_model="numpy", nogil=True)
_compile_step = njit(cache=True, error_model="numpy", _nrt=False)


def kernel(func):
    """Compile ``func`` with numba, cached on disk, numpy's error model (module docstring).

    Parameters
    ----------
    func : function
        Defined in a file of :data:`~ppamsafety._sourcehash.KERNEL_FILES` (else ImportError).
    """
    check_kernel_file(func)
    return _compile(func)


def leaf(func):
    """:func:`kernel`, and inlined into every compiled caller at the numba IR level.

    Parameters
    ----------
    func : function
        Defined in a file of :data:`~ppamsafety._sourcehash.KERNEL_FILES` (else ImportError).
    """
    check_kernel_file(func)
    return _compile_inline(func)


def nogil_kernel(func):
    """:func:`kernel` that releases the GIL, so that :func:`run_threaded` runs it on every core.

    Parameters
    ----------
    func : function
        Defined in a file of :data:`~ppamsafety._sourcehash.KERNEL_FILES` (else ImportError).
    """
    check_kernel_file(func)
    return _compile_nogil(func)


def step_kernel(func):
    """:func:`kernel` without numba's reference counting (no array is made or freed inside).

    For the per-step kernels of the closed loop, called millions of times.

    Parameters
    ----------
    func : function
        Defined in a file of :data:`~ppamsafety._sourcehash.KERNEL_FILES` (else ImportError).
    """
    check_kernel_file(func)
    return _compile_step(func)

#: Parts per thread a batch is cut into by :func:`run_threaded`: a thread that finishes its
#: part early takes the next, so rows of unequal cost still share the cores evenly.
PARTS_PER_THREAD = 4
#: Threads of :func:`run_threaded` when none are given (None: every core this process may
#: use, :func:`available_cores`); set with :func:`set_default_threads`.
_default_threads = [None]
#: The thread pool of this process: (process id, pool, threads), made on first use (a pool
#: made before a ``fork`` has no threads in the child, so the child makes its own).
_pool = [None, None, 0]
_pool_lock = threading.Lock()


def available_cores() -> int:
    """Cores this process may run on (its CPU affinity; the CPU count where there is none)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def set_default_threads(threads) -> None:
    """Set the threads of :func:`run_threaded` when a call gives none (None: every core).

    The report's worker processes, which already keep every core busy with a section each,
    may lower it; a library user rarely needs it (``threads=`` of the batch functions).

    Parameters
    ----------
    threads : int or None
        Threads, >= 1, or None for :func:`available_cores`.
    """
    if threads is not None and (isinstance(threads, bool) or not isinstance(threads, int)
                                or threads < 1):
        raise ValueError(f"threads must be an int >= 1 or None, got {threads!r}")
    _default_threads[0] = threads


def default_threads() -> int:
    """Threads of :func:`run_threaded` when a call gives none (:func:`set_default_threads`)."""
    return _default_threads[0] or available_cores()


def _thread_pool(threads: int) -> ThreadPoolExecutor:
    """This process' pool with at least ``threads`` threads (made, or grown, here)."""
    with _pool_lock:
        pid, pool, size = _pool
        if pool is None or pid != os.getpid() or size < threads:
            if pool is not None and pid == os.getpid():
                pool.shutdown(wait=False)
            pool = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="ppamsafety")
            _pool[:] = [os.getpid(), pool, threads]
        return pool


def run_threaded(func, n: int, threads=None) -> None:
    """Call ``func(first, last)`` over consecutive ranges covering ``range(n)``, in threads.

    ``func`` calls a :data:`nogil_kernel` on the rows ``first <= b < last`` of a batch;
    the rows must be independent (each writes only its own outputs), so the result does
    not depend on the number of threads.  With one thread, or one row, ``func(0, n)`` runs
    in the calling thread.  Otherwise the rows are cut into about
    :data:`PARTS_PER_THREAD` parts per thread, handed out in order to the first free thread.
    An exception in a part (or Ctrl-C) cancels the parts not yet started and is raised once
    the running ones have finished.

    Parameters
    ----------
    func : callable
        ``func(first, last)``.
    n : int
        Rows of the batch, >= 0.
    threads : int, optional
        Threads (default :func:`default_threads`); never more than ``n`` are used.
    """
    threads = default_threads() if threads is None else threads
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads must be an int >= 1, got {threads!r}")
    threads = min(threads, n)
    if threads <= 1:
        if n > 0:
            func(0, n)
        return
    parts = min(n, threads * PARTS_PER_THREAD)
    edges = [n * i // parts for i in range(parts + 1)]
    pool = _thread_pool(threads)
    futures = [pool.submit(func, a, b) for a, b in zip(edges[:-1], edges[1:])]
    try:
        done, _ = wait(futures, return_when=FIRST_EXCEPTION)
        for f in done:
            f.result()                                   # raises the first error
    except BaseException:
        for f in futures:
            f.cancel()
        wait(futures)                                    # running parts write into our arrays
        raise


def kernel_array(a) -> np.ndarray:
    """``a`` as the one array type the kernels are compiled for: float64, C-contiguous, writable.

    numba compiles a kernel once per argument *type*, and a read-only row (the
    cached ``plant.layout.pack(arm)``) or a Fortran-ordered or strided array
    is a different type from a writable C-contiguous one: passing both
    compiles the kernel, and every kernel it calls, a second time (1-3 s
    each for the small kernels, measured).  Python functions call their
    kernels with this.  Copies only when ``a`` is not already of that type.

    Parameters
    ----------
    a : array_like
        Values (already validated by the caller).

    Returns
    -------
    numpy.ndarray
    """
    return np.require(a, np.float64, ["C_CONTIGUOUS", "WRITEABLE", "ALIGNED"])


__all__ = ["available_cores", "default_threads", "kernel", "kernel_array", "leaf", "nogil_kernel",
           "run_threaded", "set_default_threads"]
