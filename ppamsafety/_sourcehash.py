"""Hashes of the package source that the caches follow: one for results, one for compiled kernels.

Two caches depend on different parts of the code, so they have two keys:

* :func:`source_hash` -- every ``*.py`` of the package.  The sweep result
  cache (:mod:`ppamsafety.sweep`) is keyed on it: a cached result may depend
  on any Python code (a section's post-processing, a default parameter, a
  table), so any edit anywhere gives fresh results.
* :func:`kernel_source_hash` -- only the files holding what compiled code
  depends on, plus the interpreter, library versions and numba settings that
  change the machine code.  The compiled-kernel cache (:mod:`ppamsafety._jit`)
  is keyed on it: numba alone only notices edits of a kernel's own file, not
  of a kernel it calls in another module nor of a module constant it reads
  from there (numba freezes global values at compile time), so editing any of
  those must change the key; editing a plot, a report section, the command
  line, the sweeps or the docs must not.

What the compiled code depends on (:func:`kernel_dependencies`) is found from
the source tree alone, by reading each file's syntax tree (nothing is imported,
nothing is listed by hand, so files may move), at the level of *names*: the
unit is a top-level statement of a module (a ``def``, a ``class``, an
assignment, an import, a call ...), and a file is in the key when one of its
statements is needed.

1. *Roots*: every statement that uses a compiler: numba's (``njit``, ``jit``,
   ``vectorize``, ... -- any name of numba but its types, settings and
   helpers), or a name made from one, found by following imports and
   assignments (``kernel = njit(...)`` and ``leaf`` in ``_jit``, ``k =
   kernel``, ``from .._jit import kernel as k``, ``partial(njit, ...)``, a
   function whose body calls a compiler).  A root is a decorated function, or
   ``f = kernel(g)`` / ``njit(sig)(g)`` (these make compiled functions, not
   new decorators; a plain Python function calling a kernel is no root).
2. *What a needed statement reads*: every global name its code reads (body,
   decorators, default values, annotations; a name bound in the function is
   local and skipped), as a chain: ``lay.L1`` on a module alias is name
   ``L1`` of that module, ``eng.impact_rhs`` likewise.  A name is resolved to
   the statements of its module that bind it (every one: a ``def``, a class --
   its whole body --, an assignment, an augmented assignment, a ``for``/
   ``with``/``if``/``try`` block, a function declaring it ``global``), and
   through imports to the module it comes from (``from pkg import sub`` of a
   submodule is the submodule); each import passed through is needed too (its
   file says where the name comes from).  Those statements are needed, and so
   on.  Names outside the package (numpy, math) are counted by the version of
   their distribution.
3. *Module-level statements that are not plain definitions* (a call such as
   ``register(...)``, an ``assert``, an ``if``/``try``/``for``/``with`` block,
   a store into an attribute or item, a star import) are needed whenever
   their module is in the key, and so are those of the parent packages'
   ``__init__`` (they run first) -- they may compute or change a value a
   kernel freezes.  A definition (``def``, ``class``, import, assignment to
   plain names) is needed only when a name it binds is.
4. *Writes on import from elsewhere*: a top-level statement of *any* module
   whose code run on import stores into a needed object (``consts.OFFSET =
   1``, ``TABLE[0] = 1``, ``setattr(TABLE, ...)``, ``del``), into a module of
   the key, into numba's settings, or into an object whose definition holds a
   needed one (``GROUP = (TABLE,)``), is needed, with what it reads.  So is
   any top-level statement that imports by a computed name, ``exec`` or
   ``eval`` on import.
5. *Conservative fallbacks* (listed in :attr:`KernelDependencies.fallbacks`):
   a star import is the whole source module; a name nobody binds (made by
   ``globals()`` or ``setattr`` from elsewhere) is the whole module, and a
   module used as an object (``getattr(mod, name)``, passed to a function) the
   whole module; ``globals()``/``vars()``/``locals()`` in a needed statement
   is its whole module; a computed import (``importlib.import_module``,
   ``__import__``), ``exec`` or ``eval`` in a needed statement is the whole
   package; a module ``__getattr__`` answers names a module does not bind; a
   file that does not parse is hashed whole (it fails on import anyway).

The key hashes every file holding a needed statement, whole (being
conservative within a file: any edit of a kernel module recompiles), and the
parent packages' ``__init__``.  What is *not* followed: mutation through a
method call or a function argument (``TABLE.fill(0)``, ``np.copyto(TABLE,
...)``) or through an object a call returns, and writes made inside functions
(only code run on import counts: a value changed after import, while kernels
may already be compiled, is a bug no cache key can fix).  The package keeps to
that: ``tests/test_kernel_cache.py`` imports it and checks that every global
every compiled function reads comes from a file of the key, and that the
values they read are the same when every module outside the key is replaced
by a stub.  Only ``*.py`` files count: a kernel module that read a data file
when imported would need that file added to the key (none does).

Parsing the whole package takes about 2 s, too slow for every process that
imports the kernels.  So the analyses are stored on disk (``cache_dir``, small
JSON files written atomically): each file's (its statements, with their
unresolved chains) under the hash of its bytes, and the resulting
:class:`KernelDependencies` under the hash of the whole tree.  A process reads
and hashes the files, finds the tree (about 10 ms), and otherwise parses only
the files edited since and resolves the names again (about 0.15 s); the key is
computed once per process.  An unreadable or malformed entry is analysed
again, and what gets hashed is always the current bytes of the files.
"""

