"""Hunt-Crossley contact (thesis eq. 6.2) and its closed-form phase-plane solution.

    F = k delta^n + b delta^n d(delta)/dt   for delta > 0,   F = max(F, 0),   F = 0 otherwise

(Hunt & Crossley 1975; the thesis writes the damping coefficient as b, Marhefka
& Orin 1999 as lambda).  For one mass m hitting a fixed surface with speed
v0 > 0 (or two bodies with reduced mass m), m v dv/d(delta) = -(k + b v)
delta^n integrates in closed form (Marhefka & Orin 1999, eqs. 11-14)::

    m [v/b - (k/b^2) ln(k + b v)] + delta^(n+1)/(n+1) = const

giving the maximum penetration and the exit velocity (restitution) below.
Along this solution k + b v > 0, so the force never needs clipping.

The law exists once, here, as the compiled scalar :func:`hunt_crossley_force`
(with its elastic part and potential); the impact kernels inline it, the NumPy
level (:meth:`ppamsafety.impact.head.HeadContactModel.force`) calls the batched
:func:`hunt_crossley_force_batch`, and the pymunk cross-check calls the scalar
function from its Python callback.
"""

from __future__ import annotations

import math

from .._jit import kernel, leaf
from .._validation import check_finite_result, check_positive, check_range


@leaf
def hunt_crossley_force(delta, delta_dot, k, n, b):
    """Contact force [N] for penetration ``delta`` [m] and its rate [m/s]; never negative.

    Compiled scalar kernel (no input checks: the callers validate).

    Parameters
    ----------
    delta : float
        Penetration [m] (<= 0: no contact).
    delta_dot : float
        Penetration rate [m/s].
    k : float
        Stiffness [N/m^n].
    n : float
        Exponent [-].
    b : float
        Damping [N s/m^(n+1)].

    Returns
    -------
    float
        max(k delta^n + b delta^n delta_dot, 0) for delta > 0, else 0.
    """
    if delta <= 0.0:
        return 0.0
    dn = delta ** n
    return max(k * dn + b * dn * delta_dot, 0.0)


@leaf
def hunt_crossley_elastic(delta, k, n):
    """Elastic part k max(delta, 0)^n [N] of the contact force (no damping).

    Parameters
    ----------
    delta : float
        Penetration [m].
    k : float
        Stiffness [N/m^n].
    n : float
        Exponent [-].
    """
    return k * max(delta, 0.0) ** n


@leaf
def hunt_crossley_potential(delta, k, n):
    """Contact potential energy k delta^(n+1)/(n+1) [J] for delta > 0, else 0.

    Parameters
    ----------
    delta : float
        Penetration [m].
    k : float
        Stiffness [N/m^n].
    n : float
        Exponent [-].
    """
    if delta <= 0.0:
        return 0.0
    return k * delta ** (n + 1.0) / (n + 1.0)


@kernel
def hunt_crossley_force_batch(delta, delta_dot, k, n, b, out):
    """:func:`hunt_crossley_force` element-wise over 1-D arrays ``delta``, ``delta_dot``.

    Parameters
    ----------
    delta, delta_dot : numpy.ndarray, shape (m,)
        Penetrations [m] and their rates [m/s].
    k, n, b : float
        Stiffness [N/m^n], exponent [-], damping [N s/m^(n+1)].
    out : numpy.ndarray, shape (m,)
        Filled with the forces [N].
    """
    for i in range(delta.shape[0]):
        out[i] = hunt_crossley_force(delta[i], delta_dot[i], k, n, b)


def hunt_crossley_max_penetration(mass: float, v0: float, k: float, n: float, b: float) -> float:
    """Maximum penetration [m] of a mass hitting a rigid wall, Hunt-Crossley contact.

    Closed form of Marhefka & Orin (1999), the one implementation of it
    (:func:`max_penetration` validates its inputs and calls this; the head models
    of :mod:`.head` check themselves with it): delta_max =
    [(n+1) m/b^2 (b v0 - k ln(1 + b v0/k))]^(1/(n+1)), -> [(n+1) m v0^2/(2k)]^(1/(n+1))
    for b -> 0.  Inputs already validated (positive, finite).

    Parameters
    ----------
    mass : float
        Moving mass [kg].
    v0 : float
        Approach speed at first contact [m/s], > 0.
    k : float
        Contact stiffness [N/m^n], > 0.
    n : float
        Contact exponent [-].
    b : float
        Hunt-Crossley damping [N s/m^(n+1)], >= 0 (a series expansion is used
        for b v0/k < 1e-3, which includes b = 0).
    """
    x = b * v0 / k
    if x < 1e-3:   # x - ln(1 + x) = x^2/2 - x^3/3 + x^4/4 - ..., avoids cancellation
        level = (mass * v0 * v0 / (2.0 * k)
                 * (1.0 - 2.0 * x / 3.0 + x * x / 2.0 - 2.0 * x ** 3 / 5.0))
    else:
        level = mass / (b * b) * (b * v0 - k * math.log1p(x))   # = delta_max^(n+1)/(n+1)
    return ((n + 1.0) * level) ** (1.0 / (n + 1.0)) if level > 0.0 else 0.0


