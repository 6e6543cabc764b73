"""Preisach hysteresis of the PPAM force function (thesis §3.6, eqs. (3.31)-(3.35)).

Tolerances: the Everett function is evaluated by an 8-point Gauss-Legendre
rule on pieces <= 0.5 (absolute error <= 3e-15, see ppamsafety.hysteresis.everett),
so identities that hold in exact arithmetic are checked to 1e-12 (a few
hundred additions of O(1) terms); properties that hold because the same
floating-point operations are repeated (return-point memory, wiping-out,
rate independence) are checked bitwise; comparisons with scipy's adaptive
dblquad (requested to 1e-12) use 1e-8, the brief's requirement.
"""

import math

import numpy as np
import pytest
from scipy import integrate

from ppamsafety.hysteresis import (DELTA_25_FIBRES, DELTA_40_FIBRES, EPS_MAX, MAX_DEPTH, MEMORY,
                                   STATE_LENGTH, THESIS_WEIGHT, PreisachWeight, everett,
                                   hysteresis_factor, initial_memory, major_loop,
                                   preisach_output, preisach_peek, preisach_response,
                                   preisach_update, scaled_contraction, scaled_input, w_fit)
from ppamsafety.hysteresis.tensile import (DEFAULT_FORCE_LAW, fit_delta, force_law_value,
                                           full_contraction, simulate_tensile_test)
from ppamsafety.layouts import REGISTRY
from ppamsafety.params.muscles import TABLE_B1_N_PER_BAR
from ppamsafety.units import BAR

EXACT = 1e-12


def _dense(points, per_segment=7):
    """Piecewise-linear input through ``points`` with ``per_segment`` samples per segment."""
    out = [points[0]]
    for a, b in zip(points[:-1], points[1:]):
        out.extend(np.linspace(a, b, per_segment + 1)[1:])
    return np.array(out)


def _mu(a, b, w=THESIS_WEIGHT):
    """Scalar (3.33), normalised; the two cases written out as in the thesis."""
    if a + b <= 0:
        return math.exp(-(b - a - w.c) ** 2 - (b + a - w.d) ** 2) / w.z
    return math.exp(-(b - a - w.c) ** 2 - (b + a + w.d) ** 2) / w.z


def _weight_of_box(b_lo, b_hi, a_lo, a_hi):
    """Weight of {b_lo <= beta <= b_hi, max(a_lo, beta) <= alpha <= a_hi} by nested adaptive quad.

    The inner integral is split where alpha + beta = 0 (the kink of (3.33)).
    """
    def inner(b):
        lo = max(a_lo, b)
        if lo >= a_hi:
            return 0.0
        pts = [-b] if lo < -b < a_hi else None
        return integrate.quad(lambda a: _mu(a, b), lo, a_hi, points=pts, epsabs=1e-13,
                              epsrel=1e-13, limit=200)[0]
    pts = [-a_lo, -a_hi]
    pts = [p for p in pts if b_lo < p < b_hi] or None
    return integrate.quad(inner, b_lo, b_hi, points=pts, epsabs=1e-12, epsrel=1e-12,
                          limit=200)[0]


def _asc(u):
    """Ascending major branch from negative saturation: -1 + 2 E(u, -1)."""
    return -1.0 + 2.0 * everett(u, -1.0 + 0.0 * np.asarray(u))


def _desc(u):
    """Descending major branch from positive saturation: 1 - 2 E(1, u)."""
    return 1.0 - 2.0 * everett(1.0 + 0.0 * np.asarray(u), u)


# -- weight and Everett function ------------------------------------------------------------

def test_weight_is_3_33_with_thesis_parameters():
    w = THESIS_WEIGHT
    assert (w.c, w.d) == (-0.1, -1.0)          # thesis §3.6.3, c = -0.1, d = -1
    for a, b in [(0.3, -0.5), (0.5, 0.2), (-0.1, -0.8), (0.9, -0.2)]:
        if a + b <= 0:
            raw = math.exp(-(b - a - w.c) ** 2 - (b + a - w.d) ** 2)
        else:
            raw = math.exp(-(b - a - w.c) ** 2 - (b + a + w.d) ** 2)
        assert w.mu(a, b) == pytest.approx(raw / w.z, rel=1e-14)
    assert w.mu(0.5, 0.6) == 0.0 and w.mu(1.2, 0.0) == 0.0 and w.mu(0.0, -1.2) == 0.0


@pytest.mark.parametrize("alpha,beta", [(1.0, -1.0), (0.3, -0.9), (0.9, 0.1), (-0.2, -0.7),
                                        (0.05, -0.05), (1.0, 0.0), (0.0, -1.0), (0.7, 0.65)])
