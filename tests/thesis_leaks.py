"""A detector of thesis constants in the output of a run for another arm.

A run for an arm that is not the thesis arm must show that arm's numbers.  A *leak* is a
value of the thesis arm, or a value the thesis publishes for it, printed in such a run
although the arm does not have it (a default taken from the thesis, a sentence written for
the thesis arm, a thesis table joined to another arm's results).

The constants are derived, not listed:

* every parameter of :func:`ppamsafety.params.thesis_arm` (its arm-file keys, with their units);
* every published value in the thesis data modules: module-level names of
  :mod:`ppamsafety.params`, :mod:`ppamsafety.hysteresis.force` and the report sections that
  hold a thesis value (``THESIS_*``, ``TABLE_*``, ``FIG_*``, ``CALIBRATED_*``, ``DELTA_*``), and
  every constant of the ``thesis_data`` modules; the thesis tables through their ``table_*()`` functions
  (one constant per result cell; the controller keys are settings, not results).

A constant's unit is the arm file's, or inferred from its name (:data:`NAME_UNITS`).  The
constants an arm *has* (its own parameters, its joint stiffness at the stiffness pose of
:func:`ppamsafety.design.arm_summary`, its total moving mass) are not leaks for that arm.

Matching (:func:`find_leaks`) needs a context, never a bare number (a computed value may
round to a thesis value by chance):

* **unit**: a number (or a list ``(43, 27)``, ``43/27``) followed by a unit of the
  constant's quantity (``43 Nm/rad``, ``2.5 kg``, ``1.66 bar``), or a table cell (Markdown,
  CSV, HTML) whose column header carries that unit (``K1 [Nm/rad]``, ``F_max_N``);
* **name**: a number after one of the constant's names and ``=`` or ``:``
  (``delta = 0.139``, ``hysteresis_delta=0.139``), or in a column of that name.

The number must equal the constant rounded to the printed decimals and carry at least
min(3, the constant's significant digits) significant digits, and at least as many as keep
the chance that a computed number hits one of the constants of its unit by accident below
:data:`COINCIDENCE` (:func:`required_digits`; at least 2: a constant with one significant
digit, such as 0.3 m, matches by name only; a dense thesis table, such as Table 5.2's errors,
by name only).
"""

from __future__ import annotations

import html.parser
import importlib
import json as _json
import math
import pkgutil
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ppamsafety.design import arm_summary
from ppamsafety.params import is_thesis_arm, thesis_arm
from ppamsafety.params.arm_file import arm_to_dict
from ppamsafety.units import BAR, DEG


@dataclass(frozen=True)
class Constant:
    """A thesis value: its name, SI value and unit, the names it is printed under."""

    name: str
    value: float
    unit: str          # normalised SI unit (:func:`norm_unit`), "1" if dimensionless
    aliases: tuple
    source: str


@dataclass(frozen=True)
class Leak:
    """A thesis constant found in an output."""

    where: str
    text: str
    constant: Constant

    def __str__(self):
        c = self.constant
        return (f"{self.where}: {self.text!r} is the thesis' {c.name} = {c.value:g} {c.unit} "
                f"({c.source})")


# ------------------------------------------------------------------------------------ units

def norm_unit(u: str) -> str:
    """A unit spelling without spaces, ``*``, ``·`` and ``^`` (``N m/rad`` -> ``Nm/rad``)."""
    u = u.replace("²", "2").replace("³", "3").replace("°", "deg").replace("Ω", "Ohm")
    return re.sub(r"[\s*·^]", "", u)


