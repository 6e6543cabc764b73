r"""Theoretical PPAM force and volume functions f_t0(eps, l0/R), v0(eps, l0/R).

Design-time muscle model of thesis §2.2.2-2.2.3, eqs. (2.2)-(2.5), figs.
2.2-2.4: ``F = p l0^2 f_t0(eps, l0/R)``, ``V = l0^3 v0(eps, l0/R)``.  The
thesis takes it from Daerden & Lefeber (2001) and Verrelst et al. (2006a) and
says only that it is "a system of equations involving elliptic integrals [that]
has to be solved numerically".  Those papers were not available here, so the
model is derived below from the assumptions the thesis states; it is the
N -> infinity ("membrane made entirely of Kevlar") model of Daerden & Lefeber
(2001).  Verrelst's finite-N correction is not implemented: the thesis (§2.2.2)
puts it below 3 % for N > 15 fibres (the arm's muscles have N = 25).

Pure NumPy/SciPy and not in any hot loop: evaluate it at design time, or use
the cached (2.3) fit :func:`fit_polynomial` / :func:`theoretical_coefficients`
(what the thesis did, and what :func:`theoretical_muscles`
feeds to the plant).

Derivation (all symbols SI; gauge pressure p [Pa])
--------------------------------------------------
Axisymmetric membrane of meridional, inextensible fibres of length l0, clamped
at radius R at both ends (x = +-l/2); the pleated membrane carries no hoop
stress.  Let r(x) be the meridian, r_m its largest radius (at x = 0), phi the
angle between the meridian and the axis, t the meridional tension per unit
circumference [N/m], F the pulling force of the muscle [N].

1. Meridional equilibrium with zero hoop stress: d(2 pi r t)/ds = 0, so the
   total fibre tension T = 2 pi r t is the same at every section.
2. Axial equilibrium of the part of the muscle beyond section x (membrane,
   end fitting and the gas in it; the load pulls the fitting with F, the gas
   pushes on the cut with p pi r^2)::

       T cos(phi) = F + p pi r^2,      at x = 0 (phi = 0):  T = F + p pi r_m^2.

   (Differentiating along the meridian gives t * curvature = p: normal
   equilibrium holds too.)  With rho = r / r_m and a = F / (p pi r_m^2)::

       cos(phi) = (a + rho^2) / (1 + a).

3. Substituting rho = cos(psi) (psi = 0 at the equator, psi_R = arccos(R/r_m)
   at the ends) removes the square-root end singularity: with
   D(psi) = sqrt(1 + 2a + cos^2 psi) = sqrt(2 (1 + a)) sqrt(1 - m sin^2 psi),
   m = 1 / (2 (1 + a)),

       half fibre length   l0 / 2 = r_m I1,  I1 = (1 + a) int_0^psi_R dpsi / D
                                                = sqrt((1 + a)/2) F(psi_R | m)
       half muscle length  l / 2  = r_m I2,  I2 = int_0^psi_R (a + cos^2 psi) / D dpsi
                                                = sqrt((1 + a)/2) (2 E(psi_R | m) - F(psi_R | m))
       volume              V = 2 pi r_m^3 I3,  I3 = int_0^psi_R cos^2 psi (a + cos^2 psi) / D dpsi

   with F(.|m), E(.|m) the incomplete elliptic integrals of the first and
   second kind (these are the thesis' "elliptic integrals").
4. For given slenderness s = l0/R and force parameter a >= 0, the end angle
   follows from l0/R = 2 I1 / cos(psi_R) (one monotone equation in psi_R).
   Then, with J = I1 - I2 = int_0^psi_R sin^2 psi / D dpsi (no cancellation)::

       eps  = 1 - l/l0 = J / I1 = 2 - 2 E/F,
       f_t0 = F / (p l0^2) = pi a / (4 I1^2),
       v0   = V / l0^3     = pi I3 / (4 I1^3).

   a = 0 (no force) is the maximum contraction; a -> infinity gives eps -> 0.
   f_t0(eps) is found by solving eps(a) = eps for a.  The integrals are
   evaluated by 48-point Gauss-Legendre quadrature in psi (the integrands are
   analytic on [0, psi_R], since 1 - m sin^2 psi >= 1/2): machine precision;
   the closed elliptic forms are used as a cross-check in the tests.

Consequences (checked in ``tests/test_ppam_theory.py``)
-------------------------------------------------------
* F = -p dV/dl (2.1): dv0/deps = f_t0 holds to quadrature precision, although
  f_t0 and v0 come from the force balance and the shape separately.
* Maximum contraction (a = 0): 2 E(psi_R|1/2) / F(psi_R|1/2) - 1 = 1 - eps_max
  with l0/R = sqrt(2) F(psi_R|1/2)/cos(psi_R); it rises with slenderness
  towards the R -> 0 limit 1 - (2 E(1/2) - K(1/2))/K(1/2) = 0.5431
  (complete integrals).  For l0/R = 6 it is 0.4025 (``max_contraction(6)``), the "up to 40 %"
  of §2.2.1; 0.346 for l0/R = 4, 0.455 for 10, 0.525 for 50.
* Near eps = 0 the bulge grows like sqrt(eps) (inextensible fibres), so the
  exact asymptote is f_t0 ~ pi / (l0/R * sqrt(6 eps)), an eps^(-1/2)
  singularity -- not 1/eps.  The a0/eps term of the fit (2.3) is a fitting
  device that is accurate only over the fitted range (eps >= a few %).

References
----------
Daerden, F. & Lefeber, D. (2001), "The concept and design of pleated pneumatic
artificial muscles", International Journal of Fluid Power 2(3), 41-50.
Verrelst, B. et al. (2006a), second-generation PPAM model with N fibres.
Both as cited by the thesis §2.2.2; equations above derived here, not copied.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .._validation import as_float_array, check_range, check_range_array
from ..params.muscles import MuscleGroup, MuscleSet, thesis_muscles
from ..units import CM

#: Slenderness range accepted (same as :class:`ppamsafety.params.MuscleGroup`).
SLENDERNESS_RANGE = (1.0, 50.0)
#: Smallest contraction evaluated [-]: below it eps = J/I1 loses relative
#: precision in the a -> infinity limit (a ~ l0/R / sqrt(6 eps) > 1e6).
EPS_LOWEST = 1.0e-9
#: Default fit range of (2.3) [-]: the design contraction range of the arm
#: (5 % minimum, 30 % maximum, §2.3.2.4) widened by 2 % points at each end.
DEFAULT_FIT_RANGE = (0.03, 0.32)

_X, _W = np.polynomial.legendre.leggauss(48)
_N_PSI = 60      # bisection steps on psi_R in [0, pi/2]: 2^-60 * pi/2 < 2e-18
_N_B = 64        # bisection steps on b = ln(1 + a)


def _check_s(slenderness) -> float:
    return check_range("slenderness", slenderness, *SLENDERNESS_RANGE)


def _integrals(a, psi):
    """(I1, J, I3) of the module docstring for arrays ``a``, ``psi`` (same shape)."""
    a = np.asarray(a, float)[..., None]
    half = 0.5 * np.asarray(psi, float)[..., None]
    t = half * (_X + 1.0)
    c2 = np.cos(t) ** 2
    inv_d = 1.0 / np.sqrt(1.0 + 2.0 * a + c2)
    w = half * _W
    i1 = (1.0 + a[..., 0]) * np.sum(w * inv_d, -1)
    j = np.sum(w * (1.0 - c2) * inv_d, -1)
    i3 = np.sum(w * c2 * (a + c2) * inv_d, -1)
    return i1, j, i3


def _end_angle(a, s: float):
    """psi_R solving l0/R = 2 I1(a, psi_R) / cos(psi_R) (vectorized bisection)."""
    a = np.asarray(a, float)
    lo = np.zeros_like(a)
    hi = np.full_like(a, 0.5 * np.pi)
    for _ in range(_N_PSI):
        mid = 0.5 * (lo + hi)
        i1 = _integrals(a, mid)[0]
        pos = 2.0 * i1 - s * np.cos(mid) > 0.0
        hi = np.where(pos, mid, hi)
        lo = np.where(pos, lo, mid)
    return 0.5 * (lo + hi)


def shape_state(a, slenderness) -> dict:
    """Muscle state for a given dimensionless force a = F / (p pi r_m^2).

    Parameters
    ----------
    a : array_like
        Force parameter [-], >= 0 (0 = maximum contraction) and <= 1e12.
    slenderness : float
        l0/R [-] in [1, 50].

    Returns
    -------
    dict
        Arrays ``eps`` (contraction [-]), ``f_t0`` [-], ``v0`` [-],
        ``psi_R`` [rad] (end angle parameter, R/r_m = cos psi_R) and
        ``r_max_over_l0`` (largest radius / l0 [-]).
    """
    a = as_float_array("a", a)
    check_range_array("a", np.atleast_1d(a), 0.0, 1e12)
    s = _check_s(slenderness)
    psi = _end_angle(a, s)
    i1, j, i3 = _integrals(a, psi)
    return {"eps": j / i1, "f_t0": np.pi * a / (4.0 * i1 ** 2),
            "v0": np.pi * i3 / (4.0 * i1 ** 3), "psi_R": psi, "r_max_over_l0": 0.5 / i1}


def _eps_of_b(b, s):
    a = np.expm1(b)
    i1, j, _ = _integrals(a, _end_angle(a, s))
    return j / i1


def _solve_a(eps: np.ndarray, s: float) -> np.ndarray:
    """a >= 0 with eps(a) = eps (eps decreases monotonically with a)."""
    lo = np.zeros_like(eps)
    # asymptote a ~ s / sqrt(6 eps) for eps -> 0; 4x margin, checked below
    hi = np.log1p(4.0 * s / np.sqrt(eps) + 4.0)
    if np.any(_eps_of_b(hi, s) > eps):        # pragma: no cover - bracket guard
        raise RuntimeError("ppam_theory: force bracket too small (report this)")
    for _ in range(_N_B):
        mid = 0.5 * (lo + hi)
        big = _eps_of_b(mid, s) > eps        # contraction too large -> more force
        lo = np.where(big, mid, lo)
        hi = np.where(big, hi, mid)
    return np.expm1(0.5 * (lo + hi))


@lru_cache(maxsize=64)
def _max_contraction(s: float) -> float:
    return float(shape_state(0.0, s)["eps"])


def max_contraction(slenderness) -> float:
    """Maximum contraction (zero force, largest volume) of the theoretical PPAM [-].

    Parameters
    ----------
    slenderness : float
        l0/R [-] in [1, 50].

    Returns
    -------
    float
        eps_max(l0/R); 0.4025 for l0/R = 6, tending to 0.5431 as l0/R -> infinity.
    """
    return _max_contraction(_check_s(slenderness))


def _state_of_eps(eps, slenderness):
    s = _check_s(slenderness)
    e = as_float_array("eps", eps)
    emax = _max_contraction(s)
    check_range_array("eps", np.atleast_1d(e), EPS_LOWEST, emax)
    flat = e.ravel()
    a = _solve_a(flat, s)
    st = shape_state(a, s)
    at_max = flat >= emax                    # exactly the zero-force state
    f = np.where(at_max, 0.0, st["f_t0"])
    v = st["v0"]
    shape = e.shape
    return f.reshape(shape), v.reshape(shape)


def f_t0(eps, slenderness):
    """Dimensionless force function f_t0(eps, l0/R) of the theoretical PPAM (2.2), N -> inf.

    F = p l0^2 f_t0 with p the gauge pressure [Pa] and l0 the uncontracted
    membrane length [m].

    Parameters
    ----------
    eps : float or array_like
        Contraction (l0 - l)/l0 [-] in [1e-9, max_contraction(slenderness)].
    slenderness : float
        l0/R [-] in [1, 50].

    Returns
    -------
    float or numpy.ndarray
        f_t0 [-], same shape as ``eps``; 0 at the maximum contraction.
    """
    f = _state_of_eps(eps, slenderness)[0]
    return float(f) if f.ndim == 0 else f


def v0(eps, slenderness):
    """Dimensionless volume function v0(eps, l0/R) = V / l0^3 of the theoretical PPAM (2.4).

    Parameters
    ----------
    eps : float or array_like
        Contraction [-] in [1e-9, max_contraction(slenderness)].
    slenderness : float
        l0/R [-] in [1, 50].

    Returns
    -------
    float or numpy.ndarray
        v0 [-]; tends to pi / slenderness^2 (the cylinder) as eps -> 0.
    """
    v = _state_of_eps(eps, slenderness)[1]
    return float(v) if v.ndim == 0 else v


@lru_cache(maxsize=64)
def _fit(s: float, lo: float, hi: float) -> tuple:
    e = np.linspace(lo, hi, 400)
    f = _state_of_eps(e, s)[0]
    A = np.stack([1.0 / e, np.ones_like(e), e, e ** 2, e ** 3], -1)
    coef = np.linalg.lstsq(A, f, rcond=None)[0]
    return tuple(float(c) for c in coef)


def fit_polynomial(slenderness, eps_range=DEFAULT_FIT_RANGE) -> tuple:
    """Least-squares fit (2.3) f_t0 ~ f0/eps + f1 + f2 eps + f3 eps^2 + f4 eps^3 (cached).

    The fit minimises the absolute error of f_t0 on 400 equally spaced
    contractions of ``eps_range``, as the thesis does once the slenderness is
    chosen (Verrelst et al., 2006a).

    Parameters
    ----------
    slenderness : float
        l0/R [-] in [1, 50].
    eps_range : tuple of 2 float
        (eps_lo, eps_hi) [-] with 1e-3 <= eps_lo < eps_hi <= max_contraction(slenderness).
        Default (0.03, 0.32): the arm's design range 5-30 % (§2.3.2.4) with margin.

    Returns
    -------
    tuple of 5 float
        (f0, f1, f2, f3, f4), dimensionless.
    """
    s = _check_s(slenderness)
    if not isinstance(eps_range, (tuple, list)) or len(eps_range) != 2:
        raise ValueError(f"eps_range must be a pair (eps_lo, eps_hi), got {eps_range!r}")
    emax = _max_contraction(s)
    lo = check_range("eps_range[0]", eps_range[0], 1e-3, emax)
    hi = check_range("eps_range[1]", eps_range[1], 1e-3, emax)
    if not lo < hi:
        raise ValueError(f"eps_range = ({lo:g}, {hi:g}) must be increasing")
    return _fit(s, lo, hi)


def theoretical_coefficients(slenderness, l0, eps_range=DEFAULT_FIT_RANGE) -> tuple:
    """Force-law coefficients (3.9) in N/Pa (= m^2) of the theoretical PPAM: l0^2 * (f0..f4).

    Same convention as :attr:`ppamsafety.params.MuscleGroup.coefficients`:
    F = p (a0/eps + a1 + a2 eps + a3 eps^2 + a4 eps^3) for one muscle.

    Parameters
    ----------
    slenderness : float
        l0/R [-] in [1, 50].
    l0 : float
        Uncontracted membrane length [m] in (0, 1].
    eps_range : tuple of 2 float
        Fit range [-], see :func:`fit_polynomial`.

    Returns
    -------
    tuple of 5 float
        (a0, a1, a2, a3, a4) [m^2].
    """
    s = _check_s(slenderness)
    l0 = check_range("l0", l0, 0.0, 1.0, lo_open=True, unit="m")
    return tuple(l0 ** 2 * c for c in fit_polynomial(s, eps_range))


def theoretical_muscles(slenderness: float = 6.0, l0: float = 6.0 * CM,
                        eps_range=None) -> MuscleSet:
    """The thesis' muscle groups with the theoretical force law instead of Table B.1.

    Same names, n_m = (4, 3, 4, 3) and design limits (5 %, 30 %) as
    :func:`thesis_muscles`, but every group gets the coefficients
    l0^2 * (f0..f4) of the (2.3) fit of the theoretical PPAM force function
    f_t0(eps, l0/R) (Daerden's model, thesis §2.2.2, fig. 2.2), as used at
    design time (§2.3.3.5, fig. 2.15).  See :mod:`ppamsafety.plant.ppam_theory`.

    Parameters
    ----------
    slenderness : float
        l0/R [-] in [1, 50]; thesis: 6 (§2.3.3.1).
    l0 : float
        Uncontracted membrane length [m] in (0, 1]; thesis: 6 cm.
    eps_range : tuple of 2 float, optional
        Contraction range [-] of the (2.3) fit, see
        :func:`ppamsafety.plant.ppam_theory.fit_polynomial`; default
        ``ppam_theory.DEFAULT_FIT_RANGE`` = (0.03, 0.32).

    Returns
    -------
    MuscleSet
        Four groups with the theoretical coefficients [N/Pa].
    """
    coef = theoretical_coefficients(slenderness, l0,
                                    DEFAULT_FIT_RANGE if eps_range is None else eps_range)
    base = thesis_muscles()
    groups = tuple(MuscleGroup(name=g.name, n_muscles=g.n_muscles, coefficients=coef, l0=l0,
                               slenderness=slenderness) for g in base.groups)
    return MuscleSet(groups=groups, eps_min=base.eps_min, eps_max=base.eps_max)


__all__ = ["theoretical_muscles", "f_t0", "v0", "max_contraction", "fit_polynomial", "theoretical_coefficients",
           "shape_state", "DEFAULT_FIT_RANGE", "SLENDERNESS_RANGE", "EPS_LOWEST"]
