"""Case functions for the sweep tests that run in other processes (subprocess, dask workers).

Importable as ``sweep_helpers`` from the tests folder (pytest puts it on sys.path; the
subprocess and the dask workers get it through sys.path too), so a function has the same
name, source and cache key in every process.
"""

import os
import time


def slow_square(x, calls_dir):
    """x**2 after 0.2 s; leaves one marker file per computation in ``calls_dir``."""
    with open(os.path.join(calls_dir, f"x{x}-pid{os.getpid()}-{time.monotonic_ns()}"), "w"):
        pass
    time.sleep(0.2)
    return {"y": x * x}


def counted(x, calls_dir):
    """x + 1, failing for x == 3; one marker file per computation in ``calls_dir``."""
    with open(os.path.join(calls_dir, f"x{x}-pid{os.getpid()}-{time.monotonic_ns()}"), "w"):
        pass
    if x == 3:
        raise ValueError("x = 3 is refused")
    return {"y": x + 1}


def calls_of(calls_dir) -> dict:
    """x -> number of computations recorded in ``calls_dir``."""
    out = {}
    for f in os.listdir(calls_dir):
        x = int(f.split("-")[0][1:])
        out[x] = out.get(x, 0) + 1
    return out
