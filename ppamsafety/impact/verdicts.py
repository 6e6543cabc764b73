"""One safety verdict, everywhere: named criteria per body region, evaluated one way.

A *verdict* answers one question: for a body region, a contact point of the arm and a
criterion, what is the value, the limit, the margin, pass or fail, and where do the limit
and the value come from.  Every command uses this module -- ``ppamsafety impact``, the
sweeps (:func:`ppamsafety.sweep_cases.add_verdicts`), the safety envelopes
(:mod:`ppamsafety.envelope`) and the report sections -- so the same question gets the same
answer everywhere, with the head model named.

Criteria (:class:`Criterion`, built by :func:`criteria_for` from a
:class:`~ppamsafety.params.iso_ts_15066.BodyRegion`):

* ``iso_ts_15066`` -- the ISO/TS 15066 transient contact force of the region (Annex A:
  2 x F_qs; for the skull and face the TS gives no transient value, see
  :mod:`ppamsafety.params.iso_ts_15066`);
* ``iso_ts_15066_qs`` -- the quasi-static force (for a head region: the TS reading, since
  the TS allows no transient contact with the head);
* ``iso_ts_15066_p`` and ``iso_ts_15066_p_qs`` -- the same two readings for the peak mean
  contact pressure ``p_max`` (Table A.2: the location's quasi-static pressure, and footnote
  c: 2 x for transient contact), judged where the contact geometry gives a pressure (a
  contact point with a radius or an area: :func:`ppamsafety.impact.anywhere.simulate_contacts`);
* ``pain_<study>_p<percentile>`` -- measured pain-onset forces and pressures of the location
  (region files, e.g. Behrens et al. 2022);
* for a head region only: ``maxilla`` (660 N, the thesis's line), ``mandible`` (1.78 kN),
  ``frontal_bone`` (about 4 kN) fracture forces and ``HIC36`` (650) -- head criteria, never
  applied to another region;

each with its source and whether it is confirmed.  The HIC is also turned into the
probability of AIS >= 2, 3, 4 (:func:`ais_risk`, the NHTSA lognormal curves), shown beside
the verdicts, never as a pass/fail line.

**The body struck.** A region is struck on its own body (:func:`region_head`): a head
region (skull, temple, face) on the head model given, any other region on its Annex A body
model (:func:`annex_a_head`: its effective mass and spring constant, Table A.3).  A head model
is a model of the head: given for a region that is not a head region it is refused, naming
both.

The head model decides the force: the thesis head (``thesis-frontal``, a Hunt-Crossley
contact fitted to Table 6.1) and the Annex A body model of the region (a linear spring K
with the region's effective mass m_H, :func:`annex_a_head`) can give two answers to one
question.  :func:`impact_verdicts` gives both side by side and says why they differ.

Margins: ``margin = limit - value`` (in the limit's unit) and ``margin_pct = 100 (limit -
value) / limit``; a case *passes* a criterion when its value is strictly below the limit.
The *governing* criterion is the pass/fail criterion with the smallest ``margin_pct``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..plots.impact import plot_verdicts
from ..results import Result
from .._validation import check_str, did_you_mean
from ..params.injury import AIS_RISK, AIS_SOURCE, FRACTURE_FORCES, HIC36_LIMIT
from ..params.iso_ts_15066 import SKULL_FOREHEAD, BodyRegion, resolve_region
from .head import HeadContactModel, head_model, resolve_head
from .model import simulate_impacts

#: What a criterion can bound: the result column -> its unit (SI).
METRICS = {"F_max": "N", "HIC36": "", "HIC15": "", "p_max": "Pa"}
#: How a verdict line shows a unit to a reader: SI unit -> (unit shown, SI per shown unit).
#: Pressures in N/cm^2, the unit of ISO/TS 15066 Table A.2.
SHOWN_UNITS = {"Pa": ("N/cm^2", 1.0e4)}
#: Columns of a verdict table (:meth:`Verdicts.to_pandas`).
VERDICT_COLUMNS = ("region", "contact_point", "criterion", "metric", "value", "limit", "unit",
                   "margin", "margin_pct", "passed", "kind", "head_model", "label", "source",
                   "confirmed")
#: The contact point of the arm the toolkit evaluates today.
TOOL_POINT = "tool point"


@dataclass(frozen=True)
class Criterion:
    """One named limit on one result of an impact.

    Attributes
    ----------
    name : str
        Short name (``"iso_ts_15066"``, ``"maxilla"``, ``"HIC36"`` ...).
    metric : str
        The result it bounds (:data:`METRICS`: ``"F_max"`` [N], ``"HIC36"``, ``"HIC15"``).
    limit : float
        The limit (strict: a value below it passes).
    kind : str
        ``"pain onset"`` (ISO/TS 15066, measured thresholds), ``"fracture"``, ``"injury
        risk"``.
    label : str
        What it is, with its value.
    source : str
        Where the limit comes from.
    confirmed : bool
        A public source we read prints the limit (module :mod:`ppamsafety.params.iso_ts_15066`).
    region : str
        The body region (location) name it belongs to.
    """

    name: str
    metric: str
    limit: float
    kind: str
    label: str
    source: str
    confirmed: bool
    region: str = ""

    def __post_init__(self):
        check_str("Criterion.name", self.name, allow_empty=False)
        if self.metric not in METRICS:
            raise ValueError(f"Criterion.metric = {self.metric!r}: must be one of "
                             f"{list(METRICS)}")
        if not (isinstance(self.limit, (int, float)) and not isinstance(self.limit, bool)
                and math.isfinite(self.limit) and self.limit > 0):
            raise ValueError(f"Criterion.limit = {self.limit!r}: must be a positive finite "
                             f"number [{METRICS[self.metric] or '-'}]")

    @property
    def unit(self) -> str:
        """Unit of the limit (``"N"``, or ``""`` for HIC)."""
        return METRICS[self.metric]

    def with_limit(self, value: float, *, source: str = "chosen by the user") -> "Criterion":
        """The same criterion with another limit value (e.g. an envelope's own limit).

        Parameters
        ----------
        value : float
            The new limit [unit of the metric], positive.
        source : str
            Where it comes from.
        """
        unit = f" {self.unit}" if self.unit else ""
        return Criterion(self.name, self.metric, float(value), self.kind,
                         f"{float(value):g}{unit} (chosen, in place of {self.label})", source,
                         False, self.region)


def criteria_for(region=None, *, contact: str = "transient") -> tuple:
    """The criteria of one body region (location), in the order they are reported.

    Parameters
    ----------
    region : BodyRegion, str, int or path-like, optional
        The region (:func:`~ppamsafety.params.iso_ts_15066.resolve_region`; default
        ``"skull/forehead"``, where the thesis's head is hit).
    contact : {"transient", "quasi-static"}
        Free impact (the toolkit's impacts) or clamping.

    Returns
    -------
    tuple of Criterion
    """
    r = resolve_region(region)
    if contact not in ("transient", "quasi-static"):
        raise ValueError(f"contact = {contact!r}: must be 'transient' or 'quasi-static'")
    out = []
    for metric, qs, tr, fac_name, what in (
            ("F_max", "force_quasi_static", "force_transient", "transient_factor", "force"),
            ("p_max", "pressure_quasi_static", "pressure_transient",
             "pressure_transient_factor", "pressure")):
        suffix, tag = ("", "") if metric == "F_max" else ("_p", " pressure")
        unit, per = SHOWN_UNITS.get(METRICS[metric], (METRICS[metric], 1.0))
        v_qs, v_tr = getattr(r, qs), getattr(r, tr)
        ok = r.confirmed(qs)
        if contact == "transient":
            fac = getattr(r, fac_name)
            note = "" if r.transient_in_ts else "; not in the TS for this region"
            out.append(Criterion(
                f"iso_ts_15066{suffix}", metric, v_tr, "pain onset",
                f"ISO/TS 15066 {r.name} transient contact{tag} {v_tr / per:g} {unit} "
                f"({fac:g} x {v_qs / per:g} {unit}{note})",
                f"{r.source_of(qs)}; multiplier: {r.source_of(fac_name)}",
                ok and r.confirmed(fac_name), r.name))
        if contact == "quasi-static" or not r.transient_in_ts:
            reading = ("quasi-static contact" if contact == "quasi-static" or r.transient_in_ts
                       else f"quasi-static {what}, the TS reading for a head region")
            out.append(Criterion(
                f"iso_ts_15066{suffix}_qs", metric, v_qs, "pain onset",
                f"ISO/TS 15066 {r.name} {reading} {v_qs / per:g} {unit}"
                + ("" if metric == "F_max" or reading.startswith("quasi-static " + what)
                   else f" ({what})"),
                r.source_of(qs), ok, r.name))
    for p in r.pain:
        if p.contact != contact:
            continue
        metric = "F_max" if p.quantity == "force" else "p_max"
        unit, per = SHOWN_UNITS.get(p.unit, (p.unit, 1.0))
        for pct, v in p.percentiles:
            out.append(Criterion(
                f"pain_{p.study}{'' if metric == 'F_max' else '_pressure'}_p{pct:g}", metric,
                v, "pain onset",
                f"pain onset {p.study} {pct:g}th percentile {v / per:g} {unit} ({p.contact})",
                p.source, p.confirmed, r.name))
    if r.head and contact == "transient":
        for key in ("maxilla", "mandible", "frontal bone"):
            t = FRACTURE_FORCES[key]
            out.append(Criterion(key.replace(" ", "_"), "F_max", t.value, "fracture", t.label,
                                 t.source, t.confirmed, r.name))
        out.append(Criterion("HIC36", "HIC36", HIC36_LIMIT.value, "injury risk",
                             HIC36_LIMIT.label, HIC36_LIMIT.source, HIC36_LIMIT.confirmed,
                             r.name))
    return tuple(out)


#: Names an envelope or a study file may give a limit by, besides the criteria's own
#: names: the thesis's ``"F_max"`` (the maxilla line).
ALIASES = {"F_max": "maxilla"}


def criterion(name: str, region=None) -> Criterion:
    """One criterion of a region by name (:func:`criteria_for`, :data:`ALIASES`).

    Parameters
    ----------
    name : str
        ``"iso_ts_15066"``, ``"iso_ts_15066_qs"``, ``"maxilla"`` (alias ``"F_max"``),
        ``"mandible"``, ``"frontal_bone"``, ``"HIC36"`` or a pain criterion of the region.
    region : optional
        The body region (default ``"skull/forehead"``).

    Returns
    -------
    Criterion
    """
    check_str("name", name)
    crit = {c.name: c for c in criteria_for(region)}
    if region is None or resolve_region(region).head:
        crit.update({c.name: c for c in criteria_for(region, contact="quasi-static")
                     if c.name not in crit})
    key = ALIASES.get(name, name)
    if key not in crit:
        names = [*crit, *(a for a, k in ALIASES.items() if k in crit)]
        raise ValueError(f"limit = {name!r} is not a criterion of the body region "
                         f"{resolve_region(region).name!r}{did_you_mean(name, names)}; choose "
                         f"from {names}")
    return crit[key]


def criterion_names(region=None) -> list:
    """Names :func:`criterion` accepts for a region (aliases included).

    Parameters
    ----------
    region : optional
        The body region (default ``"skull/forehead"``).
    """
    names = [c.name for c in criteria_for(region)]
    names += [c.name for c in criteria_for(region, contact="quasi-static") if c.name not in names]
    return names + [a for a, k in ALIASES.items() if k in names]


@dataclass
class Verdicts(Result):
    """Verdicts of one impact (or one case) against a set of criteria.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per (head model, criterion): :data:`VERDICT_COLUMNS`.
    risk : pandas.DataFrame
        P(AIS >= n) from the HIC per head model (:func:`ais_risk_table`).
    reason : str
        Why two head models give two answers ("" when they agree or one head is used).
    """

    table: pd.DataFrame
    risk: pd.DataFrame = field(default_factory=pd.DataFrame)
    reason: str = ""

    def to_pandas(self) -> pd.DataFrame:
        """The verdict table."""
        return self.table.copy()

    @property
    def passed(self) -> bool:
        """Every criterion passes (with every head model)."""
        return bool(self.table["passed"].all())

    def governing(self, head: str | None = None) -> pd.Series:
        """The row of the smallest relative margin of one head model.

        Parameters
        ----------
        head : str, optional
            The head model's name (default the first of the table).
        """
        t = self.table
        h = t["head_model"].iloc[0] if head is None else head
        sub = t[t["head_model"] == h]
        return sub.loc[sub["margin_pct"].idxmin()]

    def lines(self) -> list:
        """The verdicts as aligned text lines (the terminal's)."""
        return verdict_lines(self.table, self.risk, self.reason)

    def plot(self, *, title: str = ""):
        """Every verdict as value / limit [%], pass or fail; a matplotlib Figure.

        Parameters
        ----------
        title : str, keyword-only
            Axes title (default the region and contact point).
        """
        return plot_verdicts(self.table, title=title)


def evaluate(values, criteria, *, head: str = "", contact_point: str = TOOL_POINT,
             region: str = "") -> pd.DataFrame:
    """Verdict rows of one result against criteria.

    Parameters
    ----------
    values : mapping
        The results by metric name (``{"F_max": 250.7, "HIC36": 0.13}``); a missing
        metric leaves its criteria out.
    criteria : sequence of Criterion
        The criteria.
    head : str
        Name of the head model the values were computed with.
    contact_point : str
        The arm's contact point.
    region : str
        The region name (default: each criterion's).

    Returns
    -------
    pandas.DataFrame
        :data:`VERDICT_COLUMNS`, one row per criterion.
    """
    return pd.DataFrame(verdict_rows(values, criteria, head=head, contact_point=contact_point,
                                     region=region), columns=list(VERDICT_COLUMNS))


def verdict_rows(values, criteria, *, head: str = "", contact_point: str = TOOL_POINT,
                 region: str = "") -> list:
    """The rows of :func:`evaluate` as dicts (:data:`VERDICT_COLUMNS`), without the table.

    For a caller that judges thousands of impacts and keeps only the governing row of each
    (:func:`~ppamsafety.impact.summary.region_point_verdicts`): building a table per impact
    costs more than the verdicts.

    Parameters
    ----------
    values : mapping
        The results by metric name (``{"F_max": 250.7, "HIC36": 0.13}``); a missing
        metric leaves its criteria out.
    criteria : sequence of Criterion
        The criteria.
    head : str
        Name of the head model the values were computed with.
    contact_point : str
        The arm's contact point.
    region : str
        The region name (default: each criterion's).

    Returns
    -------
    list of dict
        One per criterion whose metric is in ``values``, in the order of ``criteria``.
    """
    rows = []
    for c in criteria:
        if c.metric not in values:
            continue
        v = float(values[c.metric])
        if not math.isfinite(v):
            raise ValueError(f"{c.metric} = {v}: a verdict needs a finite value")
        rows.append({"region": region or c.region, "contact_point": contact_point,
                     "criterion": c.name, "metric": c.metric, "value": v, "limit": c.limit,
                     "unit": c.unit, "margin": c.limit - v,
                     "margin_pct": 100.0 * (c.limit - v) / c.limit, "passed": bool(v < c.limit),
                     "kind": c.kind, "head_model": head, "label": c.label, "source": c.source,
                     "confirmed": c.confirmed})
    return rows


def ais_risk(hic, level: int):
    """Probability of an injury of AIS >= ``level`` from an HIC (NHTSA lognormal curve).

    P = Phi((ln HIC - mu) / sigma) with the coefficients of
    :data:`ppamsafety.params.injury.AIS_RISK` (source :data:`~ppamsafety.params.injury.AIS_SOURCE`).

    Parameters
    ----------
    hic : float or array_like
        HIC, >= 0 (0 gives probability 0).
    level : {2, 3, 4}
        The AIS level.

    Returns
    -------
    float or numpy.ndarray
        Probability in [0, 1].
    """
    if level not in AIS_RISK:
        raise ValueError(f"level = {level!r}: the NHTSA curves exist for AIS >= {list(AIS_RISK)}")
    h = np.asarray(hic, dtype=float)
    if not np.all(np.isfinite(h)) or np.any(h < 0):
        raise ValueError(f"hic = {hic!r}: must be finite and non-negative")
    mu, sigma = AIS_RISK[level]
    with np.errstate(divide="ignore"):
        z = (np.log(h) - mu) / sigma
    p = np.array([0.5 * math.erfc(-x / math.sqrt(2.0)) for x in z.ravel()]).reshape(z.shape)
    return float(p) if p.ndim == 0 else p


def ais_risk_table(hic: float, *, head: str = "", hic_name: str = "HIC36") -> pd.DataFrame:
    """P(AIS >= 2, 3, 4) of one HIC, with the source (one row per level).

    Parameters
    ----------
    hic : float
        The HIC value.
    head : str
        Head model name (a column).
    hic_name : str
        Which HIC it is (``"HIC36"`` or ``"HIC15"``; the curves were fitted with HIC15 and
        HIC36, see :mod:`ppamsafety.params.injury`).
    """
    return pd.DataFrame([{"head_model": head, "HIC": hic_name, "HIC_value": float(hic),
                          "level": f"AIS {lv}+", "probability": ais_risk(hic, lv),
                          "source": AIS_SOURCE} for lv in sorted(AIS_RISK)])


def annex_a_head(region=None) -> HeadContactModel:
    """The ISO/TS 15066 Annex A body model of a region as a contact model.

    A free body of the region's effective mass m_H behind a linear undamped spring of its
    effective spring constant K (Table A.3): the model under the Annex's transient limits
    and its speed formula v = F / sqrt(mu K).

    Parameters
    ----------
    region : optional
        The body region (default ``"skull/forehead"``).

    Returns
    -------
    HeadContactModel
        Named ``iso15066-<region>-<m_H>kg`` (``iso15066-skull-4.4kg`` for the forehead);
        radius 0.1 m, or more for a soft region so that a 5 m/s tool stops before its
        centre.
    """
    r = resolve_region(region)
    base = head_model("iso15066-forehead")
    short = r.name.split("/")[0].replace(" ", "-")
    d5 = 5.0 * math.sqrt(r.effective_mass / r.spring_constant)   # penetration at 5 m/s
    radius = min(1.0, max(base.radius, 1.25 * d5))
    return base.replace(
        name=f"iso15066-{short}-{r.effective_mass:g}kg", mass=r.effective_mass,
        stiffness=r.spring_constant, radius=radius,
        source=f"{r.source_of('spring_constant')}: K = {r.spring_constant / 1e3:g} N/mm, m_H = "
               f"{r.effective_mass:g} kg, linear undamped",
        checks=(("iso_ts_15066", True, f"is the Annex A body model of {r.name}"),
                *base.checks[1:]))


def check_head_for_region(region, head) -> None:
    """Refuse a head model for a body region that is not part of the head.

    A head model (``thesis-frontal``, the validated head, a head file) is a model of the head:
    its mass and contact law are the head's.  Striking the chest with it gives the head's
    force, judged on the chest's limits.

    Parameters
    ----------
    region : BodyRegion, str, int or path-like
        The body region (:func:`~ppamsafety.params.iso_ts_15066.resolve_region`).
    head : HeadContactModel, BodyContact, str or None
        The head model chosen (None: none chosen).

    Raises
    ------
    ValueError
        Naming the head model and the region, when the region is not a head region.
    """
    r = resolve_region(region)
    if head is None or r.head:
        return
    name = getattr(head, "name", head)
    raise ValueError(f"head model {name!r} with body region {r.name!r}: a head model is a model "
                     f"of the head, and {r.name!r} is not a head region; {r.name!r} is struck "
                     f"as its ISO/TS 15066 Annex A body model (effective mass "
                     f"{r.effective_mass:g} kg, spring constant {r.spring_constant / 1e3:g} "
                     f"N/mm, Table A.3): leave out the head model, or choose a head region "
                     f"(skull/forehead, skull/temple, face)")


def region_head(region=None, head=None) -> HeadContactModel:
    """The body a region is struck on at the tool point (the thesis' impact engine).

    Parameters
    ----------
    region : optional
        The body region (default ``"skull/forehead"``).
    head : HeadContactModel or str, optional
        A head model chosen by the user (:func:`~ppamsafety.impact.head.resolve_head`).

    Returns
    -------
    HeadContactModel
        For a head region the head model given (default ``thesis-frontal``, the thesis'
        head: a contact fitted to the thesis arm's Table 6.1); for any other region its Annex
        A body model (:func:`annex_a_head`).

    Raises
    ------
    ValueError
        A head model given for a region that is not a head region
        (:func:`check_head_for_region`).
    """
    r = resolve_region(region)
    check_head_for_region(r, head)
    if not r.head:
        return annex_a_head(r)
    return head_model() if head is None else resolve_head(head)


def describe_head(h: HeadContactModel) -> str:
    """One phrase: the contact law and mass of a head model.

    Parameters
    ----------
    h : HeadContactModel
        The head model.
    """
    if h.exponent == 1.0 and h.damping == 0.0:
        return f"linear spring {h.stiffness / 1e3:g} N/mm, {h.mass:g} kg"
    return (f"Hunt-Crossley k = {h.stiffness:.3g} N/m^{h.exponent:g}, n = {h.exponent:g}, "
            f"damping {h.damping:.3g}, {h.mass:g} kg")


def disagreement(table: pd.DataFrame, heads) -> str:
    """Why two head models give two answers to the same criteria ("" when they agree).

    Parameters
    ----------
    table : pandas.DataFrame
        Verdict rows of both heads (:func:`evaluate`).
    heads : pair of HeadContactModel
        The two heads, in the order of the table.
    """
    a, b = heads
    ta = table[table.head_model == a.name].set_index("criterion")
    tb = table[table.head_model == b.name].set_index("criterion")
    both = [c for c in ta.index if c in tb.index]
    differ = [c for c in both if bool(ta.loc[c, "passed"]) != bool(tb.loc[c, "passed"])]
    if not differ:
        return ""
    c = differ[0]
    m = ta.loc[c, "metric"]
    u = f" {ta.loc[c, 'unit']}" if ta.loc[c, "unit"] else ""
    return (f"the head models disagree on {', '.join(differ)}: {m} = "
            f"{ta.loc[c, 'value']:.4g}{u} with {a.name} ({describe_head(a)}) and "
            f"{tb.loc[c, 'value']:.4g}{u} with {b.name} ({describe_head(b)}), limit "
            f"{ta.loc[c, 'limit']:.4g}{u}; the contact law and the struck mass set the force "
            f"at a given speed: ISO/TS 15066 states its transient limits for its linear "
            f"two-body model (Annex A), the thesis's head is a Hunt-Crossley contact fitted to "
            f"Table 6.1 (softer than the linear spring at low speed, stiffer at high speed)")


def impact_verdicts(arm, q, qd, stiffness, *, head=None, region=None, dt: float = 2e-5,
                    criteria=None) -> Verdicts:
    """Verdicts of one impact at the tool point, struck on the region's body.

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    q, qd : array_like (2,)
        Pose [rad] and joint speeds [rad/s] at impact.
    stiffness : array_like (2,)
        Joint stiffness [N m/rad].
    head : HeadContactModel, optional
        The head model of a head region (default ``thesis-frontal``); refused for another
        region (:func:`region_head`).
    region : optional
        The body region struck and judged (default ``"skull/forehead"``).
    dt : float
        Integration step [s].
    criteria : sequence of Criterion, optional
        Default :func:`criteria_for` the region.

    Returns
    -------
    Verdicts
        For a head region: rows for both heads (the given one first), the AIS risk of each
        head's HIC and, when they disagree, the reason.  For any other region: the rows of
        its Annex A body model alone, no AIS risk (a head criterion).
    """
    r = resolve_region(region)
    h1 = region_head(r, head)
    heads = (h1, annex_a_head(r)) if r.head else (h1,)
    crit = criteria_for(r) if criteria is None else tuple(criteria)
    rows, risk = [], []
    for h in heads:
        s = simulate_impacts(arm, q, qd, stiffness, head=h, dt=dt).summary.iloc[0]
        vals = {"F_max": float(s.F_max), "HIC36": float(s.HIC36), "HIC15": float(s.HIC15)}
        rows.append(evaluate(vals, crit, head=h.name, region=r.name))
        if r.head:                    # the AIS curves are head injury risks
            risk.append(ais_risk_table(vals["HIC15"], head=h.name, hic_name="HIC15"))
    table = pd.concat(rows, ignore_index=True)
    return Verdicts(table, pd.concat(risk, ignore_index=True) if risk else pd.DataFrame(),
                    disagreement(table, heads) if len(heads) == 2 else "")


def model_kind(region) -> str:
    """What the body of a region is called: ``"head model"`` for a head region, else
    ``"body model"``.

    Parameters
    ----------
    region : str, int, path-like or BodyRegion
        The region (one that cannot be resolved: ``"body model"``).
    """
    try:
        return "head model" if resolve_region(region).head else "body model"
    except (TypeError, ValueError, OSError):
        return "body model"


def verdict_lines(table: pd.DataFrame, risk: pd.DataFrame | None = None,
                  reason: str = "") -> list:
    """Aligned text lines of a verdict table (and the AIS risk), for a terminal.

    Parameters
    ----------
    table : pandas.DataFrame
        Verdict rows (:func:`evaluate`).
    risk : pandas.DataFrame, optional
        :func:`ais_risk_table` rows.
    reason : str
        The disagreement of two heads, if any.
    """
    out = []
    for h, g in table.groupby("head_model", sort=False):
        gov = g.loc[g["margin_pct"].idxmin()]
        out.append(f"verdicts with {model_kind(g['region'].iloc[0])} {h} (body region "
                   f"{g['region'].iloc[0]}, contact "
                   f"at the {g['contact_point'].iloc[0]}): "
                   f"{'PASS' if g['passed'].all() else 'FAIL'}, governed by {gov.criterion}")
        for _, r in g.iterrows():
            unit, per = SHOWN_UNITS.get(r.unit, (r.unit, 1.0))
            u = f" {unit}" if unit else ""
            out.append(f"  {'pass' if r.passed else 'FAIL'}  {r.criterion:<16} {r.metric} "
                       f"{r.value / per:8.4g}{u} vs limit {r.limit / per:8.4g}{u}: margin "
                       f"{r.margin / per:+.4g}{u} "
                       f"({r.margin_pct:+.1f} %){'' if r.confirmed else '  [limit unconfirmed]'}"
                       f"  -- {r.label}")
    if risk is not None and len(risk):
        for h, g in risk.groupby("head_model", sort=False):
            out.append(f"injury risk from {g['HIC'].iloc[0]} = {g['HIC_value'].iloc[0]:.4g} "
                       f"({h}): " + ", ".join(f"P({r.level}) = {r.probability:.2e}"
                                               for r in g.itertuples())
                       + " (NHTSA lognormal curves, car-crash data)")
    if reason:
        out.append(f"note: {reason}")
    return out


__all__ = ["Criterion", "Verdicts", "METRICS", "VERDICT_COLUMNS", "TOOL_POINT", "ALIASES",
           "criteria_for", "criterion", "criterion_names", "evaluate", "verdict_rows", "ais_risk",
           "ais_risk_table", "annex_a_head", "region_head", "check_head_for_region",
           "SHOWN_UNITS", "model_kind", "describe_head", "disagreement", "impact_verdicts",
           "verdict_lines", "SKULL_FOREHEAD", "BodyRegion"]
