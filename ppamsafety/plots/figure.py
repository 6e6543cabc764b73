"""The figure and the file: a new pyplot-free Figure, and saving it as PNG.

Every plot function of :mod:`ppamsafety.plots` starts from :func:`new_figure`.

Figures are built with the object-oriented API (:class:`matplotlib.figure.Figure`),
never with :mod:`matplotlib.pyplot`: they need no GUI backend, so importing
:mod:`ppamsafety` neither selects a backend nor imports pyplot (the user's
interactive session keeps its own), report generation works on machines
without a display, and no figure is left registered in pyplot's figure
manager.  In Jupyter a returned Figure displays like any other; in a
pyplot script, ``fig.savefig(...)`` writes it.
"""

from __future__ import annotations

GROUP_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red")


def new_figure(nrows: int = 1, ncols: int = 1, *, figsize=None, layout=None, **kwargs):
    """A pyplot-free Figure with a grid of axes, like ``pyplot.subplots``.

    Parameters
    ----------
    nrows, ncols : int
        Grid of axes.
    figsize : (float, float), optional
        Figure size [inch] (default: rcParams).
    layout : str, optional
        Layout engine of the figure (``"constrained"``, ``"tight"``; default: none).
    **kwargs
        Passed to :meth:`matplotlib.figure.Figure.subplots` (``sharex``,
        ``sharey``, ``squeeze``, ...).

    Returns
    -------
    fig : matplotlib.figure.Figure
        The new figure.
    axes : Axes or numpy.ndarray of Axes
        As returned by ``Figure.subplots``.
    """
    # matplotlib is imported by the first figure, not by importing ppamsafety.plots: the
    # computing packages import their plot functions for .plot(), and a simulation that draws
    # nothing should not pay the 0.6 s import (tests/test_no_global_state.py checks it)
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, layout=layout)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def save(fig, path) -> str:
    """Save a figure as PNG (150 dpi); returns the path.

    A figure laid out once by ``fig.tight_layout()`` keeps a placeholder layout
    engine, and whenever a figure has an engine ``savefig`` first draws all of it
    without output so that the engine can lay it out: a third of the time of a
    save, for nothing, since the placeholder lays out nothing.  The placeholder
    is therefore set aside for the save and put back (the same PNG bytes,
    measured); a real engine (``layout="constrained"``) is left alone.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : path-like
        Target file.

    Returns
    -------
    str
        ``str(path)``.
    """
    import matplotlib as mpl
    from matplotlib.layout_engine import PlaceHolderLayoutEngine

    fit_titles(fig)
    engine = fig.get_layout_engine()
    if not isinstance(engine, PlaceHolderLayoutEngine):
        fig.savefig(path, dpi=150)
        return str(path)
    # set_layout_engine(None) means "no engine" only while these rc switches are off
    with mpl.rc_context({"figure.autolayout": False, "figure.constrained_layout.use": False}):
        fig.set_layout_engine(None)
    try:
        fig.savefig(path, dpi=150)
    finally:
        fig.set_layout_engine(engine)
    return str(path)


def _wrap(text, width_px: float, renderer) -> None:
    """Wrap a Text artist's string at word boundaries until every line fits ``width_px``."""
    import textwrap

    s = text.get_text()
    w = text.get_window_extent(renderer).width if s else 0.0
    if w <= width_px:
        return
    longest = max(len(line) for line in s.split("\n"))
    for chars in range(max(int(longest * width_px / w), 10), 9, -1):
        text.set_text("\n".join(textwrap.fill(line, chars) for line in s.split("\n")))
        if text.get_window_extent(renderer).width <= width_px:
            return


def fit_titles(fig) -> None:
    """Wrap a figure's title and its axes' titles that are wider than the figure or their axes
    (a title that does not fit is never cut off).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure; its titles are changed in place.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    titles = [ax.title for ax in fig.axes if ax.title.get_text()]
    sup = getattr(fig, "_suptitle", None)
    if not titles and (sup is None or not sup.get_text()):
        return
    canvas = fig.canvas if hasattr(fig.canvas, "get_renderer") else FigureCanvasAgg(fig)
    renderer = canvas.get_renderer()
    width = fig.get_figwidth() * fig.dpi
    if sup is not None:
        _wrap(sup, 0.96 * width, renderer)
    for t in titles:
        ax_w = t.axes.get_window_extent(renderer).width
        _wrap(t, min(0.96 * width, max(1.1 * ax_w, 0.2 * width)), renderer)


__all__ = ["GROUP_COLORS", "new_figure", "save", "fit_titles"]
