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

from .._jit import kernel
from .._validation import as_float_array, check_positive, check_range
from ..units import G0
from .contact import hunt_crossley_force
from .hic import hic_kernel


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
        h36, i1, i2 = hic_kernel(acc, dt, w36)
        h15 = hic_kernel(acc, dt, w15)[0] if i2 - i1 > w15 else h36
        out[c, 0], out[c, 1], out[c, 2], out[c, 3], out[c, 4] = fmax, tmax, h36, h15, dmax
        out[c, 5] = -dd   # final relative velocity (separation speed once apart)


def two_body_impact(speed, *, arm_mass, head_mass: float = 5.0, stiffness: float,
                    exponent: float, damping: float = 0.0, dt: float = 1e-5,
                    duration: float = 0.05) -> dict:
    """Peak force, HIC and penetration of two-body Hunt-Crossley impacts.

    Parameters
    ----------
    speed : array_like
        Approach speeds [m/s] (> 0).
    arm_mass : float or array_like
        Effective arm mass at the tool along the impact direction [kg];
        ``np.inf`` for a fixed surface.
    head_mass : float or array_like
        Head mass [kg].
    stiffness, exponent, damping : float, keyword-only
        Hunt-Crossley k [N/m^n], n [-], b [N s/m^(n+1)].
    dt, duration : float
        Integration step and simulated time [s].

    Returns
    -------
    dict of numpy.ndarray
        ``F_max`` [N], ``t_Fmax`` [s], ``HIC36``, ``HIC15``, ``delta_max`` [m],
        ``separation_speed`` [m/s] (relative, at the end).
    """
    v = np.atleast_1d(as_float_array("speed", speed))
    if np.any(v <= 0):
        raise ValueError("speed must be positive [m/s]")
    ma = np.broadcast_to(np.asarray(arm_mass, dtype=float), v.shape)
    mh = np.broadcast_to(as_float_array("head_mass", head_mass), v.shape)
    if np.any(ma <= 0) or np.any(mh <= 0):
        raise ValueError("arm_mass and head_mass must be positive [kg]")
    finite = np.isfinite(ma)
    mu = mh.astype(float).copy()
    mu[finite] = ma[finite] * mh[finite] / (ma[finite] + mh[finite])
    check_positive("stiffness", stiffness, unit="N/m^n")
    check_range("exponent", exponent, 0.5, 5.0)
    check_range("damping", damping, 0.0, 1e22, unit="N s/m^(n+1)")
    check_range("dt", dt, 1e-9, 1e-3, unit="s")
    nsteps = int(math.ceil(check_positive("duration", duration, unit="s") / dt))
    out = np.empty((v.size, 6))
    acc = np.empty(nsteps + 1)
    w36 = int(math.floor(0.036 / dt * (1 + 1e-9)))
    w15 = int(math.floor(0.015 / dt * (1 + 1e-9)))
    _twobody_batch(np.ascontiguousarray(v, dtype=float), np.ascontiguousarray(mu),
                   np.ascontiguousarray(mh, dtype=float), float(stiffness), float(exponent),
                   float(damping), float(dt), nsteps, w36, w15, out, acc)
    keys = ["F_max", "t_Fmax", "HIC36", "HIC15", "delta_max", "separation_speed"]
    return {key: out[:, i] for i, key in enumerate(keys)}
