"""Two-body impact: an effective arm mass against the free head, along one line.

The reduced 1-D problem behind the full impact model: an arm of effective
mass m_a at the tool, moving with speed v, hits a free head of mass m_h at
rest through a Hunt-Crossley contact.  The penetration obeys
mu d2(delta)/dt2 = -F(delta, d(delta)/dt) with mu = m_a m_h/(m_a + m_h), and
the head accelerates with F/m_h.  With m_a -> infinity it is a head hitting
a fixed surface (drop tests).

Used to explain why the joint stiffness barely matters (thesis §6.3.4) and to
fit the head contact model (:mod:`ppamsafety.impact.head_fit`).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel, kernel_array
from .._validation import (as_float_array, check_finite_result, check_positive, check_range,
                           check_range_array)
from ..units import G0
from .contact import hunt_crossley_force
from .hic import hic_pair_kernel


@kernel
def _twobody_batch(V, MU, MH, k, n, b, dt, nsteps, w36, w15, out, acc):
    for c in range(V.shape[0]):
        d, dd = 0.0, V[c]
        mu, mh = MU[c], MH[c]
        fmax, tmax, dmax = 0.0, 0.0, 0.0
        for s in range(nsteps + 1):
            f = hunt_crossley_force(d, dd, k, n, b)
            acc[s] = f / (mh * G0)
            if f > fmax:
                fmax, tmax = f, s * dt
            dmax = max(dmax, d)
            if s == nsteps:
                break
            # RK4 on (delta, delta_dot)
            k1v = -hunt_crossley_force(d, dd, k, n, b) / mu
            d2, dd2 = d + 0.5 * dt * dd, dd + 0.5 * dt * k1v
            k2v = -hunt_crossley_force(d2, dd2, k, n, b) / mu
            d3, dd3 = d + 0.5 * dt * dd2, dd + 0.5 * dt * k2v
            k3v = -hunt_crossley_force(d3, dd3, k, n, b) / mu
            d4, dd4 = d + dt * dd3, dd + dt * k3v
            k4v = -hunt_crossley_force(d4, dd4, k, n, b) / mu
            d += dt / 6.0 * (dd + 2.0 * dd2 + 2.0 * dd3 + dd4)
            dd += dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
            if d < 0.0 and dd <= 0.0:
                # apart and not closing, and no other force acts: every later force is
                # exactly 0 and dd stays as it is, so the rest of the record is zeros and
                # stepping on would change no result
                for r in range(s + 1, nsteps + 1):
                    acc[r] = 0.0
                break
        h36, _, _, h15, _, _ = hic_pair_kernel(acc, dt, w36, w15, False)
        out[c, 0], out[c, 1], out[c, 2], out[c, 3], out[c, 4] = fmax, tmax, h36, h15, dmax
        out[c, 5] = -dd   # final relative velocity (separation speed once apart)


#: Largest number of integration steps duration / dt of one call.
MAX_STEPS = 10 ** 7


def _broadcast(name, value, shape, *, allow_inf=False):
    a = as_float_array(name, value, allow_nonfinite=allow_inf)
    if np.any(np.isnan(a)) or np.any(a == -np.inf):
        raise ValueError(f"{name} contains NaN or -inf")
    check_range_array(name, a, 0.0, np.inf, unit="kg")
    if np.any(a <= 0):
        raise ValueError(f"{name} = {a.min():g} kg must be positive")
    try:
        return np.broadcast_to(a, shape)
    except ValueError:
        raise ValueError(f"{name} (shape {a.shape}) does not broadcast against speed "
                         f"(shape {shape})") from None


def two_body_impact(speed, *, arm_mass, head_mass: float = 5.0, stiffness: float,
                    exponent: float, damping: float = 0.0, dt: float = 1e-5,
                    duration: float = 0.05) -> dict:
    """Peak force, HIC and penetration of two-body Hunt-Crossley impacts.

    Parameters
    ----------
    speed : array_like
        Approach speeds [m/s], each in (0, 1000].
    arm_mass : float or array_like
        Effective arm mass at the tool along the impact direction [kg] (> 0);
        ``np.inf`` for a fixed surface.  Broadcast against ``speed``.
    head_mass : float or array_like
        Head mass [kg] (> 0, finite), broadcast against ``speed``.
    stiffness : float, keyword-only
        Hunt-Crossley k [N/m^n] (> 0).
    exponent : float, keyword-only
        Hunt-Crossley n [-] in [0.5, 5].
    damping : float, keyword-only
        Hunt-Crossley b [N s/m^(n+1)] in [0, 1e22].
    dt : float
        Integration step [s] in [1e-9, 1e-3].
    duration : float
        Simulated time [s] (> 0, at least dt; duration / dt <= 1e7).

    Returns
    -------
    dict of numpy.ndarray
        ``F_max`` [N], ``t_Fmax`` [s], ``HIC36``, ``HIC15``, ``delta_max`` [m],
        ``separation_speed`` [m/s] (relative, at the end).

    Raises
    ------
    ValueError
        Also if the result is not finite (overflow for extreme parameters).
    """
    v = np.atleast_1d(as_float_array("speed", speed, ndim=(0, 1)))
    check_range_array("speed", v, 0.0, 1e3, unit="m/s")
    if np.any(v <= 0):
        raise ValueError(f"speed = {v.min():g} m/s must be positive")
    ma = _broadcast("arm_mass", arm_mass, v.shape, allow_inf=True)
    mh = _broadcast("head_mass", head_mass, v.shape)
    finite = np.isfinite(ma)
    mu = mh.astype(float).copy()
    mu[finite] = ma[finite] * mh[finite] / (ma[finite] + mh[finite])
    stiffness = check_positive("stiffness", stiffness, unit="N/m^n")
    exponent = check_range("exponent", exponent, 0.5, 5.0)
    damping = check_range("damping", damping, 0.0, 1e22, unit="N s/m^(n+1)")
    dt = check_range("dt", dt, 1e-9, 1e-3, unit="s")
    duration = check_positive("duration", duration, unit="s")
    if duration < dt:
        raise ValueError(f"duration = {duration:g} s is shorter than dt = {dt:g} s")
    if duration / dt > MAX_STEPS:
        raise ValueError(f"duration / dt = {duration:g} s / {dt:g} s exceeds {MAX_STEPS} steps; "
                         f"use a larger dt or a shorter duration")
    nsteps = int(math.ceil(duration / dt))
    out = np.empty((v.size, 6))
    acc = np.empty(nsteps + 1)
    w36 = int(math.floor(0.036 / dt * (1 + 1e-9)))
    w15 = int(math.floor(0.015 / dt * (1 + 1e-9)))
    _twobody_batch(kernel_array(v), kernel_array(mu), kernel_array(mh), float(stiffness),
                   float(exponent), float(damping), float(dt), nsteps, w36, w15, out, acc)
    def span(x):
        if np.size(x) == 0:
            return "[]"
        # min == max, not ptp: ptp of an infinite arm mass (a rigid plate) is inf - inf
        return (f"{np.min(x):g}" if np.min(x) == np.max(x)
                else f"{np.min(x):g}..{np.max(x):g}")

    # an overflow can come from any input (e.g. a tiny mass with a stiff, damped contact):
    # the message names them all
    check_finite_result("two_body_impact", out,
                        f"speed = {span(v)} m/s, arm_mass = {span(ma)} kg, "
                        f"head_mass = {span(mh)} kg, stiffness = {stiffness:g}, "
                        f"exponent = {exponent:g}, damping = {damping:g}, dt = {dt:g}, "
                        f"duration = {duration:g}")
    keys = ["F_max", "t_Fmax", "HIC36", "HIC15", "delta_max", "separation_speed"]
    return {key: out[:, i] for i, key in enumerate(keys)}
