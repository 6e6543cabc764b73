"""The compiled-kernel cache key (issue 23.1) and the pruning of old cache folders (23.2).

The key tests edit a temporary copy of the package source, never the package itself: the key
is computed from a source tree (``kernel_source_hash(root)``), nothing is imported from it.
The rules of the analysis are checked on small made-up packages; two subprocess tests check
it against the imported package (what the compiled functions actually read).
"""

from __future__ import annotations

import ast
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

import ppamsafety
from ppamsafety import _jit
from ppamsafety._sourcehash import kernel_dependencies, kernel_source_hash, source_hash

PACKAGE = Path(ppamsafety.__file__).resolve().parent


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """A folder of stored per-file analyses shared by the tests (each copy parses only its
    edited files)."""
    return tmp_path_factory.mktemp("kernel-deps")


@pytest.fixture
def tree(tmp_path):
    """A copy of the package source, to edit."""
    root = tmp_path / PACKAGE.name
    shutil.copytree(PACKAGE, root, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return root


def _file(root: Path, module) -> Path:
    """The file of ``module`` (an imported module of the package) in the copy ``root``."""
    return root / Path(module.__file__).resolve().relative_to(PACKAGE)


def _rel(root: Path, module) -> str:
    """The key's name of the file of ``module`` (``ppamsafety/plant/layout.py``)."""
    return _file(root, module).relative_to(root.parent).as_posix()


def _insert_after(path: Path, lineno: int, text: str) -> None:
    lines = path.read_text().splitlines(keepends=True)
    lines.insert(lineno, text + "\n")
    path.write_text("".join(lines))


def _definition(path: Path, name: str, cls: str | None = None):
    """The module-level function or class ``name`` of ``path`` (a method of class ``cls``)."""
    body = ast.parse(path.read_text()).body
    if cls is not None:
        body = next(n for n in body if isinstance(n, ast.ClassDef) and n.name == cls).body
    return next(n for n in body if isinstance(n, (ast.FunctionDef, ast.ClassDef))
                and n.name == name)


def _edit_function(path: Path, name: str, cls: str | None = None) -> None:
    """Insert a statement before the last statement of function ``name`` (a method of
    ``cls``)."""
    last = _definition(path, name, cls).body[-1]
    _insert_after(path, last.lineno - 1, " " * last.col_offset + "_edited = 1.0  # test edit")


def _shift_constant(path: Path, name: str) -> None:
    """Shift the module-level constant ``name`` by one, right after the statement defining it."""
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.Assign) and name in {
                n.id for t in node.targets for n in ast.walk(t) if isinstance(n, ast.Name)}:
            _insert_after(path, node.end_lineno, f"{name} = {name} + 1  # test edit")
            return
    raise AssertionError(f"no module-level assignment of {name} in {path}")


