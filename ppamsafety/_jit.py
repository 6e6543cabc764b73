"""The two decorators used for every compiled kernel, and where they are cached.

* :data:`kernel` -- ``numba.njit`` with on-disk caching (compiled once per
  machine, reused by later processes and by sweep workers) and numpy's
  floating-point error model (division by zero gives inf/nan instead of
  raising; kernels validate their inputs instead).
* :data:`leaf` -- the same for small scalar helpers, additionally inlined
  into their callers at the numba IR level.  Cached numba functions are
  otherwise called through a function pointer, which for helpers of a few
  dozen flops costs more than the work itself (measured: the four muscle
  lever arms took 160 ns per evaluation as separate functions, 27 ns
  inlined).

Cache location.  numba invalidates a cached function only when *its own*
source file changes, not when a kernel it calls in another module does, so a
stale cache could silently run old physics after an edit.  The cache
therefore lives in a directory named after a hash of every source file of
the package (``~/.cache/ppamsafety/numba-<hash>``, or
``$PPAMSAFETY_CACHE_DIR/numba-<hash>``): any edit gives a fresh cache.  An
explicit ``NUMBA_CACHE_DIR`` set by the user is respected.

Set ``NUMBA_DISABLE_JIT=1`` to run the kernels as plain Python for debugging.
"""

import os

import numba
import numpy as np
from numba import njit

from ._sourcehash import source_hash as _source_hash


def _configure_cache() -> None:
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    base = os.environ.get("PPAMSAFETY_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "ppamsafety")
    path = os.path.join(base, f"numba-{_source_hash()}")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:          # read-only home: fall back to numba's default locations
        return
    numba.config.CACHE_DIR = path


_configure_cache()

kernel = njit(cache=True, error_model="numpy")
leaf = njit(cache=True, error_model="numpy", inline="always")


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


__all__ = ["kernel", "kernel_array", "leaf"]