def test_everett_matches_double_integral(alpha, beta):
    ref = _weight_of_box(beta, alpha, beta, alpha)          # the triangle T(alpha, beta)
    assert everett(alpha, beta) == pytest.approx(ref, abs=1e-8)
    # and scipy's dblquad directly on the thesis formula (no help with the kink)
    ref2, _ = integrate.dblquad(lambda a, b: _mu(a, b), beta, alpha, lambda b: b,
                                lambda b: alpha, epsabs=1e-10, epsrel=1e-10)
    assert everett(alpha, beta) == pytest.approx(ref2, abs=1e-8)


def test_everett_normalised_and_zero_on_diagonal():
    assert everett(1.0, -1.0) == pytest.approx(1.0, abs=1e-15)
    assert np.all(everett([0.3, -0.5, 1.0], [0.3, -0.5, 1.0]) == 0.0)
    assert np.all(everett([0.1], [0.4]) == 0.0)              # alpha < beta: empty triangle
    # other weights of the family normalise too
    assert everett(1.0, -1.0, weight=PreisachWeight(0.0, -0.5)) == pytest.approx(1.0, abs=1e-14)


# -- operator properties --------------------------------------------------------------------

def test_saturation_values_and_normalisation():
    assert preisach_response([-1.0])[0] == -1.0                  # W(-1) = -1, negative saturation
    assert preisach_response([1.0])[0] == 1.0                    # W(1) = 1
    assert preisach_response([0.999999])[0] == pytest.approx(1.0, abs=1e-5)
    assert preisach_response([1.0], initial="positive")[0] == 1.0
    assert preisach_response([-1.0], initial="positive")[0] == -1.0
    loop = major_loop(400)
    assert loop.W.min() == -1.0 and loop.W.max() == 1.0          # W spans exactly [-1, 1]
    # from negative saturation, rising to u switches on the triangle T(u, -1)
    u = np.array([-0.5, 0.0, 0.4])
    np.testing.assert_allclose(preisach_response(u), _asc(u), atol=EXACT)
    np.testing.assert_allclose(preisach_response(-u, initial="positive"), _desc(-u), atol=EXACT)


def test_monotone_major_branches():
    loop = major_loop(2000)
    up = loop[loop.branch == "ascending"]
    down = loop[loop.branch == "descending"]
    assert np.all(np.diff(up.W) > 0.0)
    assert np.all(np.diff(down.W) < 0.0)
    # the loop is closed and its branches are the closed-form major branches
    assert loop.W.iloc[0] == -1.0 and loop.W.iloc[-1] == -1.0
    np.testing.assert_allclose(up.W, _asc(up.u.to_numpy()), atol=EXACT)
    np.testing.assert_allclose(down.W.iloc[1:], _desc(down.u.to_numpy()[1:]), atol=EXACT)


def test_wiping_out():
    # the extrema 0.8/-0.5, 0.6/-0.2 are wiped out when the input passes 0.9 > 0.8
    hist = _dense([-1.0, 0.8, -0.5, 0.6, -0.2, 0.9])
    w_a, z_a = preisach_response(hist, return_state=True)
    w_b, z_b = preisach_response(_dense([-1.0, 0.9]), return_state=True)
    assert w_a[-1] == w_b[-1]
    n = int(MEMORY.read(z_a, "depth"))
    assert n == int(MEMORY.read(z_b, "depth")) == 1
    # the memories are the same: any later input gives the same output, bit for bit
    later = _dense([0.9, -0.3, 0.5, -0.7, 0.2])
    np.testing.assert_array_equal(preisach_response(later, state=z_a),
                                  preisach_response(later, state=z_b))
    # a partial passage wipes only the inner pair
    _, z_c = preisach_response(_dense([-1.0, 0.8, -0.5, 0.6, -0.2, 0.7]), return_state=True)
    np.testing.assert_array_equal(MEMORY.read(z_c, "extrema")[:3], [-1.0, 0.8, -0.5])
    assert MEMORY.read(z_c, "depth") == 3


def test_return_point_memory():
    outer = _dense([-1.0, 0.7, -0.3], 9)                  # descending branch reversal at -0.3
    loop = _dense([-0.3, 0.35, -0.3], 9)[1:]              # minor loop back to -0.3
    cont = _dense([-0.3, -0.8], 9)[1:]                    # continue the outer branch
    w_loop = preisach_response(np.concatenate([outer, loop, cont]))
    w_ref = preisach_response(np.concatenate([outer, cont]))
    k = outer.size
    assert w_loop[k + loop.size - 1] == w_loop[k - 1]     # back at the reversal value, bitwise
    np.testing.assert_array_equal(w_loop[k + loop.size:], w_ref[k:])   # outer branch continues
    assert np.ptp(w_loop[k:k + loop.size]) > 0.05          # the minor loop did move the output


