"""Every import the README and the docs show works, and so do the former paths of moved names.

Issue 18 moved modules between layers; a user's script that follows the documentation, or
an older version of it, must keep running.
"""

import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_FROM = re.compile(r"^\s*from (ppamsafety[\w.]*) import ([\w, ()]+?)\s*(?:#.*)?$", re.M)


def _from_import(module, name):
    """What ``from module import name`` binds (a submodule is imported as that statement does)."""
    mod = importlib.import_module(module)
    if not hasattr(mod, name):
        importlib.import_module(f"{module}.{name}")
    return getattr(mod, name)


def _documented_imports():
    out = set()
    for doc in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        for mod, names in _FROM.findall(doc.read_text(encoding="utf-8")):
            for name in names.replace("(", "").replace(")", "").split(","):
                if name.strip():
                    out.add((doc.name, mod, name.strip()))
    return sorted(out)


def test_the_docs_show_imports():
    assert len(_documented_imports()) > 15


@pytest.mark.parametrize("doc, module, name", _documented_imports())
def test_documented_import_works(doc, module, name):
    assert _from_import(module, name) is not None, f"{doc}: from {module} import {name}"


@pytest.mark.parametrize("module, name", [
    ("ppamsafety.studies", "responses"),          # the report sections' former package
    ("ppamsafety.studies", "REGISTRY"),
    ("ppamsafety.studies", "run_study"),
    ("ppamsafety.studies", "StudyResult"),
    ("ppamsafety.experiments", "ExperimentCase"),
    ("ppamsafety.experiments", "run_batch"),
    ("ppamsafety.experiments.trajectories", "REFERENCE_ROW"),
    ("ppamsafety.experiments.trajectories", "NREF"),
    ("ppamsafety.diagnose", "Diagnosis"),
    ("ppamsafety.diagnose", "diagnose"),
    ("ppamsafety.diagnose", "synthesize"),
    ("ppamsafety.control", "PIDDerivative"),
    ("ppamsafety.control", "GCMode"),
    ("ppamsafety.params.head", "MAXILLA_FRACTURE_N"),
    ("ppamsafety.params", "load_arm"),            # data checks only: design.load_arm adds physics
])
def test_former_paths_still_import(module, name):
    assert _from_import(module, name) is not None


def test_the_former_section_package_gives_the_same_modules():
    from ppamsafety import sections, studies
    assert studies.responses is sections.responses
    assert studies.run_study is sections.run_section