#: Printed unit (normalised) -> (normalised SI unit, factor to SI).
PRINTED_UNITS = {
    "N": ("N", 1.0), "kN": ("N", 1e3),
    "kg": ("kg", 1.0),
    "m": ("m", 1.0), "mm": ("m", 1e-3), "cm": ("m", 1e-2),
    "s": ("s", 1.0), "ms": ("s", 1e-3),
    "rad": ("rad", 1.0), "deg": ("rad", DEG),
    "rad/s": ("rad/s", 1.0), "deg/s": ("rad/s", DEG),
    "Pa": ("Pa", 1.0), "kPa": ("Pa", 1e3), "MPa": ("Pa", 1e6), "bar": ("Pa", BAR),
    "mbar": ("Pa", 1e-3 * BAR),
    "Nm/rad": ("Nm/rad", 1.0), "Nm/deg": ("Nm/rad", 1.0 / DEG),
    "Nm": ("Nm", 1.0), "Nms/rad": ("Nms/rad", 1.0),
    "kgm": ("kgm", 1.0), "kgm2": ("kgm2", 1.0),
    "N/Pa": ("N/Pa", 1.0), "N/bar": ("N/Pa", 1.0 / BAR),
    "m/s2": ("m/s2", 1.0), "m/s": ("m/s", 1.0),
    "Hz": ("Hz", 1.0), "kHz": ("Hz", 1e3), "MHz": ("Hz", 1e6),
    "rad2": ("rad2", 1.0), "rad2/s2": ("rad2/s2", 1.0),
}
#: Unit suffixes of column names such as ``F_max_N``, ``lambda_s``, ``K1_Nm_per_rad``.
SUFFIX_UNITS = {"N": "N", "kg": "kg", "m": "m", "mm": "mm", "s": "s", "ms": "ms", "deg": "deg",
                "rad": "rad", "bar": "bar", "Pa": "Pa", "Nm_per_rad": "Nm/rad",
                "Nm_rad": "Nm/rad", "m_s": "m/s"}

_UNIT_RE = re.compile(
    r"\s?(" + "|".join(sorted((re.escape(u) for u in
                               ("N", "kN", "kg", "m", "mm", "cm", "s", "ms", "rad", "deg", "°",
                                "rad/s", "deg/s", "Pa", "kPa", "MPa", "bar", "mbar", "Nm/rad",
                                "N m/rad", "N·m/rad", "N m / rad", "Nm/deg", "Nm", "N m", "N·m",
                                "N m s/rad", "kg m", "kg m^2", "kg m²", "kg·m²", "N/Pa",
                                "N/bar", "m/s^2", "m/s²", "m/s", "Hz", "kHz", "MHz")),
                              key=len, reverse=True)) + r")(?![\w/^²])")


# -------------------------------------------------------------------------------- constants

#: Name patterns -> (SI unit as written, factor to SI, extra names it is printed under).
#: The first match wins; a name matching none is a dimensionless value printed under its own
#: name only.
NAME_UNITS = (
    (r"STIFFNESS", "Nm/rad", 1.0, ("K", "K1", "K2", "stiffness")),
    (r"MASS", "kg", 1.0, ("M", "mass")),
    (r"_DEG$|^RMS", "rad", DEG, ("RMS",)),
    (r"DELTA", "1", 1.0, ("delta", "δ", "hysteresis_delta")),
    (r"^HIC", "1", 1.0, ("HIC", "HIC36")),
    (r"^Fmax|^F_|_N$", "N", 1.0, ("F_max", "Fmax")),
    (r"_m$", "m", 1.0, ()),
    (r"N_PER_BAR", "N/Pa", 1.0 / BAR, ()),
    (r"P_MEAN|PRESSURE", "Pa", 1.0, ("p_m", "mean_pressure")),
)
#: Arm-file keys printed under other names as well.
KEY_ALIASES = {"hysteresis_delta": ("delta", "δ"), "mean_pressure": ("p_m", "p_mean"),
               "time_constant": ("T",), "polytropic_n": ("n",), "m2": ("m_2",),
               "m1": ("m_1",)}
#: Modules holding published thesis values.
PUBLISHED_MODULES = ("ppamsafety.params", "ppamsafety.hysteresis.force",
                     "ppamsafety.impact.thesis_data", "ppamsafety.experiments.thesis_data",
                     "ppamsafety.sections")
_PUBLISHED_NAME = re.compile(r"THESIS|^TABLE_|^FIG_|^CALIBRATED_|^DELTA_\d")
#: Columns of the thesis tables that key a row (controller settings), not results.
SETTING_COLUMNS = ("controller_family", "ki_bar", "lambda_s", "Ki", "lambda", "period_s")


