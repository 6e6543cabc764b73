"""Every Sphinx-style cross-reference in the package and the docs points to something that exists.

A reference such as :func:`ppamsafety.impact.worst_instant` in a docstring or a Markdown page
is a promise to the reader that the object is there; when a module moves, the reference
must move with it.  The rules:

* a fully qualified reference (``ppamsafety.…``, with or without ``~``) must import: the
  longest importable module prefix, then attribute by attribute (a dataclass field or an
  annotated class attribute counts);
* a relative reference (``.x``, ``~.x.y``) or a bare one (``x``, ``Class.attr``) in a package
  module is looked up as Sphinx's search does, from that module outward: the module itself,
  then each enclosing package, then as an absolute name; a bare ``:meth:``/``:attr:`` name
  may also be a member of a class of that module (its own class);
* a bare name found none of these ways may still be an object defined in another module of
  the package (Sphinx's fuzzy search finds it); the test accepts it only if exactly one
  module of the package defines it, so that the reader's search finds one object.

Markdown pages and the scripts of ``studies/`` use fully qualified references only (they have
no enclosing package module).
"""

import importlib
import inspect
import pkgutil
import re
from functools import lru_cache
from pathlib import Path

import pytest

import ppamsafety

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "ppamsafety"
ROLE = re.compile(r":(?:py:)?(func|mod|class|meth|data|attr|exc|obj|const):"
                  r"`(?:[^`<]*<)?~?([\w.]+)>?`")


def _member(obj, name):
    """``getattr(obj, name)``, or a marker for a dataclass field / annotated class attribute."""
    try:
        return getattr(obj, name)
    except AttributeError:
        if inspect.isclass(obj) and any(name in getattr(k, "__annotations__", {})
                                        for k in obj.__mro__):
            return _member
        raise


def resolves(name):
    """Whether the dotted ``name`` imports (module prefix, then attributes)."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for attr in parts[i:]:
                obj = _member(obj, attr)
        except AttributeError:
            return False
        return True
    return False


def _module_name(path):
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


@lru_cache(maxsize=1)
def _definitions():
    """Bare name -> the package modules that define it (at module level or in a class)."""
    out = {}
    for info in pkgutil.walk_packages(ppamsafety.__path__, "ppamsafety."):
        if info.name.endswith("__main__"):
            continue
        mod = importlib.import_module(info.name)
        for key, value in vars(mod).items():
            if getattr(value, "__module__", None) == info.name or inspect.ismodule(value):
                out.setdefault(key, set()).add(info.name)
            if inspect.isclass(value) and value.__module__ == info.name:
                for attr in set(vars(value)) | set(getattr(value, "__annotations__", {})):
                    out.setdefault(f"{key}.{attr}", set()).add(info.name)
                    out.setdefault(attr, set()).add(info.name)
        out.setdefault(info.name.rsplit(".", 1)[-1], set()).add(info.name)
    return out


def resolves_in(module, name, role):
    """Whether ``name`` (relative or bare) resolves from ``module`` outward (module doc)."""
    bare = name.lstrip(".")
    parts = module.split(".")
    if any(resolves(".".join(parts[:i] + [bare])) for i in range(len(parts), 0, -1)):
        return True
    if resolves(bare):
        return True
    mod = importlib.import_module(module)
    if role in ("meth", "attr") and "." not in bare:
        for cls in vars(mod).values():
            if inspect.isclass(cls) and cls.__module__ == module:
                try:
                    _member(cls, bare)
                    return True
                except AttributeError:
                    pass
    return len(_definitions().get(bare, ())) == 1


def _references():
    out = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for m in ROLE.finditer(path.read_text(encoding="utf-8")):
            out.append((path.relative_to(ROOT).as_posix(), _module_name(path), *m.groups()))
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")),
                 *sorted((ROOT / "studies").rglob("*.py"))]:
        for m in ROLE.finditer(path.read_text(encoding="utf-8")):
            out.append((path.relative_to(ROOT).as_posix(), None, *m.groups()))
    return out


def test_the_pattern_reads_every_form():
    text = (":func:`ppamsafety.a.b` :class:`~ppamsafety.c.D` :mod:`.x` :py:meth:`E.f` "
            ":data:`the row <ppamsafety.layouts.Layout>`")
    assert [m.group(2) for m in ROLE.finditer(text)] == [
        "ppamsafety.a.b", "ppamsafety.c.D", ".x", "E.f", "ppamsafety.layouts.Layout"]


def test_resolution_tells_a_missing_object():
    assert resolves("ppamsafety.impact.worst_instant")
    assert resolves("ppamsafety.params.MuscleGroup.coefficients")      # a dataclass field
    assert not resolves("ppamsafety.diagnose.selection")               # no such module
    assert not resolves("ppamsafety.impact.no_such_function")
    assert resolves_in("ppamsafety.diagnose.arm.pipeline", ".selection", "mod")
    assert not resolves_in("ppamsafety.diagnose.arm.pipeline", ".no_such_module", "mod")


def test_there_are_references():
    assert len(_references()) > 500


def test_every_reference_resolves():
    broken = []
    for where, module, role, name in _references():
        ok = resolves(name) if name.startswith("ppamsafety.") or module is None \
            else resolves_in(module, name, role)
        if not ok:
            broken.append(f"{where}: :{role}:`{name}`")
    assert not broken, "references to objects that do not exist:\n" + "\n".join(broken)