def test_congruency_of_minor_loops():
    lo, hi = -0.2, 0.4
    loop = _dense([lo, hi, lo], 20)
    hist_a = _dense([-1.0, 0.9, lo])                       # reached from above
    hist_b = _dense([-1.0, 0.5, -0.6, 0.45, lo])           # another history, also descending
    w_a = preisach_response(np.concatenate([hist_a, loop[1:]]))[hist_a.size - 1:]
    w_b = preisach_response(np.concatenate([hist_b, loop[1:]]))[hist_b.size - 1:]
    shift = w_a[0] - w_b[0]
    assert abs(shift) > 0.05                               # different vertical positions ...
    np.testing.assert_allclose(w_a - w_a[0], w_b - w_b[0], atol=EXACT)   # ... same shape


def test_rate_independence():
    rng = np.random.default_rng(7)
    ext = [-1.0, 0.85, -0.6, 0.5, -0.1, 0.3, 0.0, 0.95, -0.9, 0.2]
    coarse = _dense(ext, 3)
    # time-rescaled: same path, variable speed (random number of samples per stretch), with holds
    fine, idx = [coarse[0]], [0]
    for a, b in zip(coarse[:-1], coarse[1:]):
        m = int(rng.integers(1, 40))
        s = np.sort(rng.uniform(0.0, 1.0, m - 1))
        fine.extend(a + (b - a) * s)
        fine.extend([b] * int(rng.integers(1, 3)))           # the input rests a while
        idx.append(len(fine) - 1)
    w_coarse = preisach_response(coarse)
    w_fine = preisach_response(np.array(fine))
    np.testing.assert_array_equal(w_fine[idx], w_coarse)


def test_output_stays_inside_major_loop():
    rng = np.random.default_rng(2009)
    u = np.clip(np.cumsum(rng.normal(0.0, 0.15, 3000)), -1.0, 1.0)
    u[::97] = rng.uniform(-1.0, 1.0, u[::97].size)          # occasional jumps
    w = preisach_response(u)
    assert np.all(w >= _asc(u) - EXACT)
    assert np.all(w <= _desc(u) + EXACT)
    assert np.all(np.abs(w) <= 1.0)
    # the bound is not trivial: the random path visits the interior of the loop
    assert np.mean((w > _asc(u) + 0.05) & (w < _desc(u) - 0.05)) > 0.2


def test_initial_memory_from_history():
    hist = [-1.0, 0.8, -0.4, 0.3]
    u = _dense([0.3, -0.2, 0.6, -0.9], 5)[1:]
    w_given = preisach_response(u, initial=hist)
    w_full = preisach_response(np.concatenate([_dense(hist, 5), u]))[-u.size:]
    np.testing.assert_array_equal(w_given, w_full)
    z = initial_memory(hist)
    np.testing.assert_array_equal(MEMORY.read(z, "extrema")[:3], [-1.0, 0.8, -0.4])
    assert MEMORY.read(z, "input") == 0.3
    # the layout defaults are negative saturation
    np.testing.assert_array_equal(MEMORY.pack(), initial_memory("negative"))


# -- bounded depth ---------------------------------------------------------------------------

def _nested(n, amp=0.9, ratio=0.93):
    """Input that reverses n times with strictly nested, shrinking extrema."""
    ext = [-1.0] + [amp * ratio ** k * (1 if k % 2 == 0 else -1) for k in range(n)]
    return np.array(ext)


@pytest.mark.parametrize("cap", [4, MAX_DEPTH])
def test_depth_overflow_error_bound(cap):
    ext = _nested(cap + 12)
    u = _dense(ext, 5)
    w_cap, z = preisach_response(u, capacity=cap, return_state=True)
    w_ref = preisach_response(u, capacity=1000)
    assert int(z[MEMORY.offset("depth")]) <= cap
    # the dropped pairs are consecutive input extrema (nested input): bound 4 a / z each
    amps = np.abs(np.diff(ext))[cap - 1:]
    bound = 4.0 / THESIS_WEIGHT.z * amps.sum()
    err = np.abs(w_cap - w_ref)
    assert err.max() > 0.0                                   # something was dropped ...
    assert err.max() <= bound                                # ... within the bound
    assert np.all(err[: 5 * cap + 1] == 0.0)                 # exact until the first drop
    # the error disappears once the input leaves the enclosing bracket (wiping-out)
    tail = np.array([0.99, -0.3])
    w1 = preisach_response(tail, state=z, capacity=cap)
    _, z_ref = preisach_response(u, capacity=1000, return_state=True)
    w2 = preisach_response(tail, state=z_ref, capacity=1000)
    np.testing.assert_allclose(w1, w2, atol=EXACT)


