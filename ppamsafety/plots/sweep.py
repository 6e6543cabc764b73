"""Figures of a sweep's results and of a safety envelope (``ppamsafety sweep``).

Each function takes the result table (a DataFrame) or a result object by duck typing
and returns a pyplot-free Figure; the limit lines are data of :mod:`ppamsafety.params`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..params.head import HIC_SERIOUS_5PCT, MAXILLA_FRACTURE_N
from ..params.iso_ts_15066 import SKULL_FOREHEAD
from .figure import new_figure

#: Result columns a sweep figure draws, with their axis labels (the ones present are drawn).
RESULTS = (("F_max", "F_max [N]"), ("HIC36", "HIC36 [-]"), ("HIC15", "HIC15 [-]"),
           ("tcp_speed", "TCP speed at impact [m/s]"), ("track_rms", "tracking error RMS [m]"),
           ("p_max", "peak contact pressure [Pa]"),
           ("covering_use", "covering compression / its limit [-]"))
#: Marker of the points above a limit line.
ABOVE = dict(marker="o", ms=8, mfc="none", mec="r", mew=1.2, ls="none")
#: Most lines per panel: beyond, the other swept parameters are drawn as points.
MAX_LINES = 8


def limit_lines(column: str) -> list:
    """The limit lines drawn on a panel of ``column``: (value, label, colour, style).

    Parameters
    ----------
    column : str
        A result column (``F_max``, ``HIC36``, ``HIC15`` ...).

    Returns
    -------
    list of tuple
    """
    if column == "F_max":
        return [(MAXILLA_FRACTURE_N, f"maxilla fracture {MAXILLA_FRACTURE_N:g} N", "r", "--"),
                (SKULL_FOREHEAD.force_transient,
                 f"ISO/TS 15066 forehead, transient {SKULL_FOREHEAD.force_transient:g} N"
                 + ("" if SKULL_FOREHEAD.transient_in_ts else " (not in the TS: 2 x F_qs)"),
                 "darkorange", ":")]
    if column.startswith("HIC"):
        return [(HIC_SERIOUS_5PCT, f"HIC {HIC_SERIOUS_5PCT:g} (5 % AIS 3+)", "r", "--")]
    return []


def _label(v, unit=None) -> str:
    """A swept value with its unit (``"140 kPa"``); a number given as text (a group key) too."""
    if isinstance(v, str):
        try:
            v = float(v)
        except ValueError:
            return v
    if isinstance(v, (int, float, np.integer, np.floating)):
        return f"{v:g}" + ("" if unit in (None, "-") else f" {unit}")
    return str(v)


def _result_label(col: str, lab: str, unit, ok: pd.DataFrame) -> str:
    """The axis label of a result: the unit it is shown in, and for ``tcp_speed`` of a sweep at
    another contact point, that point's speed."""
    if col == "tcp_speed" and "contact_point" in ok.columns:
        pts = sorted({str(p) for p in ok["contact_point"].dropna()} - {"", "tool point"})
        if pts:
            lab = (f"{pts[0]} speed at impact [m/s]" if len(pts) == 1 and
                   set(map(str, ok["contact_point"].dropna())) == {pts[0]}
                   else "contact point speed at impact [m/s]")
    if unit and unit != "-" and lab.endswith("]"):
        lab = lab[:lab.rindex("[")] + f"[{unit}]"
    return lab


def _with_unit(name: str, unit) -> str:
    return name if unit is None else f"{name} [{unit}]"


def mark_above(ax, x, y, column: str) -> bool:
    """Ring the points of ``column`` above its lowest limit line; whether there were any.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The panel.
    x, y : array_like
        The points.
    column : str
        The result column (its limits: :func:`limit_lines`).
    """
    lines = limit_lines(column)
    if not lines:
        return False
    lo = min(v for v, *_ in lines)
    y = np.asarray(y, dtype=float)
    above = np.isfinite(y) & (y > lo)
    if above.any():
        ax.plot(np.asarray(x)[above], y[above], **ABOVE)
    return bool(above.any())


