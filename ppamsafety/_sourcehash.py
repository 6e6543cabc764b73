"""Hashes of the package source that the caches follow: one for results, one for compiled kernels.

Two caches depend on different parts of the code, so they have two keys:

* :func:`source_hash` -- every ``*.py`` of the package.  The sweep result
  cache (:mod:`ppamsafety.sweep`) is keyed on it: a cached result may depend
  on any Python code (a study's post-processing, a default parameter, a
  table), so any edit anywhere gives fresh results.
* :func:`kernel_source_hash` -- only the modules that compiled code can depend
  on, plus the interpreter, library versions and numba settings that change
  the machine code.  The compiled-kernel cache (:mod:`ppamsafety._jit`) is
  keyed on it: editing a study, most figures, the command line or the docs
  recompiles nothing, and editing anything a kernel can reach recompiles
  every kernel (numba alone only notices edits of a kernel's own file, not of
  a kernel or a constant it uses from another module).

Which modules the kernels can depend on (:func:`kernel_dependencies`) is found
from the source tree alone, by reading each file's syntax tree (nothing is
imported, no module list is written down), so the key follows files that move
between packages:

1. The *kernel modules*: every module that imports numba (at any level), and
   every module that imports a name from a module importing numba at module
   level (``_jit``, whose ``kernel`` and ``leaf`` are ``numba.njit``).  Every
   module that defines compiled code is one of them.
2. Their *closure*.  A kernel reads only the globals of its own module (names
   defined there or imported at module level), and numba freezes them at
   compile time: layout offsets, enum members, the other kernels it calls.
   Those values are made by running the modules imported at module level.
   So from the kernel modules the closure follows, transitively:

   * every module-level import of a package module (``import a.b`` counts
     ``a`` and ``a.b``; ``from a import b`` counts ``a`` and, when ``b`` is a
     submodule, ``a.b``; ``from a import *`` every submodule of ``a``),
     including imports under ``if``/``try``/``with`` and in class bodies;
   * the imports inside functions, too, of the kernel modules (numba refuses
     an import inside a kernel, but a Python function run when the module is
     imported may compute a constant with one);
   * the imports inside a module-level ``__getattr__`` (a lazy module runs
     it when another module imports a name from it);
   * the parent packages of every module (their ``__init__`` runs first);
   * every module of the package of a module that imports by a computed name
     (``importlib.import_module``, ``__import__``, ``exec``, ``eval``): the
     lazy ``experiments/__init__.py`` pulls in all of ``experiments``.

   Imports inside functions of the other modules are not followed: the plot
   methods import the figure modules that way, which in turn import the
   studies and the command line.  ``tests/test_kernel_cache.py`` checks that
   importing every kernel module imports nothing outside the closure, and
   that every compiled function found in the imported package is defined in
   a kernel module.

Only ``*.py`` files count: a kernel module that read a data file when imported
would need that file added to the key (none does).

Parsing the whole package takes about 1 s (building the syntax trees of
1.7 MB of source; 0.3 s of it without the garbage collector), too slow for
every process that imports the kernels.  So the analyses are stored on disk
(``cache_dir``, small JSON files written atomically): each file's (its
imports, unresolved, and whether it imports by a computed name) under the
hash of its bytes, and the resulting :class:`KernelDependencies` under the
hash of the whole tree.  A process reads and hashes the files, finds the tree
(about 10 ms), and otherwise parses only the files edited since; the key is
computed once per process.  An unreadable or malformed entry is analysed
again, and what gets hashed is always the current bytes of the files.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import importlib.metadata
import json
import os
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

_ROOT = Path(__file__).resolve().parent

#: Functions that import a module whose name is only known at run time.
_DYNAMIC_IMPORTS = frozenset({"__import__", "import_module", "exec", "eval", "run_module",
                              "run_path", "exec_module", "load_module"})
#: numba settings (``numba.core.config``) that change the generated machine code but are
#: not part of numba's own cache key (measured for ``BOUNDSCHECK``: a bounds-checked run
#: loaded the unchecked machine code of an earlier run from the same cache folder).
_NUMBA_CODEGEN_SETTINGS = ("OPT", "BOUNDSCHECK", "DEBUGINFO_DEFAULT", "LOOP_VECTORIZE",
                           "SLP_VECTORIZE", "ENABLE_AVX", "USING_SVML", "CPU_NAME",
                           "CPU_FEATURES", "EXTEND_VARIABLE_LIFETIMES", "LLVM_REFPRUNE_PASS",
                           "LLVM_REFPRUNE_FLAGS", "ENABLE_PROFILING")
#: Stored analyses beyond which the entries of files no longer in the tree are deleted.
_MAX_STORED_ANALYSES = 2000


def source_hash(root=None) -> str:
    """Hex digest (16 characters) of the relative path and bytes of every ``*.py`` of the package.

    The key of the sweep result cache (:mod:`ppamsafety.sweep`): a result can
    depend on any Python code of the package, not only on compiled code, so
    every file counts and any edit gives fresh results.  (The compiled-kernel
    cache uses the narrower :func:`kernel_source_hash`.)

    Parameters
    ----------
    root : str or path-like, optional
        The package folder; default this package, whose hash is computed once
        per process (the package is not expected to change under a running
        process; a new process sees the edit).  For another root it is
        computed at every call.

    Returns
    -------
    str
    """
    if root is None:
        return _package_source_hash()
    return _source_hash(_package_root(root))


@functools.lru_cache(maxsize=1)
def _package_source_hash() -> str:
    return _source_hash(_ROOT)


def _source_hash(root: Path) -> str:
    h = hashlib.sha1()
    for f in sorted(root.rglob("*.py")):
        h.update(f.relative_to(root).as_posix().encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


@dataclass(frozen=True)
class KernelDependencies:
    """What the compiled kernels of a source tree can depend on (:func:`kernel_dependencies`).

    Attributes
    ----------
    kernel_modules : tuple of str
        Modules that define compiled code or the decorators that compile it
        (they import numba, or a name from a module importing numba at module
        level), sorted.
    modules : tuple of str
        Their closure (see :mod:`ppamsafety._sourcehash`), the kernel modules
        included, sorted.
    files : tuple of str
        Paths of the files of :attr:`modules`, relative to the parent of the
        package folder (``ppamsafety/plant/model.py``), sorted.
    packages : tuple of str
        Top-level names of the modules outside the package and the standard
        library that :attr:`modules` import (``numpy``, ``scipy``, ...), sorted.
    """

    kernel_modules: tuple
    modules: tuple
    files: tuple
    packages: tuple


def kernel_dependencies(root=None, cache_dir=None) -> KernelDependencies:
    """The modules the compiled kernels of the package at ``root`` can depend on.

    Parameters
    ----------
    root : str or path-like, optional
        The package folder (holding its ``__init__.py``); its name is the
        package name.  Default: this package.
    cache_dir : str or path-like, optional
        Folder of the stored analyses, per file and per tree (created if
        missing; see :mod:`ppamsafety._sourcehash`); None analyses every file
        in this process and stores nothing.

    Returns
    -------
    KernelDependencies
    """
    return _analyse_tree(_package_root(root), cache_dir)[0]


def kernel_source_hash(root=None, cache_dir=None) -> str:
    """Hex digest (16 characters) of everything the compiled kernels' machine code depends on.

    The key of the compiled-kernel cache (:mod:`ppamsafety._jit`).  numba's own
    cache notices an edit of a kernel's file, not of a kernel or a module
    constant it uses from another module, so the cache folder is named after
    this key.  It hashes:

    * the relative path and bytes of every file of
      :attr:`KernelDependencies.modules` (the kernel modules and what they
      import, see :mod:`ppamsafety._sourcehash`), so editing anything a
      kernel can reach changes it and editing a study, a figure module that
      no kernel module imports, the command line or the docs does not;
    * the Python version, the numba, llvmlite and numpy versions, the version
      of every other package those modules import (by distribution name; a
      package installed under another name counts by name only), and the
      numba settings that change machine code without being part of numba's
      own cache key (``NUMBA_BOUNDSCHECK``, ``NUMBA_OPT``, ...).  numba keys
      each cached function on the CPU itself.

    Unlike :func:`source_hash` it does not change when a file no kernel can
    reach changes, so it must not key caches of Python results.

    Parameters
    ----------
    root : str or path-like, optional
        The package folder; default this package, whose key is computed once
        per process (for another root it is computed at every call).
    cache_dir : str or path-like, optional
        Folder of the stored analyses (see :func:`kernel_dependencies`).

    Returns
    -------
    str
    """
    if root is None:
        return _package_kernel_hash(None if cache_dir is None else os.fspath(cache_dir))
    return _kernel_hash(_package_root(root), cache_dir)


@functools.lru_cache(maxsize=4)
def _package_kernel_hash(cache_dir) -> str:
    return _kernel_hash(_ROOT, cache_dir)


def _kernel_hash(root: Path, cache_dir) -> str:
    deps, data = _analyse_tree(root, cache_dir)
    h = hashlib.sha1(b"ppamsafety kernel key 1\0")
    for name, value in _machine_code_environment(deps.packages):
        h.update(f"{name}={value}\0".encode())
    for rel in deps.files:
        b = data[rel]
        h.update(f"{rel}\0{len(b)}\0".encode())
        h.update(b)
    return h.hexdigest()[:16]


def _machine_code_environment(packages) -> list:
    """(name, value) pairs outside the source that change the kernels' machine code, sorted."""
    import llvmlite
    import numba
    import numpy
    from numba.core import config

    env = [("python", f"{sys.implementation.name} {sys.version}"),
           ("numba", numba.__version__), ("llvmlite", llvmlite.__version__),
           ("numpy", numpy.__version__)]
    env += [(f"numba.config.{s}", repr(getattr(config, s, None)))
            for s in _NUMBA_CODEGEN_SETTINGS]
    for p in packages:
        if p not in ("numba", "llvmlite", "numpy"):
            env.append((f"package {p}", _distribution_version(p)))
    return sorted(env)


