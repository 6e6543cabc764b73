"""The result protocol: one face for every result object of the toolkit.

Every public result class (what a public function or a report section returns) derives from
:class:`Result` and so answers the same five questions:

``to_pandas()``
    The main table, a :class:`pandas.DataFrame` (with units in the column names or in the
    class docstring).  ``result.table`` is the same table.
``plot(**kw)``
    One :class:`matplotlib.figure.Figure`, drawn by a function of :mod:`ppamsafety.plots`
    (pyplot-free: nothing is shown, nothing is kept by a global figure manager).
``figures()``
    ``{name: Figure}``: every figure of the result (a single ``{name: plot()}`` where there is
    one; a report section's figures under the names of their PNG files).
``to_dict()``
    A JSON-ready dict with the schema :data:`SCHEMA` (below).
``write(folder)``
    ``result.json`` (the dict), one CSV per table and, with ``figures=True``, one PNG per
    figure, written through :class:`ppamsafety.output.OutputFolder` (kind ``"result"``): a
    folder holding files the toolkit did not write is refused and a previous result is
    replaced only with ``overwrite=True``.

A class implements ``to_pandas()`` (a result of scalars only need not: its table is one row of
them) and one of ``plot()`` / ``figures()``; the rest comes from
here.  A result with further tables (a section's several CSVs) names them in
:meth:`Result.tables`; the default holds the main table and every :class:`pandas.DataFrame`
attribute.  A result with a schema of its own (the diagnosis, the identification) overrides
``to_dict()`` and ``write()`` and documents it where its command line writes it.

Schema ``ppamsafety-result/1`` of ``to_dict()`` (and of ``result.json``)::

    {"schema": "ppamsafety-result/1",
     "tool": "ppamsafety", "version": "<package version>",
     "kind": "<class name>",
     "values": {"<attribute>": number | str | bool | null | [numbers...] | {str: number...}},
     "tables": {"<name>": {"file": "<name>.csv", "rows": int, "columns": [str, ...]}}}

``values`` holds the attributes that are scalars (numbers, strings, flags; non-finite numbers
become ``null``), short sequences of scalars and flat mappings of them (at most
:data:`MAX_LIST` entries); arrays, tables and nested objects are left out of it (tables are
under ``tables``, written as CSV by ``write``).  The CSV files name a column with a unit
``"column [unit]"`` (:meth:`Result.column_units`; ``[-]``: dimensionless), and ``columns``
lists the names the files hold; :func:`strip_unit` gives the name and unit back.
"""

from __future__ import annotations

import dataclasses
import enum
import json
import math
import re
from pathlib import PurePath

import numpy as np
import pandas as pd

from ._validation import check_bool
from ._version import __version__
from .output import OutputFolder

__all__ = ["Result", "SCHEMA", "MAX_LIST", "JSON_NAME", "unit_name", "strip_unit", "with_units",
           "layout_units"]

#: Schema name of :meth:`Result.to_dict`.
SCHEMA = "ppamsafety-result/1"
#: Longest sequence or mapping of scalars kept under ``values``.
MAX_LIST = 64
#: File name of the dict in :meth:`Result.write`.
JSON_NAME = "result.json"


class _MainTable:
    """``result.table``: the table ``to_pandas()`` returns.

    A non-data descriptor, so that a dataclass field named ``table`` (the table itself) takes
    precedence on the instance; on the class it is absent (a dataclass would take an inherited
    attribute for a field's default).
    """

    def __get__(self, obj, cls=None):
        if obj is None:
            raise AttributeError("table is an attribute of a result, not of its class")
        return obj.to_pandas()


def _snake(name: str) -> str:
    return re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", name).lower()


def _scalar(v):
    """A JSON scalar for ``v``, or ``_SKIP``."""
    if v is None or isinstance(v, (bool, str)):
        return v
    if isinstance(v, enum.Enum):
        return _scalar(v.value)
    if isinstance(v, PurePath):
        return str(v)
    if isinstance(v, np.bool_):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return v if math.isfinite(v) else None
    if isinstance(v, np.ndarray) and v.ndim == 0:
        return _scalar(v.item())
    return _SKIP


_SKIP = object()


def _value(v):
    """The JSON form of an attribute under ``values``, or ``_SKIP``."""
    s = _scalar(v)
    if s is not _SKIP:
        return s
    if isinstance(v, np.ndarray) and v.ndim == 1 and v.size <= MAX_LIST:
        v = v.tolist()
    if isinstance(v, (list, tuple)) and len(v) <= MAX_LIST:
        out = [_scalar(x) for x in v]
        return _SKIP if any(x is _SKIP for x in out) else out
    if isinstance(v, dict) and len(v) <= MAX_LIST and all(isinstance(k, str) for k in v):
        out = {k: _scalar(x) for k, x in v.items()}
        return _SKIP if any(x is _SKIP for x in out.values()) else out
    return _SKIP


def _attributes(obj) -> dict:
    if dataclasses.is_dataclass(obj):
        return {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)
                if not f.name.startswith("_")}
    return {k: v for k, v in vars(obj).items() if not k.startswith("_")}


#: A column name that already says its unit: ``"F_max [N]"``.
_HAS_UNIT = re.compile(r"\[[^\]]*\]\s*$")


def unit_name(column: str, unit) -> str:
    """``"column [unit]"`` (``column`` unchanged without a unit or when it names one).

    Parameters
    ----------
    column : str
        A column name.
    unit : str or None
        Its unit (``"-"``: dimensionless; None or ``""``: none).
    """
    if not unit or _HAS_UNIT.search(str(column)):
        return str(column)
    return f"{column} [{unit}]"


