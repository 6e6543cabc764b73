"""Safety envelopes: where a parameter's safe range ends, bracketed, with every crossing.

For a chosen limit -- a criterion of :mod:`ppamsafety.impact.verdicts` (the 660 N maxilla
fracture force ``"F_max"``, ``"HIC36"`` = 650, the ISO/TS 15066 transient force of a body
region ``"iso_ts_15066"`` or its quasi-static force ``"iso_ts_15066_qs"`` ...), or any
value of its metric (``limit_value``) -- :func:`safety_envelope` finds where a
parameter's safe range ends: a PSMC's lambda, the mean pressure p_m (the stiffness knob
of a PPAM joint, ``arm.pneumatics.mean_pressure``), the tool speed of one impact, or any
numeric case parameter or dotted arm parameter.

It never answers with a single bisection point:

1. a *scan* of ``scan`` evenly spaced values over the range (both ends included) finds
   every crossing of the limit the scan can see;
2. each crossing is *bracketed* by bisection on the sweep engine
   (:func:`ppamsafety.sweep.run_sweep`; each round evaluates as many points inside the
   bracket as there are worker processes) until the bracket is narrower than
   ``tolerance``;
3. the result reports every crossing (:attr:`SafetyEnvelope.crossings`), the *margin*
   (limit minus the result) at the safe end of the boundary and the smallest margin over
   the safe range evaluated, and flags a curve that is *flat* near the limit (it changes
   by less than :data:`FLAT_FRACTION` of the limit across the scan interval of a
   crossing: the boundary then moves far for a small change of the model) and a curve
   that is *non-monotone* (more than one crossing).

A case is safe when its worst impact over the instants it evaluates stays strictly below
the limit: with :func:`~ppamsafety.sweep_cases.safety_case` that is the worst of the four
heuristic instants (``instants="heuristic"``) or of every instant (``instants="all"``);
with :func:`~ppamsafety.sweep_cases.impact_case` (``parameter="speed"``) the one impact.
The verdict of every evaluation is the one :func:`ppamsafety.impact.verdicts.evaluate`
gives, so an envelope, a sweep and the report agree on the same case.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ._jit import available_cores
from .results import Result
from ._validation import check_int, check_range, check_str
from .impact.head import HeadContactModel, head_model
from .impact.verdicts import Criterion, criterion, criterion_names, model_kind
from .params.iso_ts_15066 import resolve_region
from .plots.sweep import plot_envelope
from .sweep import run_sweep
from .sweep_cases import case_function, check_case, check_impact_case, is_dotted

#: A crossing whose scan interval changes the result by less than this fraction of the
#: limit is reported as *flat*: the verdict hangs on a plateau near the limit.
FLAT_FRACTION = 0.02
#: Default number of scan points of :func:`safety_envelope` (ends included).
SCAN = 9


@dataclass(frozen=True)
class Limit:
    """A safety limit an envelope keeps a result below.

    Attributes
    ----------
    name : str
        How the limit is chosen (a criterion name of
        :func:`ppamsafety.impact.verdicts.criterion_names`, e.g. ``"F_max"``, ``"HIC36"``,
        ``"iso_ts_15066"``).
    metric : str
        The result column it bounds.
    value : float
        The limit (strict: safe means below).
    label : str
        What it is and where it comes from.
    criterion : Criterion or None
        The verdict criterion it is.
    """

    name: str
    metric: str
    value: float
    label: str
    criterion: Criterion | None = None


def resolve_limit(limit="F_max", limit_value=None, region=None) -> Limit:
    """The limit of an envelope: a named criterion of a body region, its value optionally
    replaced.

    Parameters
    ----------
    limit : str
        A criterion name of :func:`~ppamsafety.impact.verdicts.criterion_names` (default
        ``"F_max"``, the 660 N maxilla line).
    limit_value : float, optional
        Another value of the limit, in the unit of its metric (N for a force).
    region : optional
        The body region of the criteria (default ``"skull/forehead"``).

    Returns
    -------
    Limit
    """
    check_str("limit", limit)
    c = criterion(limit, region)
    if limit_value is not None:
        v = check_range("limit_value", limit_value, 0.0, 1e7, lo_open=True,
                        unit=c.unit or "")
        c = c.with_limit(v)
    return Limit(limit, c.metric, c.limit, c.label, c)


#: The limits of :func:`safety_envelope` for the default body region (skull/forehead).
LIMITS = {n: resolve_limit(n) for n in criterion_names()}
#: Numeric safety_case parameters an envelope can search (besides dotted arm parameters).
NUMERIC = ("lam", "kp_bar", "ki_bar", "kd_bar", "task_kp", "task_ki", "task_kd", "stiffness",
           "duration", "covering_thickness", "covering_modulus", "covering_hysteresis")


@dataclass
class SafetyEnvelope(Result):
    """Result of :func:`safety_envelope`.

    Attributes
    ----------
    parameter : str
        The searched parameter.
    limit : str
        The limit's name (:data:`LIMITS`).
    metric : str
        The result column the limit bounds.
    limit_value : float
        The limit.
    limit_label : str
        What the limit is.
    bounds : tuple of 2 float
        The searched range.
    safe_value : float or None
        The safe end of the boundary's bracket: the largest (``direction="largest"``) or
        smallest safe value of the safe range that starts at the safe end of the searched
        range; when the whole range is safe, the bound where the result is nearer the
        limit; None when no evaluated value is safe.
    unsafe_value : float or None
        The unsafe end of that bracket (None when the whole range is safe).
    direction : str
        ``"largest"`` (safe below the boundary), ``"smallest"`` (safe above it),
        ``"all safe"``, ``"none safe"`` or ``"inside"`` (neither end of the range is safe:
        safe between two crossings).
    monotone : bool
        The evaluations are consistent with one crossing.
    evaluations : pandas.DataFrame
        Every evaluated case: ``round`` (0 = the scan), ``value``, ``status``, the result,
        ``margin`` (limit - result), ``safe``.
    tolerance : float
        Relative width of the final bracket asked for.
    crossings : list of dict
        Every crossing found: ``safe_value``, ``unsafe_value`` (the bracket),
        ``result_safe``, ``result_unsafe`` (the result at both ends), ``margin`` (limit -
        result at the safe end), ``spread`` (change of the result across the scan interval
        that held the crossing) and ``flat`` (spread < :data:`FLAT_FRACTION` x limit).
    margin : float or None
        Limit - result at :attr:`safe_value` (in the limit's unit).
    min_margin : float or None
        The smallest margin over the scan's values inside the safe range reported (the
        bisection's values near the boundary excluded: their margin is small by
        construction).
    safe_ranges : list of (float, float)
        Every stretch of the searched range the evaluations show safe (ends: a bound of
        the range or the safe end of a crossing's bracket).
    head : str
        The head model the results were computed with.
    region : str
        The body region of the limit.
    """

    parameter: str
    limit: str
    metric: str
    limit_value: float
    limit_label: str
    bounds: tuple
    safe_value: float | None
    unsafe_value: float | None
    direction: str
    monotone: bool
    evaluations: pd.DataFrame = field(repr=False)
    tolerance: float = 0.01
    crossings: list = field(default_factory=list)
    margin: float | None = None
    min_margin: float | None = None
    head: str = ""
    region: str = ""
    safe_ranges: list = field(default_factory=list)

    @property
    def unit(self) -> str:
        """Unit of the limit (``"N"`` for a force, ``""`` for HIC)."""
        return "N" if self.metric.startswith("F") else ""

    @property
    def flat(self) -> bool:
        """A crossing lies on a flat stretch of the curve (see :data:`FLAT_FRACTION`)."""
        return any(c["flat"] for c in self.crossings)

    @property
    def description(self) -> str:
        """One sentence: the envelope found, the limit, the head model and the margin."""
        lo, hi = self.bounds
        u = f" {self.unit}" if self.unit else ""
        with_head = (f" with {model_kind(self.region or 'skull/forehead')} {self.head}"
                     if self.head else "")
        if self.direction == "all safe":
            return (f"{self.metric} stays below {self.limit_label} over {self.parameter} in "
                    f"[{lo:.4g}, {hi:.4g}]{with_head}; smallest margin "
                    f"{self.min_margin:.4g}{u} (at {self.parameter} = {self.safe_value:.4g})")
        if self.direction == "none safe":
            return (f"{self.metric} reaches {self.limit_label} everywhere in {self.parameter} "
                    f"in [{lo:.4g}, {hi:.4g}]{with_head}")
        if self.direction == "inside":
            where = " and ".join(f"[{a:.4g}, {b:.4g}]" for a, b in self.safe_ranges)
            return (f"safe only for {self.parameter} in {where} (both ends of [{lo:.4g}, "
                    f"{hi:.4g}] unsafe): {self.metric} below {self.limit_label}{with_head}; "
                    f"margin {self.margin:.4g}{u} at {self.safe_value:.4g}"
                    + (f", at least {self.min_margin:.4g}{u} inside"
                       if self.min_margin is not None else ""))
        rel = "<=" if self.direction == "largest" else ">="
        return (f"safe for {self.parameter} {rel} {self.safe_value:.4g} (unsafe at "
                f"{self.unsafe_value:.4g}): {self.metric} below {self.limit_label}{with_head}; "
                f"margin {self.margin:.4g}{u} at the boundary"
                + (f", at least {self.min_margin:.4g}{u} at the scan values of the safe range"
                   if self.min_margin is not None else ""))

    def lines(self) -> list:
        """The envelope as text lines (the terminal's): the answer, every crossing, warnings."""
        u = f" {self.unit}" if self.unit else ""
        out = [self.description]
        if len(self.crossings) > 1:
            out.append(f"the limit is crossed {len(self.crossings)} times (not monotone): safe "
                       f"for {self.parameter} in " + " and ".join(
                           f"[{a:.4g}, {b:.4g}]" for a, b in self.safe_ranges))
        if self.min_margin is not None and self.min_margin < FLAT_FRACTION * self.limit_value:
            out.append(f"NARROW: the smallest margin at the scan values of the safe range is "
                       f"{self.min_margin:.3g}{u}, {100 * self.min_margin / self.limit_value:.2g} % "
                       f"of the limit: the verdict hangs on less than {FLAT_FRACTION:.0%} of "
                       f"the limit")
        for c in self.crossings:
            out.append(f"  crossing in {self.parameter} between {c['safe_value']:.6g} (safe, "
                       f"{self.metric} {c['result_safe']:.5g}{u}, margin {c['margin']:+.3g}{u}) "
                       f"and {c['unsafe_value']:.6g} (unsafe, {c['result_unsafe']:.5g}{u})"
                       + (f"; FLAT: {self.metric} changes by only {c['spread']:.3g}{u} across "
                          f"the scan interval ({100 * c['spread'] / self.limit_value:.2g} % "
                          f"of the limit), so a small change of the model moves this "
                          f"boundary far" if c["flat"] else ""))
        return out

    def to_pandas(self) -> pd.DataFrame:
        """Every evaluated case, sorted by the parameter value."""
        return self.evaluations.sort_values("value").reset_index(drop=True)

    def plot(self, **kwargs):
        """The limited result against the parameter, the limit and the boundary.

        Parameters
        ----------
        **kwargs
            Passed to :func:`ppamsafety.plots.sweep.plot_envelope`.
        """
        return plot_envelope(self, **kwargs)


def _check_parameter(parameter: str, kind: str) -> str:
    check_str("parameter", parameter)
    if kind == "impact":
        return parameter
    if parameter in NUMERIC or is_dotted(parameter):
        return parameter
    raise ValueError(f"parameter = {parameter!r} cannot be searched: give 'speed' (the tool "
                     f"speed of one impact), one of {list(NUMERIC)} or a dotted arm parameter "
                     f"such as 'arm.pneumatics.mean_pressure'")


def check_bounds(parameter: str, bounds, case=None, *, arm=None, head=None) -> None:
    """Check the cases at both ends of an envelope's range, before anything runs.

    Parameters
    ----------
    parameter : str
        The parameter searched (:func:`safety_envelope`).
    bounds : pair of float
        Its range (low, high).
    case : dict, optional
        The other parameters of every case.
    arm : ArmParameters, optional, keyword-only
        The arm.
    head : str or HeadContactModel, optional, keyword-only
        The head model of the cases (``speed`` only: the impact's head).

    Raises
    ------
    ValueError
        Naming the bound, the parameter and why its case is not allowed.
    """
    base = dict(case or {})
    for i, b in enumerate(bounds):
        try:
            if parameter == "speed":
                kw = dict(base)
                if head is not None:
                    kw.setdefault("head", head)
                check_impact_case(float(b), arm=arm, **kw)
            else:
                check_case(**base, **{parameter: float(b)}, arm=arm)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"bounds[{i}] = {b:g}: {parameter} = {b:g} is not allowed "
                             f"({exc}); narrow bounds = ({bounds[0]:g}, {bounds[1]:g})") \
                from None


def safety_envelope(parameter: str, bounds, *, limit: str = "F_max", limit_value=None,
                    region=None, case=None, arm=None, head=None, tolerance: float = 0.01,
                    scan: int = SCAN, processes: int | None = None, max_rounds: int = 20,
                    progress: bool = False, cache_dir=None,
                    name: str = "envelope") -> SafetyEnvelope:
    """Find where a parameter's safe range ends: every crossing bracketed, with the margin.

    Parameters
    ----------
    parameter : str
        ``"speed"`` (tool speed of one impact, :func:`~ppamsafety.sweep_cases.impact_case`
        [m/s]), a numeric :func:`~ppamsafety.sweep_cases.safety_case` parameter
        (``"lam"`` [s], ``"ki_bar"`` ...) or a dotted one
        (``"arm.pneumatics.mean_pressure"`` [Pa], ``"effects.payload_mass"`` [kg]).
    bounds : pair of float
        The range searched, low < high (SI units of the parameter).
    limit : str, keyword-only
        A criterion of the body region (:func:`~ppamsafety.impact.verdicts.criterion_names`:
        ``"F_max"`` (660 N maxilla), ``"HIC36"``, ``"iso_ts_15066"``, ``"iso_ts_15066_qs"``
        ...).
    limit_value : float, optional, keyword-only
        Another value of the limit in its metric's unit (N for a force): the limit chosen.
    region : optional, keyword-only
        The body region of the criteria (a name, an Annex A number, a region file or a
        BodyRegion; default ``"skull/forehead"``).
    case : dict, optional, keyword-only
        The other parameters of every case (of ``impact_case`` for ``"speed"``, else of
        ``safety_case``; e.g. ``{"controller": "PSMC joint", "instants": "all"}``).
    arm : ArmParameters, optional, keyword-only
        The arm (default the thesis arm).
    head : HeadContactModel, optional, keyword-only
        The head (default ``"thesis-frontal"``, or the case's ``head``).
    tolerance : float, keyword-only
        Stop when a bracket is narrower than ``tolerance`` x the larger of its ends'
        magnitudes, in [1e-6, 0.5].
    scan : int, keyword-only
        Evenly spaced values evaluated first, ends included, in [2, 1000] (default 9): every
        crossing the scan sees is bracketed; 2 evaluates only the ends (one crossing
        assumed).
    processes : int, optional, keyword-only
        Points per bisection round, each in its own worker process (default 1: plain
        bisection in this process, the fastest for cases of a second or less; every round
        starts its workers, which load the compiled kernels, so more pays off only for slow
        cases such as ``instants="all"``).
    max_rounds : int, keyword-only
        Largest number of bisection rounds per crossing, in [1, 100].
    progress : bool, keyword-only
        Progress bars of the sweep rounds.
    cache_dir : path-like, optional, keyword-only
        Resume folder of the sweep engine (every evaluated case is stored).
    name : str, keyword-only
        Sweep name (part of the cache key).

    Returns
    -------
    SafetyEnvelope

    Raises
    ------
    ValueError
        For bad arguments, or when a value cannot be evaluated (the case fails there: the
        message says why; narrow the range).
    """
    kind = "impact" if parameter == "speed" else "safety"
    parameter = _check_parameter(parameter, kind)
    try:
        reg = resolve_region(region)
        lim = resolve_limit(limit, limit_value, reg)
    except ValueError as exc:
        raise ValueError(str(exc)) from None
    lo, hi = _bounds(bounds)
    tolerance = check_range("tolerance", tolerance, 1e-6, 0.5)
    scan = check_int("scan", scan, 2, 1000)
    max_rounds = check_int("max_rounds", max_rounds, 1, 100)
    procs = 1 if processes is None else min(check_int("processes", processes, 1, 1024),
                                            available_cores())
    base = dict(case or {})
    if parameter in base:
        raise ValueError(f"case sets {parameter!r}, the parameter searched; leave it out")
    if "arm" in base or "histories" in base:
        raise ValueError("case must not set 'arm' (pass arm=...) or 'histories'")
    if region is not None:              # the region is struck on its own body, and judged
        if base.get("region") is not None and base["region"] != region:
            raise ValueError(f"case region = {base['region']!r} and region = {region!r}: the "
                             f"envelope's region is the one struck and judged; give one")
        base["region"] = region
    func = case_function(arm, head, kind=kind)
    check_bounds(parameter, (lo, hi), base, arm=arm, head=head)   # both ends, before running
    hname = (head.name if isinstance(head, HeadContactModel) else
             base["head"].name if isinstance(base.get("head"), HeadContactModel) else
             str(base.get("head", head_model().name)))
    bodies = []                         # the body model the cases were simulated with

    def evaluate(values):
        cases = [{**base, parameter: float(v)} for v in values]
        with warnings.catch_warnings():      # a failed case is reported by the envelope itself
            warnings.filterwarnings("ignore", message=r"sweep .* cases? failed",
                                    category=RuntimeWarning)
            df = run_sweep(func, cases, name=f"{name}-{parameter}-{lim.metric}",
                           processes=procs, progress=progress, on_error="record",
                           cache_dir=cache_dir).table
        bodies.extend(str(b) for b in df.get("body_model", pd.Series(dtype=object)).dropna())
        return [(r.get("status", "ok"), r.get("error", ""),
                 float(r[lim.metric]) if r.get("status", "ok") == "ok" else math.nan)
                for _, r in df.iterrows()]

    found = _search(evaluate, lo, hi, lim.value, lim.metric, parameter=parameter,
                    tolerance=tolerance, scan=scan, max_rounds=max_rounds, points=procs)
    if bodies:
        hname = bodies[0]
    return SafetyEnvelope(parameter=parameter, limit=limit, metric=lim.metric,
                          limit_value=lim.value, limit_label=lim.label, bounds=(lo, hi),
                          tolerance=tolerance, head=hname, region=reg.name, **found)


def search_envelope(func, bounds, *, limit_value: float, metric: str = "F_max",
                    parameter: str = "x", limit_label: str = "", tolerance: float = 0.01,
                    scan: int = SCAN, max_rounds: int = 20) -> SafetyEnvelope:
    """The envelope search of :func:`safety_envelope` on any function of one parameter.

    Parameters
    ----------
    func : callable
        ``func(value) -> result`` (a finite number in the limit's unit).
    bounds : pair of float
        The range searched, low < high.
    limit_value : float, keyword-only
        The limit (strict: a result below it is safe), positive.
    metric : str, keyword-only
        Name of the result.
    parameter : str, keyword-only
        Name of the parameter.
    limit_label : str, keyword-only
        What the limit is.
    tolerance, scan, max_rounds : keyword-only
        As :func:`safety_envelope`.

    Returns
    -------
    SafetyEnvelope
    """
    if not callable(func):
        raise TypeError(f"func must be callable, got {type(func).__name__}")
    lo, hi = _bounds(bounds)
    lv = check_range("limit_value", limit_value, 0.0, 1e12, lo_open=True)
    tolerance = check_range("tolerance", tolerance, 1e-6, 0.5)
    scan = check_int("scan", scan, 2, 1000)
    max_rounds = check_int("max_rounds", max_rounds, 1, 100)

    def evaluate(values):
        out = []
        for v in values:
            try:
                m = float(func(v))
            except (TypeError, ValueError) as exc:
                out.append(("failed", f"{type(exc).__name__}: {exc}", math.nan))
                continue
            out.append(("ok", "", m) if math.isfinite(m) else
                       ("failed", f"ValueError: result {m}", math.nan))
        return out

    found = _search(evaluate, lo, hi, lv, metric, parameter=parameter, tolerance=tolerance,
                    scan=scan, max_rounds=max_rounds, points=1)
    return SafetyEnvelope(parameter=parameter, limit="", metric=metric, limit_value=lv,
                          limit_label=limit_label or f"{lv:g}", bounds=(lo, hi),
                          tolerance=tolerance, **found)


def _search(evaluate, lo, hi, limit_value, metric, *, parameter, tolerance, scan, max_rounds,
            points) -> dict:
    """Scan, bracket every crossing, and the margins (the fields of a SafetyEnvelope).

    ``evaluate(values) -> [(status, error, result), ...]``.
    """
    rows = []

    def run(values, rnd):
        new = []
        for v, (status, error, m) in zip(values, evaluate(values)):
            new.append({"round": rnd, "value": float(v), "status": status, "error": error,
                        metric: m, "margin": limit_value - m,
                        "safe": bool(status == "ok" and m < limit_value)})
        rows.extend(new)
        return new

    pts = [lo + (hi - lo) * i / (scan - 1) for i in range(scan)]
    pts[-1] = hi
    res = run(pts, 0)
    for r in res:
        if r["status"] != "ok":
            raise ValueError(f"{parameter} = {r['value']:g} cannot be evaluated ({r['error']}); "
                             f"narrow bounds = ({lo:g}, {hi:g})")
    crossings = []
    for i in range(scan - 1):
        ra, rb = res[i], res[i + 1]
        if ra["safe"] == rb["safe"]:
            continue
        a, b = (ra, rb) if ra["safe"] else (rb, ra)          # a safe, b unsafe
        spread = abs(ra[metric] - rb[metric])
        for rnd in range(1, max_rounds + 1):
            if abs(b["value"] - a["value"]) <= tolerance * max(abs(a["value"]),
                                                                abs(b["value"]), 1e-300):
                break
            inner = [a["value"] + (b["value"] - a["value"]) * (k + 1) / (points + 1)
                     for k in range(points)]
            got = run(inner, rnd)
            failed = [r for r in got if r["status"] != "ok"]
            if failed:
                raise ValueError(f"{parameter} = {failed[0]['value']:g} cannot be evaluated "
                                 f"({failed[0]['error']}) inside bounds = ({lo:g}, {hi:g})")
            for r in got:                       # from the safe end towards the unsafe end
                if not r["safe"]:
                    b = r
                    break
                a = r
        crossings.append({"safe_value": a["value"], "unsafe_value": b["value"],
                          "result_safe": a[metric], "result_unsafe": b[metric],
                          "margin": limit_value - a[metric], "spread": spread,
                          "flat": bool(spread < FLAT_FRACTION * limit_value)})
    s_lo, s_hi = res[0]["safe"], res[-1]["safe"]
    ev = pd.DataFrame(rows)
    ok = ev[ev.status == "ok"].sort_values("value")
    order = ok["safe"].to_numpy()
    monotone = int(np.count_nonzero(order[1:] != order[:-1])) <= 1
    if not crossings:
        direction = "all safe" if s_lo else "none safe"
        # all safe: the end nearest the limit (the most aggressive safe value) is the envelope
        safe = (hi if res[-1][metric] >= res[0][metric] else lo) if s_lo else None
        unsafe = None
        margin = None if safe is None else limit_value - max(res[0][metric], res[-1][metric])
        min_margin = float(ok[ok["round"] == 0]["margin"].min()) if s_lo else None
    else:
        # the safe range that starts at a safe end of the searched range; if neither end is
        # safe, the first safe stretch from the low end (between two crossings)
        if s_lo:
            c, direction = crossings[0], "largest"
            inside = ok[ok.value <= c["safe_value"]]
        elif s_hi:
            c, direction = crossings[-1], "smallest"
            inside = ok[ok.value >= c["safe_value"]]
        else:
            c, direction = crossings[0], "inside"
            end = crossings[1]["safe_value"] if len(crossings) > 1 else c["safe_value"]
            inside = ok[(ok.value >= c["safe_value"]) & (ok.value <= end)]
        safe, unsafe, margin = c["safe_value"], c["unsafe_value"], c["margin"]
        inside = inside[inside.safe & (inside["round"] == 0)]       # the scan's values
        min_margin = float(inside["margin"].min()) if len(inside) else None
    # the safe ranges the evaluations show: from a safe end or a crossing's safe end to the
    # next crossing's safe end or a safe end of the range
    marks = sorted([(c["safe_value"], c["unsafe_value"]) for c in crossings])
    ranges, start = [], (lo if s_lo else None)
    for sv, uv in marks:
        if sv < uv:                               # safe below this crossing: a range ends
            ranges.append((lo if start is None else start, sv))
            start = None
        else:                                     # safe above it: a range starts
            start = sv
    if start is not None or (s_hi and not marks):
        ranges.append((lo if start is None else start, hi))
    if not ranges and s_lo:
        ranges = [(lo, hi)]
    return {"safe_value": safe, "unsafe_value": unsafe, "direction": direction,
            "safe_ranges": ranges,
            "monotone": monotone, "evaluations": ev, "crossings": crossings, "margin": margin,
            "min_margin": min_margin}


def _bounds(bounds) -> tuple:
    """The checked range (low, high) of a search."""
    if not (isinstance(bounds, (list, tuple)) and len(bounds) == 2):
        raise ValueError(f"bounds = {bounds!r} must be a pair (low, high)")
    lo = check_range("bounds[0]", bounds[0], -1e12, 1e12)
    hi = check_range("bounds[1]", bounds[1], -1e12, 1e12)
    if not lo < hi:
        raise ValueError(f"bounds = ({lo:g}, {hi:g}): low must be smaller than high")
    return lo, hi


__all__ = ["Limit", "LIMITS", "NUMERIC", "SCAN", "FLAT_FRACTION", "SafetyEnvelope",
           "safety_envelope", "search_envelope", "check_bounds", "resolve_limit"]