def _distribution_version(name: str) -> str:
    """Version of the installed distribution ``name`` (reads only its metadata header).

    ``importlib.metadata.version`` parses the whole metadata file as an e-mail
    message, 10 times slower; the header lines before the first blank line
    hold the version.  A package whose distribution has another name counts
    by name only.
    """
    try:
        text = importlib.metadata.distribution(name).read_text("METADATA") or ""
    except importlib.metadata.PackageNotFoundError:
        return "no distribution of that name"
    for line in text.splitlines():
        if not line.strip():
            break
        if line.startswith("Version:"):
            return line[len("Version:"):].strip()
    return importlib.metadata.version(name)


def _package_root(root) -> Path:
    """``root`` as a resolved package folder (this package for None); ValueError if not one."""
    if root is None:
        return _ROOT
    root = Path(root).resolve()
    if not (root / "__init__.py").is_file():
        raise ValueError(f"root must be a package folder holding __init__.py, got {root}")
    return root


# --- stored analyses ---------------------------------------------------------------------


@functools.lru_cache(maxsize=1)
def _analyser_tag() -> str:
    """Version of the stored analyses: the bytes of this file and the Python version."""
    h = hashlib.sha1(Path(__file__).read_bytes())
    h.update(f"{sys.version_info[:2]}".encode())
    return h.hexdigest()[:10]


