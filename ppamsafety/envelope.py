"""Safety envelopes: the largest (or smallest) parameter value that keeps an arm safe.

For a chosen limit -- the 660 N maxilla fracture force, HIC36 = 650 or the ISO/TS 15066
transient force limit of the forehead -- :func:`safety_envelope` finds where a parameter's
safe range ends: a PSMC's lambda, the mean pressure p_m (the stiffness knob of a PPAM
joint, ``arm.pneumatics.mean_pressure``), the tool speed of one impact, or any numeric
case parameter or dotted arm parameter.  It bisects on the sweep engine
(:func:`ppamsafety.sweep.run_sweep`): each round evaluates as many points inside the
bracket as there are worker processes, so the bracket shrinks by (processes + 1) per
round, and every evaluated case is kept.

A case is safe when its worst impact over the instants it evaluates stays strictly below
the limit: with :func:`~ppamsafety.sweep_cases.safety_case` that is the worst of the four
heuristic instants (``instants="heuristic"``) or of every instant (``instants="all"``);
with :func:`~ppamsafety.sweep_cases.impact_case` (``parameter="speed"``) the one impact.

The search assumes one crossing in the range (the result is monotone in the parameter,
as HIC and F_max are in lambda, fig. 6.6); the evaluations are checked for it and
:attr:`SafetyEnvelope.monotone` says whether they agree.
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ._validation import check_int, check_range, check_str
from .params.head import HIC_SERIOUS_5PCT, MAXILLA_FRACTURE_N
from .params.iso_ts_15066 import SKULL_FOREHEAD
from .plots.sweep import plot_envelope
from .sweep import run_sweep
from .sweep_cases import case_function, check_case, check_impact_case, is_dotted


@dataclass(frozen=True)
class Limit:
    """A safety limit an envelope keeps a result below.

    Attributes
    ----------
    name : str
        How the limit is chosen (``"F_max"``, ``"HIC36"``, ``"iso_ts_15066"``).
    metric : str
        The result column it bounds.
    value : float
        The limit (strict: safe means below).
    label : str
        What it is and where it comes from.
    """

    name: str
    metric: str
    value: float
    label: str


#: The limits of :func:`safety_envelope`.
LIMITS = {
    "F_max": Limit("F_max", "F_max", MAXILLA_FRACTURE_N,
                   f"maxilla fracture {MAXILLA_FRACTURE_N:g} N (Haddadin et al. 2007a, thesis "
                   f"§6.3.3)"),
    "HIC36": Limit("HIC36", "HIC36", HIC_SERIOUS_5PCT,
                   f"HIC36 {HIC_SERIOUS_5PCT:g}: 5 % risk of AIS 3+ (thesis §6.3.3)"),
    "iso_ts_15066": Limit("iso_ts_15066", "F_max", SKULL_FOREHEAD.force_transient,
                          f"ISO/TS 15066 skull/forehead transient contact "
                          f"{SKULL_FOREHEAD.force_transient:g} N "
                          f"({SKULL_FOREHEAD.transient_factor:g} x "
                          f"{SKULL_FOREHEAD.force_quasi_static:g} N, Annex A)"),
}
#: Numeric safety_case parameters an envelope can search (besides dotted arm parameters).
NUMERIC = ("lam", "kp_bar", "ki_bar", "kd_bar", "task_kp", "task_ki", "task_kd", "stiffness",
           "duration", "covering_thickness", "covering_modulus", "covering_hysteresis")


@dataclass
class SafetyEnvelope:
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
        The safe end of the final bracket: the largest (``direction="largest"``) or
        smallest safe value found; when the whole range is safe, the bound where the result
        is nearer the limit; None when no evaluated value is safe.
    unsafe_value : float or None
        The unsafe end of the final bracket (None when the whole range is safe).
    direction : str
        ``"largest"`` (safe below the boundary), ``"smallest"`` (safe above it),
        ``"all safe"`` or ``"none safe"``.
    monotone : bool
        The evaluations are consistent with one crossing.
    evaluations : pandas.DataFrame
        Every evaluated case: ``round``, ``value``, ``status``, the results, ``safe``.
    tolerance : float
        Relative width of the final bracket asked for.
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

    @property
    def description(self) -> str:
        """One sentence: the envelope found."""
        lo, hi = self.bounds
        if self.direction == "all safe":
            return (f"{self.metric} stays below {self.limit_label} over {self.parameter} in "
                    f"[{lo:.4g}, {hi:.4g}]")
        if self.direction == "none safe":
            return (f"{self.metric} reaches {self.limit_label} everywhere in {self.parameter} "
                    f"in [{lo:.4g}, {hi:.4g}]")
        rel = "<=" if self.direction == "largest" else ">="
        return (f"safe for {self.parameter} {rel} {self.safe_value:.4g} (unsafe at "
                f"{self.unsafe_value:.4g}): {self.metric} below {self.limit_label}")

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


def safety_envelope(parameter: str, bounds, *, limit: str = "F_max", case=None, arm=None,
                    head=None, tolerance: float = 0.01, processes: int | None = None,
                    max_rounds: int = 20, progress: bool = False, cache_dir=None,
                    name: str = "envelope") -> SafetyEnvelope:
    """Find the largest (or smallest) value of a parameter that keeps a case below a limit.

    Parameters
    ----------
    parameter : str
        ``"speed"`` (tool speed of one impact, :func:`~ppamsafety.sweep_cases.impact_case`
        [m/s]), a numeric :func:`~ppamsafety.sweep_cases.safety_case` parameter
        (``"lam"`` [s], ``"ki_bar"`` ...) or a dotted one
        (``"arm.pneumatics.mean_pressure"`` [Pa], ``"effects.payload_mass"`` [kg]).
    bounds : pair of float
        The range searched, low < high (SI units of the parameter).
    limit : {"F_max", "HIC36", "iso_ts_15066"}, keyword-only
        The limit (:data:`LIMITS`).
    case : dict, optional, keyword-only
        The other parameters of every case (of ``impact_case`` for ``"speed"``, else of
        ``safety_case``; e.g. ``{"controller": "PSMC joint", "instants": "all"}``).
    arm : ArmParameters, optional, keyword-only
        The arm (default the thesis arm).
    head : HeadContactModel, optional, keyword-only
        The head (default ``"thesis-frontal"``, or the case's ``head``).
    tolerance : float, keyword-only
        Stop when the bracket is narrower than ``tolerance`` x the larger of its ends'
        magnitudes, in [1e-6, 0.5].
    processes : int, optional, keyword-only
        Points per round, each in its own worker process (default 1: plain bisection in
        this process, the fastest for cases of a second or less; every round starts its
        workers, which load the compiled kernels, so more pays off only for slow cases
        such as ``instants="all"``).
    max_rounds : int, keyword-only
        Largest number of rounds after the two bounds, in [1, 100].
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
        For bad arguments, or when a bound cannot be evaluated (the case fails there:
        the message says why; narrow the range).
    """
    kind = "impact" if parameter == "speed" else "safety"
    parameter = _check_parameter(parameter, kind)
    if limit not in LIMITS:
        raise ValueError(f"limit = {limit!r} is not one of {list(LIMITS)}")
    lim = LIMITS[limit]
    if not (isinstance(bounds, (list, tuple)) and len(bounds) == 2):
        raise ValueError(f"bounds = {bounds!r} must be a pair (low, high)")
    lo = check_range("bounds[0]", bounds[0], -1e12, 1e12)
    hi = check_range("bounds[1]", bounds[1], -1e12, 1e12)
    if not lo < hi:
        raise ValueError(f"bounds = ({lo:g}, {hi:g}): low must be smaller than high")
    tolerance = check_range("tolerance", tolerance, 1e-6, 0.5)
    max_rounds = check_int("max_rounds", max_rounds, 1, 100)
    procs = 1 if processes is None else min(check_int("processes", processes, 1, 1024),
                                                _cores())
    base = dict(case or {})
    if parameter in base:
        raise ValueError(f"case sets {parameter!r}, the parameter searched; leave it out")
    if "arm" in base or "histories" in base:
        raise ValueError("case must not set 'arm' (pass arm=...) or 'histories'")
    func = case_function(arm, head, kind=kind)
    check_bounds(parameter, (lo, hi), base, arm=arm, head=head)   # both ends, before running
    rows = []

    def evaluate(values, rnd):
        cases = [{**base, parameter: float(v)} for v in values]
        with warnings.catch_warnings():      # a failed case is reported by the envelope itself
            warnings.filterwarnings("ignore", message=r"sweep .* cases? failed",
                                    category=RuntimeWarning)
            df = run_sweep(func, cases, name=f"{name}-{parameter}-{limit}", processes=procs,
                           progress=progress, on_error="record", cache_dir=cache_dir)
        for v, (_, r) in zip(values, df.iterrows()):
            ok = r.get("status", "ok") == "ok"
            m = float(r[lim.metric]) if ok else math.nan
            rows.append({"round": rnd, "value": float(v), "status": r.get("status", "ok"),
                         "error": r.get("error", ""), lim.metric: m,
                         "safe": bool(ok and m < lim.value)})
        return [rows[-len(values) + i] for i in range(len(values))]

    ends = evaluate([lo, hi], 0)
    for r in ends:
        if r["status"] != "ok":
            raise ValueError(f"{parameter} = {r['value']:g} cannot be evaluated ({r['error']}); "
                             f"narrow bounds = ({lo:g}, {hi:g})")
    s_lo, s_hi = ends[0]["safe"], ends[1]["safe"]
    if s_lo == s_hi:
        direction = "all safe" if s_lo else "none safe"
        # all safe: the end nearest the limit (the most aggressive safe value) is the envelope
        safe = (hi if ends[1][lim.metric] >= ends[0][lim.metric] else lo) if s_lo else None
        unsafe = None
    else:
        direction = "largest" if s_lo else "smallest"
        a, b = (lo, hi) if s_lo else (hi, lo)            # a safe, b unsafe
        for rnd in range(1, max_rounds + 1):
            if abs(b - a) <= tolerance * max(abs(a), abs(b), 1e-300):
                break
            pts = [a + (b - a) * (i + 1) / (procs + 1) for i in range(procs)]
            res = evaluate(pts, rnd)
            failed = [r for r in res if r["status"] != "ok"]
            if failed:
                raise ValueError(f"{parameter} = {failed[0]['value']:g} cannot be evaluated "
                                 f"({failed[0]['error']}) inside bounds = ({lo:g}, {hi:g})")
            for r in res:                       # from the safe end towards the unsafe end
                if not r["safe"]:
                    b = r["value"]
                    break
                a = r["value"]
        safe, unsafe = a, b
    ev = pd.DataFrame(rows)
    order = ev[ev.status == "ok"].sort_values("value")["safe"].to_numpy()
    monotone = int(np.count_nonzero(order[1:] != order[:-1])) <= 1
    return SafetyEnvelope(parameter=parameter, limit=limit, metric=lim.metric,
                          limit_value=lim.value, limit_label=lim.label, bounds=(lo, hi),
                          safe_value=safe, unsafe_value=unsafe, direction=direction,
                          monotone=monotone, evaluations=ev, tolerance=tolerance)


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return 1


__all__ = ["Limit", "LIMITS", "NUMERIC", "SafetyEnvelope", "safety_envelope", "check_bounds"]
