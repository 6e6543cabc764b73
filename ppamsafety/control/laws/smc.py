"""The compiled law of :mod:`ppamsafety.control.smc`: its declared rows and step kernel."""

from __future__ import annotations

import math
from enum import IntEnum

from ..._jit import leaf, step_kernel
from ...layouts import Field, Layout
from ...plant import layout as lay
from ...plant.dynamics import forward_dynamics, mass_matrix_cs
from ...plant.torque import torque_functions_cs, torque_kernel
from ..reference import R_Q, R_QD, R_QDD, R_QDDD


H_Q = 1e-6      # finite-difference steps [rad], [rad/s]
H_W = 1e-5


class SMCCoupling(IntEnum):
    """Linearisation of :class:`SlidingModeControl`."""

    SISO = 0        #: each link with respect to its own states (thesis)
    MIMO = 1        #: all states and the 2x2 input matrix


SMC_PARAMS = Layout("SMC parameters", [
    Field("alpha0", 2, "1/s^2", "error-dynamics coefficients alpha0 = poles^2 (4.35)"),
    Field("alpha1", 2, "1/s", "error-dynamics coefficients alpha1 = 2 poles (4.35)"),
    Field("gain", 2, "rad/s^3", "switching gains K (4.41)"),
    Field("boundary_layer", 2, "rad/s^2", "boundary-layer widths Gamma"),
    Field("coupling", 1, "code", "SMCCoupling: siso or mimo linearisation"),
])
P_A0, P_A1, P_K, P_GAMMA, P_COUPLING = SMC_PARAMS.offsets(
    "alpha0", "alpha1", "gain", "boundary_layer", "coupling")

SMC_INTERNALS = Layout("SMC internals", [
    Field("s", 2, "rad/s^2", "sliding variables s (4.35)"),
    Field("a_diag", 2, "1/(s^3 Pa)", "diagonal input gains a_ii (4.33)", columns=("a11", "a22")),
    Field("b", 2, "rad/s^3", "drift terms b_i (4.33)"),
    Field("u_smc", 2, "Pa", "commanded Delta p (4.41)"),
])
I_S, I_A, I_B, I_U = SMC_INTERNALS.offsets("s", "a_diag", "b", "u_smc")

SMC_SCRATCH = Layout("SMC scratch", [
    Field("qdd_buf", 4, "m^3", "work memory of model_qdd (torque functions)"),
    Field("mt", 4, "m^3", "m_tau of the four muscle groups at the measured q (B.2)"),
    Field("vol", 4, "m^3", "group volumes"),
    Field("dmt", 4, "m^3/rad", "d m_tau / dq"),
    Field("fp", 4, "Pa/s", "pressure drift (valve towards p_m, polytropic coupling)"),
    Field("gp", 4, "1/s", "pressure input direction"),
    Field("b", 2, "rad/s^3", "drift terms b_i (4.33)"),
    Field("a", 4, "1/(s^3 Pa)", "input gains a_ij (4.33), row by row"),
    Field("v", 2, "rad/s^3", "the right-hand sides of (4.41)"),
])
X_BUF, X_MT, X_VOL, X_DMT, X_FP, X_GP, X_B, X_A, X_V = SMC_SCRATCH.offsets(
    "qdd_buf", "mt", "vol", "dmt", "fp", "gp", "b", "a", "v")


@step_kernel
def model_qdd(q1, q2, w1, w2, p, Pm, buf):
    """Model joint accelerations for state (q, qd, p) (compiled, unchecked).

    The joint torques are the muscle torques sum p_i m_tau,i of the four
    groups (B.2), fed to the model's forward dynamics (no external torque).

    Parameters
    ----------
    q1, q2 : float
        Joint angles [rad].
    w1, w2 : float
        Joint velocities [rad/s].
    p : numpy.ndarray, shape (4,)
        Gauge pressures of the four muscle groups [Pa].
    Pm : numpy.ndarray
        The controller's model row (layout ``PLANT``).
    buf : numpy.ndarray, shape (>= 4,)
        Work memory: m_tau [m^3] of the four groups (``qdd_buf`` of ``SMC_SCRATCH``),
        overwritten.

    Returns
    -------
    tuple of float
        Joint accelerations (qdd1, qdd2) [rad/s^2].
    """
    mt = buf[0:4]
    torque_functions_cs(math.cos(q1), math.sin(q1), math.cos(q1 + q2), math.sin(q1 + q2), Pm,
                        mt)
    return forward_dynamics(q1, q2, w1, w2, p[0] * mt[0] + p[1] * mt[1],
                            p[2] * mt[2] + p[3] * mt[3], Pm)


@leaf
def _sat(x):
    return min(max(x, -1.0), 1.0)