def _replace(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert text.count(old) == 1, (path, old)
    path.write_text(text.replace(old, new))


# --- (a) edits of what the kernels need change the key --------------------------------------


def test_editing_a_callee_in_another_module_changes_the_key(tree, store):
    """The controller step (control/dispatch.py) calls the PID step of control/laws/pid.py."""
    from ppamsafety.control import dispatch
    from ppamsafety.control.laws import pid

    assert dispatch.pid_step is pid.pid_step and dispatch.__file__ != pid.__file__
    before = kernel_source_hash(tree, store)
    _edit_function(_file(tree, pid), "pid_step")
    assert kernel_source_hash(tree, store) != before


def test_editing_a_layout_offset_or_field_read_by_kernels_changes_the_key(tree, store):
    """plant/layout.py defines no kernel: it holds the offsets of the plant row (made from its
    Fields) that the plant kernels import and numba freezes at compile time."""
    from ppamsafety.plant import layout, muscle

    deps = kernel_dependencies(tree, store)
    assert layout.__name__ not in deps.kernel_modules and _rel(tree, layout) in deps.files
    assert muscle.__name__ in deps.kernel_modules and muscle.COEF == layout.COEF
    before = kernel_source_hash(tree, store)
    _shift_constant(_file(tree, layout), "COEF")
    shifted = kernel_source_hash(tree, store)
    assert shifted != before
    _replace(_file(tree, layout), 'Field("X11", 1,', 'Field("X11", 2,')
    assert kernel_source_hash(tree, store) not in (before, shifted)


def test_editing_the_function_a_constant_is_computed_with_changes_the_key(tree, store):
    """The offsets of every law's row are computed by ``Layout.offsets`` of layouts.py."""
    from ppamsafety import layouts

    before = kernel_source_hash(tree, store)
    _edit_function(_file(tree, layouts), "offsets", cls="Layout")
    assert kernel_source_hash(tree, store) != before


@pytest.mark.parametrize("module", [
    "ppamsafety.layouts", "ppamsafety._jit", "ppamsafety.__init__", "ppamsafety.units",
    "ppamsafety.control.kinds", "ppamsafety.control.laws.__init__",
    "ppamsafety.hysteresis.memory", "ppamsafety.experiments.__init__"])
def test_editing_what_the_kernels_need_changes_the_key(tree, store, module):
    """The layout machinery, the decorators, a constant a kernel reads from another module
    (``units.G0``), the controller kinds (an IntEnum the dispatch compares with), the parent
    packages' ``__init__`` (run before their modules), a kernel module."""
    import importlib

    before = kernel_source_hash(tree, store)
    path = _file(tree, importlib.import_module(module.removesuffix(".__init__")))
    path.write_text(path.read_text() + "\n# test edit\n")
    assert kernel_source_hash(tree, store) != before


def test_numba_settings_change_the_key(tree, store, monkeypatch):
    """numba's own cache ignores NUMBA_BOUNDSCHECK: a bounds-checked run must not load code
    compiled without the checks."""
    from numba.core import config

    before = kernel_source_hash(tree, store)
    monkeypatch.setattr(config, "BOUNDSCHECK", not config.BOUNDSCHECK)
    assert kernel_source_hash(tree, store) != before


# --- (b) edits no kernel can see keep it ---------------------------------------------------


def test_the_key_holds_the_kernels_needs_and_not_the_rest(tree, store):
    """The expected members on the current tree; plots, sections, the report, the CLI, the
    sweeps and the diagnosis are out, though kernel modules import plots at module level."""
    deps = kernel_dependencies(tree, store)
    files = set(deps.files)
    for rel in ("ppamsafety/_jit.py", "ppamsafety/layouts.py", "ppamsafety/control/dispatch.py",
                "ppamsafety/control/laws/pid.py", "ppamsafety/hysteresis/memory.py",
                "ppamsafety/plant/layout.py", "ppamsafety/plant/model.py",
                "ppamsafety/impact/engine.py", "ppamsafety/experiments/closed_loop.py"):
        assert rel in files, rel
    for prefix in ("ppamsafety/plots/", "ppamsafety/sections/", "ppamsafety/report/",
                   "ppamsafety/diagnose/", "ppamsafety/studies/", "ppamsafety/cli.py",
                   "ppamsafety/study_files.py", "ppamsafety/sweep_cases.py",
                   "ppamsafety/sweep.py", "ppamsafety/impact/model.py"):
        assert not [f for f in files if f.startswith(prefix)], prefix
    assert "ppamsafety.plant.model:rk4_step" in deps.kernels
    assert "ppamsafety.impact.engine:impact_rhs" in deps.kernels      # impact_rhs = kernel(f)
    assert not deps.fallbacks, deps.fallbacks
    assert len(files) <= 80, len(files)         # the module-level closure had 144


def test_editing_plots_sections_the_cli_and_studies_keeps_the_key(tree, store):
    """Every file outside the key edited at once: among them a plot module that a kernel
    module imports at module level (experiments/closed_loop.py imports plots/control.py), a
    report section, the command line, a module calling kernels; the sweep key still
    changes."""
    from ppamsafety import cli, study_files, sweep_cases
    from ppamsafety.experiments import closed_loop
    from ppamsafety.impact import model
    from ppamsafety.plots import control as plots_control
    from ppamsafety.plots import impact as plots_impact
    from ppamsafety.report import build
    from ppamsafety.sections import safety

    deps = kernel_dependencies(tree, store)
    outside = sorted({p.relative_to(tree.parent).as_posix() for p in tree.rglob("*.py")}
                     - set(deps.files))
    assert _rel(tree, closed_loop) in deps.files
    assert closed_loop.plot_experiment is plots_control.plot_experiment
    for m in (cli, build, safety, plots_control, plots_impact, model, study_files, sweep_cases):
        assert _rel(tree, m) in outside, m.__name__
    before, sweep_before = kernel_source_hash(tree, store), source_hash(tree)
    for rel in outside:
        path = tree.parent / rel
        path.write_text(path.read_text() + "\n# test edit\n")
    _edit_function(_file(tree, plots_control), "plot_experiment")
    _edit_function(_file(tree, model), "plot", cls="ImpactResults")   # a .plot() method
    assert kernel_source_hash(tree, store) == before
    assert source_hash(tree) != sweep_before


def test_the_key_ignores_files_that_are_not_python(tree, store):
    before = kernel_source_hash(tree, store)
    (tree / "notes.txt").write_text("x")
    (tree / "plant" / "README.md").write_text("x")
    assert kernel_source_hash(tree, store) == before


# --- (c) the rules, on small packages ---------------------------------------------------------


_SMALL = {
    "__init__.py": "",
    "_jit.py": "import numba\nkernel = numba.njit(cache=True)\n",
    "base.py": "N = 3\n\ndef unused():\n    return 1\n",
    "helper.py": "def make(n):\n    return tuple(range(n))\n",
    "consts.py": ("from .base import N\nfrom . import helper\nfrom .rows import Row\n"
                  "ROW = Row(('a', 'b'))\nOFFSET = ROW.offset('b') + N\n"
                  "TABLE = helper.make(N)\nOTHER = 7\nGROUP = (OTHER, [TABLE])\n"),
    "rows.py": ("from .position import position\n\nclass Row:\n    def __init__(self, names):\n"
                "        self.names = names\n\n    def offset(self, name):\n"
                "        return position(self.names, name)\n"),
    "position.py": "def position(names, name):\n    return names.index(name)\n",
    "reexport.py": "from .core.callee import h\n",
    "figures.py": "def draw(x):\n    return x\n",
    "kinds.py": "from enum import IntEnum\n\nclass Kind(IntEnum):\n    A = 0\n    B = 1\n",
    "core/__init__.py": "",
    "core/callee.py": ("from .._jit import kernel\n\n@kernel\ndef h(x):\n    return x\n\n"
                       "def python_only():\n    return 2\n"),
    "core/k.py": ("from .._jit import kernel\nfrom .. import consts as c\n"
                  "from ..figures import draw\nfrom ..kinds import Kind\n"
                  "from ..reexport import h\n\n"
                  "@kernel\ndef f(x):\n    return h(x[c.OFFSET]) + c.TABLE[0] + Kind.B\n\n"
                  "class Result:\n    def plot(self):\n        return draw(self)\n"),
    "study.py": "from .core.k import f, Result\n\ndef run():\n    return f\n",
}


def _small_package(tmp_path, files=None, name="small", extra=None):
    root = tmp_path / name
    for rel, text in {**(_SMALL if files is None else files), **(extra or {})}.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    return root


def _changes(root: Path, rel: str, text: str = "\n# edit\n") -> bool:
    """Whether appending ``text`` to ``rel`` changes the key of the package at ``root``."""
    before = kernel_source_hash(root)
    path = root / rel
    path.write_text(path.read_text() + text)
    return kernel_source_hash(root) != before


def test_name_level_rules_on_a_small_package(tmp_path):
    root = _small_package(tmp_path)
    deps = kernel_dependencies(root)
    assert deps.kernels == ("small._jit:kernel", "small.core.callee:h", "small.core.k:f")
    assert deps.kernel_modules == ("small._jit", "small.core.callee", "small.core.k")
    # the callee's module and the module it is imported through, the constants and what
    # they are made from (base.N, helper.make, the Row class and the function its method
    # calls), the enum, the parent packages; not the figure module nor the study
    assert deps.files == tuple(f"small/{f}" for f in (
        "__init__.py", "_jit.py", "base.py", "consts.py", "core/__init__.py", "core/callee.py",
        "core/k.py", "helper.py", "kinds.py", "position.py", "reexport.py", "rows.py"))
    assert deps.packages == ("numba",) and not deps.fallbacks
    assert _changes(root, "helper.py", "\ndef make(n):\n    return tuple(range(n + 1))\n")
    assert not _changes(root, "figures.py") and not _changes(root, "study.py")


def test_a_module_level_statement_of_a_needed_module_counts(tmp_path):
    """A call, an ``if`` block binding a name, an ``assert``: counted, with what they read."""
    root = _small_package(tmp_path, extra={
        "consts.py": _SMALL["consts.py"] + ("from .registry import register\nregister(OFFSET)\n"
                                            "from . import flags\nif flags.FAST:\n"
                                            "    OTHER = 8\nfrom . import checks\n"
                                            "assert checks.ok()\n"),
        "registry.py": "SEEN = []\n\ndef register(x):\n    SEEN.append(x)\n",
        "flags.py": "FAST = True\n",
        "checks.py": "def ok():\n    return True\n"})
    files = kernel_dependencies(root).files
    assert {"small/registry.py", "small/flags.py", "small/checks.py"} <= set(files)
    assert _changes(root, "flags.py")


def test_a_write_on_import_into_what_kernels_read_counts(tmp_path):
    """A module outside the compiled code that stores into a needed object when imported:
    counted, whatever the type of the object (the analysis does not know types)."""
    extra = {"figures.py": "from . import consts\nconsts.OTHER = 1\n\ndef draw(x):\n    return x\n"}
    root = _small_package(tmp_path, extra=extra)
    assert "small/figures.py" not in kernel_dependencies(root).files     # OTHER: not read
    extra["figures.py"] = extra["figures.py"].replace("consts.OTHER = 1", "consts.OFFSET = 1")
    root = _small_package(tmp_path, name="small2", extra=extra)
    deps = kernel_dependencies(root)
    assert "small2/figures.py" in deps.files
    assert any("writes on import" in f for f in deps.fallbacks)
    extra["figures.py"] = "from .consts import TABLE\nsetattr(TABLE, 'x', 1)\n"
    root = _small_package(tmp_path, name="small3", extra=extra)
    assert "small3/figures.py" in kernel_dependencies(root).files
    # into a container whose definition holds a needed object (GROUP holds TABLE)
    extra["figures.py"] = "from .consts import GROUP\nGROUP[1][0] = 1\n"
    root = _small_package(tmp_path, name="small4", extra=extra)
    assert "small4/figures.py" in kernel_dependencies(root).files


def test_star_imports_dynamic_imports_and_unknown_names_fall_back_to_whole_modules(tmp_path):
    # a star import: the whole source module, whatever the kernel reads
    root = _small_package(tmp_path, extra={"core/k.py": _SMALL["core/k.py"].replace(
        "from ..figures import draw\n", "from ..figures import *\n")})
    deps = kernel_dependencies(root)
    assert any("star import" in f for f in deps.fallbacks)
    assert "small/figures.py" in deps.files
    # a computed import in what a kernel needs: the whole package
    root = _small_package(tmp_path, name="small2", extra={"helper.py": (
        "import importlib\n\ndef make(n):\n"
        "    return importlib.import_module('small2.base').N * (0,)\n")})
    deps = kernel_dependencies(root)
    assert any("computed import" in f for f in deps.fallbacks)
    assert "small2/study.py" in deps.files and "small2/figures.py" in deps.files
    # a name bound nowhere (made by globals()): the whole module
    root = _small_package(tmp_path, name="small3", extra={"base.py": (
        "globals()['N'] = 3\n\ndef unused():\n    from . import figures\n    return figures\n")})
    deps = kernel_dependencies(root)
    assert any("namespace as a dict" in f for f in deps.fallbacks)
    assert "small3/figures.py" in deps.files        # whole base.py: unused() counts too
    # a module attribute nobody binds: the whole module
    root = _small_package(tmp_path, name="small4", extra={"core/k.py": _SMALL["core/k.py"].replace(
        "c.TABLE[0]", "c.MISSING")})
    deps = kernel_dependencies(root)
    assert any("small4.consts.MISSING" in f for f in deps.fallbacks)
    # a global a kernel reads that its module does not bind: the whole module, so even the
    # figure module its .plot() method calls
    root = _small_package(tmp_path, name="small5", extra={"core/k.py": _SMALL["core/k.py"].replace(
        "c.TABLE[0]", "MAGIC")})
    deps = kernel_dependencies(root)
    assert any("global MAGIC bound nowhere" in f for f in deps.fallbacks)
    assert "small5/figures.py" in deps.files


def test_every_way_of_making_compiled_code_is_a_root(tmp_path):
    """Aliases of the decorators through imports, assignments and wrappers; ``kernel(f)`` and
    ``njit(...)(g)``; numba's other compilers.  A plain Python caller of a kernel is not one."""
    root = _small_package(tmp_path, files={
        "__init__.py": "from ._jit import kernel as exported\n",
        "_jit.py": "from numba import njit\nkernel = njit(cache=True)\n",
        "a.py": "from ._jit import kernel as k\n\n@k\ndef a1(x):\n    return x\n",
        "b.py": ("from . import exported\nimport functools, numba as nb\n"
                 "fast = nb.njit\nlater = functools.partial(nb.njit, cache=True)\n"
                 "def wrap(f):\n    return nb.njit(f)\n\n@fast\ndef b1():\n    return 1\n\n"
                 "@later()\ndef b2():\n    return 2\n\n@wrap\ndef b3():\n    return 3\n\n"
                 "@exported\ndef b4():\n    return 4\n\ndef _py(x):\n    return x\n\n"
                 "b5 = exported(_py)\nb6 = nb.njit('f8(f8)')(_py)\nb7 = nb.vectorize(_py)\n\n"
                 "def caller():\n    return b1() + b5(1.0)\n"),
        "c.py": "from numba import types\nSIG = types.float64\n\ndef uses():\n    return SIG\n",
    })
    deps = kernel_dependencies(root)
    assert deps.kernels == ("small._jit:kernel", "small.a:a1", "small.b:b1", "small.b:b2",
                            "small.b:b3", "small.b:b4", "small.b:b5", "small.b:b6",
                            "small.b:b7", "small.b:fast", "small.b:later", "small.b:wrap")
    assert "small/c.py" not in deps.files


def test_the_analysis_follows_a_module_that_moves(tmp_path):
    """consts.py moved into core/ (and its importers updated): still in the key, under its
    new name; a renamed top package too."""
    files = dict(_SMALL)
    files["core/consts.py"] = files.pop("consts.py").replace("from .", "from ..")
    files["core/k.py"] = files["core/k.py"].replace("from .. import consts", "from . import consts")
    deps = kernel_dependencies(_small_package(tmp_path, files, name="renamed"))
    assert "renamed.core.consts" in deps.modules and "renamed.base" in deps.modules
    assert "renamed.study" not in deps.modules


def test_a_folder_without_init_is_followed(tmp_path):
    """A constant read from a module of a namespace folder (no ``__init__.py``)."""
    root = _small_package(tmp_path, extra={
        "ns/values.py": "EXTRA = 1\n",
        "consts.py": _SMALL["consts.py"].replace("OTHER = 7", "from .ns import values\n"
                                                 "OTHER = 7\nOFFSET += values.EXTRA")})
    deps = kernel_dependencies(root)
    assert "small/ns/values.py" in deps.files and not deps.fallbacks


def test_stored_analyses_give_the_same_key_and_bad_entries_are_redone(tree, tmp_path):
    fresh = kernel_source_hash(tree)
    store = tmp_path / "store"
    assert kernel_source_hash(tree, store) == fresh
    entries = sorted(store.glob("*.json"))
    assert len(entries) > 100                   # one per file, one for the tree
    for i, e in enumerate(entries):             # unreadable, or readable but wrong
        e.write_text("{" if i % 2 else json.dumps({"parsed": True, "stmts": [{"line": 1}]}))
    assert kernel_source_hash(tree, store) == fresh
    assert kernel_dependencies(tree, store) == kernel_dependencies(tree)


def test_a_root_that_is_not_a_package_is_refused(tmp_path):
    with pytest.raises(ValueError, match="package folder"):
        kernel_source_hash(tmp_path)


# --- (d) the key against the imported package --------------------------------------------


_PROBE = r"""
import hashlib, importlib, importlib.abc, importlib.machinery, inspect, json, pkgutil, sys
import types
import numpy as np

key = json.loads(sys.argv[1])
modules, files, stub = set(key["modules"]), set(key["files"]), sys.argv[2] == "stub"

if stub:
    # every module of the package outside the key is replaced by a stub that answers
    # everything: what the kernels read must not come from there
    class _Meta(type):
        def __getattr__(cls, name):
            if name.startswith("__"):
                raise AttributeError(name)
            return Stub
        def __call__(cls, *args, **kwargs):
            return Stub
        def __getitem__(cls, key):
            return Stub
        def __iter__(cls):
            return iter(())

    class Stub(metaclass=_Meta):
        pass

    class StubModule(types.ModuleType):
        def __getattr__(self, name):
            if name.startswith("__"):
                raise AttributeError(name)
            return Stub

    class Finder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
        def find_spec(self, name, path, target=None):
            if name.split(".")[0] == "ppamsafety" and name not in modules:
                return importlib.machinery.ModuleSpec(name, self, is_package=True)
            return None
        def create_module(self, spec):
            m = StubModule(spec.name)
            m.__path__ = []
            return m
        def exec_module(self, module):
            pass

    sys.meta_path.insert(0, Finder())
    for m in sorted(modules):
        importlib.import_module(m)
else:
    import ppamsafety
    for info in pkgutil.walk_packages(ppamsafety.__path__, "ppamsafety."):
        try:
            importlib.import_module(info.name)
        except ImportError:       # an optional dependency (cvxpy, dask, pymunk) is missing
            pass

from numba.core.registry import CPUDispatcher


def rel(path):
    parts = path.replace("\\", "/").split("/")
    return "/".join(parts[len(parts) - 1 - parts[::-1].index("ppamsafety"):]) \
        if "ppamsafety" in parts else None


def origin(v):
    # the file of the package that defines v, or None (builtin, numpy, numba, a value)
    if isinstance(v, CPUDispatcher):
        return rel(v.py_func.__code__.co_filename)
    if isinstance(v, types.ModuleType):
        return rel(getattr(v, "__file__", None) or "")
    if isinstance(v, types.FunctionType):
        return rel(v.__code__.co_filename)
    if isinstance(v, type) and v.__module__.split(".")[0] == "ppamsafety":
        return rel(sys.modules[v.__module__].__file__)
    if isinstance(type(v), type) and type(v).__module__.split(".")[0] == "ppamsafety" \
            and not isinstance(v, int):
        return rel(sys.modules[type(v).__module__].__file__)
    return None


def fingerprint(v, depth=0):
    if isinstance(v, CPUDispatcher):
        return ["dispatcher", v.py_func.__module__, v.py_func.__qualname__]
    if isinstance(v, types.ModuleType):
        return ["module", v.__name__]
    if isinstance(v, types.FunctionType):
        return ["function", v.__module__, v.__qualname__]
    if isinstance(v, type):
        return ["class", v.__module__, v.__qualname__]
    if isinstance(v, np.ndarray):
        return ["array", str(v.dtype), list(v.shape), hashlib.sha1(v.tobytes()).hexdigest()]
    if isinstance(v, (tuple, list)) and depth < 3:
        return [type(v).__name__] + [fingerprint(x, depth + 1) for x in v]
    if isinstance(v, (bool, int, float, complex, str, bytes, type(None), np.generic)):
        return [type(v).__name__, repr(v)]
    return ["object", type(v).__module__, type(v).__qualname__]


def code_names(code):
    names = set(code.co_names)
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            names |= code_names(c)
    return names


compiled = {}
for mod in list(sys.modules.values()):
    if (getattr(mod, "__name__", "").split(".")[0] != "ppamsafety"
            or type(mod).__name__ == "StubModule"):
        continue
    for obj in list(vars(mod).values()):
        if isinstance(obj, CPUDispatcher):
            compiled[f"{obj.py_func.__module__}:{obj.py_func.__qualname__}"] = obj

report = {"outside": [], "prints": {}}
for name, d in sorted(compiled.items()):
    f = d.py_func
    if rel(f.__code__.co_filename) not in files:
        report["outside"].append([name, "defined in", rel(f.__code__.co_filename)])
    names = code_names(f.__code__)
    read = {}
    for n in sorted(names):
        if n in f.__globals__:
            v = f.__globals__[n]
            read[n] = v
            if isinstance(v, types.ModuleType):          # lay.L1: the attributes read
                for a in sorted(names):
                    if a in vars(v):
                        read[f"{n}.{a}"] = vars(v)[a]
    for i, cell in enumerate(f.__closure__ or ()):
        read[f"<closure {i}>"] = cell.cell_contents
    for n, v in read.items():
        o = origin(v)
        if o is not None and o not in files:
            report["outside"].append([name, n, o])
    report["prints"][name] = {n: fingerprint(v) for n, v in read.items()}
print(json.dumps(report))
"""


def _probe(tmp_path, deps, mode):
    env = {**os.environ, "PPAMSAFETY_CACHE_DIR": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)
    env["PYTHONPATH"] = str(PACKAGE.parent) + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, "-c", _PROBE,
                          json.dumps({"modules": deps.modules, "files": deps.files}), mode],
                         env=env, check=True, capture_output=True, text=True, timeout=600,
                         cwd=tmp_path).stdout
    return json.loads(out.strip().splitlines()[-1])