def _unit_of(name: str):
    for pat, unit, factor, aliases in NAME_UNITS:
        if re.search(pat, name):
            return norm_unit(unit), factor, aliases
    return "1", 1.0, ()


def _numbers(name, value, unit, factor, aliases, source):
    """Constants of a number, a sequence or a dict of numbers (recursively)."""
    if isinstance(value, bool) or value is None:
        return []
    if isinstance(value, (int, float, np.floating, np.integer)):
        v = float(value) * factor
        return [Constant(name, v, unit, aliases, source)] if math.isfinite(v) else []
    if isinstance(value, dict):
        out = []
        for k, v in value.items():
            u, f, a = _unit_of(str(k))
            if u == "1" and not a:
                u, f, a = unit, factor, aliases
            out += _numbers(f"{name}[{k!r}]", v, u, f, (*a, str(k)), source)
        return out
    if isinstance(value, (tuple, list)):
        out = []
        for i, v in enumerate(value):
            out += _numbers(f"{name}[{i}]", v, unit, factor, aliases, source)
        return out
    return []


def _arm_values(arm) -> list:
    """(dotted key, SI value, normalised unit) of every number of an arm's file."""
    out = []

    def walk(prefix, d):
        for k, v in d.items():
            key = f"{prefix}.{k}" if prefix else k
            if isinstance(v, dict) and "value" in v and "unit" in v:
                vals, unit = v["value"], norm_unit(v["unit"])
            elif isinstance(v, dict):
                walk(key, v)
                continue
            else:
                vals, unit = v, "1"
            seq = vals if isinstance(vals, (list, tuple)) else [vals]
            for i, x in enumerate(seq):
                if isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x):
                    out.append((key + (f"[{i}]" if len(seq) > 1 else ""), float(x), unit))
    walk("", arm_to_dict(arm))
    return out


def _modules():
    for name in PUBLISHED_MODULES:
        mod = importlib.import_module(name)
        yield mod
        if hasattr(mod, "__path__"):
            for info in pkgutil.iter_modules(mod.__path__):
                yield importlib.import_module(f"{name}.{info.name}")


def thesis_constants() -> list:
    """Every thesis constant: the thesis arm's parameters and the published values.

    Returns
    -------
    list of Constant
    """
    out = []
    for key, v, unit in _arm_values(thesis_arm()):
        leaf = re.sub(r"\[\d+\]$", "", key).rsplit(".", 1)[-1]
        out.append(Constant(f"arm {key}", v, unit, (leaf, *KEY_ALIASES.get(leaf, ())),
                            "thesis_arm()"))
    seen = set()
    for mod in _modules():
        tables = {n for n in dir(mod) if n.startswith("table_") and callable(getattr(mod, n))
                  and getattr(getattr(mod, n), "__module__", None) == mod.__name__}
        for fn in sorted(tables):
            if (mod.__name__, fn) in seen:
                continue
            seen.add((mod.__name__, fn))
            df = getattr(mod, fn)()
            if not isinstance(df, pd.DataFrame):
                continue
            for col in df.columns:
                if col in SETTING_COLUMNS or not pd.api.types.is_numeric_dtype(df[col]):
                    continue
                unit, factor, aliases = _unit_of(col)
                for v in df[col].dropna():
                    out += _numbers(f"{mod.__name__}.{fn}() {col}", v, unit, factor,
                                    (*aliases, col), f"{mod.__name__}.{fn}")
        for name, value in vars(mod).items():
            data_module = mod.__name__.endswith("thesis_data") and name.isupper()
            if not (data_module or _PUBLISHED_NAME.search(name)) or name.lower() in tables:
                continue
            if getattr(value, "__module__", None) and not isinstance(value, (int, float)):
                continue                      # a class or function, not data
            origin = (mod.__name__, name, repr(value))
            if origin in seen:
                continue
            seen.add(origin)
            unit, factor, aliases = _unit_of(name)
            out += _numbers(f"{mod.__name__}.{name}", value, unit, factor, (*aliases, name),
                            mod.__name__)
    # one entry per (value, unit): the first name found
    uniq = {}
    for c in out:
        uniq.setdefault((round(c.value, 12), c.unit), c)
    return list(uniq.values())