@leaf
def smc_step(C, S, Pm, dt, qm, qdm, pm, ref, dp, internals, scratch):
    """One sliding-mode-control update (4.33)-(4.41) (compiled, unchecked).

    Parameters
    ----------
    C : numpy.ndarray
        Parameter row (layout ``SMC_PARAMS``: alpha0 [1/s^2], alpha1 [1/s],
        K [rad/s^3], Gamma [rad/s^2] per joint, :class:`SMCCoupling` code).
    S : numpy.ndarray
        State; SMC has none (empty layout), not read.
    Pm : numpy.ndarray
        The controller's model row (layout ``PLANT``, see
        :meth:`SlidingModeControl.model_row`).
    dt : float
        Control period [s]; not read (the control law is static).
    qm, qdm : numpy.ndarray, shape (2,)
        Measured joint angles [rad] and velocities [rad/s].
    pm : numpy.ndarray, shape (4,)
        Measured gauge pressures of the four muscle groups [Pa].
    ref : numpy.ndarray, shape (12,)
        Reference row (q_d [rad], qd_d [rad/s], qdd_d [rad/s^2], qddd_d
        [rad/s^3] in the ``R_Q`` .. ``R_QDDD`` columns).
    dp : numpy.ndarray, shape (2,)
        Output Delta p = u per joint [Pa] (4.41), written.
    internals : numpy.ndarray
        Logged internals (layout ``SMC_INTERNALS``), written.
    scratch : numpy.ndarray, shape (SMC_SCRATCH.size,)
        Work memory (layout ``SMC_SCRATCH``), overwritten.
    """
    buf = scratch[X_BUF:X_BUF + 4]
    q1, q2, w1, w2 = qm[0], qm[1], qdm[0], qdm[1]
    mt = scratch[X_MT:X_MT + 4]
    vol = scratch[X_VOL:X_VOL + 4]
    torque_kernel(q1, q2, Pm, mt, scratch[X_DMT:X_DMT + 4], vol)
    # the muscle torques depend on q and p only: model_qdd at (q, qd + h) is the forward
    # dynamics at these torques, so the measured state and the four velocity perturbations
    # share one torque evaluation (same values as model_qdd; it is the costly part, to run
    # and to compile)
    t1 = pm[0] * mt[0] + pm[1] * mt[1]
    t2 = pm[2] * mt[2] + pm[3] * mt[3]
    a1, a2 = forward_dynamics(q1, q2, w1, w2, t1, t2, Pm)
    # pressure drift (valve towards p_m, polytropic coupling) and input direction
    fp = scratch[X_FP:X_FP + 4]
    gp = scratch[X_GP:X_GP + 4]
    n = Pm[lay.NPOLY]
    for i in range(4):
        w = w1 if i < 2 else w2
        pmean = Pm[lay.PM1] if i < 2 else Pm[lay.PM2]
        T = Pm[lay.TV + i]
        fp[i] = (pmean - pm[i]) / T - n * (Pm[lay.PATM] + pm[i]) * mt[i] * w / vol[i]
        gp[i] = (1.0 if i % 2 == 0 else -1.0) / T
    # d qdd / d p (only through the joint torques): H^-1 columns times m_tau
    h11, h12, h22 = mass_matrix_cs(math.cos(q2), math.sin(q2), Pm)
    det = h11 * h22 - h12 * h12
    hi11, hi12, hi22 = h22 / det, -h12 / det, h11 / det
    # sensitivities of qdd to q and qd by central differences
    d1q1 = model_qdd(q1 + H_Q, q2, w1, w2, pm, Pm, buf)
    d2q1 = model_qdd(q1 - H_Q, q2, w1, w2, pm, Pm, buf)
    d1q2 = model_qdd(q1, q2 + H_Q, w1, w2, pm, Pm, buf)
    d2q2 = model_qdd(q1, q2 - H_Q, w1, w2, pm, Pm, buf)
    d1w1 = forward_dynamics(q1, q2, w1 + H_W, w2, t1, t2, Pm)
    d2w1 = forward_dynamics(q1, q2, w1 - H_W, w2, t1, t2, Pm)
    d1w2 = forward_dynamics(q1, q2, w1, w2 + H_W, t1, t2, Pm)
    d2w2 = forward_dynamics(q1, q2, w1, w2 - H_W, t1, t2, Pm)
    mimo = int(C[P_COUPLING]) == SMCCoupling.MIMO
    acc = (a1, a2)
    hinv = ((hi11, hi12), (hi12, hi22))
    dq = ((d1q1[0] - d2q1[0], d1q2[0] - d2q2[0]), (d1q1[1] - d2q1[1], d1q2[1] - d2q2[1]))
    dw = ((d1w1[0] - d2w1[0], d1w2[0] - d2w2[0]), (d1w1[1] - d2w1[1], d1w2[1] - d2w2[1]))
    b = scratch[X_B:X_B + 2]
    A = scratch[X_A:X_A + 4]                       # A[2 i + j] = a_ij
    v = scratch[X_V:X_V + 2]
    b[:] = 0.0
    A[:] = 0.0
    v[:] = 0.0
    for i in range(2):
        for j in range(2):
            if j != i and not mimo:
                continue
            b[i] += dq[i][j] / (2 * H_Q) * qdm[j] + dw[i][j] / (2 * H_W) * acc[j]
            for k in (2 * j, 2 * j + 1):
                b[i] += hinv[i][j] * mt[k] * fp[k]
                A[2 * i + j] += hinv[i][j] * mt[k] * gp[k]
        e = ref[R_Q + i] - qm[i]
        ed = ref[R_QD + i] - qdm[i]
        edd = ref[R_QDD + i] - acc[i]
        s = edd + C[P_A1 + i] * ed + C[P_A0 + i] * e
        v[i] = ref[R_QDDD + i] - b[i] + C[P_A1 + i] * edd + C[P_A0 + i] * ed
        internals[I_S + i] = s
        internals[I_A + i] = A[3 * i]
        internals[I_B + i] = b[i]
        v[i] += C[P_K + i] * _sat(s / C[P_GAMMA + i])
    if mimo:
        det_a = A[0] * A[3] - A[1] * A[2]
        dp[0] = (A[3] * v[0] - A[1] * v[1]) / det_a
        dp[1] = (A[0] * v[1] - A[2] * v[0]) / det_a
    else:
        dp[0] = v[0] / A[0]
        dp[1] = v[1] / A[3]
    internals[I_U] = dp[0]
    internals[I_U + 1] = dp[1]
