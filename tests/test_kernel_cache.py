"""The compiled-kernel cache key (the explicit list of kernel files) and the pruning of old
cache folders.

The key tests edit a temporary copy of the package source, never the package itself: the key
is computed from a source tree (``kernel_source_hash(root)``), nothing is imported from it.
Two subprocess tests check the list against the imported package (what the compiled functions
actually read).
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
from ppamsafety._sourcehash import KERNEL_FILES, check_kernel_file, kernel_source_hash, source_hash

PACKAGE = Path(ppamsafety.__file__).resolve().parent


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


def test_editing_a_callee_in_another_module_changes_the_key(tree):
    """The controller step (control/dispatch.py) calls the PID step of control/laws/pid.py."""
    from ppamsafety.control import dispatch
    from ppamsafety.control.laws import pid

    assert dispatch.pid_step is pid.pid_step and dispatch.__file__ != pid.__file__
    before = kernel_source_hash(tree)
    _edit_function(_file(tree, pid), "pid_step")
    assert kernel_source_hash(tree) != before


def test_editing_a_layout_offset_or_field_read_by_kernels_changes_the_key(tree):
    """plant/layout.py defines no kernel: it holds the offsets of the plant row (made from its
    Fields) that the plant kernels import and numba freezes at compile time."""
    from ppamsafety.plant import layout, muscle

    assert "plant/layout.py" in KERNEL_FILES and muscle.COEF == layout.COEF
    before = kernel_source_hash(tree)
    _shift_constant(_file(tree, layout), "COEF")
    shifted = kernel_source_hash(tree)
    assert shifted != before
    _replace(_file(tree, layout), 'Field("X11", 1,', 'Field("X11", 2,')
    assert kernel_source_hash(tree) not in (before, shifted)


def test_editing_the_function_a_constant_is_computed_with_changes_the_key(tree):
    """The offsets of every law's row are computed by ``Layout.offsets`` of layouts.py."""
    from ppamsafety import layouts

    before = kernel_source_hash(tree)
    _edit_function(_file(tree, layouts), "offsets", cls="Layout")
    assert kernel_source_hash(tree) != before


@pytest.mark.parametrize("module", [
    "ppamsafety.layouts", "ppamsafety._jit", "ppamsafety.__init__", "ppamsafety.units",
    "ppamsafety.control.kinds", "ppamsafety.control.laws.__init__",
    "ppamsafety.hysteresis.memory", "ppamsafety.experiments.__init__"])
def test_editing_what_the_kernels_need_changes_the_key(tree, module):
    """The layout machinery, the decorators, a constant a kernel reads from another module
    (``units.G0``), the controller kinds (an IntEnum the dispatch compares with), the parent
    packages' ``__init__`` (run before their modules), a kernel module."""
    import importlib

    before = kernel_source_hash(tree)
    path = _file(tree, importlib.import_module(module.removesuffix(".__init__")))
    path.write_text(path.read_text() + "\n# test edit\n")
    assert kernel_source_hash(tree) != before


def test_numba_settings_change_the_key(tree, monkeypatch):
    """numba's own cache ignores NUMBA_BOUNDSCHECK: a bounds-checked run must not load code
    compiled without the checks."""
    from numba.core import config

    before = kernel_source_hash(tree)
    monkeypatch.setattr(config, "BOUNDSCHECK", not config.BOUNDSCHECK)
    assert kernel_source_hash(tree) != before


# --- (b) edits no kernel can see keep it ---------------------------------------------------


def test_the_list_holds_the_kernel_modules_and_not_the_rest():
    """Plots, sections, the report, the CLI, the sweeps and the diagnosis are out, though
    kernel modules import plots at module level; every listed file exists."""
    for rel in KERNEL_FILES:
        assert (PACKAGE / rel).is_file(), rel
    assert len(set(KERNEL_FILES)) == len(KERNEL_FILES)
    for prefix in ("plots/", "sections/", "report/", "diagnose/", "cli.py", "study_files.py",
                   "sweep_cases.py", "sweep.py", "impact/model.py", "params/"):
        assert not [f for f in KERNEL_FILES if f.startswith(prefix)], prefix


