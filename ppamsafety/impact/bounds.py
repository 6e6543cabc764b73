"""Rigorous a-priori upper bounds on F_max and HIC of an impact (no simulation).

Used by :func:`ppamsafety.impact.instants.worst_instant` to skip impact
instants that provably cannot be the worst of an experiment.

Setting (:mod:`ppamsafety.impact.engine`): flexible-joint arm, joint springs
unloaded at t0, motor side frozen, free head (mass m_h, sphere radius R) at
rest or moving, Hunt-Crossley contact F = max(delta^n (k + b delta'), 0) for
delta > 0.  Let E0 be the kinetic energy at t0 (arm + head).

**Energy.**  The only non-conservative force is the contact damping, whose
power (F - k delta^n) delta' is >= 0 (unclipped: b delta^n delta'^2; clipped,
F = 0: -k delta^n delta' with delta' < -k/b < 0); the Coriolis terms do no
work and the frozen motor side none either.  Hence at every time::

    T_kin + V_springs + k delta^(n+1)/(n+1) <= E0.                       (1)

**Relative speed.**  For any unit vector e, the kinetic energy of the arm is
at least (1/2) m_eff(q, e) (e . v_tcp)^2, m_eff = 1/(e^T J H^-1 J^T e) (the
least kinetic energy giving the tool point that velocity component), and
m_eff >= m_min := min over q2 and e (:func:`min_effective_mass`; J H^-1 J^T
depends on q2 only up to a rotation).  With the head's (1/2) m_h (e . v_h)^2,
minimising a x^2 + c y^2 subject to x - y = s gives
T_kin >= (1/2) mu (e . (v_h - v_tcp))^2 with mu = m_h m_min/(m_h + m_min), so
every component of the relative velocity, in particular delta', obeys::

    (1/2) mu delta'^2 + k delta^(n+1)/(n+1) <= E0.                        (2)

**Force bound.**  With V = sqrt(2 E0/mu) and delta_m = ((n+1) E0/k)^(1/(n+1))
(the largest delta allowed by (2)), write delta = x delta_m, x in [0, 1]:
(2) gives delta' <= V sqrt(1 - x^(n+1)), so
F <= delta_m^n x^n (k + b V sqrt(1 - x^(n+1))).  On each cell [x_i, x_i+1]
of a uniform grid this is <= delta_m^n x_{i+1}^n (k + b V sqrt(1 - x_i^(n+1)))
(first factor increasing, second decreasing in x); the largest cell value
bounds F_max.

**HIC bound.**  a = F/(m_h g0) <= a_m := F bound/(m_h g0).  For any window of
length L <= W with mean m: HIC = L m^2.5 = (L m) m^1.5 <= I a_m^1.5 with I the
integral of a over [0, T], and HIC <= W a_m^2.5.  For I: let u be the
initial normal and x = x_h - r_tcp (x(0) = R u).  Its component across u,
l(t), has |l'| <= |v_h - v_tcp| <= V, so |l| <= V T.  By (2), |x| >= R -
delta_m.  If s := V T/(R - delta_m) < 1, the component along u never
vanishes (it would need |x| = |l| < R - delta_m), so it stays positive, and in
contact (|x| <= R) n . u = sqrt(1 - l^2/|x|^2) >= c := sqrt(1 - s^2).
As F n . u >= 0, integral F dt <= (1/c) integral F n . u dt = (m_h/c) (v_h(T)
- v_h(0)) . u <= (1/c) (sqrt(2 m_h E0) + m_h |v_h(0)|) (head kinetic energy
<= E0).  Hence HIC <= min(W a_m^2.5, a_m^1.5 I) with I = that impulse bound
/(m_h g0) (only the first term if s >= 1).

The bounds hold for the exact solution of the model; the simulated values
carry the integrator's error (< 2e-4 relative at the default step, see the
engine tests), so the returned bounds are multiplied by :data:`MARGIN`.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .._validation import as_float_array, check_range
from ..plant import dynamics as dyn
from ..plant import geometry as geo
from ..units import G0
from .model import check_arm, resolve_head

#: Safety factor on the bounds against integration and rounding error of the simulated values.
MARGIN = 1.01
#: Cells of the grid in x = delta/delta_m on which the force bound is maximised.
FORCE_CELLS = 256
#: Grid points over q2 in [-pi, pi] for the smallest effective mass ...
MASS_GRID = 20001
#: ... and the factor applied to the grid minimum (the function varies by far less than 1 %
#: between neighbouring grid points; checked against a 10x finer grid in the tests).
MASS_GRID_FACTOR = 0.99


def _min_eig_mass(q2, arm):
    q = np.stack([np.zeros_like(q2), q2], axis=-1)
    J = geo.jacobian(q, arm)
    M = J @ np.linalg.inv(dyn.inertia_matrix(q, arm)) @ np.swapaxes(J, -1, -2)
    return 1.0 / np.linalg.eigvalsh(M)[..., -1]


@functools.lru_cache(maxsize=8)
def _min_effective_mass_cached(arm, n):
    q2 = np.linspace(-np.pi, np.pi, n)
    return float(_min_eig_mass(q2, arm).min())


def min_effective_mass(arm, *, grid: int = MASS_GRID) -> float:
    """Smallest effective mass of the arm at the tool over all q2 and directions [kg].

    m_min = min over q2 of 1/lambda_max(J H^-1 J^T) (independent of q1), from a
    grid of ``grid`` points over [-pi, pi], times :data:`MASS_GRID_FACTOR`.

    Parameters
    ----------
    arm : ArmParameters
        Kinematics and link inertias.
    grid : int
        Grid points over q2 (>= 101).
    """
    if not isinstance(grid, (int, np.integer)) or grid < 101:
        raise ValueError(f"grid = {grid!r} must be an integer >= 101")
    try:
        m = _min_effective_mass_cached(arm, int(grid))
    except TypeError:                       # unhashable arm: no caching
        m = float(_min_eig_mass(np.linspace(-np.pi, np.pi, int(grid)), arm).min())
    return m * MASS_GRID_FACTOR


def impact_bounds(arm, q, qd, *, head, head_velocity=None, duration: float = 0.05,
                  window: float = 0.036) -> tuple[np.ndarray, np.ndarray]:
    """Upper bounds on F_max [N] and HIC of impacts (module docstring), no simulation.

    Parameters
    ----------
    arm : ArmParameters
        Kinematics and link inertias.
    q, qd : array_like, shape (N, 2) or (2,)
        Link angles [rad] and velocities [rad/s] at the impact instant.
    head : HeadContactModel or str, keyword-only
        Head and contact parameters (a model or a head model name).
    head_velocity : array_like, shape (N, 2) or (2,), optional
        Initial head velocity [m/s] (default at rest).
    duration : float
        Simulated time T [s], in [1e-4, 10] (as :func:`~ppamsafety.impact.simulate_impacts`).
    window : float
        HIC window limit W [s] (0.036 for HIC36, 0.015 for HIC15).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        F_max bound [N] and HIC bound [-], shape (N,); ``inf`` where no finite
        bound follows (never smaller than the true value).
    """
    arm = check_arm(arm)
    q = np.atleast_2d(as_float_array("q", q, shape_tail=(2,), ndim=(1, 2)))
    qd = as_float_array("qd", qd, shape_tail=(2,), ndim=(1, 2))
    head = resolve_head(head)
    if np.atleast_2d(qd).shape[0] not in (1, q.shape[0]):
        raise ValueError(f"qd has {np.atleast_2d(qd).shape[0]} rows, q has {q.shape[0]}")
    qd = np.broadcast_to(qd, q.shape)
    vh = np.zeros(q.shape) if head_velocity is None else np.broadcast_to(
        as_float_array("head_velocity", head_velocity, shape_tail=(2,), ndim=(1, 2)), q.shape)
    duration = check_range("duration", duration, 1e-4, 10.0, unit="s")
    window = check_range("window", window, 1e-9, math.inf, unit="s")
    mh, R, k, n, b = head.mass, head.radius, head.stiffness, head.exponent, head.damping
    H = dyn.inertia_matrix(q, arm)
    e0 = 0.5 * np.einsum("ni,nij,nj->n", qd, H, qd) + 0.5 * mh * np.einsum("ni,ni->n", vh, vh)
    mmin = min_effective_mass(arm)
    mu = mh * mmin / (mh + mmin)
    V = np.sqrt(2.0 * e0 / mu)
    dm = ((n + 1.0) * e0 / k) ** (1.0 / (n + 1.0))
    x = np.linspace(0.0, 1.0, FORCE_CELLS + 1)
    cell = x[1:] ** n * (k + b * np.outer(V, np.sqrt(np.maximum(1.0 - x[:-1] ** (n + 1.0), 0.0))))
    fb = dm ** n * cell.max(axis=1) * MARGIN
    am = fb / (mh * G0)
    hic = window * am ** 2.5
    s = np.minimum(V * duration / np.maximum(R - dm, 1e-300), 2.0)   # >= 1: no cone bound
    ok = (s < 1.0) & (R > dm)
    c = np.sqrt(np.clip(1.0 - s * s, 1e-300, None))
    imp = (np.sqrt(2.0 * mh * e0) + mh * np.linalg.norm(vh, axis=1)) / c / (mh * G0)
    hic = np.where(ok, np.minimum(hic, am ** 1.5 * imp * MARGIN), hic)
    return fb, hic
