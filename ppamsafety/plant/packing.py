"""From an :class:`~ppamsafety.params.ArmParameters` to the flat kernel row, and back.

:func:`pack` fills the row declared in :mod:`.layout` (:data:`~.layout.PLANT`) by
field name, with the quantities the kernels need but the parameter set does not
hold: the connection lengths (A.35)-(A.38), the volume anchors and the
zero-force contractions of the muscles, computed once per geometry and muscle
set by the plant's own kernels (:mod:`.geometry`, :mod:`.muscle`), and the plant
effects of ``ArmParameters.effects``.  :func:`controller_view` and
:func:`model_view` are the rows the controllers believe in;
:func:`with_effects` changes the effect section of a packed row.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..hysteresis import EPS_MAX, initial_memory, w_fit
from . import geometry as geo
from . import muscle as mus
from .layout import (EFFECT_STATE, EFFECTS, LCONN, NP, NZ, PACK_TIME_EFFECTS, PLANT,
                     HysteresisStages, Switch, geometry_values)


@lru_cache(maxsize=128)
def pack(arm, dynamics=None) -> np.ndarray:
    """Pack an :class:`ArmParameters` into the flat kernel row ``P`` (layout :data:`PLANT`).

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    dynamics : BaseParameters, optional
        Rigid-body parameters to store in the dynamics slots.  Default
        (None): the **plant truth** -- the physical links ``arm.plant_base``
        with the optional plant effects ``arm.effects`` applied (see below).
        Pass ``arm.model`` or ``arm.model_gravity`` (or any other
        :class:`~ppamsafety.params.BaseParameters`) to build a **belief**
        view, e.g. the controllers' (:func:`controller_view`,
        :func:`model_view`): it holds these parameters and the nominal
        valves, pneumatics and friction, and ignores ``arm.effects``.

    Returns
    -------
    numpy.ndarray, shape (NP,)
        Read-only row (cached per argument pair).  ``effect_state_length``
        covers the effect state z of the effects with state that are on
        (0 when none is; see :data:`EFFECT_STATE`).

    Notes
    -----
    Pack-time effects (``arm.effects``, :class:`~ppamsafety.params.effects.Effects`),
    plant truth view only, each applied only when on (so a row with every
    effect off is bitwise the nominal row) and recorded by its
    :class:`Switch` flag in the effect section:

    * payload M at the load point A_L = (L_L, d_L) in link-2 coordinates
      (Table 2.2, (A.21), the convention of
      :func:`ppamsafety.plant.geometry.load_point`): a point mass changes the
      base parameters (B.5) exactly by the parallel-axis terms
      theta1 += M L1, theta3 += M L1^2, theta4 += M L_L, theta5 += M d_L,
      theta6 += M (L_L^2 + d_L^2) (theta2, the link-1 offset, is unchanged),
      so H, C and G of (3.1) include it consistently;
    * friction (3.30), valve offsets v1 / gains v2 (3.12), valve time
      constants T (3.2), polytropic exponent n (3.3): the override replaces
      the nominal value in the plant row;
    * effects with state, read by the kernels (:mod:`ppamsafety.plant.model`):
      muscle hysteresis (3.35) (delta per group, eps_max = 0.35, the W_fit
      line of :func:`ppamsafety.hysteresis.w_fit` and the initial Preisach
      memories) and valve dead time (delays, ring length); they set
      ``effect_state_length``.
    """
    groups = arm.muscles.groups
    lconn, eps_a, eps_f0, v_c = _muscle_terms(arm.geometry, arm.muscles)
    valves = arm.valves.valves
    pn = arm.pneumatics
    dyn = arm.plant_base if dynamics is None else dynamics
    values = geometry_values(arm.geometry)
    values.update(
        lconn=lconn, n_muscles=[grp.n_muscles for grp in groups], l0=[grp.l0 for grp in groups],
        coef=[c for grp in groups for c in grp.coefficients], eps_anchor=eps_a, v_c=v_c,
        eps_f0=eps_f0, tv=[v.time_constant for v in valves], v1=[v.v1 for v in valves],
        v2=[v.v2 for v in valves], p_mean=pn.p_mean, p_max=pn.p_max, p_atm=pn.p_atm,
        n_poly=pn.polytropic_n, theta=dyn.as_vector(), coulomb=dyn.coulomb,
        viscous=dyn.viscous, gravity=arm.gravity, v_friction=arm.friction_velocity)
    if dynamics is None:
        _apply_effects(values, arm)
    P = PLANT.pack(values)
    P.setflags(write=False)
    return P


def payload_theta(mass: float, L1: float, LL: float, dL: float) -> np.ndarray:
    """Change of the base parameters theta1..theta6 (B.5) by a point mass at A_L.

    Parameters
    ----------
    mass : float
        Point mass M [kg].
    L1 : float
        Length of link 1 [m].
    LL, dL : float
        Coordinates of the load point A_L along / perpendicular to link 2
        (Table 2.2, sign convention of (A.21)) [m].

    Returns
    -------
    numpy.ndarray, shape (6,)
        [M L1, 0, M L1^2, M L_L, M d_L, M (L_L^2 + d_L^2)] (kg m, kg m, kg m^2,
        kg m, kg m, kg m^2): the mass adds to m2 L1 (theta1), m2 L1^2
        (theta3) and, as part of link 2, to m2 L_G2, m2 d_G2 and I_zS,2.
    """
    return np.array([mass * L1, 0.0, mass * L1 * L1, mass * LL, mass * dL,
                     mass * (LL * LL + dL * dL)])


def _apply_effects(values: dict, arm) -> None:
    """Fold ``arm.effects`` into the plant-truth ``values`` (see :func:`pack`); in place."""
    fx = arm.effects
    if fx.payload_mass > 0.0:
        g = arm.geometry
        values["theta"] = values["theta"] + payload_theta(fx.payload_mass, g.L1, g.LL, g.dL)
        values.update(payload_mode=Switch.ON, payload_mass=fx.payload_mass)
    if fx.friction_coulomb is not None or fx.friction_viscous is not None:
        if fx.friction_coulomb is not None:
            values["coulomb"] = fx.friction_coulomb
        if fx.friction_viscous is not None:
            values["viscous"] = fx.friction_viscous
        values["friction_mode"] = Switch.ON
    for field, flag, override in (("v1", "valve_offset_mode", fx.valve_offset),
                                  ("v2", "valve_gain_mode", fx.valve_gain),
                                  ("tv", "valve_lag_mode", fx.valve_time_constant)):
        if override is not None:
            values[field] = override
            values[flag] = Switch.ON
    if fx.polytropic_n is not None:
        values.update(n_poly=fx.polytropic_n, polytropic_mode=Switch.ON)
    if fx.joint_torque_bias is not None:
        values.update(torque_bias_mode=Switch.ON, torque_bias=fx.joint_torque_bias)
    nz = 0
    if fx.hysteresis_delta is not None:
        init = fx.hysteresis_initial
        rows = [initial_memory(init if isinstance(init, str) else init[k]) for k in range(4)]
        values.update(hysteresis_mode=Switch.ON, hysteresis_delta=fx.hysteresis_delta,
                      hysteresis_eps_max=EPS_MAX, hysteresis_wfit=w_fit(),
                      hysteresis_initial=np.concatenate(rows),
                      hysteresis_stages=HysteresisStages.EXACT if fx.hysteresis_exact_stages
                      else HysteresisStages.SECANT)
        nz = EFFECT_STATE.size
    if fx.valve_dead_time is not None:
        D = max(fx.valve_dead_time) + 1
        values.update(dead_time_mode=Switch.ON, dead_time=fx.valve_dead_time,
                      dead_time_length=D)
        nz = EFFECT_STATE.size + 4 * D
    values["effect_state_length"] = nz


def plant_effects(P) -> dict:
    """Which effects are on in plant row(s) ``P``: ``{mode field: bool or bool array}``.

    Parameters
    ----------
    P : array_like, shape (NP,) or (..., NP)
        Packed plant row(s) (layout :data:`PLANT`).

    Returns
    -------
    dict
        For each ``*_mode`` field of :data:`PACK_TIME_EFFECTS`: True where
        its :class:`Switch` code is ``ON`` (a bool, or a bool array of the
        leading shape of ``P``).
    """
    P = np.asarray(P, dtype=float)
    return {name: P[..., PLANT.offset(name)] == Switch.ON
            for name in PACK_TIME_EFFECTS if name.endswith("_mode")}


#: Largest effect-state length a row may ask for.
MAX_EFFECT_STATE = 1_000_000


def with_effects(P, **effects) -> np.ndarray:
    """Copy of plant row(s) ``P`` with effect parameters set by name.

    Parameters
    ----------
    P : array_like, shape (NP,) or (B, NP)
        Packed plant row(s) (:func:`pack`).
    **effects
        Run-time fields of :data:`EFFECTS` and their values, e.g.
        ``effect_state_length=3``.  The pack-time effects
        (:data:`PACK_TIME_EFFECTS`: payload, truth overrides) are folded into
        other slots by :func:`pack` and are set through
        ``ArmParameters.effects`` instead.

    Returns
    -------
    numpy.ndarray
        A new writable array of the shape of ``P``.

    Raises
    ------
    KeyError
        For a name that is not an effect field.
    ValueError
        For a row of the wrong length, an invalid value or a pack-time effect.
    """
    out = np.array(P, dtype=float)
    if out.ndim not in (1, 2) or out.shape[-1] != NP:
        raise ValueError(f"P must have shape ({NP},) or (B, {NP}), got {out.shape}")
    for name, value in effects.items():
        EFFECTS.field(name)                      # KeyError naming the fields
        if name in PACK_TIME_EFFECTS:
            raise ValueError(f"{name} is a pack-time effect: set it through "
                             f"ArmParameters.effects (params.effects.Effects) and pack(arm), "
                             f"not on a packed row")
        if name == "effect_state_length":
            if (isinstance(value, bool) or not isinstance(value, (int, np.integer, float))
                    or not float(value).is_integer() or not 0 <= value <= MAX_EFFECT_STATE):
                raise ValueError(f"effect_state_length = {value!r} must be an integer in "
                                 f"[0, {MAX_EFFECT_STATE}]")
        out[..., PLANT.slice(name)] = value
    return out


def effect_state_lengths(rows) -> np.ndarray:
    """Effect-state length of each plant row, validated; int array of shape (B,).

    Parameters
    ----------
    rows : array_like, shape (NP,) or (B, NP)
        Packed plant row(s) (layout :data:`PLANT`); the
        ``effect_state_length`` slot (:data:`NZ`) is read.

    Returns
    -------
    numpy.ndarray of int64, shape (B,)
        Length of the effect state z each row needs (B = 1 for one row).

    Raises
    ------
    ValueError
        If a length is not an integer in [0, :data:`MAX_EFFECT_STATE`].
    """
    n = np.atleast_2d(rows)[:, NZ]
    if not np.all((n == np.round(n)) & (n >= 0) & (n <= MAX_EFFECT_STATE)):
        raise ValueError(f"params: effect_state_length must be an integer in "
                         f"[0, {MAX_EFFECT_STATE}], got {n}")
    return n.astype(np.int64)


@lru_cache(maxsize=64)
def _muscle_terms(geometry, muscles) -> tuple:
    """Derived muscle data (connection lengths, volume constants), cached per geometry.

    Only these need a search over the working area; caching them makes packing
    a parameter variant that differs elsewhere (valves, pressures, inertia)
    cheap.  Each comes from the physics module that owns it: the connection
    lengths from :func:`.geometry.geometry_row`, the anchor and zero-force
    contractions and the volume constants from :func:`.muscle.muscle_terms`.
    """
    lconn = geo.geometry_row(geometry, muscles)[LCONN:LCONN + 4]
    eps_a, eps_f0, v_c = mus.muscle_terms(muscles)
    return tuple(float(x) for x in lconn), eps_a, eps_f0, v_c


def controller_view(arm) -> np.ndarray:
    """Packed row with the controllers' identified gravity model (Table 3.1).

    Parameters
    ----------
    arm : ArmParameters
        The arm; ``arm.model_gravity`` fills the dynamics slots, with the
        nominal valves, pneumatics and friction (no plant effects).

    Returns
    -------
    numpy.ndarray, shape (NP,)
        Read-only row (layout :data:`PLANT`), see :func:`pack`.
    """
    return pack(arm, arm.model_gravity)


def model_view(arm) -> np.ndarray:
    """Packed row with the identified dynamic model (Table 3.5).

    Parameters
    ----------
    arm : ArmParameters
        The arm; ``arm.model`` fills the dynamics slots, with the nominal
        valves, pneumatics and friction (no plant effects).

    Returns
    -------
    numpy.ndarray, shape (NP,)
        Read-only row (layout :data:`PLANT`), see :func:`pack`.
    """
    return pack(arm, arm.model)


__all__ = ["pack", "controller_view", "model_view", "with_effects", "plant_effects",
           "effect_state_lengths", "payload_theta", "MAX_EFFECT_STATE"]
