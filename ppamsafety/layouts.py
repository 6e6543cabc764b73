"""Declared layouts of the flat float64 arrays shared with the compiled kernels.

The simulation core is written as numba kernels that take their data as flat
``float64`` rows (parameters, controller state, reference samples, log rows,
impact cases ...).  Flat rows are the fastest form numba can cache, but an
offset numbered by hand is a silent bug waiting to happen.  Every such array
is therefore **declared once**, in the module that owns it, as a
:class:`Layout`: a table of named :class:`Field` s (name, length, unit,
one-line meaning).  Offsets, lengths, packing, unpacking and column names are
generated from that table::

    >>> from ppamsafety.layouts import Field, Layout
    >>> CASE = Layout("example case", [
    ...     Field("q", 2, "rad", "link angles"),
    ...     Field("k", 2, "N m/rad", "joint stiffnesses"),
    ...     Field("mass", 1, "kg", "head mass")])
    >>> CASE.size, CASE.offset("k"), CASE.columns()
    (5, 2, ['q1', 'q2', 'k1', 'k2', 'mass'])
    >>> row = CASE.pack(q=[0.1, 0.2], k=[40.0, 30.0], mass=5.0)
    >>> CASE.read(row, "mass")
    5.0

Kernels index rows with module-level integer constants taken from the
layout (``Q, K = CASE.offsets("q", "k")``), which numba freezes at compile
time: the generated code is the same as with hand-written literals, so the
layout costs nothing at run time.  Outside the declaring module no code
indexes a declared array with a literal number.

Flags are stored in the float rows as small integers (codes of an
:class:`enum.IntEnum`) and read back with ``int(row[OFFSET])``; kernels compare
them with the enum members, never with float thresholds.

Every layout registers itself in :data:`REGISTRY`, so the tests can check a
pack -> read-by-name round trip for all of them, and
``docs/architecture.md`` can list them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from ._validation import did_you_mean

#: Every layout declared so far, by name (filled as modules are imported).
REGISTRY: dict = {}


@dataclass(frozen=True)
class Field:
    """One named field of a :class:`Layout`.

    Attributes
    ----------
    name : str
        Identifier (a Python name).
    length : int
        Number of float64 slots, >= 1.
    unit : str
        SI unit of the values ("-" for dimensionless, "code" for enum flags).
    doc : str
        One-line meaning, with its thesis reference where there is one.
    columns : tuple of str, optional
        Column names of the slots; default ``name`` for a scalar field and
        ``name1 .. nameN`` otherwise.
    default : float or None
        Value used by :meth:`Layout.pack` when the field is not given; None
        (the default) makes the field required.
    """

    name: str
    length: int
    unit: str
    doc: str
    columns: tuple | None = None
    default: float | None = None

    def __post_init__(self):
        if not (isinstance(self.name, str) and self.name.isidentifier()):
            raise ValueError(f"Field.name must be a Python identifier, got {self.name!r}")
        if isinstance(self.length, bool) or not isinstance(self.length, int) or self.length < 1:
            raise ValueError(f"Field {self.name}: length must be an int >= 1, got {self.length!r}")
        if self.columns is not None:
            cols = tuple(self.columns)
            if len(cols) != self.length or not all(isinstance(c, str) for c in cols):
                raise ValueError(f"Field {self.name}: columns must be {self.length} strings, "
                                 f"got {self.columns!r}")
            object.__setattr__(self, "columns", cols)

    def column_names(self) -> list:
        """Column names of the field's slots."""
        if self.columns is not None:
            return list(self.columns)
        if self.length == 1:
            return [self.name]
        return [f"{self.name}{i + 1}" for i in range(self.length)]


