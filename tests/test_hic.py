"""Head Injury Criterion (thesis eq. 6.1): exact fast kernel, closed forms, validation, speed."""

import time

import numpy as np
import pytest

from ppamsafety.impact.hic import (
    _hic_branch_and_bound,
    _hic_unimodal,
    _unimodal_peak,
    half_sine_optimal_width,
    hic,
    hic_bruteforce,
    hic_bruteforce_kernel,
    hic_half_sine,
    hic_kernel,
    hic_rectangular,
)

DT = 1e-5  # impact integration rate [s]
N = 5001  # 50 ms record


def half_sine(n, dt, amp, dur, t0):
    """A sin(pi (t - t0)/T) on [t0, t0 + T], zero elsewhere [g], n samples."""
    x = (np.arange(n) * dt - t0) / dur
    return np.where((x >= 0) & (x <= 1), amp * np.sin(np.pi * np.clip(x, 0, 1)), 0.0)


def window_hic(a, dt, t1, t2):
    """HIC of one sample window by numpy's trapezoid (independent of the kernels)."""
    i, j = round(t1 / dt), round(t2 / dt)
    area = np.trapezoid(a[i:j + 1], dx=dt)
    return (t2 - t1) * (area / (t2 - t1)) ** 2.5


rng = np.random.default_rng(20240611)
SIGNALS = {
    "noise": (rng.random(3000), DT),
    "sparse noise": (rng.random(3000) * (rng.random(3000) < 0.05), DT),
    "half-sine 1 ms at start": (half_sine(N, DT, 80.0, 0.001, 0.0), DT),
    "half-sine 5 ms mid": (half_sine(N, DT, 60.0, 0.005, 0.021), DT),
    "half-sine 15 ms mid": (half_sine(N, DT, 40.0, 0.015, 0.010), DT),
    "half-sine 10 ms cut at end": (half_sine(N, DT, 40.0, 0.010, 0.045), DT),
    "two pulses": (half_sine(N, DT, 50.0, 0.008, 0.005) + half_sine(N, DT, 45.0, 0.004, 0.030), DT),
    "pulse + small 2nd bump": (half_sine(N, DT, 50.0, 0.010, 0.012)
                               + half_sine(N, DT, 8.0, 0.004, 0.025), DT),
    "constant": (np.full(2000, 3.0), DT),
    "shorter than window": (half_sine(1500, DT, 30.0, 0.006, 0.004), DT),
    "coarse noise, window longer than record": (rng.random(200), 1e-3),
}


@pytest.mark.parametrize("name", list(SIGNALS))
def test_hic_equals_bruteforce(name):
    """Fast = brute force over all sample pairs, relative 1e-12 (rounding of the same formula).

    Also the returned value is the HIC of the returned window (numpy trapezoid, 1e-12
    relative) and the window respects 0 < t2 - t1 <= W.
    """
    a, dt = SIGNALS[name]
    fast, ref = hic(a, dt), hic_bruteforce(a, dt)
    assert fast.value == pytest.approx(ref.value, rel=1e-12)
    assert fast.value == pytest.approx(window_hic(a, dt, fast.t1, fast.t2), rel=1e-12)
    assert 0.0 < fast.t2 - fast.t1 <= 0.036 + 1e-12
    assert fast.value > 0.0


def test_random_small_signals_match_bruteforce_exactly():
    """600 seeded random cases (noise, sparse, ties, heavy tails; N, Wn random): rel 1e-12.

    Exercises every pruning rule and the zero-run shrinking against the O(N Wn) reference.
    """
    gen = np.random.default_rng(7)
    for trial in range(600):
        n, wn = int(gen.integers(2, 300)), int(gen.integers(1, 350))
        a = gen.random(n)
        kind = trial % 4
        if kind == 1:
            a *= gen.random(n) < 0.1
        elif kind == 2:
            a = np.round(3 * a) * (gen.random(n) < 0.5)
        elif kind == 3:
            a = 1e3 * a ** 8
        v, i, j = hic_kernel(a, 1e-4, wn)
        v_ref, _, _ = hic_bruteforce_kernel(a, 1e-4, wn)
        assert v == pytest.approx(v_ref, rel=1e-12, abs=0.0), (trial, n, wn)
        assert 1 <= j - i <= wn or v == 0.0


