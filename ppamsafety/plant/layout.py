"""Flat parameter row shared by all compiled (numba) plant kernels.

The simulation core is written as small ``numba.njit`` kernels so that a
closed-loop experiment or a batch of impacts runs without per-step Python
overhead.  Kernels take the parameters as one float64 row ``P`` whose
contents are declared once, here, as the :class:`~ppamsafety.layouts.Layout`
:data:`PLANT` (name, length, unit, meaning and thesis reference of every
field).  The module-level integer constants (``L1``, ``COEF``, ``THETA4``
...) are generated from that declaration and frozen by numba at compile
time.  :func:`ppamsafety.plant.packing.pack` builds ``P`` from an
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

All entries are SI.  This module only declares the row; the kernels of
:mod:`.geometry`, :mod:`.muscle` and the others read it by these constants, and
:mod:`.packing` fills it (with the derived quantities: connection lengths,
volume anchors, zero-force contractions).
"""

from __future__ import annotations

import enum

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
#: (payload and the truth overrides, see :func:`ppamsafety.plant.packing.pack`) are folded
#: into the nominal slots of the row, so no kernel reads their flags: the flags record
#: which slots of the row differ from the nominal arm the controllers know.
EFFECT_FIELDS = (
    Field("effect_state_length", 1, "-",
          "length of the effect-state vector z this row needs (0: no effect with state)",
          default=0.0),
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
    # --- stateless effects the kernels read at every evaluation -----------------------------
    Field("torque_bias_mode", 1, "code", "Switch: a constant joint torque (a disturbance the "
          "model lacks: cable drag, a spring, an offset load) adds to the muscle torques",
          default=0.0),
    Field("torque_bias", 2, "N m", "the constant joint torques of torque_bias_mode",
          default=0.0),
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
#: stateless effects read by the kernels: a constant joint torque
TORQUE_BIAS_MODE, TORQUE_BIAS = PLANT.offsets("torque_bias_mode", "torque_bias")
#: offsets in the effect state z (:data:`EFFECT_STATE`); the delay line starts at Z_DELAY
Z_HYST, Z_HYST_W, Z_HYST_SLOPE, Z_HYST_DIR, Z_DELAY_COUNT = EFFECT_STATE.offsets(
    "hysteresis_memory", "hysteresis_output", "hysteresis_slope", "hysteresis_direction",
    "delay_count")
Z_DELAY = EFFECT_STATE.size
#: Effect fields applied when the row is packed (from ``ArmParameters.effects``): every field
#: of the effect section but the state length; they cannot be changed on a packed row by
#: :func:`ppamsafety.plant.packing.with_effects`.
PACK_TIME_EFFECTS = tuple(f.name for f in EFFECT_FIELDS if f.name != "effect_state_length")
NP = PLANT.size                        #: length of the row

#: Contraction floor used by the force/volume kernels (eps <= 0 is undefined).
EPS_FLOOR = 1e-3


def partial_row(values) -> np.ndarray:
    """A row with the given fields set and every other slot at its default (0).

    Parameters
    ----------
    values : dict
        Field name of :data:`PLANT` -> value (SI units).

    Returns
    -------
    numpy.ndarray, shape (NP,)
    """
    P = PLANT.empty()
    for name, v in values.items():
        P[PLANT.slice(name)] = v
    return P


def geometry_values(g) -> dict:
    """The geometry fields of :data:`PLANT` from an :class:`~ppamsafety.params.ArmGeometry`.

    Parameters
    ----------
    g : ArmGeometry
        Attachment points, link lengths and working area [m, rad].

    Returns
    -------
    dict
        Field name -> value, for :func:`partial_row`.
    """
    return {f.name: getattr(g, f.name) for f in GEOMETRY_FIELDS}