from __future__ import annotations

import ast
import builtins
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

#: Functions that import a module whose name is only known at run time, or run code given as
#: text.
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
    """What the compiled kernels of a source tree depend on (:func:`kernel_dependencies`).

    Attributes
    ----------
    kernel_modules : tuple of str
        Modules holding compiled code or the decorators that compile it (a statement that
        uses numba's compilers or a name made from them, such as ``kernel``), sorted.
    kernels : tuple of str
        Those statements, as ``module:names`` (``ppamsafety.plant.model:rk4_step``), sorted.
    modules : tuple of str
        The modules of the key: those holding a statement the compiled code needs (see
        :mod:`ppamsafety._sourcehash`) and their parent packages, sorted.
    files : tuple of str
        Paths of the files of :attr:`modules`, relative to the parent of the package folder
        (``ppamsafety/plant/model.py``), sorted.
    packages : tuple of str
        Top-level names of the modules outside the package and the standard library that
        the needed statements use (``numpy``, ``scipy``, ...), sorted.
    fallbacks : tuple of str
        The conservative fallbacks taken (a star import, a name bound nowhere, a computed
        import, a write on import into what the kernels read ...), for review, sorted.
    """

    kernel_modules: tuple
    kernels: tuple
    modules: tuple
    files: tuple
    packages: tuple
    fallbacks: tuple


def kernel_dependencies(root=None, cache_dir=None) -> KernelDependencies:
    """What the compiled kernels of the package at ``root`` depend on, and the files holding it.

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
      :attr:`KernelDependencies.files` (those holding a statement compiled
      code needs, and their parent packages' ``__init__``, see
      :mod:`ppamsafety._sourcehash`), so editing anything a kernel needs
      changes it and editing a section, a plot (even one a kernel module
      imports), the command line or the docs does not;
    * the Python version, the numba, llvmlite and numpy versions, the version
      of every other package the needed statements use (by distribution name; a
      package installed under another name counts by name only), and the
      numba settings that change machine code without being part of numba's
      own cache key (``NUMBA_BOUNDSCHECK``, ``NUMBA_OPT``, ...).  numba keys
      each cached function on the CPU itself.

    Unlike :func:`source_hash` it does not change when a file the kernels do
    not need changes, so it must not key caches of Python results.

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
    h = hashlib.sha1(b"ppamsafety kernel key 2\0")
    for name, value in _machine_code_environment(deps.packages):
        h.update(f"{name}={value}\0".encode())
    for rel in deps.files:
        b = data[rel]
        h.update(f"{rel}\0{len(b)}\0".encode())
        h.update(b)
    return h.hexdigest()[:16]


def _machine_code_environment(packages) -> list:
    """(name, value) pairs outside the source that change the kernels' machine code, sorted."""
    # deferred on purpose (the one exception in this module): hashing source needs no numba,
    # and this bottom-layer module is imported by every command, `--help` included; numba and
    # llvmlite take 1.5 s to import (python -X importtime) and are needed only for a kernel key
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


def _valid_chain(c) -> bool:
    """Whether ``c`` is a chain (see :func:`_analyse_source`)."""
    if type(c) is not list or len(c) < 2:
        return False
    if c[0] == "i":
        return len(c) >= 4 and type(c[1]) is int and all(type(x) is str for x in c[2:])
    return c[0] in ("g", "s") and all(type(x) is str for x in c[1:])


def _valid_spec(s) -> bool:
    return (type(s) is list and len(s) == 3 and type(s[0]) is int and type(s[1]) is str
            and type(s[2]) is str)


def _valid_statement(s) -> bool:
    applied = s.get("applied")
    return (type(s.get("line")) is int and type(s.get("node")) is str
            and s.get("kind") in ("def", "side")
            and type(s.get("binds")) is list
            and all(type(b) is list and len(b) == 2 and type(b[0]) is str
                    and (b[1] is None or _valid_spec(b[1])) for b in s["binds"])
            and type(s.get("star")) is list
            and all(type(x) is list and len(x) == 2 and type(x[0]) is int
                    and type(x[1]) is str for x in s["star"])
            and all(type(s.get(k)) is list and all(_valid_chain(c) for c in s[k])
                    for k in ("head", "body"))
            and type(s.get("writes")) is list
            and all(type(w) is list and len(w) == 2 and _valid_chain(w[0])
                    and (w[1] is None or type(w[1]) is str) for w in s["writes"])
            and all(type(s.get(k)) is bool for k in ("dynamic", "import_dynamic", "reflective"))
            and (applied is None or type(applied) is list and len(applied) == 2
                 and type(applied[0]) is list and all(_valid_chain(c) for c in applied[0])
                 and (applied[1] is None or applied[1] == "lambda"
                      or _valid_chain(applied[1]))))