def _load(folder, name: str, valid):
    """The JSON object stored as ``folder/name`` if it passes ``valid``, else None."""
    if folder is None:
        return None
    try:
        with open(os.path.join(folder, name), "rb") as fh:
            obj = json.loads(fh.read())
    except (OSError, ValueError):            # missing or unreadable: analyse again
        return None
    return obj if valid(obj) else None


def _store(folder, entries: dict, keep: set) -> None:
    """Write ``entries`` (file name -> JSON object) into ``folder``, each atomically.

    Storing is only a speed-up: if the folder is not writable, every process
    analyses the files again, with the same result, so an ``OSError`` is
    ignored.  Once the folder holds more than :data:`_MAX_STORED_ANALYSES`
    entries, those whose names are not in ``keep`` (the current tree's) are
    deleted.
    """
    if folder is None or not entries:
        return
    try:
        os.makedirs(folder, exist_ok=True)
        for name, obj in entries.items():
            fd, tmp = tempfile.mkstemp(dir=folder, prefix=".tmp-", suffix=".part")
            try:
                with os.fdopen(fd, "w") as fh:
                    json.dump(obj, fh)
                os.replace(tmp, os.path.join(folder, name))
            except BaseException:
                os.unlink(tmp)
                raise
        stored = [e for e in os.scandir(folder) if e.name.endswith(".json")]
        if len(stored) > _MAX_STORED_ANALYSES:
            for e in stored:
                if e.name not in keep:
                    os.unlink(e.path)
    except OSError:
        pass


