"""A hash of every source file of the package, shared by every cache that must follow edits.

The compiled-kernel cache (:mod:`ppamsafety._jit`) and the sweep cache
(:mod:`ppamsafety.sweep`) are both keyed on it, so that an edit anywhere in the
package never lets a cache silently return results of the old code.
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

_ROOT = Path(__file__).resolve().parent


@functools.lru_cache(maxsize=1)
def source_hash() -> str:
    """Hex digest (16 characters) of the relative path and bytes of every ``*.py`` of the package.

    Computed once per process (the package is not expected to change under a
    running process; a new process sees the edit).
    """
    h = hashlib.sha1()
    for f in sorted(_ROOT.rglob("*.py")):
        h.update(f.relative_to(_ROOT).as_posix().encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:16]