def sig_digits(x: float, most: int = 6) -> int:
    """Significant digits needed to write ``x`` (at most ``most``)."""
    if x == 0:
        return 1
    for s in range(1, most + 1):
        if math.isclose(float(f"{x:.{s}g}"), x, rel_tol=1e-9):
            return s
    return most


def _round_sig(x: float, s: int) -> float:
    return float(f"{x:.{s}g}")


def own_values(arm) -> list:
    """(SI value, normalised unit) of what an arm has: its parameters, its stiffness at the
    stiffness pose of :func:`ppamsafety.design.arm_summary`, its total moving mass."""
    vals = [(v, u) for _, v, u in _arm_values(arm)]
    s = arm_summary(arm, n=11)
    vals += [(k, "Nm/rad") for k in s.stiffness]
    vals.append((arm.links.m1 + arm.links.m2 + arm.effects.payload_mass, "kg"))
    return vals


def constants_for(arm) -> list:
    """The thesis constants an arm does not have (the leaks to look for in its output).

    A constant is the arm's own when a value of the arm in the same unit rounds to it at the
    constant's significant digits.
    """
    if is_thesis_arm(arm):
        return []
    own = own_values(arm)
    out = []
    for c in thesis_constants():
        s = sig_digits(c.value)
        if any(u == c.unit and math.isclose(_round_sig(v, s), _round_sig(c.value, s),
                                            rel_tol=1e-9, abs_tol=1e-300) for v, u in own):
            continue
        out.append(c)
    return out


# --------------------------------------------------------------------------------- matching

_NUM = r"[-−]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_NUM_RE = re.compile(rf"(?<![\w.§]){_NUM}(?![\w]|\.\d)")
_SEP = r"\s*(?:,|/|;|\band\b|\bto\b|\.\.|–)\s*"
_GROUP_RE = re.compile(rf"(?<![\w.§])[(\[]?\s*({_NUM}(?:{_SEP}{_NUM})*)\s*[)\]]?(?![\w]|\.\d)")


def _parse(tok: str):
    """(value, decimals, significant digits) of a printed number, or None."""
    t = tok.replace("−", "-").strip()
    try:
        v = float(t)
    except ValueError:
        return None
    if not math.isfinite(v):
        return None
    mant = re.sub(r"[eE].*$", "", t.lstrip("-+"))
    exp = int(re.search(r"[eE]([-+]?\d+)", t).group(1)) if re.search(r"[eE]", t) else 0
    dec = len(mant.split(".")[1]) if "." in mant else 0
    digits = mant.replace(".", "").lstrip("0")
    if "." not in mant:
        digits = digits.rstrip("0") or "0"
    return v, dec - exp, max(len(digits), 1)


#: Largest chance that a computed number printed with the required digits rounds to one of
#: the constants of its unit within a decade by accident.
COINCIDENCE = 0.05


def required_digits(c: Constant, constants) -> int:
    """Significant digits a number must show to be taken for ``c``: at least 2, and enough
    that the constants of its unit within a factor 10 are hit by chance with a probability of
    at most :data:`COINCIDENCE` (about n / (9 10^(s-1)) for n such constants)."""
    if c.value == 0:
        return 99
    n = sum(1 for d in constants if d.unit == c.unit and d.value != 0
            and abs(math.log10(abs(d.value) / abs(c.value))) < 1)
    s = 2
    while n / (9 * 10 ** (s - 1)) > COINCIDENCE:
        s += 1
    return s


def _matches(token: str, c: Constant, factor: float, need: int) -> bool:
    """Whether ``token`` (printed in a unit of SI factor ``factor``) spells ``c`` with at least
    ``need`` significant digits."""
    p = _parse(token)
    if p is None:
        return False
    v, dec, sig = p
    cv = c.value / factor
    if sig < max(need, min(3, sig_digits(cv))) or cv == 0:
        return False
    return math.isclose(round(cv, dec), v, rel_tol=1e-9, abs_tol=0.5 * 10.0 ** -(dec + 6))