def _valid_analysis(a) -> bool:
    """Whether ``a`` has the form :func:`_analyse_source` returns."""
    return (isinstance(a, dict) and set(a) == {"parsed", "stmts"} and type(a["parsed"]) is bool
            and type(a["stmts"]) is list
            and all(isinstance(s, dict) and _valid_statement(s) for s in a["stmts"]))


def _valid_dependencies(d) -> bool:
    """Whether ``d`` holds the fields of :class:`KernelDependencies` as lists of str."""
    return (isinstance(d, dict) and set(d) == set(KernelDependencies.__dataclass_fields__)
            and all(type(v) is list and all(type(x) is str for x in v) for v in d.values()))


# --- per-file analysis: the top-level statements and what each references -----------------
#
# A reference is a chain, a JSON list: ``["g", name, attr, ...]`` a global name of the module
# (``lay.L1`` is ``["g", "lay", "L1"]``), ``["s", name, attr, ...]`` a name a class body may
# read from its own namespace or else from the module (resolved only if the module binds it),
# ``["i", level, module, name, attr, ...]`` a name bound by an import inside a function
# (``name`` is "" for ``import module``).


_FUNCTIONS = (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)
_COMPREHENSIONS = (ast.ListComp, ast.SetComp, ast.DictComp, ast.GeneratorExp)
#: Calls that, without arguments, give the namespace of the module as a dict.
_REFLECTIVE = frozenset({"globals", "vars", "locals"})


def _import_spec(node, alias) -> tuple:
    """(bound name, [level, module, name]) of one alias of an import statement.

    ``import a.b`` binds ``a`` to module ``a`` (name ""), ``import a.b as c`` binds ``c`` to
    module ``a.b``, ``from m import n as c`` binds ``c`` to attribute ``n`` of module ``m``.
    """
    if isinstance(node, ast.Import):
        if alias.asname:
            return alias.asname, [0, alias.name, ""]
        top = alias.name.split(".")[0]
        return top, [0, top, ""]
    return alias.asname or alias.name, [node.level, node.module or "", alias.name]


class _Scope:
    """Names bound in one function, class or comprehension scope."""

    __slots__ = ("kind", "local", "imports", "declared_global")

    def __init__(self, kind):
        self.kind = kind
        self.local = set()
        self.imports = {}
        self.declared_global = set()


def _collect_bindings(nodes, scope: _Scope) -> None:
    """Add to ``scope`` the names that ``nodes`` (statements or expressions of it) bind.

    Does not enter nested functions, classes or comprehensions (their names are their
    own), only their names and the parts evaluated in this scope.
    """
    stack = list(nodes)
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            scope.local.add(node.name)
            stack += node.decorator_list
            if isinstance(node, ast.ClassDef):
                stack += node.bases + [k.value for k in node.keywords]
            else:
                stack += _argument_heads(node.args)
            continue
        if isinstance(node, ast.Lambda):
            stack += _argument_heads(node.args)
            continue
        if isinstance(node, _COMPREHENSIONS):
            stack.append(node.generators[0].iter)
            continue
        if isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
            scope.local.add(node.id)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            for a in node.names:
                if a.name == "*":
                    continue
                name, spec = _import_spec(node, a)
                scope.local.add(name)
                scope.imports[name] = spec
        elif isinstance(node, (ast.Global, ast.Nonlocal)):
            if isinstance(node, ast.Global):
                scope.declared_global.update(node.names)
        elif isinstance(node, ast.ExceptHandler) and node.name:
            scope.local.add(node.name)
        elif isinstance(node, (ast.MatchAs, ast.MatchStar)) and node.name:
            scope.local.add(node.name)
        elif isinstance(node, ast.MatchMapping) and node.rest:
            scope.local.add(node.rest)
        stack += ast.iter_child_nodes(node)
    scope.local -= scope.declared_global


def _argument_heads(args: ast.arguments) -> list:
    """Default values and annotations of ``args``: evaluated where the function is defined."""
    heads = list(args.defaults) + [d for d in args.kw_defaults if d is not None]
    for a in args.posonlyargs + args.args + args.kwonlyargs + [args.vararg, args.kwarg]:
        if a is not None and a.annotation is not None:
            heads.append(a.annotation)
    return heads


def _argument_names(args: ast.arguments) -> set:
    return {a.arg for a in args.posonlyargs + args.args + args.kwonlyargs
            + [args.vararg, args.kwarg] if a is not None}


def _chain(node):
    """(base Name node, [attr, ...]) of an attribute chain ``a.b.c``; None if not one."""
    attrs = []
    while isinstance(node, ast.Attribute):
        attrs.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        return node, attrs[::-1]
    return None