def _check(mass, v0, k, n, b):
    return (check_range("mass", mass, 0.0, 1e6, lo_open=True, unit="kg"),
            check_range("v0", v0, 0.0, 1e3, lo_open=True, unit="m/s"),
            check_range("k", k, 0.0, 1e20, lo_open=True, unit="N/m^n"),
            check_range("n", n, 0.5, 5.0),
            check_range("b", b, 0.0, 1e20, unit="N s/m^(n+1)"))


def max_penetration(mass, v0, k, n, b=0.0) -> float:
    """Maximum penetration [m] of a Hunt-Crossley impact (Marhefka & Orin 1999).

    delta_max = [(n+1) m/b^2 (b v0 - k ln(1 + b v0/k))]^(1/(n+1)), which tends to
    [(n+1) m v0^2/(2k)]^(1/(n+1)) for b -> 0.

    Parameters
    ----------
    mass : float
        Impacting (or reduced) mass [kg], in (0, 1e6].
    v0 : float
        Approach speed [m/s], in (0, 1000].
    k : float
        Contact stiffness [N/m^n], in (0, 1e20].
    n : float
        Exponent [-], in [0.5, 5].
    b : float
        Damping [N s/m^(n+1)], in [0, 1e20].

    Returns
    -------
    float
        delta_max [m].

    Raises
    ------
    ValueError
        Out-of-range input, or a result that is not a positive finite number
        (under- or overflow for extreme combinations).
    """
    m, v0, k, n, b = _check(mass, v0, k, n, b)
    out = hunt_crossley_max_penetration(m, v0, k, n, b)
    check_finite_result("max_penetration", out, f"mass = {m:g}, v0 = {v0:g}, k = {k:g}, "
                        f"n = {n:g}, b = {b:g}")
    if not out > 0.0:
        raise ValueError(f"max_penetration underflows to 0 for mass = {m:g} kg, v0 = {v0:g} m/s, "
                         f"k = {k:g}, n = {n:g}, b = {b:g}: the contact is too stiff or damped")
    return out


def exit_velocity(mass, v0, k, n, b=0.0) -> float:
    """Rebound speed [m/s] (positive) of a Hunt-Crossley impact with approach speed v0.

    The phase-plane invariant at delta = 0 on entry (velocity v0) and exit
    (velocity u = -v_out in (-k/b, 0)) gives, with x = b v0/k and y = b u/k,
    x - ln(1 + x) = y - ln(1 + y), solved for y in (-1, 0).  Independent of m
    and n; the restitution is e = v_out/v0.  ``mass`` and ``n`` are only
    validated.

    Parameters
    ----------
    mass : float
        Impacting (or reduced) mass [kg], in (0, 1e6] (validated only).
    v0 : float
        Approach speed [m/s], in (0, 1000].
    k : float
        Contact stiffness [N/m^n], in (0, 1e20].
    n : float
        Exponent [-], in [0.5, 5] (validated only).
    b : float
        Damping [N s/m^(n+1)], in [0, 1e20].

    Returns
    -------
    float
        Rebound speed [m/s], in [0, v0].

    Raises
    ------
    ValueError
        Out-of-range input, or b v0 / k beyond 1e300 (no finite phase-plane level).
    """
    from scipy.optimize import brentq

    _, v0, k, n, b = _check(mass, v0, k, n, b)
    if b == 0.0:
        return v0
    x = b * v0 / k
    if not x <= 1e300:
        raise ValueError(f"b v0 / k = {b:g} x {v0:g} / {k:g} overflows: damping b too large "
                         f"for stiffness k")
    if x < 1e-8:   # y = -x + 2 x^2 / 3 + O(x^3): v_out = v0 (1 - 2x/3), error ~ x^2
        return v0 * (1.0 - 2.0 * x / 3.0)
    target = _x_minus_log1p(x)
    if target > 30.0:   # y -> -1: 1 + y = exp(y - target) = exp(-1 - target) (< 1e-13)
        return k / b * (1.0 - math.exp(-1.0 - target))
    y = brentq(lambda y: _x_minus_log1p(y) - target, -1.0 + 1e-15, 0.0, xtol=1e-300,
               rtol=1e-15, maxiter=500)
    return check_finite_result("exit_velocity", -k / b * y,
                               f"v0 = {v0:g}, k = {k:g}, b = {b:g}")


def _x_minus_log1p(x: float) -> float:
    """x - ln(1 + x), accurate also for small |x| (series below 1e-3)."""
    if abs(x) < 1e-3:
        return x * x * (0.5 - x / 3.0 + x * x / 4.0 - x ** 3 / 5.0)
    return x - math.log1p(x)


def restitution(v0, k, b) -> float:
    """Coefficient of restitution e = v_out / v0 of a Hunt-Crossley impact [-].

    Parameters
    ----------
    v0 : float
        Approach speed [m/s], in (0, 1000].
    k : float
        Contact stiffness [N/m^n], in (0, 1e20].
    b : float
        Damping [N s/m^(n+1)], in [0, 1e20].

    Returns
    -------
    float
        e in [0, 1] (1 without damping).
    """
    return exit_velocity(1.0, v0, k, 1.0, b) / check_positive("v0", v0, unit="m/s")
