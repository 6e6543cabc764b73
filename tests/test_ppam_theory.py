"""Theoretical PPAM force/volume functions (ppamsafety.plant.ppam_theory, issue 9).

Reference values and their sources:

* F = -p dV/dl (thesis eq. 2.1) <=> dv0/deps = f_t0: holds exactly in the
  model; checked numerically to 1e-6 relative (brief of issue 9).
* Maximum contraction: thesis §2.2.1 "up to 40% of the muscle's maximum
  length" for the arm's l0/R = 6 muscles -> 0.40 +- 0.01; R -> 0 limit
  1 - (2E(1/2) - K(1/2))/K(1/2) = 0.54305 (complete elliptic integrals, derived
  in the module docstring), approached from below.
* Near eps = 0: f_t0 ~ pi / (l0/R sqrt(6 eps)) (asymptote derived in the module
  docstring); ratio -> 1 with an O(sqrt(eps)) correction.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import ellipe, ellipeinc, ellipk, ellipkinc

from ppamsafety.plant import ppam_theory as pt

S = 6.0


def test_force_volume_identity_2_1():
    """dV/dl = -F/p, i.e. dv0/deps = f_t0, to 1e-6 relative (central differences)."""
    e = np.array([0.02, 0.05, 0.1, 0.2, 0.3, 0.38])
    h = 1e-5
    dv = (pt.v0(e + h, S) - pt.v0(e - h, S)) / (2 * h)
    np.testing.assert_allclose(dv, pt.f_t0(e, S), rtol=1e-6)


def test_closed_form_elliptic_integrals():
    """Quadrature state equals the closed forms with F(psi|m), E(psi|m), m = 1/(2(1+a))."""
    a = np.array([0.0, 0.3, 2.0, 50.0])
    st = pt.shape_state(a, S)
    m = 1.0 / (2.0 * (1.0 + a))
    F, E = ellipkinc(st["psi_R"], m), ellipeinc(st["psi_R"], m)
    np.testing.assert_allclose(st["eps"], 2.0 - 2.0 * E / F, rtol=1e-12, atol=1e-14)
    i1 = np.sqrt((1 + a) / 2) * F
    np.testing.assert_allclose(2 * i1 / np.cos(st["psi_R"]), S, rtol=1e-12)
    np.testing.assert_allclose(st["f_t0"], np.pi * a / (4 * i1 ** 2), rtol=1e-12)


def test_monotonic_decrease_and_zero_at_max():
    emax = pt.max_contraction(S)
    e = np.linspace(0.01, emax, 60)
    f = pt.f_t0(e, S)
    assert np.all(np.diff(f) < 0)
    assert f[-1] == 0.0 and f[-2] > 0
    # volume grows with contraction up to its maximum at eps_max
    v = pt.v0(e, S)
    assert np.all(np.diff(v) > 0)


def test_small_contraction_asymptote():
    """f_t0 -> infinity like pi/(s sqrt(6 eps)) (not 1/eps): ratio -> 1 from above."""
    e = np.array([1e-6, 1e-5, 1e-4])
    r = pt.f_t0(e, S) * S * np.sqrt(6 * e) / np.pi
    assert np.all(np.diff(r) > 0)            # correction shrinks as eps -> 0
    assert abs(r[0] - 1.0) < 5e-3
    assert pt.f_t0(1e-6, S) > 100 * pt.f_t0(0.1, S)
    # volume -> cylinder pi/s^2, the excess (bulge) growing like sqrt(eps)
    dv = pt.v0(np.array([1e-9, 1e-7]), S) - np.pi / S ** 2
    assert np.all(dv > 0) and abs(dv[0] / dv[1] - 0.1) < 0.005


def test_max_contraction_plausible():
    em = [pt.max_contraction(s) for s in (4.0, 6.0, 10.0, 50.0)]
    assert abs(em[1] - 0.40) < 0.01          # thesis §2.2.1: "up to 40%"
    assert np.all(np.diff(em) > 0)
    limit = 1 - (2 * ellipe(0.5) - ellipk(0.5)) / ellipk(0.5)
    assert 0.54 < limit < 0.545 and em[-1] < limit and limit - em[-1] < 0.03


def test_polynomial_fit_2_3():
    """The (2.3) fit reproduces f_t0 within 0.01 (abs; 2 % rel) over the default range."""
    lo, hi = pt.DEFAULT_FIT_RANGE
    c = pt.fit_polynomial(S)
    e = np.linspace(lo, hi, 97)
    fit = c[0] / e + c[1] + c[2] * e + c[3] * e ** 2 + c[4] * e ** 3
    f = pt.f_t0(e, S)
    assert np.max(np.abs(fit - f)) < 0.01
    assert np.max(np.abs(fit - f) / f) < 0.02
    assert pt.fit_polynomial(S) is c         # cached


def test_theoretical_muscles_coefficients():
    from ppamsafety.params import thesis_muscles
    from ppamsafety.plant.ppam_theory import theoretical_muscles
    ms = theoretical_muscles(slenderness=S, l0=0.06)
    ref = thesis_muscles()
    assert [g.n_muscles for g in ms.groups] == [g.n_muscles for g in ref.groups]
    np.testing.assert_allclose(ms.groups[0].coefficients,
                               0.06 ** 2 * np.array(pt.fit_polynomial(S)), rtol=1e-15)
    assert (ms.eps_min, ms.eps_max) == (ref.eps_min, ref.eps_max)


@pytest.mark.parametrize("call", [
    lambda: pt.f_t0(0.5, S),                 # beyond max contraction
    lambda: pt.f_t0(0.0, S),
    lambda: pt.f_t0(0.1, 0.5),               # slenderness out of range
    lambda: pt.v0(np.nan, S),
    lambda: pt.fit_polynomial(S, (0.3, 0.1)),
    lambda: pt.theoretical_coefficients(S, -1.0),
])
def test_bad_input_raises(call):
    with pytest.raises(ValueError):
        call()


def test_theoretical_max_load_minimum_finite():
    """Max-load map (fig. 2.15) with the theoretical muscles: finite minimum (coarse grid)."""
    from ppamsafety import design
    from ppamsafety.params import thesis_arm
    from ppamsafety.plant.ppam_theory import theoretical_muscles
    arm = thesis_arm().replace(muscles=theoretical_muscles())
    ml = design.max_load_map(arm, links=design.cad_links(), n1=41, n2=41)
    ident = design.max_load_map(thesis_arm(), links=design.cad_links(), n1=41, n2=41)
    assert np.isfinite(ml.minimum)
    assert ml.minimum != ident.minimum