def _random_unimodal(gen, n):
    """A seeded random weakly unimodal record: zero tails, plateaus, ties, spikes, ramps."""
    p = int(gen.integers(0, n))
    rise = np.sort(gen.random(p) * (gen.random(p) < 0.8))
    fall = np.sort(gen.random(n - p) * (gen.random(n - p) < 0.8))[::-1]
    a = np.concatenate([rise, fall])
    kind = int(gen.integers(0, 4))
    if kind == 1:
        a = np.round(4 * a) / 4            # plateaus and exact ties between the two flanks
    elif kind == 2:
        a = 1e3 * a ** 8                   # a sharp spike on long, tiny tails
    elif kind == 3:
        a[a < 0.3] = 0.0                   # a compact pulse inside zero tails
    return a


def test_unimodal_records_take_the_greedy_path_and_match_bruteforce():
    """800 seeded random unimodal records (N, Wn random): the O(N) path = brute force, rel 1e-12.

    Also the dispatcher sends them to :func:`_hic_unimodal` (same value and pair) and the
    branch and bound agrees; the returned pair is a valid window with that value.
    """
    gen = np.random.default_rng(11)
    for trial in range(800):
        n, wn = int(gen.integers(2, 300)), int(gen.integers(1, 350))
        a = _random_unimodal(gen, n)
        p = _unimodal_peak(a)
        assert p >= 0 and a[p] == a.max() and (p == 0 or a[p - 1] < a[p]), trial
        v, i, j = hic_kernel(a, 1e-4, wn)
        assert (v, i, j) == _hic_unimodal(a, 1e-4, wn, p), trial
        v_ref, _, _ = hic_bruteforce_kernel(a, 1e-4, wn)
        v_bb, _, _ = _hic_branch_and_bound(a, 1e-4, wn)
        assert v == pytest.approx(v_ref, rel=1e-12, abs=0.0), (trial, n, wn)
        assert v_bb == pytest.approx(v_ref, rel=1e-12, abs=0.0), (trial, n, wn)
        if v > 0.0:
            assert 1 <= j - i <= wn
            assert v == pytest.approx(window_hic(a, 1e-4, i * 1e-4, j * 1e-4), rel=1e-12)


@pytest.mark.parametrize("a, unimodal", [
    ([0.0, 1.0, 2.0, 2.0, 1.0, 0.0], True),
    ([3.0, 2.0, 1.0], True),
    ([1.0, 2.0, 3.0], True),
    ([0.0, 0.0, 0.0], True),
    ([1.0, 0.0, 1.0], False),
    ([0.0, 2.0, 1.0, 1.5, 0.0], False),
    ([0.0, 1.0, 0.0, 0.0, 1e-300], False),
])
def test_unimodal_peak_detects_single_pulses(a, unimodal):
    """Hand-made records: a second rise, however small, sends the record to branch and bound."""
    p = _unimodal_peak(np.asarray(a))
    assert (p >= 0) == unimodal
    if unimodal:
        assert a[p] == max(a) and all(x < a[p] for x in a[:p])


def test_all_zero_signal_has_hic_zero():
    """a = 0 everywhere: every window has zero area, HIC = 0 exactly."""
    r = hic(np.zeros(N), DT)
    assert r.value == 0.0 == hic_bruteforce(np.zeros(N), DT).value


def test_half_sine_constant_and_optimal_width():
    """g(beta*) = 0.414646 to 6 digits and beta* = 0.670 within 1e-3 (maximisation of g),
    confirmed on an independent grid of 10^6 widths (grid step 1e-6 -> g error ~1e-12)."""
    assert round(hic_half_sine(1.0, 1.0, window=1.0), 6) == 0.414646
    assert half_sine_optimal_width() == pytest.approx(0.670, abs=1e-3)
    beta = np.linspace(1e-6, 1.0, 1_000_000)
    g = beta * (2 * np.sin(np.pi * beta / 2) / (np.pi * beta)) ** 2.5
    assert g.max() == pytest.approx(hic_half_sine(1.0, 1.0, window=1.0), rel=1e-9)
    assert beta[g.argmax()] == pytest.approx(half_sine_optimal_width(), abs=1e-5)