def test_every_compiled_function_reads_only_what_the_key_holds(tmp_path):
    """The whole package imported: every compiled function is defined in a file of the key,
    and every global it reads (its bytecode's names, the attributes of a module it reads,
    its closure) that is a function, class, module or object of the package comes from a
    file of the key."""
    r = _probe(tmp_path, kernel_dependencies(), "full")
    assert len(r["prints"]) >= 100, sorted(r["prints"])
    assert not r["outside"], r["outside"]


def test_the_files_outside_the_key_do_not_change_what_kernels_read(tmp_path):
    """Every module outside the key replaced by a stub that answers anything: the kernel
    modules still import, and every global each compiled function reads has the same value
    (numbers, arrays, tuples, enum members, functions by name) as with the real package."""
    deps = kernel_dependencies()
    full, stubbed = _probe(tmp_path, deps, "full"), _probe(tmp_path, deps, "stub")
    assert sorted(stubbed["prints"]) == sorted(full["prints"])
    for name, prints in full["prints"].items():
        assert stubbed["prints"][name] == prints, name


# --- (d) pruning -----------------------------------------------------------------------------


def _age(path: Path, age: float) -> Path:
    """Set the times of ``path`` and its subfolders to ``age`` seconds ago."""
    t = time.time() - age
    for p in [*(q for q in path.rglob("*") if q.is_dir() and not q.is_symlink()), path]:
        os.utime(p, (t, t))
    return path