def _unit_factor(unit_text: str):
    """(normalised SI unit, factor) of a printed unit, or None."""
    return PRINTED_UNITS.get(norm_unit(unit_text))


def _header_unit(header: str):
    """(name, unit text or None) of a column header: ``F_max [N]``, ``F_max_N``, ``x (mm)``."""
    h = header.strip()
    m = re.search(r"\[([^\]]+)\]\s*$", h) or re.search(r"\[([^\]]+)\]", h)
    if m:
        return h[:m.start()].strip(), m.group(1)
    m = re.search(r"\(([^)]+)\)\s*$", h)
    if m and _unit_factor(m.group(1)):
        return h[:m.start()].strip(), m.group(1)
    for suf in sorted(SUFFIX_UNITS, key=len, reverse=True):
        if h.endswith("_" + suf):
            return h[:-len(suf) - 1], SUFFIX_UNITS[suf]
    return h, None


class Detector:
    """Finds the given constants in text, Markdown, CSV and HTML.

    Parameters
    ----------
    constants : list of Constant
        What to look for (:func:`constants_for`).
    """

    def __init__(self, constants):
        self.constants = list(constants)
        self.need = {c: required_digits(c, self.constants) for c in self.constants}
        # a constant written with fewer digits than its neighbourhood requires (a dense thesis
        # table) is recognised by its name only
        self.by_unit_ok = {c for c in self.constants if sig_digits(c.value) >= self.need[c]}
        self.by_unit = {}
        for c in self.constants:
            self.by_unit.setdefault(c.unit, []).append(c)

    def _named(self, name: str) -> list:
        key = name.strip().strip("`*")
        return [c for c in self.constants if key in c.aliases]

    def _first(self, tok, unit, names):
        """The constant ``tok`` spells in printed unit ``unit`` (text or None) or under one of
        the constants ``names``; None if none."""
        uf = _unit_factor(unit) if unit else None
        if uf:
            for c in self.by_unit.get(uf[0], []):
                if c in self.by_unit_ok and _matches(tok, c, uf[1], self.need[c]):
                    return c
        for c in names:     # by name: in the unit printed, or SI when none is
            f = 1.0 if c.unit == "1" or uf is None else (uf[1] if uf[0] == c.unit else None)
            if f is not None and _matches(tok, c, f, self.need[c]):
                return c
        return None

    def cell(self, cell: str, header: str, where: str) -> list:
        """Leaks in one table cell under its column header."""
        name, unit = _header_unit(header)
        names = self._named(name)
        found = []
        for m in _NUM_RE.finditer(cell):
            c = self._first(m.group(0), unit, names)
            if c is not None:
                found.append(Leak(where, f"{header}: {cell.strip()}", c))
        return found

    def text(self, text: str, where: str) -> list:
        """Leaks in prose (Markdown or plain text; Markdown tables cell by cell)."""
        found = []
        header = None
        for i, line in enumerate(text.splitlines(), 1):
            s = line.strip()
            if s.startswith("|") and s.endswith("|") and len(s) > 1:
                cells = [x.strip() for x in s[1:-1].split("|")]
                if header is None:
                    header = cells
                    continue
                if all(re.fullmatch(r":?-{2,}:?", x) for x in cells if x):
                    continue
                for h, cell in zip(header, cells):
                    found += self.cell(cell, h, f"{where}:{i}")
                continue
            header = None
            found += self._prose(line, f"{where}:{i}")
        return found

    def _prose(self, line, where):
        found = []
        for m in _GROUP_RE.finditer(line):
            um = _UNIT_RE.match(line[m.end():])
            nm = re.search(r"([\w\u0370-\u03ff]+)\s*(?:=|:|≈)\s*$", line[:m.start()])
            names = self._named(nm.group(1)) if nm else []
            for tok in re.findall(_NUM, m.group(1)):
                c = self._first(tok, um.group(1) if um else None, names)
                if c is not None:
                    found.append(Leak(where, line.strip()[:160], c))
        return found

    def csv(self, path) -> list:
        """Leaks in a CSV file: every cell under its column header."""
        path = Path(path)
        try:
            df = pd.read_csv(path, dtype=str, keep_default_na=False)
        except (pd.errors.EmptyDataError, pd.errors.ParserError):
            return []
        found = []
        for col in df.columns:
            for r, cell in enumerate(df[col]):
                found += self.cell(str(cell), str(col), f"{path.name}:{r + 2}")
        return found

    def json(self, path) -> list:
        """Leaks in a JSON file: every number under its key."""
        found = []

        def walk(key, v, where):
            if isinstance(v, dict):
                for k, x in v.items():
                    walk(str(k), x, f"{where}.{k}")
            elif isinstance(v, list):
                for i, x in enumerate(v):
                    walk(key, x, f"{where}[{i}]")
            elif isinstance(v, (int, float)) and not isinstance(v, bool):
                found.extend(self.cell(repr(v), key, where))
            elif isinstance(v, str):
                found.extend(self._prose(v, where))
        walk("", _json.loads(Path(path).read_text(encoding="utf-8")), Path(path).name)
        return found