class _StatementVisitor:
    """References, writes and flags of one top-level statement (see :func:`_analyse_source`)."""

    def __init__(self):
        self.refs = []              # chains (JSON lists), in order, duplicates removed later
        self.writes = []            # [chain, attr or None or "*"] of import-time code
        self.dynamic = False        # a computed import, exec or eval anywhere
        self.import_dynamic = False   # ... in the code run when the statement runs
        self.reflective = False     # globals(), vars(), locals(): the namespace as a dict
        self.global_binds = set()   # module names bound by functions (``global``)

    # -- names --------------------------------------------------------------------------

    def _name_ref(self, name: str, attrs: list, scopes: list) -> list | None:
        """The chain of a read of ``name`` (then ``attrs``) from ``scopes``; None if local."""
        for i in range(len(scopes) - 1, -1, -1):
            s = scopes[i]
            if s.kind == "class" and i != len(scopes) - 1:
                continue                # a class namespace is not seen by nested scopes
            if name in s.declared_global:
                return ["g", name, *attrs]
            if name in s.imports:
                level, module, imported = s.imports[name]
                return ["i", level, module, imported, *attrs]
            if name in s.local:
                if s.kind == "class":
                    return ["s", name, *attrs]    # the class namespace, or else the module
                return None
        return ["g", name, *attrs]

    def _ref(self, name, attrs, scopes):
        r = self._name_ref(name, attrs, scopes)
        if r is not None:
            self.refs.append(r)
        return r

    # -- traversal -----------------------------------------------------------------------

    def visit_all(self, nodes, scopes, runtime):
        for n in nodes:
            self.visit(n, scopes, runtime)

    def visit(self, node, scopes, runtime):
        """Record what ``node`` reads; ``runtime``: inside a function body (not run on import)."""
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            self.visit_all(node.decorator_list + _argument_heads(node.args), scopes, runtime)
            if node.returns is not None:
                self.visit(node.returns, scopes, runtime)
            self._function(node.args, node.body, scopes)
            return
        if isinstance(node, ast.Lambda):
            self.visit_all(_argument_heads(node.args), scopes, runtime)
            self._function(node.args, [node.body], scopes)
            return
        if isinstance(node, ast.ClassDef):
            self.visit_all(node.decorator_list + node.bases + [k.value for k in node.keywords],
                           scopes, runtime)
            scope = _Scope("class")
            _collect_bindings(node.body, scope)
            self.visit_all(node.body, scopes + [scope], runtime)
            return
        if isinstance(node, _COMPREHENSIONS):
            first = node.generators[0]
            self.visit(first.iter, scopes, runtime)     # evaluated in the enclosing scope
            scope = _Scope("function")
            for g in node.generators:
                _collect_bindings([g.target], scope)
            inner = scopes + [scope]
            self.visit(first.target, inner, runtime)
            for c in first.ifs:
                self.visit(c, inner, runtime)
            for g in node.generators[1:]:
                self.visit_all([g.target, g.iter, *g.ifs], inner, runtime)
            if isinstance(node, ast.DictComp):
                self.visit_all([node.key, node.value], inner, runtime)
            else:
                self.visit(node.elt, inner, runtime)
            return
        if isinstance(node, ast.Global):
            return
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            return                      # bindings, resolved through the scopes
        if isinstance(node, ast.Name):
            if isinstance(node.ctx, ast.Load):
                self._ref(node.id, [], scopes)
            elif scopes and node.id in scopes[-1].declared_global:
                self.global_binds.add(node.id)
            return
        if isinstance(node, ast.Attribute):
            c = _chain(node)
            if c is not None and isinstance(node.ctx, ast.Load):
                self._ref(c[0].id, c[1], scopes)
                return
            if c is not None:           # a.b.c = v, del a.b.c: a.b is read, and written
                r = self._ref(c[0].id, c[1][:-1], scopes)
                if not runtime and r is not None:
                    self.writes.append([r, node.attr])
                return
            if isinstance(node.ctx, ast.Load):
                self.visit(node.value, scopes, runtime)
            else:                       # a[i].c = v: into what a holds
                self._store_into(node.value, scopes, runtime)
            return
        if isinstance(node, ast.Subscript) and not isinstance(node.ctx, ast.Load):
            self._store_into(node.value, scopes, runtime)   # a.b[i] = v: a.b is written
            self.visit(node.slice, scopes, runtime)
            return
        if isinstance(node, ast.AugAssign) and not isinstance(node.target, ast.Name):
            # a.b += v, a[i] += v: the target is read too
            self.visit(node.target, scopes, runtime)
            t = node.target
            if isinstance(t, ast.Attribute) and _chain(t) is not None:
                c = _chain(t)
                self._ref(c[0].id, c[1], scopes)
            elif isinstance(t, ast.Subscript) and _chain(t.value) is not None:
                c = _chain(t.value)
                self._ref(c[0].id, c[1], scopes)
            self.visit(node.value, scopes, runtime)
            return
        if isinstance(node, ast.AugAssign):
            self._ref(node.target.id, [], scopes)
            if scopes and node.target.id in scopes[-1].declared_global:
                self.global_binds.add(node.target.id)
            self.visit(node.value, scopes, runtime)
            return
        if isinstance(node, ast.Call):
            self._call(node, scopes, runtime)
        for child in ast.iter_child_nodes(node):
            self.visit(child, scopes, runtime)

    def _store_into(self, obj, scopes, runtime):
        """Record a store into (an attribute or item of) the object ``obj``.

        ``a.b[i] = v``, ``a.b[i][j] = v``, ``a.b[i].c = v``: all write into what ``a.b``
        holds, so the write is recorded on ``a.b`` (the attributes up to the first item).
        """
        path = []
        node = obj
        while isinstance(node, (ast.Attribute, ast.Subscript)):
            path.append(node)
            node = node.value
        if not isinstance(node, ast.Name):
            self.visit(obj, scopes, runtime)    # into what a call returns: not followed
            return
        attrs = []
        for p in reversed(path):
            if not isinstance(p, ast.Attribute):
                break
            attrs.append(p.attr)
        r = self._ref(node.id, attrs, scopes)
        if not runtime and r is not None:
            self.writes.append([r, None])
        for p in path:
            if isinstance(p, ast.Subscript):
                self.visit(p.slice, scopes, runtime)

    def _function(self, args, body, scopes):
        scope = _Scope("function")
        scope.local |= _argument_names(args)
        _collect_bindings(body, scope)
        self.visit_all(body, scopes + [scope], True)

    def _call(self, node, scopes, runtime):
        f = node.func
        name = f.id if isinstance(f, ast.Name) else getattr(f, "attr", None)
        if name in _DYNAMIC_IMPORTS:
            self.dynamic = True
            self.import_dynamic = self.import_dynamic or not runtime
        if isinstance(f, ast.Name) and name in _REFLECTIVE and not node.args:
            self.reflective = True
        if (not runtime and isinstance(f, ast.Name) and name in ("setattr", "delattr")
                and node.args):
            c = _chain(node.args[0])
            if c is not None:
                r = self._name_ref(c[0].id, c[1], scopes)
                if r is not None:
                    a = node.args[1] if len(node.args) > 1 else None
                    attr = a.value if isinstance(a, ast.Constant) and isinstance(
                        a.value, str) else "*"
                    self.writes.append([r, attr])


