"""Flat parameter row shared by all compiled (numba) plant kernels.

The simulation core is written as small ``numba.njit`` kernels so that a
closed-loop experiment or a batch of impacts runs without per-step Python
overhead.  Kernels take the parameters as one float64 row ``P`` whose
contents are declared once, here, as the :class:`~ppamsafety.layouts.Layout`
:data:`PLANT` (name, length, unit, meaning and thesis reference of every
field).  The module-level integer constants (``L1``, ``COEF``, ``THETA4``
...) are generated from that declaration and frozen by numba at compile
time.  :func:`pack` builds ``P`` from an
:class:`~ppamsafety.params.ArmParameters` by field name; a batch of
parameter variants is simply a 2-D array of such rows.

Vector fields are indexed ``P[FIELD + i]`` only with a loop/group index
(``P[COEF + 5 * k + i]``, ``P[TV + i]``); a slot with its own meaning has its
own constant: the six base parameters are the field ``theta`` (length 6)
with the named constants ``THETA1`` .. ``THETA6``, the mean pressures the
field ``p_mean`` with ``PM1``, ``PM2``.

The row ends with the **effect section** (:data:`EFFECTS`): parameters of
optional plant effects (hysteresis, valve dead time, payload ...) and the
length of the per-row effect-state vector ``z`` they need; every effect is
off by default and the section then changes nothing.  The contents of ``z``
are declared in :data:`EFFECT_STATE`.  How to add an effect: see
:mod:`ppamsafety.plant.model`.

All entries are SI.  Derived quantities (connection lengths, volume anchors,
zero-force contractions) are computed here once from the geometry and muscle
data; the force polynomial is evaluated by the same compiled kernels the
plant uses (:mod:`ppamsafety.plant.muscle`).
"""

from __future__ import annotations

import enum
from functools import lru_cache

import numpy as np

from ..hysteresis.memory import STATE_LENGTH as HYST_ROW
from ..layouts import Field, Layout

#: Geometry fields, named as the :class:`~ppamsafety.params.ArmGeometry` attributes.
GEOMETRY_FIELDS = (
    Field("X11", 1, "m", "x-distance of base attachment A11 = (-X11, Y11), Table 2.1"),
    Field("Y11", 1, "m", "y of base attachment A11, Table 2.1"),
    Field("X21", 1, "m", "x of base attachment A21 = (X21, -Y21), Table 2.1"),
    Field("Y21", 1, "m", "y-distance of base attachment A21, Table 2.1"),
    Field("L12", 1, "m", "position of A12 along link 1, Table 2.1, (A.14)"),
    Field("d12", 1, "m", "offset of A12 from link 1, Table 2.1, (A.14)"),
    Field("L22", 1, "m", "position of A22 along link 1, Table 2.1, (A.16)"),
    Field("d22", 1, "m", "offset of A22 from link 1, Table 2.1, (A.16)"),
    Field("L32", 1, "m", "position of A32 along link 1, Table 2.1, (A.17)"),
    Field("d32", 1, "m", "offset of A32 from link 1, Table 2.1, (A.17)"),
    Field("L42", 1, "m", "position of A42 along link 1, Table 2.1, (A.19)"),
    Field("d42", 1, "m", "offset of A42 from link 1, Table 2.1, (A.19)"),
    Field("L33", 1, "m", "position of A33 along link 2, Table 2.1, (A.18)"),
    Field("d33", 1, "m", "offset of A33 from link 2, Table 2.1, (A.18)"),
    Field("L43", 1, "m", "position of A43 along link 2, Table 2.1, (A.20)"),
    Field("d43", 1, "m", "offset of A43 from link 2, Table 2.1, (A.20)"),
    Field("L1", 1, "m", "length of link 1 (O to joint S), Table 2.1"),
    Field("L2", 1, "m", "length of link 2 (S to TCP), Table 2.1"),
    Field("LL", 1, "m", "position of the load point A_L along link 2, Table 2.2, (A.21)"),
    Field("dL", 1, "m", "offset of the load point A_L from link 2, Table 2.2, (A.21)"),
)

class HysteresisStages(enum.IntEnum):
    """How the Preisach output W is evaluated inside the RK4 stages (see plant.model)."""

    SECANT = 0      #: W(u) + secant slope of the last step (no Everett call per stage)
    EXACT = 1       #: preisach_peek at every stage (4 x 3 Everett calls per step more)


class Switch(enum.IntEnum):
    """On/off code of a plant effect, stored in its ``*_mode`` field of :data:`EFFECTS`."""

    OFF = 0
    ON = 1