class _HTMLText(html.parser.HTMLParser):
    """The text of an HTML page as lines, tables as Markdown tables."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.lines, self.buf, self.row, self.cell, self.skip = [], [], None, None, 0

    def handle_starttag(self, tag, attrs):
        if tag in ("script", "style"):
            self.skip += 1
        elif tag == "tr":
            self.flush()
            self.row = []
        elif tag in ("td", "th"):
            self.cell = []
        elif tag in ("p", "br", "li", "h1", "h2", "h3", "h4", "div", "table", "pre"):
            self.flush()

    def handle_endtag(self, tag):
        if tag in ("script", "style"):
            self.skip -= 1
        elif tag in ("td", "th") and self.row is not None and self.cell is not None:
            self.row.append(" ".join("".join(self.cell).split()).replace("|", "/"))
            self.cell = None
        elif tag == "tr" and self.row is not None:
            self.lines.append("| " + " | ".join(self.row) + " |")
            self.row = None
        elif tag == "table":
            self.lines.append("")
        elif tag in ("p", "li", "h1", "h2", "h3", "h4", "div", "pre"):
            self.flush()

    def handle_data(self, data):
        if self.skip:
            return
        if self.cell is not None:
            self.cell.append(data)
        else:
            self.buf.append(data)

    def flush(self):
        text = " ".join("".join(self.buf).split())
        if text:
            self.lines.append(text)
        self.buf = []


def html_text(page: str) -> str:
    """The readable text of an HTML page (tables as Markdown tables)."""
    p = _HTMLText()
    p.feed(page)
    p.flush()
    return "\n".join(p.lines)


def strip_arm_text(text: str, arm) -> str:
    """``text`` without the arm's own words (its name and ``source`` strings), which may
    quote the thesis on purpose."""
    for s in sorted([arm.name or "", *(t for _, t in arm.sources)], key=len, reverse=True):
        if s:
            text = text.replace(s, "")
    return text


#: Files of an output folder that are inputs echoed back (the arm, head and study files).
ECHOED = ("arm.toml", "head.toml", "study.toml")


def scan_folder(folder, arm) -> list:
    """Leaks in every Markdown, HTML, CSV, JSON and text file of an output folder."""
    det = Detector(constants_for(arm))
    found = []
    for f in sorted(Path(folder).rglob("*")):
        if not f.is_file() or f.name in ECHOED or "cache" in f.relative_to(folder).parts:
            continue
        if f.suffix == ".csv":
            found += det.csv(f)
        elif f.suffix == ".json":
            found += det.json(f)
        elif f.suffix in (".md", ".txt"):
            found += det.text(strip_arm_text(f.read_text(encoding="utf-8"), arm), f.name)
        elif f.suffix == ".html":
            found += det.text(strip_arm_text(html_text(f.read_text(encoding="utf-8")), arm),
                              f.name)
    return found


def scan_output(text: str, arm, where: str = "stdout") -> list:
    """Leaks in a command's printed output."""
    return Detector(constants_for(arm)).text(strip_arm_text(text, arm), where)


# ------------------------------------------------------------------------------ other arms