def _statement_kind(node) -> str:
    """"def" for a plain definition (needed only for the names it binds), "side" otherwise.

    Plain definitions: def, class, import, and assignments to plain names.  Everything else
    (calls, asserts, ``if``/``try``/``for``/``with`` blocks, stores into attributes or
    items, ``del``) is counted whenever its module is in the key.
    """
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        return "def"
    if isinstance(node, ast.Import):
        return "def"
    if isinstance(node, ast.ImportFrom):
        return "side" if any(a.name == "*" for a in node.names) else "def"
    if isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
        targets = node.targets if isinstance(node, ast.Assign) else [node.target]
        names_only = all(isinstance(n, (ast.Name, ast.Tuple, ast.List, ast.Starred,
                                        ast.Store, ast.Load))
                         for t in targets for n in ast.walk(t))
        return "def" if names_only else "side"
    return "side"


def _applied(node):
    """[chains read by the called expression, first argument] of ``name = f(g, ...)``; else None.

    ``impact_rhs = kernel(_impact_rhs_py)`` applies ``kernel`` to a function: it makes a
    compiled function, not another decorator.  The first argument is a chain, "lambda", or
    None (anything else).
    """
    value = getattr(node, "value", None)
    if (not isinstance(node, (ast.Assign, ast.AnnAssign)) or not isinstance(value, ast.Call)
            or not value.args):
        return None
    v = _StatementVisitor()
    v.visit(value.func, [], False)
    a = value.args[0]
    c = _chain(a)
    first = "lambda" if isinstance(a, ast.Lambda) else None if c is None else ["g", c[0].id, *c[1]]
    return [_unique(v.refs), first]


def _unique(chains) -> list:
    seen, out = set(), []
    for c in chains:
        t = tuple(c)
        if t not in seen:
            seen.add(t)
            out.append(c)
    return out


def _analyse_statement(node) -> dict:
    """What one top-level statement binds, reads and writes (see :func:`_analyse_source`)."""
    module_scope = _Scope("module")
    binds = []
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        binds.append([node.name, None])
    else:
        _collect_bindings([node], module_scope)
        for name in sorted(module_scope.local - set(module_scope.imports)):
            binds.append([name, None])
        for name, spec in sorted(module_scope.imports.items()):
            binds.append([name, spec])
    star = [[n.level, n.module or ""] for n in ast.walk(node)
            if isinstance(n, ast.ImportFrom) and any(a.name == "*" for a in n.names)]
    v = _StatementVisitor()
    head = body = None
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        # head: what runs where it is defined (decorators, defaults, annotations, bases);
        # body: the function's code, or the class body
        heads = list(node.decorator_list)
        if isinstance(node, ast.ClassDef):
            heads += node.bases + [k.value for k in node.keywords]
        else:
            heads += _argument_heads(node.args) + ([node.returns] if node.returns else [])
        v.visit_all(heads, [], False)
        head = _unique(v.refs)
        n_head = len(v.refs)
        if isinstance(node, ast.ClassDef):
            scope = _Scope("class")
            _collect_bindings(node.body, scope)
            v.visit_all(node.body, [scope], False)
        else:
            v._function(node.args, node.body, [])
        body = _unique(v.refs[n_head:])
    else:
        v.visit(node, [], False)
        head, body = _unique(v.refs), []
    for name in sorted(v.global_binds - {b[0] for b in binds}):
        binds.append([name, None])           # ``global name`` in a function binds it
    return {"line": node.lineno, "node": type(node).__name__, "kind": _statement_kind(node),
            "binds": binds, "star": star, "head": head, "body": body, "writes": v.writes,
            "dynamic": v.dynamic, "import_dynamic": v.import_dynamic,
            "reflective": v.reflective, "applied": _applied(node)}


