"""With every effect off, the closed loop is bitwise what it was before the refactoring.

Reference: ``tests/data/closed_loop_golden.npz``, written by
``tests/data/make_closed_loop_golden.py`` on commit 4530509 (before the
declared layouts): the Table 6.1 experiments (step and switch, ten thesis
variants each) and one circle (P = 10 s, 15 s, ten variants).  Tolerance:
none -- the SHA-256 of every log must match (issue 7, item 2).
"""

import hashlib
import importlib.util
from pathlib import Path

import numpy as np
import pytest

_DATA = Path(__file__).resolve().parent / "data"


@pytest.fixture(scope="module")
def golden():
    return np.load(_DATA / "closed_loop_golden.npz")


@pytest.fixture(scope="module")
def current_logs():
    spec = importlib.util.spec_from_file_location("make_golden",
                                                  _DATA / "make_closed_loop_golden.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.logs()


def test_nominal_closed_loop_is_bitwise_unchanged(golden, current_logs):
    keys = [str(k) for k in golden["keys"]]
    assert [f"{n}|{lab}" for n, lab, _ in current_logs] == keys
    stride = int(golden["stride"])
    starts = np.concatenate([[0], np.cumsum(golden["lengths"])])
    for i, (name, label, log) in enumerate(current_logs):
        rows = golden["rows"][starts[i]:starts[i + 1]]
        cur = log[::stride]
        assert cur.shape == rows.shape, f"{keys[i]}: log shape changed"
        # first the sampled rows, to say where a difference starts ...
        same = (cur == rows) | (np.isnan(cur) & np.isnan(rows))
        if not same.all():
            r, c = np.argwhere(~same)[0]
            pytest.fail(f"{keys[i]}: first difference at sampled row {r * stride}, column {c}: "
                        f"{cur[r, c]!r} != {rows[r, c]!r}")
        # ... then every bit of the whole log
        assert hashlib.sha256(log.tobytes()).hexdigest() == str(golden["hashes"][i]), keys[i]