def _cache_folder(base: Path, i: int, age: float) -> Path:
    """A folder ``numba-<16 hex>`` as numba fills it, last used ``age`` seconds ago."""
    path = base / f"numba-{i:016x}"
    sub = path / "work_src_ppamsafety_plant"
    sub.mkdir(parents=True)
    (sub / "model.rk4_step-100.py311.nbi").write_bytes(b"i")
    (sub / "model.rk4_step-100.py311.1.nbc").write_bytes(b"c")
    (sub / "model.rk4_step-100.py311.nbi.tmp.0123abcd").write_bytes(b"t")   # an interrupted save
    return _age(path, age)


def test_pruning_keeps_the_newest_and_the_current_and_never_touches_foreign_files(tmp_path):
    base = tmp_path / "cache"
    current = _cache_folder(base, 99, age=7 * 86400.0)        # oldest, but this process' own
    ours = [_cache_folder(base, i, age=86400.0 * (i + 1)) for i in range(6)]   # newest first
    foreign = {
        "other": base / "other",                                 # not a numba-<hash> name
        "short": base / "numba-abc",
        "upper": base / "numba-0000000000000ABC",
        "file": base / "numba-00000000000000f1",                  # a file, not a folder
        "extra": _cache_folder(base, 0xf2, age=0.0),             # holds a file of its own
        "link": base / "numba-00000000000000f3",                  # a symbolic link
        "linked": _cache_folder(base, 0xf4, age=0.0),            # holds a symbolic link
    }
    for name in ("other", "short", "upper"):
        foreign[name].mkdir()
        (foreign[name] / "x.nbi").write_text("x")
    foreign["file"].write_text("x")
    (foreign["extra"] / "notes.txt").write_text("mine")
    target = tmp_path / "elsewhere"
    target.mkdir()
    (target / "x.nbi").write_text("x")
    foreign["link"].symlink_to(target)
    (foreign["linked"] / "work_src_ppamsafety_plant" / "link.nbi").symlink_to(target / "x.nbi")
    for name in ("other", "short", "upper", "extra", "linked"):
        _age(foreign[name], 30 * 86400.0)

    removed = _jit._prune_caches(str(base), str(current), keep=3)

    assert sorted(removed) == sorted(str(p) for p in ours[2:])
    assert current.is_dir() and ours[0].is_dir() and ours[1].is_dir()
    assert all(p.exists() or p.is_symlink() for p in foreign.values())
    assert (foreign["extra"] / "notes.txt").read_text() == "mine"
    assert all((foreign[n] / "x.nbi").exists() for n in ("other", "short", "upper"))
    assert (target / "x.nbi").read_text() == "x"
    assert _jit._prune_caches(str(base), str(current), keep=3) == []    # nothing left to do
    assert _jit._prune_caches(str(base), str(current), keep=1) == [str(p) for p in ours[:2]]


