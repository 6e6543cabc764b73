"""PPAM force law (3.9) and the volume function derived from it.

Force of one muscle (all muscles of a group are in series, so this is also
the group force)::

    F = p f(eps),   f(eps) = max(0, a0/eps + a1 + a2 eps + a3 eps^2 + a4 eps^3)

with p the gauge pressure [Pa] and f in N/Pa = m^2.  The polynomial fit goes
negative beyond full contraction; a muscle cannot push, so f is clipped at
zero (the contraction where this happens, ``EPS_F0`` in the packed vector, is
where the volume is maximal).

Volume.  The thesis gives no volume coefficients (2.5).  Eq. (2.1),
F = -p dV/dl with l = l0 (1 - eps), gives for one muscle::

    dV/deps = l0 F/p = l0 f(eps)

so V(eps) = V(eps_a) + l0 * integral_{eps_a}^{eps} f, integrated in closed
form (a0 ln(eps/eps_a) + a1 (eps - eps_a) + ...).  The anchor V(eps_a) is
explained in :func:`anchor_volume`.  A group of
n_m muscles holds n_m V.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from .._jit import kernel, kernel_array, leaf
from .._validation import as_float_array, check_int
from . import layout as lay
from ._checks import accelerations, angles, check_pressures, checks_arm, speeds, torques  # noqa: F401
from .layout import COEF, EPS_F0, EPS_FLOOR, L0, V_C


# --- the force polynomial (3.9): the one implementation --------------------------------
# Everything that evaluates the polynomial, its derivative or its antiderivative -- the
# plant kernels below and, through :func:`polynomial` / :func:`antiderivative`, the
# pack-time derived data in :mod:`ppamsafety.plant.layout` and the design studies --
# goes through these three leaves.

@leaf
def poly_value(a0, a1, a2, a3, a4, e):
    """a0/e + a1 + a2 e + a3 e^2 + a4 e^3 [N/Pa] (Horner form), unclipped.

    The force polynomial of (3.9) without the clipping at zero.

    Parameters
    ----------
    a0, a1, a2, a3, a4 : float
        Force-law coefficients of (3.9), Table B.1 [N/Pa = m^2].
    e : float
        Contraction eps [-]; must be nonzero (a0/e).
    """
    return a0 / e + a1 + e * (a2 + e * (a3 + e * a4))


@leaf
def poly_slope(a0, a1, a2, a3, a4, e):
    """Derivative of :func:`poly_value` with respect to e [N/Pa].

    Parameters
    ----------
    a0, a1, a2, a3, a4 : float
        Force-law coefficients of (3.9), Table B.1 [N/Pa = m^2]
        (``a1`` does not enter the derivative).
    e : float
        Contraction eps [-]; must be nonzero.
    """
    return -a0 / (e * e) + a2 + e * (2.0 * a3 + 3.0 * e * a4)


@leaf
def poly_integral(a0, a1, a2, a3, a4, e):
    """Antiderivative of :func:`poly_value` without the constant (log form) [N/Pa].

    a0 ln e + a1 e + a2 e^2/2 + a3 e^3/3 + a4 e^4/4.

    Parameters
    ----------
    a0, a1, a2, a3, a4 : float
        Force-law coefficients of (3.9), Table B.1 [N/Pa = m^2].
    e : float
        Contraction eps [-]; must be positive (ln e).
    """
    e2 = e * e
    return (a0 * math.log(e) + a1 * e + a2 * e2 / 2.0
            + a3 * e2 * e / 3.0 + a4 * e2 * e2 / 4.0)


@leaf
def _poly(k, e, P):
    b = COEF + 5 * k
    return poly_value(P[b], P[b + 1], P[b + 2], P[b + 3], P[b + 4], e)


@leaf
def force_per_pressure(k, eps, P):
    """f_k(eps) of group ``k`` [N/Pa]: muscle force per unit gauge pressure.

    The force law (3.9), clipped at zero at and beyond the zero-force
    contraction ``eps_f0`` and evaluated at ``EPS_FLOOR`` below that floor.

    Parameters
    ----------
    k : int
        Muscle group index 0..3 (thesis groups 1..4).
    eps : float
        Contraction of a muscle of the group [-].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads the group's ``coef`` [N/Pa] and ``eps_f0`` [-] fields.
    """
    e = max(eps, EPS_FLOOR)
    if e >= P[EPS_F0 + k]:
        return 0.0
    return max(_poly(k, e, P), 0.0)


@leaf
def dforce_deps(k, eps, P):
    """d f_k / d eps [N/Pa] (zero where f is clipped).

    Also zero below the contraction floor ``EPS_FLOOR``, where
    :func:`force_per_pressure` is held constant.

    Parameters
    ----------
    k : int
        Muscle group index 0..3 (thesis groups 1..4).
    eps : float
        Contraction of a muscle of the group [-].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads the group's ``coef`` [N/Pa] and ``eps_f0`` [-] fields.
    """
    e = max(eps, EPS_FLOOR)
    if e >= P[EPS_F0 + k] or eps < EPS_FLOOR or _poly(k, e, P) <= 0.0:
        return 0.0
    b = COEF + 5 * k
    return poly_slope(P[b], P[b + 1], P[b + 2], P[b + 3], P[b + 4], e)


@leaf
def integral(k, e, P):
    """Antiderivative of the force polynomial of group ``k`` without the constant [N/Pa].

    :func:`poly_integral` with the group's coefficients (unclipped).

    Parameters
    ----------
    k : int
        Muscle group index 0..3 (thesis groups 1..4).
    e : float
        Contraction [-]; must be positive.
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads the group's ``coef`` field [N/Pa].
    """
    b = COEF + 5 * k
    return poly_integral(P[b], P[b + 1], P[b + 2], P[b + 3], P[b + 4], e)


@leaf
def muscle_volume(k, eps, P):
    """Volume of one muscle of group ``k`` at contraction ``eps`` [m^3].

    Satisfies dV/deps = l0 f_k(eps) exactly (also in the clipped regions:
    constant beyond the zero-force contraction, linear below the floor).

    Parameters
    ----------
    k : int
        Muscle group index 0..3 (thesis groups 1..4).
    eps : float
        Contraction of a muscle of the group [-].
    P : ndarray of float64, shape (NP,)
        Packed plant parameter row (:data:`ppamsafety.plant.layout.PLANT`);
        reads the group's ``coef`` [N/Pa], ``eps_f0`` [-], ``v_c`` [m^3] and
        ``l0`` [m] fields.
    """
    e = min(max(eps, EPS_FLOOR), P[EPS_F0 + k])
    v = P[V_C + k] + P[L0 + k] * integral(k, e, P)
    if eps < EPS_FLOOR:
        v += P[L0 + k] * force_per_pressure(k, EPS_FLOOR, P) * (eps - EPS_FLOOR)
    return v


@kernel
def _eval_many(kind, k, eps, P, out):
    for n in range(eps.shape[0]):
        if kind == 0:
            out[n] = force_per_pressure(k, eps[n], P)
        elif kind == 1:
            out[n] = dforce_deps(k, eps[n], P)
        elif kind == 2:
            out[n] = muscle_volume(k, eps[n], P)
        else:
            out[n] = _poly(k, eps[n], P)


def _evaluate(kind, group, eps, arm):
    k = check_int("group", group, 1, 4) - 1
    e = as_float_array("eps", eps)
    flat = kernel_array(e.reshape(-1))
    out = np.empty_like(flat)
    _eval_many(kind, k, flat, kernel_array(muscle_row(arm.muscles)), out)
    return out.reshape(e.shape)


@kernel
def _coef_many(kind, a0, a1, a2, a3, a4, eps, out):
    for n in range(eps.shape[0]):
        if kind == 0:
            out[n] = poly_value(a0, a1, a2, a3, a4, eps[n])
        else:
            out[n] = poly_integral(a0, a1, a2, a3, a4, eps[n])


def _coef_eval(kind, coefficients, eps):
    c = as_float_array("coefficients", coefficients, shape_tail=(5,))
    if c.shape != (5,):
        raise ValueError(f"coefficients must be 5 numbers a0..a4, got shape {c.shape}")
    e = as_float_array("eps", eps)
    flat = np.ascontiguousarray(e.reshape(-1))
    out = np.empty_like(flat)
    _coef_many(kind, float(c[0]), float(c[1]), float(c[2]), float(c[3]), float(c[4]), flat, out)
    return out.reshape(e.shape)


def polynomial(coefficients, eps) -> np.ndarray:
    """The force polynomial (3.9) a0/eps + a1 + ... + a4 eps^3, unclipped [N/Pa].

    Parameters
    ----------
    coefficients : array_like, shape (5,)
        a0..a4 in SI (N/Pa), as ``MuscleGroup.coefficients``.
    eps : array_like
        Contraction [-] (nonzero).

    Returns
    -------
    numpy.ndarray of the shape of ``eps``
        Evaluated by the plant kernel :func:`poly_value`.
    """
    return _coef_eval(0, coefficients, eps)


def antiderivative(coefficients, eps) -> np.ndarray:
    """Antiderivative of :func:`polynomial` without the constant [N/Pa] (``eps`` > 0).

    Parameters
    ----------
    coefficients : array_like, shape (5,)
        a0..a4 in SI (N/Pa).
    eps : array_like
        Contraction [-], > 0.
    """
    return _coef_eval(1, coefficients, eps)


def zero_force_contraction(coef, eps_a: float, eps_hi: float = 0.6) -> float:
    """First contraction above ``eps_a`` where the force polynomial (3.9) is zero.

    The polynomial is evaluated by the plant's own kernel (:func:`poly_value`).

    Parameters
    ----------
    coef : array_like, shape (5,)
        Force-law coefficients a0..a4 (3.9) [N/Pa].
    eps_a : float
        Anchor contraction [-] where the search starts.
    eps_hi : float
        Largest contraction searched [-]; returned when the force stays positive.

    Returns
    -------
    float
        The zero-force contraction [-].
    """
    from scipy.optimize import brentq

    e = np.linspace(eps_a, eps_hi, 5001)
    f = polynomial(coef, e)
    idx = np.nonzero(f <= 0.0)[0]
    if idx.size == 0:
        return eps_hi
    j = idx[0]
    a0, a1, a2, a3, a4 = (float(c) for c in coef)
    fun = lambda x: poly_value(a0, a1, a2, a3, a4, x)  # noqa: E731
    return float(brentq(fun, e[j - 1], e[j])) if j > 0 else float(e[0])


def anchor_volume(group, eps_a: float) -> float:
    """Volume of one muscle at the anchor contraction ``eps_a`` [m^3].

    The fitted force law (3.9) has an a0/eps term whose integral diverges at
    eps = 0, so the volume cannot be integrated from the uncontracted cylinder
    directly.  Near eps = 0 the membrane bulge grows like sqrt(eps), so
    dV/deps ~ c/sqrt(eps); matching c to the fitted dV/deps = l0 F/p at eps_a
    gives V(eps_a) = pi R^2 l0 + 2 eps_a l0 f(eps_a), with the cylinder of
    radius R = l0/slenderness as the eps = 0 value (thesis fig. 2.4 scale).

    Parameters
    ----------
    group : MuscleGroup
        The muscle group (force-law coefficients (3.9), membrane length l0
        [m], radius [m]).
    eps_a : float
        Anchor contraction [-] (``MuscleSet.eps_min``), > 0.
    """
    f_a = float(polynomial(group.coefficients, eps_a))
    r = group.radius
    return float(np.pi * r ** 2 * group.l0 + 2.0 * eps_a * group.l0 * max(f_a, 0.0))


@lru_cache(maxsize=64)
def muscle_terms(muscles) -> tuple:
    """Derived data of the four muscle groups the force and volume kernels read.

    Parameters
    ----------
    muscles : MuscleSet
        The muscle groups and their contraction range.

    Returns
    -------
    eps_a, eps_f0, v_c : tuple of 4 float
        Anchor contraction ``eps_min`` [-], zero-force contraction
        (:func:`zero_force_contraction`) [-] and volume constant (volume at
        ``eps_a`` (:func:`anchor_volume`) minus l0 times the force-law
        antiderivative there) [m^3] of each group.
    """
    groups = muscles.groups
    eps_a = (muscles.eps_min,) * 4
    eps_f0 = tuple(zero_force_contraction(g.coefficients, muscles.eps_min) for g in groups)
    v_c = tuple(anchor_volume(g, muscles.eps_min)
                - g.l0 * float(antiderivative(g.coefficients, muscles.eps_min)) for g in groups)
    return eps_a, eps_f0, v_c


@lru_cache(maxsize=64)
def muscle_row(muscles) -> np.ndarray:
    """The plant row with the fields the muscle kernels read; every other slot 0.

    The same values as in :func:`ppamsafety.plant.packing.pack`, so the force and
    volume of a muscle need no full packed row.

    Parameters
    ----------
    muscles : MuscleSet
        The muscle groups.

    Returns
    -------
    numpy.ndarray, shape (NP,)
        Read-only row (layout :data:`~ppamsafety.plant.layout.PLANT`).
    """
    groups = muscles.groups
    eps_a, eps_f0, v_c = muscle_terms(muscles)
    P = lay.partial_row({"n_muscles": [g.n_muscles for g in groups], "l0": [g.l0 for g in groups],
                         "coef": [c for g in groups for c in g.coefficients],
                         "eps_anchor": eps_a, "eps_f0": eps_f0, "v_c": v_c})
    P.setflags(write=False)
    return P


@checks_arm
def muscle_force(group: int, eps, pressure, arm) -> np.ndarray:
    """Force of one muscle (= the group force) by (3.9) [N].

    Parameters
    ----------
    group : int
        Muscle group 1..4.
    eps : array_like
        Contraction [-].
    pressure : array_like
        Gauge pressure [Pa] (broadcast against ``eps``).
    arm : ArmParameters
    """
    p = as_float_array("pressure", pressure)
    return p * _evaluate(0, group, eps, arm)


@checks_arm
def force_function(group: int, eps, arm) -> np.ndarray:
    """Force per unit gauge pressure f(eps) of one muscle [N/Pa = m^2].

    Parameters
    ----------
    group : int
        Muscle group 1..4.
    eps : array_like
        Contraction [-].
    arm : ArmParameters
        The arm.
    """
    return _evaluate(0, group, eps, arm)


@checks_arm
def force_polynomial(group: int, eps, arm) -> np.ndarray:
    """The raw force polynomial of ``group`` at ``eps``, without the clipping [N/Pa].

    Unlike :func:`force_function` this is negative beyond the zero-force
    contraction (used to diagnose where the fit stops being physical).

    Parameters
    ----------
    group : int
        Muscle group 1..4.
    eps : array_like
        Contraction [-] (nonzero).
    arm : ArmParameters
    """
    return _evaluate(3, group, eps, arm)


@checks_arm
def muscle_volume_of(group: int, eps, arm) -> np.ndarray:
    """Volume of one muscle of ``group`` at contraction ``eps`` [m^3].

    Parameters
    ----------
    group : int
        Muscle group 1..4.
    eps : array_like
        Contraction [-].
    arm : ArmParameters
        The arm.
    """
    return _evaluate(2, group, eps, arm)


@checks_arm
def group_volume(group: int, eps, arm) -> np.ndarray:
    """Volume of the whole group (n_m muscles) [m^3].

    Parameters
    ----------
    group : int
        Muscle group 1..4.
    eps : array_like
        Contraction [-].
    arm : ArmParameters
        The arm.
    """
    n = arm.muscles.groups[check_int("group", group, 1, 4) - 1].n_muscles
    return n * muscle_volume_of(group, eps, arm)
