"""Side-by-side measurements against an earlier version of the code (a git revision).

A speed figure is a ratio measured in one run: the benchmark scripts that compare with an
earlier version check the revision out once (``git archive``) into a folder of its own under
``~/.cache/ppamsafety/bench-trees/<commit>`` (a stable path, so that the earlier version's
compiled kernels stay cached between runs), and run the same measuring code (the script of
the working tree, with its measuring option) in a child process for each version, with the
version's package on ``PYTHONPATH``, alternating between the versions so that a change of
the machine's load hits both alike.  The measuring code prints one JSON object on its last
line of output.

Run from the repository root (the benchmarks import the package from the working tree).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

#: Where earlier versions are checked out (one folder per commit).
TREES = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "ppamsafety" / \
    "bench-trees"
#: The working tree (the repository root this file lives in).
HERE = Path(__file__).resolve().parents[2]


def commit_of(rev: str) -> str:
    """The full commit hash of the git revision ``rev`` of this repository."""
    out = subprocess.run(["git", "rev-parse", "--verify", f"{rev}^{{commit}}"], cwd=HERE,
                         capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(f"bench: --baseline {rev!r} is not a git revision of {HERE}: "
                         f"{out.stderr.strip()}")
    return out.stdout.strip()


def checkout(rev: str) -> Path:
    """The source tree of ``rev`` (checked out on first use); its root folder."""
    sha = commit_of(rev)
    dest = TREES / sha
    if (dest / "ppamsafety" / "__init__.py").exists():
        return dest
    TREES.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=TREES) as tmp:
        tar = Path(tmp) / "tree.tar"
        subprocess.run(["git", "archive", "--format=tar", "-o", str(tar), sha], cwd=HERE,
                       check=True)
        part = Path(tmp) / "tree"
        with tarfile.open(tar) as t:
            t.extractall(part, filter="data")
        os.replace(part, dest)
    return dest


def run(tree: Path, args: list, *, env: dict | None = None, timeout: float = 7200.0,
        cpus: set | None = None) -> dict:
    """Run ``python *args`` with the package of ``tree``; the JSON object it printed last.

    Typically ``args`` is a benchmark script of the working tree and its measuring option:
    the script is the same for both versions, the package it imports is the version's.

    Parameters
    ----------
    tree : Path
        Root of a source tree (``HERE`` or a :func:`checkout`).
    args : list of str
        Arguments of the Python interpreter; the last line of output is a JSON object.
    env : dict, optional
        Extra environment variables.
    timeout : float
        Seconds.
    cpus : set of int, optional
        Run the child on these CPUs only (``os.sched_setaffinity``).
    """
    e = dict(os.environ, PYTHONPATH=str(tree), **(env or {}))
    pre = (lambda: os.sched_setaffinity(0, cpus)) if cpus else None
    out = subprocess.run([sys.executable, *args], cwd=tree, env=e, capture_output=True,
                         text=True, timeout=timeout, preexec_fn=pre)
    if out.returncode != 0:
        raise RuntimeError(f"bench snippet failed in {tree} (exit {out.returncode}):\n"
                           f"{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def load() -> str:
    """The load averages (1, 5, 15 min) as text, for the record of a measurement."""
    return ", ".join(f"{v:.2f}" for v in os.getloadavg())


def ratio_line(label: str, before: float, after: float, unit: str = "s") -> str:
    """``label: before -> after (ratio before/after)`` with the unit."""
    return (f"{label}: {before:.4g} {unit} -> {after:.4g} {unit} "
            f"(ratio {before / after:.2f})")
