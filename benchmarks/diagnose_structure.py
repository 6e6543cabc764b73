"""The size and the duplication of ``ppamsafety/diagnose``: lines, names defined more than once,
and how many files name each candidate by hand.

    python benchmarks/diagnose_structure.py [--root DIR] [--list]

* **lines**: every line of the package's ``.py`` files (what ``wc -l`` counts), and without
  the fits of the thesis's own numbers (``as_built``, ``summary_fit``), which are not a
  diagnosis of a record;
* **names defined more than once**: module-level functions, classes and assignments (public
  and private) whose name is defined in two or more modules of the package -- the same idea
  written again for another data shape (``run_battery``, ``_where``, ``TUNING_SEEDS``, ...).
  A name re-exported by an import is not a definition;
* **files naming a candidate**: for every candidate of every record kind, the package files
  (outside the other kinds' subpackages) in which its name appears as a string literal
  (``"payload"``, a docstring counts): each is a place a new candidate must be added or kept
  true by hand.  The candidates are read from the registries, so the count follows the code.

Prints one block of numbers; ``--list`` also prints every duplicated name with its modules.
Run from the repository root (or give ``--root``).
"""

from __future__ import annotations

import argparse
import ast
import statistics
from collections import defaultdict
from pathlib import Path

#: Modules that fit the thesis's own numbers (not a diagnosis of a record).
THESIS_FITS = ("as_built.py", "summary_fit.py")


def python_files(pkg: Path) -> list:
    """Every ``.py`` file under ``pkg``, sorted."""
    return sorted(p for p in pkg.rglob("*.py") if "__pycache__" not in p.parts)


def lines(files) -> int:
    """Total number of lines of ``files``."""
    return sum(len(p.read_text(encoding="utf-8").splitlines()) for p in files)


def definitions(path: Path) -> set:
    """Module-level names ``path`` defines (functions, classes, assignments; not imports)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(node.name)
        elif isinstance(node, ast.Assign):
            for t in node.targets:
                for n in ast.walk(t):
                    if isinstance(n, ast.Name):
                        out.add(n.id)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            out.add(node.target.id)
    return out - {"__all__", "__signature__"}


def duplicated_names(pkg: Path) -> dict:
    """Name -> the modules (relative paths) of ``pkg`` that define it, for names defined in
    more than one module."""
    where = defaultdict(list)
    for p in python_files(pkg):
        for n in definitions(p):
            where[n].append(str(p.relative_to(pkg)))
    return {n: sorted(m) for n, m in sorted(where.items()) if len(m) > 1}


def string_literals(path: Path) -> set:
    """Every string constant of ``path`` (docstrings included: a docstring naming a
    candidate is a place to keep true too)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant)
            and isinstance(n.value, str)}


def candidate_places(pkg: Path, names, *, exclude=()) -> dict:
    """Candidate name -> the files of ``pkg`` holding it as a whole string literal, outside
    the subpackages ``exclude`` (another record kind's files: a name two kinds share, such as
    ``hysteresis``, is counted for each kind in its own files and the shared ones)."""
    lits = {p: string_literals(p) for p in python_files(pkg)
            if p.relative_to(pkg).parts[0] not in exclude}
    return {n: sorted(str(p.relative_to(pkg)) for p, s in lits.items() if n in s)
            for n in names}


def candidate_names() -> dict:
    """Record kind -> (its candidate names, read from the package's own registries; the
    subpackages of the other kinds)."""
    import ppamsafety.diagnose  # noqa: F401  (registers every kind's candidate library)
    from ppamsafety.diagnose.bench.friction import VOCABULARY
    from ppamsafety.diagnose.core.candidate import library
    return {"arm": (tuple(library("arm")), ("bench",)),
            "muscle bench": (tuple(library("muscle")), ("arm",)),
            "cylinder campaign": (tuple(VOCABULARY), ("arm",))}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", default=".", help="repository root (default: .)")
    ap.add_argument("--list", action="store_true", help="print every duplicated name")
    args = ap.parse_args(argv)
    pkg = Path(args.root) / "ppamsafety" / "diagnose"
    files = python_files(pkg)
    total = lines(files)
    fits = lines([p for p in files if p.name in THESIS_FITS])
    dup = duplicated_names(pkg)
    print(f"lines of ppamsafety/diagnose: {total} ({len(files)} files); without the fits of "
          f"the thesis's own numbers ({', '.join(THESIS_FITS)}): {total - fits}")
    print(f"names defined in more than one module: {len(dup)} "
          f"({sum(len(m) for m in dup.values())} definitions)")
    for kind, (names, other) in candidate_names().items():
        places = candidate_places(pkg, names, exclude=other)
        counts = [len(v) for v in places.values()]
        print(f"{kind}: files naming a candidate by hand: median "
              f"{statistics.median(counts):g}, max {max(counts)} "
              f"({', '.join(f'{n} {c}' for n, c in zip(names, counts))})")
    if args.list:
        for n, mods in dup.items():
            print(f"  {n}: {', '.join(mods)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