def _analyse_source(source: bytes, filename: str) -> dict:
    """What each top-level statement of one file binds, reads and writes.

    ``{"parsed": bool, "stmts": [statement, ...]}``, each statement a dict: ``line``,
    ``kind`` ("def" or "side", see :func:`_statement_kind`), ``binds`` ([name, import] with
    import None or [level, module, name]), ``star`` ([level, module] of star imports),
    ``head`` and ``body`` (the chains it reads: for a def or class, ``head`` is what runs
    where it is defined and ``body`` its code; for other statements all of it is ``head``),
    ``writes`` ([chain, attribute] stored into by the code run on import), the flags
    ``dynamic``, ``import_dynamic``, ``reflective``, ``getattr``, and ``applied_to``.  A file
    that does not parse (it cannot be imported either) has ``parsed=False``.
    """
    try:
        tree = ast.parse(source, filename)
    except (SyntaxError, ValueError):        # ValueError: null bytes
        return {"parsed": False, "stmts": []}
    return {"parsed": True, "stmts": [_analyse_statement(node) for node in tree.body]}


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
    deps = _dependencies(root.name, names, analyses)
    new[tree_entry] = {k: list(v) for k, v in vars(deps).items()}
    _store(cache_dir, new, set(entries.values()) | {tree_entry})
    return deps, files


# --- the whole tree: names, what the compiled code needs, the files that hold it -----------


#: numba names that compile nothing (types, settings, helpers read inside kernels); any other
#: use of numba counts as a compiler (``numba.njit``, ``numba.core.decorators.jit``, ...).
_NUMBA_NOT_COMPILERS = frozenset({
    "types", "typeof", "typed", "config", "prange", "literal_unroll", "literally", "errors",
    "from_dtype", "carray", "farray", "objmode", "get_num_threads", "set_num_threads",
    "get_thread_id", "threading_layer", "__version__", "version_info"})
#: Names every module has without binding them.
_MODULE_DUNDERS = frozenset({"__name__", "__file__", "__doc__", "__spec__", "__loader__",
                             "__package__", "__path__", "__builtins__", "__cached__",
                             "__annotations__", "__dict__"})