#: Effect parameters at the end of the plant row (all effects off by default).
#: The ``*_mode`` fields hold :class:`Switch` codes.  The pack-time effects
#: (payload and the truth overrides, see :func:`pack`) are folded into the
#: nominal slots of the row, so no kernel reads their flags: the flags record
#: which slots of the row differ from the nominal arm the controllers know.
EFFECT_FIELDS = (
    Field("effect_state_length", 1, "-",
          "length of the effect-state vector z this row needs (0: no effect with state), "
          "issue 7 item 2", default=0.0),
    Field("payload_mode", 1, "code", "Switch: a point mass at A_L is folded into theta, "
          "(2.19), (A.21)", default=0.0),
    Field("payload_mass", 1, "kg", "payload mass M at A_L folded into theta (0 when off), "
          "§2.3.3.5", default=0.0),
    Field("friction_mode", 1, "code", "Switch: coulomb/viscous hold the plant-truth override "
          "Effects.friction_* instead of arm.links (3.30)", default=0.0),
    Field("valve_offset_mode", 1, "code", "Switch: v1 holds the plant-truth override "
          "Effects.valve_offset (3.12)", default=0.0),
    Field("valve_gain_mode", 1, "code", "Switch: v2 holds the plant-truth override "
          "Effects.valve_gain (3.12)", default=0.0),
    Field("valve_lag_mode", 1, "code", "Switch: tv holds the plant-truth override "
          "Effects.valve_time_constant (3.2)", default=0.0),
    Field("polytropic_mode", 1, "code", "Switch: n_poly holds the plant-truth override "
          "Effects.polytropic_n (3.3)", default=0.0),
    # --- effects with state (kernels read these; z laid out by EFFECT_STATE) ---------------
    Field("hysteresis_mode", 1, "code", "Switch: muscle force hysteresis (3.35), Preisach "
          "memory per group in z, §3.6", default=0.0),
    Field("hysteresis_delta", 4, "-", "scale delta_k of (3.35) per muscle group, §3.6.5 "
          "(0.139 for 25 fibres)", default=0.0),
    Field("hysteresis_eps_max", 1, "-", "eps_max of the map eps_s = 2 eps/eps_max - 1 "
          "(3.34), 0.35 (§3.6.4)", default=0.0),
    Field("hysteresis_wfit", 2, "-", "slope and intercept of W_fit, the least-squares line "
          "of the major loop (fig. 3.12)", default=0.0, columns=("wfit_slope", "wfit_intercept")),
    Field("hysteresis_initial", 4 * HYST_ROW, "-", "Preisach memory rows of the four groups "
          "at t = 0 (layout hysteresis.memory.MEMORY), §3.6.6", default=0.0),
    Field("hysteresis_stages", 1, "code", "HysteresisStages: W inside the RK4 stages by the "
          "secant of the last step (fast) or by exact preisach_peek", default=0.0),
    Field("dead_time_mode", 1, "code", "Switch: valve set values delayed by whole control "
          "periods (delay line in z), §4.2.4", default=0.0),
    Field("dead_time", 4, "-", "dead time d_i of valve i [control periods]", default=0.0),
    Field("dead_time_length", 1, "-", "ring length D = max(d_i) + 1 of the delay line of "
          "each valve in z", default=0.0),
)

