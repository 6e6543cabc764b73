"""The compiled-kernel cache key (issue 23.1) and the pruning of old cache folders (23.2).

The key tests edit a temporary copy of the package source, never the package itself: the key
is computed from a source tree (``kernel_source_hash(root)``), nothing is imported from it.
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


def _insert_after(path: Path, lineno: int, text: str) -> None:
    lines = path.read_text().splitlines(keepends=True)
    lines.insert(lineno, text + "\n")
    path.write_text("".join(lines))


def _edit_function(path: Path, name: str) -> None:
    """Insert a statement before the last statement of the module-level function ``name``."""
    fn = next(n for n in ast.parse(path.read_text()).body
              if isinstance(n, ast.FunctionDef) and n.name == name)
    last = fn.body[-1]
    _insert_after(path, last.lineno - 1, " " * last.col_offset + "_edited = 1.0  # test edit")


def _shift_constant(path: Path, name: str) -> None:
    """Shift the module-level constant ``name`` by one, right after the statement defining it."""
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.Assign) and name in {
                n.id for t in node.targets for n in ast.walk(t) if isinstance(n, ast.Name)}:
            _insert_after(path, node.end_lineno, f"{name} = {name} + 1  # test edit")
            return
    raise AssertionError(f"no module-level assignment of {name} in {path}")


# --- (a), (b): edits the kernels can see change the key ----------------------------------


def test_editing_a_callee_in_another_module_changes_the_key(tree, store):
    """The controller step (control/dispatch.py) calls the PID step of control/pid.py."""
    from ppamsafety.control import dispatch, pid

    assert dispatch.pid_step is pid.pid_step and dispatch.__file__ != pid.__file__
    before = kernel_source_hash(tree, store)
    _edit_function(_file(tree, pid), "pid_step")
    after = kernel_source_hash(tree, store)
    assert after != before


def test_editing_a_layout_offset_read_by_kernels_changes_the_key(tree, store):
    """plant/layout.py defines no kernel: it holds the offsets of the plant row that the plant
    kernels import at module level and numba freezes at compile time."""
    from ppamsafety.plant import layout, muscle

    deps = kernel_dependencies(tree, store)
    assert layout.__name__ not in deps.kernel_modules       # reached through the imports only
    assert muscle.__name__ in deps.kernel_modules and muscle.COEF == layout.COEF
    before = kernel_source_hash(tree, store)
    _shift_constant(_file(tree, layout), "COEF")
    assert kernel_source_hash(tree, store) != before


@pytest.mark.parametrize("module", ["ppamsafety.layouts", "ppamsafety.params.valves",
                                    "ppamsafety._jit", "ppamsafety.__init__"])
def test_editing_what_the_kernel_modules_import_changes_the_key(tree, store, module):
    """The layout machinery (offsets are computed by it), a parameter module two imports away
    from any kernel module (params.valves <- params.arm <- control.base), the decorators, and
    the package's ``__init__`` (run before every module)."""
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


# --- (c): edits no kernel can see keep it ----------------------------------------------------


def test_editing_studies_figures_and_the_cli_keeps_the_key(tree, store):
    """Every module outside the closure edited at once: a study, a figure module no kernel
    module imports, the command line, the sweeps ...; the sweep key still changes."""
    from ppamsafety import cli
    from ppamsafety.report import build, impact_figures
    from ppamsafety.studies import stiffness

    deps = kernel_dependencies(tree, store)
    outside = sorted({p.relative_to(tree.parent).as_posix() for p in tree.rglob("*.py")}
                     - set(deps.files))
    for m in (cli, build, impact_figures, stiffness):
        assert _file(tree, m).relative_to(tree.parent).as_posix() in outside, m.__name__
    assert len(outside) >= 40, outside          # most of the package is plain Python
    before, sweep_before = kernel_source_hash(tree, store), source_hash(tree)
    for rel in outside:
        path = tree.parent / rel
        path.write_text(path.read_text() + "\n# test edit\n")
    stiffness_file = _file(tree, stiffness)
    _shift_constant(stiffness_file, next(n.targets[0].id for n in ast.parse(
        stiffness_file.read_text()).body if isinstance(n, ast.Assign)
        and isinstance(n.targets[0], ast.Name)))
    assert kernel_source_hash(tree, store) == before
    assert source_hash(tree) != sweep_before


def test_the_key_ignores_files_that_are_not_python(tree, store):
    before = kernel_source_hash(tree, store)
    (tree / "notes.txt").write_text("x")
    (tree / "plant" / "README.md").write_text("x")
    assert kernel_source_hash(tree, store) == before


# --- how the closure is found -------------------------------------------------------------


_SMALL = {
    "__init__.py": "",
    "_jit.py": "import numba\nkernel = numba.njit(cache=True)\n",
    "consts.py": "from .base import N\nOFFSET = N + 1\n",
    "base.py": "N = 3\n",
    "core/__init__.py": "",
    "core/helper.py": "from .._jit import kernel\n@kernel\ndef h(x):\n    return x\n",
    "core/k.py": ("from .._jit import kernel\nfrom ..consts import OFFSET\nfrom .helper import h\n"
                  "@kernel\ndef f(x):\n    return h(x[OFFSET])\n"
                  "def plot(x):\n    from ..figures import draw\n    draw(x)\n"),
    "figures.py": "def draw(x):\n    from .study import run\n    return run\n",
    "study.py": "from .core.k import f\nfrom . import figures\n\ndef run():\n    return f\n",
    "lazy/__init__.py": ("import importlib\n\ndef __getattr__(name):\n"
                         "    return importlib.import_module('.' + name, __name__)\n"),
    "lazy/a.py": "A = 1\n",
    "lazy/b.py": "B = 2\n",
    "uses_lazy.py": "from .lazy import a\n",
    "jitted.py": ("from numba import njit\nfrom .uses_lazy import a\n"
                  "@njit\ndef g():\n    return 1\n"),
    "broken.py": "def (:\n",
    "deep/__init__.py": "SCALE = 2.0\n",
    "deep/inner/__init__.py": "",
    "deep/inner/solo.py": "import numba\nfrom ...lazier import L\n",
    "lazier/__init__.py": ("def __getattr__(name):\n    from .impl import L\n    return L\n\n"
                           "def unrelated():\n    from .other import O\n"),
    "lazier/impl.py": "L = 1\n",
    "lazier/other.py": "O = 1\n",
}