def test_single_drop_bound():
    ext = [-1.0, 0.8, -0.6, 0.5, -0.2]                    # 4 extrema stored, reversal at -0.2
    u = np.concatenate([_dense(ext, 5), _dense([-0.2, 0.3, -0.1, 0.45, -0.55, 0.55], 9)[1:]])
    w4 = preisach_response(u, capacity=4)
    wr = preisach_response(u, capacity=100)
    a = 0.5 - (-0.2)                                       # amplitude of the dropped pair
    err = np.abs(w4 - wr)
    assert 0.0 < err.max() <= 4.0 * a / THESIS_WEIGHT.z
    assert err[-1] <= EXACT                                # passed 0.5: wiped out in both


# -- plant leaves ----------------------------------------------------------------------------

def test_plant_leaves_on_flat_state_vector():
    assert STATE_LENGTH == MEMORY.size == 2 + 2 * MAX_DEPTH
    assert REGISTRY["preisach memory"] is MEMORY
    rng = np.random.default_rng(3)
    u1 = np.clip(np.cumsum(rng.normal(0, 0.2, 400)), -1, 1)
    u2 = np.clip(np.cumsum(rng.normal(0, 0.2, 400)), -1, 1)
    off1, off2 = 5, 5 + STATE_LENGTH
    z = np.full(5 + 2 * STATE_LENGTH + 3, 123.0)          # neighbours must stay untouched
    z[off1:off1 + STATE_LENGTH] = initial_memory()
    z[off2:off2 + STATE_LENGTH] = initial_memory()
    w1, w2 = np.empty(400), np.empty(400)
    for i in range(400):
        before = z.copy()
        p1 = preisach_peek(z, u1[i], off1)
        np.testing.assert_array_equal(z, before)           # peek writes nothing
        w1[i] = preisach_update(z, u1[i], off1)
        w2[i] = preisach_update(z, u2[i], off2)
        assert p1 == w1[i]
        assert preisach_output(z, off1) == w1[i]
    np.testing.assert_array_equal(w1, preisach_response(u1))
    np.testing.assert_array_equal(w2, preisach_response(u2))
    assert np.all(z[:off1] == 123.0) and np.all(z[off2 + STATE_LENGTH:] == 123.0)
    # out-of-range input saturates
    assert preisach_update(z, 1.7, off1) == 1.0 and preisach_update(z, -3.0, off1) == -1.0


# -- major loop and W_fit (fig. 3.12) --------------------------------------------------------

def test_major_loop_and_w_fit_like_fig_3_12():
    slope, intercept = w_fit()
    # (3.33) is symmetric under (alpha, beta) -> (-beta, -alpha): the loop is point-symmetric
    # about the origin, so the fitted line goes through it
    assert abs(intercept) < EXACT
    u = np.linspace(-1.0, 1.0, 41)
    np.testing.assert_allclose(_desc(u), -_asc(-u), atol=EXACT)
    # the line joins the loop's ends approximately: W(+-1) = +-1 and the line's slope is
    # close to 1 (the loop is a thin S around the diagonal); a line through the origin
    # that left the loop at u = +-1 by more than 10 % would not be "its linear approximation"
    assert abs(slope - 1.0) < 0.1
    # loop width at u = 0 equals twice the weight of the square beta in [-1, 0], alpha in [0, 1]
    loop = major_loop(4000)
    w_up = loop.W[(loop.branch == "ascending") & (loop.u.abs() < 1e-12)].iloc[0]
    w_dn = loop.W[(loop.branch == "descending") & (loop.u.abs() < 1e-12)].iloc[0]
    square = _weight_of_box(-1.0, 0.0, 0.0, 1.0)
    assert w_dn - w_up == pytest.approx(2.0 * square, abs=1e-8)
    assert w_up < slope * 0.0 + intercept < w_dn            # the line runs inside the loop
    # the fit is converged in the number of samples
    s2, _ = w_fit(8000)
    assert s2 == pytest.approx(slope, abs=1e-6)