class Layout:
    """A flat float64 row made of named fields, declared once.

    Parameters
    ----------
    name : str
        Human-readable name, unique in :data:`REGISTRY` (e.g.
        ``"plant parameters"``).
    fields : sequence of Field
        The fields in memory order.
    register : bool, keyword-only
        Add the layout to :data:`REGISTRY` (default True).
    """

    def __init__(self, name: str, fields: Sequence[Field], *, register: bool = True):
        if not isinstance(name, str) or not name:
            raise ValueError(f"Layout name must be a non-empty string, got {name!r}")
        fields = tuple(fields)
        if not all(isinstance(f, Field) for f in fields):
            raise TypeError(f"Layout {name!r}: fields must be Field objects")
        self.name = name
        self.fields = fields
        self._by_name = {}
        self._offset = {}
        off = 0
        for f in fields:
            if f.name in self._by_name:
                raise ValueError(f"Layout {name!r}: field {f.name!r} declared twice")
            self._by_name[f.name] = f
            self._offset[f.name] = off
            off += f.length
        self.size = off
        cols = [c for f in fields for c in f.column_names()]
        if len(set(cols)) != len(cols):
            dup = sorted({c for c in cols if cols.count(c) > 1})
            raise ValueError(f"Layout {name!r}: duplicate column names {dup}")
        self._columns = cols
        if register:
            if name in REGISTRY and REGISTRY[name] is not self:
                raise ValueError(f"a layout named {name!r} is already registered")
            REGISTRY[name] = self

    # -- structure ------------------------------------------------------------------------
    def __repr__(self) -> str:
        return f"Layout({self.name!r}, {len(self.fields)} fields, size {self.size})"

    def __contains__(self, name) -> bool:
        return name in self._by_name

    def __len__(self) -> int:
        return self.size

    def field(self, name: str) -> Field:
        """The :class:`Field` called ``name``.

        Parameters
        ----------
        name : str
            Field name as declared.

        Raises
        ------
        KeyError
            If the layout has no such field (the message lists the fields).
        """
        try:
            return self._by_name[name]
        except (KeyError, TypeError):
            raise KeyError(f"layout {self.name!r} has no field {name!r}; fields: "
                           f"{', '.join(self._by_name)}") from None

    def offset(self, name: str) -> int:
        """Index of the first slot of field ``name``.

        Parameters
        ----------
        name : str
            Field name as declared.

        Raises
        ------
        KeyError
            If the layout has no such field.
        """
        self.field(name)
        return self._offset[name]

    def offsets(self, *names: str) -> tuple:
        """Offsets of several fields, for module-level kernel constants.

        Parameters
        ----------
        *names : str
            Field names; the offsets are returned in the same order.

        Raises
        ------
        KeyError
            If one of the names is not a field.
        """
        return tuple(self.offset(n) for n in names)

    def length(self, name: str) -> int:
        """Number of slots of field ``name``.

        Parameters
        ----------
        name : str
            Field name as declared.
        """
        return self.field(name).length

    def slice(self, name: str) -> slice:
        """Slice of field ``name`` in a row.

        Parameters
        ----------
        name : str
            Field name as declared.
        """
        o = self.offset(name)
        return slice(o, o + self._by_name[name].length)

    def columns(self) -> list:
        """Column names of all slots, in memory order."""
        return list(self._columns)

    def column_index(self, column: str) -> int:
        """Slot index of the column called ``column`` (see :meth:`columns`).

        Parameters
        ----------
        column : str
            Column name: the field name for a scalar field, otherwise one of the
            per-slot names of :meth:`Field.column_names`.

        Raises
        ------
        KeyError
            If no slot has that column name.
        """
        try:
            return self._columns.index(column)
        except ValueError:
            raise KeyError(f"layout {self.name!r} has no column {column!r}") from None

    def table(self):
        """The declaration as a DataFrame: field, offset, length, unit, meaning."""
        return pd.DataFrame([{"field": f.name, "offset": self._offset[f.name], "length": f.length,
                              "unit": f.unit, "meaning": f.doc} for f in self.fields])

    # -- packing --------------------------------------------------------------------------
    def empty(self, *lead: int) -> np.ndarray:
        """Array of shape ``lead + (size,)`` filled with the defaults (0 where none).

        Parameters
        ----------
        *lead : int
            Leading (batch) dimensions; none gives a single row of shape
            ``(size,)``.
        """
        out = np.zeros(tuple(lead) + (self.size,))
        for f in self.fields:
            if f.default is not None:
                out[..., self.slice(f.name)] = f.default
        return out

    def pack(self, values: Mapping | None = None, *, out: np.ndarray | None = None,
             **kwargs) -> np.ndarray:
        """Build a row from field values given by name.

        Parameters
        ----------
        values : mapping, optional
            ``{field name: value}``; merged with ``kwargs``.
        out : numpy.ndarray, optional
            Row to fill in place (shape ``(size,)``).
        **kwargs
            Field values by name.  A scalar field takes a number, a field of
            length n a sequence of n numbers (a scalar is broadcast).

        Returns
        -------
        numpy.ndarray, shape (size,)

        Raises
        ------
        KeyError
            For a name that is not a field.
        ValueError
            For a missing required field, a value of the wrong length or a
            non-numeric value.
        """
        vals = dict(values or {})
        vals.update(kwargs)
        unknown = [k for k in vals if k not in self._by_name]
        if unknown:
            raise KeyError(f"layout {self.name!r} has no field(s) {unknown}; fields: "
                           f"{', '.join(self._by_name)}")
        row = np.zeros(self.size) if out is None else out
        if row.shape != (self.size,):
            raise ValueError(f"out must have shape ({self.size},), got {row.shape}")
        for f in self.fields:
            if f.name in vals:
                v = vals[f.name]
            elif f.default is not None:
                v = f.default
            else:
                raise ValueError(f"layout {self.name!r}: field {f.name!r} ({f.doc}) is required")
            try:
                arr = np.asarray(v, dtype=float)
            except (TypeError, ValueError):
                raise ValueError(f"layout {self.name!r}: field {f.name!r} must be numeric, "
                                 f"got {v!r}") from None
            if arr.ndim == 0:
                arr = np.full(f.length, float(arr))
            if arr.shape != (f.length,):
                raise ValueError(f"layout {self.name!r}: field {f.name!r} needs {f.length} "
                                 f"value(s), got shape {arr.shape}")
            row[self.slice(f.name)] = arr
        return row

    def read(self, row, name: str):
        """Value of field ``name`` in ``row`` (float for a scalar field, array otherwise).

        ``row`` may have leading batch dimensions; the field is taken along
        the last axis.

        Parameters
        ----------
        row : array_like, shape (..., size)
            One row or a batch of rows of this layout.
        name : str
            Field name as declared.

        Raises
        ------
        KeyError
            If the layout has no such field.
        ValueError
            If the last axis of ``row`` is not ``size`` long.
        """
        f = self.field(name)
        r = np.asarray(row)
        if r.shape[-1] != self.size:
            raise ValueError(f"layout {self.name!r}: row has {r.shape[-1]} slots, expected "
                             f"{self.size}")
        v = r[..., self.slice(name)]
        if f.length == 1:
            v = v[..., 0]
            return float(v) if v.ndim == 0 else v
        return v

    def unpack(self, row) -> dict:
        """All fields of ``row`` as ``{name: value}`` (see :meth:`read`).

        Parameters
        ----------
        row : array_like, shape (..., size)
            One row or a batch of rows of this layout.
        """
        return {f.name: self.read(row, f.name) for f in self.fields}

    def frame(self, rows, *, columns: Iterable[str] | None = None):
        """A 2-D array of rows as a DataFrame with :meth:`columns` as column names.

        Parameters
        ----------
        rows : array_like, shape (n, size)
            Rows of this layout.
        columns : iterable of str, optional
            Keep only these columns (in this order); default all.

        Raises
        ------
        ValueError
            If ``rows`` does not have shape ``(n, size)``.
        """
        a = np.asarray(rows)
        if a.ndim != 2 or a.shape[1] != self.size:
            raise ValueError(f"layout {self.name!r}: rows must have shape (n, {self.size}), "
                             f"got {a.shape}")
        df = pd.DataFrame(a, columns=self._columns)
        return df if columns is None else df[list(columns)]


def check_flag(enum_cls, value, name: str) -> int:
    """Validate a flag given as an enum member, its name or its code; return the code.

    Parameters
    ----------
    enum_cls : type of enum.IntEnum
    value : enum member, str or int
    name : str
        Argument name for the error message.
    """
    if isinstance(value, enum_cls):
        return int(value)
    if isinstance(value, str):
        # the documented lower-case name or the member's own upper-case name, words joined by
        # "_", "-" or " "; no other case (the policy of ppamsafety._validation)
        key = value.replace("-", "_").replace(" ", "_")
        if key in (key.lower(), key.upper()) and key.upper() in enum_cls.__members__:
            return int(enum_cls.__members__[key.upper()])
    elif isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        if int(value) in {int(m) for m in enum_cls}:
            return int(value)
    elif isinstance(value, float) and math.isfinite(value) and value.is_integer():
        if int(value) in {int(m) for m in enum_cls}:
            return int(value)
    names = [m.name.lower() for m in enum_cls]
    allowed = ", ".join(map(repr, names))
    raise ValueError(f"{name} = {value!r} is not one of {allowed}{did_you_mean(value, names)}")


__all__ = ["Field", "Layout", "REGISTRY", "check_flag"]
