"""The two decorators used for every compiled kernel.

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

Set the environment variable ``NUMBA_DISABLE_JIT=1`` to run the kernels as
plain Python for debugging.
"""

from numba import njit

kernel = njit(cache=True, error_model="numpy")
leaf = njit(error_model="numpy", inline="always")

__all__ = ["kernel", "leaf"]
