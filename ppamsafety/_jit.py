"""The two decorators used for every compiled kernel, and where they are cached.

* :data:`kernel` -- ``numba.njit`` with on-disk caching (compiled once per
  machine, reused by later processes and by sweep workers) and numpy's
  floating-point error model (division by zero gives inf/nan instead of
  raising; kernels validate their inputs instead).
* :data:`leaf` -- the same, additionally inlined into every caller at the
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
