"""The README's Python examples run as written, in order, in one namespace.

Every ```python block of README.md is executed, top to bottom, in a fresh temporary folder
that holds a link to the repository's ``examples/`` (the README loads the example arm by its
relative path), so an example that stops working -- a renamed function, a changed column, a
file it writes twice -- fails here.  The examples are written at quick sizes (a sweep of two
cases, one rehearsal record), so the whole README runs in seconds once the kernels are
compiled.
"""

import contextlib
import io
import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
_BLOCK = re.compile(r"^```python\n(.*?)^```$", re.M | re.S)


def readme_blocks(text=None):
    """The README's ```python blocks, in order."""
    return _BLOCK.findall(README.read_text(encoding="utf-8") if text is None else text)


def test_the_block_pattern_finds_fenced_python_only():
    text = "a\n```python\nx = 1\n```\n```bash\nls\n```\n```python\ny = 2\n```\n"
    assert readme_blocks(text) == ["x = 1\n", "y = 2\n"]


def test_the_readme_has_examples():
    assert len(readme_blocks()) >= 5


def test_the_readme_examples_run(tmp_path, monkeypatch):
    (tmp_path / "examples").symlink_to(ROOT / "examples", target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__readme__"}
    out = io.StringIO()
    for i, block in enumerate(readme_blocks(), 1):
        code = compile(block, f"README.md python block {i}", "exec")
        with contextlib.redirect_stdout(out):
            exec(code, namespace)
    printed = out.getvalue()
    # What the README's comments promise the examples show.
    assert "payload" in printed
    assert namespace["diagnosis"].names == ("payload",)
    assert (tmp_path / "diagnosis" / "diagnosis.json").is_file()
    assert len(namespace["df"]) == 2 and (namespace["df"]["status"] == "ok").all()
    # The examples ran in the temporary folder (none changed directory), and wrote there.
    assert os.getcwd() == str(tmp_path)
    assert (tmp_path / "my_arm.toml").is_file() and (tmp_path / "sweep_cache").is_dir()


def test_the_readme_is_a_users_guide_in_its_order():
    """What the toolkit is, the two commands, your own arm, one impact / experiment / sweep /
    diagnosis, the report, speed, the documentation."""
    heads = re.findall(r"^## (.+)$", README.read_text(encoding="utf-8"), re.M)
    assert heads == ["The two commands", "Your own arm", "One impact",
                     "One experiment and its impacts", "One sweep", "One diagnosis",
                     "What the report contains", "Speed", "Documentation"]


def test_every_document_the_readme_links_exists():
    text = README.read_text(encoding="utf-8")
    links = re.findall(r"\]\(((?:docs|examples|reports)/[^)#]+)", text)
    assert links
    for link in links:
        assert (ROOT / link).exists(), link


def test_ci_runs_the_test_command_the_readme_states():
    """The README promises that its test command is exactly what CI runs (``.ci/run``)."""
    text = README.read_text(encoding="utf-8")
    section = text[text.index("Run the test suite"):]
    command = re.search(r"```bash\n(.+?)\n```", section, re.S).group(1).strip()
    assert "pytest" in command
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    assert command in [line.strip() for line in ci], command


def test_every_relative_link_of_the_readme_and_the_docs_exists():
    """A moved or renamed page breaks no link of README.md or docs/*.md."""
    broken, checked = [], 0
    for page in [README, *sorted((ROOT / "docs").glob("*.md"))]:
        text = page.read_text(encoding="utf-8")
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text):
            if "://" in target or target.startswith("mailto:"):
                continue
            checked += 1
            if not (page.parent / target).exists():
                broken.append(f"{page.relative_to(ROOT)}: {target}")
    assert checked > 20 and not broken, broken