def plot_sweep(df: pd.DataFrame, swept, *, title: str = "", units=None,
               region_limits=None, limits=None, failed=None):
    """Each result of a sweep against each swept parameter, with the safety limits.

    Parameters
    ----------
    df : pandas.DataFrame
        The sweep's result table (case parameters, ``status``, the results), the swept
        values in the units of ``units``.
    swept : sequence of str
        The case parameters that vary (one column of panels each).
    title : str
        Figure title (wrapped when it is wider than the figure).
    units : dict, optional
        Column -> unit shown on the axes and in the legends (``"-"`` dimensionless, None
        none; the values are in these units); default: the SI units of :data:`RESULTS` only.
        With a ``contact_point`` column, ``tcp_speed`` is labelled as that point's speed.
    region_limits : dict, optional
        Body region name -> {result column: limit} (e.g. ``{"face": {"F_max": 130.0}}``):
        each region that appears in the table's ``body_region`` column gets its limit line
        on the panels of that result.
    limits : dict, optional
        Result column -> list of ``(value, label)``: the limit lines of that panel, in the
        unit of the column (e.g. the limits that decide the verdicts,
        :func:`ppamsafety.sweep_cases.verdict_limits`); replaces :func:`limit_lines` for
        the columns it names.
    failed : dict, optional
        Result column -> boolean array aligned with ``df``: the cases that fail a criterion
        on that result, ringed red (in place of the points above the lowest line).

    Returns
    -------
    matplotlib.figure.Figure
        One row of panels per result of :data:`RESULTS` present, one column per swept
        parameter; F_max panels carry the 660 N maxilla line and the ISO/TS 15066
        transient forehead limit, HIC panels the HIC 650 line (log scale), and the limits
        of the body regions present (``region_limits``), each labelled in the panel's legend;
        points above the lowest limit of their panel are ringed red.
    """
    units = dict(units or {})
    ok = df[df["status"] == "ok"] if "status" in df.columns else df
    results = [(c, lab) for c, lab in RESULTS if c in ok.columns and ok[c].notna().any()]
    swept = list(swept) or ["case"]
    if swept == ["case"]:
        ok = ok.assign(case=np.arange(len(ok)))
    nr, nc = max(1, len(results)), len(swept)
    fig, axes = new_figure(nr, nc, figsize=(4.2 * nc + 1.0, 3.0 * nr + 0.6), squeeze=False,
                           layout="constrained")
    for j, x in enumerate(swept):
        others = [s for s in swept if s != x]
        xs = ok[x].map(lambda v: str(v) if isinstance(v, (list, tuple, dict)) else v)
        numeric = pd.api.types.is_numeric_dtype(xs)
        cats = None if numeric else list(dict.fromkeys(xs))
        xv = xs if numeric else xs.map({c: i for i, c in enumerate(cats)})
        groups = (list(ok.assign(_x=xv).groupby([ok[o].map(str) for o in others], sort=False))
                  if others else [("", ok.assign(_x=xv))])
        for i, (col, lab) in enumerate(results):
            ax = axes[i, j]
            lines = len(groups) <= MAX_LINES
            for key, g in groups:
                g = g.sort_values("_x")
                name = ", ".join(f"{o} = {_label(k, units.get(o))}" for o, k in zip(
                    others, key if isinstance(key, tuple) else (key,))) if others else None
                ax.plot(g["_x"], g[col], "o-" if lines else "o", ms=3, lw=1,
                        label=name if lines else None)
            drawn = (limit_lines(col) if col not in (limits or {}) else
                     [(v, text, "r" if k == 0 else f"C{(k + 5) % 10}", "--" if k == 0 else ":")
                      for k, (v, text) in enumerate(limits[col])])
            for v, text, color, style in drawn:
                ax.axhline(v, color=color, ls=style, lw=1, label=text)
            if col in (failed or {}):
                bad = np.asarray(failed[col], dtype=bool)[
                    np.asarray(ok.index.map(df.index.get_loc), dtype=int)]
                if bad.any():
                    ax.plot(np.asarray(xv)[bad], ok[col].to_numpy(float)[bad], **ABOVE)
                    ax.plot([], [], label="fails its verdict", **ABOVE)
            elif mark_above(ax, xv, ok[col], col):
                ax.plot([], [], label="above a limit", **ABOVE)
            present = set(ok["body_region"]) if "body_region" in ok.columns else set()
            for k, (region, lims) in enumerate(sorted((region_limits or {}).items())):
                if region in present and col in lims:
                    ax.axhline(lims[col], color=f"C{(k + 3) % 10}", ls="-.", lw=1,
                               label=f"{region}: {lims[col]:g}")
            if col.startswith("HIC") and (ok[col] > 0).all():
                ax.set_yscale("log")
            ax.set_ylabel(_result_label(col, lab, units.get(col), ok))
            ax.set_xlabel(_with_unit(x, units.get(x)))
            if cats is not None:
                ax.set_xticks(range(len(cats)), cats, rotation=20, fontsize=7)
            ax.grid(alpha=0.3)
            if i == 0 or drawn:
                ax.legend(fontsize=6)
    if title:
        fig.suptitle(title)
    return fig


