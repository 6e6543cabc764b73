"""Declared layouts: the machinery, and a pack -> read-by-name round trip for every layout."""

import importlib
import pkgutil
from enum import IntEnum

import numpy as np
import pytest

import ppamsafety
from ppamsafety.layouts import REGISTRY, Field, Layout, check_flag


def _import_all():
    for m in pkgutil.walk_packages(ppamsafety.__path__, "ppamsafety."):
        importlib.import_module(m.name)


def test_offsets_columns_and_pack():
    lay = Layout("test layout", [Field("q", 2, "rad", "angles"), Field("k", 1, "N", "force"),
                                 Field("m", 3, "-", "x", columns=("a", "b", "c"), default=7.0)],
                 register=False)
    assert lay.size == 6 and lay.offsets("q", "k", "m") == (0, 2, 3)
    assert lay.columns() == ["q1", "q2", "k", "a", "b", "c"]
    row = lay.pack(q=[1.0, 2.0], k=3.0)
    np.testing.assert_array_equal(row, [1, 2, 3, 7, 7, 7])
    assert lay.read(row, "k") == 3.0
    np.testing.assert_array_equal(lay.read(np.stack([row, 2 * row]), "q"), [[1, 2], [2, 4]])
    with pytest.raises(ValueError, match="'q'.*required"):
        lay.pack(k=1.0)
    with pytest.raises(ValueError, match="needs 2 value"):
        lay.pack(q=[1, 2, 3], k=1.0)
    with pytest.raises(KeyError, match="no field"):
        lay.pack(q=[1, 2], k=1.0, bogus=3)
    with pytest.raises(ValueError, match="numeric"):
        lay.pack(q="ab", k=1.0)
    with pytest.raises(ValueError, match="declared twice"):
        Layout("dup", [Field("a", 1, "-", ""), Field("a", 1, "-", "")], register=False)


def test_check_flag_accepts_members_names_and_codes_only():
    class Mode(IntEnum):
        OFF = 0
        PROXY = 3

    assert check_flag(Mode, Mode.PROXY, "mode") == 3
    assert check_flag(Mode, "proxy", "mode") == 3
    assert check_flag(Mode, 0, "mode") == 0
    for bad in ("nope", 1, 2.5, True, None):
        with pytest.raises(ValueError, match="mode"):
            check_flag(Mode, bad, "mode")


def test_every_registered_layout_round_trips():
    _import_all()
    assert REGISTRY, "no layout registered"
    rng = np.random.default_rng(0)
    for name, lay in REGISTRY.items():
        assert len(lay.columns()) == lay.size, name
        values = {f.name: rng.normal(size=f.length) for f in lay.fields}
        row = lay.pack(values)
        assert row.shape == (lay.size,)
        for f in lay.fields:
            got = lay.read(row, f.name)
            np.testing.assert_array_equal(np.atleast_1d(got), values[f.name], err_msg=f"{name}.{f.name}")
        # the fields tile the row without gaps or overlaps
        seen = np.zeros(lay.size, int)
        for f in lay.fields:
            seen[lay.slice(f.name)] += 1
        assert np.all(seen == 1), name
        assert len(lay.table()) == len(lay.fields)
