"""The layer contract (issue 18): imports run downward, function-level ones included.

The contract is `[tool.importlinter]` in pyproject.toml (drawn in docs/architecture.md);
`.ci/run` also runs `lint-imports`.  These tests keep it honest: the contract holds, the
import graph it checks does see imports inside functions, no two top-level packages import
each other, and the computing packages load no matplotlib until a figure is drawn.
"""

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

grimp = pytest.importorskip("grimp")
importlinter = pytest.importorskip("importlinter")

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def graph():
    return grimp.build_graph("ppamsafety", include_external_packages=True, cache_dir=None)


def test_the_layer_contract_holds():
    code = ("import sys; from importlinter.cli import lint_imports; "
            "sys.exit(lint_imports(no_cache=True))")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]
    assert re.search(r"Contracts: [1-9]\d* kept, 0 broken", r.stdout), r.stdout[-2000:]


def test_the_graph_counts_imports_inside_functions(graph):
    # plots.figure imports matplotlib only inside new_figure(): the contract must see it
    src = (ROOT / "ppamsafety" / "plots" / "figure.py").read_text()
    assert "\n    from matplotlib.figure import Figure" in src
    assert "matplotlib" in graph.find_modules_directly_imported_by("ppamsafety.plots.figure")


def test_no_two_top_level_packages_import_each_other(graph):
    top = lambda m: ".".join(m.split(".")[:2])        # noqa: E731
    edges = set()
    for m in graph.modules:
        if not m.startswith("ppamsafety."):
            continue
        for i in graph.find_modules_directly_imported_by(m):
            if i.startswith("ppamsafety.") and top(i) != top(m):
                edges.add((top(m), top(i)))
    mutual = sorted({tuple(sorted(e)) for e in edges if e[::-1] in edges})
    assert not mutual, mutual


_SCRIPT = r"""
import json, sys
import ppamsafety.impact, ppamsafety.experiments, ppamsafety.diagnose, ppamsafety.design
import ppamsafety.identify, ppamsafety.sweep_cases
print(json.dumps("matplotlib" in sys.modules))
"""


def test_computing_packages_load_no_matplotlib():
    """Their .plot() methods call ppamsafety.plots, which imports matplotlib at the first figure."""
    r = subprocess.run([sys.executable, "-c", _SCRIPT], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.strip().splitlines()[-1]) is False
