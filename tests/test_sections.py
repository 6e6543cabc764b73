"""The report sections are registered once and everything that lists them is derived or checked.

A new section touches its own module (with its ``SECTION`` info), one line of
``ppamsafety.sections.REGISTRY`` (it runs alone with ``ppamsafety report --only NAME``); the README's table is
the output of ``python -m ppamsafety.sections`` (issue 23).
"""

import pkgutil
import re
from pathlib import Path

import pytest

from ppamsafety import sections
from ppamsafety.sections import REGISTRY, SectionInfo, readme_table, section_infos

ROOT = Path(__file__).resolve().parents[1]


def test_every_section_module_is_registered_once():
    modules = {m.name for m in pkgutil.iter_modules(sections.__path__) if m.name != "__main__"}
    assert modules == set(REGISTRY)
    assert len(REGISTRY) == len(set(REGISTRY))


def test_every_section_declares_its_info():
    infos = section_infos()
    assert list(infos) == list(REGISTRY)
    for name, info in infos.items():
        assert isinstance(info, SectionInfo), name
        assert info.typical_seconds > 0 and info.summary and info.thesis, name


def test_readme_holds_the_generated_section_table():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert readme_table() in readme, "regenerate the table: python -m ppamsafety.sections"
    counts = re.findall(r"all\s+(\d+)\s+sections", readme)
    assert counts and all(int(c) == len(REGISTRY) for c in counts)


def test_one_way_to_run_a_section():
    """``ppamsafety report --only NAME``: no runner script per section, no alias package."""
    assert not list((ROOT / "studies").glob("*.py")) or all(
        "ppamsafety.sections" not in p.read_text(encoding="utf-8")
        for p in (ROOT / "studies").glob("*.py"))
    assert not (ROOT / "ppamsafety" / "studies").exists()


def test_benchmarks_live_in_their_own_folder():
    assert sorted(p.name for p in (ROOT / "benchmarks").glob("bench_*.py"))
    assert not list((ROOT / "studies").rglob("bench_*.py"))


@pytest.mark.parametrize("kwargs, match", [
    ({"summary": "", "thesis": "x", "typical_seconds": 1.0}, "summary"),
    ({"summary": "x", "thesis": 3, "typical_seconds": 1.0}, "thesis"),
    ({"summary": "x", "thesis": "x", "typical_seconds": -1.0}, "typical_seconds"),
])
def test_section_info_refuses_bad_values(kwargs, match):
    with pytest.raises(ValueError, match=match):
        SectionInfo(**kwargs)
