"""A head collision inside the full closed loop: detection and reaction (issue 12, item 7).

The impact engine (:mod:`ppamsafety.impact.engine`, thesis §6.3.2) freezes the
arm on constant joint springs and ignores controller and valves: valid for the
first few ms of one impact.  Here the head (a free rigid sphere, Hunt-Crossley
contact (6.2), :class:`~ppamsafety.impact.head.HeadContactModel`) is coupled to
the *full* closed loop of :mod:`ppamsafety.experiments.closed_loop` -- sensors,
force estimators, controller, Delta-p approach, valves (first-order (3.2),
time constants ``ValveSet``), muscle pressures (3.6) and rigid-body dynamics
with gravity -- and simulated through and beyond the first impact, so that the
pressures and the controller act and a second impact can happen.

Integration.  Each 1 ms control period is integrated as in the closed loop
(``substeps`` RK4 steps of :func:`~ppamsafety.plant.model.rk4_step`, the head
advanced separately) while head and tool are far apart; once the gap at the
start of a period is below ``fine_gap`` + 2 dt (|v_tcp| + |v_head|) (or they are in
contact) the period is integrated with ``contact_substeps`` coupled RK4 steps
(default 50: 20 us, the engine's default step) in which plant and head form
one ODE and the contact force is evaluated at every RK4 stage.  The works of
the contact force on the head and on the arm and the contact dissipation are
integrated alongside (energy check: :attr:`CollisionResult.energy`).  The
head acceleration is sampled on the fine grid for F_max and the exact HIC
(:func:`~ppamsafety.impact.hic.hic_kernel`).  Runs whose head never comes near
the tool reproduce :func:`~ppamsafety.experiments.closed_loop.run_batch`
bitwise (tests).

Detection.  The generalized-momentum observer (5.51)-(5.56) runs every period
on the measured signals; a collision is *detected* at the first sample k with
|r_i(k)| > ``threshold[i]`` for a joint i (:func:`calibrate_threshold`: a
margin above the largest residual of the same task without a head).

Reactions (:class:`Reaction`), applied from the detection sample on, all
through the controller and the valves (no pressure ever jumps; the valves'
first-order lag (3.2) shapes every change):

* ``NONE``: nothing (the undetected run);
* ``STOP``: the reference becomes the measured position at detection, at rest;
* ``RETRACT``: the reference becomes the measured position ``retract_lookback``
  (default 100 ms) before detection -- back along the travelled path -- at rest;
* ``VENT``: every valve set value 0 Pa gauge (atmosphere): the muscles empty
  with the valve time constants, the arm goes limp (and falls under gravity);
* ``EQUALIZE``: Delta p = 0 on both joints: each antagonistic pair is driven to
  its mean pressure (3.7), no net actuator torque change request, stiffness kept.

Data layouts: :data:`COLLISION` (parameters of one run), :data:`HEAD_STATE`
(head integrator state), :data:`COLLISION_LOG` (one row per control period)
and :data:`FINE_TRACE` (one row per fine step).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np
import pandas as pd

from .._jit import kernel, kernel_array, step_kernel
from .._validation import (InvalidTypeError, as_float_array, check_int, check_range,
                           check_shape, describe)
from ..control.dispatch import NINT, NSCRATCH, NSTATE, controller_step
from ..control.estimation import (EI_R, ESTIMATOR_SCRATCH, ESTIMATOR_STATE, ForceEstimator,
                                  estimator_step)
from ..control.reference import NREF, R_Q_D, R_R_D
from ..control.sensors import (N_Q, N_QD, NSENSOR, SENSOR_NOISE, pressure_read, sensor_init,
                               sensor_read, sensor_reset, sensor_track_joints)
from ..experiments.case import ExperimentCase
from ..experiments.closed_loop import (DIVERGENCE_VELOCITY, IL_EST, IL_F, L_DP, L_INT, L_P, L_Q,
                                       L_QD, L_QDM, L_QM, L_T, L_U, L_X, L_XD, L_Y, L_YD, NEST,
                                       Z_INTERNALS, Z_PARAMS, Z_SCRATCH, Z_STATE, ExperimentResult,
                                       NILOG, NLOG, _EST_NAMES, _EXT_NAMES, _check_valves,
                                       _controller_rows)
from ..experiments.trajectories import Reference
from ..layouts import Field, Layout
from ..plant import packing
from ..plant.geometry import tcp_jacobian, tcp_position, forward_kinematics
from ..plant.model import (NWORK, NX, X_P, X_Q, X_QD, effect_state_length, effects_init,
                           effects_update, plant_rhs, rk4_step, valve_delay, rest_state)
from ..plant.pneumatics import delta_p_to_set_values
from ..plots.reaction import plot_collision
from ..units import G0
from .contact import hunt_crossley_elastic, hunt_crossley_force
from .engine import HP_B, HP_K, HP_M, HP_N, HP_R, pack_head
from .hic import hic_kernel
from .model import resolve_head


class Reaction(IntEnum):
    """What the controller does once a collision is detected (field ``reaction``)."""

    #: Nothing: the run is the undetected one.
    NONE = 0
    #: Hold the measured position at detection (set point at rest).
    STOP = 1
    #: Go back to the measured position ``retract_lookback`` before detection.
    RETRACT = 2
    #: All valve set values 0 Pa gauge: vent the muscles to the atmosphere.
    VENT = 3
    #: Delta p = 0: each antagonistic pair to its mean pressure (3.7).
    EQUALIZE = 4


class RunStatus(IntEnum):
    """How a collision run ended (returned by the kernel)."""

    OK = 0
    #: A joint speed reached DIVERGENCE_VELOCITY or an angle became non-finite.
    DIVERGED = 1
    #: A coarse period ended with head and tool interpenetrating (fine_gap too small).
    MISSED_CONTACT = 2
    #: The head overlapped the tool when it appeared (``head_appears``).
    OVERLAP = 3


#: Default detection margin: the threshold on each joint's observer residual is this
#: factor times the largest |r_i| of the same task without a head (no false alarm on it).
DETECTION_MARGIN = 1.5
#: Default fine step count per 1 ms period (20 us, the impact engine's default step).
CONTACT_SUBSTEPS = 50
#: Default gap [m] below which the run switches to fine coupled steps (the TCP moves
#: < 5 mm per period at the < 5 m/s of the thesis' experiments).
FINE_GAP = 0.02
#: Default look-back of RETRACT [s].
RETRACT_LOOKBACK = 0.1
#: Two contact episodes are separate impacts when the force stays zero this long [s].
SEPARATION_TIME = 1e-3

COLLISION = Layout("collision parameters", [
    Field("x_head0", 2, "m", "initial head centre (world x, y)", columns=("xh0", "yh0")),
    Field("v_head0", 2, "m/s", "initial head velocity", columns=("vxh0", "vyh0")),
    Field("neck_stiffness", 1, "N/m", "spring pulling the head to x_head0 (0: free head, thesis)"),
    Field("neck_damping", 1, "N s/m", "damper on the head velocity (0: free head, thesis)"),
    Field("threshold", 2, "N m", "detection thresholds on |r_1|, |r_2| (5.54)",
          columns=("r1_th", "r2_th")),
    Field("reaction", 1, "code", "Reaction code", default=float(Reaction.NONE)),
    Field("retract_lookback", 1, "s", "RETRACT: back to the measured position this long ago"),
    Field("fine_gap", 1, "m", "gap below which fine coupled steps start"),
    Field("contact_substeps", 1, "-", "coupled RK4 steps per control period in fine mode"),
    Field("head_appears", 1, "s", "time from which the head is present (no contact before)"),
])
(CC_XH0, CC_VH0, CC_KN, CC_BN, CC_TH, CC_REACT, CC_LOOK, CC_GAP, CC_NSUB,
 CC_ON) = COLLISION.offsets("x_head0", "v_head0", "neck_stiffness", "neck_damping", "threshold",
                            "reaction", "retract_lookback", "fine_gap", "contact_substeps",
                            "head_appears")

HEAD_STATE = Layout("collision head state", [
    Field("x_head", 2, "m", "head centre", columns=("xh", "yh")),
    Field("v_head", 2, "m/s", "head velocity", columns=("vxh", "vyh")),
    Field("W_head", 1, "J", "work of the contact force on the head"),
    Field("W_arm", 1, "J", "work of the contact force on the arm"),
    Field("E_dissipated", 1, "J", "contact dissipation integral (F - k delta^n) d delta"),
])
H_X, H_V, H_WH, H_WA, H_ED = HEAD_STATE.offsets("x_head", "v_head", "W_head", "W_arm",
                                                "E_dissipated")
NH = HEAD_STATE.size

COLLISION_LOG = Layout("collision log", [
    Field("F", 1, "N", "contact force at the sample (Hunt-Crossley (6.2))"),
    Field("gap", 1, "m", "|x_head - r_tcp| - R (negative: penetration)"),
    Field("x_head", 2, "m", "head centre", columns=("x_head", "y_head")),
    Field("v_head", 2, "m/s", "head velocity", columns=("vx_head", "vy_head")),
    Field("detected", 1, "flag", "1 from the detection sample on"),
    Field("fine", 1, "flag", "1 when the period is integrated with fine coupled steps"),
])
CL_F, CL_GAP, CL_XH, CL_VH, CL_DET, CL_FINE = COLLISION_LOG.offsets(
    "F", "gap", "x_head", "v_head", "detected", "fine")
NCLOG = COLLISION_LOG.size

FINE_TRACE = Layout("collision fine trace", [
    Field("F", 1, "N", "contact force at the start of each fine step"),
    Field("a_head_g", 1, "g", "head acceleration magnitude / g0 at that instant"),
])
FT_F, FT_A = FINE_TRACE.offsets("F", "a_head_g")
NFINE = FINE_TRACE.size


@step_kernel
def _contact(x, hs, P, hp):
    """Contact at plant state x, head state hs: (F, nx, ny, delta, ddelta, vx, vy, J)."""
    xt, yt = tcp_position(x[X_Q], x[X_Q + 1], P)
    j11, j12, j21, j22 = tcp_jacobian(x[X_Q], x[X_Q + 1], P)
    vx = j11 * x[X_QD] + j12 * x[X_QD + 1]
    vy = j21 * x[X_QD] + j22 * x[X_QD + 1]
    dx, dy = hs[H_X] - xt, hs[H_X + 1] - yt
    dist = math.sqrt(dx * dx + dy * dy)
    nx, ny = dx / dist, dy / dist
    delta = hp[HP_R] - dist
    dd = -(nx * (hs[H_V] - vx) + ny * (hs[H_V + 1] - vy))
    f = hunt_crossley_force(delta, dd, hp[HP_K], hp[HP_N], hp[HP_B])
    return f, nx, ny, delta, dd, vx, vy, j11, j12, j21, j22


@step_kernel
def _head_rhs(hs, f, nx, ny, vx, vy, delta, dd, hp, CP, dh):
    """Head derivative with contact force f along n (tool -> head) and the neck."""
    fnx = -CP[CC_KN] * (hs[H_X] - CP[CC_XH0]) - CP[CC_BN] * hs[H_V]
    fny = -CP[CC_KN] * (hs[H_X + 1] - CP[CC_XH0 + 1]) - CP[CC_BN] * hs[H_V + 1]
    dh[H_X], dh[H_X + 1] = hs[H_V], hs[H_V + 1]
    dh[H_V] = (f * nx + fnx) / hp[HP_M]
    dh[H_V + 1] = (f * ny + fny) / hp[HP_M]
    dh[H_WH] = f * (nx * hs[H_V] + ny * hs[H_V + 1])
    dh[H_WA] = -f * (nx * vx + ny * vy)
    dh[H_ED] = (f - hunt_crossley_elastic(delta, hp[HP_K], hp[HP_N])) * dd if delta > 0.0 \
        else 0.0


@step_kernel
def _coupled_rhs(x, hs, z, u, P, hp, CP, dx, dh, tau, buf):
    """Plant + head derivative with the contact force at this stage; returns F [N].

    Compiled on its own (not a leaf), so that the large plant derivative is
    not inlined at five call sites (first compilation of the collision
    kernel 21 s -> 15 s; same results).
    """
    f, nx, ny, delta, dd, vx, vy, j11, j12, j21, j22 = _contact(x, hs, P, hp)
    # force on the tool is -F n; tau = J^T (-F n)
    tau[0] = -(j11 * nx + j21 * ny) * f
    tau[1] = -(j12 * nx + j22 * ny) * f
    plant_rhs(x, z, u, tau, P, dx, buf)
    _head_rhs(hs, f, nx, ny, vx, vy, delta, dd, hp, CP, dh)
    return f


@step_kernel
def _coupled_rk4(x, hs, z, u, h, P, hp, CP, k1, k2, k3, k4, xt, g1, g2, g3, g4, ht, tau, buf):
    """One coupled RK4 step of plant and head; returns (F, |a_head|) at the step start."""
    f = _coupled_rhs(x, hs, z, u, P, hp, CP, k1, g1, tau, buf)
    for i in range(NX):
        xt[i] = x[i] + 0.5 * h * k1[i]
    for i in range(NH):
        ht[i] = hs[i] + 0.5 * h * g1[i]
    _coupled_rhs(xt, ht, z, u, P, hp, CP, k2, g2, tau, buf)
    for i in range(NX):
        xt[i] = x[i] + 0.5 * h * k2[i]
    for i in range(NH):
        ht[i] = hs[i] + 0.5 * h * g2[i]
    _coupled_rhs(xt, ht, z, u, P, hp, CP, k3, g3, tau, buf)
    for i in range(NX):
        xt[i] = x[i] + h * k3[i]
    for i in range(NH):
        ht[i] = hs[i] + h * g3[i]
    _coupled_rhs(xt, ht, z, u, P, hp, CP, k4, g4, tau, buf)
    a = math.sqrt(g1[H_V] * g1[H_V] + g1[H_V + 1] * g1[H_V + 1])
    for i in range(NX):
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    for i in range(NH):
        hs[i] += h / 6.0 * (g1[i] + 2.0 * g2[i] + 2.0 * g3[i] + g4[i])
    effects_update(x, z, u, P)
    return f, a


@step_kernel
def _head_free_rk4(hs, h, hp, CP, g1, g2, g3, g4, ht):
    """One RK4 step of the head alone (no contact; neck only)."""
    _head_rhs(hs, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, hp, CP, g1)
    for i in range(NH):
        ht[i] = hs[i] + 0.5 * h * g1[i]
    _head_rhs(ht, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, hp, CP, g2)
    for i in range(NH):
        ht[i] = hs[i] + 0.5 * h * g2[i]
    _head_rhs(ht, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, hp, CP, g3)
    for i in range(NH):
        ht[i] = hs[i] + h * g3[i]
    _head_rhs(ht, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, hp, CP, g4)
    for i in range(NH):
        hs[i] += h / 6.0 * (g1[i] + 2.0 * g2[i] + 2.0 * g3[i] + g4[i])


_NES, _NESCR = ESTIMATOR_STATE.size, ESTIMATOR_SCRATCH.size


@kernel
def _run_collision(x0, R, Pp, Pm, kind, C, sizes, cfg, noise, dt, substeps, EP, PE, hp, CP,
                   LOG, ILOG, CLOG, REFLOG, FINE, HS_OUT):
    """One closed-loop run with a head; returns (RunStatus code, detection sample or -1,
    penetration [m] at the end).

    Mirrors ``closed_loop._run_batch`` for one case with the estimator on;
    ``sizes`` are the controller's declared (params, state, internals,
    scratch) sizes.  FINE has n * contact_substeps + 1 rows.
    """
    n = LOG.shape[0]
    nf = int(CP[CC_NSUB])
    react = int(CP[CC_REACT])
    h = dt / substeps
    hf = dt / nf
    kon = int(math.ceil(CP[CC_ON] / dt - 1e-9))
    x = np.empty(NX)
    x[:] = x0
    hs = np.zeros(NH)
    hs[H_X], hs[H_X + 1] = CP[CC_XH0], CP[CC_XH0 + 1]
    hs[H_V], hs[H_V + 1] = CP[CC_VH0], CP[CC_VH0 + 1]
    work = np.empty(NWORK)
    tau0 = np.zeros(2)
    tau = np.zeros(2)
    k1, k2, k3, k4, xt = np.empty(NX), np.empty(NX), np.empty(NX), np.empty(NX), np.empty(NX)
    g1, g2, g3, g4, ht = np.empty(NH), np.empty(NH), np.empty(NH), np.empty(NH), np.empty(NH)
    buf = np.empty(NWORK)
    S_buf = np.zeros(NSTATE)
    st = np.empty(NSENSOR)
    qm, qdm, pmeas, dp, u = np.empty(2), np.empty(2), np.empty(4), np.empty(2), np.empty(4)
    internals = np.zeros(NINT)
    scratch_buf = np.empty(NSCRATCH)
    fest = np.zeros(NEST)
    ES = np.empty(_NES)
    escr = np.empty(_NESCR)
    hold = np.zeros(NREF)
    sensor_reset(st)
    z = np.zeros(effect_state_length(Pp))
    effects_init(z, Pp)
    Cr = C[:sizes[Z_PARAMS]]
    S = S_buf[:sizes[Z_STATE]]
    ints = internals[:sizes[Z_INTERNALS]]
    scratch = scratch_buf[:sizes[Z_SCRATCH]]
    sensor_init(x[X_Q], x[X_Q + 1], cfg, st)
    detected = False
    kdet = -1
    fine = False
    status = 0
    FINE[:, :] = 0.0
    for k in range(n):
        t = k * dt
        for j in range(2):
            a, w = sensor_read(j, x[X_Q + j], x[X_QD + j], t, cfg, st)
            qm[j] = a + noise[k, N_Q + j]
            qdm[j] = w + noise[k, N_QD + j]
        pressure_read(x, X_P, cfg, pmeas)
        estimator_step(EP, ES, PE, k, dt, qm, qdm, pmeas, fest, escr)
        ILOG[k, IL_EST:IL_EST + NEST] = fest
        if (not detected) and (abs(fest[EI_R]) > CP[CC_TH] or abs(fest[EI_R + 1]) > CP[CC_TH + 1]):
            detected = True
            kdet = k
            if react == Reaction.STOP or react == Reaction.RETRACT:
                qa, qb = qm[0], qm[1]
                if react == Reaction.RETRACT:
                    kb = k - int(round(CP[CC_LOOK] / dt))
                    if kb < 0:
                        kb = 0
                    if kb < k:
                        qa, qb = LOG[kb, L_QM], LOG[kb, L_QM + 1]
                hold[:] = 0.0
                hold[R_Q_D], hold[R_Q_D + 1] = qa, qb
                hold[R_R_D], hold[R_R_D + 1] = tcp_position(qa, qb, Pm)
        if detected and (react == Reaction.STOP or react == Reaction.RETRACT):
            Rk = hold
        else:
            Rk = R[k]
        REFLOG[k] = Rk
        controller_step(kind, Cr, S, Pm, k, dt, qm, qdm, pmeas, Rk, fest, dp, ints, scratch)
        delta_p_to_set_values(dp[0], dp[1], Pm, u)
        if detected and react == Reaction.VENT:
            u[:] = 0.0
        elif detected and react == Reaction.EQUALIZE:
            delta_p_to_set_values(0.0, 0.0, Pm, u)
        row = LOG[k]
        row[L_T] = t
        row[L_Q:L_Q + 2] = x[X_Q:X_Q + 2]
        row[L_QD:L_QD + 2] = x[X_QD:X_QD + 2]
        row[L_P:L_P + 4] = x[X_P:X_P + 4]
        row[L_QM:L_QM + 2] = qm
        row[L_QDM:L_QDM + 2] = qdm
        row[L_U:L_U + 4] = u
        row[L_DP:L_DP + 2] = dp
        row[L_X], row[L_Y] = tcp_position(x[X_Q], x[X_Q + 1], Pp)
        j11, j12, j21, j22 = tcp_jacobian(x[X_Q], x[X_Q + 1], Pp)
        row[L_XD] = j11 * x[X_QD] + j12 * x[X_QD + 1]
        row[L_YD] = j21 * x[X_QD] + j22 * x[X_QD + 1]
        row[L_INT:L_INT + NINT] = internals
        f, nx, ny, delta, dd, vx, vy, _, _, _, _ = _contact(x, hs, Pp, hp)
        present = k >= kon
        if not present:
            f = 0.0
        elif k == kon and delta > 0.0:
            status = RunStatus.OVERLAP
            break
        ILOG[k, IL_F], ILOG[k, IL_F + 1] = -f * nx, -f * ny
        c = CLOG[k]
        c[CL_F], c[CL_GAP] = f, -delta
        c[CL_XH], c[CL_XH + 1] = hs[H_X], hs[H_X + 1]
        c[CL_VH], c[CL_VH + 1] = hs[H_V], hs[H_V + 1]
        c[CL_DET] = 1.0 if detected else 0.0
        valve_delay(z, u, Pp)
        speed = math.sqrt(vx * vx + vy * vy) + math.sqrt(hs[H_V] ** 2 + hs[H_V + 1] ** 2)
        fine = present and (f > 0.0 or -delta < CP[CC_GAP] + 2.0 * dt * speed)
        c[CL_FINE] = 1.0 if fine else 0.0
        if fine:
            for i in range(nf):
                q_old0, q_old1 = x[X_Q], x[X_Q + 1]
                fi, ai = _coupled_rk4(x, hs, z, u, hf, Pp, hp, CP, k1, k2, k3, k4, xt,
                                      g1, g2, g3, g4, ht, tau, buf)
                FINE[k * nf + i, FT_F] = fi
                FINE[k * nf + i, FT_A] = ai / G0
                sensor_track_joints(q_old0, q_old1, x[X_Q], x[X_Q + 1], t + i * hf, hf, cfg,
                                    st)
        else:
            for i in range(substeps):
                q_old0, q_old1 = x[X_Q], x[X_Q + 1]
                rk4_step(x, z, u, tau0, h, Pp, work)
                _head_free_rk4(hs, h, hp, CP, g1, g2, g3, g4, ht)
                sensor_track_joints(q_old0, q_old1, x[X_Q], x[X_Q + 1], t + i * h, h, cfg,
                                    st)
            fe = _contact(x, hs, Pp, hp)
            if present and fe[3] > 0.0:
                status = RunStatus.MISSED_CONTACT
        if not (np.isfinite(x[X_Q]) and np.isfinite(x[X_Q + 1])
                and abs(x[X_QD]) < DIVERGENCE_VELOCITY
                and abs(x[X_QD + 1]) < DIVERGENCE_VELOCITY):
            status = RunStatus.DIVERGED
            LOG[k + 1:, :] = np.nan
            ILOG[k + 1:, :] = np.nan
            CLOG[k + 1:, :] = np.nan
            break
        if status != 0:
            break
    d_end = math.nan
    if status == 0:
        fe = _contact(x, hs, Pp, hp)
        d_end = fe[3]
        FINE[n * nf, FT_F] = fe[0]
        _coupled_rhs(x, hs, z, u, Pp, hp, CP, k1, g1, tau, buf)
        FINE[n * nf, FT_A] = math.sqrt(g1[H_V] ** 2 + g1[H_V + 1] ** 2) / G0
    HS_OUT[:] = hs
    return status, kdet, d_end


# ---- Python interface -----------------------------------------------------------------------

def check_reaction(reaction) -> Reaction:
    """``reaction`` as a :class:`Reaction` (a member, its name or its code).

    Parameters
    ----------
    reaction : Reaction, str or int
        E.g. ``Reaction.VENT``, ``"vent"`` or ``3``.

    Returns
    -------
    Reaction
    """
    if isinstance(reaction, Reaction):
        return reaction
    if isinstance(reaction, str):
        try:
            return Reaction[reaction.upper()]
        except KeyError:
            pass
    elif isinstance(reaction, (int, np.integer)) and not isinstance(reaction, bool):
        try:
            return Reaction(int(reaction))
        except ValueError:
            pass
    raise ValueError(f"reaction = {reaction!r} is not a Reaction; choose from "
                     f"{[r.name for r in Reaction]}")


def _check_threshold(threshold) -> np.ndarray:
    th = np.asarray(threshold, dtype=float) if not isinstance(threshold, str) else None
    if th is None or th.shape not in ((), (2,)) or np.any(np.isnan(th)) or np.any(th <= 0):
        raise ValueError(f"threshold = {threshold!r} must be one or two positive numbers [N m] "
                         f"(math.inf: never detect)")
    return np.broadcast_to(th, (2,)).astype(float)


def calibrate_threshold(free_run, *, margin: float = DETECTION_MARGIN) -> np.ndarray:
    """Detection thresholds [N m] from a collision-free run of the same task.

    r_th,i = ``margin`` x max_t |r_i(t)|: the momentum observer's residual
    (5.54) never exceeds its largest collision-free value on this task (the
    "phantom" torque from model error (``arm.model`` vs the plant), encoder
    quantisation and the timing-board velocity), so the threshold gives no
    false alarm on it; ``margin`` covers run-to-run variation.  A different
    task needs its own calibration (or the largest threshold of all tasks).

    Parameters
    ----------
    free_run : ExperimentResult
        The run without head, with a force estimator (signals ``r1``, ``r2``).
    margin : float
        Factor >= 1 (default :data:`DETECTION_MARGIN` = 1.5).

    Returns
    -------
    numpy.ndarray, shape (2,)
        Thresholds on |r_1|, |r_2| [N m].
    """
    if not isinstance(free_run, ExperimentResult):
        raise InvalidTypeError(f"free_run must be an ExperimentResult, got {describe(free_run)}")
    margin = check_range("margin", margin, 1.0, 1e3)
    if "r1" not in free_run.interaction_names:
        raise ValueError("free_run has no force-estimator signals r1, r2: run it with "
                         "ExperimentCase(estimator=ForceEstimator())")
    r = np.abs(free_run.signals("r1", "r2"))
    if not np.all(np.isfinite(r)):
        raise ValueError("free_run has non-finite residuals (diverged?)")
    return margin * np.maximum(r.max(axis=0), 1e-9)


def head_touching(free_run, k0: int, head=None) -> tuple:
    """Head placement of thesis §6.3.2 at sample ``k0`` of a run: touching, along the TCP velocity.

    Parameters
    ----------
    free_run : ExperimentResult
        The collision-free run.
    k0 : int
        Impact sample (0 <= k0 < n); the TCP must move there.
    head : HeadContactModel or str, optional
        Head model (default ``"thesis-frontal"``); its radius places the centre.

    Returns
    -------
    x_head : numpy.ndarray, shape (2,)
        Head centre r_tcp(k0) + R u [m].
    u : numpy.ndarray, shape (2,)
        Unit TCP velocity direction at k0.
    """
    if not isinstance(free_run, ExperimentResult):
        raise InvalidTypeError(f"free_run must be an ExperimentResult, got {describe(free_run)}")
    k0 = check_int("k0", k0, 0, len(free_run.t) - 1)
    hm = resolve_head(head)
    r = free_run.signals("x", "y")[k0]
    v = free_run.signals("xd", "yd")[k0]
    s = float(np.hypot(*v))
    if not s > 1e-9:
        raise ValueError(f"k0 = {k0}: the TCP is at rest (|v| = {s:.3g} m/s); no impact direction")
    u = v / s
    return r + hm.radius * u, u


@dataclass
class CollisionResult:
    """One closed-loop run with a head: :func:`simulate_collision`.

    Attributes
    ----------
    experiment : ExperimentResult
        The closed-loop record (log, estimator internals; ``Fx_ext``,
        ``Fy_ext`` is the contact force on the TCP; the reference is the one
        the controller saw, i.e. with the reaction's hold set point).
    log : numpy.ndarray, shape (n, NCLOG)
        :data:`COLLISION_LOG` per control period.
    fine : numpy.ndarray, shape (n * contact_substeps + 1, NFINE)
        :data:`FINE_TRACE` on the fine grid (zero where the run was coarse).
    fine_dt : float
        Fine step [s].
    reaction : Reaction
    threshold : numpy.ndarray, shape (2,)
        Detection thresholds [N m].
    head : HeadContactModel
    status : RunStatus
    k_detect : int
        Detection sample (-1: not detected).
    impacts : pandas.DataFrame
        One row per contact episode (:func:`contact_episodes`).
    energy : dict
        ``W_head``, ``W_arm``, ``E_dissipated``, ``U_contact_end``,
        ``head_kinetic_change`` [J], ``contact_balance_error`` (W_head + W_arm +
        U + E_diss relative to the largest term) and ``head_work_error``
        ((Delta KE_head - W_head) / max(W_head, 1e-12 J), only meaningful
        without neck).
    meta : dict
    """

    experiment: object
    log: np.ndarray
    fine: np.ndarray
    fine_dt: float
    reaction: Reaction
    threshold: np.ndarray
    head: object
    status: RunStatus
    k_detect: int
    impacts: pd.DataFrame
    energy: dict
    meta: dict = field(default_factory=dict)

    @property
    def t(self) -> np.ndarray:
        """Sample times [s]."""
        return self.experiment.t

    @property
    def fine_t(self) -> np.ndarray:
        """Times of the fine trace [s]."""
        return np.arange(self.fine.shape[0]) * self.fine_dt

    @property
    def t_detect(self) -> float:
        """Detection time [s] (NaN if not detected)."""
        return self.k_detect * self.experiment.reference.dt if self.k_detect >= 0 else math.nan

    @property
    def t_contact(self) -> float:
        """Start of the first contact [s] (NaN without contact)."""
        return float(self.impacts["t_start"].iloc[0]) if len(self.impacts) else math.nan

    @property
    def detection_delay(self) -> float:
        """t_detect - t_contact [s] (NaN if either is missing)."""
        return self.t_detect - self.t_contact

    def impact(self, i: int) -> pd.Series:
        """Contact episode ``i`` (0: first impact), or a row of NaN if there is none.

        Parameters
        ----------
        i : int
            Episode index, >= 0.
        """
        i = check_int("i", i, 0)
        if i < len(self.impacts):
            return self.impacts.iloc[i]
        return pd.Series(np.nan, index=self.impacts.columns)

    def to_pandas(self) -> pd.DataFrame:
        """Per-sample signals: closed loop, head, contact force, residuals, detection."""
        e = self.experiment
        df = pd.DataFrame({"t": e.t})
        for c in ("q1", "q2", "qd1", "qd2", "x", "y", "xd", "yd", "p1", "p2", "p3", "p4",
                  "u1", "u2", "u3", "u4", "r1", "r2", "Fx_mo", "Fy_mo", "q1_d", "q2_d"):
            df[c] = e.signal(c)
        for c in COLLISION_LOG.columns():
            df[c] = self.log[:, COLLISION_LOG.column_index(c)]
        return df

    def plot(self, **kwargs):
        """Force, positions and residual vs time (:func:`ppamsafety.plots.reaction.plot_collision`).

        Parameters
        ----------
        **kwargs
            Passed to the plot function (``title``, ``t_range``).
        """
        return plot_collision(self, **kwargs)


def contact_episodes(force, a_head_g, dt: float, *, separation: float = SEPARATION_TIME,
                     window: float = 0.036) -> pd.DataFrame:
    """Split a sampled contact force into impacts and rate each (F_max, HIC).

    Parameters
    ----------
    force : array_like, shape (m,)
        Contact force samples [N] (>= 0) on a uniform grid starting at t = 0.
    a_head_g : array_like, shape (m,)
        Head acceleration magnitude [g] at the same samples.
    dt : float
        Sample spacing [s].
    separation : float
        Zero-force time [s] that separates two impacts (default 1 ms).
    window : float
        HIC window limit [s] (default 36 ms: HIC36).

    Returns
    -------
    pandas.DataFrame
        Per episode: ``t_start``, ``t_end`` [s], ``duration`` [s], ``F_max``
        [N], ``t_Fmax`` [s], ``impulse`` [N s], ``HIC36`` (exact, over windows
        inside the episode).
    """
    F = as_float_array("force", force).reshape(-1)
    a = as_float_array("a_head_g", a_head_g).reshape(-1)
    if a.shape != F.shape:
        raise ValueError(f"a_head_g has shape {a.shape}, force {F.shape}")
    dt = check_range("dt", dt, 1e-9, 1.0, unit="s")          # as hic()
    separation = check_range("separation", separation, 0.0, 10.0, unit="s")
    window = check_range("window", window, 0.0, 1.0, lo_open=True, unit="s")
    cols = ["t_start", "t_end", "duration", "F_max", "t_Fmax", "impulse", "HIC36"]
    on = np.nonzero(F > 0.0)[0]
    if on.size == 0:
        return pd.DataFrame(columns=cols, dtype=float)
    gap = int(math.ceil(separation / dt - 1e-9))
    splits = np.nonzero(np.diff(on) > max(gap, 1))[0]
    starts = np.concatenate([[on[0]], on[splits + 1]])
    ends = np.concatenate([on[splits], [on[-1]]])
    rows = []
    wn = int(window / dt + 1e-9)
    for s, e in zip(starts, ends):
        lo, hi = max(s - 1, 0), min(e + 2, F.size)
        seg = F[lo:hi]
        i = int(np.argmax(seg))
        aseg = np.ascontiguousarray(a[lo:hi])
        hic = hic_kernel(aseg, dt, wn)[0]
        rows.append({"t_start": s * dt, "t_end": e * dt, "duration": (e - s + 1) * dt,
                     "F_max": float(seg[i]), "t_Fmax": (lo + i) * dt,
                     "impulse": float(np.sum(seg) * dt), "HIC36": float(hic)})
    return pd.DataFrame(rows, columns=cols)


def simulate_collision(case, *, head_position, head=None, head_velocity=(0.0, 0.0),
                       neck_stiffness: float = 0.0, neck_damping: float = 0.0,
                       threshold=math.inf, reaction=Reaction.NONE,
                       retract_lookback: float = RETRACT_LOOKBACK,
                       contact_substeps: int = CONTACT_SUBSTEPS, fine_gap: float = FINE_GAP,
                       substeps: int = 1, head_appears: float = 0.0) -> CollisionResult:
    """Run one closed-loop experiment with a head in the workspace; detect and react.

    Parameters
    ----------
    case : ExperimentCase
        The experiment (arm, controller, reference, sensors, x0).  Without an
        estimator it gets ``ForceEstimator()`` (thesis gains, model
        ``arm.model``); an external force or hand is refused.  Its reference
        sets the run's length and the control period dt.
    head_position : array_like, shape (2,)
        Initial head centre [m] (world frame); at least the head radius away
        from the initial tool point (see :func:`head_touching`).
    head : HeadContactModel or str, optional
        Head model (default ``"thesis-frontal"``: 5 kg, thesis §6.3.2).
    head_velocity : array_like, shape (2,)
        Initial head velocity [m/s] (default at rest), |v| <= 10 m/s.
    neck_stiffness : float
        Spring [N/m] pulling the head back to ``head_position``, in [0, 1e6]
        (default 0: free head, as the thesis).
    neck_damping : float
        Damper [N s/m] on the head velocity, in [0, 1e5] (default 0).
    threshold : float or array_like, shape (2,)
        Detection thresholds on |r_1|, |r_2| [N m], > 0; ``math.inf`` (the
        default) never detects (:func:`calibrate_threshold`).
    reaction : Reaction, str or int
        What to do on detection (:class:`Reaction`; default NONE).
    retract_lookback : float
        RETRACT goes back to the measured position this long [s] before
        detection, in [dt, 10].
    contact_substeps : int
        Coupled RK4 steps per control period near and in contact, in
        [10, 1000] (default 50: 20 us at 1 kHz).
    fine_gap : float
        Gap [m] below which fine steps start, in [1e-4, 1] (default 2 cm).
    substeps : int
        RK4 steps per control period far from the head (as in
        :func:`~ppamsafety.experiments.closed_loop.run_batch`), in [1, 1000].
    head_appears : float
        Time [s] from which the head is present, in [0, run length) (default
        0).  Before it there is no contact (the head steps into the path,
        e.g. shortly before the impact instant of a path that passed its
        place earlier); the head must not overlap the tool then.

    Returns
    -------
    CollisionResult

    Raises
    ------
    TypeError, ValueError
        For a bad argument (named in the message); ``RuntimeError`` if a
        coarse period ended in contact (``fine_gap`` too small).

    Warns
    -----
    UserWarning
        If the closed loop diverged.
    """
    if not isinstance(case, ExperimentCase):
        raise InvalidTypeError(f"case must be an ExperimentCase, got {describe(case)}")
    if case.has_external_input:
        raise ValueError("case has an external force or hand; simulate_collision applies the "
                         "head's contact force only")
    hm = resolve_head(head)
    xh0 = check_shape("head_position", as_float_array("head_position", head_position), (2,))
    vh0 = check_shape("head_velocity", as_float_array("head_velocity", head_velocity), (2,))
    if np.hypot(*vh0) > 10.0:
        raise ValueError(f"head_velocity = {vh0.tolist()} m/s exceeds 10 m/s")
    kn = check_range("neck_stiffness", neck_stiffness, 0.0, 1e6, unit="N/m")
    bn = check_range("neck_damping", neck_damping, 0.0, 1e5, unit="N s/m")
    th = _check_threshold(threshold)
    reaction = check_reaction(reaction)
    ref = case.reference
    dt = ref.dt
    look = check_range("retract_lookback", retract_lookback, dt, 10.0, unit="s")
    nf = check_int("contact_substeps", contact_substeps, 10, 1000)
    gap = check_range("fine_gap", fine_gap, 1e-4, 1.0, unit="m")
    substeps = check_int("substeps", substeps, 1, 1000)
    t_on = check_range("head_appears", head_appears, 0.0, (ref.n_steps - 1) * dt, unit="s")
    arm = case.arm
    est = case.estimator if case.estimator is not None else ForceEstimator()
    est.check_period(dt)
    x0 = case.x0 if case.x0 is not None else rest_state(ref.field("q_d")[0], arm)[0]
    x0 = np.array(x0, dtype=float)
    # writable rows, as in run_batch: a read-only row is a different numba type and would
    # compile controller_step, rk4_step and plant_rhs a second time (about 15 s, cold cache)
    Pp = kernel_array(packing.pack(arm))
    _check_valves(Pp, dt, substeps, case.name)
    r0 = forward_kinematics(x0[:2], arm)
    if t_on == 0.0 and np.hypot(*(xh0 - r0)) <= hm.radius:
        raise ValueError(f"head_position = {xh0.tolist()} m lies within the head radius "
                         f"{hm.radius:g} m of the initial tool point {r0.tolist()} m")
    kind, C, sizes, Pm = _controller_rows(arm, case.controller)
    Pm = kernel_array(Pm)
    n = ref.n_steps
    noise = (case.sensors.noise_samples(n) if case.sensors.noise
             else np.zeros((n, SENSOR_NOISE.size)))
    CP = COLLISION.pack(x_head0=xh0, v_head0=vh0, neck_stiffness=kn, neck_damping=bn,
                        threshold=np.minimum(th, 1e300), reaction=float(reaction),
                        retract_lookback=look, fine_gap=gap, contact_substeps=float(nf),
                        head_appears=t_on)
    LOG = np.empty((n, NLOG))
    ILOG = np.zeros((n, NILOG))
    CLOG = np.zeros((n, NCLOG))
    REFLOG = np.empty((n, NREF))
    FINE = np.zeros((n * nf + 1, NFINE))
    HS = np.zeros(NH)
    status, kdet, d_end = _run_collision(x0, np.ascontiguousarray(ref.data), Pp, Pm, kind, C,
                                  np.array(sizes, dtype=np.int64), case.sensors.pack(), noise,
                                  float(dt), substeps, est.pack(), kernel_array(est.model_row(arm)),
                                  pack_head(hm), CP, LOG, ILOG, CLOG, REFLOG, FINE, HS)
    status = RunStatus(int(status))
    if status == RunStatus.MISSED_CONTACT:
        raise RuntimeError(f"simulate_collision: case {case.name!r}: a coarse control period "
                           f"ended in contact; increase fine_gap = {gap:g} m")
    if status == RunStatus.OVERLAP:
        raise ValueError(f"simulate_collision: case {case.name!r}: the head at head_position = "
                         f"{xh0.tolist()} m overlaps the tool when it appears at head_appears = "
                         f"{t_on:g} s")
    if status == RunStatus.DIVERGED:
        warnings.warn(f"simulate_collision: case {case.name!r} diverged", UserWarning,
                      stacklevel=2)
    eff_ref = Reference(f"{ref.name} ({reaction.name.lower()})", ref.t.copy(), REFLOG, dt)
    desc = {**case.controller.describe(), "kind": int(case.controller.kind)}
    exp = ExperimentResult(case.name, desc, eff_ref, LOG, status == RunStatus.DIVERGED,
                           dict(case.meta), ILOG, _EXT_NAMES + _EST_NAMES)
    hf = dt / nf
    impacts = contact_episodes(FINE[:, FT_F], FINE[:, FT_A], hf)
    m = hm.mass
    ke = 0.5 * m * (HS[H_V] ** 2 + HS[H_V + 1] ** 2) - 0.5 * m * float(vh0 @ vh0)
    wh, wa, ed = HS[H_WH], HS[H_WA], HS[H_ED]
    u_end = hm.stiffness * d_end ** (hm.exponent + 1.0) / (hm.exponent + 1.0) if d_end > 0 else 0.0
    scale = max(abs(wh), abs(wa), ed, 1e-12)
    energy = {"W_head": wh, "W_arm": wa, "E_dissipated": ed, "U_contact_end": u_end,
              "head_kinetic_change": ke,
              "contact_balance_error": (wh + wa + u_end + ed) / scale,
              "head_work_error": (ke - wh) / max(abs(wh), 1e-12)}
    return CollisionResult(exp, CLOG, FINE, hf, reaction, th, hm, status, int(kdet), impacts,
                           energy, dict(case.meta))

