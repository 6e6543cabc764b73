"""Widened intervals (ppamsafety.diagnose.core.omitted): closed-form checks on linear
least squares, and the fields the arm and the bench report."""

import numpy as np
import pytest
from scipy import stats

from ppamsafety.diagnose import diagnose, synthesize
from ppamsafety.diagnose.bench.battery import CASES
from ppamsafety.diagnose.bench.synthesize import synthesize_actuator
from ppamsafety.diagnose.core.omitted import (HINT_P, OmittedEffect, omitted_effects,
                                              widened_interval)
from ppamsafety.diagnose.core.solve import pinv_psd

Z95 = stats.norm.isf(0.025)


def _problem(seed, n=400, beta_c=0.0):
    """y = X_M theta + x_c beta_c + unit white noise; x_c correlated with X_M."""
    rng = np.random.default_rng(seed)
    XM = rng.standard_normal((n, 2))
    xc = 0.6 * XM[:, :1] + 0.8 * rng.standard_normal((n, 1))
    theta = np.array([1.0, -2.0])
    y = XM @ theta + beta_c * xc[:, 0] + rng.standard_normal(n)
    return XM, xc, y, theta


def _fit(X, y):
    phi, *_ = np.linalg.lstsq(X, y, rcond=None)
    return phi, y - X @ phi


def test_shift_and_covariance_are_those_of_the_larger_fit():
    """Adding c to M: the coefficients move by ``shift`` and their covariance grows by V,
    exactly (Frisch-Waugh; unit noise, so the covariance is (X^T X)^-1); tolerance 1e-10
    relative (floating point)."""
    XM, xc, y, _ = _problem(1, beta_c=0.3)
    phi_m, e = _fit(XM, y)
    X = np.concatenate([XM, xc], axis=1)
    om = omitted_effects(X.T @ X, X.T @ e, np.arange(2), {"c": np.array([2])})["c"]
    phi_mc, _ = _fit(X, y)
    np.testing.assert_allclose(phi_m + om.shift, phi_mc[:2], rtol=1e-10)
    cov_m = np.linalg.inv(XM.T @ XM)
    cov_mc = np.linalg.inv(X.T @ X)[:2, :2]
    np.testing.assert_allclose(cov_m + om.V, cov_mc, rtol=1e-10)
    # the LR statistic is the decrease of chi2
    chi2_m = np.sum(e ** 2)
    chi2_mc = np.sum((y - X @ phi_mc) ** 2)
    assert om.lr == pytest.approx(chi2_m - chi2_mc, rel=1e-10)
    assert om.k == 1


def test_pinv_psd_is_the_inverse_of_a_regular_matrix():
    rng = np.random.default_rng(0)
    M = rng.standard_normal((5, 5))
    A = M @ M.T + np.diag([1e6, 1, 1e-3, 1, 1])       # badly scaled, regular
    np.testing.assert_allclose(pinv_psd(A) @ A, np.eye(5), atol=1e-8)
    assert pinv_psd(np.zeros((0, 0))).shape == (0, 0)


def test_union_holds_the_fit_interval_and_is_the_fit_interval_without_hints():
    V = np.array([[4.0]])
    quiet = OmittedEffect(V=V, shift=np.array([5.0]), lr=0.1, k=1)     # p = 0.75
    hinted = OmittedEffect(V=V, shift=np.array([5.0]), lr=9.0, k=1)    # p = 0.0027
    assert not quiet.hinted and hinted.hinted
    lo, hi, by = widened_interval(1.0, 0.5, np.array([1.0]), {"q": quiet})
    assert (lo, hi) == pytest.approx((1.0 - Z95 * 0.5, 1.0 + Z95 * 0.5))
    assert by == ()
    lo, hi, by = widened_interval(1.0, 0.5, np.array([1.0]), {"q": quiet, "h": hinted})
    half = Z95 * np.sqrt(0.25 + 4.0)
    assert lo == pytest.approx(1.0 - Z95 * 0.5)
    assert hi == pytest.approx(6.0 + half)
    assert by == ("h",)


