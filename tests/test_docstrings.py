"""Every public function, method and class documents each of its parameters (numpydoc).

Modelled on python-control's ``control/tests/docstrings_test.py``, without a
numpydoc dependency: a small parser reads the ``Parameters`` section (and,
for classes, also ``Attributes`` -- dataclass fields are documented there)
and collects the names it documents (``a, b : float`` documents ``a`` and
``b``).  ``*args``/``**kwargs`` must appear as ``*args``/``**kwargs``;
``self``/``cls`` are skipped.

What is checked: objects defined in a ``ppamsafety`` module (``__module__``
is that module) whose name does not start with ``_``: functions, classes
(their constructor signature) and the public methods, classmethods and
staticmethods defined in those classes.  numba dispatchers (``@njit``
kernels) are checked through their ``py_func`` (the Python function they
compile); dispatcher-like objects without a ``py_func`` or whose signature
``inspect`` cannot read (e.g. ``@vectorize`` ufuncs) are skipped.  Enum
classes are skipped (their constructor is the enum machinery's).

ALLOWLIST: functions exempt from the check.  It listed the items that were
undocumented when this test was added (issue 7 item 9); all of them are
documented now and it is empty.  ``test_allowlist_has_no_stale_entries``
fails once an entry is documented, so the list can only shrink.  Do not add
to it.
"""

from __future__ import annotations

import enum
import importlib
import inspect
import pkgutil
import re

import pytest

import ppamsafety

_HEADER = re.compile(r"^\s*([A-Za-z][A-Za-z ]*)\n\s*-{3,}\s*$", re.M)


def _sections(doc: str) -> dict:
    """Section title -> body text of a numpydoc docstring."""
    doc = inspect.cleandoc(doc or "")
    lines = doc.splitlines()
    out, title, body = {}, None, []
    i = 0
    while i < len(lines):
        if (i + 1 < len(lines) and re.fullmatch(r"\s*-{3,}\s*", lines[i + 1])
                and lines[i].strip()):
            if title is not None:
                out[title] = "\n".join(body)
            title, body = lines[i].strip(), []
            i += 2
            continue
        body.append(lines[i])
        i += 1
    if title is not None:
        out[title] = "\n".join(body)
    return out


def documented_names(doc: str, sections=("Parameters",)) -> set:
    """Names documented in the given sections (``name : type`` or bare ``name`` lines)."""
    names = set()
    for title, body in _sections(doc).items():
        if title not in sections:
            continue
        lines = body.splitlines()
        indents = [len(ln) - len(ln.lstrip()) for ln in lines if ln.strip()]
        base = min(indents) if indents else 0
        for ln in lines:
            if not ln.strip() or len(ln) - len(ln.lstrip()) != base:
                continue
            head = ln.split(" : ", 1)[0].strip()
            for part in head.split(","):
                names.add(part.strip())
    return names


def _param_names(func) -> list | None:
    try:
        sig = inspect.signature(func)
    except (TypeError, ValueError):
        return None
    out = []
    for p in sig.parameters.values():
        if p.name in ("self", "cls"):
            continue
        if p.kind is p.VAR_POSITIONAL:
            out.append(f"*{p.name}")
        elif p.kind is p.VAR_KEYWORD:
            out.append(f"**{p.name}")
        else:
            out.append(p.name)
    return out


def _missing(func, doc, sections=("Parameters",)) -> list:
    params = _param_names(func)
    if params is None:
        return []
    have = documented_names(doc, sections)
    return [p for p in params if p not in have]


def _modules():
    mods = []
    for info in pkgutil.walk_packages(ppamsafety.__path__, "ppamsafety."):
        if any(part.startswith("_") for part in info.name.split(".")):
            continue                                # private modules are not public API
        mods.append(importlib.import_module(info.name))
    return [ppamsafety] + mods


def _public_items():
    """(qualified name, callable, docstring, sections) of everything checked."""
    items = []
    for mod in _modules():
        for name, obj in sorted(vars(mod).items()):
            if name.startswith("_"):
                continue
            if getattr(obj, "__module__", None) != mod.__name__:
                continue
            qual = f"{mod.__name__}.{name}"
            if inspect.isclass(obj):
                if issubclass(obj, enum.Enum):
                    continue
                init = obj.__dict__.get("__init__")
                doc = (obj.__doc__ or "") + "\n\n" + ((init.__doc__ or "") if init else "")
                # a class documents its constructor in Parameters or (dataclass) Attributes
                items.append((qual, obj, doc, ("Parameters", "Attributes")))
                for mname, m in sorted(obj.__dict__.items()):
                    if mname.startswith("_"):
                        continue
                    if isinstance(m, (staticmethod, classmethod)):
                        m = m.__func__
                    if inspect.isfunction(m):
                        items.append((f"{qual}.{mname}", m, m.__doc__, ("Parameters",)))
            elif inspect.isfunction(obj):
                items.append((qual, obj, obj.__doc__, ("Parameters",)))
            elif hasattr(obj, "py_func") and inspect.isfunction(obj.py_func):
                # numba dispatcher: check the Python function it compiles
                items.append((qual, obj.py_func, obj.py_func.__doc__, ("Parameters",)))
            # other objects (constants, dispatchers without py_func, ufuncs): not checked
    return items


def undocumented() -> dict:
    """Qualified name -> list of undocumented parameters, over the whole package."""
    out = {}
    for qual, func, doc, sections in _public_items():
        miss = _missing(func, doc, sections)
        if miss:
            out[qual] = miss
    return out


#: Items exempt from the check.  Empty: every item of the original list (issue 7 item 9)
#: is documented now.  Do not add to it: document the parameters instead.
ALLOWLIST: set = set()


def test_parser_reads_numpydoc_parameters():
    def f(a, b, *args, c=1, **kwargs):
        """Summary.

        Parameters
        ----------
        a, b : float
            Two numbers.
        *args
            More.
        c : int
            Third; the line below is a description, not a parameter.
              d : not a parameter
        **kwargs
            Options.

        Returns
        -------
        x : float
            Not a parameter.
        """
    assert _missing(f, f.__doc__) == []
    assert documented_names(f.__doc__) == {"a", "b", "*args", "c", "**kwargs"}

    def g(a, *args, **kw):
        """No sections at all."""
    assert _missing(g, g.__doc__) == ["a", "*args", "**kw"]


def test_every_public_callable_documents_its_parameters():
    found = undocumented()
    assert len(_public_items()) > 100            # the walk did find the package
    new = {k: v for k, v in found.items() if k not in ALLOWLIST}
    assert not new, "undocumented parameters (numpydoc 'Parameters' section):\n" + "\n".join(
        f"  {k}: {v}" for k, v in sorted(new.items()))


def test_allowlist_has_no_stale_entries():
    found = undocumented()
    stale = sorted(k for k in ALLOWLIST if k not in found)
    assert not stale, f"documented now, remove from ALLOWLIST: {stale}"


if __name__ == "__main__":      # print the current list (to refresh /work/undocumented.txt)
    for k, v in sorted(undocumented().items()):
        print(f"{k}: {', '.join(v)}")
    pytest.main([__file__, "-q"])