class _Tree:
    """Name resolution over the analysed files of one package (see :func:`_dependencies`).

    A *value* is a tuple: ``("n", module, i)`` the object bound by top-level statement ``i``,
    ``("v", module, i)`` an import statement passed through on the way, ``("m", module)`` a
    module of the package used by name, ``("w", module)`` the whole of a module (a module
    used as an object, a name nobody binds), ``("x", dotted)`` something outside the package.
    """

    def __init__(self, package: str, names: dict, analyses: dict):
        self.package = package
        self.files = names
        self.is_package = {m: rel.endswith("/__init__.py") for m, rel in names.items()}
        self.stmts = {m: analyses[rel]["stmts"] for m, rel in names.items()}
        self.parsed = {m: analyses[rel]["parsed"] for m, rel in names.items()}
        self.bind, self.stars, self.getattr = {}, {}, {}
        for m, stmts in self.stmts.items():
            bind = self.bind[m] = {}
            for i, s in enumerate(stmts):
                for name, spec in s["binds"]:
                    bind.setdefault(name, []).append((i, spec))
            self.stars[m] = [i for i, s in enumerate(stmts) if s["star"]]
            self.getattr[m] = [i for i, _ in bind.get("__getattr__", [])]
        self.builtins = frozenset(dir(builtins))
        self.fallbacks = set()      # conservative fallbacks taken, for review
        self._attr_memo, self._chain_memo, self._active = {}, {}, set()

    def internal(self, module: str) -> bool:
        return module == self.package or module.startswith(self.package + ".")

    def import_values(self, module: str, spec) -> list:
        """Values of an import ``[level, target, name]`` made in ``module``."""
        level, target, name = spec
        absolute = _resolve(module, self.is_package[module], level, target)
        if absolute is None:
            return []                       # beyond the top package: fails on import
        if not name:
            if not self.internal(absolute):
                return [("x", absolute)]
            return [("m", absolute)] if absolute in self.files else []
        return self.attr(absolute, name)

    def lookup(self, module: str, name: str) -> list:
        """Values of the module-level bindings of ``name`` in ``module`` (star imports too)."""
        out = []
        for i, spec in self.bind[module].get(name, ()):
            if spec is None:
                out.append(("n", module, i))
            else:
                out.append(("v", module, i))
                out += self.import_values(module, spec)
        for i in self.stars[module]:        # may bind any name: the whole source module
            out.append(("v", module, i))
            for level, target in self.stmts[module][i]["star"]:
                absolute = _resolve(module, self.is_package[module], level, target)
                if absolute is not None and self.internal(absolute):
                    if absolute in self.files:
                        out.append(("w", absolute))
                elif absolute is not None:
                    out.append(("x", absolute))
            self.fallbacks.add(f"{module}: star import, whole module")
        return out

    def attr(self, module: str, name: str) -> list:
        """Values of ``module.name`` read from outside ``module``."""
        if not self.internal(module):
            return [("x", f"{module}.{name}")]
        if module not in self.files:        # a folder without __init__: its submodules
            sub = f"{module}.{name}"
            return [("m", sub)] if sub in self.files else []
        key = (module, name)
        if key in self._attr_memo:
            return self._attr_memo[key]
        if key in self._active:             # a cycle of imports: count the whole module
            return [("w", module)]
        self._active.add(key)
        out = self.lookup(module, name)
        if f"{module}.{name}" in self.files:
            out.append(("m", f"{module}.{name}"))
        if not out:
            if self.getattr[module]:        # a module __getattr__ answers
                out = [("n", module, i) for i in self.getattr[module]]
            elif name not in _MODULE_DUNDERS:
                out = [("w", module)]
                self.fallbacks.add(f"{module}.{name}: bound nowhere, whole module")
        self._active.discard(key)
        self._attr_memo[key] = out = _dedupe(out)
        return out

    def values(self, module: str, chain) -> list:
        """Values of a chain read in ``module``; modules used by name become whole modules."""
        key = (module, tuple(chain))
        if key in self._chain_memo:
            return self._chain_memo[key]
        kind = chain[0]
        if kind == "i":
            vals, attrs = self.import_values(module, chain[1:4]), chain[4:]
        else:
            name, attrs = chain[1], chain[2:]
            vals = self.lookup(module, name)
            if not vals and kind == "g" and name not in self.builtins \
                    and name not in _MODULE_DUNDERS:
                vals = [("w", module)]      # bound by nobody we can see
                self.fallbacks.add(f"{module}: global {name} bound nowhere, whole module")
        vals = self._follow(vals, attrs)
        out = _dedupe([("w", v[1]) if v[0] == "m" else v for v in vals])
        self._chain_memo[key] = out
        return out

    def _follow(self, vals, attrs) -> list:
        for a in attrs:
            new = []
            for v in vals:
                if v[0] == "m":
                    new += self.attr(v[1], a)
                elif v[0] == "x":
                    new.append(("x", f"{v[1]}.{a}"))
                else:
                    new.append(v)           # an attribute of an object: the object
            vals = new
        return vals

    def write_targets(self, module: str, chain, attr) -> list:
        """Values a write ``chain.attr = ...`` (``attr`` None: ``chain[...] = ...``) changes."""
        kind = chain[0]
        if kind == "i":
            vals, attrs = self.import_values(module, chain[1:4]), chain[4:]
        else:
            vals, attrs = self.lookup(module, chain[1]), chain[2:]
        out = []
        for v in self._follow(vals, attrs):
            if v[0] == "m":
                if attr is None or attr == "*":
                    out.append(("w", v[1]))
                else:
                    out += self.attr(v[1], attr)
            else:
                out.append(v)
        return out

    def stmt(self, node) -> dict:
        return self.stmts[node[1]][node[2]]


def _dedupe(vals) -> list:
    return list(dict.fromkeys(vals))


def _is_compiler_path(path: str) -> bool:
    """Whether the name ``path`` outside the package may be one of numba's compilers."""
    parts = path.split(".")
    return (parts[0] == "numba" and (len(parts) == 1 or parts[1] not in _NUMBA_NOT_COMPILERS)
            and not (len(parts) > 2 and parts[1] == "core"
                     and parts[2] in _NUMBA_NOT_COMPILERS))


