"""Sliding mode control with feedback linearisation of the pressure dynamics.

Thesis §4.3 and Appendix C.  Each link is a 4th-order input-affine system in
x_i = (q_i, qd_i, p_2i-1, p_2i) with input u_i = Delta p_i and relative
degree 3: with xi3 = qdd_i (no input), b_i = d(qdd_i)/dt along the drift and
a_i = its sensitivity to u_i,

    qddd_i = b_i + a_i u_i                                     (4.33)
    s_i    = edd_i + alpha1 ed_i + alpha0 e_i,  e = q_d - q     (4.35)
    u_i    = (qddd_d - b_i + alpha1 edd_i + alpha0 ed_i + K_i sat(s_i/Gamma_i)) / a_i   (4.41)

so that on the model ds_i/dt = -K_i sat(s_i/Gamma_i): reaching at rate K_i
outside the boundary layer, exponential decay with rate K_i/Gamma_i inside.

The Lie derivatives are evaluated numerically (central differences of the
model's forward dynamics) rather than from the thesis' symbolic expressions.
``coupling="siso"`` reproduces the thesis (each link linearised with respect
to its own states only; the other link's motion is a disturbance);
``coupling="mimo"`` uses all states and the 2x2 input matrix, which cancels
the modelled dynamics exactly.

The model is the physically consistent plant by default (the identified
Table 3.5 inertia matrix is indefinite and cannot be inverted); its valve
time constants can be set independently of the plant's (§4.4.2: the thesis
chose them 20-50 % lower than measured to reduce chattering).
"""

from __future__ import annotations

import math
from enum import IntEnum

import numpy as np

from .._jit import kernel, leaf
from .._validation import check_instance, check_vector
from ..params.inertia import LinkInertia
from ..layouts import Field, Layout, check_flag
from ..plant import layout as lay
from ..plant.dynamics import forward_dynamics, mass_matrix_cs
from ..plant.torque import torque_kernel
from .base import KIND_SMC, R_Q, R_QD, R_QDD, R_QDDD, Controller, pair

H_Q = 1e-6      # finite-difference steps [rad], [rad/s]
H_W = 1e-5

#: Largest pole accepted [1/s] (alpha0 = poles^2; 1e4 1/s is ten times the control rate).
POLE_MAX = 1.0e4
#: Largest switching gain K [rad/s^3] and boundary layer Gamma [rad/s^2] accepted.
SMC_GAIN_MAX = 1.0e9
#: Shortest model valve time constant accepted [s], as for the valves themselves
#: (:class:`~ppamsafety.params.valves.Valve`): the 1 kHz controller cannot act faster.
MODEL_T_MIN = 1.0e-3


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
    Field("qdd_buf", 12, "-", "work memory of model_qdd (torque functions)"),
    Field("mt", 4, "m^3", "m_tau of the four muscle groups at the measured q (B.2)"),
    Field("vol", 4, "m^3", "group volumes"),
    Field("dmt", 4, "m^3/rad", "d m_tau / dq"),
    Field("fp", 4, "Pa/s", "pressure drift (valve towards p_m, polytropic coupling)"),
    Field("gp", 4, "1/s", "pressure input direction"),
])
X_BUF, X_MT, X_VOL, X_DMT, X_FP, X_GP = SMC_SCRATCH.offsets(
    "qdd_buf", "mt", "vol", "dmt", "fp", "gp")


