"""Saving a report figure: the same PNG as ``savefig``, the figure left as it was."""

import hashlib
import io

import matplotlib as mpl
import pytest
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine, PlaceHolderLayoutEngine

from ppamsafety.plots.figure import save


def _figure(layout=None):
    fig = Figure(figsize=(4, 3), layout=layout)
    ax = fig.add_subplot()
    ax.plot([0, 1, 2], [0, 1, 4], label="a line")
    ax.set_xlabel("x [s]")
    ax.legend()
    if layout is None:
        fig.tight_layout()          # leaves a placeholder engine, as the report's figures do
    return fig


def _png(fn, fig):
    buf = io.BytesIO()
    fn(fig, buf)
    return hashlib.sha1(buf.getvalue()).hexdigest()


@pytest.mark.parametrize("layout, engine", [(None, PlaceHolderLayoutEngine),
                                            ("constrained", ConstrainedLayoutEngine)])
def test_save_writes_the_savefig_bytes_and_keeps_the_engine(layout, engine):
    fig = _figure(layout)
    assert isinstance(fig.get_layout_engine(), engine)
    before = fig.get_layout_engine()
    assert _png(save, fig) == _png(lambda f, b: f.savefig(b, dpi=150), fig)
    assert fig.get_layout_engine() is before


def test_save_under_autolayout_rc_still_writes_the_same_png():
    fig = _figure()
    expected = _png(lambda f, b: f.savefig(b, dpi=150), fig)
    with mpl.rc_context({"figure.autolayout": True}):
        assert _png(save, fig) == expected
    assert isinstance(fig.get_layout_engine(), PlaceHolderLayoutEngine)
