"""Figures from data: every function takes computed data and returns a pyplot-free Figure.

One module per subject: :mod:`.figure` (a new Figure, saving it as PNG), :mod:`.design`,
:mod:`.control`, :mod:`.identify`, :mod:`.impact`, :mod:`.iso`, :mod:`.reaction`,
:mod:`.interaction`, :mod:`.effects`, :mod:`.diagnose`, :mod:`.bench`.

The layer rule (``docs/architecture.md``): these functions take result objects,
DataFrames and arrays by duck typing and import nothing of the packages that
compute them, so that the computing packages can offer ``.plot()`` by calling
down into this package.  A constant a figure needs (a limit line, a set of
variants, an event time) is an argument, or data of :mod:`ppamsafety.params`.
Importing this package does not import matplotlib: the first figure does
(:func:`.figure.new_figure`).
"""