def test_a_kernel_outside_the_list_is_refused_at_import(tmp_path):
    """The decorators check the file that defines the function: a kernel added to a module of
    the package that is not listed fails on import, naming the list."""
    def f(x):
        return x

    f.__code__ = f.__code__.replace(co_filename=str(PACKAGE / "sections" / "safety.py"))
    for decorator in (_jit.kernel, _jit.leaf):
        with pytest.raises(ImportError, match="KERNEL_FILES"):
            decorator(f)
    f.__code__ = f.__code__.replace(co_filename=str(PACKAGE / "plant" / "model.py"))
    check_kernel_file(f)                                      # listed: accepted
    f.__code__ = f.__code__.replace(co_filename=str(tmp_path / "user_code.py"))
    check_kernel_file(f)                                      # outside the package: accepted


def test_editing_plots_sections_the_cli_and_studies_keeps_the_key(tree):
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

    outside = sorted({p.relative_to(tree.parent).as_posix() for p in tree.rglob("*.py")}
                     - {f"{PACKAGE.name}/{f}" for f in KERNEL_FILES})
    assert _rel(tree, closed_loop) not in outside
    assert closed_loop.plot_experiment is plots_control.plot_experiment
    for m in (cli, build, safety, plots_control, plots_impact, model, study_files, sweep_cases):
        assert _rel(tree, m) in outside, m.__name__
    before, sweep_before = kernel_source_hash(tree), source_hash(tree)
    for rel in outside:
        path = tree.parent / rel
        path.write_text(path.read_text() + "\n# test edit\n")
    _edit_function(_file(tree, plots_control), "plot_experiment")
    _edit_function(_file(tree, model), "plot", cls="ImpactResult")   # a .plot() method
    assert kernel_source_hash(tree) == before
    assert source_hash(tree) != sweep_before


def test_the_key_ignores_files_that_are_not_python(tree):
    before = kernel_source_hash(tree)
    (tree / "notes.txt").write_text("x")
    (tree / "plant" / "README.md").write_text("x")
    assert kernel_source_hash(tree) == before


# --- (c) the list against the imported package --------------------------------------------


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


def _listed():
    """The listed modules by name and their files relative to the package's parent folder."""
    modules = [".".join(["ppamsafety", *f.removesuffix(".py").split("/")]).removesuffix(
        ".__init__") for f in KERNEL_FILES]
    return {"modules": modules, "files": [f"ppamsafety/{f}" for f in KERNEL_FILES]}


def _probe(tmp_path, mode):
    env = {**os.environ, "PPAMSAFETY_CACHE_DIR": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)
    env["PYTHONPATH"] = str(PACKAGE.parent) + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, "-c", _PROBE,
                          json.dumps(_listed()), mode],
                         env=env, check=True, capture_output=True, text=True, timeout=600,
                         cwd=tmp_path).stdout
    return json.loads(out.strip().splitlines()[-1])


def test_every_compiled_function_reads_only_what_the_key_holds(tmp_path):
    """The whole package imported: every compiled function is defined in a file of the key,
    and every global it reads (its bytecode's names, the attributes of a module it reads,
    its closure) that is a function, class, module or object of the package comes from a
    file of the key."""
    r = _probe(tmp_path, "full")
    assert len(r["prints"]) >= 100, sorted(r["prints"])
    assert not r["outside"], r["outside"]


def test_the_files_outside_the_key_do_not_change_what_kernels_read(tmp_path):
    """Every module outside the key replaced by a stub that answers anything: the kernel
    modules still import, and every global each compiled function reads has the same value
    (numbers, arrays, tuples, enum members, functions by name) as with the real package."""
    full, stubbed = _probe(tmp_path, "full"), _probe(tmp_path, "stub")
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
