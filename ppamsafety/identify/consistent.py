"""Physically consistent dynamic identification: least squares under LMIs.

The unconstrained estimate of :func:`~ppamsafety.identify.dynamic.identify_dynamic`
need not belong to any rigid body: the thesis' Table 3.5 has
theta3 theta6 < L1^2 (theta4^2 + theta5^2), so its inertia matrix H(q) is
indefinite for some q2.  :func:`identify_dynamic_consistent` solves the same
filtered least-squares problem (3.28) restricted to parameters that some pair
of links with non-negative mass density realises (Wensing, Kim & Slotine,
"Linear matrix inequalities for physically consistent inertial parameter
identification", IEEE RA-L 3(1), 2017), a convex semidefinite programme.

**Planar links.**  Only the planar moments of a link enter the planar
dynamics: mass m, first moment h = integral (x, y) dm in the link frame and
the moment of inertia about the joint axis I = integral (x^2 + y^2) dm.
A triple (m, h, I) comes from a non-negative mass distribution iff (in the
closure of that set)::

    J(m, h, I) = [[I,   h_x, h_y],
                  [h_x, m,   0  ],
                  [h_y, 0,   m  ]]  >= 0                                  (LMI)

*Necessity*: Cauchy-Schwarz, |h|^2 = sum_k (integral x_k dm)^2
<= integral dm * integral |x|^2 dm = m I, and I, m >= 0; by the Schur
complement (m > 0) that is J >= 0 (m = 0 forces h = 0).  *Sufficiency*
(m > 0): two masses m/2 at h/m +- r e with r^2 = (I - |h|^2/m)/m >= 0 have
exactly (m, h, I) (parallel-axis theorem).  The out-of-plane moments of the
full 4x4 pseudo-inertia do not appear in the planar dynamics and can always
be completed (a planar density realises them), so the LMI is the exact
condition on the identifiable quantities.

**Physical parameters and the map to (B.5).**  phi = (m1, h1x, h1y, I1, m2,
h2x, h2y, I2): link 1 about the shoulder O in the link-1 frame, link 2 about
the elbow S in the link-2 frame, with the sign convention of (B.5)/fig. 2.9
(theta2 = m1 d_G1 and theta5 = m2 d_G2 enter the potential energy of
:func:`ppamsafety.plant.dynamics.potential_energy` with a minus sign, i.e.
d_G is measured opposite to the counter-clockwise normal; the LMI depends
on |h| only, so the sign does not matter for consistency).  With L1 the
upper-arm length::

    theta1 = h1x + L1 m2          theta4 = h2x
    theta2 = h1y                  theta5 = h2y
    theta3 = I1 + L1^2 m2         theta6 = I2

(:func:`base_map`).  m1 does not enter theta at all and m2 only through the
combinations above, so the masses are not identifiable; they are decision
variables of the programme, bounded by ``mass_bounds`` (default [0, 100] kg:
m1 appears only in the link-1 LMI, and an unbounded m1 drifts to huge values
that spoil the solver's accuracy).  Without upper mass bounds the feasible set in theta is exactly
{theta6 > 0, theta3 theta6 >= L1^2 (theta4^2 + theta5^2)} (choose
|h2|^2/theta6 <= m2 <= theta3/L1^2, then m1 large enough), i.e. precisely
"H(q) >= 0 for every q" (det H = theta3 theta6 - L1^2 (theta4 cos q2 +
theta5 sin q2)^2); :func:`base_lmi_matrix` is that 3x3 LMI.

**The programme.**  minimise ||W^(1/2) (tau_f - K_f theta)||^2 over theta
(10 with friction), m1, m2 subject to J1', J2' >= margin * I (the LMIs scaled
to kg by diag(1/L1, 1, 1), ``margin`` = 1e-6 kg makes the solution strictly
consistent although an interior-point solver meets constraints only to its
tolerance), Coulomb and viscous coefficients >= 0 and the mass bounds.
The least-squares part is reduced exactly by the SVD of the column-scaled
regressor (10x10), so the SDP is tiny whatever the record length; solver
Clarabel through cvxpy (optional dependency, extra ``[identify]``).  If the
unconstrained estimate is already strictly feasible it is the solution of the
convex programme and is returned unchanged (so the constrained and
unconstrained estimates agree exactly when the constraints are inactive).

**Statistics.**  A constrained estimate has no simple covariance.  The
reported standard errors and intervals are those of the *unconstrained*
(W)LS estimate, centred at the constrained one: exact when no constraint is
active, and in the active directions they ignore the information the
constraint adds (the constrained estimator has smaller spread but may be
biased there).  As for :mod:`.dynamic`, they assume white residuals and are
optimistic for the strongly autocorrelated filtered residuals.
``result.active`` says which constraints are active.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .._validation import check_range
from .dynamic import (DROP_SAMPLES, DYNAMIC_NAMES, DYNAMIC_UNITS, FILTER_OMEGA, DynamicResult,
                      _as_records, _nparams, filtered_system, identify_dynamic)
from .lsq import LSQResult

PHYSICAL_NAMES = ("m1", "h1x", "h1y", "I_zO,1", "m2", "h2x", "h2y", "I_zS,2")
PHYSICAL_UNITS = ("kg", "kg m", "kg m", "kg m^2", "kg", "kg m", "kg m", "kg m^2")
CONSTRAINT_NAMES = ("link 1 LMI", "link 2 LMI", "m1 bounds", "m2 bounds",
                    "c1 >= 0", "c2 >= 0", "b1 >= 0", "b2 >= 0")
#: Default mass bounds [kg]: the range :class:`~ppamsafety.params.inertia.LinkInertia` accepts.
#: A finite upper bound keeps the programme bounded (m1 does not enter theta).
DEFAULT_MASS_BOUNDS = ((0.0, 100.0), (0.0, 100.0))
#: Default strict margin of the scaled LMIs [kg].
DEFAULT_MARGIN = 1e-6
#: A scaled LMI whose smallest eigenvalue is within this of the margin is "active" [kg].
ACTIVE_TOL = 1e-5


def base_map(L1: float) -> np.ndarray:
    """A of theta[:6] = A phi (see the module docstring), shape (6, 8).

    Parameters
    ----------
    L1 : float
        Upper-arm length [m], in (0, 5].
    """
    L1 = check_range("L1", L1, 0.0, 5.0, lo_open=True, unit="m")
    A = np.zeros((6, 8))
    A[0, 1], A[0, 4] = 1.0, L1
    A[1, 2] = 1.0
    A[2, 3], A[2, 4] = 1.0, L1 ** 2
    A[3, 5] = A[4, 6] = A[5, 7] = 1.0
    return A


def link_lmi_matrix(m, hx, hy, inertia) -> np.ndarray:
    """J(m, h, I) = [[I, hx, hy], [hx, m, 0], [hy, 0, m]] of one planar link.

    J >= 0 iff a non-negative planar mass distribution has mass ``m`` [kg],
    first moment (hx, hy) [kg m] and moment of inertia ``inertia`` [kg m^2]
    about the reference point (module docstring).

    Parameters
    ----------
    m : float
        Mass [kg].
    hx, hy : float
        First moment [kg m].
    inertia : float
        Moment of inertia about the link's joint axis [kg m^2].
    """
    return np.array([[inertia, hx, hy], [hx, m, 0.0], [hy, 0.0, m]], dtype=float)


def base_lmi_matrix(theta, L1: float) -> np.ndarray:
    """[[theta3, L1 theta4, L1 theta5], [L1 theta4, theta6, 0], [L1 theta5, 0, theta6]].

    Positive semidefinite iff some pair of links with non-negative masses
    realises theta (no mass bounds), iff H(q) >= 0 for every q.

    Parameters
    ----------
    theta : array_like, shape (>= 6,)
        Base parameters (B.5) (friction entries ignored).
    L1 : float
        Upper-arm length [m].
    """
    t = np.asarray(theta, dtype=float)
    if t.ndim != 1 or t.size < 6 or not np.all(np.isfinite(t[:6])):
        raise ValueError(f"theta must be a finite vector of at least 6 entries, got {t!r}")
    L1 = check_range("L1", L1, 0.0, 5.0, lo_open=True, unit="m")
    return np.array([[t[2], L1 * t[3], L1 * t[4]], [L1 * t[3], t[5], 0.0], [L1 * t[4], 0.0, t[5]]])


def _check_mass_bounds(mass_bounds):
    if mass_bounds is None:
        return DEFAULT_MASS_BOUNDS
    try:
        mb = tuple((float(lo), float(hi)) for lo, hi in mass_bounds)
    except (TypeError, ValueError):
        raise TypeError("mass_bounds must be ((m1_lo, m1_hi), (m2_lo, m2_hi)) in kg, got "
                        f"{mass_bounds!r}") from None
    if len(mb) != 2 or any(not (0.0 <= lo < hi < math.inf) for lo, hi in mb):
        raise ValueError("mass_bounds must be ((m1_lo, m1_hi), (m2_lo, m2_hi)) with "
                         f"0 <= lo < hi [kg], got {mass_bounds!r}")
    return mb


def _cvxpy():
    try:
        import cvxpy as cp
    except ImportError:   # pragma: no cover - depends on the environment
        raise ImportError("physically consistent identification needs cvxpy: "
                          "pip install 'ppamsafety[identify]'") from None
    return cp


def _scaled_lmis(cp, theta, m1, m2, L1):
    """The two link LMIs in (theta, m1, m2), scaled to kg by diag(1/L1, 1, 1)."""
    i1 = theta[2] / L1 ** 2 - m2
    h1x = theta[0] / L1 - m2
    h1y = theta[1] / L1
    J1 = cp.bmat([[i1, h1x, h1y], [h1x, m1, 0.0], [h1y, 0.0, m1]])
    J2 = cp.bmat([[theta[5] / L1 ** 2, theta[3] / L1, theta[4] / L1],
                  [theta[3] / L1, m2, 0.0], [theta[4] / L1, 0.0, m2]])
    return J1, J2


def _solve(prob, cp, what):
    with warnings.catch_warnings():   # "may be inaccurate": the status is checked below and
        warnings.simplefilter("ignore", UserWarning)   # every estimate is re-verified in NumPy
        try:
            prob.solve(solver=cp.CLARABEL)
        except cp.error.SolverError:   # pragma: no cover - fallback solver
            prob.solve(solver=cp.SCS, eps=1e-9, max_iters=200000)
    if prob.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
        raise RuntimeError(f"{what}: the semidefinite programme ended with status {prob.status!r}")


def realisation(theta, L1: float, *, mass_bounds=None):
    """Most interior physical realisation phi of the base parameters ``theta``.

    maximise t subject to J1', J2' >= t I (scaled LMIs, module docstring), the
    mass bounds and theta fixed; ties between equally interior realisations
    are broken towards small masses (a 1e-6 weight).  phi is one of many
    realisations: m1 and m2 are not identifiable.

    Parameters
    ----------
    theta : array_like, shape (>= 6,)
        Base parameters (B.5) (friction entries ignored).
    L1 : float
        Upper-arm length [m].
    mass_bounds : ((float, float), (float, float)), optional, keyword-only
        Finite bounds [kg] on m1 and m2, 0 <= lo < hi (default
        :data:`DEFAULT_MASS_BOUNDS`).

    Returns
    -------
    phi : numpy.ndarray, shape (8,)
        (m1, h1x, h1y, I1, m2, h2x, h2y, I2) in kg, kg m, kg m^2.
    margin : float
        t [kg]: >= 0 iff theta is physically consistent (within the bounds).
    """
    cp = _cvxpy()
    L1 = check_range("L1", L1, 0.0, 5.0, lo_open=True, unit="m")
    t_ = np.asarray(theta, dtype=float)
    base_lmi_matrix(t_, L1)   # validates theta
    mb = _check_mass_bounds(mass_bounds)
    m1, m2, t = cp.Variable(), cp.Variable(), cp.Variable()
    J1, J2 = _scaled_lmis(cp, t_[:6], m1, m2, L1)
    eye = np.eye(3)
    cons = [J1 - t * eye >> 0, J2 - t * eye >> 0, t <= 10.0]
    for m, (lo, hi) in zip((m1, m2), mb):
        cons += [m >= lo, m <= hi]
    _solve(cp.Problem(cp.Maximize(t - 1e-6 * (m1 + m2)), cons), cp, "realisation")
    mm1, mm2 = float(m1.value), float(m2.value)
    phi = np.array([mm1, t_[0] - L1 * mm2, t_[1], t_[2] - L1 ** 2 * mm2, mm2, t_[3], t_[4], t_[5]])
    return phi, float(t.value)


def _min_eig_scaled(phi, L1):
    s = np.diag([1.0 / L1, 1.0, 1.0])
    out = []
    for k in (0, 4):
        J = s @ link_lmi_matrix(phi[k], phi[k + 1], phi[k + 2], phi[k + 3]) @ s
        out.append(float(np.linalg.eigvalsh(J)[0]))
    return np.array(out)


@dataclass(frozen=True)
class ConsistentResult(DynamicResult):
    """Physically consistent estimate; a :class:`DynamicResult` plus the constraints.

    Everything of :class:`DynamicResult` (``estimates``, ``predict_torque``,
    ``validation_table`` use ...) refers to the constrained estimate.

    Attributes
    ----------
    lsq : LSQResult
        The constrained estimate with its (unconstrained, see module doc)
        statistics; ``lsq.predicted`` is K_f theta_constrained.
    friction, sign_velocity, datasets, omega, joint_sigma
        As in :class:`DynamicResult` (``joint_sigma`` from the unconstrained
        LS residuals).
    unconstrained : DynamicResult
        The ordinary (W)LS estimate of the same data.
    phi : numpy.ndarray, shape (8,)
        A physical realisation (m1, h1x, h1y, I1, m2, h2x, h2y, I2): the
        programme's masses when a constraint is active, else the most interior
        one (:func:`realisation`).  The masses are not identifiable.
    lmi_margins : numpy.ndarray, shape (2,)
        Smallest eigenvalue of the scaled link LMIs at ``phi`` [kg] (> 0).
    active : dict
        ``{constraint name: bool}`` for :data:`CONSTRAINT_NAMES` (friction
        entries only with friction).
    mass_bounds : tuple
        ((m1_lo, m1_hi), (m2_lo, m2_hi)) [kg] used.
    margin : float
        Strict margin of the scaled LMIs [kg].
    """

    unconstrained: DynamicResult = field(default=None, repr=False)
    phi: np.ndarray = field(default=None)
    lmi_margins: np.ndarray = field(default=None)
    active: dict = field(default_factory=dict)
    mass_bounds: tuple = DEFAULT_MASS_BOUNDS
    margin: float = DEFAULT_MARGIN

    @property
    def any_active(self) -> bool:
        """Whether any constraint is active (the estimate differs from the unconstrained one)."""
        return any(self.active.values())

    def to_pandas(self) -> pd.DataFrame:
        """One row per parameter as :meth:`DynamicResult.to_pandas` plus ``unconstrained``.

        Standard errors are those of the unconstrained estimate (module
        docstring); ``attrs["active"]`` lists the active constraints.
        """
        df = self.lsq.to_pandas()
        df["unconstrained"] = self.unconstrained.estimates
        df.attrs["active"] = [k for k, v in self.active.items() if v]
        df.attrs["std_error"] = "unconstrained (W)LS, centred at the constrained estimate"
        return df

    def physical_to_pandas(self) -> pd.DataFrame:
        """The realisation phi: one row per physical parameter (value, unit)."""
        return pd.DataFrame({"value": self.phi, "unit": list(PHYSICAL_UNITS)},
                            index=pd.Index(PHYSICAL_NAMES, name="parameter"))


def identify_dynamic_consistent(data, arm, *, friction: bool = True, method: str = "LS",
                                sign_velocity: float | None = None, omega: float = FILTER_OMEGA,
                                drop: int = DROP_SAMPLES, confidence: float = 0.95,
                                gravity_acc: float | None = None, mass_bounds=None,
                                margin: float = DEFAULT_MARGIN) -> ConsistentResult:
    """Dynamic base parameters by (W)LS under the planar pseudo-inertia LMIs.

    See the module docstring for the constraints, the programme and what the
    standard errors mean.

    Parameters
    ----------
    data : DynamicData or list of DynamicData
        Records (as for :func:`~ppamsafety.identify.dynamic.identify_dynamic`).
    arm : ArmParameters
        Supplies L1 and g.
    friction : bool, keyword-only
        10 parameters with Coulomb + viscous friction (constrained >= 0) or 6.
    method : {"LS", "WLS"}, keyword-only
        WLS: joint weights 1/s_j^2 from the unconstrained LS residuals (as in
        ``identify_dynamic``), used in the constrained programme as well.
    sign_velocity, omega, drop, confidence, gravity_acc
        As in :func:`~ppamsafety.identify.dynamic.identify_dynamic`.
    mass_bounds : ((float, float), (float, float)), optional, keyword-only
        Finite bounds [kg] on m1 and m2, 0 <= lo < hi: prior knowledge
        (e.g. the §6.3.3 masses).  Default :data:`DEFAULT_MASS_BOUNDS`,
        [0, 100] kg, which makes the constraint practically "H(q) > 0 for
        all q" (module docstring).
    margin : float, keyword-only
        Strict margin of the scaled LMIs [kg], in [0, 0.1].

    Returns
    -------
    ConsistentResult
    """
    cp = _cvxpy()
    mb = _check_mass_bounds(mass_bounds)
    margin = check_range("margin", margin, 0.0, 0.1, unit="kg")
    records = _as_records(data)
    kw = dict(friction=friction, sign_velocity=sign_velocity, omega=omega, drop=drop,
              gravity_acc=gravity_acc)
    unc = identify_dynamic(records, arm, method=method, confidence=confidence, **kw)
    L1 = arm.geometry.L1
    p = _nparams(friction)
    names = list(CONSTRAINT_NAMES[:4] + (CONSTRAINT_NAMES[4:] if friction else ()))
    theta_u = unc.estimates
    fric_ok = not friction or np.all(theta_u[6:] >= 0)
    phi_u, t_u = realisation(theta_u, L1, mass_bounds=mb)
    if fric_ok and t_u > margin:
        # the unconstrained minimiser is strictly feasible: it solves the convex programme
        theta, active = theta_u.copy(), {k: False for k in names}
        lsq, phi = unc.lsq, phi_u
    else:
        Kf, tf = filtered_system(records, arm, **kw)
        A = np.concatenate([Kf[:, 0, :], Kf[:, 1, :]])
        y = np.concatenate([tf[:, 0], tf[:, 1]])
        w = unc.lsq.weights
        sw = np.ones_like(y) if w is None else np.sqrt(w)
        Aw, yw = A * sw[:, None], y * sw
        scale = np.linalg.norm(Aw, axis=0)
        U, s, Vt = np.linalg.svd(Aw / scale, full_matrices=False)
        M, c = s[:, None] * Vt, U.T @ yw
        z, m1, m2 = cp.Variable(p), cp.Variable(), cp.Variable()
        th = cp.multiply(1.0 / scale, z)
        J1, J2 = _scaled_lmis(cp, th, m1, m2, L1)
        eye = np.eye(3)
        cons = [J1 - margin * eye >> 0, J2 - margin * eye >> 0]
        for m, (lo, hi) in zip((m1, m2), mb):
            cons += [m >= lo, m <= hi]
        if friction:
            cons.append(z[6:] >= 0)
        _solve(cp.Problem(cp.Minimize(cp.sum_squares(M @ z - c)), cons), cp,
               "identify_dynamic_consistent")
        theta = np.asarray(z.value, dtype=float) / scale
        if friction:
            theta[6:] = np.maximum(theta[6:], 0.0)   # solver tolerance on z >= 0
        mm = (float(m1.value), float(m2.value))
        phi = np.array([mm[0], theta[0] - L1 * mm[1], theta[1], theta[2] - L1 ** 2 * mm[1],
                        mm[1], theta[3], theta[4], theta[5]])
        J1v = np.asarray(J1.value, dtype=float)
        J2v = np.asarray(J2.value, dtype=float)
        active = {names[0]: bool(np.linalg.eigvalsh(J1v)[0] <= margin + ACTIVE_TOL),
                  names[1]: bool(np.linalg.eigvalsh(J2v)[0] <= margin + ACTIVE_TOL)}
        for k, (mv, (lo, hi)) in enumerate(zip(mm, mb)):
            active[names[2 + k]] = bool(mv <= lo + ACTIVE_TOL or mv >= hi - ACTIVE_TOL)
        if friction:
            for k in range(4):
                active[names[4 + k]] = bool(theta[6 + k] <= 1e-9 * max(1.0, abs(theta_u[6 + k])))
        pred = A @ theta
        r_w = (y - pred) * sw
        dof = unc.lsq.dof
        se = unc.lsq.std_errors
        from scipy import stats

        tq = float(stats.t.ppf(0.5 + 0.5 * confidence, dof))
        tag = "with friction" if friction else "frictionless"
        lsq = LSQResult(names=tuple(DYNAMIC_NAMES[:p]), units=tuple(DYNAMIC_UNITS[:p]),
                        estimates=theta, std_errors=se, covariance=unc.lsq.covariance,
                        ci_low=theta - tq * se, ci_high=theta + tq * se,
                        confidence=float(confidence), sigma=float(np.sqrt(r_w @ r_w / dof)),
                        residual_rms=float(np.sqrt(np.mean((y - pred) ** 2))),
                        condition_number=unc.lsq.condition_number, dof=dof, measured=y,
                        predicted=pred, method=f"LMI-constrained {method} {tag}",
                        quantity=unc.lsq.quantity, weights=w)
    eig = _min_eig_scaled(phi, L1)
    if not np.all(eig > 0):
        raise RuntimeError("identify_dynamic_consistent: the solver returned an estimate outside "
                           f"the consistent set (LMI margins {eig} kg); try a larger margin")
    return ConsistentResult(lsq=lsq, friction=friction, sign_velocity=sign_velocity,
                            datasets=unc.datasets, omega=float(omega), joint_sigma=unc.joint_sigma,
                            unconstrained=unc, phi=phi, lmi_margins=eig, active=active,
                            mass_bounds=mb, margin=float(margin))


__all__ = ["PHYSICAL_NAMES", "PHYSICAL_UNITS", "CONSTRAINT_NAMES", "DEFAULT_MARGIN", "base_map",
           "link_lmi_matrix", "base_lmi_matrix", "realisation", "ConsistentResult",
           "identify_dynamic_consistent"]