def test_pruning_keeps_folders_used_recently(tmp_path):
    """Within MIN_AGE a folder is kept however many newer ones there are (protects a process
    that holds no lock), and its subfolders count: numba writes there."""
    base = tmp_path / "cache"
    current = _cache_folder(base, 1, age=0.0)
    recent = _cache_folder(base, 2, age=_jit.MIN_AGE / 2)
    written = _cache_folder(base, 3, age=30 * 86400.0)
    os.utime(written / "work_src_ppamsafety_plant")            # numba just wrote a file there
    assert _jit._prune_caches(str(base), str(current), keep=1) == []
    assert _jit._prune_caches(str(base), str(current), keep=1, min_age=0.0) == sorted(
        [str(recent), str(written)], key=lambda p: p != str(written))


def test_pruning_never_deletes_a_folder_in_use(tmp_path):
    """A folder whose lock another process holds (here: another open file description in this
    process, as flock locks belong to those) is kept, however old."""
    fcntl = pytest.importorskip("fcntl")
    base = tmp_path / "cache"
    current = _cache_folder(base, 1, age=0.0)
    old = _cache_folder(base, 2, age=30 * 86400.0)
    fd = os.open(old / _jit._IN_USE, os.O_RDWR | os.O_CREAT)
    _age(old, 30 * 86400.0)                 # creating the lock file touched the folder
    try:
        fcntl.flock(fd, fcntl.LOCK_SH)
        assert _jit._prune_caches(str(base), str(current), keep=1) == []
        assert old.is_dir()
    finally:
        os.close(fd)
    assert _jit._prune_caches(str(base), str(current), keep=1) == [str(old)]
    assert not old.exists()