def _dependencies(package: str, names: dict, analyses: dict) -> KernelDependencies:
    """What the compiled code of a tree needs (see the module docstring).

    Parameters
    ----------
    package : str
        Name of the top package.
    names : dict
        Module name -> relative path of its file.
    analyses : dict
        Relative path -> :func:`_analyse_source` of the file.
    """
    t = _Tree(package, names, analyses)
    nodes = [(m, i) for m in sorted(t.stmts) for i in range(len(t.stmts[m]))]

    # 1. compilers: numba's decorators and every name made from them (kernel, leaf, aliases)
    aliases = set()

    def compiles(module, chains) -> bool:
        for c in chains:
            for v in t.values(module, c):
                if v[0] == "x" and _is_compiler_path(v[1]):
                    return True
                if v[0] == "n" and (v[1], v[2]) in aliases:
                    return True
                if v[0] == "w" and any(a[0] == v[1] for a in aliases):
                    return True
        return False

    def applies_to_function(module, s) -> bool:
        """Whether ``s`` is ``name = <compiler>(function)`` (a compiled function)."""
        func_chains, first = s["applied"] or ([], None)
        if first is None or not compiles(module, func_chains):
            return False
        rest = [c for c in s["head"] if c not in func_chains and c != first]
        if compiles(module, rest):
            return False
        if first == "lambda":
            return True
        vals = [v for v in t.values(module, first) if v[0] != "v"]
        return bool(vals) and all(v[0] == "n" and t.stmt(v)["node"] in (
            "FunctionDef", "AsyncFunctionDef") for v in vals)

    changed = True
    while changed:
        changed = False
        for m, i in nodes:
            if (m, i) in aliases:
                continue
            s = t.stmts[m][i]
            if s["node"] in ("FunctionDef", "AsyncFunctionDef", "ClassDef"):
                alias = compiles(m, s["body"])      # makes compiled code when called
            else:
                alias = compiles(m, s["head"]) and not applies_to_function(m, s)
            if alias:
                aliases.add((m, i))
                changed = True

    # 2. roots: every statement that uses a compiler
    roots = {(m, i) for m, i in nodes
             if (m, i) in aliases or compiles(m, t.stmts[m][i]["head"] + t.stmts[m][i]["body"])}

    # 3. what they need, and what code run on import writes into it
    all_modules = sorted(t.files)
    writers = [(m, i) for m, i in nodes
               if t.stmts[m][i]["writes"] or t.stmts[m][i]["import_dynamic"]]
    extra = set()
    while True:
        needed, key, outside = _needed(t, roots | extra, all_modules)
        grown = False
        for m, i in writers:
            if (m, i) in needed or (m, i) in extra:
                continue
            s = t.stmts[m][i]
            hit = s["import_dynamic"]
            for chain, attr in s["writes"]:
                if hit:
                    break
                hit = any(_changes_needed(t, v, needed, key)
                          for v in t.write_targets(m, chain, attr))
            if hit:
                t.fallbacks.add(f"{m} line {s['line']}: writes on import into what kernels read")
                extra.add((m, i))
                grown = True
        if not grown:
            break

    def label(m, i):
        s = t.stmts[m][i]
        return f"{m}:" + (",".join(b[0] for b in s["binds"]) or f"line {s['line']}")

    return KernelDependencies(
        kernel_modules=tuple(sorted({m for m, _ in roots})),
        kernels=tuple(sorted(label(m, i) for m, i in roots)),
        modules=tuple(sorted(key)),
        files=tuple(sorted(t.files[m] for m in key)),
        packages=tuple(sorted(outside)),
        fallbacks=tuple(sorted(t.fallbacks)))


def _changes_needed(t: _Tree, v, needed: set, key: set) -> bool:
    """Whether writing into value ``v`` can change something the kernels need.

    A needed object, a module of the key, numba itself (its settings), or an object whose
    definition holds a needed one (``TABLE = (A, B)``: writing into ``TABLE[0]`` writes into
    ``A``).
    """
    if v[0] == "x":
        return _is_compiler_path(v[1]) or v[1].split(".")[0] in ("numba", "llvmlite")
    if v[0] == "w":
        return v[1] in key
    seen, work = set(), [(v[1], v[2])]
    while work:
        node = work.pop()
        if node in needed:
            return True
        if node in seen:
            continue
        seen.add(node)
        s = t.stmts[node[0]][node[1]]
        for c in s["head"] + (s["body"] if s["node"] == "ClassDef" else []):
            for u in t.values(node[0], c):
                if u[0] == "w" and u[1] in key:
                    return True
                if u[0] in ("n", "v"):
                    work.append((u[1], u[2]))
    return False


def _needed(t: _Tree, roots: set, all_modules: list):
    """(needed statements, modules of the key, outside packages) reached from ``roots``.

    A needed statement's module is in the key, with every "side" statement of it and its
    parent packages (their ``__init__`` runs first); what a needed statement reads is needed;
    a whole module is every statement of it; a computed import, ``exec`` or ``eval`` makes
    the whole package needed, ``globals()`` the whole module.
    """
    needed, key, whole, outside = set(), set(), set(), set()
    work = sorted(roots, reverse=True)

    def add_module(m):
        while m and m not in key:
            if m in t.files:                # not a folder without __init__
                key.add(m)
                if not t.parsed[m]:
                    t.fallbacks.add(f"{m}: does not parse")
                work.extend((m, i) for i, s in enumerate(t.stmts[m]) if s["kind"] == "side")
            m = m.rpartition(".")[0]

    def add_whole(m):
        if m not in whole:
            whole.add(m)
            add_module(m)
            work.extend((m, i) for i in range(len(t.stmts[m])))

    while work:
        node = work.pop()
        if node in needed:
            continue
        needed.add(node)
        m, i = node
        add_module(m)
        s = t.stmts[m][i]
        for c in s["head"] + s["body"]:
            for v in t.values(m, c):
                if v[0] in ("n", "v"):
                    if (v[1], v[2]) not in needed:
                        work.append((v[1], v[2]))
                elif v[0] == "w":
                    add_whole(v[1])
                else:
                    top = v[1].split(".")[0]
                    if top not in sys.stdlib_module_names:
                        outside.add(top)
        for b in s["binds"]:
            if b[1] is not None:            # an import of something outside the package
                for v in t.import_values(m, b[1]):
                    if v[0] == "x" and v[1].split(".")[0] not in sys.stdlib_module_names:
                        outside.add(v[1].split(".")[0])
        if s["dynamic"]:
            t.fallbacks.add(f"{m} line {s['line']}: computed import, exec or eval: whole package")
            for other in all_modules:
                add_whole(other)
        if s["reflective"]:
            t.fallbacks.add(f"{m} line {s['line']}: module namespace as a dict: whole module")
            add_whole(m)
    return needed, key, outside