def test_coverage_with_an_effect_left_out_of_the_model():
    """A correlated effect below any naming threshold biases the model's coefficient; the
    widened interval covers at about its level where the fit's own does not.  500 seeded
    replicates; binomial tolerance: the fit's own interval covers the biased coefficient
    clearly less than 0.95 (< 0.85), the widened one at least 0.90 (4 binomial standard
    errors under 0.95 is 0.93)."""
    own, wide = [], []
    for seed in range(500):
        XM, xc, y, theta = _problem(seed, n=200, beta_c=0.25)
        phi, e = _fit(XM, y)
        X = np.concatenate([XM, xc], axis=1)
        om = omitted_effects(X.T @ X, X.T @ e, np.arange(2), {"c": np.array([2])})
        se = np.sqrt(np.linalg.inv(XM.T @ XM)[0, 0])
        own.append(abs(phi[0] - theta[0]) <= Z95 * se)
        lo, hi, _ = widened_interval(phi[0], se, np.array([1.0, 0.0]), om)
        wide.append(lo <= theta[0] <= hi)
    assert np.mean(own) < 0.85
    assert np.mean(wide) >= 0.90


def _check_reported(dg):
    assert dg.effects
    for e in dg.effects:
        for d in e.parameters.values():
            assert d.ci_low_noise is not None and isinstance(d.widened_by, tuple)
            # the reported interval holds the fit's own (before the cut at the physical range)
            assert d.raw_interval[0] <= d.ci_low_noise + 1e-12
            assert d.raw_interval[1] >= d.ci_high_noise - 1e-12
    assert "hint" in dg.settings["intervals"]


def test_arm_reports_both_intervals():
    """Each named arm parameter carries the fit's own interval and the reported one."""
    _check_reported(diagnose(synthesize(effects={"payload_mass": 0.3}, seed=3,
                                        duration=8.0), seed=0))


@pytest.mark.filterwarnings("ignore::ppamsafety.data.MeasuredDataWarning")
def test_bench_reports_both_intervals():
    """... and each named muscle-bench parameter."""
    _check_reported(diagnose(synthesize_actuator(CASES["hysteresis"][0], seed=11)))


def test_a_candidate_column_the_model_reproduces_is_dropped_not_inverted():
    """A candidate [3 x_0, w]: its first column copies a model column exactly.  The Schur
    complement's first direction is rounding error; scaled by its own size it used to be
    inverted into an interval millions of times the fit's (review of cd9edef).  It is dropped:
    one degree of freedom, and the interval stays the size the real column w gives."""
    for seed in range(6):
        rng = np.random.default_rng(seed)
        n = 300
        XM = rng.standard_normal((n, 2))
        w = 0.5 * XM[:, 0] + rng.standard_normal(n)
        y = XM @ np.array([1.0, -2.0]) + 0.3 * w + rng.standard_normal(n)
        phi, e = _fit(XM, y)
        X = np.column_stack([XM, 3.0 * XM[:, 0], w])
        om = omitted_effects(X.T @ X, X.T @ e, np.arange(2), {"c": np.array([2, 3])})["c"]
        assert om.k == 1
        ref = omitted_effects(X.T @ X, X.T @ e, np.arange(2), {"w": np.array([3])})["w"]
        np.testing.assert_allclose(om.shift, ref.shift, rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(om.V, ref.V, rtol=1e-6, atol=1e-12)
    # wholly reproduced: nothing to add, the candidate is left out
    X = np.column_stack([XM, 2.0 * XM[:, 1]])
    assert omitted_effects(X.T @ X, X.T @ e, np.arange(2), {"c": np.array([2])}) == {}


def test_widened_interval_refuses_what_is_not_finite():
    om = {"c": OmittedEffect(V=np.array([[np.nan]]), shift=np.array([0.0]), lr=50.0, k=1)}
    with pytest.raises(ValueError, match="'c'"):
        widened_interval(1.0, 0.1, np.array([1.0]), om)
    with pytest.raises(ValueError, match="se = nan"):
        widened_interval(1.0, float("nan"), np.array([1.0]), {})