def test_a_process_keeps_its_folder_locked(tmp_path):
    """Another process (with the package imported) holds the lock of its folder: pruning from
    here keeps it; once it exits, the folder goes."""
    base = tmp_path / "cache"
    mine = _cache_folder(base, 1, age=0.0)
    env = {**os.environ, "PPAMSAFETY_CACHE_DIR": str(base)}
    env.pop("NUMBA_CACHE_DIR", None)
    env["PYTHONPATH"] = str(PACKAGE.parent) + os.pathsep + env.get("PYTHONPATH", "")
    script = ("import sys, numba, ppamsafety._jit; print(numba.config.CACHE_DIR, flush=True); "
              "sys.stdin.read()")
    p = subprocess.Popen([sys.executable, "-c", script], env=env, stdin=subprocess.PIPE,
                         stdout=subprocess.PIPE, text=True, cwd=tmp_path)
    try:
        theirs = Path(p.stdout.readline().strip())
        assert theirs.parent == base and theirs.is_dir() and theirs != mine
        t = time.time() - 30 * 86400.0
        os.utime(theirs, (t, t))
        assert _jit._prune_caches(str(base), str(mine), keep=1) == []
    finally:
        p.communicate("", timeout=60)
    assert _jit._prune_caches(str(base), str(mine), keep=1) == [str(theirs)]


def test_pruning_failures_warn_and_never_raise(tmp_path):
    with pytest.warns(RuntimeWarning, match="could not list"):
        assert _jit._prune_caches(str(tmp_path / "missing"), str(tmp_path / "x")) == []
    with pytest.raises(ValueError, match="keep"):
        _jit._prune_caches(str(tmp_path), str(tmp_path / "x"), keep=0)