#: Units of the results an envelope limits (its ``metric``).
METRIC_UNITS = {"F_max": "N", "HIC36": "-", "HIC15": "-", "p_max": "Pa"}


def plot_envelope(envelope, *, title: str = "", unit=None):
    """A safety envelope: the limited result against the parameter, and the boundary.

    Parameters
    ----------
    envelope : SafetyEnvelope
        Result of :func:`ppamsafety.envelope.safety_envelope` (``evaluations``,
        ``parameter``, ``metric``, ``limit_value``, ``limit_label``, ``safe_value``).
    title : str
        Figure title (default: the envelope's description); wrapped to the figure.
    unit : str, optional
        Unit of the parameter (its values are SI).

    Returns
    -------
    matplotlib.figure.Figure
        The evaluations (points above the limit ringed red), the labelled limit line and the
        envelope's boundary.
    """
    ev = envelope.evaluations.sort_values("value")
    fig, ax = new_figure(figsize=(6.5, 4.0), layout="constrained")
    ok = ev[ev["status"] == "ok"]
    ax.plot(ok["value"], ok[envelope.metric], "o-", ms=4, lw=1, label="evaluated")
    ax.axhline(envelope.limit_value, color="r", ls="--", lw=1, label=envelope.limit_label)
    y = ok[envelope.metric].to_numpy(float)
    above = np.isfinite(y) & (y > envelope.limit_value)
    if above.any():
        ax.plot(ok["value"].to_numpy(float)[above], y[above], label="above the limit", **ABOVE)
    if envelope.safe_value is not None:
        ax.axvline(envelope.safe_value, color="g", lw=1.2,
                   label=f"envelope: {envelope.parameter} = "
                         f"{_label(envelope.safe_value, unit)}")
    for i, c in enumerate(getattr(envelope, "crossings", ())):
        ax.axvspan(min(c["safe_value"], c["unsafe_value"]), max(c["safe_value"],
                                                                c["unsafe_value"]),
                   color="tab:orange" if c["flat"] else "tab:gray", alpha=0.3,
                   label=("crossing bracket" + (" (flat)" if c["flat"] else "")) if i == 0
                   else None)
    ax.set_xlabel(_with_unit(envelope.parameter, unit))
    ax.set_ylabel(_with_unit(envelope.metric, METRIC_UNITS.get(envelope.metric)))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title(title or envelope.description, fontsize=9)
    return fig


__all__ = ["plot_sweep", "plot_envelope", "limit_lines", "mark_above", "RESULTS",
           "METRIC_UNITS"]