PLANT = Layout("plant parameters", GEOMETRY_FIELDS + (
    # --- muscles -----------------------------------------------------------------------
    Field("lconn", 4, "m", "connection lengths L_conn,i per group, (A.35)-(A.38), Table A.1"),
    Field("n_muscles", 4, "-", "number of muscles in series per group, Table 2.1"),
    Field("l0", 4, "m", "membrane length l0 of one muscle per group, §2.2"),
    Field("coef", 20, "N/Pa", "force-law coefficients a0..a4 per group (group-major), (3.9), "
          "Table B.1", columns=tuple(f"a{i}_g{k}" for k in range(1, 5) for i in range(5))),
    Field("eps_anchor", 4, "-", "volume anchor contraction per group (muscles.eps_min), "
          "see anchor_volume"),
    Field("v_c", 4, "m^3", "volume constant: V(eps) = v_c + l0 * antiderivative(eps), "
          "from (2.1) and (3.9)"),
    Field("eps_f0", 4, "-", "first contraction above the anchor where the force law (3.9) "
          "reaches zero (maximal volume)"),
    # --- valves ------------------------------------------------------------------------
    Field("tv", 4, "s", "valve time constants T_i, (3.2), Table 3.2"),
    Field("v1", 4, "Pa", "static valve offsets v1_i, (3.12)"),
    Field("v2", 4, "-", "static valve gains v2_i, (3.12)"),
    # --- pneumatics --------------------------------------------------------------------
    Field("p_mean", 2, "Pa", "mean pressures p_m of joints 1, 2 (Delta-p approach), (3.7)"),
    Field("p_max", 1, "Pa", "maximum gauge pressure (valve range), §3.1"),
    Field("p_atm", 1, "Pa", "atmospheric pressure, (3.3)"),
    Field("n_poly", 1, "-", "polytropic exponent n, (3.3)"),
    # --- rigid-body dynamics: base parameters (B.5) + friction (3.30) ------------------
    Field("theta", 6, "kg m, kg m, kg m^2, kg m, kg m, kg m^2",
          "base parameters theta1..theta6 = [m1 L_G1 + m2 L1, m1 d_G1, I_zO1 + m2 L1^2, "
          "m2 L_G2, m2 d_G2, I_zS2], (B.5)"),
    Field("coulomb", 2, "N m", "Coulomb friction c_j, (3.30)"),
    Field("viscous", 2, "N m s/rad", "viscous friction b_j, (3.30)"),
    Field("gravity", 1, "m/s^2", "gravitational acceleration g"),
    Field("v_friction", 1, "rad/s", "velocity scale v_s of the smooth Coulomb term c tanh(qd/v_s)"),
) + EFFECT_FIELDS)

#: The effect section of :data:`PLANT` on its own (same fields, offsets relative to the section).
EFFECTS = Layout("plant effect parameters", EFFECT_FIELDS)

#: Contents of the effect-state vector z: the fixed part.  A row with an effect with state
#: on has ``effect_state_length = EFFECT_STATE.size`` (+ the delay line: with valve dead
#: time the ring buffers of the four valves follow at :data:`Z_DELAY`, ``4 D`` floats,
#: valve-major, D = ``dead_time_length``); a row with every effect off has length 0.
EFFECT_STATE = Layout("plant effect state", [
    Field("hysteresis_memory", 4 * HYST_ROW, "-", "Preisach memory row of each muscle group "
          "(layout hysteresis.memory.MEMORY, group-major), §3.6.3"),
    Field("hysteresis_output", 4, "-", "Preisach output W of each group at its committed "
          "input (cache of the last preisach_update)"),
    Field("hysteresis_slope", 4, "-", "secant dW/deps_s of each group over its last move "
          "(RK4 stages, HysteresisStages.SECANT)"),
    Field("hysteresis_direction", 4, "-", "sign of each group's last move of eps_s "
          "(+1 rising, -1 falling, 0 none yet)"),
    Field("delay_count", 1, "-", "number of set values pushed into the delay line so far"),
])

# --- module constants for the kernels (frozen by numba at compile time) ----------------
(X11, Y11, X21, Y21, L12, D12, L22, D22, L32, D32, L42, D42, L33, D33, L43, D43,
 L1, L2, LL, DL) = PLANT.offsets(*(f.name for f in GEOMETRY_FIELDS))
LCONN, NM, L0, COEF, EPS_A, V_C, EPS_F0 = PLANT.offsets(
    "lconn", "n_muscles", "l0", "coef", "eps_anchor", "v_c", "eps_f0")
TV, V1, V2 = PLANT.offsets("tv", "v1", "v2")
PM, PMAX, PATM, NPOLY = PLANT.offsets("p_mean", "p_max", "p_atm", "n_poly")
PM1, PM2 = PM, PM + 1                  #: mean pressure of joint 1, joint 2
TH, COUL, VISC, GRAV, VFRIC = PLANT.offsets("theta", "coulomb", "viscous", "gravity",
                                            "v_friction")
#: the six base parameters theta1..theta6 of (B.5), one constant each
THETA1, THETA2, THETA3, THETA4, THETA5, THETA6 = (TH + i for i in range(6))
#: first slot of the effect section, and the effect-state length
EFFECTS_START = PLANT.offset(EFFECT_FIELDS[0].name)
NZ = PLANT.offset("effect_state_length")
#: effect flags and the payload mass (pack-time effects: recorded, not read by kernels)
(PAYLOAD_MODE, PAYLOAD_MASS, FRICTION_MODE, VALVE_OFFSET_MODE, VALVE_GAIN_MODE, VALVE_LAG_MODE,
 POLYTROPIC_MODE) = PLANT.offsets("payload_mode", "payload_mass", "friction_mode",
                                  "valve_offset_mode", "valve_gain_mode", "valve_lag_mode",
                                  "polytropic_mode")
