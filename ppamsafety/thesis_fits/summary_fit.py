"""Fitting plant effects to summary statistics: the thesis' Table 5.2.

The thesis does not publish its tracking records, only Table 5.2: the mean
and the maximum of the task-space error ||r_d - r|| per controller variant
and circle period (§5.3.5).  Our nominal simulation gives errors about three
times smaller.  This module asks which single effect of the library
(:class:`ppamsafety.params.effects.Effects`), put into the plant truth while
the controllers keep the nominal model, brings the simulated table onto the
thesis's -- and how much a table of summary statistics can identify at all.

Data and uncertainty
--------------------
The statistics are compared as **log ratios** r = ln(simulated / thesis):
a factor-3 gap is a multiplicative error and the cells span 1-50 mm.  Each
r is divided by its standard uncertainty

    s = sqrt(s_rep^2 + (s_print / thesis)^2)

with s_print = 0.1 mm / sqrt(12) = 0.029 mm, the rounding of the printed
values (4 decimals in metres), and s_rep = :data:`REPRODUCIBILITY` = 0.10,
a 10 % run-to-run reproducibility of a tracking statistic on the real arm.
The thesis gives no repeat measurements; 10 % is **our assumption** (the
three lambda rows of one Ki, which the thesis says hardly differ, spread by
up to 10 % in its Table 5.2).  chi2 = sum (r/s)^2.

Effects and their magnitude axes
--------------------------------
Each effect has an axis theta in [0, 1]: theta = 0 is the nominal plant,
theta = 1 the largest plausible magnitude (:data:`AXES`, with the reason).
The simulated statistics are evaluated on a grid of theta (one batched
closed-loop run of all variants, periods and grid points,
:func:`ppamsafety.experiments.closed_loop.run_batch`), interpolated
piecewise linearly in theta, and chi2 is profiled on a fine theta grid:
best theta, chi2_min, and the interval where chi2 - chi2_min <= s2 (the
profile interval scaled by the residual variance s2 = chi2_min/(m - 1),
as in :mod:`ppamsafety.diagnose.arm.selection`).

Identifiability
---------------
The sensitivity matrix J (m statistics x K effects; whitened residual
change per unit theta, the first grid step) gives the Fisher information
F = J^T J.  Reported: the singular values of J (normalised by the
largest), its numerical rank (singular values above :data:`RANK_TOL` of
the largest), the condition number, and the cosine between every pair of
columns -- two effects whose columns have |cos| >= :data:`CONFOUNDED_COS`
change the table in the same proportions and cannot be told apart by it.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.interpolate import RegularGridInterpolator

from .._validation import check_range
from ..control import SensorConfig
from ..experiments.case import ExperimentCase
from ..experiments.catalog import thesis_reference, thesis_variants
from ..experiments.closed_loop import run_batch
from ..experiments.metrics import tracking_stats
from ..experiments.thesis_data import table_5_2
from ..params import thesis_arm
from ..params.effects import Effects, MagnitudeAxis
from ..plots.diagnose import plot_pair_fit, plot_summary_profiles
from ..results import Result
from ..diagnose.arm.synthesize import plant_with

#: Relative run-to-run reproducibility of a tracking statistic (our assumption, see above).
REPRODUCIBILITY = 0.10
#: Rounding of the printed Table 5.2 values: 0.1 mm / sqrt(12) [m].
PRINT_STD = 1e-4 / math.sqrt(12.0)
#: Singular values below this fraction of the largest count as zero (numerical rank).
RANK_TOL = 0.05
#: |cosine| between two sensitivity columns at or above which the effects are confounded.
CONFOUNDED_COS = 0.95


#: An effect's magnitude axis (declared with the effect, :class:`~ppamsafety.params.effects.Effects`).
Axis = MagnitudeAxis
#: The library's effects and their axes: every effect of ``Effects`` that declares one, in
#: declaration order (derived: a new effect with an axis is fitted without an edit here).
AXES = Effects.axes()


def axis(name: str) -> Axis:
    """The :class:`Axis` called ``name``.

    Parameters
    ----------
    name : str
        One of the names in :data:`AXES`.
    """
    for a in AXES:
        if a.name == name:
            return a
    raise ValueError(f"unknown effect axis {name!r}; allowed: {[a.name for a in AXES]}")


def plant_at(arm, name: str, theta: float, *, dt: float = 1e-3):
    """The plant truth with effect ``name`` at ``theta`` (the controllers keep ``arm``).

    Parameters
    ----------
    arm : ArmParameters
        Nominal arm.
    name : str
        Effect axis name (:data:`AXES`).
    theta : float
        Position on its axis, in [0, 1].
    dt : float, keyword-only
        Control period [s] (the dead time is a whole number of periods).

    Returns
    -------
    ArmParameters
    """
    theta = check_range("theta", theta, 0.0, 1.0)
    ax = axis(name)
    if theta == 0.0:
        return arm
    v = ax.value(theta)
    if name == "valve_dead_time":
        k = int(round(v / dt))
        return arm if k == 0 else arm.replace(effects=arm.effects.replace(
            valve_dead_time=(k,) * 4))
    if name == "hysteresis_delta":
        return arm.replace(effects=arm.effects.replace(hysteresis_delta=(v,) * 4))
    return plant_with(arm, {name: v})[0]


def plant_with_axes(arm, thetas: dict, *, dt: float = 1e-3):
    """The plant truth with several effects at once: ``{axis name: theta}``.

    Parameters
    ----------
    arm : ArmParameters
        Nominal arm.
    thetas : dict
        Axis name -> theta in [0, 1].
    dt : float, keyword-only
        Control period [s].

    Returns
    -------
    ArmParameters
    """
    if not isinstance(thetas, dict):
        raise TypeError(f"thetas must be a dict {{axis name: theta}}, got {type(thetas).__name__}")
    eff = arm.effects
    for name, th in thetas.items():
        e = plant_at(arm, name, th, dt=dt).effects
        eff = eff.replace(**{f: getattr(e, f) for f in e.enabled()})
    return arm if eff == arm.effects else arm.replace(effects=eff)


@dataclass(frozen=True)
class TableDesign:
    """Which cells of Table 5.2 are simulated and how.

    Attributes
    ----------
    variants : tuple of str
        Thesis variant labels (rows of Table 5.2).
    periods : tuple of float
        Circle periods [s].
    warmup : float
        Warm-up before the window [s].
    window : float
        Evaluation window [s] (the thesis: 40 s; shorter windows cover at
        least one period of the slowest circle).
    """

    variants: tuple = ("PID", "PSMC joint Ki=2 λ=0.4", "PSMC joint Ki=12 λ=0.4",
                       "PSMC task λ=0.4")
    periods: tuple = (5.0, 10.0, 20.0)
    warmup: float = 5.0
    window: float = 20.0


def simulate_table(arm, plants: list, design: TableDesign, *, dt: float = 1e-3) -> np.ndarray:
    """Mean and max tracking error of every design cell for every plant (one batched run).

    Parameters
    ----------
    arm : ArmParameters
        Nominal arm (references, controllers).
    plants : list of ArmParameters
        Plant truths.
    design : TableDesign
    dt : float, keyword-only
        Control period [s].

    Returns
    -------
    numpy.ndarray, shape (len(plants), len(variants) * len(periods), 2)
        [mean, max] [m] per cell (variant-major); NaN for a diverged run.
    """
    variants = {v.label: v for v in thesis_variants()}
    bad = [v for v in design.variants if v not in variants]
    if bad:
        raise ValueError(f"design.variants: {bad} are not thesis variants ({list(variants)})")
    dur = design.warmup + design.window
    refs = {P: thesis_reference(arm, f"circle{P:g}", duration=dur, dt=dt)
            for P in design.periods}
    sens = SensorConfig()
    cases = [ExperimentCase(pl, variants[v].controller, refs[P], sensors=sens)
             for pl in plants for v in design.variants for P in design.periods]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)        # divergence: NaN statistics
        res = run_batch(cases, dt=dt)
    out = np.empty((len(res), 2))
    for i, r in enumerate(res):
        s = tracking_stats(r, t_from=design.warmup)
        out[i] = s["mean"], s["max"]
    return out.reshape(len(plants), len(design.variants) * len(design.periods), 2)


def thesis_cells(design: TableDesign) -> np.ndarray:
    """Thesis Table 5.2 values of the design cells, shape (cells, 2) [m] (mean, max).

    Parameters
    ----------
    design : TableDesign
    """
    t = table_5_2()
    out = []
    for v in design.variants:
        for P in design.periods:
            row = t[(t.variant == v) & (t.period_s == P)]
            if len(row) != 1:
                raise ValueError(f"no Table 5.2 cell for {v!r} at P = {P:g} s")
            out.append([float(row.thesis_mean_m.iloc[0]), float(row.thesis_max_m.iloc[0])])
    return np.array(out)


def whitened(sim: np.ndarray, thesis: np.ndarray) -> np.ndarray:
    """Whitened log ratios (module docstring), flattened: shape (..., 2 cells).

    Parameters
    ----------
    sim : numpy.ndarray, shape (..., cells, 2)
        Simulated statistics [m].
    thesis : numpy.ndarray, shape (cells, 2)
        Thesis statistics [m].
    """
    s = np.sqrt(REPRODUCIBILITY ** 2 + (PRINT_STD / thesis) ** 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.log(sim / thesis) / s
    return r.reshape(*sim.shape[:-2], -1)


@dataclass(eq=False)
class SummaryFit(Result):
    """Result of :func:`fit_summary`.

    Attributes
    ----------
    design : TableDesign
    thetas : numpy.ndarray
        Grid of theta per effect (shared).
    stats : dict
        name -> array (len(thetas), cells, 2) simulated [m] (theta = 0 is the nominal).
    thesis : numpy.ndarray, shape (cells, 2)
    profiles : pandas.DataFrame
        name, theta, value, chi2 on the fine grid.
    table : pandas.DataFrame
        One row per effect: best theta and magnitude, interval, chi2_min,
        chi2 reduction, chi2 per statistic, mean ratio sim/thesis at the best.
    sensitivity : numpy.ndarray, shape (m, K)
        J (whitened residual change per unit theta).
    singular_values : numpy.ndarray
        Of J, divided by the largest.
    rank : int
    condition : float
        Largest / smallest singular value.
    cosines : pandas.DataFrame
        |cos| between sensitivity columns (K x K).
    confounded : list of tuple
        Pairs with |cos| >= :data:`CONFOUNDED_COS`.
    nominal_chi2 : float
    m : int
        Number of statistics.
    wall_time_s : float
    metrics : dict
    """

    design: TableDesign
    thetas: np.ndarray
    stats: dict
    thesis: np.ndarray
    profiles: pd.DataFrame
    table: pd.DataFrame
    sensitivity: np.ndarray
    singular_values: np.ndarray
    rank: int
    condition: float
    cosines: pd.DataFrame
    confounded: list
    nominal_chi2: float
    m: int
    wall_time_s: float = 0.0
    metrics: dict = field(default_factory=dict)

    def to_pandas(self) -> pd.DataFrame:
        """The per-effect fit table."""
        return self.table

    def cells(self, effect: str | None = None) -> pd.DataFrame:
        """Thesis vs simulated statistics per cell: nominal plant and ``effect`` at its best fit.

        Parameters
        ----------
        effect : str, optional
            Effect axis name (default the best-fitting effect).

        Returns
        -------
        pandas.DataFrame
            variant, period_s, statistic, thesis_m, nominal_m, ratio_nominal,
            best_m, ratio_best (simulated / thesis) [m, -].
        """
        effect = self.table.effect.iloc[0] if effect is None else axis(effect).name
        if effect not in self.stats:
            raise ValueError(f"effect = {effect!r} was not fitted; fitted: {list(self.stats)}")
        th = float(self.table.set_index("effect").loc[effect, "best_theta"])
        st = self.stats[effect]
        ok = np.all(np.isfinite(st.reshape(st.shape[0], -1)), axis=1)
        rows, c = [], 0
        for v in self.design.variants:
            for P in self.design.periods:
                for k, name in enumerate(("mean", "max")):
                    best = float(np.exp(np.interp(th, self.thetas[ok], np.log(st[ok, c, k]))))
                    t = float(self.thesis[c, k])
                    nom = float(st[0, c, k])
                    rows.append({"variant": v, "period_s": P, "statistic": name,
                                 "thesis_m": t, "nominal_m": nom, "ratio_nominal": nom / t,
                                 "best_m": best, "ratio_best": best / t})
                c += 1
        return pd.DataFrame(rows)

    def plot(self):
        """Profiles of chi2 along every effect axis; a matplotlib Figure."""
        return plot_summary_profiles(self, rank_tol=RANK_TOL)


def fit_summary(arm=None, *, effects=None, thetas=(0.0, 0.5, 1.0), design=None,
                fine: int = 101) -> SummaryFit:
    """Fit each effect alone to Table 5.2 and analyse identifiability (module docstring).

    Parameters
    ----------
    arm : ArmParameters, optional
        Nominal arm (default the thesis arm).
    effects : sequence of str, optional, keyword-only
        Axis names (default all of :data:`AXES`).
    thetas : sequence of float, keyword-only
        Grid on every axis, increasing, starting at 0 (the nominal).
    design : TableDesign, optional, keyword-only
        Cells simulated (default :class:`TableDesign`).
    fine : int, keyword-only
        Points of the fine profile grid.

    Returns
    -------
    SummaryFit
    """
    t0 = time.perf_counter()
    arm = thesis_arm() if arm is None else arm
    names = [a.name for a in AXES] if effects is None else [axis(n).name for n in effects]
    thetas = np.asarray(thetas, float)
    if thetas.ndim != 1 or thetas.size < 2 or thetas[0] != 0.0 or np.any(np.diff(thetas) <= 0) \
            or thetas[-1] > 1.0:
        raise ValueError(f"thetas must increase from 0 to at most 1 with >= 2 points, got "
                         f"{thetas.tolist()}")
    design = TableDesign() if design is None else design
    if not isinstance(design, TableDesign):
        raise TypeError(f"design must be a TableDesign, got {type(design).__name__}")
    plants = [arm] + [plant_at(arm, n, th) for n in names for th in thetas[1:]]
    sim = simulate_table(arm, plants, design)
    thesis = thesis_cells(design)
    nth = thetas.size
    stats = {n: np.concatenate([sim[:1], sim[1 + k * (nth - 1):1 + (k + 1) * (nth - 1)]])
             for k, n in enumerate(names)}
    r0 = whitened(sim[0], thesis)
    m = r0.size
    nominal_chi2 = float(np.sum(r0 ** 2))
    fine_t = np.linspace(0.0, thetas[-1], fine)
    prof_rows, rows, J = [], [], []
    for n in names:
        ax = axis(n)
        R = whitened(stats[n], thesis)                     # (nth, m)
        J.append((R[1] - R[0]) / thetas[1])
        ok = np.all(np.isfinite(R), axis=1)
        Rf = np.array([np.interp(fine_t, thetas[ok], R[ok, j]) for j in range(m)]).T
        chi2 = np.sum(Rf ** 2, axis=1)
        chi2[fine_t > thetas[ok].max()] = np.inf           # beyond a diverged grid point
        for th, c in zip(fine_t, chi2):
            prof_rows.append({"effect": n, "theta": th, "value": ax.value(th), "chi2": c})
        i = int(np.argmin(chi2))
        s2 = max(chi2[i] / max(m - 1, 1), 1.0)
        inside = fine_t[chi2 - chi2[i] <= s2]
        lo, hi = float(inside.min()), float(inside.max())
        simb = np.exp(np.array([np.interp(fine_t[i], thetas[ok], np.log(stats[n][ok, c, k]))
                                for c in range(thesis.shape[0]) for k in range(2)]))
        rows.append({"effect": n, "unit": ax.unit, "best_theta": float(fine_t[i]),
                     "best_value": ax.value(fine_t[i]), "interval_low": ax.value(lo),
                     "interval_high": ax.value(hi), "chi2_min": float(chi2[i]),
                     "chi2_per_stat": float(chi2[i] / m),
                     "chi2_reduction": float(1.0 - chi2[i] / nominal_chi2),
                     "ratio_geo_mean": float(np.exp(np.mean(np.log(simb / thesis.ravel())))),
                     "at_edge": bool(i == fine - 1 and fine_t[i] == thetas[-1]),
                     "diverged_points": int((~ok).sum())})
    table = pd.DataFrame(rows).sort_values("chi2_min").reset_index(drop=True)
    J = np.array(J).T
    J = np.where(np.isfinite(J), J, 0.0)
    sv = np.linalg.svd(J, compute_uv=False)
    svn = sv / sv[0] if sv[0] > 0 else sv
    rank = int(np.sum(svn > RANK_TOL))
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf
    norms = np.linalg.norm(J, axis=0)
    C = (J.T @ J) / np.outer(np.maximum(norms, 1e-300), np.maximum(norms, 1e-300))
    cos = pd.DataFrame(np.abs(C), index=names, columns=names)
    conf = [(a, b, float(abs(C[i, j]))) for i, a in enumerate(names) for j, b in enumerate(names)
            if j > i and abs(C[i, j]) >= CONFOUNDED_COS]
    best = table.iloc[0]
    metrics = {"nominal_chi2": nominal_chi2, "statistics": m, "effects": len(names),
               "best_effect": best.effect, "best_value": float(best.best_value),
               "best_chi2": float(best.chi2_min),
               "best_chi2_per_stat": float(best.chi2_per_stat),
               "nominal_ratio_geo_mean": float(np.exp(np.mean(np.log(
                   sim[0].ravel() / thesis.ravel())))),
               "sensitivity_rank": rank, "sensitivity_condition": cond,
               "confounded_pairs": len(conf)}
    return SummaryFit(design=design, thetas=thetas, stats=stats, thesis=thesis,
                      profiles=pd.DataFrame(prof_rows), table=table, sensitivity=J,
                      singular_values=svn, rank=rank, condition=cond, cosines=cos,
                      confounded=conf, nominal_chi2=nominal_chi2, m=m,
                      wall_time_s=time.perf_counter() - t0, metrics=metrics)


@dataclass(eq=False)
class PairFit(Result):
    """Result of :func:`fit_pair`: two effects fitted together.

    Attributes
    ----------
    names : tuple of str
        The two axis names.
    best_theta : tuple of float
    best_value : tuple of float
        Physical magnitudes at the best point.
    chi2_min : float
    chi2_per_stat : float
    chi2_single : float
        Best chi2 of either effect alone.
    grid : pandas.DataFrame
        theta_a, theta_b, chi2 on the fine grid.
    m : int
        Number of statistics.
    """

    names: tuple
    best_theta: tuple
    best_value: tuple
    chi2_min: float
    chi2_per_stat: float
    chi2_single: float
    grid: pd.DataFrame
    m: int = 1

    def to_pandas(self) -> pd.DataFrame:
        """chi2 on the fine grid: ``theta_a``, ``theta_b`` [-] and ``chi2`` [-]."""
        return self.grid

    def plot(self):
        """chi2 per statistic over the two thetas, the best point marked; a Figure."""
        return plot_pair_fit(self.grid, self.names, self.best_theta, statistics=self.m,
                             chi2_single=self.chi2_single)


def fit_pair(fit: SummaryFit, arm=None, names=None, *, fine: int = 41) -> PairFit:
    """Fit the two best single effects of ``fit`` together (does a pair close the gap?).

    The statistics on the theta grid of both axes are known on the edges from
    ``fit``; the interior points are simulated with both effects on (one
    batched run), interpolated bilinearly in the log statistics and chi2 is
    minimised on a fine grid.

    Parameters
    ----------
    fit : SummaryFit
        One-at-a-time fit (same design).
    arm : ArmParameters, optional
        Nominal arm (default the thesis arm).
    names : sequence of 2 str, optional
        Axis names (default the two best of ``fit.table``).
    fine : int, keyword-only
        Points per axis of the fine grid.

    Returns
    -------
    PairFit
    """


    if not isinstance(fit, SummaryFit):
        raise TypeError(f"fit must be a SummaryFit, got {type(fit).__name__}")
    arm = thesis_arm() if arm is None else arm
    names = tuple(fit.table.effect.iloc[:2]) if names is None else tuple(names)
    if len(names) != 2 or names[0] == names[1] or any(n not in fit.stats for n in names):
        raise ValueError(f"names must be two different fitted effects of {list(fit.stats)}, "
                         f"got {names!r}")
    th = fit.thetas
    n = th.size
    inner = [(i, j) for i in range(1, n) for j in range(1, n)]
    sim = simulate_table(arm, [plant_with_axes(arm, {names[0]: th[i], names[1]: th[j]})
                               for i, j in inner], fit.design)
    S = np.empty((n, n) + fit.stats[names[0]].shape[1:])
    S[:, 0] = fit.stats[names[0]]
    S[0, :] = fit.stats[names[1]]
    for (i, j), v in zip(inner, sim):
        S[i, j] = v
    with np.errstate(invalid="ignore", divide="ignore"):
        logS = np.log(S)
    interp = RegularGridInterpolator((th, th), logS.reshape(n, n, -1))
    f = np.linspace(0.0, th[-1], fine)
    A, B = np.meshgrid(f, f, indexing="ij")
    L = interp(np.stack([A.ravel(), B.ravel()], axis=1))
    R = whitened(np.exp(L).reshape(L.shape[0], -1, 2), fit.thesis)
    chi2 = np.sum(R ** 2, axis=1)
    chi2 = np.where(np.isfinite(chi2), chi2, np.inf)
    k = int(np.argmin(chi2))
    bt = (float(A.ravel()[k]), float(B.ravel()[k]))
    single = float(fit.table.set_index("effect").loc[list(names), "chi2_min"].min())
    return PairFit(names=names, best_theta=bt,
                   best_value=(axis(names[0]).value(bt[0]), axis(names[1]).value(bt[1])),
                   chi2_min=float(chi2[k]), chi2_per_stat=float(chi2[k] / fit.m),
                   chi2_single=single, m=fit.m,
                   grid=pd.DataFrame({"theta_a": A.ravel(), "theta_b": B.ravel(),
                                      "chi2": chi2}))


__all__ = ["Axis", "AXES", "axis", "plant_at", "plant_with_axes", "PairFit", "fit_pair",
           "TableDesign", "simulate_table", "thesis_cells",
           "whitened", "SummaryFit", "fit_summary", "REPRODUCIBILITY", "PRINT_STD", "RANK_TOL",
           "CONFOUNDED_COS"]