def _valid_analysis(a) -> bool:
    """Whether ``a`` has the form :func:`_analyse_source` returns."""
    return (isinstance(a, dict) and type(a.get("dynamic")) is bool
            and type(a.get("parsed")) is bool and type(a.get("imports")) is list
            and all(type(i) is list and len(i) == 4 and type(i[0]) is int
                    and type(i[1]) is str and type(i[2]) is list and type(i[3]) is bool
                    and all(type(n) is str for n in i[2]) for i in a["imports"]))


def _valid_dependencies(d) -> bool:
    """Whether ``d`` holds the fields of :class:`KernelDependencies` as lists of str."""
    return (isinstance(d, dict) and set(d) == set(KernelDependencies.__dataclass_fields__)
            and all(type(v) is list and all(type(x) is str for x in v) for v in d.values()))


# --- per-file analysis and closure ----------------------------------------------------------


def _analyse_source(source: bytes, filename: str) -> dict:
    """Imports of one file (unresolved) and whether it imports by a computed name.

    ``{"imports": [[level, module, names, in_function], ...], "dynamic": bool,
    "parsed": bool}``.  A file that does not parse (it cannot be imported
    either) has no imports and ``parsed=False``.
    """
    try:
        tree = ast.parse(source, filename)
    except (SyntaxError, ValueError):        # ValueError: null bytes
        return {"imports": [], "dynamic": False, "parsed": False}
    imports, dynamic = [], False
    stack = [(tree, False)]
    while stack:
        node, in_function = stack.pop()
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.Import):
                imports += [[0, a.name, [], in_function] for a in child.names]
            elif isinstance(child, ast.ImportFrom):
                imports.append([child.level, child.module or "", [a.name for a in child.names],
                                in_function])
            elif isinstance(child, ast.Call):
                f = child.func
                name = f.id if isinstance(f, ast.Name) else getattr(f, "attr", None)
                dynamic = dynamic or name in _DYNAMIC_IMPORTS
            # a module-level __getattr__ (PEP 562) runs when ``from module import name``
            # asks for a missing name: its imports count as the module's own
            function = (isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
                        and not (isinstance(node, ast.Module)
                                 and getattr(child, "name", "") == "__getattr__"))
            stack.append((child, in_function or function))
    imports.sort()                           # deterministic, independent of the walk order
    return {"imports": imports, "dynamic": dynamic, "parsed": True}


def _module_name(folder: str, filename: str):
    """Dotted name of module ``filename`` in ``folder`` (``pkg/sub``); None if not importable."""
    parts = folder.split("/")
    if filename != "__init__.py":
        parts.append(filename[:-3])
    return ".".join(parts) if all(p.isidentifier() for p in parts) else None


def _resolve(module: str, is_package: bool, level: int, target: str):
    """Absolute name of an import of ``target`` at ``level`` from ``module``; None if invalid."""
    if level == 0:
        return target
    base = module.split(".") if is_package else module.split(".")[:-1]
    if level - 1 >= len(base):
        return None
    base = base[:len(base) - (level - 1)]
    return ".".join(base + [target] if target else base)


def _read_tree(root: Path):
    """({relative path: bytes}, {module: relative path}) of the ``*.py`` files under ``root``."""
    files, names = {}, {}
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames.sort()
        folder = Path(dirpath).relative_to(root.parent).as_posix()
        for fn in sorted(filenames):
            name = _module_name(folder, fn) if fn.endswith(".py") else None
            if name is None:
                continue
            rel = f"{folder}/{fn}"
            with open(os.path.join(dirpath, fn), "rb") as fh:
                files[rel] = fh.read()
            names[name] = rel
    return files, names


