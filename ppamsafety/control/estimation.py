"""External TCP force estimation without a force sensor (thesis §5.4.2).

Both estimators of the thesis run inside the compiled closed loop
(:func:`estimator_step`, called by :mod:`ppamsafety.experiments.closed_loop`
once per control period, before the controller), from the *measured* signals
only -- the sensor readings q_m, qd_m, the muscle pressures p (the thesis
measures them; here the simulated pressures) -- and the estimator's *model*
(by default the identified dynamics ``arm.model``, Table 3.5), never the
plant truth.  The actuator torque is tau = sum_i p_i m_tau,i(q_m) with the
model's torque functions (2.17).

Model (5.48), friction (3.30) with the smooth Coulomb law of the plant
(c tanh(qd/v_s), ``ArmParameters.friction_velocity``)::

    H(q) qdd + C(q, qd) qd + G(q) + tau_f(qd) = tau + tau_d,   tau_d = J^T(q) f_e

Write p = H(q) qd (generalized momentum) and
u = tau + C^T(q, qd) qd - G(q) - tau_f(qd) (= tau + W4 theta, (5.55)), so that
dp/dt = u + tau_d (5.50).

**Generalized-momentum observer** (§5.4.2.2, De Luca & Mattone), (5.51)-(5.56)::

    r = K_I (p - p(0) - int_0^t (u + r) dt),    f_mo = J^-T(q) r      (5.54), (5.56)

K_I = 10 pi rad/s on both joints (thesis).  Continuous time:
R(s) = K_I/(s + K_I) T_d(s) (5.53).  Discretisation: the integral by the
trapezoidal rule, which makes the update implicit in r_k but linear, solved
in closed form::

    r_k = K_I (p_k - p_0 - I_{k-1} - T/2 (g_{k-1} + u_k)) / (1 + K_I T/2)
    g_k = u_k + r_k,   I_k = I_{k-1} + T/2 (g_{k-1} + g_k)

so that r_k = K_I (p_k - p_0 - I_k) exactly and the error dynamics are the
bilinear (Tustin) image of K_I/(s + K_I): pole rho = (1 - a)/(1 + a),
a = K_I T/2, with rho^n = exp(-K_I n T) exp(-n (K_I T)^3/12 + ...) -- after
100 samples the step response differs from 1 - exp(-K_I t) by < 3e-4 of the
step (forward Euler would be 1.5e-2).  Start: r_0 = 0 (no disturbance assumed
at t = 0), I_0 = 0, g_{-1} = -u_0.

**Recursive least squares** (§5.4.2.1), (5.44)-(5.47), on the filtered model::

    A_f = <J^T(q)>_F                                  (5.44)
    y_f = K_f(q, qd) theta - <tau>_F                  (5.45)
    A_f f_e = y_f                                     (5.46)
    f[k] = f[k-1] + L[k] (y_f[k] - A_f[k] f[k-1])
    L[k] = P[k-1] A^T (mu I + A P[k-1] A^T)^-1
    P[k] = (P[k-1] - L[k] A P[k-1]) / mu              (exponential forgetting, (5.47))

mu = 0.99 (memory T_0 = 1/(1 - mu) = 100 samples = 0.1 s, thesis),
F(s) = 1/(s/omega + 1), omega = 10 pi rad/s (3.21), discretised by the bilinear
transform exactly as in :mod:`ppamsafety.identify.dynamic`.  K_f theta is
formed without accelerations (3.26): with W1 theta = p and
(W3 - W2) theta = G + tau_f - C^T qd (Hdot = C + C^T)::

    y_f = omega p - <omega p + u>_F

The thesis notes (§5.4.2.3) that y_f equals the observer's r when
K_I = omega; with the discretisations above the two recursions are
*identical*, (1 + a) y_k - (1 - a) y_{k-1} = omega (p_k - p_{k-1}) -
a (u_k + u_{k-1}), so y_f and r differ only by the decaying start transient
(y_f starts at the model residual of the first sample, r at 0): tested.  The
filter states start in steady state at the first sample's input (as if the
arm had rested before t = 0) instead of the thesis' zero state plus R = 300
dropped samples.  P[0] = ``p0`` I (m^-2), f[0] = 0.

The dead zone of §5.4.3 (|f| <= F_min = 3 N -> 0) is :func:`dead_zone`; the
admittance controller applies it (:mod:`ppamsafety.control.admittance`), the
estimators log raw estimates.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel, leaf, step_kernel
from .._validation import check_instance, check_range, as_float_array
from ..layouts import Field, Layout
from ..params.inertia import BaseParameters
from ..plant.dynamics import coriolis_cs, friction_cs, gravity_cs, mass_matrix_cs
from ..plant.geometry import tcp_jacobian
from ..plant.packing import pack
from ..plant.torque import torque_kernel

#: Thesis values (§5.4.2-5.4.3): forgetting factor, observer gain [rad/s], filter
#: cut-off [rad/s] (3.21), dead zone F_min [N].
MU_THESIS = 0.99
K_I_THESIS = 10.0 * math.pi
OMEGA_THESIS = 10.0 * math.pi
DEAD_ZONE_THESIS = 3.0

ESTIMATOR_PARAMS = Layout("force estimator parameters", [
    Field("mu", 1, "-", "RLS forgetting factor mu (5.47), thesis 0.99"),
    Field("k_i", 1, "rad/s", "observer gain K_I on both joints (5.51), thesis 10 pi"),
    Field("omega", 1, "rad/s", "cut-off of the filter F(s) = 1/(s/omega + 1) (3.21), (5.44)"),
    Field("p0", 1, "1/m^2", "initial RLS covariance P[0] = p0 I"),
])
EP_MU, EP_KI, EP_OMEGA, EP_P0 = ESTIMATOR_PARAMS.offsets("mu", "k_i", "omega", "p0")

ESTIMATOR_STATE = Layout("force estimator state", [
    Field("p0", 2, "N m s", "momentum p(0) = H(q0) qd0 at the first sample (5.54)"),
    Field("integral", 2, "N m s", "observer integral I_k of (5.54)"),
    Field("g_prev", 2, "N m", "previous integrand g_{k-1} = u_{k-1} + r_{k-1}"),
    Field("r", 2, "N m", "observer residual r_k (5.54)"),
    Field("s_in", 2, "N m", "previous filter input omega p + u"),
    Field("s_out", 2, "N m", "filter output <omega p + u>_F"),
    Field("a_in", 4, "m", "previous J^T entries (j11, j21, j12, j22)"),
    Field("a_out", 4, "m", "A_f = <J^T>_F entries (a11, a12, a21, a22) (5.44)"),
    Field("f", 2, "N", "RLS estimate f[k] (x, y)"),
    Field("cov", 4, "1/m^2", "RLS covariance P[k] (p11, p12, p21, p22)"),
])
(ES_P0, ES_I, ES_G, ES_R, ES_SIN, ES_SOUT, ES_AIN, ES_AOUT, ES_F, ES_COV) = \
    ESTIMATOR_STATE.offsets("p0", "integral", "g_prev", "r", "s_in", "s_out", "a_in", "a_out",
                            "f", "cov")

ESTIMATOR_INTERNALS = Layout("force estimator internals", [
    Field("f_rls", 2, "N", "RLS estimate of the external TCP force (world x, y) (5.47)",
          columns=("Fx_rls", "Fy_rls")),
    Field("f_mo", 2, "N", "momentum-observer estimate J^-T r (world x, y) (5.56)",
          columns=("Fx_mo", "Fy_mo")),
    Field("r", 2, "N m", "observer residual r (low-pass filtered disturbance torque) (5.53)",
          columns=("r1", "r2")),
    Field("y_f", 2, "N m", "filtered torque residual y_f of the RLS (5.45)",
          columns=("yf1", "yf2")),
])
EI_FRLS, EI_FMO, EI_R, EI_YF = ESTIMATOR_INTERNALS.offsets("f_rls", "f_mo", "r", "y_f")

ESTIMATOR_SCRATCH = Layout("force estimator scratch", [
    Field("mt", 4, "m^3", "m_tau of the four muscle groups at q_m (2.17)"),
    Field("dmt", 4, "m^3/rad", "d m_tau / dq"),
    Field("vol", 4, "m^3", "group volumes"),
])
XE_MT, XE_DMT, XE_VOL = ESTIMATOR_SCRATCH.offsets("mt", "dmt", "vol")


@leaf
def dead_zone(fx, fy, fmin):
    """Dead zone of §5.4.3: (0, 0) if ||(fx, fy)|| <= ``fmin`` [N], else (fx, fy) unchanged.

    Parameters
    ----------
    fx, fy : float
        Estimated force components [N].
    fmin : float
        F_min [N].
    """
    if math.sqrt(fx * fx + fy * fy) <= fmin:
        return 0.0, 0.0
    return fx, fy


@step_kernel
def estimator_step(E, ES, Pe, k, dt, qm, qdm, pm, out, scratch):
    """One sample of both force estimators.

    Compiled on its own (not inlined): the closed loop and the collision kernel
    both call it, once per control period, so it is compiled once for both.

    Parameters
    ----------
    E : numpy.ndarray
        Parameter row (``ESTIMATOR_PARAMS``).
    ES : numpy.ndarray
        State (``ESTIMATOR_STATE``), initialised at ``k == 0``, updated in place.
    Pe : numpy.ndarray
        Packed plant-layout row of the estimator's model (theta, friction,
        geometry, torque functions).
    k : int
        Sample index.
    dt : float
        Control period [s].
    qm, qdm : numpy.ndarray, shape (2,)
        Measured angles [rad] and velocities [rad/s].
    pm : numpy.ndarray, shape (4,)
        Measured gauge pressures [Pa].
    out : numpy.ndarray
        Written: ``ESTIMATOR_INTERNALS``.
    scratch : numpy.ndarray
        Work memory (``ESTIMATOR_SCRATCH``).
    """
    mu, ki, om = E[EP_MU], E[EP_KI], E[EP_OMEGA]
    q1, q2, w1, w2 = qm[0], qm[1], qdm[0], qdm[1]
    c1, s1 = math.cos(q1), math.sin(q1)
    c2, s2 = math.cos(q2), math.sin(q2)
    c12, s12 = math.cos(q1 + q2), math.sin(q1 + q2)
    mt = scratch[XE_MT:XE_MT + 4]
    torque_kernel(q1, q2, Pe, mt, scratch[XE_DMT:XE_DMT + 4], scratch[XE_VOL:XE_VOL + 4])
    tau1 = pm[0] * mt[0] + pm[1] * mt[1]
    tau2 = pm[2] * mt[2] + pm[3] * mt[3]
    h11, h12, h22 = mass_matrix_cs(c2, s2, Pe)
    k11, k12, k21, k22 = coriolis_cs(c2, s2, w1, w2, Pe)
    g1, g2 = gravity_cs(c1, s1, c12, s12, Pe)
    f1, f2 = friction_cs(w1, w2, True, Pe)
    p1 = h11 * w1 + h12 * w2                         # p = H qd
    p2 = h12 * w1 + h22 * w2
    u1 = tau1 + k11 * w1 + k21 * w2 - g1 - f1        # u = tau + C^T qd - G - tau_f (5.55)
    u2 = tau2 + k12 * w1 + k22 * w2 - g2 - f2
    j11, j12, j21, j22 = tcp_jacobian(q1, q2, Pe)
    # J^T = [[j11, j21], [j12, j22]]
    half = 0.5 * dt
    wt = om * dt
    b0 = wt / (2.0 + wt)                             # bilinear F(z), as identify.dynamic
    a1 = (2.0 - wt) / (2.0 + wt)
    if k == 0:
        ES[ES_P0], ES[ES_P0 + 1] = p1, p2
        ES[ES_I], ES[ES_I + 1] = 0.0, 0.0
        ES[ES_G], ES[ES_G + 1] = -u1, -u2            # gives r_0 = 0
        ES[ES_SIN], ES[ES_SIN + 1] = om * p1 + u1, om * p2 + u2
        ES[ES_SOUT], ES[ES_SOUT + 1] = om * p1 + u1, om * p2 + u2   # steady state
        ES[ES_AIN], ES[ES_AIN + 1], ES[ES_AIN + 2], ES[ES_AIN + 3] = j11, j21, j12, j22
        ES[ES_AOUT], ES[ES_AOUT + 1], ES[ES_AOUT + 2], ES[ES_AOUT + 3] = j11, j21, j12, j22
        ES[ES_F], ES[ES_F + 1] = 0.0, 0.0
        ES[ES_COV], ES[ES_COV + 1] = E[EP_P0], 0.0
        ES[ES_COV + 2], ES[ES_COV + 3] = 0.0, E[EP_P0]
    # -- momentum observer (5.54), trapezoidal integral --------------------------------
    den = 1.0 + ki * half
    r1 = ki * (p1 - ES[ES_P0] - ES[ES_I] - half * (ES[ES_G] + u1)) / den
    r2 = ki * (p2 - ES[ES_P0 + 1] - ES[ES_I + 1] - half * (ES[ES_G + 1] + u2)) / den
    ga, gb = u1 + r1, u2 + r2
    ES[ES_I] += half * (ES[ES_G] + ga)
    ES[ES_I + 1] += half * (ES[ES_G + 1] + gb)
    ES[ES_G], ES[ES_G + 1] = ga, gb
    ES[ES_R], ES[ES_R + 1] = r1, r2
    # f_mo = J^-T r (5.56): solve [[j11, j21], [j12, j22]] f = r
    det = j11 * j22 - j21 * j12
    out[EI_FMO] = (j22 * r1 - j21 * r2) / det
    out[EI_FMO + 1] = (j11 * r2 - j12 * r1) / det
    out[EI_R], out[EI_R + 1] = r1, r2
    # -- filtered model (5.44)-(5.45) --------------------------------------------------
    for i in range(2):
        x_in = om * (p1 if i == 0 else p2) + (u1 if i == 0 else u2)
        ES[ES_SOUT + i] = a1 * ES[ES_SOUT + i] + b0 * (x_in + ES[ES_SIN + i])
        ES[ES_SIN + i] = x_in
    y1 = om * p1 - ES[ES_SOUT]
    y2 = om * p2 - ES[ES_SOUT + 1]
    out[EI_YF], out[EI_YF + 1] = y1, y2
    jt0, jt1, jt2, jt3 = j11, j21, j12, j22
    for i in range(4):
        x_in = jt0 if i == 0 else (jt1 if i == 1 else (jt2 if i == 2 else jt3))
        ES[ES_AOUT + i] = a1 * ES[ES_AOUT + i] + b0 * (x_in + ES[ES_AIN + i])
        ES[ES_AIN + i] = x_in
    A11, A12, A21, A22 = ES[ES_AOUT], ES[ES_AOUT + 1], ES[ES_AOUT + 2], ES[ES_AOUT + 3]
    # -- RLS with exponential forgetting (5.47) ----------------------------------------
    P11, P12, P21, P22 = ES[ES_COV], ES[ES_COV + 1], ES[ES_COV + 2], ES[ES_COV + 3]
    # B = P A^T
    B11 = P11 * A11 + P12 * A12
    B12 = P11 * A21 + P12 * A22
    B21 = P21 * A11 + P22 * A12
    B22 = P21 * A21 + P22 * A22
    # M = mu I + A B
    M11 = mu + A11 * B11 + A12 * B21
    M12 = A11 * B12 + A12 * B22
    M21 = A21 * B11 + A22 * B21
    M22 = mu + A21 * B12 + A22 * B22
    dm = M11 * M22 - M12 * M21
    # L = B M^-1
    L11 = (B11 * M22 - B12 * M21) / dm
    L12 = (B12 * M11 - B11 * M12) / dm
    L21 = (B21 * M22 - B22 * M21) / dm
    L22 = (B22 * M11 - B21 * M12) / dm
    fx, fy = ES[ES_F], ES[ES_F + 1]
    e1 = y1 - (A11 * fx + A12 * fy)
    e2 = y2 - (A21 * fx + A22 * fy)
    fx += L11 * e1 + L12 * e2
    fy += L21 * e1 + L22 * e2
    ES[ES_F], ES[ES_F + 1] = fx, fy
    # P = (P - L A P)/mu = (P - L B^T)/mu, symmetrised
    n11 = (P11 - (L11 * B11 + L12 * B12)) / mu
    n12 = (P12 - (L11 * B21 + L12 * B22)) / mu
    n21 = (P21 - (L21 * B11 + L22 * B12)) / mu
    n22 = (P22 - (L21 * B21 + L22 * B22)) / mu
    off = 0.5 * (n12 + n21)
    ES[ES_COV], ES[ES_COV + 1], ES[ES_COV + 2], ES[ES_COV + 3] = n11, off, off, n22
    out[EI_FRLS], out[EI_FRLS + 1] = fx, fy


class ForceEstimator:
    """Both external-force estimators of §5.4.2, run inside the closed loop.

    Give it to :class:`~ppamsafety.experiments.ExperimentCase` (``estimator=``);
    the run's signals then include ``Fx_rls``, ``Fy_rls`` (RLS), ``Fx_mo``,
    ``Fy_mo`` (observer) [N], ``r1``, ``r2`` and ``yf1``, ``yf2`` [N m].

    Parameters
    ----------
    mu : float, keyword-only
        RLS forgetting factor in (0, 1] (thesis 0.99).
    k_i : float, keyword-only
        Observer gain K_I [rad/s] on both joints, in (0, pi/dt) (thesis 10 pi).
    omega : float, keyword-only
        Cut-off of the acceleration-eliminating filter F(s) [rad/s] (thesis
        10 pi, (3.21)).
    p0 : float, keyword-only
        Initial RLS covariance P[0] = p0 I [1/m^2], > 0 (default 10: a weak
        prior; the steady value for constant A_f is (1 - mu) (A^T A)^-1 ~ 0.04).
    model : BaseParameters, optional, keyword-only
        Rigid-body parameters the estimators believe in; default None uses the
        arm's identified dynamics ``arm.model`` (Table 3.5).  Pass e.g.
        ``arm.plant_base`` for a perfect model, or an identified
        ``DynamicResult.to_base_parameters()``.

    Raises
    ------
    ValueError
        For a parameter outside its range.
    TypeError
        For a ``model`` that is not a BaseParameters.
    """

    PARAMS = ESTIMATOR_PARAMS
    STATE = ESTIMATOR_STATE
    INTERNALS = ESTIMATOR_INTERNALS
    SCRATCH = ESTIMATOR_SCRATCH.size

    def __init__(self, *, mu: float = MU_THESIS, k_i: float = K_I_THESIS,
                 omega: float = OMEGA_THESIS, p0: float = 10.0, model=None):
        self.mu = check_range("ForceEstimator.mu", mu, 0.0, 1.0, lo_open=True)
        self.k_i = check_range("ForceEstimator.k_i", k_i, 0.0, 1e4, lo_open=True, unit="rad/s")
        self.omega = check_range("ForceEstimator.omega", omega, 0.0, 1e4, lo_open=True,
                                 unit="rad/s")
        self.p0 = check_range("ForceEstimator.p0", p0, 0.0, 1e12, lo_open=True, unit="1/m^2")
        if model is not None:
            check_instance("ForceEstimator.model", model, BaseParameters)
        self.model = model

    def check_period(self, dt: float) -> None:
        """Refuse gains the bilinear discretisation cannot represent at period ``dt``.

        Parameters
        ----------
        dt : float
            Control period [s].
        """
        for nm, w in (("k_i", self.k_i), ("omega", self.omega)):
            if w * dt >= 2.0:
                raise ValueError(f"ForceEstimator.{nm} = {w:g} rad/s is too fast for the "
                                 f"control period dt = {dt:g} s (needs {nm} dt < 2)")

    def pack(self) -> np.ndarray:
        """Parameter row (``ESTIMATOR_PARAMS``) of the compiled step."""
        return ESTIMATOR_PARAMS.pack(mu=self.mu, k_i=self.k_i, omega=self.omega, p0=self.p0)

    def model_row(self, arm) -> np.ndarray:
        """Packed plant-layout row of the estimator's model (``model`` or ``arm.model``).

        Parameters
        ----------
        arm : ArmParameters
            Supplies geometry, torque functions and (default) ``arm.model``.
        """
        return pack(arm, arm.model if self.model is None else self.model)

    def describe(self) -> dict:
        """Parameters as a flat dict."""
        return {"mu": self.mu, "k_i": self.k_i, "omega": self.omega, "p0": self.p0,
                "model": "arm.model" if self.model is None else "given"}

    def __repr__(self) -> str:
        return (f"ForceEstimator(mu={self.mu:g}, k_i={self.k_i:g}, omega={self.omega:g}, "
                f"p0={self.p0:g}, model={'arm.model' if self.model is None else 'given'})")


def apply_dead_zone(force, f_min: float = DEAD_ZONE_THESIS) -> np.ndarray:
    """Dead zone of §5.4.3 on force samples: rows with ||f|| <= ``f_min`` become 0.

    Parameters
    ----------
    force : array_like, shape (..., 2)
        Force samples (x, y) [N].
    f_min : float
        F_min [N] (thesis 3 N), >= 0.

    Returns
    -------
    numpy.ndarray, shape (..., 2)
    """
    f = as_float_array("force", force, shape_tail=(2,))
    f_min = check_range("f_min", f_min, 0.0, 1e6, unit="N")
    return np.where(np.linalg.norm(f, axis=-1, keepdims=True) <= f_min, 0.0, f)


__all__ = ["ForceEstimator", "apply_dead_zone", "dead_zone", "estimator_step",
           "ESTIMATOR_PARAMS", "ESTIMATOR_STATE", "ESTIMATOR_INTERNALS", "ESTIMATOR_SCRATCH",
           "MU_THESIS", "K_I_THESIS", "OMEGA_THESIS", "DEAD_ZONE_THESIS"]
