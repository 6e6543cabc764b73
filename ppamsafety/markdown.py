"""Plain-text table rendering (Markdown) without extra dependencies."""

from __future__ import annotations

import math

import pandas as pd


def _fmt(v, digits: int) -> str:
    if isinstance(v, (bool,)):
        return "yes" if v else "no"
    if isinstance(v, float):
        if math.isnan(v):
            return ""
        if v == 0:
            return "0"
        if v != 0 and (abs(v) >= 1e5 or abs(v) < 10 ** (-digits)):
            return f"{v:.{digits}g}"
        txt = f"{v:.{digits}f}"
        txt = txt.rstrip("0").rstrip(".") if "." in txt else txt
        return "0" if txt in ("-0", "0") else txt
    return str(v)


def markdown_table(df: pd.DataFrame, *, digits: int = 4, index: bool = False) -> str:
    """Render a DataFrame as a GitHub-flavoured Markdown table.

    Parameters
    ----------
    df : pandas.DataFrame
        The table.
    digits : int
        Decimals of floats (trailing zeros dropped; very large or small
        values in ``g`` format); NaN renders as an empty cell, bools as
        yes/no.
    index : bool
        Include the index as leading column(s).

    Returns
    -------
    str
        The Markdown table.
    """
    d = df.reset_index() if index else df
    cols = [str(c) for c in d.columns]
    lines = ["| " + " | ".join(cols) + " |", "|" + "|".join("---" for _ in cols) + "|"]
    for row in d.itertuples(index=False):
        lines.append("| " + " | ".join(_fmt(v, digits) for v in row) + " |")
    return "\n".join(lines)