def _with_links(arm, m1: float, m2: float):
    """``arm`` with link masses m1, m2 [kg] (centres of gravity kept, centroidal inertias
    scaled with the mass) and the controllers' identified models updated by the same first
    and second moments (what a re-identification would find)."""
    L, g = arm.links, arm.geometry
    d1, d2 = m1 - L.m1, m2 - L.m2
    IG1, IG2 = L.IG1 * m1 / L.m1, L.IG2 * m2 / L.m2
    links = L.replace(m1=m1, m2=m2, IG1=IG1, IG2=IG2)

    def model(b, second: bool):
        ch = {"m1LG1_m2L1": b.m1LG1_m2L1 + d1 * L.LG1 + d2 * g.L1, "m1dG1": b.m1dG1 + d1 * L.dG1,
              "m2LG2": b.m2LG2 + d2 * L.LG2, "m2dG2": b.m2dG2 + d2 * L.dG2}
        if second:
            ch["IO1_m2L1sq"] = (b.IO1_m2L1sq + IG1 - L.IG1 + d1 * (L.LG1 ** 2 + L.dG1 ** 2)
                                + d2 * g.L1 ** 2)
            ch["IS2"] = b.IS2 + IG2 - L.IG2 + d2 * (L.LG2 ** 2 + L.dG2 ** 2)
        return b.replace(**ch)
    return arm.replace(links=links, model=model(arm.model, True),
                       model_gravity=model(arm.model_gravity, False))


def random_arm(seed: int):
    """A plausible arm that is not the thesis arm, drawn from the valid ranges with ``seed``.

    The thesis arm with its link masses (upper arm x 0.85-1.2, forearm -0.2..+0.5 kg, the
    identified models updated), mean pressures (1.3-2.0 bar each), valve time constants
    (x 0.7-1.8 each), valve offsets (+-0.05 bar each) and a declared muscle hysteresis
    (delta 0.05-0.4) drawn; a draw whose arm cannot hold the stiffness pose is drawn again
    (from the same seed's stream).

    Parameters
    ----------
    seed : int
        Seed of the draw.

    Returns
    -------
    ArmParameters
    """
    from ppamsafety.params.arm_file import apply_arm_changes
    from ppamsafety.params.effects import Effects

    rng = np.random.default_rng(seed)
    base = thesis_arm()
    for _ in range(50):
        arm = _with_links(base, base.links.m1 * rng.uniform(0.85, 1.2),
                          base.links.m2 + rng.uniform(-0.2, 0.5))
        T = [v.time_constant * rng.uniform(0.7, 1.8) for v in arm.valves.valves]
        off = [v.v1 + rng.uniform(-0.05, 0.05) * BAR for v in arm.valves.valves]
        ch = {"arm.pneumatics.mean_pressure": [float(x) for x in rng.uniform(1.3, 2.0, 2) * BAR]}
        for k in range(4):
            ch[f"arm.valves.valve{k + 1}.time_constant"] = float(T[k])
            ch[f"arm.valves.valve{k + 1}.offset"] = float(off[k])
        arm = apply_arm_changes(arm, ch)
        arm = arm.replace(effects=Effects(hysteresis_delta=(float(rng.uniform(0.05, 0.4)),) * 4),
                          name=f"random arm (seed {seed})")
        if arm_summary(arm, n=11).pose_holdable:
            return arm
    raise RuntimeError(f"no holdable arm drawn from seed {seed}")


def user_variant():
    """The arm of a user: the shipped example (40-fibre muscles, delta = 0.299, a 1.6 kg
    forearm) at mean pressures 1.4/1.5 bar with valves 1.4 times slower."""
    from ppamsafety.params import load_arm
    from ppamsafety.params.arm_file import apply_arm_changes

    arm = load_arm(EXAMPLE)
    ch = {"arm.pneumatics.mean_pressure": [1.4 * BAR, 1.5 * BAR]}
    for k, v in enumerate(arm.valves.valves):
        ch[f"arm.valves.valve{k + 1}.time_constant"] = 1.4 * v.time_constant
    return apply_arm_changes(arm, ch).replace(name="user variant: 1.4/1.5 bar, slower valves")


#: The shipped example arm.
EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "arms" / \
    "forty_fibre_heavy_forearm.toml"