def test_sampled_half_sine_matches_closed_form():
    """T = 5 ms, A = 100 g at dt = 1 us: HIC within 1e-4 relative of 0.414646 A^2.5 T.

    The trapezoid error is O((dt/T)^2) ~ 1e-7 and the window-end quantisation enters to
    second order at the optimum; the window is centred on the peak with width beta* T
    (to 1e-3 T: HIC is flat in the width near the optimum).
    """
    T, t0, dt = 0.005, 0.001, 1e-6
    r = hic(half_sine(8001, dt, 100.0, T, t0), dt)
    assert r.value == pytest.approx(0.414646 * 100.0 ** 2.5 * T, rel=1e-4)
    assert r.value == pytest.approx(hic_half_sine(100.0, T), rel=1e-4)
    assert (r.t2 - r.t1) / T == pytest.approx(half_sine_optimal_width(), abs=1e-3)
    assert (r.t1 + r.t2) / 2 == pytest.approx(t0 + T / 2, abs=2 * dt)


def test_window_limited_half_sine():
    """T = 80 ms > W/beta*: HIC = W (2AT/(pi W) sin(pi W/2T))^2.5 within 1e-4, width = W."""
    T = 0.080
    r = hic(half_sine(10001, DT, 100.0, T, 0.010), DT)
    expected = 0.036 * (2 * 100.0 * T / (np.pi * 0.036) * np.sin(np.pi * 0.036 / (2 * T))) ** 2.5
    assert hic_half_sine(100.0, T) == pytest.approx(expected, rel=1e-14)
    assert r.value == pytest.approx(expected, rel=1e-4)
    assert r.t2 - r.t1 == pytest.approx(0.036, abs=1e-12)


def test_hic15_versus_hic36():
    """Short pulse (beta* T < 15 ms): HIC15 = HIC36 (same window).  Long pulse (30 ms):
    HIC15 < HIC36, HIC15 equals the window-limited closed form (1e-4) and lasts <= 15 ms."""
    short = half_sine(N, DT, 100.0, 0.010, 0.005)
    s15, s36 = hic(short, DT, window=0.015), hic(short, DT)
    assert (s15.value, s15.t1, s15.t2) == (s36.value, s36.t1, s36.t2)
    assert (s15.window, s36.window) == (0.015, 0.036)
    long = half_sine(N, DT, 100.0, 0.030, 0.005)
    r15, r36 = hic(long, DT, window=0.015), hic(long, DT)
    assert r15.value < 0.95 * r36.value
    assert r15.value == pytest.approx(hic_half_sine(100.0, 0.030, window=0.015), rel=1e-4)
    assert r36.value == pytest.approx(hic_half_sine(100.0, 0.030), rel=1e-4)
    assert r15.t2 - r15.t1 <= 0.015 + 1e-12


@pytest.mark.parametrize("T", [0.010, 0.050])
def test_rectangular_pulse(T):
    """a = A on [t0, t0 + T]: A^2.5 min(T, W) within 1e-3, the edge resolution dt/T = 1e-3
    (each edge ramps over one sample interval of dt = 1e-5 s)."""
    a = np.zeros(8001)
    a[1000:1000 + round(T / DT) + 1] = 20.0
    assert hic(a, DT).value == pytest.approx(hic_rectangular(20.0, T), rel=1e-3)
    assert hic_rectangular(20.0, T) == pytest.approx(20.0 ** 2.5 * min(T, 0.036), rel=1e-15)


def test_batch_equals_per_record():
    """2-D input (records along the last axis) gives exactly the per-record results."""
    A = np.stack([SIGNALS[k][0] for k in ("half-sine 5 ms mid", "two pulses",
                                          "pulse + small 2nd bump")] + [np.zeros(N)])
    r = hic(A, DT, window=0.015)
    assert r.value.shape == r.t1.shape == r.t2.shape == (4,)
    for k, row in enumerate(A):
        one = hic(row, DT, window=0.015)
        assert (r.value[k], r.t1[k], r.t2[k]) == (one.value, one.t1, one.t2)
    np.testing.assert_allclose(hic_bruteforce(A, DT, window=0.015).value, r.value, rtol=1e-12)


