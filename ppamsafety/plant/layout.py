"""Flat parameter vector shared by all compiled (numba) kernels.

The simulation core is written as small ``numba.njit`` kernels so that a
closed-loop experiment or a batch of impacts runs without per-step Python
overhead.  Kernels take the parameters as one float64 vector ``P`` and read
fields by the integer offsets defined here (compile-time constants for
numba).  :func:`pack` builds ``P`` from an :class:`~ppamsafety.params.ArmParameters`;
a batch of parameter variants is simply a 2-D array of such rows.

All entries are SI.  Derived quantities (connection lengths, volume anchors)
are computed here once from the geometry and muscle data.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

# --- geometry (Table 2.1 / 2.2) [m] -------------------------------------
X11, Y11, X21, Y21 = 0, 1, 2, 3
L12, D12, L22, D22, L32, D32, L42, D42 = 4, 5, 6, 7, 8, 9, 10, 11
L33, D33, L43, D43 = 12, 13, 14, 15
L1, L2, LL, DL = 16, 17, 18, 19
# --- muscles --------------------------------------------------------------
LCONN = 20          # 4 connection lengths [m]            (A.35)-(A.38)
NM = 24             # 4 numbers of muscles in series [-]
L0 = 28             # 4 membrane lengths l0 [m]
COEF = 32           # 4 x 5 force coefficients a0..a4 [N/Pa]  (3.9)
EPS_A = 52          # 4 volume anchor contractions [-]
V_C = 56            # 4 volume constants: V(eps) = V_C + l0 * antiderivative(eps) [m^3]
EPS_F0 = 60         # 4 contraction where the force law reaches zero [-]
# --- valves ----------------------------------------------------------------
TV = 64             # 4 time constants [s]                (3.2)
V1 = 68             # 4 static offsets [Pa]               (3.12)
V2 = 72             # 4 static gains [-]
# --- pneumatics -----------------------------------------------------------
PM1, PM2, PMAX, PATM, NPOLY = 76, 77, 78, 79, 80
# --- rigid-body dynamics: base parameters (B.5) + friction (3.30) -----------
TH = 81             # 6 base parameters theta1..theta6
COUL = 87           # 2 Coulomb [N m]
VISC = 89           # 2 viscous [N m s/rad]
GRAV = 91           # gravity [m/s^2]
VFRIC = 92          # friction velocity scale [rad/s]
NP = 93             # length of the vector

#: Contraction floor used by the force/volume kernels (eps <= 0 is undefined).
EPS_FLOOR = 1e-3


def _force_root(coef, eps_a: float, eps_hi: float = 0.6) -> float:
    """First contraction above ``eps_a`` where the force polynomial is zero."""
    e = np.linspace(eps_a, eps_hi, 5001)
    a0, a1, a2, a3, a4 = coef
    f = a0 / e + a1 + a2 * e + a3 * e ** 2 + a4 * e ** 3
    idx = np.nonzero(f <= 0.0)[0]
    if idx.size == 0:
        return eps_hi
    from scipy.optimize import brentq
    j = idx[0]
    fun = lambda x: a0 / x + a1 + a2 * x + a3 * x ** 2 + a4 * x ** 3  # noqa: E731
    return float(brentq(fun, e[j - 1], e[j])) if j > 0 else float(e[0])


def _antiderivative(coef, e: float) -> float:
    """Antiderivative of the force polynomial (same as ``muscle.integral``)."""
    a0, a1, a2, a3, a4 = coef
    return float(a0 * np.log(e) + a1 * e + a2 * e ** 2 / 2 + a3 * e ** 3 / 3 + a4 * e ** 4 / 4)


def _fill_geometry(P, g):
    vals = (g.X11, g.Y11, g.X21, g.Y21, g.L12, g.d12, g.L22, g.d22, g.L32, g.d32, g.L42, g.d42,
            g.L33, g.d33, g.L43, g.d43, g.L1, g.L2, g.LL, g.dL)
    P[:20] = vals


@lru_cache(maxsize=128)
def pack(arm, dynamics=None) -> np.ndarray:
    """Pack an :class:`ArmParameters` into the flat kernel vector ``P``.

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    dynamics : BaseParameters, optional
        Rigid-body parameters to store in the dynamics slots.  Default: the
        physical plant (``arm.plant_base``).  Pass ``arm.model`` or
        ``arm.model_gravity`` to build the *controller's* view of the arm.

    Returns
    -------
    numpy.ndarray, shape (NP,)
        Read-only vector (cached per argument pair).
    """
    P = np.zeros(NP)
    _fill_geometry(P, arm.geometry)
    groups = arm.muscles.groups
    for i, grp in enumerate(groups):
        P[NM + i] = grp.n_muscles
        P[L0 + i] = grp.l0
        P[COEF + 5 * i: COEF + 5 * i + 5] = grp.coefficients
    lconn, eps_a, eps_f0, v_c = _muscle_terms(arm.geometry, arm.muscles)
    P[LCONN:LCONN + 4] = lconn
    P[EPS_A:EPS_A + 4] = eps_a
    P[EPS_F0:EPS_F0 + 4] = eps_f0
    P[V_C:V_C + 4] = v_c
    for i, v in enumerate(arm.valves.valves):
        P[TV + i], P[V1 + i], P[V2 + i] = v.time_constant, v.v1, v.v2
    pn = arm.pneumatics
    P[PM1], P[PM2], P[PMAX], P[PATM], P[NPOLY] = (pn.p_mean[0], pn.p_mean[1], pn.p_max,
                                                  pn.p_atm, pn.polytropic_n)
    dyn = arm.plant_base if dynamics is None else dynamics
    P[TH:TH + 6] = dyn.as_vector()
    P[COUL:COUL + 2] = dyn.coulomb
    P[VISC:VISC + 2] = dyn.viscous
    P[GRAV] = arm.gravity
    P[VFRIC] = arm.friction_velocity
    P.setflags(write=False)
    return P


@lru_cache(maxsize=64)
def _muscle_terms(geometry, muscles) -> tuple:
    """Derived muscle data (connection lengths, volume constants), cached per geometry.

    Only these need a search over the working area; caching them makes packing
    a parameter variant that differs elsewhere (valves, pressures, inertia)
    cheap.
    """
    from . import geometry as geo  # local import: the geometry kernels need this module

    P = np.zeros(NP)
    _fill_geometry(P, geometry)
    for i, grp in enumerate(muscles.groups):
        P[NM + i] = grp.n_muscles
        P[L0 + i] = grp.l0
    lconn = geo.design_connection_lengths(P, geometry, muscles.eps_min, muscles.eps_max)
    eps_a = [muscles.eps_min] * 4
    eps_f0 = [_force_root(g.coefficients, muscles.eps_min) for g in muscles.groups]
    v_c = [anchor_volume(g, muscles.eps_min) - g.l0 * _antiderivative(g.coefficients, muscles.eps_min)
           for g in muscles.groups]
    return tuple(lconn), tuple(eps_a), tuple(eps_f0), tuple(v_c)


def anchor_volume(group, eps_a: float) -> float:
    """Volume of one muscle at the anchor contraction ``eps_a`` [m^3].

    The fitted force law (3.9) has an a0/eps term whose integral diverges at
    eps = 0, so the volume cannot be integrated from the uncontracted cylinder
    directly.  Near eps = 0 the membrane bulge grows like sqrt(eps), so
    dV/deps ~ c/sqrt(eps); matching c to the fitted dV/deps = l0 F/p at eps_a
    gives V(eps_a) = pi R^2 l0 + 2 eps_a l0 f(eps_a), with the cylinder of
    radius R = l0/slenderness as the eps = 0 value (thesis fig. 2.4 scale).
    """
    a0, a1, a2, a3, a4 = group.coefficients
    f_a = a0 / eps_a + a1 + a2 * eps_a + a3 * eps_a ** 2 + a4 * eps_a ** 3
    r = group.radius
    return float(np.pi * r ** 2 * group.l0 + 2.0 * eps_a * group.l0 * max(f_a, 0.0))


def controller_view(arm) -> np.ndarray:
    """Packed vector with the controllers' identified gravity model (Table 3.1)."""
    return pack(arm, arm.model_gravity)


def model_view(arm) -> np.ndarray:
    """Packed vector with the identified dynamic model (Table 3.5)."""
    return pack(arm, arm.model)
