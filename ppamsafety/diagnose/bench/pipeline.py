"""The discrepancy workflow on a test bench: one actuator's force against its nominal law.

Thesis §3.5.1.6 localised the muscle hysteresis by comparing the measured
muscle force with the force the law (3.9) predicts from the measured
pressure and contraction.  :func:`diagnose_actuator` does that for an
actuator record (``kind = "actuator"``, ``docs/measured_data.md``):

1. **residual** ``r = F_measured - p (a0/eps + a1 + a2 eps + a3 eps^2 + a4 eps^3)``
   with the record's own coefficients (a cylinder: ``a = [0, A, 0, 0, 0]``),
   eps from the ``contraction`` column or ``(l0 - position)/l0``;
2. **noise level** of r from its high-frequency content
   (:func:`~.noise.interpolation_sigma`: each sample against the line
   through its neighbours, valid for non-uniform sampling).  Filtered
   (correlated) sensor noise is detected by comparing the estimate on every
   sample with the estimate on every 2nd, 4th, ... sample: white noise gives
   the same value, correlated noise a larger one at larger strides.  The
   statistics then use the smallest stride whose estimate reaches
   :data:`NOISE_PLATEAU` of the largest, i.e. samples that are approximately
   independent.  These estimates are taken on the residual of the whole
   library fitted at once, so that the smooth part of a missing effect does
   not leak into them, and the level is made local (heteroscedastic noise,
   :func:`local_sigma`);
3. **direction of motion** by a reversal detector with a dead band of
   :data:`REVERSAL_SIGMAS` x the contraction noise (a noisy contraction
   rate would flip sign at every sample): +1 contracting, -1 extending,
   held through rests (a stopped actuator keeps the friction of its last
   motion), 0 before any motion; speed by a centred difference over a
   window long enough for the noise;
4. **candidates** (:mod:`.actuator_candidates`), **ranking and forward
   selection** with refit under the arm workflow's naming rule
   (:mod:`.linear_selection`), **unexplained** when the final residual RMS
   exceeds ``rho_max`` x the noise, and **where**: the final residual per
   direction of motion, pressure level, contraction level and time segment.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..._validation import check_range, as_float_array
from ...data.measured import MeasuredData
from ..core.linear_selection import fit_linear, forward_selection_linear
from ..core.noise import interpolation_sigma, MAD_GAUSS
from ..core.record import longest_segment
from ..core.result import HIGH_CONFIDENCE, Diagnosis
from .candidates import build_extensions, ACTUATOR_VOCABULARY

#: Minimum samples of the diagnosed segment.
MIN_SAMPLES = 30
#: Dead band of the reversal detector, in contraction noise standard deviations.
REVERSAL_SIGMAS = 12.0
#: Stride of approximately independent samples: the smallest whose noise estimate reaches
#: this fraction of the largest estimate over the strides 1, 2, 4, ... (white noise gives
#: the same value at every stride, filtered noise a growing one up to its correlation time).
NOISE_PLATEAU = 0.85
#: A stride is tried only if it leaves at least this many samples.
MIN_STRIDE_SAMPLES = 400
#: Samples this many contraction noise levels around a reversal point have an ambiguous
#: direction of motion and are left out of the statistics.
AMBIGUOUS_SIGMAS = 6.0
#: A sample after a turning point within this many contraction noise levels of it still
#: rests there (keeps the old direction of motion).
REST_SIGMAS = 6.0
#: Pressures whose 95th/5th percentile ratio is below this are "one level": a force or
#: pressure sensor offset is then exactly in the span of a refitted force law.
PRESSURE_LEVELS_RATIO = 1.3
#: Window of the rolling noise level [samples used by the statistics].
LOCAL_WINDOW = 301
#: Fewest reversals of the motion for a history effect (friction, hysteresis) to be named
#: with high confidence: two full loops.
MIN_REVERSALS_HIGH = 4
HISTORY_EFFECTS = ("actuator_friction", "hysteresis")
#: Rule 5 of the naming rule: an effect is named only if its fitted contribution has an
#: RMS of at least this many noise levels (chi2 falls by >= its square per sample).
MIN_EFFECT_RMS = 0.2
#: "high" confidence needs the final residual this close to the noise (RMS ratio): the
#: estimated noise level is good to a few per cent, a model error of half the noise is not.
RHO_HIGH = 1.15
#: Largest stride tried for correlated noise.
MAX_STRIDE = 32


@dataclass(frozen=True, eq=False)
class ActuatorRecord:
    """The arrays of one gap-free actuator record (SI units).

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Time from the first sample [s].
    force : numpy.ndarray, shape (N,)
        Measured force [N].
    pressure : numpy.ndarray, shape (N,)
        Measured gauge pressure [Pa].
    eps : numpy.ndarray, shape (N,)
        Contraction [-].
    a : numpy.ndarray, shape (5,)
        Nominal force-law coefficients a0..a4 of (3.9) [N/Pa].
    l0 : float
        Uncontracted length [m] (NaN when the record does not give it).
    source : str
        File or label.
    rows : tuple of (int, int)
        Row range used.
    """

    t: np.ndarray
    force: np.ndarray
    pressure: np.ndarray
    eps: np.ndarray
    a: np.ndarray
    l0: float
    source: str = "<data>"
    rows: tuple = (0, 0)

    def __len__(self) -> int:
        return self.t.size

    def nominal_force(self) -> np.ndarray:
        """Force of the nominal law (3.9) at the measured p, eps [N]."""
        a, e = self.a, self.eps
        inv = a[0] / e if a[0] != 0.0 else 0.0
        return self.pressure * (inv + a[1] + e * (a[2] + e * (a[3] + e * a[4])))


def actuator_record(data) -> tuple:
    """The longest gap-free segment of an actuator record as an :class:`ActuatorRecord`.

    Parameters
    ----------
    data : MeasuredData
        ``kind = "actuator"`` with force, pressure and contraction or position.

    Returns
    -------
    ActuatorRecord
    list of str
        Notes.
    """
    if not isinstance(data, MeasuredData):
        raise TypeError(f"data must be a MeasuredData, got {type(data).__name__}")
    if data.kind != "actuator":
        raise ValueError(f"{data.source}: data.kind = {data.kind!r}; the test-bench diagnosis "
                         f"needs kind = 'actuator'")

    if data.actuator_type == "cylinder":
        raise ValueError(f"{data.source}: a cylinder record is diagnosed by "
                         f"ppamsafety.diagnose.bench.campaign.diagnose_campaign (diagnose() "
                         f"routes it there); this pipeline is for muscles")
    a0, b0, notes = longest_segment(data)
    n = b0 - a0
    if n < MIN_SAMPLES:
        raise ValueError(f"{data.source}: the diagnosed segment has {n} samples; at least "
                         f"{MIN_SAMPLES} are needed")
    law = data.meta["force_law"]
    a = np.asarray(law["a"], float)
    l0 = float(law["l0"]) if "l0" in law else math.nan
    eps = data.contraction()[a0:b0]
    if data.has("contraction") and data.has("position"):
        notes.append("both contraction and position are given; contraction is used")
    if a[0] != 0.0 and np.any(eps <= 0):
        k = int(np.argmin(eps))
        raise ValueError(f"{data.source}: the force law has an a0/eps term (a0 = {a[0]:g} N/Pa) "
                         f"but the contraction reaches {eps[k]:g} <= 0 (row {a0 + k}); check "
                         f"the contraction/position column and l0")
    t = data.column("t")[a0:b0]
    rec = ActuatorRecord(t=t - t[0], force=data.column("force")[a0:b0],
                         pressure=data.column("pressure")[a0:b0], eps=eps, a=a, l0=l0,
                         source=data.source, rows=(a0, b0))
    return rec, notes


def motion_direction(eps, threshold: float, rest: float = 0.0) -> np.ndarray:
    """Direction of motion with a dead band: +1 contracting, -1 extending, 0 before any motion.

    A reversal is registered when the contraction has come back by more than
    ``threshold`` from its running extremum; the samples up to that extremum,
    and after it the samples still within ``rest`` of it (a rest at the
    turning point, blurred by noise), keep the old direction.  Rests keep the
    direction of the last motion.

    Parameters
    ----------
    eps : array_like, shape (N,)
        Contraction [-].
    threshold : float
        Dead band [-], > 0.
    rest : float
        Contraction within which a sample after the extremum still counts as
        resting at it [-], in [0, threshold).

    Returns
    -------
    numpy.ndarray of int, shape (N,)
    """
    e = as_float_array("eps", eps)
    if e.ndim != 1:
        raise ValueError(f"eps must be 1-D, got shape {e.shape}")
    threshold = check_range("threshold", threshold, 0.0, math.inf, lo_open=True)
    rest = check_range("rest", rest, 0.0, threshold, hi_open=True)
    n = e.size
    d = np.zeros(n, dtype=int)
    cur, start, imax, imin = 0, 0, 0, 0
    for k in range(1, n):
        x = e[k]
        if cur == 0:
            if x > e[imax]:
                imax = k
            if x < e[imin]:
                imin = k
            if x - e[imin] > threshold:
                j = _last_within(e, imin, k, rest)
                cur, start, imax = 1, j + 1, k
            elif e[imax] - x > threshold:
                j = _last_within(e, imax, k, rest)
                cur, start, imin = -1, j + 1, k
        elif cur > 0:
            if x > e[imax]:
                imax = k
            elif e[imax] - x > threshold:
                j = _last_within(e, imax, k, rest)
                d[start:j + 1] = 1
                cur, start, imin = -1, j + 1, k
        else:
            if x < e[imin]:
                imin = k
            elif x - e[imin] > threshold:
                j = _last_within(e, imin, k, rest)
                d[start:j + 1] = -1
                cur, start, imax = 1, j + 1, k
    d[start:] = cur
    return d


def _last_within(e, i, k, rest):
    """Last index in [i, k) whose value is within ``rest`` of e[i]."""
    seg = np.abs(e[i:k] - e[i]) <= rest
    return i + int(np.flatnonzero(seg)[-1])


def monotone_contraction(eps, direction) -> np.ndarray:
    """The contraction made monotone between detected reversals (the Preisach input).

    Within every run of constant direction of motion the least-squares
    monotone fit (isotonic regression: non-decreasing while contracting,
    non-increasing while extending) replaces the noisy samples; before the
    first motion the median of those samples.  The Preisach operator
    registers a reversal at every sign change of its input: fed the raw
    contraction, measurement noise would start a new (flat) branch at almost
    every sample and make W lag its true path.

    Parameters
    ----------
    eps : numpy.ndarray, shape (N,)
        Contraction [-].
    direction : numpy.ndarray of int, shape (N,)
        From :func:`motion_direction`.

    Returns
    -------
    numpy.ndarray, shape (N,)
    """
    from scipy.optimize import isotonic_regression

    out = np.asarray(eps, float).copy()
    edges = np.flatnonzero(np.diff(direction)) + 1
    bounds = np.concatenate([[0], edges, [out.size]])
    for a, b in zip(bounds[:-1], bounds[1:]):
        d = direction[a]
        if d == 0:
            out[a:b] = np.median(out[a:b])
        elif b - a > 1:
            out[a:b] = isotonic_regression(out[a:b], increasing=bool(d > 0)).x
    return out


def segment_speed_ratio(t, eps_monotone, direction) -> float:
    """Ratio of the fastest to the slowest monotone run of the motion.

    A run's speed is its contraction change between 10 % and 90 % of its
    span divided by the time it took (rests at the ends do not count).  1
    means every run had the same speed: viscous friction is then not
    separable from Coulomb friction.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Time [s].
    eps_monotone : numpy.ndarray, shape (N,)
        Contraction made monotone between reversals (:func:`monotone_contraction`).
    direction : numpy.ndarray of int, shape (N,)
        From :func:`motion_direction`.
    """
    edges = np.flatnonzero(np.diff(direction)) + 1
    bounds = np.concatenate([[0], edges, [t.size]])
    v = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        if direction[a] == 0 or b - a < 5:
            continue
        x = eps_monotone[a:b] * direction[a]          # rising in both directions
        lo, hi = x[0], x[-1]
        if not hi > lo:
            continue
        i1 = int(np.searchsorted(x, lo + 0.1 * (hi - lo)))
        i2 = int(np.searchsorted(x, lo + 0.9 * (hi - lo)))
        i2 = min(i2, x.size - 1)
        if i2 > i1:
            v.append((x[i2] - x[i1]) / (t[a + i2] - t[a + i1]))
    if len(v) < 2:
        return 1.0
    return max(v) / min(v)


def reversal_band(eps, direction, band: float) -> np.ndarray:
    """Samples next to a reversal of ``direction`` whose contraction is within ``band`` of it.

    Parameters
    ----------
    eps : numpy.ndarray, shape (N,)
        Contraction [-].
    direction : numpy.ndarray of int, shape (N,)
        From :func:`motion_direction`.
    band : float
        Half-width in contraction [-], >= 0.

    Returns
    -------
    numpy.ndarray of bool, shape (N,)
    """
    n = eps.size
    out = np.zeros(n, bool)
    turns = np.flatnonzero((direction[1:] != direction[:-1]) & (direction[1:] != 0)
                           & (direction[:-1] != 0))
    for k in turns:                       # k: last sample of the old direction (the extremum)
        ref = eps[k]
        j = k
        while j >= 0 and abs(eps[j] - ref) <= band:
            out[j] = True
            j -= 1
        j = k + 1
        while j < n and abs(eps[j] - ref) <= band:
            out[j] = True
            j += 1
    return out


def contraction_rate(t, eps, sigma_eps: float) -> np.ndarray:
    """d eps/dt [1/s] by a centred difference over a window long enough for the noise.

    The half-window h (samples) makes the typical change over 2h samples
    about 20 noise standard deviations.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Time [s].
    eps : numpy.ndarray, shape (N,)
        Contraction [-].
    sigma_eps : float
        Noise of the contraction [-].
    """
    n = eps.size
    inc = float(np.sum(np.abs(np.diff(eps)))) / max(n - 1, 1)
    steady = float(np.abs(eps[-1] - eps[0])) / max(n - 1, 1)
    inc = max(inc - 2 * sigma_eps * 0.8, steady, 1e-300)   # remove the noise's share
    h = int(np.clip(math.ceil(10.0 * sigma_eps / inc), 1, max(1, n // 10)))
    k = np.arange(n)
    lo, hi = np.clip(k - h, 0, n - 1), np.clip(k + h, 0, n - 1)
    return (eps[hi] - eps[lo]) / (t[hi] - t[lo])


def residual_noise(t, r) -> tuple:
    """Noise level of the force residual and the stride of approximately independent samples.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Time [s].
    r : numpy.ndarray, shape (N,)
        Force residual [N].

    Returns
    -------
    sigma : float
        [N].
    stride : int
        Use every ``stride``-th sample for the statistics.
    estimates : dict
        stride -> sigma estimate [N].
    """
    est = {}
    s = 1
    while s <= MAX_STRIDE and r[::s].size >= MIN_STRIDE_SAMPLES:
        est[s] = interpolation_sigma(t[::s], r[::s])
        s *= 2
    if not est:
        est[1] = interpolation_sigma(t, r)
    top = max(est.values())
    chosen = min(k for k, v in est.items() if v >= NOISE_PLATEAU * top)
    sigma = est[chosen]
    scale = float(np.max(np.abs(r))) if r.size else 1.0
    sigma = max(sigma, 1e-9 * max(scale, 1e-300), 1e-300)
    return sigma, chosen, est


def local_sigma(t, r, stride: int = 1) -> np.ndarray:
    """Noise level of every sample of the residual: a rolling robust scale (heteroscedastic noise).

    The pressure noise reaches the residual multiplied by the force function
    (``sigma_p f(eps)``, ten times larger at 5 % than at 25 % contraction for
    the thesis law) and the load-cell noise may depend on the range: one
    number for the whole record would under-weight the quiet parts and
    over-weight the noisy ones, and bias chi2.  The interpolation residuals
    ``d`` of :func:`~.noise.interpolation_sigma` (on every ``stride``-th
    sample) are turned into ``1.4826 median |d|`` over a centred window of
    :data:`LOCAL_WINDOW` samples (at least a quarter of it at the ends),
    interpolated back to every sample and floored at 0.2 x the global level.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Time [s].
    r : numpy.ndarray, shape (N,)
        Force residual [N].
    stride : int
        Stride of approximately independent samples (:func:`residual_noise`).

    Returns
    -------
    numpy.ndarray, shape (N,)
        [N].
    """
    ts, xs = t[::stride], r[::stride]
    w = (ts[2:] - ts[1:-1]) / (ts[2:] - ts[:-2])
    d = np.abs(xs[1:-1] - (w * xs[:-2] + (1.0 - w) * xs[2:])) / np.sqrt(1.0 + w ** 2
                                                                        + (1.0 - w) ** 2)
    glob = MAD_GAUSS * float(np.median(d))
    win = int(min(LOCAL_WINDOW, max(5, d.size // 4)))
    loc = MAD_GAUSS * pd.Series(d).rolling(win, center=True, min_periods=max(3, win // 4)) \
        .median().to_numpy()
    loc = np.where(np.isfinite(loc), loc, glob)
    out = np.interp(t, ts[1:-1], loc)
    floor = max(0.2 * glob, 1e-300)
    return np.maximum(out, floor)


def _where(e, feats, rho_max):
    """Operating regions of significant residual (same columns as the arm's table)."""
    from scipy import stats

    zcrit = stats.norm.isf(0.0005)
    rows = []
    d = feats["direction"]
    groups = {
        "direction of motion": {"contracting (d eps/dt > 0)": d > 0,
                                "extending (d eps/dt < 0)": d < 0, "before any motion": d == 0},
        "pressure level": _terciles(feats["pressure"], "p", 1e-5, "bar"),
        "contraction level": _terciles(feats["eps"], "eps", 100.0, "%"),
        "time segment": {f"t {a:.4g}-{b:.4g} s": m for a, b, m in _segments(feats["t"])},
    }
    for region, gs in groups.items():
        for g, m in gs.items():
            n = int(m.sum())
            if n == 0:
                continue
            mean = float(e[m].mean())
            rms = float(np.sqrt(np.mean(e[m] ** 2)))
            z = mean * math.sqrt(n)
            rows.append({"channel": "force", "region": region, "group": g, "blocks": n,
                         "mean": mean, "rms": rms, "z": z,
                         "significant": bool(abs(z) > zcrit or rms > rho_max)})
    return pd.DataFrame(rows)


def _terciles(x, name, scale, unit):
    a, b = np.quantile(x, [1 / 3, 2 / 3])
    if a == b:
        return {f"{name} = {a * scale:.3g} {unit}": np.ones(x.size, bool)}
    return {f"{name} low (< {a * scale:.3g} {unit})": x < a, f"{name} mid": (x >= a) & (x < b),
            f"{name} high (>= {b * scale:.3g} {unit})": x >= b}


def _segments(t, n=8):
    edges = np.linspace(t.min(), t.max() + 1e-12, n + 1)
    return [(edges[i], edges[i + 1], (t >= edges[i]) & (t < edges[i + 1])) for i in range(n)]


def diagnose_actuator(data, *, candidates=None, alpha: float = 0.01, rho_max: float = 1.5,
                      experiment: str | None = None):
    """Diagnose an actuator (test-bench) record against its nominal force law.

    See the module docstring; the result has the arm's schema
    (``docs/diagnose.md``, tester keys documented there).

    Parameters
    ----------
    data : MeasuredData
        ``kind = "actuator"`` record (:func:`ppamsafety.data.load_measured`).
    candidates : sequence of str, optional, keyword-only
        Subset of :data:`~.candidates.ACTUATOR_VOCABULARY` (default all).
    alpha : float, keyword-only
        Level of the likelihood-ratio test (Bonferroni-divided per step), in (0, 0.5].
    rho_max : float, keyword-only
        Largest residual/noise RMS ratio of an explained record, in [1, 100].
    experiment : str, optional, keyword-only
        Hint that must agree with the metadata when given.

    Returns
    -------
    Diagnosis
    """
    t0 = time.perf_counter()
    check_range("alpha", alpha, 0.0, 0.5, lo_open=True)
    check_range("rho_max", rho_max, 1.0, 100.0)
    if candidates is not None:
        if isinstance(candidates, str) or not all(isinstance(c, str) for c in candidates):
            raise TypeError(f"candidates must be a sequence of names, got {candidates!r}")
        bad = [c for c in candidates if c not in ACTUATOR_VOCABULARY]
        if bad:
            raise ValueError(f"candidates = {list(candidates)}: {bad} not in the tester "
                             f"vocabulary {list(ACTUATOR_VOCABULARY)}")
    rec, notes = actuator_record(data)
    if experiment is not None and experiment != data.experiment:
        raise ValueError(f"experiment = {experiment!r} does not match the record's metadata "
                         f"experiment = {data.experiment!r}")
    notes = list(data.notes) + notes
    f_nom = rec.nominal_force()
    r = rec.force - f_nom
    sigma_eps = max(interpolation_sigma(rec.t, rec.eps), 1e-12)
    span = float(np.ptp(rec.eps))
    thr = max(REVERSAL_SIGMAS * sigma_eps, 1e-9)
    direction = motion_direction(rec.eps, thr, REST_SIGMAS * sigma_eps)
    rate = contraction_rate(rec.t, rec.eps, sigma_eps)
    if math.isfinite(rec.l0):
        speed, speed_unit = rate * rec.l0, "m/s"
    else:
        speed, speed_unit = rate, "1/s"
        notes.append("no l0 in the force law: speeds are contraction rates [1/s] and a viscous "
                     "friction coefficient is in N s")
    turns = int(np.count_nonzero(np.diff(direction[direction != 0]))) if np.any(direction) else 0
    if turns < MIN_REVERSALS_HIGH:
        notes.append(f"only {turns} reversal(s) of the motion (< {MIN_REVERSALS_HIGH}): "
                     f"hysteresis and friction, which show at reversals, are hard to tell from "
                     f"a slow drift on this record and are reported with low confidence at most")
    p_lo, p_hi = np.quantile(rec.pressure, [0.05, 0.95])
    one_level = not (p_lo > 0 and p_hi / p_lo >= PRESSURE_LEVELS_RATIO)
    eps_mono = monotone_contraction(rec.eps, direction)
    ctx = {"eps": rec.eps, "pressure": rec.pressure, "f_nom": f_nom, "direction": direction,
           "speed": speed, "speed_unit": speed_unit, "a": rec.a, "eps_monotone": eps_mono,
           "speed_ratio": segment_speed_ratio(rec.t, eps_mono, direction),
           "eps_span_sigmas": float(np.subtract(*np.quantile(rec.eps, [0.95, 0.05])))
           / sigma_eps}
    exts, enotes = build_extensions(ctx, candidates)
    notes += enotes
    # the noise level is estimated on the residual of the full library (every applicable
    # candidate fitted at once, unweighted): smooth structure of a missing effect must not
    # leak into the estimate at the larger strides
    r_full = r
    if exts:
        A = np.concatenate([x.columns for x in exts.values()], axis=1)
        sc = np.sqrt(np.sum(A ** 2, axis=0))
        sc[sc == 0] = 1.0
        coef, *_ = np.linalg.lstsq(A / sc, r, rcond=None)
        r_full = r - (A / sc) @ coef
    sigma, stride, est = residual_noise(rec.t, r_full)
    if stride > 1:
        listed = ", ".join(f"{v:.3g} N at stride {k}" for k, v in est.items())
        notes.append(f"the residual noise is correlated (estimates {listed}): the statistics "
                     f"use every {stride}th sample")
    ambiguous = reversal_band(rec.eps, direction, AMBIGUOUS_SIGMAS * sigma_eps)
    idx = np.arange(0, len(rec), stride)
    if direction.any():
        # before the first motion the friction force is unknown (anything within +-c)
        ambiguous = ambiguous | (direction == 0)
    idx = idx[~ambiguous[idx]]
    if ambiguous.any():
        notes.append(f"{int(ambiguous.sum())} sample(s) before the first motion or within "
                     f"{AMBIGUOUS_SIGMAS:g} contraction noise levels of a reversal point "
                     f"(direction of motion ambiguous) are left out of the statistics")
    if idx.size < MIN_SAMPLES:
        raise ValueError(f"{data.source}: only {idx.size} samples remain for the statistics; "
                         f"at least {MIN_SAMPLES} are needed")
    sig = local_sigma(rec.t, r_full, stride)
    e0 = r[idx] / sig[idx]
    cols = {n: x.columns[idx] / sig[idx, None] for n, x in exts.items()}
    t1 = time.perf_counter()

    def admissible(fit, name):
        sl = fit.slices[name]
        return exts[name].admissible(fit.phi[sl], fit.cov[sl, sl])

    nominal = fit_linear(e0, cols, [])
    fit, steps = forward_selection_linear(e0, cols, admissible, alpha=alpha,
                                          max_effects=len(exts),
                                          min_gain_per_equation=MIN_EFFECT_RMS ** 2)
    t2 = time.perf_counter()
    rho = fit.rho()
    effects, partial = [], []
    for s in steps:
        if s.chosen is None:
            continue
        row = next(x for x in s.table if x["name"] == s.chosen)
        sl = fit.slices[s.chosen]
        params = exts[s.chosen].values(fit.phi[sl], fit.cov[sl, sl])
        ev = {k: row[k] for k in ("delta_bic", "lr_stat", "lr_df", "p_value", "cv_gain")}
        ev["evidence_ratio_log10"] = row.get("evidence_ratio_log10")
        ev["subsystem_rho"] = {"force": rho}
        entry = {"name": s.chosen, "subsystem": "force", "parameters": params, "evidence": ev,
                 "confidence": row["bic_weight"]}
        (effects if rho <= rho_max else partial).append(entry)
    unexplained = bool(rho > rho_max)
    if one_level and "force_law_refit" in fit.names:
        notes.append("the pressure takes essentially one level (95th/5th percentile ratio < "
                     f"{PRESSURE_LEVELS_RATIO}): a refitted force law cannot be told from a "
                     "force- or pressure-sensor offset, so force_law_refit is reported with low "
                     "confidence; record several pressures to separate them")
    if "force_law_refit" in fit.names:
        # issue 19 item 3: a force-sensor gain and a pressure-sensor gain scale the force the
        # same way as a refitted law's level; the record cannot tell them apart
        notes.append("force_law_refit: the part of the refit that scales the whole force "
                     "function (p f(eps) times a constant) is confounded with a force-sensor "
                     "gain and a pressure-sensor gain; to separate them: a dead-weight check of "
                     "the load cell and a reference gauge on the pressure port")
    for e in effects:
        sl = fit.slices[e["name"]]
        moved = exts[e["name"]].moved(fit.phi[sl], fit.cov[sl, sl])
        ok = (e["confidence"] >= HIGH_CONFIDENCE and not unexplained and moved
              and rho <= RHO_HIGH)
        if e["name"] == "force_law_refit" and one_level:
            ok = False
        if e["name"] in HISTORY_EFFECTS and turns < MIN_REVERSALS_HIGH:
            ok = False
        e["confidence_level"] = "high" if ok else "low"
    for e in partial:
        e["confidence_level"] = "low"
    # the diagnosed force on every sample (the fit's coefficients, all samples)
    f_after = f_nom.copy()
    for n in fit.names:
        f_after += exts[n].columns @ fit.phi[fit.slices[n]]
    e_all_before = r / sig
    e_all_after = (rec.force - f_after) / sig
    rr = {"force": {"unit": "N", "before": float(np.sqrt(np.mean(r ** 2))),
                    "after": float(np.sqrt(np.mean((rec.force - f_after) ** 2))),
                    "noise": float(np.sqrt(np.mean(sig ** 2)))},
          "block_force": {"unit": "N / noise (residual ratio, samples used by the statistics)",
                          "before": nominal.rho(), "after": rho, "noise": 1.0}}
    feats = {"t": rec.t[idx], "direction": direction[idx], "pressure": rec.pressure[idx],
             "eps": rec.eps[idx]}
    where = _where(fit.e, feats, rho_max)
    bad = ["force"] if unexplained else []
    if unexplained:
        sigw = where[where["significant"]]
        worst = sigw.reindex(sigw["z"].abs().sort_values(ascending=False).index).head(3)
        where_txt = "; ".join(f"{r_.region}: {r_.group} (mean {r_.mean:+.2f} noise)"
                              for r_ in worst.itertuples()) or "everywhere"
        notes.append(f"force residual {rho:.2f} x the noise (> {rho_max}): no effect of the "
                     f"tester library explains it; largest where {where_txt}")
    settings = {"kind": "actuator", "alpha": alpha, "rho_max": rho_max,
                "criterion": "BIC (known noise level), LR test p < alpha/K, 2-fold CV gain, "
                             "parameters inside widened bounds (dissipative ones not < 0), "
                             f"effect RMS >= {MIN_EFFECT_RMS} x noise",
                "min_effect_rms": MIN_EFFECT_RMS, "rho_high": RHO_HIGH,
                "high_confidence": HIGH_CONFIDENCE,
                "candidates": list(ACTUATOR_VOCABULARY if candidates is None else candidates),
                "candidates_applicable": list(exts), "samples": int(len(rec)),
                "samples_used": int(idx.size), "stride": int(stride),
                "dt_s_median": float(np.median(np.diff(rec.t))), "rows": list(rec.rows),
                "noise_estimate": {"force_residual_N": float(sigma),
                                   "force_residual_local_N": [float(sig.min()),
                                                              float(np.median(sig)),
                                                              float(sig.max())],
                                   "by_stride_N": {str(k): float(v) for k, v in est.items()},
                                   "contraction": float(sigma_eps)},
                "noise_method": "robust interpolation residual: 1.4826 MAD(x[k] - (w x[k-1] + "
                                "(1-w) x[k+1]))/sqrt(1 + w^2 + (1-w)^2); per sample: rolling "
                                f"median over {LOCAL_WINDOW} samples (local_N: min, median, "
                                "max)",
                "reversal_threshold": float(thr), "reversals": turns,
                "pressure_one_level": bool(one_level),
                "speed_ratio": float(ctx["speed_ratio"]),
                "contraction_span": span, "speed_unit": speed_unit,
                "force_law": {"a": [float(x) for x in rec.a],
                              "l0": float(rec.l0) if math.isfinite(rec.l0) else None,
                              "name": data.meta["force_law"].get("name", "")},
                "data": {"kind": data.kind, "experiment": data.experiment,
                         "description": data.meta.get("description", "")}}
    timings = {"residuals_and_noise": t1 - t0, "selection": t2 - t1,
               "total": time.perf_counter() - t0}
    return Diagnosis(source=data.source, effects=effects, partial=partial,
                     unexplained=unexplained, unexplained_channels=bad, residual_rms=rr,
                     where=where, steps=steps,
                     replay={"t": rec.t, "eps": rec.eps, "pressure": rec.pressure,
                             "direction": direction, "measured": rec.force, "before": f_nom,
                             "after": f_after},
                     settings=settings, timings=timings, notes=tuple(notes),
                     blocks={"t": rec.t, "before": e_all_before[:, None],
                             "after": e_all_after[:, None], "eps": rec.eps},
                     kind="actuator")


__all__ = ["ActuatorRecord", "actuator_record", "motion_direction", "contraction_rate",
           "residual_noise", "diagnose_actuator", "REVERSAL_SIGMAS", "NOISE_PLATEAU"]