def test_force_factor():
    assert (DELTA_25_FIBRES, DELTA_40_FIBRES, EPS_MAX) == (0.139, 0.299, 0.35)   # §3.6.4-3.6.5
    assert hysteresis_factor(0.2, 0.5, 0.4, 1.03, 0.0) == pytest.approx(1 + 0.2 * (0.5 - 0.412))
    assert hysteresis_factor(0.0, 0.9, 0.1, 1.0, 0.0) == 1.0
    assert scaled_contraction(0.175, 0.35) == 0.0
    assert scaled_contraction(-0.1, 0.35) == -1.0 and scaled_contraction(0.5, 0.35) == 1.0
    np.testing.assert_allclose(scaled_input([0.0, 0.35, 0.0875]), [-1.0, 1.0, -0.5])


# -- tensile test and delta fit (§3.6.1, §3.6.5) ---------------------------------------------

@pytest.mark.parametrize("delta", [DELTA_25_FIBRES, DELTA_40_FIBRES])
def test_delta_recovered_noise_free(delta):
    rec = simulate_tensile_test(delta)
    assert rec.force_command.min() == pytest.approx(750 - 1400)     # F = A sin + B, §3.6.1
    assert rec.force_command.max() == pytest.approx(750 + 1400)
    assert rec.t.iloc[-1] == pytest.approx(500.0)                   # one period of 2 pi/omega
    fit = fit_delta(rec.eps, rec.force, rec.attrs["pressure"])
    assert fit.delta == pytest.approx(delta, abs=1e-9)
    assert fit.rms_residual < 1e-9 * fit.rms_residual_nominal + 1e-9
    assert fit.rms_residual_nominal > 1.0                           # N: delta = 0 does not fit


def test_delta_recovered_with_noise():
    # noise of 5 N on the recorded force (a load cell of ~0.2 % of 2150 N full scale)
    rec = simulate_tensile_test(DELTA_25_FIBRES, noise_std=5.0, seed=42, periods=2)
    fit = fit_delta(rec.eps, rec.force, rec.attrs["pressure"])
    # 4 standard errors: fails by chance with probability 6e-5
    assert abs(fit.delta - DELTA_25_FIBRES) < 4.0 * fit.std_error
    assert fit.std_error < 0.01
    assert fit.rms_residual == pytest.approx(5.0, rel=0.1)          # residual = the noise


def test_tensile_model_consistency():
    rec = simulate_tensile_test(0.2, samples_per_period=500)
    p = rec.attrs["pressure"]
    slope, intercept = w_fit()
    model = p * force_law_value(rec.eps) * (1 + 0.2 * (rec.W - (slope * rec.eps_s + intercept)))
    np.testing.assert_allclose(model, rec.force, atol=1e-8)          # N, solve converged
    assert rec.eps.max() == pytest.approx(full_contraction())         # slack at F <= 0
    np.testing.assert_allclose(DEFAULT_FORCE_LAW, np.array(TABLE_B1_N_PER_BAR[0]) / BAR)


# -- validation ------------------------------------------------------------------------------

def test_input_validation():
    with pytest.raises(ValueError, match="u must lie in"):
        preisach_response([0.0, 1.5])
    np.testing.assert_array_equal(preisach_response([0.0, 1.5], clip=True)[-1], 1.0)
    with pytest.raises(ValueError, match="u contains NaN"):
        preisach_response([0.0, np.nan])
    with pytest.raises(ValueError, match="initial"):
        preisach_response([0.0], initial="neutral")
    with pytest.raises(ValueError, match="saturation"):
        preisach_response([0.0], initial=[0.5, 0.2])
    with pytest.raises(TypeError, match="weight"):
        preisach_response([0.0], weight=(-0.1, -1.0))
    with pytest.raises(ValueError, match="capacity"):
        preisach_response([0.0], capacity=1)
    with pytest.raises(ValueError, match="state"):
        preisach_response([0.0], state=np.zeros(5))
    with pytest.raises(ValueError, match="alpha"):
        everett(1.2, 0.0)
    with pytest.raises(ValueError, match="PreisachWeight.c"):
        PreisachWeight(c=float("nan"))
    with pytest.raises(ValueError, match="n must be even"):
        major_loop(101)
    with pytest.raises(ValueError, match="delta"):
        simulate_tensile_test(-0.1)
    with pytest.raises(ValueError, match="eps and force"):
        fit_delta([0.1, 0.2], [1.0], 1.5 * BAR)
    with pytest.raises(ValueError, match="pressure"):
        fit_delta([0.1, 0.2], [1.0, 2.0], -1.0)
    with pytest.raises(ValueError, match="force_law"):
        fit_delta([0.1, 0.2], [1.0, 2.0], BAR, force_law=(1.0, 2.0))
