"""The candidate library of a pneumatic cylinder on a bench: seal friction and sensor faults.

Every candidate adds terms, linear in its coefficients, to the force residual
``r = F - p A`` (measured force minus the nominal law), with ``s`` the
direction of motion (+1 while the rod extends), ``p`` the gauge pressure,
``v`` the speed, ``dx`` the travel since the last reversal, ``x`` the rod
position and ``t`` the time since the record's start (:mod:`.strokes`).  A
friction force opposes the motion, so it enters as ``-s f``:

======================== ========================================== ===============================
name                     terms added to r                           parameters (SI)
======================== ========================================== ===============================
coulomb                  ``-c0 s``                                  c0 [N]
coulomb_pressure         ``-c1 p s``  (F_c = c0 + c1 p, the         c1 [N/Pa]
                         standard seal model; >= 2 pressures)
coulomb_pressure2        ``-c2 p^2 s``  (>= 3 pressures)            c2 [N/Pa^2]
viscous                  ``-b v``  (only when the speed varies      b [N s/m]
                         at one pressure and direction)
stribeck                 ``-(dS0 + dS1 p) s exp(-(v/v_s)^2)``       dS0 [N], dS1 [N/Pa]; v_s [m/s]
                         (velocity weakening: dS >= 0)              profiled
presliding               ``-(h0 + h1 p) s exp(-dx/x_d)``            h0 [N], h1 [N/Pa]; x_d [m]
                         (Dahl: after a reversal the friction       profiled; ideal Dahl
                         moves from -F_c to +F_c over a few x_d;    h = -2 F_c, so h <= 0
                         LuGre's extra terms are viscous/Stribeck)
stroke_profile           ``s B(x) beta + B(x) gamma`` (cubic        K [-] profiled; the RMS of
                         B-splines along the bore: a printed bore   both profiles [N]
                         is not uniform)
stroke_profile_pressure  ``p B(x) beta' + s p B(x) gamma'`` (an     K [-]; RMS at the mean
                         effective area or seal load that varies    pressure [N]
                         along the bore)
friction_drift           ``-cd t s + od t`` (warming, lubricant;    cd, od [N/s]
                         t from the middle of each record)
force_sensor_offset      ``o``                                      o [N]
pressure_sensor_offset   ``A dp``                                   dp [Pa]
force_sensor_gain        ``g p A``  (to first order)                g [-]
pressure_sensor_gain     ``g_p p A``                                g_p [-]
force_law_refit          ``dA p``  (an effective area)              dA [m^2]
record_offsets           one constant per record (only with         o_r [N]
                         repeated records at one pressure)
======================== ========================================== ===============================

Sensor faults and plant effects that give the same terms on a campaign (a
force-sensor offset and a pressure-sensor offset; a force gain, a pressure
gain and an area error; on one pressure level all of them) are **confounded**:
the diagnosis reports the group with the experiment that would separate
them (:data:`SEPARATING`), and never names one of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats
from scipy.interpolate import BSpline

from ..core.result import Estimate

VOCABULARY = ("coulomb", "coulomb_pressure", "coulomb_pressure2", "viscous", "stribeck",
              "presliding", "stroke_profile", "stroke_profile_pressure", "friction_drift",
              "force_sensor_offset", "pressure_sensor_offset", "force_sensor_gain",
              "pressure_sensor_gain", "force_law_refit", "record_offsets")
#: Friction physics (the rest are sensor faults and the force law).
FRICTION = ("coulomb", "coulomb_pressure", "coulomb_pressure2", "viscous", "stribeck",
            "presliding", "stroke_profile", "stroke_profile_pressure", "friction_drift")
#: Profiled grids: Dahl length [m], Stribeck speed as a fraction of the stroke speed, knots.
XD_GRID = (0.05e-3, 0.1e-3, 0.2e-3, 0.3e-3, 0.5e-3, 0.8e-3, 1.2e-3, 2.0e-3)
VS_FRACTIONS = (0.05, 0.1, 0.2, 0.35)
K_GRID = (8, 16, 32)
K2_GRID = (4, 8, 16)
#: The experiment that separates the members of a confounded group.
SEPARATING = {
    frozenset({"force_sensor_offset", "pressure_sensor_offset"}):
        "read both sensors at rest with the rod free and the cylinder vented (p = 0, F = 0): "
        "a load-cell zero error shows in F, a pressure-sensor zero error in p",
    frozenset({"force_sensor_gain", "pressure_sensor_gain", "force_law_refit"}):
        "a dead-weight check of the load cell (known masses on the rod), a calibrated "
        "reference gauge on the pressure port, and the bore measured: a force-gain error "
        "scales the dead weights, a pressure-gain error the gauge reading, an area error "
        "neither",
}
#: Fallback text for any other group.
SEPARATING_DEFAULT = ("repeat the campaign over a wider operating range (several pressures, "
                      "several speeds at one pressure, repeated records) and check the sensors "
                      "against references (dead weights, a reference gauge): these candidates "
                      "give the same terms on this campaign")
#: Admissible ranges: largest |gain|, largest relative area change, largest offset as a
#: fraction of max |F_nom| (each widened by half for the 95 % interval, as the arm's rule 3).
GAIN_MAX = 0.2
AREA_MAX_RELATIVE = 0.5
OFFSET_MAX_FRACTION = 0.2
Z95 = float(stats.norm.ppf(0.975))


@dataclass(frozen=True, eq=False)
class Variant:
    """One candidate with its profiled scalars fixed: the columns it adds.

    Attributes
    ----------
    name : str
        Candidate name (:data:`VOCABULARY`).
    setting : dict
        Profiled scalars (e.g. ``{"x_d": 2e-4}``), SI.
    label : str
        Readable setting ("x_d = 0.2 mm").
    columns : numpy.ndarray, shape (N, k)
        Terms per unit coefficient [N per unit].
    coef : tuple of (str, str)
        Coefficient names and units.
    """

    name: str
    setting: dict
    label: str
    columns: np.ndarray = field(repr=False)
    coef: tuple

    @property
    def k(self) -> int:
        """Number of coefficients."""
        return self.columns.shape[1]


SIGNATURE = {
    "coulomb": "a force opposing the motion: a step of 2 c0 at every reversal, at every pressure",
    "coulomb_pressure": "the friction step grows with the pressure (seal pressed harder)",
    "coulomb_pressure2": "the friction step grows faster than linearly with the pressure",
    "viscous": "friction growing with the speed, seen only if the speed varies at one pressure",
    "stribeck": "friction larger at low speed (break-away), right after each reversal",
    "presliding": "after a reversal the friction moves from one level to the other over a "
                  "fraction of a mm of travel (Dahl), not at once",
    "stroke_profile": "friction and force that depend on where the rod is along the bore, the "
                      "same in every cycle",
    "stroke_profile_pressure": "a force along the bore that grows with the pressure (an "
                               "effective area or seal load varying along the bore)",
    "friction_drift": "the friction level changes steadily during a record (warming, "
                      "lubricant redistribution)",
    "force_sensor_offset": "a constant force at every pressure, in both directions",
    "pressure_sensor_offset": "a constant force A dp at every pressure, in both directions",
    "force_sensor_gain": "a force proportional to the measured force, in both directions",
    "pressure_sensor_gain": "a force proportional to p A, in both directions",
    "force_law_refit": "a force proportional to the pressure, in both directions (an "
                       "effective area)",
    "record_offsets": "a different constant force in each record (re-zeroed sensor, re-seated "
                      "seal)",
}


def bspline_basis(x, K, lo, hi):
    """K-1 centred cubic B-splines on [lo, hi] (one of K dropped: the constant is elsewhere).

    Parameters
    ----------
    x : numpy.ndarray
        Positions [m] (clipped to [lo, hi]).
    K : int
        Number of B-splines, >= 4.
    lo, hi : float
        Range [m].

    Returns
    -------
    numpy.ndarray, shape (x.size, K - 1)
        Each column minus its mean over a uniform grid of [lo, hi].
    """
    deg = 3
    inner = np.linspace(lo, hi, K - deg + 1)
    knots = np.concatenate([[lo] * deg, inner, [hi] * deg])
    xx = np.clip(x, lo, hi - 1e-12 * (hi - lo))
    B = BSpline.design_matrix(xx, knots, deg).toarray()[:, 1:]
    g = np.linspace(lo, hi, 801)
    Bg = BSpline.design_matrix(g, knots, deg).toarray()[:, 1:]
    return B - Bg.mean(axis=0)


def build_variants(ctx: dict, names=None) -> tuple:
    """Every variant of every applicable candidate on a campaign's stacked samples.

    Parameters
    ----------
    ctx : dict
        Stacked arrays (N,): ``s``, ``p`` [Pa], ``v`` [m/s], ``dx`` [m],
        ``x`` [m], ``trec`` [s], ``f_nom`` [N], ``rec`` (record index);
        scalars ``area`` [m^2], ``levels`` (nominal pressures [Pa] per record),
        ``stroke_speed`` [m/s], ``x_range`` (lo, hi) [m] of the stroke
        profile, ``speed_r2`` (share of the sliding-speed variance explained
        by record and direction), ``repeats`` (two records share a nominal
        pressure).
    names : sequence of str, optional
        Subset of :data:`VOCABULARY` (default all).

    Returns
    -------
    dict
        name -> list of :class:`Variant`.
    list of str
        Notes: candidates left out and why.
    """
    names = VOCABULARY if names is None else tuple(names)
    bad = [n for n in names if n not in VOCABULARY]
    if bad:
        raise ValueError(f"candidates: unknown {bad}; allowed on a cylinder campaign: "
                         f"{list(VOCABULARY)}")
    s, p, v, dx = ctx["s"].astype(float), ctx["p"], ctx["v"], ctx["dx"]
    x, tr, fn, rec = ctx["x"], ctx["trec"], ctx["f_nom"], ctx["rec"]
    A = ctx["area"]
    nlev = np.unique(np.round(np.asarray(ctx["levels"]) / 1e3)).size   # kPa resolution
    out, notes = {}, []

    def one(name, cols, coef, setting=None, label=""):
        out.setdefault(name, []).append(Variant(name, dict(setting or {}), label,
                                                np.column_stack(cols), tuple(coef)))

    for n in names:
        if n == "coulomb":
            one(n, [-s], [("c0", "N")])
        elif n == "coulomb_pressure":
            if nlev < 2:
                notes.append("coulomb_pressure: one pressure level; the pressure dependence of "
                             "the friction needs records at >= 2 pressures")
                continue
            one(n, [-s * p], [("c1", "N/Pa")])
        elif n == "coulomb_pressure2":
            if nlev < 3:
                notes.append("coulomb_pressure2: needs records at >= 3 pressures")
                continue
            one(n, [-s * p * p], [("c2", "N/Pa^2")])
        elif n == "viscous":
            if ctx["speed_r2"] > 0.95:
                notes.append(f"viscous: not identifiable: the sliding speed is set by the "
                             f"record and the direction of motion (R^2 = {ctx['speed_r2']:.3f}), "
                             f"so b v is a Coulomb level per record; record several speeds at "
                             f"one pressure to measure it")
                continue
            one(n, [-v], [("b", "N s/m")])
        elif n == "stribeck":
            for f in VS_FRACTIONS:
                vs = f * ctx["stroke_speed"]
                g = np.exp(-(v / vs) ** 2)
                cols = [-s * g] + ([-s * p * g] if nlev >= 2 else [])
                coef = [("dS0", "N")] + ([("dS1", "N/Pa")] if nlev >= 2 else [])
                one(n, cols, coef, {"v_s": vs}, f"v_s = {1e3 * vs:.3g} mm/s")
        elif n == "presliding":
            d = np.where(np.isfinite(dx), dx, np.inf)
            for xd in XD_GRID:
                E = np.exp(-d / xd)
                cols = [-s * E] + ([-s * p * E] if nlev >= 2 else [])
                coef = [("h0", "N")] + ([("h1", "N/Pa")] if nlev >= 2 else [])
                one(n, cols, coef, {"x_d": xd}, f"x_d = {1e3 * xd:.3g} mm")
        elif n in ("stroke_profile", "stroke_profile_pressure"):
            lo, hi = ctx["x_range"]
            if not hi > lo:
                notes.append(f"{n}: no stroke range common to every record and direction")
                continue
            if n == "stroke_profile_pressure" and nlev < 2:
                notes.append(f"{n}: needs records at >= 2 pressures")
                continue
            pb = p / max(float(np.mean(p)), 1.0)
            for K in (K_GRID if n == "stroke_profile" else K2_GRID):
                B = bspline_basis(x, K, lo, hi)
                if n == "stroke_profile":
                    C = np.concatenate([-s[:, None] * B, B], axis=1)
                else:
                    C = np.concatenate([-(pb * s)[:, None] * B, pb[:, None] * B], axis=1)
                k = B.shape[1]
                coef = [(f"beta{j}", "N") for j in range(k)] + [(f"gamma{j}", "N")
                                                                for j in range(k)]
                out.setdefault(n, []).append(Variant(n, {"K": K}, f"K = {K}", C, tuple(coef)))
        elif n == "friction_drift":
            # time from the middle of each record: a drift within records, orthogonal to
            # per-record constants (records of different lengths at different pressures
            # would otherwise make t a proxy of p)
            R = int(rec.max()) + 1
            tm = np.bincount(rec, weights=tr, minlength=R) / np.maximum(
                np.bincount(rec, minlength=R), 1)
            tc = tr - tm[rec]
            one(n, [-s * tc, tc], [("cd", "N/s"), ("od", "N/s")])
        elif n == "force_sensor_offset":
            one(n, [np.ones_like(s)], [("o", "N")])
        elif n == "pressure_sensor_offset":
            one(n, [np.full_like(s, A)], [("dp", "Pa")])
        elif n == "force_sensor_gain":
            one(n, [fn], [("g", "-")])
        elif n == "pressure_sensor_gain":
            one(n, [p * A], [("g_p", "-")])
        elif n == "force_law_refit":
            one(n, [p], [("dA", "m^2")])
        elif n == "record_offsets":
            if not ctx["repeats"]:
                notes.append("record_offsets: no two records share a nominal pressure, so "
                             "an offset per record cannot be told from a force growing with the "
                             "pressure (area, gains); repeat a pressure level to test it")
                continue
            R = int(rec.max()) + 1
            one(n, [(rec == i).astype(float) for i in range(R)],
                [(f"o_{i}", "N") for i in range(R)])
    return out, notes


def _row(value, se, unit, nominal=0.0):
    return Estimate(value=float(value), unit=unit, ci_low=float(value - Z95 * se),
                    ci_high=float(value + Z95 * se), std_error=float(se), nominal=nominal)


def _fixed(value, unit):
    return Estimate(value=float(value), unit=unit, ci_low=math.nan, ci_high=math.nan,
                    std_error=math.nan, nominal=math.nan)


def parameters(var: Variant, phi, cov, ctx) -> dict:
    """Reported parameters of a fitted variant (values, 95 % intervals, SI units).

    Stroke profiles report the RMS of their two parts along the stroke (delta
    method), with K; presliding and Stribeck their profiled x_d or v_s.

    Parameters
    ----------
    var : Variant
        The variant in the model.
    phi : numpy.ndarray, shape (k,)
        Its coefficients.
    cov : numpy.ndarray, shape (k, k)
        Their (cluster-robust) covariance.
    ctx : dict
        As :func:`build_variants` (``area``, ``x_range``).

    Returns
    -------
    dict
        name -> :class:`~ppamsafety.diagnose.core.result.Estimate`.
    """
    out = {}
    if var.name in ("stroke_profile", "stroke_profile_pressure"):
        K = var.setting["K"]
        lo, hi = ctx["x_range"]
        B = bspline_basis(np.linspace(lo, hi, 201), K, lo, hi)
        k = B.shape[1]
        for sl, nm in ((slice(0, k), "rms_friction_profile"), (slice(k, 2 * k),
                                                               "rms_force_profile")):
            prof = B @ phi[sl]
            a = float(np.sqrt(np.mean(prof ** 2)))
            grad = B.T @ prof / (B.shape[0] * a) if a > 0 else np.zeros(k)
            se = float(math.sqrt(max(float(grad @ cov[sl, sl] @ grad), 0.0)))
            out[nm] = _row(a, se, "N")
        out["K"] = _fixed(K, "-")
        return out
    for i, (nm, unit) in enumerate(var.coef):
        out[nm] = _row(phi[i], math.sqrt(max(cov[i, i], 0.0)), unit)
    if var.name == "force_law_refit":
        A = ctx["area"]
        out["A"] = _row(A + phi[0], math.sqrt(max(cov[0, 0], 0.0)), "m^2", nominal=A)
    for key, unit in (("x_d", "m"), ("v_s", "m/s")):
        if key in var.setting:
            out[key] = _fixed(var.setting[key], unit)
    return out


def level_curve(model: dict, phi, cov, slices, levels, terms):
    """A pressure-dependent level sum_j c_j p^j at the given pressures, with standard errors.

    Parameters
    ----------
    model : dict
        name -> Variant in the model.
    phi, cov : numpy.ndarray
        Coefficients and covariance of the whole model.
    slices : dict
        name -> slice of phi.
    levels : array_like
        Pressures [Pa].
    terms : sequence of (str, int, int)
        (candidate, coefficient index, power of p) summed.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray) or None
        Values and standard errors; None if no term is in the model.
    """
    lv = np.asarray(levels, float)
    w = np.zeros((lv.size, phi.size))
    used = False
    for name, j, pw in terms:
        if name in model and j < model[name].k:
            w[:, slices[name].start + j] = lv ** pw
            used = True
    if not used:
        return None
    se = np.sqrt(np.maximum(np.einsum("li,ij,lj->l", w, cov, w), 0.0))
    return w @ phi, se


COULOMB_TERMS = (("coulomb", 0, 0), ("coulomb_pressure", 0, 1), ("coulomb_pressure2", 0, 2))
STRIBECK_TERMS = (("stribeck", 0, 0), ("stribeck", 1, 1))
DAHL_TERMS = (("presliding", 0, 0), ("presliding", 1, 1))


def admissible(name: str, model: dict, phi, cov, slices, ctx) -> bool:
    """Rule 3 for a candidate inside a fitted model: its parameters are physically possible.

    * Coulomb terms: the friction level c0 + c1 p + c2 p^2 is not
      significantly negative at any record's pressure (and below half the
      largest force);
    * viscous: b not significantly negative;
    * stribeck: the low-speed excess dS0 + dS1 p not significantly negative
      at any level (a "Stribeck" term that *lowers* the friction at low
      speed is the lag of presliding, not velocity weakening);
    * presliding: h0 + h1 p not significantly positive at any level (after
      a reversal the friction starts from the other side);
    * gains within +-20 %, an area change within +-50 %, offsets within 20 %
      of max abs(F_nom), each widened by half; profiles and drift below half
      of max abs(F_nom).

    Parameters
    ----------
    name : str
        The candidate.
    model : dict
        name -> Variant of the fitted model (``name`` included).
    phi, cov : numpy.ndarray
        Coefficients and covariance of the whole model.
    slices : dict
        name -> slice.
    ctx : dict
        As :func:`build_variants`.
    """
    fmax = float(np.max(np.abs(ctx["f_nom"]))) or 1.0
    sl = slices[name]
    ph = phi[sl]
    se = np.sqrt(np.maximum(np.diag(cov[sl, sl]), 0.0))
    lv = ctx["levels"]
    if name in ("coulomb", "coulomb_pressure", "coulomb_pressure2"):
        val, e = level_curve(model, phi, cov, slices, lv, COULOMB_TERMS)
        return bool(np.all(val + Z95 * e >= 0) and np.all(val <= 0.5 * fmax))
    if name == "viscous":
        return bool(ph[0] + Z95 * se[0] >= 0)
    if name == "stribeck":
        val, e = level_curve(model, phi, cov, slices, lv, STRIBECK_TERMS)
        return bool(np.all(val + Z95 * e >= 0))
    if name == "presliding":
        val, e = level_curve(model, phi, cov, slices, lv, DAHL_TERMS)
        return bool(np.all(val - Z95 * e <= 0) and np.all(np.abs(val) <= fmax))
    if name in ("force_sensor_gain", "pressure_sensor_gain"):
        return bool(abs(ph[0]) + Z95 * se[0] <= 1.5 * GAIN_MAX)
    if name == "force_law_refit":
        return bool(abs(ph[0]) + Z95 * se[0] <= 1.5 * AREA_MAX_RELATIVE * ctx["area"])
    if name in ("force_sensor_offset", "record_offsets"):
        return bool(np.all(np.abs(ph) + Z95 * se <= 1.5 * OFFSET_MAX_FRACTION * fmax))
    if name == "pressure_sensor_offset":
        return bool((abs(ph[0]) + Z95 * se[0]) * ctx["area"] <= 1.5 * OFFSET_MAX_FRACTION * fmax)
    if name in ("stroke_profile", "stroke_profile_pressure", "friction_drift"):
        contrib = model[name].columns @ ph
        return bool(np.max(np.abs(contrib)) <= 0.5 * fmax)
    return True


def separating_experiment(members, *, table=None, default: str | None = None) -> str:
    """The experiment that would separate the members of a confounded group.

    Parameters
    ----------
    members : iterable of str
        Candidate names.
    table : dict, optional, keyword-only
        frozenset of names -> text (default :data:`SEPARATING`, the cylinder's; the muscle
        library passes its own, :data:`~.candidates.SEPARATING`).
    default : str, optional, keyword-only
        Text for a group no entry covers (default :data:`SEPARATING_DEFAULT`).
    """
    table = SEPARATING if table is None else table
    default = SEPARATING_DEFAULT if default is None else default
    m = frozenset(members)
    for key, txt in table.items():
        if m <= key:
            return txt
    touched = [k for k in table if m & k]
    if touched and m <= frozenset().union(*touched):
        return ("record at several pressures (a constant force and one proportional to the "
                "pressure are then distinct); then: " + "; ".join(table[k] for k in touched))
    return default


__all__ = ["VOCABULARY", "FRICTION", "Variant", "build_variants", "parameters", "admissible",
           "level_curve", "separating_experiment", "bspline_basis", "SIGNATURE", "SEPARATING",
           "XD_GRID", "VS_FRACTIONS", "K_GRID", "K2_GRID", "COULOMB_TERMS", "STRIBECK_TERMS",
           "DAHL_TERMS"]
