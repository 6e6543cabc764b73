"""The diagnosis's one least-squares solve and rank rule (``diagnose.core.solve``).

Every record kind (arm, muscle bench, cylinder campaign) fits through these functions; the
oracle is numpy's SVD-based least squares on problems whose rank is unambiguous.
"""

import numpy as np
import pytest

from ppamsafety.diagnose.bench.gram import fit as cluster_fit
from ppamsafety.diagnose.core.gram import Gram, solve as arm_solve
from ppamsafety.diagnose.core.linear_selection import LinearGram
from ppamsafety.diagnose.core.solve import EIG_MIN, lstsq, pinv_psd, solve_normal
from ppamsafety.lstsq import solve_subset


def _problem(seed, m=400, k=6):
    rng = np.random.default_rng(seed)
    # columns of very different scales, as a payload [kg] beside a sensor offset [Pa]
    X = rng.standard_normal((m, k)) * np.logspace(-3, 4, k)
    y = X @ rng.standard_normal(k) + 0.1 * rng.standard_normal(m)
    return X, y


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_full_rank_solution_equals_numpy_lstsq(seed):
    X, y = _problem(seed)
    ref = np.linalg.lstsq(X, y, rcond=None)[0]
    np.testing.assert_allclose(lstsq(X, y), ref, rtol=1e-9)
    np.testing.assert_allclose(solve_normal(X.T @ X, X.T @ y), ref, rtol=1e-8)
    # several right-hand sides at once
    Y = np.column_stack([y, 2 * y])
    np.testing.assert_allclose(lstsq(X, Y)[:, 1], 2 * ref, rtol=1e-9)


def test_nested_columns_give_the_minimum_norm_solution():
    # a column that is another one times a gain: rank k-1, minimum-norm coefficients
    X, y = _problem(3)
    Xn = np.column_stack([X, 3.0 * X[:, 0]])
    ref = np.linalg.lstsq(Xn / np.linalg.norm(Xn, axis=0), y, rcond=1e-6)[0] \
        / np.linalg.norm(Xn, axis=0)
    got = lstsq(Xn, y)
    np.testing.assert_allclose(got, ref, rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(Xn @ got, X @ np.linalg.lstsq(X, y, rcond=None)[0], rtol=1e-8)
    inv, rank = pinv_psd(Xn.T @ Xn, rank=True)
    assert rank == X.shape[1]
    assert np.all(np.isfinite(inv))


def test_rank_rule_is_relative_to_the_unit_diagonal():
    # eigenvalues of the scaled matrix just above and below EIG_MIN of the largest
    for ratio, kept in ((100 * EIG_MIN, 2), (0.01 * EIG_MIN, 1)):
        A = np.diag([1.0, ratio])
        B = np.array([[1.0, np.sqrt(1 - ratio)], [np.sqrt(1 - ratio), 1.0]])
        _, rank = pinv_psd(np.diag([1e4, 1e-4]) @ B @ np.diag([1e4, 1e-4]), rank=True)
        assert rank == kept, (ratio, rank)
        assert pinv_psd(A, rank=True)[1] == 2          # a diagonal matrix is never deficient


def test_empty_problems():
    assert solve_normal(np.zeros((0, 0)), np.zeros(0)).shape == (0,)
    assert lstsq(np.zeros((5, 0)), np.ones(5)).shape == (0,)
    inv, rank = pinv_psd(np.zeros((0, 0)), rank=True)
    assert inv.shape == (0, 0) and rank == 0


def test_every_record_kind_fits_through_the_one_solve():
    """The arm's chunk x channel Grams, the muscle bench's fold Grams and the campaign's
    stroke Grams give the same coefficients as the compiled kernel on the same data (to the
    rounding of Grams summed in another order: columns 7 decades apart)."""
    X, y = _problem(4, k=4)
    aug = np.column_stack([X, y])
    A = aug.T @ aug
    ref = np.empty(4)
    solve_subset(A, np.arange(4, dtype=np.int64), ref)
    # arm: one chunk, one channel, sigma 1
    f = arm_solve(A[None], np.arange(4), np.ones(1))
    np.testing.assert_allclose(f.phi, ref, rtol=1e-12)
    # muscle bench
    lg = LinearGram(y, {f"c{j}": X[:, j:j + 1] for j in range(4)})
    np.testing.assert_allclose(lg.fit([f"c{j}" for j in range(4)]).phi, ref, rtol=1e-8)
    # cylinder campaign: strokes as clusters
    cg = Gram.from_samples(X, y, np.ones(y.size), np.arange(y.size) % 7)
    np.testing.assert_allclose(cluster_fit(cg, np.arange(7), np.arange(4)).phi, ref,
                               rtol=1e-8)


def test_one_gram_class_sums_groups_and_keeps_empty_ones():
    X, y = _problem(5, m=60, k=3)
    group = np.repeat([0, 2], 30)                     # group 1 has no samples
    g = Gram.from_samples(X, y, np.full(60, 4.0), group, groups=4)
    assert g.G.shape == (4, 1, 4, 4) and not g.G[1].any() and not g.G[3].any()
    aug = np.column_stack([X, y]) * 2.0               # weights 4: sqrt applied to the rows
    np.testing.assert_allclose(g.summed()[0], aug.T @ aug, rtol=1e-12)
    np.testing.assert_array_equal(g.n, [30, 0, 30, 0])
    np.testing.assert_allclose(g.weight, [120.0, 0.0, 120.0, 0.0])
    fit = cluster_fit(g, np.array([0, 2]), np.arange(3))
    np.testing.assert_allclose(fit.phi, np.linalg.lstsq(X, y, rcond=None)[0], rtol=1e-8)
    assert fit.mse == pytest.approx(fit.chi2 / 240.0)