#: effects with state: hysteresis (3.35) and valve dead time
(HYST_MODE, HYST_DELTA, HYST_EPS_MAX, HYST_WFIT, HYST_INIT, HYST_STAGES, DEAD_MODE, DEAD,
 DEAD_LEN) = PLANT.offsets("hysteresis_mode", "hysteresis_delta", "hysteresis_eps_max",
                           "hysteresis_wfit", "hysteresis_initial", "hysteresis_stages",
                           "dead_time_mode", "dead_time", "dead_time_length")
HYST_WFIT_SLOPE, HYST_WFIT_INTERCEPT = HYST_WFIT, HYST_WFIT + 1
#: offsets in the effect state z (:data:`EFFECT_STATE`); the delay line starts at Z_DELAY
Z_HYST, Z_HYST_W, Z_HYST_SLOPE, Z_HYST_DIR, Z_DELAY_COUNT = EFFECT_STATE.offsets(
    "hysteresis_memory", "hysteresis_output", "hysteresis_slope", "hysteresis_direction",
    "delay_count")
Z_DELAY = EFFECT_STATE.size
#: Effect fields applied when the row is packed (from ``ArmParameters.effects``); they
#: cannot be changed on a packed row by :func:`with_effects`.
PACK_TIME_EFFECTS = ("payload_mode", "payload_mass", "friction_mode", "valve_offset_mode",
                     "valve_gain_mode", "valve_lag_mode", "polytropic_mode",
                     "hysteresis_mode", "hysteresis_delta", "hysteresis_eps_max",
                     "hysteresis_wfit", "hysteresis_initial", "hysteresis_stages",
                     "dead_time_mode", "dead_time", "dead_time_length")
NP = PLANT.size                        #: length of the row

#: Contraction floor used by the force/volume kernels (eps <= 0 is undefined).
EPS_FLOOR = 1e-3


def _partial_row(values) -> np.ndarray:
    """A row with the given fields set and every other slot at its default (0)."""
    P = PLANT.empty()
    for name, v in values.items():
        P[PLANT.slice(name)] = v
    return P


def _geometry_values(g) -> dict:
    return {f.name: getattr(g, f.name) for f in GEOMETRY_FIELDS}


def _force_root(coef, eps_a: float, eps_hi: float = 0.6) -> float:
    """First contraction above ``eps_a`` where the force polynomial (3.9) is zero.

    The polynomial is evaluated by the plant's own kernel
    (:func:`ppamsafety.plant.muscle.poly_value`).
    """
    from scipy.optimize import brentq

    from .muscle import poly_value, polynomial

    e = np.linspace(eps_a, eps_hi, 5001)
    f = polynomial(coef, e)
    idx = np.nonzero(f <= 0.0)[0]
    if idx.size == 0:
        return eps_hi
    j = idx[0]
    a0, a1, a2, a3, a4 = (float(c) for c in coef)
    fun = lambda x: poly_value(a0, a1, a2, a3, a4, x)  # noqa: E731
    return float(brentq(fun, e[j - 1], e[j])) if j > 0 else float(e[0])


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
    values = _geometry_values(arm.geometry)
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
    nz = 0
    if fx.hysteresis_delta is not None:
        from ..hysteresis import EPS_MAX, initial_memory, w_fit

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
    cheap.
    """
    from . import geometry as geo  # local imports: these kernels need this module
    from .muscle import antiderivative

    groups = muscles.groups
    P = _partial_row({**_geometry_values(geometry), "n_muscles": [g.n_muscles for g in groups],
                      "l0": [g.l0 for g in groups]})
    lconn = geo.design_connection_lengths(P, geometry, muscles.eps_min, muscles.eps_max)
    eps_a = [muscles.eps_min] * 4
    eps_f0 = [_force_root(g.coefficients, muscles.eps_min) for g in groups]
    v_c = [anchor_volume(g, muscles.eps_min)
           - g.l0 * float(antiderivative(g.coefficients, muscles.eps_min)) for g in groups]
    return tuple(lconn), tuple(eps_a), tuple(eps_f0), tuple(v_c)


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
    from .muscle import polynomial

    f_a = float(polynomial(group.coefficients, eps_a))
    r = group.radius
    return float(np.pi * r ** 2 * group.l0 + 2.0 * eps_a * group.l0 * max(f_a, 0.0))


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