def strip_unit(column: str) -> tuple:
    """``(name, unit)`` of a column name ``"name [unit]"`` (unit None without one).

    Parameters
    ----------
    column : str
        A column name as a CSV file of the toolkit holds it.
    """
    m = re.fullmatch(r"(.*?)\s*\[([^\]]*)\]\s*", str(column))
    return (m.group(1), m.group(2)) if m else (str(column), None)


def with_units(table: pd.DataFrame, units: dict) -> pd.DataFrame:
    """``table`` with its columns named ``"column [unit]"`` by ``units`` (a copy; columns
    without a unit keep their name).

    Parameters
    ----------
    table : pandas.DataFrame
    units : dict
        ``{column: unit}``.
    """
    if not units:
        return table
    return table.rename(columns={c: unit_name(c, units.get(c)) for c in table.columns})


def layout_units(*layouts) -> dict:
    """``{column: unit}`` of the columns of declared layouts
    (:class:`ppamsafety.layouts.Layout`).

    Parameters
    ----------
    *layouts : Layout
    """
    return {c: f.unit for lay in layouts for f in lay.fields for c in f.column_names()}


class Result:
    """Base of every public result class: the protocol of the module docstring.

    Subclasses implement :meth:`to_pandas` and :meth:`plot` or :meth:`figures`.
    """

    table = _MainTable()

    def to_pandas(self) -> pd.DataFrame:
        """The main table; by default one row of the scalar attributes (a result of numbers)."""
        row = {k: v for k, v in _attributes(self).items() if _scalar(v) is not _SKIP}
        if not row:
            raise NotImplementedError(f"{type(self).__name__} does not define to_pandas()")
        return pd.DataFrame([row])

    def figure_name(self) -> str:
        """Name of the figure :meth:`plot` draws, in :meth:`figures` (the class name, snake case)."""
        return _snake(type(self).__name__)

    def plot(self, **kw):
        """The main figure, a matplotlib Figure (the first of :meth:`figures`).

        Parameters
        ----------
        **kw
            Passed to :meth:`figures` (a subclass that draws one figure takes the options
            of its plot function instead).
        """
        if type(self).figures is Result.figures:
            raise NotImplementedError(f"{type(self).__name__} defines neither plot() nor "
                                      f"figures()")
        figs = self.figures(**kw)
        return figs[next(iter(figs))]

    def figures(self, **kw) -> dict:
        """``{name: Figure}``: every figure of the result.

        Parameters
        ----------
        **kw
            Passed to :meth:`plot` (a subclass with several figures takes options of its own).
        """
        if type(self).plot is Result.plot:
            raise NotImplementedError(f"{type(self).__name__} defines neither plot() nor "
                                      f"figures()")
        return {self.figure_name(): self.plot(**kw)}

    def tables(self) -> dict:
        """``{name: DataFrame}``: the main table as ``"table"`` and every DataFrame attribute
        under its name (the main table once)."""
        main = self.to_pandas()
        out = {"table": main}
        for k, v in _attributes(self).items():
            if isinstance(v, pd.DataFrame) and v is not main and k not in out:
                out[k] = v
        return out

    def column_units(self) -> dict:
        """``{column: unit}`` of the columns of :meth:`tables` (``"-"``: a dimensionless
        number); :meth:`write` names them ``"column [unit]"`` in the CSV files.  The default
        knows none: a subclass whose columns have units says them."""
        return {}

    def _written_tables(self) -> dict:
        """:meth:`tables` as the CSV files hold them: numeric columns with their units."""
        units = self.column_units()
        return {name: with_units(t, units) for name, t in self.tables().items()}

    def to_dict(self) -> dict:
        """A JSON-ready dict, schema :data:`SCHEMA` (module docstring)."""
        values = {}
        for k, v in _attributes(self).items():
            j = _value(v)
            if j is not _SKIP:
                values[k] = j
        tables = {name: {"file": f"{name}.csv", "rows": int(len(t)),
                         "columns": [str(c) for c in t.columns]}
                  for name, t in self._written_tables().items()}
        return {"schema": SCHEMA, "tool": "ppamsafety", "version": __version__,
                "kind": type(self).__name__, "values": values, "tables": tables}

    def write(self, folder, *, figures: bool = False, overwrite: bool = False,
              replace_kind: bool = False) -> list:
        """Write ``result.json``, one CSV per table and, with ``figures``, the PNGs.

        Through :class:`ppamsafety.output.OutputFolder` (kind ``"result"``).

        Parameters
        ----------
        folder : path-like
            Output folder (created if missing; used only if empty or a previous
            ppamsafety result).
        figures : bool, keyword-only
            Also write every figure of :meth:`figures` as ``<name>.png``.
        overwrite : bool, keyword-only
            Replace a previous ppamsafety result in ``folder``.
        replace_kind : bool, keyword-only
            Allow replacing a previous ppamsafety output of another kind.

        Returns
        -------
        list of pathlib.Path
            The files written.
        """
        check_bool("figures", figures)
        check_bool("overwrite", overwrite)
        check_bool("replace_kind", replace_kind)
        text = json.dumps(self.to_dict(), indent=1, allow_nan=False, ensure_ascii=False) + "\n"
        tables = self._written_tables()
        figs = self.figures() if figures else {}
        out = OutputFolder(folder, kind="result", overwrite=overwrite, replace_kind=replace_kind)
        with out as st:
            (st / JSON_NAME).write_text(text, encoding="utf-8")
            for name, t in tables.items():
                t.to_csv(st / f"{name}.csv", index=not isinstance(t.index, pd.RangeIndex))
            for name, fig in figs.items():
                png = name if name.endswith(".png") else f"{name}.png"
                fig.savefig(st / png, dpi=110)
        return [out.path / f for f in out.written]
