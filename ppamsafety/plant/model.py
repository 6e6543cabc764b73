"""The assembled plant: one ODE for arm, muscles and valves.

State (8,): ``x = [q1, q2, qd1, qd2, p1, p2, p3, p4]`` (rad, rad/s, Pa gauge).
Input (4,): valve set values ``u = [p_s1 .. p_s4]`` (Pa), optional external
joint torques ``tau_ext`` (2,) (N m).

    qdd = H^-1 (sum_i p_i m_tau,i + tau_ext - C qd - G - tau_f)       (3.1), (2.17)
    pd_i = (v1_i + v2_i u_i - p_i)/T_i - n (P_atm + p_i) m_tau,i qd_j / V_i    (3.6), (3.12)

Integration is a fixed-step classical Runge-Kutta 4 (:func:`rk4_step`) with
the input held constant over the step (zero-order hold), the natural scheme
for a 1 kHz digital control loop: one control period is ``substeps`` RK4
steps.  Everything is a numba kernel; :func:`simulate` also accepts a leading
batch axis (one row of parameters, initial state and inputs per variant).

Effect state (issue 7, item 2)
------------------------------
Beside the 8 physical states every plant kernel carries an **effect-state
vector** ``z`` (float64, length ``effect_state_length`` of the parameter
row, read with :func:`effect_state_length`; zero-length when no effect with
state is on -- numba handles the empty array, no minimum length is needed).
It is the memory of optional plant effects that are not part of the ODE
state: Preisach hysteresis reversal points per muscle group, valve dead-time
delay lines, a payload that can be dropped ...  The kernels' signatures are
fixed once and for all::

    plant_rhs(x, z, u, tau_ext, P, dx, work)     # z read-only inside the RK4 stages
    rk4_step(x, z, u, tau_ext, h, P, work)       # ends with effects_update(x, z, u, P)
    effects_update(x, z, u, P)                   # once per RK4 step, after the step

With every effect off (the default of :func:`~ppamsafety.plant.packing.pack`)
``z`` is empty, :func:`effects_update` does nothing and the results are
bitwise those of the plant without the extension point
(``tests/test_golden.py``).

How to add an effect
~~~~~~~~~~~~~~~~~~~~
``docs/architecture.md`` ("Add an effect to the plant") lists the files each kind of effect
touches (:class:`~ppamsafety.params.effects.EffectKind`); the kernel side, in detail:

1. *Parameters.*  Add its fields to ``EFFECT_FIELDS`` in
   :mod:`ppamsafety.plant.layout` (name, length, unit, meaning with thesis
   reference), including an on/off (or mode) flag ``Field("<name>_mode", 1,
   "code", ..., default=0)`` whose codes are an ``enum.IntEnum`` declared
   there (``OFF = 0``).  Every default must mean "effect off".  The fields
   land in the plant row after the existing ones (nothing else moves), and
   ``tests/test_layouts.py`` round-trips them automatically.  Give the
   effect a way to be switched on: a field of
   :class:`~ppamsafety.params.effects.Effects` (``ArmParameters.effects``)
   that :func:`~ppamsafety.plant.packing.pack` writes into the plant-truth
   row, and/or :func:`~ppamsafety.plant.packing.with_effects` for packed rows.
2. *State.*  Declare the contents of its state in ``EFFECT_STATE`` (fixed
   size), or, for a variable-length memory, an offset/length pair in its
   parameters.  Whoever switches the effect on sets ``effect_state_length``
   of the row to cover it.
3. *Kernels.*  In :func:`effects_update` add ``if int(P[<NAME>_MODE]) ==
   <Enum>.ON: ...`` updating ``z`` from the step's end state ``x`` and input
   ``u`` (discrete memories: reversal points, delay-line shift).  Where the
   effect changes the dynamics, read ``z`` (and the flag) in
   :func:`plant_rhs` or in the leaf it concerns (the force law, the valve
   model), passing ``z`` down; ``z`` is constant over the four RK4 stages.
   A continuous-time effect state would instead need ``dz`` in the RK4
   stages (extend ``NWORK`` and :func:`rk4_step`).  Never change the
   signatures above.
4. *Initial state.*  :func:`simulate` starts from ``effect_state`` (default
   :func:`initial_effect_state`), the closed loop
   (:mod:`ppamsafety.experiments.closed_loop`) from :func:`effects_init`;
   if zero is not the effect's rest state, set it there (from the row).
5. *Tests.*  With the effect off, ``tests/test_golden.py`` must still pass
   bitwise; add a test of the effect itself, and a benchmark run
   (``studies/bench/bench_plant.py``) showing the cost of the check when off.

A stateless effect that the kernels read (``EffectKind.KERNEL``, e.g. the joint
torque bias: ``torque_bias_mode`` / ``torque_bias``, added to the joint torques in
:func:`plant_rhs` and held by the static equilibria of
:func:`~ppamsafety.plant.pneumatics.gravity_compensation_dp`) needs steps 1 and 3
without state.  An effect that is a pure change of plant *parameters* needs none of steps
2-4: it is folded into the plant-truth row by
:func:`~ppamsafety.plant.packing.pack` from ``ArmParameters.effects``
(:class:`~ppamsafety.params.effects.Effects`) and only flagged in the effect
section.  That is how the parameter-only effects work -- payload at A_L (folded
into theta), plant friction, valve offset/gain/time constant and polytropic
exponent that differ from the controllers' belief -- so the kernels are
untouched and a row with every effect off is bitwise the nominal row.
Different rows of one batch may carry different effects (``simulate`` with
a list of arms).

Effects with state (implemented)
~~~~~~~~~~~~~~~~~~~~~~~~~~~~~~~~
*Muscle force hysteresis* (thesis §3.6, (3.31)-(3.35);
``Effects.hysteresis_delta``).  Parameters ``hysteresis_*`` of the row
(delta per group, eps_max = 0.35, the W_fit line, the initial memories);
state: one Preisach memory row per group (:mod:`ppamsafety.hysteresis.memory`,
``STATE_LENGTH`` floats, at ``Z_HYST + k STATE_LENGTH``) plus the output W at
the committed input, the secant slope and direction of the last move
(:data:`~ppamsafety.plant.layout.EFFECT_STATE`).  In :func:`plant_rhs` the
torque of group k is ``p_k * mt[k] * (1 + delta_k (W_k - W_fit(eps_s,k)))``,
the factor of (3.35) on the force p l0^2 f(eps) (f: the group's identified
polynomial of Table B.1, the plant's f_t0^fit; see
:mod:`ppamsafety.params.effects`).  The factor multiplies only the torques
``tau1``, ``tau2``, NOT the ``mt`` passed to
:func:`~ppamsafety.plant.pneumatics.pressure_rates`: there m_tau is the
volume derivative dV/dq (virtual work, (3.5)), geometric, without force
hysteresis.  The contraction comes from
:func:`~ppamsafety.plant.torque.group_terms` (same arithmetic as
:func:`~ppamsafety.plant.torque.torque_kernel_cs`), so delta = 0 is bitwise
the nominal plant.  Memory: :func:`effects_update` commits the end-of-step
eps_s of each group once per accepted RK4 step (``preisach_update``); a
turning point of eps inside a step is registered at the end of the step, an
O(h) error in the position of one reversal (0.5-1 ms), the order of any
discrete-time record.  Stages: the memory is frozen over the four stages;
stage 1 sits on the committed input (cached W, exact); stages 2-4 use, by
default (``HysteresisStages.SECANT``), W(u) + s (v - u) with s the secant of
the last step while the stage continues the last move, and W(u) for a stage
that reverses it (a new reversal branch starts with zero slope: its weight
grows like (v - u)^2).  Both errors are O(dv^2) per stage, dv <= one step's
change of eps_s (~1e-3), i.e. ~1e-7 in the force factor, far below the O(h)
turning-point registration; ``Effects.hysteresis_exact_stages`` evaluates
``preisach_peek`` at every stage instead (4x the Everett evaluations; the
test suite checks the two agree to 1e-3 of the hysteresis effect).  Cost
(measured, closed loop of ``studies/bench/bench_closed_loop.py``): 1.75x the
nominal run with the secant stages (3.8x with exact peeks).  The
controllers' model rows carry no hysteresis (they do not know about it).

*Valve dead time* (``Effects.valve_dead_time``): :func:`valve_delay`
replaces the set values of control period k by u_i[k - d_i] from a ring
buffer in z (at ``Z_DELAY``, D = max d_i + 1 samples per valve, primed with
the first set value); called once per period by :func:`simulate` and the
closed loop (:mod:`ppamsafety.experiments.closed_loop`) before integrating.

Initial state: :func:`effects_init` (kernels) / :func:`initial_effect_state`
(Python) set z at t = 0 from the row; both runners call it.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel, step_kernel, kernel_array, leaf
from .._validation import (as_float_array, check_bool, check_finite_result, check_int,
                           check_range, check_size)
from ..hysteresis.force import hysteresis_factor, scaled_contraction
from ..hysteresis.memory import MAX_DEPTH, MEMORY, preisach_output, preisach_peek, \
    preisach_update
from ..layouts import Field, Layout
from . import layout as lay
from . import packing
from ._checks import (accelerations, angles, check_arm, check_pressures, checks_arm,  # noqa: F401
                      speeds, torques)
from .dynamics import forward_dynamics_cs
from .layout import (DEAD, DEAD_LEN, DEAD_MODE, HYST_DELTA, HYST_EPS_MAX, HYST_INIT, HYST_MODE,
                     HYST_ROW, HYST_STAGES, HYST_WFIT_INTERCEPT, HYST_WFIT_SLOPE, NZ, Z_DELAY,
                     Z_DELAY_COUNT, Z_HYST, Z_HYST_DIR, Z_HYST_SLOPE, Z_HYST_W, HysteresisStages,
                     Switch, TORQUE_BIAS, TORQUE_BIAS_MODE)
from .pneumatics import pressure_rates_at, static_pressures
from .torque import group_contraction, group_terms

#: The plant state x, one row per batch case (thesis (3.1), (3.6)).
STATE = Layout("plant state", [
    Field("q", 2, "rad", "joint angles q1, q2 (2.6)-(2.7)"),
    Field("qd", 2, "rad/s", "joint velocities"),
    Field("p", 4, "Pa", "gauge pressures of muscle groups 1..4 (3.6)"),
])
X_Q, X_QD, X_P = STATE.offsets("q", "qd", "p")
NX = STATE.size  #: state dimension
NU = 4           #: input dimension (valve set values u1..u4 [Pa])
#: Scratch of :func:`plant_rhs`: torque-kernel outputs and the hysteresis factors.
RHS_SCRATCH = Layout("plant_rhs scratch", [
    Field("m_tau", 4, "m^3", "torque functions m_tau,i of groups 1..4 (2.10)"),
    Field("dm_tau", 4, "m^3/rad", "their derivatives along the driven joint"),
    Field("volume", 4, "m^3", "group volumes (2.4)"),
    Field("hyst_factor", 4, "-", "hysteresis force factors (3.35) (used only when on)"),
])
W_MT, W_DMT, W_VOL, W_FAC = RHS_SCRATCH.offsets("m_tau", "dm_tau", "volume", "hyst_factor")
NRHS = RHS_SCRATCH.size
#: Scratch of :func:`rk4_step`: the four stage derivatives, the stage state, plant_rhs scratch.
RK4_SCRATCH = Layout("rk4_step scratch", [
    Field("k1", NX, "state/s", "stage 1 derivative"),
    Field("k2", NX, "state/s", "stage 2 derivative"),
    Field("k3", NX, "state/s", "stage 3 derivative"),
    Field("k4", NX, "state/s", "stage 4 derivative"),
    Field("x_stage", NX, "state", "the state at which a stage is evaluated"),
    Field("rhs", NRHS, "-", "scratch of plant_rhs (RHS_SCRATCH)"),
])
W_K1, W_K2, W_K3, W_K4, W_XT, W_RHS = RK4_SCRATCH.offsets("k1", "k2", "k3", "k4", "x_stage",
                                                           "rhs")
NWORK = RK4_SCRATCH.size
#: Offsets of the four stage derivatives in the RK4 work memory.
_STAGE_OFFSETS = (W_K1, W_K2, W_K3, W_K4)
#: Largest stage change of eps_s evaluated by the secant scheme (HysteresisStages.SECANT);
#: beyond it the stage uses preisach_peek.  0.01 (an eps change of 0.00175, a contraction
#: rate of 1.75 /s over a 1 ms step) is reached only by jumps (the first step from a
#: saturated initial memory), not by the motions of the experiments.
SECANT_MAX_STEP = 0.01
#: offset of the current input in a Preisach memory row (hysteresis.memory.MEMORY)
_MEM_INPUT = MEMORY.offset("input")
_MEM_DEPTH = MEMORY.offset("depth")


@kernel
def effect_state_length(P):
    """Length of the effect-state vector z that plant row ``P`` needs.

    Parameters
    ----------
    P : float64[:]
        Plant row (layout :data:`~ppamsafety.plant.layout.PLANT`); its
        ``effect_state_length`` slot is read (not validated; see
        :func:`~ppamsafety.plant.layout.effect_state_lengths`).

    Returns
    -------
    int
        Number of floats of z (0 when no effect with state is on).
    """
    return int(P[NZ])


@leaf
def effects_update(x, z, u, P):
    """Update the effect state ``z`` after an integration step ending in state ``x``.

    Called once per RK4 step (by :func:`rk4_step`) with the step's input
    ``u``.  Muscle hysteresis: commits each group's end-of-step scaled
    contraction eps_s (3.34) to its Preisach memory (:func:`preisach_update`)
    and caches the output W.  Every other effect: nothing (with every effect
    off this is one flag test).

    Parameters
    ----------
    x : float64[:]
        State at the end of the step (8,).
    z : float64[:]
        Effect state, updated in place.
    u : float64[:]
        Set values of the step (4,) [Pa].
    P : float64[:]
        Plant row.
    """
    if int(P[HYST_MODE]) == Switch.ON:
        c1, s1 = math.cos(x[X_Q]), math.sin(x[X_Q])
        c2, s2 = math.cos(x[X_Q + 1]), math.sin(x[X_Q + 1])
        c12, s12 = c1 * c2 - s1 * s2, s1 * c2 + c1 * s2
        for k in range(4):
            es = scaled_contraction(group_contraction(k, c1, s1, c12, s12, P), P[HYST_EPS_MAX])
            o = Z_HYST + k * HYST_ROW
            u_old = z[o + _MEM_INPUT]
            w_old = z[Z_HYST_W + k]
            w = preisach_update(z, es, o)
            z[Z_HYST_W + k] = w
            du = z[o + _MEM_INPUT] - u_old
            if du != 0.0:                       # secant of this step, for the next stages
                z[Z_HYST_SLOPE + k] = (w - w_old) / du
                z[Z_HYST_DIR + k] = 1.0 if du > 0.0 else -1.0


@kernel
def effects_init(z, P):
    """Set the effect state ``z`` of plant row ``P`` to its value at t = 0 (in place).

    Hysteresis: the initial Preisach memories stored in the row
    (``hysteresis_initial``, from ``Effects.hysteresis_initial``) and their
    outputs; dead time: an empty delay line (primed with the first set value
    by :func:`valve_delay`).  Nothing for a row without effects with state.

    Parameters
    ----------
    z : float64[:]
        Effect state of the row (length ``effect_state_length``), written.
    P : float64[:]
        Plant row.
    """
    if int(P[HYST_MODE]) == Switch.ON:
        for i in range(4 * HYST_ROW):
            z[Z_HYST + i] = P[HYST_INIT + i]
        for k in range(4):
            z[Z_HYST_W + k] = preisach_output(z, Z_HYST + k * HYST_ROW)
            z[Z_HYST_SLOPE + k] = 0.0
            z[Z_HYST_DIR + k] = 0.0
    if int(P[DEAD_MODE]) == Switch.ON:
        z[Z_DELAY_COUNT] = 0.0


@step_kernel
def valve_delay(z, u, P):
    """Valve dead time: replace the set values ``u`` (4) [Pa] in place by u_i[k - d_i].

    Call once per control period (input sample) k, in order, before the
    plant is integrated over it.  The delay line (a ring of D = max d_i + 1
    samples per valve in ``z`` at :data:`~ppamsafety.plant.layout.Z_DELAY`)
    is primed with the first set value: before t = 0 the valves received
    u[0].  Does nothing when the dead time is off.

    Parameters
    ----------
    z : float64[:]
        Effect state (holds the delay line), updated in place.
    u : float64[:]
        Set values of this period (4,) [Pa]; overwritten by the delayed ones.
    P : float64[:]
        Plant row.
    """
    if int(P[DEAD_MODE]) == Switch.ON:
        D = int(P[DEAD_LEN])
        c = int(z[Z_DELAY_COUNT])
        if c == 0:
            for i in range(4):
                for j in range(D):
                    z[Z_DELAY + i * D + j] = u[i]
        slot = c % D
        for i in range(4):
            z[Z_DELAY + i * D + slot] = u[i]
            u[i] = z[Z_DELAY + i * D + (slot - int(P[DEAD + i]) + D) % D]
        z[Z_DELAY_COUNT] = c + 1


@leaf
def _hysteresis_factor(k, eps, z, P):
    """Force factor 1 + delta (W - W_fit) of (3.35) for group ``k`` at contraction ``eps``.

    W from the group's memory in ``z`` without writing it.  At the
    committed input (the first RK4 stage) the cached output of the last
    update (the same value).  Elsewhere, ``HysteresisStages.EXACT``:
    :func:`preisach_peek`; ``SECANT`` (default): W(u) + s (v - u) while the
    stage input v continues the last move (s its secant slope), W(u) for a
    stage that reverses it (a fresh reversal branch starts with zero slope),
    and :func:`preisach_peek` when there is no last move yet or the stage is
    far from the committed input (|v - u| > :data:`SECANT_MAX_STEP`, e.g.
    the first step from a saturated initial memory).
    """
    es = scaled_contraction(eps, P[HYST_EPS_MAX])
    o = Z_HYST + k * HYST_ROW
    dv = es - z[o + _MEM_INPUT]
    d = z[Z_HYST_DIR + k]
    if dv == 0.0:
        w = z[Z_HYST_W + k]
    elif (int(P[HYST_STAGES]) == HysteresisStages.EXACT or d == 0.0
          or abs(dv) > SECANT_MAX_STEP):
        w = preisach_peek(z, es, o)
    elif dv * d > 0.0:
        w = z[Z_HYST_W + k] + z[Z_HYST_SLOPE + k] * dv
        w = 1.0 if w > 1.0 else (-1.0 if w < -1.0 else w)
    else:
        w = z[Z_HYST_W + k]
    return hysteresis_factor(P[HYST_DELTA + k], w, es, P[HYST_WFIT_SLOPE],
                             P[HYST_WFIT_INTERCEPT])


@step_kernel
def plant_rhs(x, z, u, tau_ext, P, dx, work):
    """State derivative of the plant; writes ``dx`` (8,).  ``work`` >= NRHS (16) floats.

    ``z`` is the effect state (read-only here; see the module docstring).
    With the muscle hysteresis on, the force of group k in the joint
    torques is multiplied by the factor of (3.35) (not the volume
    derivative m_tau in the pressure dynamics); with the torque bias on, its
    constant joint torques add to the muscle torques.

    Parameters
    ----------
    x : float64[:]
        State (8,) [q1, q2, qd1, qd2, p1..p4] (rad, rad/s, Pa gauge).
    z : float64[:]
        Effect state (length ``effect_state_length`` of ``P``, may be
        empty), read only.
    u : float64[:]
        Valve set values (4,) [Pa].
    tau_ext : float64[:]
        External joint torques (2,) [N m].
    P : float64[:]
        Plant row (layout :data:`~ppamsafety.plant.layout.PLANT`).
    dx : float64[:]
        State derivative (8,) (rad/s, rad/s^2, Pa/s), written.
    work : float64[:]
        Work memory, at least :data:`NRHS` (16) floats: m_tau, d m_tau/dq,
        volumes and (hysteresis on) force factors of the four groups;
        overwritten.
    """
    zero = np.int64(0)          # not a compile-time constant: one compiled plant_rhs_at
    plant_rhs_at(x, zero, z, u, tau_ext, P, dx, zero, work, zero)


@step_kernel
def plant_rhs_at(x, xo, z, u, tau_ext, P, dx, do, work, wo):
    """:func:`plant_rhs` on the state ``x[xo:xo + 8]`` into ``dx[do:do + 8]``, with the work
    memory ``work[wo:wo + NRHS]``.

    Offsets instead of views: in compiled code every view of an array costs two atomic
    updates of its reference count, which took a sixth of the closed loop's time when the
    RK4 step handed views of its work memory to each stage.

    Parameters
    ----------
    x : float64[:]
        Holds the state (8,) from ``xo``.
    xo : int
        Offset of the state in ``x``.
    z, u, tau_ext, P
        As in :func:`plant_rhs`.
    dx : float64[:]
        Receives the state derivative (8,) from ``do``.
    do : int
        Offset of the derivative in ``dx``.
    work : float64[:]
        Work memory: :data:`NRHS` floats from ``wo`` (layout :data:`RHS_SCRATCH`),
        overwritten.
    wo : int
        Offset of the work memory.
    """
    mo, vo = wo + W_MT, wo + W_VOL
    c1, s1 = math.cos(x[xo + X_Q]), math.sin(x[xo + X_Q])
    c2, s2 = math.cos(x[xo + X_Q + 1]), math.sin(x[xo + X_Q + 1])
    c12, s12 = c1 * c2 - s1 * s2, s1 * c2 + c1 * s2
    p0 = xo + X_P
    if int(P[HYST_MODE]) == Switch.ON:
        fo = wo + W_FAC
        for k in range(4):
            work[mo + k], _, work[vo + k], eps = group_terms(k, c1, s1, c12, s12, P)
            work[fo + k] = _hysteresis_factor(k, eps, z, P)
        tau1 = (x[p0] * (work[mo] * work[fo]) + x[p0 + 1] * (work[mo + 1] * work[fo + 1])
                + tau_ext[0])
        tau2 = (x[p0 + 2] * (work[mo + 2] * work[fo + 2])
                + x[p0 + 3] * (work[mo + 3] * work[fo + 3]) + tau_ext[1])
    else:
        for k in range(4):
            work[mo + k], _, work[vo + k], _ = group_terms(k, c1, s1, c12, s12, P)
        tau1 = x[p0] * work[mo] + x[p0 + 1] * work[mo + 1] + tau_ext[0]
        tau2 = x[p0 + 2] * work[mo + 2] + x[p0 + 3] * work[mo + 3] + tau_ext[1]
    if int(P[TORQUE_BIAS_MODE]) == Switch.ON:
        tau1 += P[TORQUE_BIAS]
        tau2 += P[TORQUE_BIAS + 1]
    w1, w2 = x[xo + X_QD], x[xo + X_QD + 1]
    a1, a2 = forward_dynamics_cs(c1, s1, c2, s2, c12, s12, w1, w2, tau1, tau2, P)
    dx[do + X_Q] = w1
    dx[do + X_Q + 1] = w2
    dx[do + X_QD] = a1
    dx[do + X_QD + 1] = a2
    pressure_rates_at(x, p0, u, w1, w2, work, mo, work, vo, P, dx, do + X_P)


@step_kernel
def rk4_step(x, z, u, tau_ext, h, P, work):
    """Advance ``x`` in place by one RK4 step of length ``h`` [s] (inputs held).

    The effect state ``z`` is held over the stages and updated once at the
    end by :func:`effects_update`.

    Parameters
    ----------
    x : float64[:]
        State (8,) [q1, q2, qd1, qd2, p1..p4] (rad, rad/s, Pa gauge),
        updated in place.
    z : float64[:]
        Effect state (length ``effect_state_length`` of ``P``, may be
        empty), updated in place at the end of the step.
    u : float64[:]
        Valve set values (4,) [Pa], held over the step.
    tau_ext : float64[:]
        External joint torques (2,) [N m], held over the step.
    h : float
        Step length [s].
    P : float64[:]
        Plant row (layout :data:`~ppamsafety.plant.layout.PLANT`).
    work : float64[:]
        Work memory, at least :data:`NWORK` (5 * 8 + 16) floats: the four
        stage derivatives, the stage state and the :func:`plant_rhs` work;
        overwritten.
    """
    # one call site of the derivative, with offsets that are not compile-time constants:
    # numba compiles a kernel once per distinct constant argument
    for stage in range(4):
        src = x if stage == 0 else work
        plant_rhs_at(src, np.int64(0 if stage == 0 else W_XT), z, u, tau_ext, P, work,
                     _STAGE_OFFSETS[stage], work, np.int64(W_RHS))
        if stage < 3:
            c = h if stage == 2 else 0.5 * h       # x + h/2 k1, x + h/2 k2, x + h k3
            o = _STAGE_OFFSETS[stage]
            for i in range(NX):
                work[W_XT + i] = x[i] + c * work[o + i]
    for i in range(NX):
        x[i] += h / 6.0 * (work[W_K1 + i] + 2.0 * work[W_K2 + i] + 2.0 * work[W_K3 + i]
                           + work[W_K4 + i])
    effects_update(x, z, u, P)


@kernel
def _simulate_batch(X0, Z, U, TAU, dt, substeps, P, out):
    nb = X0.shape[0]
    nsteps = U.shape[1]
    work = np.empty(NWORK)
    x = np.empty(NX)
    h = dt / substeps
    u = np.empty(NU)
    tau = np.empty(2)
    for b in range(nb):
        x[:] = X0[b]
        Pb = P[b].copy()
        z = Z[b, :effect_state_length(Pb)]      # in place: Z returns the final effect states
        out[b, 0] = x
        for k in range(nsteps):
            u[:] = U[b, k]
            valve_delay(z, u, Pb)                # dead time (off: nothing)
            tau[:] = TAU[b, k]
            for _ in range(substeps):
                rk4_step(x, z, u, tau, h, Pb, work)
            out[b, k + 1] = x


#: Memory of one simulated sample of one batch row [bytes]: the copied set values and
#: torques, the states returned and the kernel's work (120 bytes measured with
#: ``tracemalloc``, rounded up).
SIM_BYTES_PER_SAMPLE = 160


def check_simulation_size(rows: int, samples: int) -> None:
    """Refuse a simulation whose arrays would exceed :data:`ppamsafety._validation.MAX_BYTES`.

    Parameters
    ----------
    rows : int
        Batch rows.
    samples : int
        Samples (control intervals) per row.
    """
    check_size(f"a simulation of {rows:,} batch row(s) x {samples:,} samples",
               rows * samples * SIM_BYTES_PER_SAMPLE,
               remedy="simulate shorter pieces (return_effect_state=True continues a run) or "
                      "fewer rows at once")


def simulate(arm, x0, set_values, *, dt: float = 1e-3, substeps: int = 2,
             tau_ext=None, params=None, effect_state=None, return_effect_state: bool = False):
    """Simulate the plant with piecewise-constant valve set values.

    Parameters
    ----------
    arm : ArmParameters or sequence of ArmParameters
        The arm.  A sequence (one per batch row) runs parameter variants.
    x0 : array_like, shape (8,) or (B, 8)
        Initial state [q1, q2, qd1, qd2, p1..p4] (rad, rad/s, Pa).
    set_values : array_like, shape (N, 4) or (B, N, 4)
        Valve set values held over each interval of length ``dt`` [Pa].  With
        a valve dead time d_i (``Effects.valve_dead_time``) the plant receives
        sample k - d_i in interval k (sample 0 before that).
    dt : float, keyword-only
        Input (control) period [s]; default 1 ms.
    substeps : int, keyword-only
        RK4 steps per ``dt``.
    tau_ext : array_like, shape (N, 2) or (B, N, 2), optional
        External joint torques [N m].
    params : numpy.ndarray, shape (NP,) or (B, NP), optional
        Pre-packed parameter rows (overrides ``arm``; for sweeps).
    effect_state : array_like, shape (nz,) or (B, nz), optional
        Initial effect state z (see the module docstring); ``nz`` must be at
        least the largest ``effect_state_length`` of the rows (each row uses
        its first ``effect_state_length`` entries).  Default
        :func:`initial_effect_state` (zeros when no effect with state is on;
        the Preisach memories of ``Effects.hysteresis_initial``; an empty
        delay line).  A given state is used as is (e.g. one returned with
        ``return_effect_state`` to continue a run); its Preisach memories are
        validated.
    return_effect_state : bool, keyword-only
        Also return the final effect states.

    Returns
    -------
    numpy.ndarray, shape (N + 1, 8) or (B, N + 1, 8)
        States at t = 0, dt, ..., N dt.
    numpy.ndarray, shape (nz,) or (B, nz)
        Only with ``return_effect_state``: the effect states after the last
        step (entries beyond a row's ``effect_state_length`` unchanged).
    """
    dt = check_range("dt", dt, 1e-6, 1.0, unit="s")
    return_effect_state = check_bool("return_effect_state", return_effect_state)
    substeps = check_int("substeps", substeps, 1, 10000)
    x0 = _state("x0", x0)
    shape = np.shape(set_values) if isinstance(set_values, np.ndarray) else ()
    if len(shape) in (2, 3):            # sized before the array is checked or copied
        check_simulation_size(shape[0] if len(shape) == 3 else 1, shape[-2])
    U = check_pressures("set_values", set_values, tail=NU)
    if U.ndim not in (2, 3):
        raise ValueError(f"set_values must have shape (N, 4) or (B, N, 4), got {U.shape}")
    if x0.ndim not in (1, 2):
        raise ValueError(f"x0 must have shape (8,) or (B, 8), got {x0.shape}")
    batched = x0.ndim == 2 or U.ndim == 3
    X0 = np.atleast_2d(x0)
    if U.ndim == 2:
        U = U[None]
    B = max(X0.shape[0], U.shape[0])
    if params is None:
        arms = list(arm) if isinstance(arm, (list, tuple)) else [arm]
        if not arms:
            raise ValueError("arm must be an ArmParameters or a non-empty sequence of them")
        for i, a in enumerate(arms):
            check_arm(a, "arm" if len(arms) == 1 and not isinstance(arm, (list, tuple))
                      else f"arm[{i}]")
        rows = np.array([packing.pack(a) for a in arms])
    else:
        rows = np.atleast_2d(as_float_array("params", params, shape_tail=(lay.NP,)))
    B = max(B, rows.shape[0])
    check_simulation_size(B, U.shape[1])
    for name, n_rows in (("x0", X0.shape[0]), ("set_values", U.shape[0]),
                         ("params" if params is not None else "arm", rows.shape[0])):
        if n_rows not in (1, B):
            raise ValueError(f"{name} has {n_rows} batch rows; every batched argument must have "
                             f"1 or B = {B}")
    X0 = np.array(np.broadcast_to(X0, (B, NX)))          # writable C copies: one
    U = np.array(np.broadcast_to(U, (B,) + U.shape[1:]))  # numba signature for all
    rows = np.array(np.broadcast_to(rows, (B, lay.NP)))
    if tau_ext is None:
        T = np.zeros((B, U.shape[1], 2))
    else:
        T = torques("tau_ext", tau_ext)
        T = np.array(np.broadcast_to(T if T.ndim == 3 else T[None], (B, U.shape[1], 2)))
    check_valve_step(rows, dt / substeps)
    nz = int(packing.effect_state_lengths(rows).max())
    if effect_state is None:
        Z = initial_effect_state(rows)
    else:
        Z = as_float_array("effect_state", effect_state)
        if Z.ndim not in (1, 2) or Z.shape[-1] < nz or (Z.ndim == 2 and Z.shape[0] not in (1, B)):
            raise ValueError(f"effect_state must have shape (nz,) or ({B}, nz) with nz >= {nz} "
                             f"(the rows' effect_state_length), got {Z.shape}")
        batched = batched or Z.ndim == 2
        Z = np.array(np.broadcast_to(Z if Z.ndim == 2 else Z[None], (B, Z.shape[-1])))
        _check_effect_state(Z, rows)
    out = np.empty((B, U.shape[1] + 1, NX))
    X0, U, T, rows = kernel_array(X0), kernel_array(U), kernel_array(T), kernel_array(rows)
    Z = kernel_array(Z)
    _simulate_batch(X0, Z, U, T, float(dt), substeps, rows, out)
    bad = np.argwhere(~np.isfinite(out))
    if bad.size:
        b, k = int(bad[0][0]), int(bad[0][1])
        raise ValueError(f"simulate: the state of batch row {b} became non-finite at step {k} "
                         f"(t = {k * dt:g} s): x0 and set_values drive the plant out of the range "
                         f"where the model is valid")
    if not (batched or B > 1):
        out, Z = out[0], Z[0]
    return (out, Z) if return_effect_state else out


def initial_effect_state(rows) -> np.ndarray:
    """Effect states z at t = 0 of plant rows (see :func:`effects_init`).

    Parameters
    ----------
    rows : numpy.ndarray, shape (NP,) or (B, NP)
        Packed plant rows.

    Returns
    -------
    numpy.ndarray, shape (B, nz)
        One z per row, nz the largest ``effect_state_length`` (each row uses
        its first ``effect_state_length`` entries; zeros when no effect with
        state is on).
    """
    rows = np.atleast_2d(np.asarray(rows, dtype=float))   # inf allowed: closed valves
    if rows.ndim != 2 or rows.shape[1] != lay.NP:
        raise ValueError(f"rows must have shape ({lay.NP},) or (B, {lay.NP}), got {rows.shape}")
    n = packing.effect_state_lengths(rows)
    Z = np.zeros((rows.shape[0], int(n.max())))
    _init_many(Z, kernel_array(rows))
    return Z


@kernel
def _init_many(Z, rows):
    for b in range(Z.shape[0]):
        effects_init(Z[b, :effect_state_length(rows[b])], rows[b])


@kernel
def _refresh_outputs(Z, rows):
    for b in range(Z.shape[0]):
        if int(rows[b, HYST_MODE]) == Switch.ON:
            for k in range(4):
                Z[b, Z_HYST_W + k] = preisach_output(Z[b], Z_HYST + k * HYST_ROW)
                if not (Z[b, Z_HYST_DIR + k] == 1.0 or Z[b, Z_HYST_DIR + k] == -1.0):
                    Z[b, Z_HYST_DIR + k] = 0.0      # no valid secant: frozen W until a move


def _check_effect_state(Z, rows) -> None:
    """Validate given effect states (Preisach memories) and refresh their output caches."""
    hyst = rows[:, HYST_MODE] == Switch.ON
    if not hyst.any():
        return
    mem = Z[hyst][:, Z_HYST:Z_HYST + 4 * HYST_ROW].reshape(-1, 4, HYST_ROW)
    depth = mem[..., _MEM_DEPTH]
    u = mem[..., _MEM_INPUT]
    if not (np.all((depth == np.round(depth)) & (depth >= 1) & (depth <= MAX_DEPTH))
            and np.all(np.abs(u) <= 1.0)):
        raise ValueError(f"effect_state: the Preisach memories (z[{Z_HYST}:"
                         f"{Z_HYST + 4 * HYST_ROW}]) of a row with hysteresis are not memory "
                         f"rows (depth 1..{MAX_DEPTH}, input in [-1, 1]); start from "
                         f"initial_effect_state(rows) or a returned effect state")
    _refresh_outputs(Z, np.ascontiguousarray(rows))


@kernel
def _hysteresis_along(X, z, P, eps_out, fac_out):
    u = np.zeros(NU)
    for n in range(X.shape[0]):
        x = X[n]
        c1, s1 = math.cos(x[X_Q]), math.sin(x[X_Q])
        c2, s2 = math.cos(x[X_Q + 1]), math.sin(x[X_Q + 1])
        c12, s12 = c1 * c2 - s1 * s2, s1 * c2 + c1 * s2
        effects_update(x, z, u, P)
        for k in range(4):
            eps = group_contraction(k, c1, s1, c12, s12, P)
            eps_out[n, k] = eps
            fac_out[n, k] = _hysteresis_factor(k, eps, z, P)   # at the committed input


def hysteresis_factors(states, arm=None, *, params=None, effect_state=None):
    """The plant's hysteresis force factors (3.35) along a state trajectory.

    Each state is committed to the memories as the end of one accepted
    integration step, as in :func:`simulate`, and the factor is the exact
    one at that state (the value the plant uses at the first stage of the
    next step).  For the output of :func:`simulate` (one state per control
    period, several RK4 steps each) this reproduces the plant's factors at
    the samples up to the registration of turning points between samples.  Use it to plot the
    plant's force-contraction loop: muscle force of group k = p_k f_k(eps_k)
    * factor_k (per unit l0^2, Table B.1 polynomial (3.9)).

    Parameters
    ----------
    states : array_like, shape (N, 8)
        Plant states [q1, q2, qd1, qd2, p1..p4] (only q is used) [rad, ...].
    arm : ArmParameters, optional
        The arm; its ``effects.hysteresis_delta`` must be set.
    params : numpy.ndarray, shape (NP,), optional
        A packed plant row instead of ``arm``.
    effect_state : array_like, shape (>= EFFECT_STATE.size,), optional
        Initial effect state; default :func:`initial_effect_state`.

    Returns
    -------
    eps : numpy.ndarray, shape (N, 4)
        Contractions of the four muscle groups [-].
    factor : numpy.ndarray, shape (N, 4)
        1 + delta_k (W_k - W_fit) [-].

    Raises
    ------
    ValueError
        If the row has no hysteresis, or for bad shapes.
    """
    X = np.ascontiguousarray(as_float_array("states", states, shape_tail=(NX,)))
    if X.ndim != 2:
        raise ValueError(f"states must have shape (N, {NX}), got {X.shape}")
    if params is None:
        if arm is None:
            raise ValueError("hysteresis_factors needs arm or params")
        P = packing.pack(arm)
    else:
        P = as_float_array("params", params, shape_tail=(lay.NP,))
        if P.ndim != 1:
            raise ValueError(f"params must be one row of shape ({lay.NP},), got {P.shape}")
    if int(P[HYST_MODE]) != Switch.ON:
        raise ValueError("hysteresis_factors: the plant row has no hysteresis "
                         "(set ArmParameters.effects.hysteresis_delta)")
    P = np.ascontiguousarray(P)
    if effect_state is None:
        z = initial_effect_state(P)[0]
    else:
        z = as_float_array("effect_state", effect_state).copy()
        if z.shape != (int(P[NZ]),) and not (z.ndim == 1 and z.size >= lay.EFFECT_STATE.size):
            raise ValueError(f"effect_state must have shape (>= {lay.EFFECT_STATE.size},), "
                             f"got {z.shape}")
        z = np.ascontiguousarray(z)
        _check_effect_state(z[None], P[None])
        z = z if z.flags.writeable else z.copy()
    eps = np.empty((X.shape[0], 4))
    fac = np.empty((X.shape[0], 4))
    _hysteresis_along(kernel_array(X), kernel_array(z), kernel_array(P), eps, fac)
    return eps, fac


def check_valve_step(rows, h: float) -> None:
    """Check that the RK4 step ``h`` resolves every valve time constant of ``rows``.

    The first-order valve lag (3.2) is integrated explicitly; a time constant
    T below the step (h/T > 1) is poorly resolved and, beyond h/T = 2.78,
    unstable.  Plant rows whose valve time constants come from
    ``ArmParameters.effects`` can be as fast as 1 ms
    (:mod:`ppamsafety.params.effects`), so the integrator's step is checked
    here rather than in the parameters.

    Parameters
    ----------
    rows : numpy.ndarray, shape (NP,) or (B, NP)
        Packed plant rows.
    h : float
        Integration step [s].

    Raises
    ------
    ValueError
        If a row has a valve time constant T < h (naming the row, valve and values).
    """
    tv = np.atleast_2d(rows)[:, lay.PLANT.slice("tv")]
    bad = np.argwhere(tv < h)
    if bad.size:
        b, i = (int(v) for v in bad[0])
        raise ValueError(f"params: row {b} valve {i + 1} time constant {tv[b, i]:g} s is below "
                         f"the integration step h = dt/substeps = {h:g} s; use more substeps "
                         f"(h <= T) or a slower valve")


@checks_arm
def state_derivative(x, set_values, arm, *, tau_ext=None) -> np.ndarray:
    """Plant state derivative for states ``x`` (..., 8) and inputs (..., 4).

    Parameters
    ----------
    x : array_like, shape (..., 8)
        States [q1, q2, qd1, qd2, p1..p4] (rad, rad/s, Pa): |q| <= 2 pi,
        |qd| <= 1000 rad/s, p in [-1 atm, 100 bar].
    set_values : array_like, shape (..., 4)
        Valve set values [Pa] (broadcast against ``x``).
    arm : ArmParameters
        The plant.
    tau_ext : array_like, shape (..., 2), optional
        External joint torques [N m], |tau| <= 1e4.

    Returns
    -------
    numpy.ndarray, shape (..., 8)
        dx/dt (finite; otherwise ``ValueError``).
    """
    x = _state("x", x)
    u = check_pressures("set_values", set_values, tail=NU)
    tau = None if tau_ext is None else torques("tau_ext", tau_ext)
    lead = [("x", x.shape), ("set_values", u.shape)] + (
        [] if tau is None else [("tau_ext", tau.shape)])
    try:
        shape = np.broadcast_shapes(*(s[:-1] for _, s in lead))
    except ValueError:
        raise ValueError("the leading dimensions of " + ", ".join(
            f"{n} (shape {s})" for n, s in lead) + " do not broadcast against each other; "
            "allowed: x (..., 8), set_values (..., 4), tau_ext (..., 2) with broadcastable "
            "'...'") from None
    xf = np.ascontiguousarray(np.broadcast_to(x, shape + (NX,)).reshape(-1, NX))
    uf = np.ascontiguousarray(np.broadcast_to(u, shape + (NU,)).reshape(-1, NU))
    tf = np.zeros((xf.shape[0], 2)) if tau is None else np.ascontiguousarray(
        np.broadcast_to(tau, shape + (2,)).reshape(-1, 2))
    out = np.empty_like(xf)
    _rhs_many(kernel_array(xf), kernel_array(uf), kernel_array(tf), kernel_array(packing.pack(arm)),
              out)
    return check_finite_result("state_derivative", out.reshape(shape + (NX,)), "these x, "
                               "set_values (the state is outside the model's valid range)")


def _state(name: str, x) -> np.ndarray:
    """Plant states (..., 8): angles, speeds and pressures in their ranges (``_checks``)."""
    x = as_float_array(name, x, shape_tail=(NX,))
    angles(f"{name}[..., 0:2] (q)", x[..., 0:2])
    speeds(f"{name}[..., 2:4] (qd)", x[..., 2:4])
    check_pressures(f"{name}[..., 4:8] (p)", x[..., 4:8])
    return x


@kernel
def _rhs_many(X, U, T, P, out):
    work = np.empty(NRHS)
    z = np.zeros(effect_state_length(P))
    effects_init(z, P)
    for n in range(X.shape[0]):
        plant_rhs(X[n], z, U[n], T[n], P, out[n], work)


@checks_arm
def rest_state(q, arm) -> tuple[np.ndarray, np.ndarray]:
    """A state at rest in ``q`` and the constant set values that hold it there.

    The pressures are the plant's exact static gravity-compensation pressures
    (Delta-p approach with the arm's mean pressures), so the state is an
    equilibrium of the ODE: of the plant truth, including the payload of
    ``arm.effects``, and the set values invert the plant's true valve
    characteristic (3.12) (``Effects.valve_offset`` / ``valve_gain`` if set).

    Parameters
    ----------
    q : array_like, shape (2,)
        Joint angles [rad].
    arm : ArmParameters
        The plant.

    Returns
    -------
    x0 : numpy.ndarray, shape (8,)
    set_values : numpy.ndarray, shape (4,)
    """
    q = angles("q", q)
    if q.shape != (2,):
        raise ValueError(f"q must be a single configuration of shape (2,), got {q.shape}")
    p = static_pressures(q, arm)
    if np.any(p < 0) or np.any(p > arm.pneumatics.p_max):
        raise ValueError(f"rest_state: configuration q = {q} needs pressures {p} Pa outside "
                         f"[0, {arm.pneumatics.p_max:g}] Pa")
    P = packing.pack(arm)
    v1 = lay.PLANT.read(P, "v1")
    v2 = lay.PLANT.read(P, "v2")
    return np.concatenate([q, [0.0, 0.0], p]), (p - v1) / v2
