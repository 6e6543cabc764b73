"""Hashes of the package source that the two caches follow: one for results, one for kernels.

* :func:`source_hash` -- every ``*.py`` of the package.  The sweep result cache
  (:mod:`ppamsafety.sweep`) is keyed on it: a cached result may depend on any Python code.
* :func:`kernel_source_hash` -- the files of :data:`KERNEL_FILES`, the interpreter, the
  numba, llvmlite and numpy versions and the numba settings that change machine code.  The
  compiled-kernel cache (:mod:`ppamsafety._jit`) is keyed on it.

Why a list.  numba's own cache notices an edit of a kernel's own file, not of a kernel it
calls in another module nor of a module constant it reads from there (numba freezes global
values at compile time: layout offsets, enum members, module-level arrays).  So the cache
folder is named after a hash of every file compiled code depends on: the modules that define
compiled functions, the modules whose globals they read, and the ``__init__`` of their
packages (run first on import).  Editing any of them compiles every kernel again; editing a
plot, a section, the report, the command line, the sweeps, the diagnosis or the docs
recompiles nothing.

The list is written by hand and checked twice: the decorators of :mod:`ppamsafety._jit`
refuse, at import, a compiled function defined in a file outside it
(:func:`check_kernel_file`), and ``tests/test_kernel_cache.py`` imports the package and
checks that every global every compiled function reads comes from a listed file and keeps
its value when every other module of the package is replaced by a stub.  Adding a kernel
module, or making a kernel read a constant of a new module: add the file here.
"""

from __future__ import annotations

import functools
import hashlib
import sys
from pathlib import Path

_ROOT = Path(__file__).resolve().parent

#: The files compiled code depends on, relative to the package folder (module docstring).
KERNEL_FILES = (
    "__init__.py", "_jit.py", "_sourcehash.py", "_validation.py", "layouts.py", "lstsq.py",
    "units.py",
    "control/__init__.py", "control/dispatch.py", "control/estimation.py", "control/kinds.py",
    "control/reference.py", "control/sensors.py",
    "control/laws/__init__.py", "control/laws/admittance.py", "control/laws/gravity.py",
    "control/laws/pid.py", "control/laws/psmc.py", "control/laws/smc.py",
    "experiments/__init__.py", "experiments/closed_loop.py", "experiments/interaction.py",
    "hysteresis/__init__.py", "hysteresis/dahl.py", "hysteresis/everett.py",
    "hysteresis/force.py", "hysteresis/memory.py", "hysteresis/tensile.py",
    "impact/__init__.py", "impact/clamping.py", "impact/collision.py", "impact/contact.py",
    "impact/engine.py", "impact/hic.py", "impact/layers.py", "impact/points.py",
    "impact/twobody.py",
    "plant/__init__.py", "plant/dynamics.py", "plant/geometry.py", "plant/layout.py",
    "plant/model.py", "plant/muscle.py", "plant/pneumatics.py", "plant/torque.py",
)
#: numba settings (``numba.core.config``) that change the generated machine code but are not
#: part of numba's own cache key (a bounds-checked run once loaded the unchecked machine code
#: of an earlier run from the same folder).
_NUMBA_CODEGEN_SETTINGS = ("OPT", "BOUNDSCHECK", "DEBUGINFO_DEFAULT", "LOOP_VECTORIZE",
                           "SLP_VECTORIZE", "ENABLE_AVX", "USING_SVML", "CPU_NAME",
                           "CPU_FEATURES", "EXTEND_VARIABLE_LIFETIMES", "LLVM_REFPRUNE_PASS",
                           "LLVM_REFPRUNE_FLAGS", "ENABLE_PROFILING")


def source_hash(root=None) -> str:
    """Hex digest (16 characters) of the relative path and bytes of every ``*.py`` of a package.

    Parameters
    ----------
    root : str or path-like, optional
        The package folder; default this package (hashed once per process: a new process
        sees an edit).
    """
    return _hash(_package_root(root), None) if root is not None else _own_hash(None)


def kernel_source_hash(root=None) -> str:
    """Hex digest (16 characters) of what the kernels' machine code depends on (module docstring).

    Parameters
    ----------
    root : str or path-like, optional
        The package folder; default this package (hashed once per process).
    """
    return _hash(_package_root(root), KERNEL_FILES) if root is not None \
        else _own_hash(KERNEL_FILES)


def check_kernel_file(func) -> None:
    """Refuse a compiled function of this package defined in a file outside :data:`KERNEL_FILES`.

    Parameters
    ----------
    func : function
        The Python function about to be compiled.
    """
    path = Path(func.__code__.co_filename).resolve()
    if _ROOT in path.parents and path.relative_to(_ROOT).as_posix() not in KERNEL_FILES:
        raise ImportError(f"{func.__module__}.{func.__qualname__} is compiled in "
                          f"{path.relative_to(_ROOT).as_posix()}, which is not in "
                          f"ppamsafety._sourcehash.KERNEL_FILES: add the file there, or the "
                          f"kernel cache would not notice an edit of it")


@functools.lru_cache(maxsize=2)
def _own_hash(files) -> str:
    return _hash(_ROOT, files)


def _hash(root: Path, files) -> str:
    paths = sorted(root.rglob("*.py")) if files is None else [root / f for f in sorted(files)]
    h = hashlib.sha1()
    if files is not None:
        h.update(b"ppamsafety kernel key 3\0")
        for name, value in _machine_code_environment():
            h.update(f"{name}={value}\0".encode())
    for f in paths:
        b = f.read_bytes()
        rel = f.relative_to(root).as_posix()
        h.update(f"{rel}\0{len(b)}\0".encode() if files is not None else rel.encode())
        h.update(b)
    return h.hexdigest()[:16]


def _machine_code_environment() -> list:
    """(name, value) pairs outside the source that change the kernels' machine code."""
    # deferred on purpose: this bottom-layer module is imported by every command, `--help`
    # included, and numba takes 1.5 s to import; only a kernel key needs it
    import llvmlite
    import numba
    import numpy
    from numba.core import config

    return [("python", f"{sys.implementation.name} {sys.version}"),
            ("numba", numba.__version__), ("llvmlite", llvmlite.__version__),
            ("numpy", numpy.__version__)] + [
        (f"numba.config.{s}", repr(getattr(config, s, None))) for s in _NUMBA_CODEGEN_SETTINGS]


def _package_root(root) -> Path:
    """``root`` as a resolved package folder; ValueError if it is not one."""
    root = Path(root).resolve()
    if not (root / "__init__.py").is_file():
        raise ValueError(f"root must be a package folder holding __init__.py, got {root}")
    return root


__all__ = ["KERNEL_FILES", "check_kernel_file", "kernel_source_hash", "source_hash"]