@pytest.mark.parametrize("args, kwargs, match", [
    ((np.array([0.0, 1.0, -0.5]), DT), {}, "a must be non-negative"),
    ((np.array([0.0, np.nan, 1.0]), DT), {}, "a contains NaN"),
    ((np.ones(10), 0.0), {}, "dt"),
    ((np.ones(10), -1e-5), {}, "dt"),
    ((np.ones(10), DT), {"window": 0.0}, "window"),
    ((np.ones(10), DT), {"window": -0.036}, "window"),
    ((np.ones(10), DT), {"window": 0.5 * DT}, "window"),
    ((np.ones((2, 2, 5)), DT), {}, "a must be 1-D or 2-D"),
    ((np.ones(1), DT), {}, "at least 2 samples"),
])
@pytest.mark.parametrize("func", [hic, hic_bruteforce])
def test_input_validation(func, args, kwargs, match):
    """Bad input raises ValueError naming the argument."""
    with pytest.raises(ValueError, match=match):
        func(*args, **kwargs)


def test_closed_form_validation():
    """Closed forms reject negative amplitude, non-positive duration and window."""
    with pytest.raises(ValueError, match="amplitude"):
        hic_half_sine(-1.0, 0.01)
    with pytest.raises(ValueError, match="duration"):
        hic_rectangular(1.0, 0.0)
    with pytest.raises(ValueError, match="window"):
        hic_half_sine(1.0, 0.01, window=-1.0)


def speedup(a, dt=DT, wn=3600, repeats=5):
    """Best-of-``repeats`` brute-force time / best fast time, after warm-up (perf_counter)."""
    def best(f, k):
        f(a, dt, wn)
        times = []
        for _ in range(k):
            t0 = time.perf_counter()
            f(a, dt, wn)
            times.append(time.perf_counter() - t0)
        return min(times)
    return best(hic_bruteforce_kernel, repeats) / best(hic_kernel, 4 * repeats)


def test_fast_is_20x_faster_than_bruteforce():
    """10 ms half-sine in a 50 ms record at dt = 10 us (N = 5001, W = 3600): >= 20x.

    (Measured ~300x; the 100x requirement is checked by the slow test and the bench.)
    """
    assert speedup(SIGNALS["pulse + small 2nd bump"][0], repeats=3) >= 20.0


@pytest.mark.slow
@pytest.mark.parametrize("name", ["half-sine 1 ms at start", "half-sine 5 ms mid",
                                  "half-sine 15 ms mid", "two pulses", "pulse + small 2nd bump"])
def test_fast_is_100x_faster_than_bruteforce(name):
    """Realistic 50 ms records at dt = 10 us, HIC36: >= 100x (see benchmarks/bench_hic.py)."""
    assert speedup(SIGNALS[name][0]) >= 100.0


def test_head_acceleration_unit_is_standard_gravity():
    """Issue 12 item 8: "g" is standard gravity, 9.80665 m/s^2 exactly (3rd CGPM, 1901).

    A constant contact force F on a free head of mass m gives a = F / (m g0) in g; with
    a rectangular pulse of duration T <= 36 ms, HIC = a^2.5 T (closed form).  With the old
    9.81 the HIC would be (9.81/9.80665)^2.5 - 1 = 8.5e-4 higher, far outside 1e-12.
    """
    from ppamsafety.units import G0

    assert G0 == 9.80665
    F, m, T, dt = 1000.0, 4.5, 0.010, 1e-5
    a_g = F / (m * G0)
    a = np.full(int(round(T / dt)) + 1, a_g)
    assert hic(a, dt).value == pytest.approx(a_g ** 2.5 * T, rel=1e-9)
    assert hic(a, dt).value == pytest.approx(hic_rectangular(a_g, T), rel=1e-9)
