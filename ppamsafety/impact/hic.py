"""Head Injury Criterion (thesis eq. 6.1): exact fast evaluation and closed forms.

For a head acceleration magnitude a(t) >= 0 [g] and a window limit W [s]
(36 ms for HIC36, 15 ms for HIC15)::

    HIC = max_{t1 < t2, t2 - t1 <= W} (t2 - t1) * [ int_{t1}^{t2} a dt / (t2 - t1) ]^2.5

On uniform samples a_k = a(k dt) the integral is the trapezoidal rule, i.e. the
difference of the cumulative trapezoid S (S_0 = 0, S_{k+1} = S_k + dt (a_k + a_{k+1})/2),
and windows are index pairs (i, j) with 1 <= j - i <= Wn.

**Single pulse** (:func:`_hic_unimodal`, chosen by :func:`hic_kernel` when the
samples rise to one maximum and then fall, plateaus allowed: 298 of the
first 300 impacts of ``studies/bench/bench_impact.py``, measured on their
histories).  The window of every length L with the largest area is found by
growing it from the largest trapezoid segment towards the larger neighbour,
so HIC is exact in O(N).

**Any record** (:func:`_hic_branch_and_bound`).  Branch and bound over blocks
I x J = [i0, i1] x [j0, j1] of index pairs.  For every pair in a block, with
area D = S_j - S_i and length L = j - i, HIC = D * m^1.5 = dt L m^2.5 with the
mean m = D / (dt L).  Because a >= 0, S is non-decreasing, so D <= S_j1 - S_i0,
L >= max(j0 - i1, 1), L <= min(j1 - i0, Wn) and m <= min(max a on [i0, j1],
(S_j1 - S_i0) / (dt L_min)); inserting these gives an upper bound for the block
(range maxima come from a sparse table).  Starting from the best window centred
on the peak sample, blocks are split depth-first (higher bound first) and dropped
when their bound cannot beat the best exact value found; blocks of at most
``_LEAF`` pairs are evaluated exactly.  Before bounding, every block is shrunk
to starts i with S_{i+1} > S_i and ends j with S_j > S_{j-1}: moving a window
end across a zero-area segment keeps D and shortens L, so such windows are
dominated (never strictly better) -- this discards the zero record around a
contact pulse at no cost.  Nothing else is approximated, so the result is the
brute-force maximum over all pairs; the bounds are inflated by 1e-12 relative so
that their own rounding cannot discard the maximum.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .._jit import kernel, step_kernel
from .._validation import as_float_array, check_finite_result, check_nonnegative, check_range

_SLACK = 1.0 + 1e-12  # bounds are inflated by this factor against their own rounding
_LEAF = 64  # blocks with at most this many index pairs are evaluated exactly
_STACK = 256  # depth-first stack; it holds <= 2 log2(N) + 2 < 130 blocks for any int64 N
#: Allowed sample spacing of :func:`hic` [s]: 1 ns (a 1 GHz accelerometer; crash measurements
#: sample at 10-20 kHz, SAE J211) to 1000 s (longer than any impact by five orders of
#: magnitude).  A spacing of 1e-300 s would only be a unit mistake.  Windows and pulse
#: durations are at least DT_MIN too (a window longer than the record is fine).
DT_MIN, DT_MAX = 1e-9, 1e3


@kernel
def _window_hic(area, width):
    """HIC of one window of ``area`` [g s] and ``width`` [s]: width * (area/width)^2.5."""
    m = area / width
    return width * m * m * math.sqrt(m)


@kernel
def _cumulative_area(a, dt):
    """Cumulative trapezoid S [g s], S[0] = 0, shape (N,)."""
    s = np.empty(a.shape[0])
    s[0] = 0.0
    for k in range(a.shape[0] - 1):
        s[k + 1] = s[k] + 0.5 * dt * (a[k] + a[k + 1])
    return s


@kernel
def hic_bruteforce_kernel(a, dt, max_window_samples):
    """Reference O(N Wn) HIC: ``(value, i, j)`` over all pairs 1 <= j - i <= Wn.

    ``a`` [g], ``dt`` [s]; returns the first maximising pair in (i, j) order
    and ``(0.0, 0, 0)`` if there is no pair (N < 2 or Wn < 1).

    Parameters
    ----------
    a : ndarray of float64, shape (N,)
        Head acceleration magnitude samples [g], non-negative (not checked
        here; see :func:`hic`).
    dt : float
        Sample spacing [s].
    max_window_samples : int
        Window limit Wn in whole sample intervals (W / dt rounded down).
    """
    n = a.shape[0]
    s = _cumulative_area(a, dt)
    best, bi, bj = -1.0, 0, 0
    for i in range(n - 1):
        for j in range(i + 1, min(i + max_window_samples, n - 1) + 1):
            v = _window_hic(s[j] - s[i], dt * (j - i))
            if v > best:
                best, bi, bj = v, i, j
    return (best, bi, bj) if best >= 0.0 else (0.0, 0, 0)


@kernel
def _positive_segments(s):
    """nxt[k] / prv[k]: first / last segment i >= k / <= k with S[i+1] > S[i] (N / -1 if none)."""
    n = s.shape[0]
    nxt = np.empty(n, np.int64)
    prv = np.empty(n, np.int64)
    last = -1
    for k in range(n):
        if k < n - 1 and s[k + 1] > s[k]:
            last = k
        prv[k] = last
    last = n
    for k in range(n - 1, -1, -1):
        if k < n - 1 and s[k + 1] > s[k]:
            last = k
        nxt[k] = last
    return nxt, prv


@kernel
def _range_max_table(a):
    """Sparse table t[k, p] = max a[p : p + 2^k] and floor-log2 table for O(1) range maxima."""
    n = a.shape[0]
    levels = 1
    while (1 << levels) <= n:
        levels += 1
    t = np.empty((levels, n))
    for p in range(n):      # a loop, not t[0] = a: the array assignment compiles numba's
        t[0, p] = a[p]      # shape-mismatch error formatting (2.4 s of first compilation)
    for k in range(1, levels):
        h = 1 << (k - 1)
        for p in range(n - (1 << k) + 1):
            t[k, p] = max(t[k - 1, p], t[k - 1, p + h])
    lg = np.zeros(n + 1, np.int64)
    for m in range(2, n + 1):
        lg[m] = lg[m // 2] + 1
    return t, lg


@step_kernel
def _clip(i0, i1, j0, j1, wn, nxt, prv):
    """Shrink a block to valid, non-dominated pairs (empty: i0 > i1 or j0 > j1 on return)."""
    i0 = nxt[max(i0, j0 - wn)]
    i1 = prv[min(i1, j1 - 1)]
    if i0 > i1:
        return i0, i1, j0, j1
    j0 = nxt[max(j0, i0 + 1) - 1] + 1
    j1 = prv[min(j1, i1 + wn) - 1] + 1
    return i0, i1, j0, j1


@step_kernel
def _bound(c, s, dt, wn, t, lg, offset):
    """Upper bound of HIC over a clipped block ``c = (i0, i1, j0, j1)``; 0 if it is empty.

    ``t``, ``lg`` is the range-maximum table of ``a[offset:]``.
    """
    i0, i1, j0, j1 = c
    if i0 > i1 or j0 > j1:
        return 0.0
    area = s[j1] - s[i0]
    k = lg[j1 - i0 + 1]
    amax = max(t[k, i0 - offset], t[k, j1 - offset - (1 << k) + 1])
    mean = min(amax, area / (dt * max(j0 - i1, 1)))
    return mean * math.sqrt(mean) * min(area, dt * min(j1 - i0, wn) * mean) * _SLACK


@step_kernel
def _push(blocks, bounds, top, c, b, best):
    """Push block ``c`` with bound ``b`` unless it cannot beat ``best``; return the new top."""
    if b <= best:
        return top
    for q in range(4):
        blocks[top, q] = c[q]
    bounds[top] = b
    return top + 1


@kernel
def _unimodal_peak(a):
    """Index of the first maximum of ``a`` if ``a`` is weakly unimodal, else -1.

    Weakly unimodal: non-decreasing up to the first maximum and non-increasing
    after it (plateaus allowed, zero tails included).
    """
    n = a.shape[0]
    p = 0
    while p + 1 < n and a[p + 1] >= a[p]:
        p += 1
    k = p
    while k + 1 < n and a[k + 1] <= a[k]:
        k += 1
    if k != n - 1:
        return -1
    while p > 0 and a[p - 1] == a[p]:      # the first sample of a top plateau
        p -= 1
    return p


@kernel
def _hic_unimodal(a, dt, max_window_samples, p):
    """Exact HIC of a weakly unimodal record by growing the window greedily: ``(value, i, j)``.

    ``p`` is the index of the first maximum of ``a`` (:func:`_unimodal_peak`).
    The trapezoid segments b_k = (a_k + a_{k+1}) dt / 2 of a unimodal record
    are unimodal (float addition and scaling are monotone).  Starting from the
    largest segment and adding, each time, the larger of the two neighbouring
    segments gives, for every length L, a window whose segments are all at
    least as large as every segment outside it (by induction: outside
    segments decrease away from the window), i.e. the largest area of any
    window of length L.  HIC is the maximum over L <= ``max_window_samples``
    of dt L (area / (dt L))^2.5, so evaluating the greedy window of every
    length gives the brute-force maximum, in O(N) instead of O(N Wn).  The
    area is taken from the cumulative trapezoid as in :func:`hic_bruteforce_kernel`;
    once both neighbours are zero the area can only stay while the width
    grows, so the search stops there.

    Parameters
    ----------
    a : ndarray of float64, shape (N,)
        Head acceleration magnitude samples [g], non-negative, finite and
        weakly unimodal (not checked here; see :func:`hic_kernel`).
    dt : float
        Sample spacing [s].
    max_window_samples : int
        Window limit Wn in whole sample intervals.
    p : int
        Index of the first maximum of ``a``.
    """
    n = a.shape[0]
    wn = min(max_window_samples, n - 1)
    if wn < 1:
        return 0.0, 0, 0
    s = _cumulative_area(a, dt)
    # the largest segment touches the peak sample: [p - 1, p] or [p, p + 1]
    if p == n - 1 or (p > 0 and a[p - 1] > a[p + 1]):
        i = p - 1
    else:
        i = p
    j = i + 1
    best, bi, bj = _window_hic(s[j] - s[i], dt), i, j
    for w in range(2, wn + 1):
        left = a[i - 1] + a[i] if i > 0 else -1.0       # neighbouring segments (x 2 / dt)
        right = a[j] + a[j + 1] if j < n - 1 else -1.0
        if left <= 0.0 and right <= 0.0:
            break
        if left >= right:
            i -= 1
        else:
            j += 1
        v = _window_hic(s[j] - s[i], dt * w)
        if v > best:
            best, bi, bj = v, i, j
    if best == 0.0:
        return 0.0, 0, 1
    return best, bi, bj


@kernel
def hic_kernel(a, dt, max_window_samples):
    """Exact HIC: ``(value, i, j)``; O(N) for unimodal records, else branch and bound.

    A weakly unimodal record (a single pulse, the usual impact) goes to
    :func:`_hic_unimodal`; any other to :func:`_hic_branch_and_bound`.  Both
    give the maximum of :func:`hic_bruteforce_kernel` (the pair may differ on
    exact ties; the value up to the rounding of the cumulative area, which
    grows with the record length: 3e-12 relative among the tied windows of
    20000 equal samples).

    Parameters
    ----------
    a : ndarray of float64, shape (N,)
        Head acceleration magnitude samples [g], non-negative and finite (not
        checked here; see :func:`hic`).
    dt : float
        Sample spacing [s].
    max_window_samples : int
        Window limit Wn in whole sample intervals (W / dt rounded down);
        values above N - 1 act as N - 1.
    """
    if a.shape[0] >= 2:
        p = _unimodal_peak(a)
        if p >= 0:
            return _hic_unimodal(a, dt, max_window_samples, p)
    return _hic_branch_and_bound(a, dt, max_window_samples)


@kernel
def hic_pair_kernel(a, dt, w36, w15, general):
    """HIC36 and HIC15 of one record: ``(hic36, i1, i2, hic15, j1, j2)`` (windows in samples).

    When the HIC36 window spans at most ``w15`` samples it is admissible for
    HIC15 too, so HIC15 equals HIC36 with the same window and is not searched
    again.

    Parameters
    ----------
    a : ndarray of float64, shape (N,)
        Head acceleration magnitude samples [g], non-negative and finite (not
        checked here).
    dt : float
        Sample spacing [s].
    w36, w15 : int
        The window limits 36 ms and 15 ms in whole sample intervals.
    general : bool
        True: always :func:`_hic_branch_and_bound` (the reference engine's
        choice); False: :func:`hic_kernel`.
    """
    if general:
        h36, i1, i2 = _hic_branch_and_bound(a, dt, w36)
    else:
        h36, i1, i2 = hic_kernel(a, dt, w36)
    if i2 - i1 <= w15:
        return h36, i1, i2, h36, i1, i2
    if general:
        h15, j1, j2 = _hic_branch_and_bound(a, dt, w15)
    else:
        h15, j1, j2 = hic_kernel(a, dt, w15)
    return h36, i1, i2, h15, j1, j2


@kernel
def _hic_branch_and_bound(a, dt, max_window_samples):
    """Exact HIC of any record by branch and bound (module docstring): ``(value, i, j)``.

    ``a`` [g] non-negative samples, ``dt`` [s], windows 1 <= j - i <= ``max_window_samples``.
    Same maximum as :func:`hic_bruteforce_kernel` (the pair may differ on exact ties);
    ``(0.0, 0, 1)`` for an all-zero record and ``(0.0, 0, 0)`` if there is no pair.

    Parameters
    ----------
    a : ndarray of float64, shape (N,)
        Head acceleration magnitude samples [g], non-negative and finite (not
        checked here; see :func:`hic`).
    dt : float
        Sample spacing [s].
    max_window_samples : int
        Window limit Wn in whole sample intervals (W / dt rounded down);
        values above N - 1 act as N - 1.
    """
    n = a.shape[0]
    wn = min(max_window_samples, n - 1)
    if wn < 1:
        return 0.0, 0, 0
    s = _cumulative_area(a, dt)
    nxt, prv = _positive_segments(s)
    if nxt[0] >= n - 1:  # no positive area anywhere: every window has HIC 0
        return 0.0, 0, 1
    first, last = nxt[0], prv[n - 2] + 1  # every useful window lies in [first, last]
    t, lg = _range_max_table(a[first:last + 1])
    best, bi, bj = 0.0, 0, 1
    peak = np.argmax(a)
    for w in range(1, min(wn, last - first) + 1):  # lower bound: windows centred on the peak
        i = min(max(peak - w // 2, 0), n - 1 - w)
        v = _window_hic(s[i + w] - s[i], dt * w)
        if v > best:
            best, bi, bj = v, i, i + w
    blocks = np.empty((_STACK, 4), np.int64)
    bounds = np.empty(_STACK)
    # run-time ints, not constants: numba compiles a kernel once per constant argument
    root = _clip(np.int64(0), n - 2, np.int64(1), n - 1, wn, nxt, prv)
    top = _push(blocks, bounds, np.int64(0), root, _bound(root, s, dt, wn, t, lg, first), best)
    while top > 0:
        top -= 1
        if bounds[top] <= best:
            continue
        i0, i1, j0, j1 = blocks[top, 0], blocks[top, 1], blocks[top, 2], blocks[top, 3]
        if (i1 - i0 + 1) * (j1 - j0 + 1) <= _LEAF:
            for i in range(i0, i1 + 1):
                for j in range(max(j0, i + 1), min(j1, i + wn) + 1):
                    v = _window_hic(s[j] - s[i], dt * (j - i))
                    if v > best:
                        best, bi, bj = v, i, j
            continue
        if i1 - i0 >= j1 - j0:  # split the longer side
            m = (i0 + i1) // 2
            lo = _clip(i0, m, j0, j1, wn, nxt, prv)
            hi = _clip(m + 1, i1, j0, j1, wn, nxt, prv)
        else:
            m = (j0 + j1) // 2
            lo = _clip(i0, i1, j0, m, wn, nxt, prv)
            hi = _clip(i0, i1, m + 1, j1, wn, nxt, prv)
        blo, bhi = _bound(lo, s, dt, wn, t, lg, first), _bound(hi, s, dt, wn, t, lg, first)
        if blo > bhi:  # push the more promising half last so that it is explored first
            lo, hi, blo, bhi = hi, lo, bhi, blo
        top = _push(blocks, bounds, top, lo, blo, best)
        top = _push(blocks, bounds, top, hi, bhi, best)
    return best, bi, bj


@kernel
def hic_batch_kernel(A, dt, max_window_samples, out_value, out_i, out_j):
    """:func:`hic_kernel` for every record (row) of ``A``, written to the ``out_*`` arrays.

    Parameters
    ----------
    A : ndarray of float64, shape (R, N), C-contiguous
        R records of N acceleration magnitude samples [g], non-negative.
    dt : float
        Sample spacing [s].
    max_window_samples : int
        Window limit Wn in whole sample intervals.
    out_value : ndarray of float64, shape (R,)
        Output, overwritten: HIC of each record [-].
    out_i, out_j : ndarray of int64, shape (R,)
        Output, overwritten: sample indices of the start and end of each
        maximising window (times ``i dt``, ``j dt``).
    """
    for r in range(A.shape[0]):
        out_value[r], out_i[r], out_j[r] = hic_kernel(A[r], dt, max_window_samples)


@kernel
def _bruteforce_batch_kernel(A, dt, max_window_samples, out_value, out_i, out_j):
    for r in range(A.shape[0]):
        out_value[r], out_i[r], out_j[r] = hic_bruteforce_kernel(A[r], dt, max_window_samples)


@dataclass(frozen=True)
class HICResult:
    """HIC and its maximising window; arrays (one entry per record) for 2-D input.

    Attributes
    ----------
    value : float or ndarray
        HIC [-] (accelerations in g, times in s, as is conventional).
    t1, t2 : float or ndarray
        Start and end of the maximising window [s], measured from the first sample.
    window : float
        Window limit W used [s].
    """

    value: float | np.ndarray
    t1: float | np.ndarray
    t2: float | np.ndarray
    window: float


_LOG_MAX = math.log(np.finfo(float).max)


#: Largest number of windows :func:`hic_bruteforce` evaluates in one call (about 20 s at
#: 10^8 windows per second); :func:`hic` has no such limit (it is linear in the samples).
BRUTEFORCE_MAX_WINDOWS = 2 * 10 ** 9


def _evaluate(single, batch, a, dt, window, max_windows=None) -> HICResult:
    arr = as_float_array("a", a)                # refuses masked arrays with masked entries
    if arr.ndim not in (1, 2) or arr.shape[-1] < 2:
        raise ValueError(f"a must be 1-D or 2-D (records along the last axis) with at least "
                         f"2 samples per record, got shape {arr.shape}")
    if arr.ndim == 2 and arr.shape[0] == 0:
        raise ValueError(f"a holds no record (shape {arr.shape}): give at least one record of "
                         f"shape (N,) or (R, N) with R >= 1")
    if np.any(arr < 0.0):
        k = tuple(int(x) for x in np.argwhere(arr < 0.0)[0])
        raise ValueError(f"a must be non-negative (acceleration magnitudes in g), "
                         f"a[{', '.join(map(str, k))}] = {arr[k]:g}")
    dt = check_range("dt", dt, DT_MIN, DT_MAX, unit="s")
    window = check_range("window", window, DT_MIN, math.inf, unit="s")
    n = arr.shape[-1]
    ratio = window / dt * (1.0 + 1e-9)   # whole sample intervals; 1e-9 absorbs rounding
    if ratio < 1.0:
        raise ValueError(f"window = {window:g} s is shorter than one sample interval dt = {dt:g} s")
    wn = n - 1 if ratio >= n - 1 else math.floor(ratio)   # longer windows cannot occur
    rows = 1 if arr.ndim == 1 else arr.shape[0]
    if max_windows is not None and rows * n * wn > max_windows:
        raise ValueError(f"a ({rows} record(s) of {n:,} samples) with window = {window:g} s "
                         f"({wn:,} samples) has {rows * n * wn:.3g} windows, more than the "
                         f"{max_windows:.3g} the brute force evaluates in one call; use hic() "
                         f"(exact, linear in the samples) or shorter records")
    # HIC <= max(a)^2.5 * (longest window): refuse records whose HIC would overflow float64
    amax = float(arr.max())
    span = min(window, dt * (n - 1))
    if amax > 0.0 and (2.5 * math.log(amax) + math.log(span) > _LOG_MAX - 1.0
                       or math.log(dt) + math.log(amax) + math.log(n) > _LOG_MAX - 1.0):
        raise ValueError(f"a (max {amax:g} g) with dt = {dt:g} s and window = {window:g} s "
                         f"gives a HIC beyond the float64 range")
    if arr.ndim == 1:
        v, i, j = single(np.ascontiguousarray(arr), dt, wn)
        check_finite_result("HIC", v, f"a (max {amax:g} g) and dt = {dt:g} s")
        return HICResult(float(v), i * dt, j * dt, window)
    v = np.empty(arr.shape[0])
    i, j = np.empty(arr.shape[0], np.int64), np.empty(arr.shape[0], np.int64)
    batch(np.ascontiguousarray(arr), dt, wn, v, i, j)
    check_finite_result("HIC", v, f"a (max {amax:g} g) and dt = {dt:g} s")
    return HICResult(v, i * dt, j * dt, window)


def _closed_form(fun, A, T, W) -> float:
    """Evaluate a closed form; overflow -> ValueError naming the arguments."""
    try:
        v = fun()
    except OverflowError:
        v = math.inf
    return float(check_finite_result(
        "HIC", v, f"amplitude = {A:g} g, duration = {T:g} s, window = {W:g} s"))


def hic(a, dt, *, window=0.036) -> HICResult:
    """Head Injury Criterion (6.1) of uniformly sampled acceleration magnitudes, exact.

    Parameters
    ----------
    a : array_like, shape (N,) or (R, N)
        Head acceleration magnitude [g], non-negative, finite, N >= 2; records along the
        last axis.
    dt : float
        Sample spacing [s], in [:data:`DT_MIN`, :data:`DT_MAX`] = [1e-9, 1e3].
    window : float, keyword-only
        Window limit W [s]: 0.036 for HIC36 (default), 0.015 for HIC15; >= 1e-9 (a window
        longer than the record covers the record).  Rounded down to a whole number of
        sample intervals (1e-9 relative tolerance).

    Raises
    ------
    TypeError
        ``a`` not an array of real numbers (strings, bools, complex, None ...), ``dt`` or
        ``window`` not a real number.
    ValueError
        ``a`` with NaN/inf, negative entries, masked entries (a masked array), fewer than
        2 samples, no record (shape (0, N)) or more than 2 dimensions; ``dt``/``window``
        below 1e-9 s, ``dt`` above 1e3 s; ``window < dt``; a record whose HIC would
        overflow float64.

    Returns
    -------
    HICResult
        The maximum over all sample windows (trapezoidal integral), computed by the
        :func:`hic_kernel`; the maximum of :func:`hic_bruteforce` up to the rounding of the
        cumulative area (below 1e-12 relative for records of 10^4 samples; exactly tied
        windows of a long constant record can differ by 1e-11 at 2 x 10^5 samples).
    """
    return _evaluate(hic_kernel, hic_batch_kernel, a, dt, window)


def hic_bruteforce(a, dt, *, window=0.036) -> HICResult:
    """:func:`hic` by brute force over all O(N W/dt) windows (reference for tests and timing).

    Parameters
    ----------
    a : array_like, shape (N,) or (R, N)
        Head acceleration magnitude [g], non-negative, finite, N >= 2; records
        along the last axis.
    dt : float
        Sample spacing [s], in [1e-9, 1e3].
    window : float, keyword-only
        Window limit W [s]: 0.036 for HIC36 (default), 0.015 for HIC15; >= 1e-9.

    Returns
    -------
    HICResult
        As :func:`hic` (same validation and errors); a call of more than
        :data:`BRUTEFORCE_MAX_WINDOWS` windows is refused (``ValueError``).
    """
    return _evaluate(hic_bruteforce_kernel, _bruteforce_batch_kernel, a, dt, window,
                     max_windows=BRUTEFORCE_MAX_WINDOWS)


def _half_sine_g(beta):
    """HIC / (A^2.5 T) of the window of width beta T centred on the peak of a half-sine."""
    return beta * (2.0 * np.sin(np.pi * beta / 2.0) / (np.pi * beta)) ** 2.5


@functools.cache
def _half_sine_optimum() -> tuple[float, float]:
    from scipy.optimize import minimize_scalar

    res = minimize_scalar(lambda b: -_half_sine_g(b), bounds=(1e-9, 1.0), method="bounded",
                          options={"xatol": 1e-12})
    return float(res.x), float(-res.fun)


def half_sine_optimal_width() -> float:
    """Optimal HIC window of a half-sine pulse relative to its duration, beta* = 0.6702.

    beta* maximises g(beta) = beta (2 sin(pi beta/2) / (pi beta))^2.5, see
    :func:`hic_half_sine`; g(beta*) = 0.414646.
    """
    return _half_sine_optimum()[0]


def hic_half_sine(amplitude, duration, *, window=0.036) -> float:
    """HIC of a(t) = A sin(pi t/T) on [0, T] (zero elsewhere), in closed form.

    Derivation: with I the integral over [t1, t2], L = t2 - t1 and mean m = I/L,
    d(L m^2.5)/dt2 = m^1.5 (2.5 a(t2) - 1.5 m) and d(L m^2.5)/dt1 = -m^1.5 (2.5 a(t1)
    - 1.5 m), so an unconstrained optimum has a(t1) = a(t2) = 0.6 m: for the symmetric
    pulse t1 + t2 = T, the window is centred on the peak (windows reaching outside
    [0, T] only gain width, never area).  A centred window of width beta T has
    I = (2 A T/pi) sin(pi beta/2), hence HIC = A^2.5 T g(beta) with
    g(beta) = beta (2 sin(pi beta/2)/(pi beta))^2.5, maximised numerically at
    beta* = 0.6702 (:func:`half_sine_optimal_width`), g(beta*) = 0.414646.  If
    beta* T > W, g increases on (0, beta*) (unimodal, checked numerically), so the best admissible window is the
    widest, W, centred on the peak: HIC = W (2 A T/(pi W) sin(pi W/(2T)))^2.5.

    Parameters
    ----------
    amplitude : float
        Peak acceleration A [g], >= 0.
    duration : float
        Pulse duration T [s], >= 1e-9.
    window : float, keyword-only
        Window limit W [s], >= 1e-9.

    Returns
    -------
    float
        HIC [-].
    """
    A = check_nonnegative("amplitude", amplitude, unit="g")
    T = check_range("duration", duration, DT_MIN, math.inf, unit="s")
    W = check_range("window", window, DT_MIN, math.inf, unit="s")
    beta, g = _half_sine_optimum()
    if beta * T <= W:
        return _closed_form(lambda: g * A ** 2.5 * T, A, T, W)
    return _closed_form(
        lambda: W * (2.0 * A * T / (math.pi * W) * math.sin(math.pi * W / (2.0 * T))) ** 2.5,
        A, T, W)


def hic_rectangular(amplitude, duration, *, window=0.036) -> float:
    """HIC of a rectangular pulse a(t) = A on [0, T], in closed form: A^2.5 min(T, W).

    Derivation: the mean over any window is <= A, so HIC <= A^2.5 L <= A^2.5 W, and a
    window longer than T has I <= A T, so HIC = I^2.5 / L^1.5 < A^2.5 T; a window of
    width min(T, W) inside the pulse attains A^2.5 min(T, W).

    Parameters
    ----------
    amplitude : float
        Pulse acceleration A [g], >= 0.
    duration : float
        Pulse duration T [s], >= 1e-9.
    window : float, keyword-only
        Window limit W [s], >= 1e-9 (default 0.036, HIC36).

    Returns
    -------
    float
        HIC [-].
    """
    A = check_nonnegative("amplitude", amplitude, unit="g")
    T = check_range("duration", duration, DT_MIN, math.inf, unit="s")
    W = check_range("window", window, DT_MIN, math.inf, unit="s")
    return _closed_form(lambda: A ** 2.5 * min(T, W), A, T, W)
