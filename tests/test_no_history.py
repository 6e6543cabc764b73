"""The package, the docs, the README, the studies and the report speak of physics, the thesis and
the standards -- never of our development history.

A reader does not know what an issue number, a commit hash or "the previous commit" refers to;
history belongs in git's commit messages.  Every text file a user reads is scanned (the package
with its data files, ``docs/``, ``README.md``, ``studies/``, ``examples/``, the committed report
``reports/*.md``); ``tests/`` is not (a test may name the defect it guards against).

Rules:

* a pattern matches across a line break and the comment markers of the next line (``# ``,
  ``#: ``), so a phrase wrapped in a docstring or a comment is found too;
* :data:`ALLOWED` lists the few matches that are not our history, each with its reason; an
  allowed match that no longer occurs fails, so the list cannot rot.
"""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: What narrates development history, with what it is.
PATTERNS = (
    (r"\bissues?\s*#?\s*\d+", "an issue number"),
    (r"\b(?:PR|pull request)\s*#?\s*\d+", "a pull-request number"),
    (r"\bcommits?\s+[0-9a-f]{7,40}\b", "a commit hash"),
    (r"\b(?:previous|last|earlier|parent)\s+commit\b", "a commit of our history"),
    (r"\bpreviously\b", "development history"),
    (r"\bworking\s+day\b", "development history"),
    (r"\b(?:previous|last|earlier|this)\s+session\b", "development history"),
    (r"\b(?:was|were|when)\s+filed\b|\bsince\s+filing\b", "an issue's history"),
    (r"\bthe\s+brief\b|\bplanning\s+document\b|\bSPEC\s*§", "a planning document not in the "
     "repository"),
)

#: (path relative to the repository, a text the match contains, why it is not our history).
ALLOWED = (
    ("ppamsafety/data/datasets/zillen2021/NOTICE.md", "6e0bcb4633bd53b2a8544cdbd497c4c06539afc7",
     "provenance of third-party data: the upstream repository's commit the files were taken "
     "from"),
)

_TEXT_SUFFIXES = {".py", ".md", ".toml", ".txt", ".rst", ".cfg", ".ini", ".html", ".json",
                  ".yaml", ".yml", ".csv"}
#: A comment marker at the start of a continued line (``#``, ``#:``), with its indentation.
_CONTINUATION = re.compile(r"\n[ \t]*(?:#:?[ \t]*)?")
_COMPILED = tuple((re.compile(p, re.I), what) for p, what in PATTERNS)


def scanned_files():
    """Every text file a user reads: the package, the docs, the README, studies, examples, the
    report's Markdown and HTML."""
    out = [ROOT / "README.md", ROOT / "pyproject.toml"]
    for folder in ("ppamsafety", "docs", "studies", "examples"):
        out += [p for p in sorted((ROOT / folder).rglob("*"))
                if p.is_file() and p.suffix in _TEXT_SUFFIXES and "__pycache__" not in p.parts]
    out += sorted((ROOT / "reports").glob("*.md")) + sorted((ROOT / "reports").glob("*.html"))
    return [p for p in out if p.is_file()]


def history_matches(text):
    """``[(line number, matched text, what it is), ...]`` of ``text`` (lines from 1)."""
    joined = _CONTINUATION.sub(" ", text)
    # map each position of the joined text back to its line: count the line breaks removed
    starts, pos = [], 0
    for m in _CONTINUATION.finditer(text):
        starts.append(m.start() - pos)
        pos += len(m.group()) - 1
    out = []
    for rx, what in _COMPILED:
        for m in rx.finditer(joined):
            line = 1 + sum(1 for s in starts if s < m.start())
            out.append((line, m.group(), what))
    return sorted(out)


@pytest.mark.parametrize("text", [
    "see issue 19", "(issue 10 item 9, issue 19)", "Issue #23 moved it", "issues 10, 19, 20",
    "the previous commit ac45d1e", "against commit 9b16eaf", "at the end of an earlier working "
    "day", "as when issue 11\n    was filed", "# plausibility (issue\n# 8)", "#: since\n#: issue 7",
    "as the brief asks", "Model (SPEC §4)", "in the last session", "PR #12",
])
def test_the_patterns_find_history(text):
    assert history_matches(text), text


@pytest.mark.parametrize("text", [
    "the tissue 3 mm", "commit the end-of-step eps_s", "issues a warning", "sha256 cce4819e21bba3b7",
    "replacing the previous ppamsafety report output", "Table 6.1, §5.3.5", "in the same commit.",
    "the issue of stiffness", "misuse 4 times", "a session of 5 s",
])
def test_the_patterns_spare_legitimate_words(text):
    assert not history_matches(text), text


def test_line_numbers_point_at_the_match():
    text = "a\nb\n    # the\n    # issue 12\nc\n"
    assert [m[0] for m in history_matches(text)] == [4]


def test_the_scan_covers_what_users_read():
    names = {p.relative_to(ROOT).as_posix() for p in scanned_files()}
    assert {"README.md", "docs/architecture.md", "ppamsafety/__init__.py",
            "reports/index.md"} <= names
    assert not any(n.startswith("tests/") for n in names)


def test_no_development_history_outside_the_tests():
    allowed = {(path, text) for path, text, _ in ALLOWED}
    found, used = [], set()
    for path in scanned_files():
        rel = path.relative_to(ROOT).as_posix()
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue
        for line, match, what in history_matches(text):
            hit = next(((p, t) for p, t in allowed
                        if p == rel and t in "\n".join(text.splitlines()[line - 1:line + 1])), None)
            if hit:
                used.add(hit)
                continue
            found.append(f"{rel}:{line}: {match!r} ({what})")
    assert not found, ("development history in what users read; state it as physics, protocol, "
                       "the thesis or the standard instead:\n" + "\n".join(found))
    assert used == allowed, f"allowed matches that no longer occur: {sorted(allowed - used)}"