def _small_package(tmp_path, files=_SMALL, name="small"):
    root = tmp_path / name
    for rel, text in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    return root


def test_closure_rules_on_a_small_package(tmp_path):
    deps = kernel_dependencies(_small_package(tmp_path))
    assert deps.kernel_modules == ("small._jit", "small.broken", "small.core.helper",
                                   "small.core.k", "small.deep.inner.solo", "small.jitted")
    # module-level imports, transitively (consts -> base); parent packages (deep, deep.inner:
    # their __init__ runs first); the function-level import of a kernel module (figures), but
    # not figures' own function-level import (study); a package importing by computed name
    # in full (lazy); the imports of a module-level __getattr__ (lazier.impl), not those of
    # other functions (lazier.other)
    assert deps.modules == ("small", "small._jit", "small.base", "small.broken", "small.consts",
                            "small.core", "small.core.helper", "small.core.k", "small.deep",
                            "small.deep.inner", "small.deep.inner.solo", "small.figures",
                            "small.jitted", "small.lazier", "small.lazier.impl", "small.lazy",
                            "small.lazy.a", "small.lazy.b", "small.uses_lazy")
    assert deps.files[0] == "small/__init__.py" and "small/core/k.py" in deps.files
    assert deps.packages == ("numba",)


def test_the_closure_follows_a_module_that_moves(tmp_path):
    """consts.py moved into core/ (and its importers updated): still in the closure, under its
    new name; a renamed top package too."""
    files = dict(_SMALL)
    files["core/consts.py"] = files.pop("consts.py").replace("from .base", "from ..base")
    files["core/k.py"] = files["core/k.py"].replace("from ..consts", "from .consts")
    deps = kernel_dependencies(_small_package(tmp_path, files, name="renamed"))
    assert "renamed.core.consts" in deps.modules and "renamed.base" in deps.modules
    assert "renamed.study" not in deps.modules


def test_stored_analyses_give_the_same_key_and_bad_entries_are_redone(tree, tmp_path):
    fresh = kernel_source_hash(tree)
    store = tmp_path / "store"
    assert kernel_source_hash(tree, store) == fresh
    entries = sorted(store.glob("*.json"))
    assert len(entries) > 100                   # one per file, one for the tree
    for i, e in enumerate(entries):             # unreadable, or readable but wrong
        e.write_text("{" if i % 2 else json.dumps({"imports": [[0]], "dynamic": True}))
    assert kernel_source_hash(tree, store) == fresh
    assert kernel_dependencies(tree, store) == kernel_dependencies(tree)


def test_a_root_that_is_not_a_package_is_refused(tmp_path):
    with pytest.raises(ValueError, match="package folder"):
        kernel_source_hash(tmp_path)


_IMPORT_PROBE = """
import importlib, json, pkgutil, sys
from ppamsafety._sourcehash import kernel_dependencies
deps = kernel_dependencies()
for m in deps.kernel_modules:
    importlib.import_module(m)
loaded = sorted(m for m in sys.modules if m.split(".")[0] == "ppamsafety")
import numba.core.registry
import ppamsafety
for info in pkgutil.walk_packages(ppamsafety.__path__, "ppamsafety."):
    try:
        importlib.import_module(info.name)
    except ImportError:           # an optional dependency (cvxpy, dask, pymunk) is missing
        pass
compiled = sorted({(name, obj.py_func.__module__)
                   for mod in list(sys.modules.values())
                   if getattr(mod, "__name__", "").split(".")[0] == "ppamsafety"
                   for name, obj in vars(mod).items()
                   if isinstance(obj, numba.core.registry.CPUDispatcher)})
print(json.dumps({"modules": deps.modules, "kernel_modules": deps.kernel_modules,
                  "loaded": loaded, "compiled": compiled}))
"""


def test_the_static_closure_covers_what_importing_the_kernels_runs(tmp_path):
    """Importing every kernel module imports only modules of the closure (so nothing else
    runs when the kernels' constants are made), and every compiled function of the package
    is defined in a kernel module."""
    env = {**os.environ, "PPAMSAFETY_CACHE_DIR": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)
    env["PYTHONPATH"] = str(PACKAGE.parent) + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, "-c", _IMPORT_PROBE], env=env, check=True,
                         capture_output=True, text=True, timeout=600, cwd=tmp_path).stdout
    r = json.loads(out.strip().splitlines()[-1])
    assert set(r["loaded"]) <= set(r["modules"]), sorted(set(r["loaded"]) - set(r["modules"]))
    assert len(r["compiled"]) >= 50, r["compiled"]
    outside = sorted({m for _, m in r["compiled"]} - set(r["kernel_modules"]))
    assert not outside, outside


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
