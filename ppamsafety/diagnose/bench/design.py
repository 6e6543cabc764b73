"""The whitened design of a muscle record: residual, motion, noise level and candidate columns.

Steps 1-4 of the test-bench diagnosis (:mod:`.pipeline`), shared by the
diagnosis, its detection limits (:mod:`.detection`), its stability check
(:mod:`.stability`) and the scenario battery (:mod:`.scenarios`), so that all
of them see the same samples, weights and columns:

1. **residual** ``r = F_measured - p (a0/eps + a1 + a2 eps + a3 eps^2 + a4 eps^3)``
   with the record's own coefficients (a cylinder: ``a = [0, A, 0, 0, 0]``),
   eps from the ``contraction`` column or ``(l0 - position)/l0``;
2. **direction of motion** by a reversal detector with a dead band of
   :data:`REVERSAL_SIGMAS` x the contraction noise (a noisy contraction
   rate would flip sign at every sample): +1 contracting, -1 extending,
   held through rests (a stopped actuator keeps the friction of its last
   motion), 0 before any motion; speed by a centred difference over a
   window long enough for the noise;
3. **noise level** of r from its high-frequency content
   (:func:`~ppamsafety.diagnose.core.noise.interpolation_sigma`: each sample
   against the line through its neighbours, valid for non-uniform sampling).
   Filtered (correlated) sensor noise is detected by comparing the estimate
   on every sample with the estimate on every 2nd, 4th, ... sample: white
   noise gives the same value, correlated noise a larger one at larger
   strides.  The statistics then use the smallest stride whose estimate
   reaches :data:`NOISE_PLATEAU` of the largest, i.e. samples that are
   approximately independent.  These estimates are taken on the residual of
   the whole library fitted at once, so that the smooth part of a missing
   effect does not leak into them, and the level is made local
   (heteroscedastic noise, :func:`local_sigma`);
4. **candidates** (:mod:`.candidates`): their columns on the samples the
   statistics use (every ``stride``-th, without those whose direction of
   motion is ambiguous), whitened by the local noise level:
   :class:`ActuatorDesign`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd
from scipy.optimize import isotonic_regression, nnls

from ..._validation import check_range, as_float_array
from ...data.measured import MeasuredData
from ..core.noise import interpolation_sigma, MAD_GAUSS
from ..core.record import longest_segment
from ..core.solve import lstsq
from .candidates import build_extensions, force_function

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
#: Largest stride tried for correlated noise.
MAX_STRIDE = 32
#: Median of chi2 with one degree of freedom (of d^2 / sigma^2 for Gaussian noise).
CHI2_1_MEDIAN = 0.454936423119572
#: Half-window of the smoothed pressure of the force-function columns [s]
#: (:func:`smooth_pressure`).
PRESSURE_WINDOW = 0.25
#: The speed's window spans a typical contraction change of this many noise levels (its
#: least-squares slope then has about 0.1 % of the speed's variance as noise: a viscous
#: friction fitted to it is biased low by that share).
RATE_WINDOW_SIGMAS = 40.0



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


def contraction_rate(t, eps, sigma_eps: float, eps_monotone=None, direction=None) -> np.ndarray:
    """d eps/dt [1/s]: the least-squares slope over a window long enough for the noise.

    The slope of the straight line fitted to the samples within h of each one
    (a centred difference of the window's ends has sqrt(n/6) x its noise, n =
    2h + 1: a viscous friction fitted to a noisy speed is biased low by the
    noise's share of the speed's variance, errors in variables).  The
    half-window h (samples) makes the typical change over 2h samples
    about :data:`RATE_WINDOW_SIGMAS` noise standard deviations; with ``direction`` the window never
    crosses a reversal (it is cut at the ends of each run of constant
    direction: a window across a reversal would blur the jump of the speed, which
    a viscous friction turns into a force).  The typical change per sample is the
    mean absolute increment of ``eps_monotone`` (the contraction made monotone
    between reversals: its increments are the motion's, not the noise's); without
    it, the mean absolute increment of ``eps`` less the noise's share (biased when
    the motion per sample is below the noise, as at high sampling rates).

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Time [s].
    eps : numpy.ndarray, shape (N,)
        Contraction [-].
    sigma_eps : float
        Noise of the contraction [-].
    eps_monotone : numpy.ndarray, shape (N,), optional
        :func:`monotone_contraction` of ``eps``.
    direction : numpy.ndarray of int, shape (N,), optional
        :func:`motion_direction` of ``eps``.
    """
    n = eps.size
    steady = float(np.abs(eps[-1] - eps[0])) / max(n - 1, 1)
    if eps_monotone is not None:
        inc = float(np.sum(np.abs(np.diff(eps_monotone)))) / max(n - 1, 1)
    else:
        inc = float(np.sum(np.abs(np.diff(eps)))) / max(n - 1, 1) - 2 * sigma_eps * 0.8
    inc = max(inc, steady, 1e-300)
    h = int(np.clip(math.ceil(0.5 * RATE_WINDOW_SIGMAS * sigma_eps / inc), 1, max(1, n // 10)))
    return window_lines(t, eps, h, direction)[1]


def window_lines(t, x, h: int, direction=None, *, leave_out: bool = False) -> tuple:
    """Straight lines fitted by least squares to the samples within h of each sample.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Time [s].
    x : numpy.ndarray, shape (N,)
        Signal.
    h : int
        Half-window [samples], >= 1.
    direction : numpy.ndarray of int, shape (N,), optional
        :func:`motion_direction`: the windows are cut at the ends of each run of
        constant direction (they never cross a reversal).
    leave_out : bool, keyword-only
        Leave each sample out of its own line (the line's value at a sample is then
        independent of that sample's noise).

    Returns
    -------
    value : numpy.ndarray, shape (N,)
        Each line at its sample's time (the sample itself where the window holds fewer
        than two other samples).
    slope : numpy.ndarray, shape (N,)
        Each line's slope [x/s] (0 where undefined).
    """
    n = x.size
    k = np.arange(n)
    first, last = np.zeros(n, int), np.full(n, n - 1)
    if direction is not None:
        edges = np.flatnonzero(np.diff(direction)) + 1
        bounds = np.concatenate([[0], edges, [n]])
        run = np.repeat(np.arange(bounds.size - 1), np.diff(bounds))
        first, last = bounds[:-1][run], bounds[1:][run] - 1
    lo, hi = np.maximum(k - h, first), np.minimum(k + h, last)
    # window sums from prefix sums (time from the record's middle: no cancellation)
    tc = t - t[n // 2]

    def window_sum(y):
        c = np.concatenate([[0.0], np.cumsum(y)])
        w = c[hi + 1] - c[lo]
        return w - y if leave_out else w
    cnt = (hi - lo + 1 - (1 if leave_out else 0)).astype(float)
    st, sx = window_sum(tc), window_sum(x)
    stt, stx = window_sum(tc * tc), window_sum(tc * x)
    safe = np.maximum(cnt, 1.0)
    den = stt - st * st / safe
    slope = np.zeros(n)
    ok = (cnt >= 2) & (den > 1e-12 * np.maximum(stt, 1e-300))
    slope[ok] = (stx[ok] - st[ok] * sx[ok] / cnt[ok]) / den[ok]
    value = np.array(x, dtype=float)
    some = cnt >= 1
    value[some] = sx[some] / cnt[some] + slope[some] * (tc[some] - st[some] / cnt[some])
    return value, slope


def smooth_pressure(t, p, direction, dt_window: float = None) -> np.ndarray:
    """The pressure through a leave-one-out local line (the argument of the force-function columns).

    The columns of a force gain, a refitted law and the hysteresis term hold the
    pressure; built on the measured one, they would carry its noise, which the
    residual also carries (as ``-n_p f(eps)``), and at one pressure level a
    combination of them would fit that noise (errors in variables).  Each sample's
    value here is the straight line through its neighbours within
    :data:`PRESSURE_WINDOW` seconds, the sample itself left out, the window cut at
    the reversals of the motion (a regulator's pressure steps when the motion
    turns).

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Time [s].
    p : numpy.ndarray, shape (N,)
        Measured pressure [Pa].
    direction : numpy.ndarray of int, shape (N,)
        :func:`motion_direction`.
    dt_window : float, optional
        Half-window [s] (default :data:`PRESSURE_WINDOW`).

    Returns
    -------
    numpy.ndarray, shape (N,)
    """
    w = PRESSURE_WINDOW if dt_window is None else float(dt_window)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    h = max(2, int(round(w / max(dt, 1e-300))))
    return window_lines(t, p, h, direction, leave_out=True)[0]


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


def local_sigma(t, r, stride: int = 1, features=None) -> np.ndarray:
    """Noise level of every sample of the residual (heteroscedastic noise).

    The pressure noise reaches the residual multiplied by the force function
    (``sigma_p f(eps)``, ten times larger at 5 % than at 25 % contraction for
    the thesis law), the contraction noise multiplied by ``p f'(eps)`` (a hundred
    times larger at 3 % than at 10 % for a law with a large a0/eps term), and the
    load-cell noise may depend on the range: one number for the whole record
    would under-weight the quiet parts and over-weight the noisy ones, and bias
    chi2.  The interpolation residuals ``d`` of
    :func:`~ppamsafety.diagnose.core.noise.interpolation_sigma` (on every
    ``stride``-th sample) give it:

    * with ``features`` (the squared sensitivities to each sensor's noise,
      e.g. ``[1, f(eps)^2, (p f'(eps))^2]``): the variance is the non-negative
      least-squares fit of ``d^2`` on them (spikes above 25 x the fit left out
      and refitted once), which follows the contraction within every loop
      whatever the sampling rate, times a slow correction: the rolling median of
      ``d^2`` over the fit (over :data:`LOCAL_WINDOW` samples, divided by the
      median of chi2 with one degree of freedom);
    * without: ``1.4826 median |d|`` over a centred window of
      :data:`LOCAL_WINDOW` samples (at least a quarter of it at the ends).

    Interpolated back to every sample and floored at 0.2 x the global level.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Time [s].
    r : numpy.ndarray, shape (N,)
        Force residual [N].
    stride : int
        Stride of approximately independent samples (:func:`residual_noise`).
    features : numpy.ndarray, shape (N, q), optional
        Non-negative variance features of every sample.

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
    floor = max(0.2 * glob, 1e-300)

    def rolling_median(x):
        out = pd.Series(x).rolling(win, center=True, min_periods=max(3, win // 4)) \
            .median().to_numpy()
        return np.where(np.isfinite(out), out, float(np.median(x)))

    if features is None:
        out = np.interp(t, ts[1:-1], MAD_GAUSS * rolling_median(d))
        return np.maximum(out, floor)
    F = np.asarray(features, float)
    Fs = F[::stride][1:-1]
    sc = np.sqrt(np.mean(Fs ** 2, axis=0))
    sc[sc == 0] = 1.0
    y = d ** 2
    keep = np.ones(y.size, bool)
    for _ in range(2):
        beta, _ = nnls(Fs[keep] / sc, y[keep])
        fitted = np.maximum((Fs / sc) @ beta, floor ** 2)
        keep = y <= 25.0 * fitted
    var_model = np.maximum((F / sc) @ beta, floor ** 2)
    corr = rolling_median(y / fitted) / CHI2_1_MEDIAN
    out = np.sqrt(var_model * np.interp(t, ts[1:-1], corr))
    return np.maximum(out, floor)


@dataclass(frozen=True, eq=False)
class ActuatorDesign:
    """Everything the statistics of a muscle record use (module docstring).

    Attributes
    ----------
    rec : ActuatorRecord
        The diagnosed segment.
    notes : tuple of str
        Notes of the steps so far.
    f_nom : numpy.ndarray, shape (N,)
        Force of the nominal law at the measured p, eps [N].
    r : numpy.ndarray, shape (N,)
        Force residual ``F - f_nom`` [N].
    sigma_eps : float
        Contraction noise [-].
    threshold : float
        Dead band of the reversal detector [-].
    direction : numpy.ndarray of int, shape (N,)
        Direction of motion (:func:`motion_direction`).
    turns : int
        Reversals of the motion.
    one_level : bool
        The pressure takes essentially one level (95th/5th percentile ratio below
        :data:`PRESSURE_LEVELS_RATIO`).
    ctx : dict
        The arrays the candidates are built from (:func:`~.candidates.build_extensions`).
    extensions : dict
        Candidate name -> :class:`~.candidates.Extension` (the applicable ones).
    sigma : float
        Global noise level of the residual [N].
    stride : int
        Every ``stride``-th sample is used.
    estimates : dict
        Stride -> noise estimate [N].
    idx : numpy.ndarray of int, shape (m,)
        The samples the statistics use.
    ambiguous : int
        Samples left out for an ambiguous direction of motion.
    sig : numpy.ndarray, shape (N,)
        Local noise level of every sample [N].
    e0 : numpy.ndarray, shape (m,)
        Whitened nominal residual on ``idx``.
    columns : dict
        Candidate name -> whitened columns on ``idx``, shape (m, k).
    """

    rec: ActuatorRecord
    notes: tuple
    f_nom: np.ndarray = field(repr=False)
    r: np.ndarray = field(repr=False)
    sigma_eps: float
    threshold: float
    direction: np.ndarray = field(repr=False)
    turns: int
    one_level: bool
    ctx: dict = field(repr=False)
    extensions: dict = field(repr=False)
    sigma: float
    stride: int
    estimates: dict
    idx: np.ndarray = field(repr=False)
    ambiguous: int
    sig: np.ndarray = field(repr=False)
    e0: np.ndarray = field(repr=False)
    columns: dict = field(repr=False)

    @property
    def m(self) -> int:
        """Number of equations (samples used)."""
        return int(self.idx.size)

    def on_force(self, force) -> "ActuatorDesign":
        """The design with every force-proportional column (hysteresis) rebuilt on ``force``.

        The hysteresis of (3.35) multiplies the muscle's force; its column is first built
        on the nominal law, and once a refitted law or a gain is fitted, on the law as
        fitted (one Gauss-Newton step of the product delta x law).

        Parameters
        ----------
        force : numpy.ndarray, shape (N,)
            [N].

        Returns
        -------
        ActuatorDesign
        """
        exts = {n: (x.on_force(force) if x.per_force is not None else x)
                for n, x in self.extensions.items()}
        cols = {n: (x.columns[self.idx] / self.sig[self.idx, None]
                    if self.extensions[n].per_force is not None else self.columns[n])
                for n, x in exts.items()}
        return replace(self, extensions=exts, columns=cols)

    def whiten(self, x) -> np.ndarray:
        """A force signal on every sample [N] as whitened equations on the samples used.

        Parameters
        ----------
        x : numpy.ndarray, shape (N,)
        """
        x = np.asarray(x, dtype=float)
        if x.shape != self.r.shape:
            raise ValueError(f"x must have the record's shape {self.r.shape}, got {x.shape}")
        return x[self.idx] / self.sig[self.idx]


def actuator_design(data, candidates=None) -> ActuatorDesign:
    """The whitened design of a muscle record (module docstring).

    Parameters
    ----------
    data : MeasuredData
        ``kind = "actuator"`` record of a muscle.
    candidates : sequence of str, optional
        Subset of :data:`~.candidates.ACTUATOR_VOCABULARY` (default all).

    Returns
    -------
    ActuatorDesign
    """
    rec, notes = actuator_record(data)
    notes = list(data.notes) + notes
    f_nom = rec.nominal_force()
    r = rec.force - f_nom
    sigma_eps = max(interpolation_sigma(rec.t, rec.eps), 1e-12)
    thr = max(REVERSAL_SIGMAS * sigma_eps, 1e-9)
    direction = motion_direction(rec.eps, thr, REST_SIGMAS * sigma_eps)
    eps_mono = monotone_contraction(rec.eps, direction)
    rate = contraction_rate(rec.t, rec.eps, sigma_eps, eps_mono, direction)
    if math.isfinite(rec.l0):
        speed, speed_unit = rate * rec.l0, "m/s"
    else:
        speed, speed_unit = rate, "1/s"
        notes.append("no l0 in the force law: speeds are contraction rates [1/s] and a viscous "
                     "friction coefficient is in N s")
    turns = int(np.count_nonzero(np.diff(direction[direction != 0]))) if np.any(direction) else 0
    p_lo, p_hi = np.quantile(rec.pressure, [0.05, 0.95])
    one_level = not (p_lo > 0 and p_hi / p_lo >= PRESSURE_LEVELS_RATIO)
    p_smooth = smooth_pressure(rec.t, rec.pressure, direction)
    f_smooth = p_smooth * force_function(rec.a, eps_mono) if not (
        rec.a[0] != 0.0 and np.any(eps_mono <= 0)) else f_nom
    ctx = {"eps": rec.eps, "pressure": rec.pressure, "p_smooth": p_smooth, "f_nom": f_nom,
           "f_smooth": f_smooth,
           "direction": direction,
           "speed": speed, "speed_unit": speed_unit, "a": rec.a, "eps_monotone": eps_mono,
           "speed_ratio": segment_speed_ratio(rec.t, eps_mono, direction),
           "eps_span_sigmas": float(np.subtract(*np.quantile(rec.eps, [0.95, 0.05])))
           / sigma_eps, "one_level": one_level}
    exts, enotes = build_extensions(ctx, candidates)
    notes += enotes
    # the noise level is estimated on the residual of the full library (every applicable
    # candidate fitted at once, unweighted): smooth structure of a missing effect must not
    # leak into the estimate at the larger strides
    r_full = r
    if exts:
        A = np.concatenate([x.columns for x in exts.values()], axis=1)
        r_full = r - A @ lstsq(A, r)
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
    a = rec.a
    em = np.maximum(eps_mono, 1e-9) if a[0] != 0.0 else eps_mono
    fprime = (-a[0] / em ** 2 if a[0] != 0.0 else 0.0) + a[2] + em * (2 * a[3] + 3 * a[4] * em)
    features = np.column_stack([np.ones_like(r), force_function(a, em) ** 2,
                                (p_smooth * fprime) ** 2])
    sig = local_sigma(rec.t, r_full, stride, features)
    e0 = r[idx] / sig[idx]
    cols = {n: x.columns[idx] / sig[idx, None] for n, x in exts.items()}
    return ActuatorDesign(rec=rec, notes=tuple(notes), f_nom=f_nom, r=r, sigma_eps=sigma_eps,
                          threshold=thr, direction=direction, turns=turns,
                          one_level=bool(one_level), ctx=ctx, extensions=exts,
                          sigma=float(sigma), stride=int(stride), estimates=est, idx=idx,
                          ambiguous=int(ambiguous.sum()), sig=sig, e0=e0, columns=cols)


__all__ = ["ActuatorRecord", "ActuatorDesign", "actuator_record", "actuator_design",
           "motion_direction", "monotone_contraction", "segment_speed_ratio", "reversal_band",
           "contraction_rate", "window_lines", "smooth_pressure", "residual_noise",
           "local_sigma", "MIN_SAMPLES", "PRESSURE_WINDOW",
           "REVERSAL_SIGMAS", "NOISE_PLATEAU", "MIN_STRIDE_SAMPLES", "AMBIGUOUS_SIGMAS",
           "REST_SIGMAS", "PRESSURE_LEVELS_RATIO", "LOCAL_WINDOW", "MAX_STRIDE",
           "RATE_WINDOW_SIGMAS"]