@kernel
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
    buf : numpy.ndarray, shape (>= 12,)
        Work memory: m_tau [m^3], d m_tau/dq [m^3/rad] and volumes [m^3] of
        the four groups (``qdd_buf`` of ``SMC_SCRATCH``), overwritten.

    Returns
    -------
    tuple of float
        Joint accelerations (qdd1, qdd2) [rad/s^2].
    """
    mt = buf[0:4]
    torque_kernel(q1, q2, Pm, mt, buf[4:8], buf[8:12])
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
    buf = scratch[X_BUF:X_BUF + 12]
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
    b = np.zeros(2)
    A = np.zeros((2, 2))
    v = np.zeros(2)
    for i in range(2):
        for j in range(2):
            if j != i and not mimo:
                continue
            b[i] += dq[i][j] / (2 * H_Q) * qdm[j] + dw[i][j] / (2 * H_W) * acc[j]
            for k in (2 * j, 2 * j + 1):
                b[i] += hinv[i][j] * mt[k] * fp[k]
                A[i, j] += hinv[i][j] * mt[k] * gp[k]
        e = ref[R_Q + i] - qm[i]
        ed = ref[R_QD + i] - qdm[i]
        edd = ref[R_QDD + i] - acc[i]
        s = edd + C[P_A1 + i] * ed + C[P_A0 + i] * e
        v[i] = ref[R_QDDD + i] - b[i] + C[P_A1 + i] * edd + C[P_A0 + i] * ed
        internals[I_S + i] = s
        internals[I_A + i] = A[i, i]
        internals[I_B + i] = b[i]
        v[i] += C[P_K + i] * _sat(s / C[P_GAMMA + i])
    if mimo:
        det_a = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
        dp[0] = (A[1, 1] * v[0] - A[0, 1] * v[1]) / det_a
        dp[1] = (A[0, 0] * v[1] - A[1, 0] * v[0]) / det_a
    else:
        dp[0] = v[0] / A[0, 0]
        dp[1] = v[1] / A[1, 1]
    internals[I_U] = dp[0]
    internals[I_U + 1] = dp[1]


class SlidingModeControl(Controller):
    """Sliding mode control with boundary layer (§4.3, App. C).

    Parameters
    ----------
    poles : float or pair, keyword-only
        The error dynamics on s = 0 get a double pole at -poles [1/s]:
        alpha1 = 2 poles, alpha0 = poles^2 (Hurwitz, (4.35)); in (0, 1e4].
    gain : float or pair
        Switching gain K [rad/s^3], in [0, 1e9].
    boundary_layer : float or pair
        Boundary-layer width Gamma [rad/s^2] (sgn replaced by sat(s/Gamma)),
        in (0, 1e9].
    coupling : {"siso", "mimo"}
        Per-link linearisation as in the thesis, or full MIMO.
    model_time_constants : sequence of 4 float, optional
        Valve time constants the controller assumes [s], each in
        [1e-3, 10] s like the valves' own; default the arm's.
    model_links : LinkInertia, optional
        Link parameters of the model; default the plant's (exact model).

    Notes
    -----
    The thesis gives no SMC gains.  The defaults (poles 40 1/s, K = 3000
    rad/s^3, Gamma = 10 rad/s^2, i.e. a gain K/Gamma = 300 1/s inside the
    boundary layer) were chosen by simulation (:mod:`ppamsafety.sections.smc`,
    which repeats the search and reports it): circle with period 5 s as in
    §4.4.1, realistic sensors (encoder, inter-pulse-timing velocity), SISO
    coupling, exact valve model; on a grid poles {10, 20, 40, 80} x K/Gamma
    {30, 100, 300} x Gamma {3, 10, 30}, the setting that minimises the
    product of the worst-case mean tracking error and the worst-case
    chattering index (RMS of the commanded Delta p above 5 Hz) over the
    nominal plant and a plant with 20 % heavier links (the mismatch of
    §4.4.1).  Ties (within 1 %) go to the smaller K, then the smaller Gamma.
    """

    kind = KIND_SMC
    name = "SMC"
    PARAMS = SMC_PARAMS
    INTERNALS = SMC_INTERNALS
    SCRATCH = SMC_SCRATCH.size

    def __init__(self, *, poles=40.0, gain=3000.0, boundary_layer=10.0, coupling: str = "siso",
                 model_time_constants=None, model_links=None):
        super().__init__()
        p = pair("SlidingModeControl.poles", poles, lo=0.0, lo_open=True, hi=POLE_MAX,
                 unit="1/s")
        self.alpha0 = tuple(x * x for x in p)
        self.alpha1 = tuple(2 * x for x in p)
        self.gain = pair("SlidingModeControl.gain", gain, hi=SMC_GAIN_MAX, unit="rad/s^3")
        self.boundary_layer = pair("SlidingModeControl.boundary_layer", boundary_layer,
                                   lo=0.0, lo_open=True, hi=SMC_GAIN_MAX, unit="rad/s^2")
        code = check_flag(SMCCoupling, coupling, "SlidingModeControl.coupling")
        self.coupling = SMCCoupling(code).name.lower()
        if model_time_constants is not None:
            # as the valves themselves (params.valves): at least 1 ms, at most 10 s
            model_time_constants = check_vector("SlidingModeControl.model_time_constants",
                                                model_time_constants, 4, MODEL_T_MIN, 10.0,
                                                unit="s")
        self.model_time_constants = model_time_constants
        if model_links is not None:
            check_instance("SlidingModeControl.model_links", model_links, LinkInertia)
        self.model_links = model_links

    def pack(self) -> np.ndarray:
        """Parameter row of the compiled step function (layout ``SMC_PARAMS``, SI units)."""
        return SMC_PARAMS.pack(
            alpha0=self.alpha0, alpha1=self.alpha1, gain=self.gain,
            boundary_layer=self.boundary_layer,
            coupling=check_flag(SMCCoupling, self.coupling, "SlidingModeControl.coupling"))

    def model_row(self, arm) -> np.ndarray:
        """Packed arm parameters the controller believes in (its model).

        Parameters
        ----------
        arm : ArmParameters
            The plant; its valves get ``model_time_constants`` and its links
            ``model_links`` where those are set.

        Returns
        -------
        numpy.ndarray
            The model row (layout ``PLANT``).
        """
        a = arm
        if self.model_time_constants is not None:
            a = a.replace(valves=a.valves.with_time_constants(self.model_time_constants))
        links = arm.links if self.model_links is None else self.model_links
        return lay.pack(a, links.base_parameters(arm.geometry.L1))

    def describe(self) -> dict:
        """Parameters as a flat dict for result tables.

        Returns
        -------
        dict
            ``controller``, ``Ki_bar_per_rad_s`` and ``lambda_s`` (NaN),
            ``boundary_layer`` of joint 1 [rad/s^2].
        """
        return {"controller": self.name, "Ki_bar_per_rad_s": np.nan, "lambda_s": np.nan,
                "boundary_layer": self.boundary_layer[0]}
