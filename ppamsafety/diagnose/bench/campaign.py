"""The discrepancy workflow on a bench campaign of a pneumatic cylinder.

:func:`diagnose_campaign` diagnoses several records of one cylinder together
(a :class:`~ppamsafety.data.campaign.Campaign`, or one record): shared
friction parameters across pressures, chosen from the library of
:mod:`.friction` by the naming rule below, with confounded sensor faults
reported as groups.

1. **Residual** ``r = F - p A`` per record; the **motion** (:mod:`.strokes`):
   direction, speed, travel since the last reversal, strokes and cycles.  The
   samples before a record's first reversal (unknown presliding state) are
   left out of the statistics.
2. **Noise, defined honestly.**  Two levels per record:

   * the *sensor noise*: the robust interpolation residual of ``r`` at
     stride 1 (force and pressure sensor noise; about 0.1 N on the shipped
     bench data);
   * the *repeatability*: the scatter of ``r`` about its own mean at the
     same rod position and direction of motion over the record's cycles
     (a look-up table r(x, s) per record, bins of 1/60 of the stroke,
     degrees of freedom corrected).  No model that is a function of the
     state of the motion can do better; real seals scatter from stroke to
     stroke (0.2-0.6 N on the shipped data), 2-6 x the sensor noise.

   The diagnosis judges against the **repeatability** (the statistics are
   weighted by it, rho is the residual RMS over it); both levels are
   reported.  Judged against the sensor noise every term would be
   "significant" and no model would ever be "explained".
3. **Candidates** (:mod:`.friction`), profiled scalars (x_d, v_s, K) on
   grids, sensor faults, and **confounding**: candidates whose columns span
   the same space on this campaign (within :data:`CONFOUND_TOL`) form one
   group, selected as one and reported under ``confounded`` with the
   experiment that separates them, never named.
4. **Naming rule** (forward selection with refit): a candidate (its best
   variant) is eligible when (a) its **held-out gain** under 2-fold
   cross-validation over alternate *full cycles* of every record is at
   least ``MIN_GAIN`` repeatability variances per sample (its held-out
   contribution >= 0.2 x the repeatability: rule 5), (b) its coefficients
   are significant in a **cluster-robust Wald test** (strokes as clusters)
   at alpha / K (Bonferroni), (c) its parameters are admissible
   (:func:`~.friction.admissible`).  The eligible candidate with the largest
   held-out gain is added.  A backward pass at the end drops a term that is
   no longer significant or no longer gains on held-out cycles once the later
   terms are in (noted).  (A BIC with a known noise level would add every
   term on these long, correlated records; the held-out gain is the
   deciding criterion and the Wald test guards it.)
5. **Confidence** (``confidence`` = stability frequency): the selection is
   rerun on each half of the cycles and, with >= 3 records, leaving out each
   record, and counts the reruns that support the name's claim
   (:data:`CLAIM_FAMILY`: a rerun that models the pressure law with c2 p^2
   instead of c1 p supports "the friction grows with the pressure");
   ``"high"`` needs support in every rerun
   (:data:`STABILITY_HIGH`), a Wald p-value below :data:`P_HIGH`, a
   held-out gain of at least :data:`GAIN_HIGH` and a profiled scalar (x_d,
   v_s) inside its grid, not at its largest value (the shape is then not the
   library's: a time-based transient looks like a long presliding) and,
   for a stroke profile, a contribution of at least :data:`MID_PROFILE_HIGH`
   repeatability levels in the middle half of the stroke (with fixed stroke
   ends anything locked to the reversals is also a function of the position
   near the ends); otherwise ``"low"``.  These
   thresholds are calibrated on synthetic campaigns
   (:mod:`.calibration`: "high" >= 97 % precision on seeds not tuned on).
6. **Explained** when the final residual RMS over the repeatability is <=
   ``rho_max``; otherwise the remaining structure is reported under
   ``where`` (per record, direction, near a reversal or sliding, position
   tercile).  Named effects stay named either way: a friction law can be
   certain while a small structure remains.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pandas as pd

from ..._validation import check_range
from ...data.campaign import Campaign
from ...data.measured import MeasuredData
from ..core.criteria import Step
from ..core.gates import HighRule, judge, level
from ..core.noise import interpolation_sigma
from ..core.pipeline import Steps, run_steps
from ..core.regions import largest_regions, region_rows
from ..core.result import ConfoundedGroup, Effect
from ..core.solve import pinv_psd
from . import friction as fr
from ..core.gram import Gram
from .gram import cv_mse, fit, sse_of, wald
from .result import BenchDiagnosis
from .strokes import stroke_state

#: Rule 5 on held-out data: smallest held-out gain [repeatability variances per sample].
MIN_GAIN = 0.2 ** 2
#: "high" confidence: selected in every stability rerun, Wald p below this, held-out gain.
STABILITY_HIGH = 1.0
P_HIGH = 1e-6
GAIN_HIGH = 0.1
#: What a name claims, for its stability: ``coulomb`` claims "a Coulomb friction" (any of its
#: terms), ``coulomb_pressure``/``coulomb_pressure2`` "the Coulomb level grows with the
#: pressure", ``stroke_profile`` "the force depends on the rod position".  A rerun that selects
#: c2 p^2 instead of c1 p supports the claim of either.
CLAIM_FAMILY = {"coulomb": {"coulomb", "coulomb_pressure", "coulomb_pressure2"},
                "coulomb_pressure": {"coulomb_pressure", "coulomb_pressure2"},
                "coulomb_pressure2": {"coulomb_pressure", "coulomb_pressure2"},
                "stroke_profile": {"stroke_profile", "stroke_profile_pressure"}}
#: "high" for a stroke profile: its RMS over the middle half of the stroke, in repeatability
#: levels, at least this.
MID_PROFILE_HIGH = 0.3
#: Two candidates whose columns' residual (relative norm) after projection on each other's
#: span is below this are confounded.
CONFOUND_TOL = 0.05
#: The campaign's rule for "high" (:mod:`ppamsafety.diagnose.core.gates`): stable in every
#: rerun, significant, a held-out gain, admissible, not at the edge of a profiled grid, and a
#: stroke profile standing out in the middle of the stroke.
CAMPAIGN_RULE = HighRule(gates=("stable", "significant", "held_out", "admissible", "not_at_edge",
                       "mid_stroke"), stability=STABILITY_HIGH, p_value=P_HIGH,
                cv_gain=GAIN_HIGH)
#: Position bins of the repeatability level (per record and direction): the stroke / this.
REPEAT_BINS = 60
#: Samples within this travel of a reversal are "near a reversal" in the where table [m].
NEAR_REVERSAL = 2e-3
#: Sliding samples (speed estimate, stroke range): at least this far from a reversal [m].
SLIDING_DX = 3e-3
MAX_STEPS = 12


def _records(data):
    if isinstance(data, Campaign):
        return data, []
    if isinstance(data, MeasuredData):
        return Campaign((data,), name=data.source), []
    if isinstance(data, (list, tuple)) and data and all(isinstance(d, MeasuredData)
                                                      for d in data):
        return Campaign(tuple(data)), []
    raise TypeError(f"data must be a Campaign, a MeasuredData or a list of them, got "
                    f"{type(data).__name__}")


def repeatability(x, s, r, use, dx=None, bins: int = REPEAT_BINS) -> float:
    """Scatter of ``r`` about its mean at the same state of the motion (module docstring).

    The state is the direction of motion and the rod position (``bins`` bins
    over the stroke) or, within :data:`SLIDING_DX` of a reversal, the travel
    since it (bins of 0.05 mm, finer than any friction transition): a
    position bin there would mix samples before and after the transition.
    Degrees of freedom corrected for the bin means.

    Parameters
    ----------
    x : numpy.ndarray
        Rod position [m].
    s : numpy.ndarray of int
        Direction of motion.
    r : numpy.ndarray
        Force residual [N].
    use : numpy.ndarray of bool
        Samples used.
    dx : numpy.ndarray, optional
        Travel since the last reversal [m].
    bins : int
        Position bins over the stroke.

    Returns
    -------
    float
        [N].
    """
    xs, ss, rs = x[use], s[use], r[use]
    if xs.size < 4 * bins:
        bins = max(4, xs.size // 8)
    lo, hi = float(np.min(xs)), float(np.max(xs))
    b = np.clip(((xs - lo) / max(hi - lo, 1e-12) * bins).astype(int), 0, bins - 1)
    if dx is not None:
        d = dx[use]
        near = np.isfinite(d) & (d < SLIDING_DX)
        nb = int(math.ceil(SLIDING_DX / 0.05e-3))
        end = xs > 0.5 * (lo + hi)
        b = np.where(near, bins + np.clip((d / 0.05e-3).astype(int), 0, nb - 1)
                     + nb * end, b)
    key = b * 2 + (ss > 0)
    cnt = np.bincount(key)
    mean = np.bincount(key, weights=rs) / np.maximum(cnt, 1)
    e = rs - mean[key]
    cells = int(np.count_nonzero(cnt))
    dof = max(xs.size - cells, 1)
    return float(math.sqrt(np.sum(e * e) / dof))


def _prepare(camp: Campaign):
    """Stacked arrays of the campaign and per-record facts."""
    levels = camp.pressure_levels()
    A = float(camp.force_law[1])
    parts, info, notes = [], [], list(camp.notes)
    cl_off = 0
    for i, d in enumerate(camp.records):
        t = d.column("t")
        F, p, x = d.column("force"), d.column("pressure"), d.column("position")
        segs = [(a, b) for a, b in d.segments if b - a >= 5]
        st = stroke_state(t, x, segs)
        fn = A * p
        r = F - fn
        use = (st.stroke >= 0) & (st.s != 0) & ~st.ambiguous
        sig_sensor = float(np.median([interpolation_sigma(t[a:b], r[a:b]) for a, b in segs
                                      if b - a >= 5]))
        sig_rep = repeatability(st.x, st.s, r, use, st.dx) if use.sum() > 50 else math.nan
        lab = camp.labels()[i]
        if st.reversals < 4:
            notes.append(f"{lab}: only {st.reversals} reversal(s) of the motion: friction is "
                         f"hard to tell from a drift on this record")
        info.append({"label": lab, "pressure_Pa": float(levels[i]), "samples": int(t.size),
                     "used": int(use.sum()), "strokes": int(st.stroke.max() + 1),
                     "reversals": st.reversals, "sigma_sensor_N": sig_sensor,
                     "sigma_repeat_N": sig_rep, "sigma_position_m": st.sigma_x,
                     "smoothing_half_window": st.half_window, "source": d.source})
        cl = np.where(st.stroke >= 0, st.stroke + cl_off, -1)
        cl_off += int(st.stroke.max() + 1) if st.stroke.max() >= 0 else 0
        parts.append(pd.DataFrame({"rec": i, "t": t, "trec": t - t[0], "F": F, "p": p,
                                   "f_nom": fn, "r": r, "x": st.x, "v": st.v, "s": st.s,
                                   "dx": st.dx, "stroke": st.stroke, "cycle": st.cycle,
                                   "cluster": cl, "use": use}))
    df = pd.concat(parts, ignore_index=True)
    rec = pd.DataFrame(info)
    bad = rec[~np.isfinite(rec["sigma_repeat_N"])]
    if len(bad):
        raise ValueError(f"records {list(bad['label'])}: too few samples after the first "
                         f"reversal of the motion to diagnose")
    return df, rec, levels, A, notes


def _context(df, rec, levels, A):
    u = df[df["use"]]
    slide = u[u["dx"] > SLIDING_DX]
    if len(slide) < 50:
        slide = u
    vabs = np.abs(slide["v"].to_numpy())
    stroke_speed = float(np.median(vabs)) if vabs.size else 1e-3
    # share of the sliding-speed variance set by record and direction
    key = slide["rec"].to_numpy() * 2 + (slide["s"].to_numpy() > 0)
    v = slide["v"].to_numpy()
    m = np.bincount(key, weights=v) / np.maximum(np.bincount(key), 1)
    r2 = 1.0 - float(np.var(v - m[key])) / max(float(np.var(v)), 1e-300)
    # stroke range common to every record and direction (sliding samples)
    los, his = [], []
    for (_, sg), g in slide.groupby(["rec", "s"]):
        if len(g) > 20:
            a, b = np.quantile(g["x"], [0.02, 0.98])
            los.append(a)
            his.append(b)
    xr = (max(los), min(his)) if los else (0.0, 0.0)
    lv_kpa = np.round(np.asarray(levels) / 1e3)
    repeats = bool(np.unique(lv_kpa).size < lv_kpa.size)
    d = df
    return {"s": d["s"].to_numpy(), "p": d["p"].to_numpy(), "v": d["v"].to_numpy(),
            "dx": d["dx"].to_numpy(), "x": d["x"].to_numpy(), "trec": d["trec"].to_numpy(),
            "f_nom": d["f_nom"].to_numpy(), "rec": d["rec"].to_numpy(), "area": A,
            "levels": np.asarray(levels, float), "stroke_speed": stroke_speed,
            "x_range": xr, "speed_r2": r2, "repeats": repeats}


class _Library:
    """Candidates (and confounded groups) with their column indices in the stacked matrix."""

    def __init__(self, variants: dict, groups: list):
        self.variants = variants          # name -> list of Variant
        cols, j = [], 0
        self.index = {}                   # name -> list of (Variant, column indices)
        for name, vs in variants.items():
            lst = []
            for v in vs:
                lst.append((v, np.arange(j, j + v.k)))
                cols.append(v.columns)
                j += v.k
            self.index[name] = lst
        self.Z = np.concatenate(cols, axis=1) if cols else np.zeros((0, 0))
        self.groups = groups              # list of tuples of member names (len >= 2)
        self.member_of = {m: g for g in groups for m in g}

    def units(self):
        """Selection units: candidates not in a group, and groups (named 'a|b')."""
        out, seen = [], set()
        for name in self.variants:
            g = self.member_of.get(name)
            if g is None:
                out.append(name)
            elif g not in seen:
                seen.add(g)
                out.append("|".join(g))
        return out

    def options(self, unit):
        """(Variant, columns) options of a selection unit (a group: its first member's)."""
        return self.index[unit.split("|")[0]]


def _confounded_groups(cg_all: np.ndarray, lib_index: dict) -> list:
    """Groups of candidates whose (first) variants span the same columns (module docstring)."""
    names = [n for n, lst in lib_index.items() if lst[0][0].k <= 4]
    G = cg_all

    def outside(a_cols, b_cols):
        """Largest relative residual norm of a's columns after projection on b's span."""
        Gbb = G[np.ix_(b_cols, b_cols)]
        inv = pinv_psd(Gbb)
        worst = 0.0
        for a in a_cols:
            gaa = G[a, a]
            if gaa <= 0:
                continue
            ba = G[b_cols, a]
            res = max(gaa - float(ba @ inv @ ba), 0.0) / gaa
            worst = max(worst, math.sqrt(res))
        return worst

    parent = {n: n for n in names}

    def find(n):
        while parent[n] != n:
            n = parent[n]
        return n

    for i, a in enumerate(names):
        for b in names[i + 1:]:
            ca, cb = lib_index[a][0][1], lib_index[b][0][1]
            if outside(ca, cb) < CONFOUND_TOL and outside(cb, ca) < CONFOUND_TOL:
                parent[find(b)] = find(a)
    groups = {}
    for n in names:
        groups.setdefault(find(n), []).append(n)
    return [tuple(g) for g in groups.values() if len(g) > 1]


def _folds_for(clusters, cl_rec, cl_cycle):
    """CV fold (0/1) of each cluster: parity of its cycle's rank within its record."""
    f = np.zeros(clusters.size, int)
    for r_ in np.unique(cl_rec[clusters]):
        m = cl_rec[clusters] == r_
        cyc = cl_cycle[clusters][m]
        uniq = np.unique(cyc)
        rank = np.searchsorted(uniq, cyc)
        f[m] = rank % 2
    return f


class _Selector:
    """Forward selection on a subset of clusters (the naming rule, module docstring)."""

    def __init__(self, cg, lib, ctx, cl_rec, cl_cycle, alpha):
        self.cg, self.lib, self.ctx = cg, lib, ctx
        self.cl_rec, self.cl_cycle = cl_rec, cl_cycle
        self.alpha = alpha

    def _model(self, chosen):
        """name -> Variant and the column indices of the chosen (unit, option) list."""
        model, cols, slices, j = {}, [], {}, 0
        for unit, (var, c) in chosen:
            key = unit.split("|")[0] if "|" in unit else unit
            model[key] = var
            slices[key] = slice(j, j + c.size)
            cols.append(c)
            j += c.size
        return model, (np.concatenate(cols) if cols else np.zeros(0, int)), slices

    def run(self, clusters, *, record_steps: bool = False):
        cg, lib = self.cg, self.lib
        folds = _folds_for(clusters, self.cl_rec, self.cl_cycle)
        Gf = [(cg.G[clusters[folds == k], 0].sum(axis=0),
               float(cg.n[clusters[folds == k]].sum())) for k in (0, 1)]
        Gall = Gf[0][0] + Gf[1][0]
        n_all = float(cg.n[clusters].sum())
        recs = np.unique(self.cl_rec[clusters])
        ctx = dict(self.ctx)
        ctx["levels"] = np.asarray(self.ctx["levels"])[recs]
        chosen, steps = [], []
        units = lib.units()
        cur_cv = cv_mse(cg, Gf, np.zeros(0, int)) * (Gf[0][1] + Gf[1][1]) / n_all
        while len(chosen) < MAX_STEPS:
            rest = [u for u in units if u not in [c[0] for c in chosen]]
            if not rest:
                break
            rows, cand = [], {}
            for u in rest:
                best = None
                for var, c in lib.options(u):
                    _, cols, _ = self._model(chosen + [(u, (var, c))])
                    cv = cv_mse(cg, Gf, cols)
                    if best is None or cv < best[0]:
                        best = (cv, var, c)
                cv, var, c = best
                trial = chosen + [(u, (var, c))]
                model, cols, slices = self._model(trial)
                f = fit(cg, clusters, cols, robust=True, Gsum=Gall)
                key = u.split("|")[0]
                if "|" in u:
                    ok = True
                else:
                    try:
                        ok = fr.admissible(key, model, f.phi, f.cov, slices, ctx)
                    except (ValueError, np.linalg.LinAlgError):
                        ok = False
                stat, df_, pv = wald(f.phi, f.cov, slices[key])
                gain = cur_cv - cv
                row = {"name": u, "variant": var.label, "k": int(c.size), "cv_mse": cv,
                       "cv_gain": gain, "wald": stat, "lr_df": df_, "p_value": pv,
                       "in_bounds": bool(ok), "delta_bic": math.nan, "bic_weight": math.nan,
                       "rms_after": math.sqrt(max(f.chi2 / n_all, 0.0))}
                row["eligible"] = bool(gain >= MIN_GAIN and pv < self.alpha / len(rest) and ok)
                rows.append(row)
                cand[u] = (var, c)
            ok_rows = [r for r in rows if r["eligible"]]
            rows.sort(key=lambda r: -r["cv_gain"])
            pick = max(ok_rows, key=lambda r: r["cv_gain"])["name"] if ok_rows else None
            if record_steps:
                steps.append(Step(tuple(c[0] for c in chosen), rows, pick, math.nan, cur_cv,
                                  math.nan))
            if pick is None:
                break
            chosen.append((pick, cand[pick]))
            cur_cv = next(r["cv_mse"] for r in rows if r["name"] == pick)
        # backward pass: a term added early can lose its support once later terms are in
        # (c1 p after c2 p^2); drop the weakest term that is no longer significant or no
        # longer gains on held-out cycles, refit, repeat
        pruned = []
        while chosen:
            model, cols, slices = self._model(chosen)
            f = fit(cg, clusters, cols, robust=True, Gsum=Gall)
            base = cv_mse(cg, Gf, cols)
            worst = None
            for i, (u, _) in enumerate(chosen):
                _, _, pv = wald(f.phi, f.cov, slices[u.split("|")[0]])
                _, cols_r, _ = self._model(chosen[:i] + chosen[i + 1:])
                loss = cv_mse(cg, Gf, cols_r) - base
                if pv >= self.alpha / len(units) or loss < MIN_GAIN:
                    if worst is None or loss < worst[0]:
                        worst = (loss, i, pv)
            if worst is None:
                break
            pruned.append({"name": chosen[worst[1]][0], "held_out_loss": worst[0],
                           "p_value": worst[2]})
            del chosen[worst[1]]
        self.pruned = pruned
        return chosen, steps


def _stroke_regions(df, e_norm, rho_max):
    """Mean, RMS and z (by strokes) of the final residual per region (in repeatability units)."""
    near = df["dx"].to_numpy() < NEAR_REVERSAL
    groups = {"record": {f"{lab}": (df["label"] == lab).to_numpy()
                         for lab in pd.unique(df["label"])},
              "direction of motion": {"extending (s = +1)": (df["s"] > 0).to_numpy(),
                                      "pushed in (s = -1)": (df["s"] < 0).to_numpy()},
              "travel since reversal": {f"< {1e3 * NEAR_REVERSAL:g} mm (transition)": near,
                                        f">= {1e3 * NEAR_REVERSAL:g} mm (sliding)": ~near}}
    x = df["x"].to_numpy()
    a, b = np.quantile(x, [1 / 3, 2 / 3])
    groups["rod position"] = {f"< {1e3 * a:.3g} mm": x < a,
                              f"{1e3 * a:.3g}-{1e3 * b:.3g} mm": (x >= a) & (x < b),
                              f">= {1e3 * b:.3g} mm": x >= b}
    return pd.DataFrame(region_rows(e_norm, groups, "force", rho_max,
                                    cluster=df["cluster"].to_numpy(), min_n=10))


class CampaignSteps(Steps):
    """The steps of :func:`diagnose_campaign` for one cylinder campaign
    (:mod:`..core.pipeline`).

    Built with :func:`diagnose_campaign`'s arguments (validated here); the stages keep the
    state on the instance.

    Parameters
    ----------
    data, candidates, alpha, rho_max, stability : object
        As :func:`diagnose_campaign`.
    """

    def __init__(self, data, *, candidates=None, alpha: float = 0.01, rho_max: float = 1.5,
                 stability: bool = True):
        check_range("alpha", alpha, 0.0, 0.5, lo_open=True)
        check_range("rho_max", rho_max, 1.0, 100.0)
        if not isinstance(stability, bool):
            raise TypeError(f"stability must be True or False, got {stability!r}")
        self.camp, self.notes = _records(data)
        camp = self.camp
        if camp.actuator_type != "cylinder":
            raise ValueError(f"{camp.name}: a campaign diagnosis is for cylinders "
                             f"([actuator] type = 'cylinder'); this is a {camp.actuator_type} "
                             f"(diagnose its records one by one)")
        if candidates is not None:
            if isinstance(candidates, str) or not all(isinstance(c, str) for c in candidates):
                raise TypeError(f"candidates must be a sequence of names, got {candidates!r}")
            bad = [c for c in candidates if c not in fr.VOCABULARY]
            if bad:
                raise ValueError(f"candidates = {list(candidates)}: {bad} not in the cylinder "
                                 f"vocabulary {list(fr.VOCABULARY)}")
        self.candidates, self.alpha, self.rho_max, self.rerun = (candidates, alpha, rho_max,
                                                                 stability)

    def design(self):
        """Strokes, repeatability levels, the candidates' variants and the per-stroke Gram
        matrices; the candidates whose terms coincide on this campaign."""
        camp, notes = self.camp, self.notes
        df, rec, levels, A, pnotes = _prepare(camp)
        notes += pnotes
        for d in camp.records:
            notes += [f"{_file_name(d.source)}: {n}" for n in d.notes]
        sig_rep = rec["sigma_repeat_N"].to_numpy()
        df["sigma"] = sig_rep[df["rec"].to_numpy()]
        df["label"] = np.asarray(rec["label"])[df["rec"].to_numpy()]
        u = df[df["use"]].reset_index(drop=True)
        ctx = _context(u, rec, levels, A)
        variants, vnotes = fr.build_variants(ctx, self.candidates)
        notes += vnotes
        lib0 = _Library(variants, [])
        w = 1.0 / u["sigma"].to_numpy() ** 2
        clusters_all = u["cluster"].to_numpy()
        cg = Gram.from_samples(lib0.Z, u["r"].to_numpy(), w, clusters_all)
        C = cg.G.shape[0]
        cl_rec = np.zeros(C, int)
        cl_cycle = np.zeros(C, int)
        cl_rec[clusters_all] = u["rec"].to_numpy()
        cl_cycle[clusters_all] = u["cycle"].to_numpy()
        groups = _confounded_groups(cg.G[:, 0].sum(axis=0), lib0.index)
        lib = _Library(variants, groups)
        for g in groups:
            notes.append(f"confounded on this campaign (the same terms within "
                         f"{CONFOUND_TOL:.0%}): {', '.join(g)}; selected together, never named")
        self.df, self.rec, self.u, self.ctx, self.variants, self.A = df, rec, u, ctx, variants, A
        self.cg, self.cl_rec, self.cl_cycle = cg, cl_rec, cl_cycle
        self.groups, self.lib, self.allc = groups, lib, np.arange(C)

    def selection(self):
        """Forward selection by held-out gain with the Wald test, then the pruning."""
        self.sel = _Selector(self.cg, self.lib, self.ctx, self.cl_rec, self.cl_cycle, self.alpha)
        self.chosen, self.steps = self.sel.run(self.allc, record_steps=True)
        self.main_pruned = self.sel.pruned

    def stability(self):
        """The selection rerun on the halves of the cycles and without each record."""
        allc, cl_rec = self.allc, self.cl_rec
        subsets = []
        if self.rerun:
            fo = _folds_for(allc, cl_rec, self.cl_cycle)
            subsets += [("cycles, half 1", allc[fo == 0]), ("cycles, half 2", allc[fo == 1])]
            if len(self.camp) >= 3:
                for i, lab in enumerate(self.rec["label"]):
                    subsets.append((f"without {lab}", allc[cl_rec != i]))
        self.picks = {}
        for nm, cs in subsets:
            ch, _ = self.sel.run(cs)
            self.picks[nm] = {c[0] for c in ch}
        self.subsets = subsets

    def covariance(self):
        """The final fit with its cluster-robust (per stroke) covariance."""
        self.model, self.cols, self.slices = self.sel._model(self.chosen)
        self.f = fit(self.cg, self.allc, self.cols, robust=True)

    def intervals(self):
        """Each selected term's parameters (a confounded group's: each member's, refitted in
        its place) and the friction laws against the pressure."""
        chosen, lib, sel, ctx, f = self.chosen, self.lib, self.sel, self.ctx, self.f
        self.params, self.interp = {}, {}
        for unit, (var, c) in chosen:
            if "|" in unit:
                interp = {}
                for mbr in unit.split("|"):
                    alt = [(mbr if uu == unit else uu, (lib.index[mbr][0] if uu == unit
                                                        else vc)) for uu, vc in chosen]
                    m2, c2, s2 = sel._model(alt)
                    f2 = fit(self.cg, self.allc, c2, robust=True)
                    sl = s2[mbr]
                    interp[mbr] = fr.parameters(lib.index[mbr][0][0], f2.phi[sl],
                                                f2.cov[sl, sl], ctx)
                self.interp[unit] = interp
                continue
            sl = self.slices[unit]
            self.params[unit] = fr.parameters(var, f.phi[sl], f.cov[sl, sl], ctx)
        # derived laws: friction level and presliding step against pressure
        self.laws = {}
        for key, terms in (("friction_level", fr.COULOMB_TERMS),
                           ("stribeck_excess", fr.STRIBECK_TERMS),
                           ("presliding_step", fr.DAHL_TERMS)):
            lc = fr.level_curve(self.model, f.phi, f.cov, self.slices, ctx["levels"], terms)
            if lc is not None:
                self.laws[key] = {"pressure_Pa": list(map(float, ctx["levels"])),
                                  "value_N": list(map(float, lc[0])),
                                  "std_error_N": list(map(float, lc[1]))}

    def explained(self):
        """The residual over the repeatability before and after; each selected term's
        evidence; a confounded group reported, never named."""
        u, f, lib = self.u, self.f, self.lib
        n_all = float(self.cg.n.sum())
        self.rho_after = math.sqrt(f.chi2 / n_all)
        pred = lib.Z[:, self.cols] @ f.phi if self.cols.size else np.zeros(len(u))
        self.e_after = u["r"].to_numpy() - pred
        self.rho_before = float(np.sqrt(np.mean((u["r"] / u["sigma"]) ** 2)))
        self.unexplained = bool(self.rho_after > self.rho_max)
        for pr in self.main_pruned:
            self.notes.append(f"{pr['name']}: selected on the way, dropped at the end (held-out "
                              f"loss without it {pr['held_out_loss']:.3g}, Wald p "
                              f"{pr['p_value']:.2g} in the final model): later terms took its "
                              f"part")
        rowof = {s_.chosen: next(r for r in s_.table if r["name"] == s_.chosen)
                 for s_ in self.steps if s_.chosen is not None}
        picks = self.picks
        self.rows, self.evidence, self.freq, self.edge = {}, {}, {}, {}
        self.confounded = []
        for unit, (var, c) in self.chosen:
            row = rowof[unit]
            fam = CLAIM_FAMILY.get(unit, {unit})
            freq = (sum(bool(fam & p_) for p_ in picks.values()) / len(picks)) if picks else 0.0
            edge = _at_grid_edge(lib.index.get(unit.split("|")[0], []), var)
            ev = {"cv_gain": row["cv_gain"], "wald": row["wald"], "wald_df": row["lr_df"],
                  "at_grid_edge": edge,
                  "p_value": row["p_value"], "stability_frequency": freq,
                  "stability_subsets": len(picks), "setting": var.label,
                  "subsystem_rho": {"force": self.rho_after}}
            if "|" in unit:
                members = unit.split("|")
                self.confounded.append(ConfoundedGroup(
                    members=tuple(members), interpretations=self.interp[unit], evidence=ev,
                    separating_experiment=fr.separating_experiment(members),
                    signature="; ".join(fr.SIGNATURE[m] for m in members)))
                continue
            self.rows[unit], self.evidence[unit] = row, ev
            self.freq[unit], self.edge[unit] = freq, edge

    def detection(self):
        """None: a campaign reports no detection limits (its stability reruns and the
        held-out gain say what it would have seen)."""

    def consistency(self):
        """Leave one record out: the final model refitted without record i predicts record i
        (the honest test of a pressure law; NaN for a single record)."""
        cg, allc, cl_rec, cols = self.cg, self.allc, self.cl_rec, self.cols
        self.left_out = []
        for i in range(len(self.rec)):
            tr_, te_ = allc[cl_rec != i], allc[cl_rec == i]
            if len(self.camp) < 2 or te_.size == 0 or tr_.size == 0:
                self.left_out.append(math.nan)
                continue
            ft = fit(cg, tr_, cols)
            Gte = cg.G[te_, 0].sum(axis=0)
            sse_te = sse_of(Gte, cols, ft.phi) if cols.size else float(Gte[-1, -1])
            self.left_out.append(math.sqrt(max(sse_te, 0.0) / float(cg.n[te_].sum())))

    def gates(self):
        """The campaign's rule for "high" (:data:`CAMPAIGN_RULE`) on every selected term."""
        f, ctx, u = self.f, self.ctx, self.u
        self.effects = []
        for unit, (var, c) in self.chosen:
            if "|" in unit:
                continue
            sl = self.slices[unit]
            row, ev = self.rows[unit], self.evidence[unit]
            ok = fr.admissible(unit, self.model, f.phi, f.cov, self.slices, ctx)
            mid_ok = True
            if unit in ("stroke_profile", "stroke_profile_pressure"):
                # structure along the bore must show where no reversal transient reaches: the
                # middle half of the stroke (at fixed stroke ends, anything locked to the
                # reversals is also a function of the position near the ends)
                lo, hi = ctx["x_range"]
                xx = u["x"].to_numpy()
                mid = (xx >= lo + 0.25 * (hi - lo)) & (xx <= hi - 0.25 * (hi - lo))
                contrib = (var.columns @ f.phi[sl]) / u["sigma"].to_numpy()
                ev["mid_stroke_rms"] = float(np.sqrt(np.mean(contrib[mid] ** 2))) \
                    if mid.any() else 0.0
                mid_ok = ev["mid_stroke_rms"] >= MID_PROFILE_HIGH
            g = judge(CAMPAIGN_RULE, stability=self.freq[unit] if self.rerun else None,
                      p_value=row["p_value"], cv_gain=row["cv_gain"], admissible=ok,
                      not_at_edge=not self.edge[unit], mid_stroke=mid_ok)
            self.effects.append(Effect(name=unit, subsystem="force", parameters=self.params[unit],
                                       evidence=ev, confidence=self.freq[unit],
                                       confidence_level=level(g),
                                       signature=fr.SIGNATURE[unit]))

    def regions(self):
        """The per-record table and curves, and where the final residual is significant."""
        df, u, rec, e_after = self.df, self.u, self.rec, self.e_after
        rrows, curves = [], {}
        e_all_norm = e_after / u["sigma"].to_numpy()
        for i, row in rec.iterrows():
            m = (u["rec"] == i).to_numpy()
            dr = df[df["rec"] == i]
            # the residual after on the samples the statistics use; NaN on the others (before
            # the first reversal, at a turning point: the friction state is not known there)
            used = dr["use"].to_numpy()
            after = np.full(used.size, np.nan)
            after[used] = e_after[m]
            rrows.append({**{k: row[k] for k in ("label", "pressure_Pa", "samples", "used",
                                                 "strokes", "sigma_sensor_N",
                                                 "sigma_repeat_N")},
                          "rms_before_N": float(np.sqrt(np.mean(u["r"][m] ** 2))),
                          "rms_after_N": float(np.sqrt(np.mean(e_after[m] ** 2))),
                          "rho_after": float(np.sqrt(np.mean(e_all_norm[m] ** 2)))})
            curves[row["label"]] = {"t": dr["t"].to_numpy(), "x": dr["x"].to_numpy(),
                                    "s": dr["s"].to_numpy(), "before": dr["r"].to_numpy(),
                                    "after": after, "used": used}
        for row, left_out in zip(rrows, self.left_out):
            row["rho_left_out"] = left_out
        self.records, self.curves = pd.DataFrame(rrows), curves
        self.where = where = _stroke_regions(u, e_all_norm, self.rho_max)
        if self.unexplained:
            worst = largest_regions(where)
            txt = "; ".join(f"{r_.region}: {r_.group} (mean {r_.mean:+.2f}, rms {r_.rms:.2f})"
                            for r_ in worst.itertuples()) or "everywhere"
            self.notes.append(f"residual {self.rho_after:.2f} x the repeatability (> "
                              f"{self.rho_max}): structure remains that the library does not "
                              f"explain; largest where {txt}")

    def result(self, seconds: dict) -> BenchDiagnosis:
        """The :class:`~.result.BenchDiagnosis` (settings and timings).
        Parameters
        ----------
        seconds : dict
            Stage -> wall time [s] (:func:`~ppamsafety.diagnose.core.pipeline.run_steps`).
        """
        t0 = time.perf_counter()
        rec, u, ctx, camp, candidates = self.rec, self.u, self.ctx, self.camp, self.candidates
        sig_sensor = float(np.sqrt(np.mean(rec["sigma_sensor_N"] ** 2)))
        sig_r = float(np.sqrt(np.mean(rec["sigma_repeat_N"] ** 2)))
        rr = {"force": {"unit": "N", "before": float(np.sqrt(np.mean(u["r"] ** 2))),
                        "after": float(np.sqrt(np.mean(self.e_after ** 2))), "noise": sig_r,
                        "sensor_noise": sig_sensor},
              "block_force": {"unit": "residual / repeatability (RMS ratio)",
                              "before": self.rho_before, "after": self.rho_after, "noise": 1.0}}
        settings = {"kind": "actuator", "actuator_type": "cylinder", "campaign": camp.name,
                    "records": len(camp), "alpha": self.alpha, "rho_max": self.rho_max,
                    "criterion": "held-out gain (2-fold CV over alternate full cycles) >= "
                                 f"{MIN_GAIN:g} repeatability variances per sample, "
                                 "cluster-robust Wald test (strokes) p < alpha/K, admissible "
                                 "parameters; the eligible candidate with the largest held-out "
                                 "gain is added",
                    "noise_definition": "repeatability: scatter of F - p A about its mean at "
                                        "the same rod position and direction within a record "
                                        f"({REPEAT_BINS} bins); sensor noise reported beside it",
                    "confidence_rule": {"stability_high": STABILITY_HIGH, "p_high": P_HIGH,
                                        "gain_high": GAIN_HIGH,
                                        "mid_profile_high": MID_PROFILE_HIGH,
                                        "profiled_scalar_inside_grid": True,
                                        "stability_subsets": [nm for nm, _ in self.subsets]},
                    "stability_picks": {k: sorted(v) for k, v in self.picks.items()},
                    "pruned": self.main_pruned,
                    "candidates": list(fr.VOCABULARY if candidates is None else candidates),
                    "candidates_applicable": list(self.variants),
                    "confounded_groups": [list(g) for g in self.groups],
                    "area_m2": self.A, "stroke_speed_m_s": ctx["stroke_speed"],
                    "speed_r2_record_direction": ctx["speed_r2"],
                    "stroke_profile_range_m": list(ctx["x_range"]), "laws": self.laws,
                    "noise_estimate": {"sensor_N": sig_sensor, "repeatability_N": sig_r}}
        timings = {"preparation": seconds["design"],
                   "selection_and_stability": seconds["selection"] + seconds["stability"],
                   "total": sum(seconds.values()) + time.perf_counter() - t0}
        unexplained = self.unexplained
        return BenchDiagnosis(source=camp.name, effects=self.effects, partial=[],
                              unexplained=unexplained,
                              unexplained_channels=["force"] if unexplained else [],
                              residual_rms=rr, where=self.where, steps=self.steps, replay={},
                              settings=settings, timings=timings, notes=tuple(self.notes),
                              blocks={}, kind="actuator", confounded=self.confounded,
                              records=self.records, curves=self.curves)


def diagnose_campaign(data, *, candidates=None, alpha: float = 0.01, rho_max: float = 1.5,
                      stability: bool = True) -> BenchDiagnosis:
    """Diagnose a bench campaign of a pneumatic cylinder (module docstring).

    Parameters
    ----------
    data : Campaign, MeasuredData or list of MeasuredData
        Cylinder records (``[actuator] type = "cylinder"``) of one actuator.
    candidates : sequence of str, optional, keyword-only
        Subset of :data:`~.friction.VOCABULARY` (default all).
    alpha : float, keyword-only
        Level of the Wald test before the Bonferroni division, in (0, 0.5].
    rho_max : float, keyword-only
        Largest residual/repeatability RMS ratio of an explained campaign, in [1, 100].
    stability : bool, keyword-only
        Rerun the selection on halves and leave-one-record-out subsets (the
        confidence levels need it; False: every named effect is "low").

    Returns
    -------
    BenchDiagnosis
    """
    return run_steps(CampaignSteps(data, candidates=candidates, alpha=alpha, rho_max=rho_max,
                                   stability=stability))


def _at_grid_edge(options, var) -> bool:
    """The profiled scalar of ``var`` is the largest of its grid (x_d, v_s; not K)."""
    if len(options) < 2 or not var.setting or "K" in var.setting:
        return False
    key = next(iter(var.setting))
    vals = [v.setting[key] for v, _ in options]
    return bool(var.setting[key] >= max(vals))


def _file_name(src: str) -> str:
    """The file name of a source string (for notes)."""
    return src.replace("\\", "/").rsplit("/", 1)[-1]


__all__ = ["diagnose_campaign", "CampaignSteps", "repeatability", "MIN_GAIN", "STABILITY_HIGH", "P_HIGH",
           "GAIN_HIGH", "CONFOUND_TOL", "MID_PROFILE_HIGH", "CLAIM_FAMILY"]