def _analyse_tree(root: Path, cache_dir):
    """(KernelDependencies, {relative path: bytes}) of the package at ``root``.

    Looks the whole tree up first (one stored entry per tree), then each
    file (one stored entry per file), and parses only the files not found.
    """
    files, names = _read_tree(root)
    tag = _analyser_tag()
    h = hashlib.sha1(tag.encode())
    for rel in sorted(files):
        h.update(f"\0{rel}\0{len(files[rel])}\0".encode())
        h.update(files[rel])
    tree_entry = f"{tag}-tree-{h.hexdigest()}.json"
    stored = _load(cache_dir, tree_entry, _valid_dependencies)
    if stored is not None:
        return KernelDependencies(**{k: tuple(v) for k, v in stored.items()}), files

    entries = {rel: f"{tag}-{hashlib.sha1(b).hexdigest()}.json" for rel, b in files.items()}
    analyses, new = {}, {}
    for rel, b in files.items():
        a = _load(cache_dir, entries[rel], _valid_analysis)
        if a is None:
            a = new[entries[rel]] = _analyse_source(b, rel)
        analyses[rel] = a
    deps = _closure(root.name, names, analyses)
    new[tree_entry] = {k: list(v) for k, v in vars(deps).items()}
    _store(cache_dir, new, set(entries.values()) | {tree_entry})
    return deps, files


def _closure(package: str, names: dict, analyses: dict) -> KernelDependencies:
    """The kernel modules of a tree and their closure (see the module docstring).

    Parameters
    ----------
    package : str
        Name of the top package.
    names : dict
        Module name -> relative path of its file.
    analyses : dict
        Relative path -> :func:`_analyse_source` of the file.
    """
    is_package = {m: rel.endswith("/__init__.py") for m, rel in names.items()}

    def resolved(m, imp):
        """(modules the import may run, names it takes, outside top-level name, in_function)."""
        level, target, imported, in_function = imp
        absolute = _resolve(m, is_package[m], level, target)
        if absolute is None:
            return (), (), None, in_function
        parts = absolute.split(".")
        if parts[0] != package:
            return (), (), parts[0], in_function
        run = [".".join(parts[:i]) for i in range(1, len(parts) + 1)]
        taken = [absolute]
        for n in imported:
            if n == "*":
                run += [s for s in names if s.rpartition(".")[0] == absolute]
            else:
                taken.append(f"{absolute}.{n}")
                run.append(f"{absolute}.{n}")
        return [r for r in run if r in names], taken, None, in_function

    imports = {m: [resolved(m, imp) for imp in analyses[rel]["imports"]]
               for m, rel in names.items()}
    numba_top, kernel_modules = set(), set()
    for m, imps in imports.items():
        for _, _, top, in_function in imps:
            if top == "numba":
                kernel_modules.add(m)
                if not in_function:
                    numba_top.add(m)
    for m, imps in imports.items():
        if not analyses[names[m]]["parsed"]:
            kernel_modules.add(m)       # cannot tell what it does: count it
        elif any(t in numba_top for _, taken, _, _ in imps for t in taken):
            kernel_modules.add(m)

    closure, outside, work = set(), set(), sorted(kernel_modules)
    while work:
        m = work.pop()
        if m in closure:
            continue
        closure.add(m)
        deps = {".".join(m.split(".")[:i]) for i in range(1, m.count(".") + 1)}   # parents
        for run, _, top, in_function in imports[m]:
            if in_function and m not in kernel_modules:
                continue
            deps.update(run)
            if top is not None and top not in sys.stdlib_module_names:
                outside.add(top)
        if analyses[names[m]]["dynamic"]:
            pkg = m if is_package[m] else m.rpartition(".")[0]
            deps.update(s for s in names if s == pkg or s.startswith(pkg + "."))
        work += sorted(deps - closure)
    return KernelDependencies(kernel_modules=tuple(sorted(kernel_modules)),
                              modules=tuple(sorted(closure)),
                              files=tuple(sorted(names[m] for m in closure)),
                              packages=tuple(sorted(outside)))
