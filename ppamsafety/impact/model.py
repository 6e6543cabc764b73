"""Public interface of the impact simulation: cases in, results out.

:func:`simulate_impacts` runs a batch of impacts of the flexible-joint arm
with a head model in one compiled call (:mod:`ppamsafety.impact.engine`) and
returns an :class:`ImpactResult` with a summary DataFrame (HIC36, HIC15 and
their windows, F_max and its time, penetration, energies) and optional time
histories.  :func:`effective_mass` gives the arm's apparent mass at the tool
along a direction, the quantity that decides the impact force (§6.3.4).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..results import Result
from .._validation import (MAX_BYTES, InvalidTypeError, as_float_array, check_bool,
                           check_choice, check_finite_result, check_int, check_range, check_size,
                           check_range_array, check_same_rows, check_str, describe,
                           did_you_mean)
from ..plant import dynamics as dyn
from ..plant import geometry as geo
from ..plant import packing
from ..plant._checks import check_arm  # noqa: F401  (also used by reference, pymunk, instants)
from ..plots.impact import plot_impact_history
from . import engine as eng
from .contact import max_penetration
from .head import HeadContactModel, head_model, head_model_names

# ---- plausibility thresholds ---------------------------------------------------------------
#: Joint angles beyond this magnitude [rad] are refused: no revolute joint of a planar
#: arm needs more than one turn, and such values are almost always degrees.
MAX_ANGLE = 2.0 * math.pi
#: Tolerance [rad] of the working-area warning: closed-loop records (e.g. the step
#: response of fig. 5.17) overshoot the limits (2.6)-(2.7) by a fraction of a degree.
ANGLE_MARGIN = math.radians(5.0)
#: Allowed RK4 step of an impact [s]: below 1e-8 s the steps of a 50 ms impact exceed 1e6,
#: above 1e-3 s (the control period) a contact of a few ms is not resolved.
DT_RANGE = (1e-8, 1e-3)
#: Joint speeds beyond this magnitude [rad/s] are refused (about 10^4 rpm: no robot arm;
#: the arithmetic would only overflow).
MAX_JOINT_SPEED = 1.0e3
#: Tool or head speeds above this [m/s] give a ``UserWarning``: the thesis' impact speeds
#: are below 2 m/s (Table 6.1) and a PPAM-driven arm of this size cannot reach 10 m/s.
PLAUSIBLE_SPEED = 10.0
#: Head speeds beyond this magnitude [m/s] are refused.
MAX_HEAD_SPEED = 1.0e3
#: Tool or head speeds above this [m/s] are refused as physically impossible for this arm:
#: three times :data:`PLAUSIBLE_SPEED`, 15 times the fastest impacts of Table 6.1 (below
#: 2 m/s) and above the tool speed of the fastest industrial robots (about 10 m/s).  Such a
#: speed is a unit mistake (deg/s given as rad/s: 90 deg/s is 1.57 rad/s) or a typo, and the
#: head models are not valid there (fitted to impacts of a few m/s).
MAX_SPEED = 30.0
#: The joint spring's period 2 pi / omega, omega^2 = max(K) / lambda_min(H(q)) (an upper
#: bound of the arm's highest natural frequency on its joint springs), must span at least
#: this many of the largest RK4 steps the engine takes (FREE_STRIDE x dt in free flight).
STEPS_PER_PERIOD = 20
#: Relative energy-balance error |E_balance_error| above which a case is flagged
#: (``energy_ok`` False) and a ``UserWarning`` is given.  Valid cases at the default step
#: stay below 1e-5 (tests); 1e-3 signals an under-resolved contact or spring.
ENERGY_TOL = 1e-3
#: Largest number of integration steps duration / dt of one call (memory of the HIC buffer).
MAX_STEPS = 10 ** 7
#: Largest memory of the recorded histories of one call [bytes].
MAX_HISTORY_BYTES = 2 * 10 ** 9
#: Memory one impact case of a call takes until its summary row is built [bytes] (the
#: checked inputs, the Jacobians, the packed kernel row, the summary array and DataFrame;
#: 880 bytes per case measured with ``tracemalloc`` on 2 x 10^4 cases, rounded up): a call
#: whose cases exceed :data:`ppamsafety._validation.MAX_BYTES` is refused before packing.
BYTES_PER_CASE = 1000


def resolve_head(head, name: str = "head") -> HeadContactModel:
    """``head`` as a :class:`HeadContactModel`: ``None`` (thesis-frontal), a name or a model.

    Parameters
    ----------
    head : HeadContactModel, str or None
        The model, one of :func:`~ppamsafety.impact.head.head_model_names`, or
        ``None`` for ``"thesis-frontal"``.
    name : str
        Argument name used in error messages.

    Returns
    -------
    HeadContactModel
    """
    if head is None:
        return head_model()
    if isinstance(head, HeadContactModel):
        return head
    names = head_model_names()
    if isinstance(head, str):
        if head not in names:
            raise ValueError(f"{name} = {head!r}: unknown head model"
                             f"{did_you_mean(head, names)}; choose from "
                             f"{', '.join(map(repr, names))} or pass a HeadContactModel")
        return head_model(head)
    raise InvalidTypeError(f"{name} must be a HeadContactModel or a head model name "
                           f"({', '.join(map(repr, names))}), got {describe(head)}")



def _fmt_cases(idx, limit: int = 5) -> str:
    idx = [int(i) for i in idx]
    more = f" and {len(idx) - limit} more" if len(idx) > limit else ""
    return ", ".join(map(str, idx[:limit])) + more


def check_angles(name: str, q: np.ndarray, arm, *, stacklevel: int = 3) -> np.ndarray:
    """Refuse joint angles that cannot be radians; warn outside the working area.

    Rules: any |q| > :data:`MAX_ANGLE` (2 pi) raises ``ValueError``
    -- with the hint "did you mean np.radians(...)?" when the values read as
    degrees lie inside the working area (2.6)-(2.7); angles outside the
    working area ``arm.geometry.q1_min..q1_max``, ``q2_min..q2_max`` but
    within 2 pi give a ``UserWarning`` when they exceed it by more than
    :data:`ANGLE_MARGIN` (5 deg; the impact model itself is valid there, e.g.
    for another arm, and closed-loop records overshoot the limits slightly).

    Parameters
    ----------
    name : str
        Argument name used in messages.
    q : numpy.ndarray, shape (..., 2)
        Finite joint angles [rad] (already converted).
    arm : ArmParameters
        Supplies the working area.
    stacklevel : int
        ``stacklevel`` of the warning.

    Returns
    -------
    numpy.ndarray
        ``q`` unchanged.
    """
    g = arm.geometry
    lo = np.array([g.q1_min, g.q2_min])
    hi = np.array([g.q1_max, g.q2_max])
    area = (f"working area q1 in [{math.degrees(g.q1_min):.0f}, {math.degrees(g.q1_max):.0f}] "
            f"deg, q2 in [{math.degrees(g.q2_min):.0f}, {math.degrees(g.q2_max):.0f}] deg")
    q2d = q.reshape(-1, 2)
    big = np.abs(q2d) > MAX_ANGLE
    if np.any(big):
        i = int(np.nonzero(big.any(axis=1))[0][0])
        val = q2d[i]
        rad = np.radians(val)
        hint = ""
        if np.all((rad >= lo) & (rad <= hi)):
            hint = (f"; looks like degrees: did you mean np.radians({val.tolist()}) = "
                    f"{np.round(rad, 4).tolist()} rad (inside the {area})?")
        where = f"[{i}]" if q.ndim > 1 else ""
        raise ValueError(f"{name}{where} = {val.tolist()} rad is not a joint angle: |{name}| "
                         f"must be <= 2 pi rad{hint or f' (the arm works in the {area})'}")
    out = np.any((q2d < lo - ANGLE_MARGIN) | (q2d > hi + ANGLE_MARGIN), axis=1)
    if np.any(out):
        i = np.nonzero(out)[0]
        warnings.warn(f"{name}: case(s) {_fmt_cases(i)} (e.g. {np.round(q2d[i[0]], 4).tolist()} "
                      f"rad) lie outside the {area} (by more than 5 deg); the impact model is "
                      f"still evaluated",
                      UserWarning, stacklevel=stacklevel)
    return q


def stiffness_limit(q, arm, step: float) -> np.ndarray:
    """Largest joint stiffness [N m/rad] an RK4 step of length ``step`` resolves at ``q``.

    k_lim = lambda_min(H(q)) (2 pi / (:data:`STEPS_PER_PERIOD` step))^2: the
    joint spring's period 2 pi sqrt(lambda_min(H)/k), with the smallest
    eigenvalue of the link inertia matrix H(q) (the lightest inertia a
    joint spring can see), then spans at least :data:`STEPS_PER_PERIOD` steps
    (RK4 itself is unstable beyond omega step = 2.83).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad].
    arm : ArmParameters
        Link inertias.
    step : float
        Largest integration step [s].

    Returns
    -------
    numpy.ndarray, shape (...)
        Stiffness limit per case [N m/rad].
    """
    q = as_float_array("q", q, shape_tail=(2,))
    step = check_range("step", step, 0.0, math.inf, lo_open=True, unit="s")
    lam = np.linalg.eigvalsh(dyn.inertia_matrix(q, arm))[..., 0]
    return lam * (2.0 * math.pi / (STEPS_PER_PERIOD * step)) ** 2


def _step_remedy(dt: float, limit: float, k: float) -> str:
    """The remedy part of a too-stiff message: the step that would resolve ``k`` [N m/rad]
    (the limit scales as 1/dt^2), or none when even dt = 1e-8 s would not."""
    dt_ok = dt * math.sqrt(limit / k)
    return (f"use dt <= {dt_ok:.3g} s, or " if dt_ok >= 1e-8 else
            "this is beyond any integration step (dt >= 1e-8 s): use ")


def check_stiffness(K: np.ndarray, q: np.ndarray, arm, step: float, dt: float,
                    name: str = "stiffness") -> np.ndarray:
    """Refuse joint stiffnesses the integration step cannot resolve (:func:`stiffness_limit`).

    Parameters
    ----------
    K : numpy.ndarray, shape (N, 2)
        Joint stiffnesses [N m/rad], finite and non-negative.
    q : numpy.ndarray, shape (N, 2)
        Joint angles [rad].
    arm : ArmParameters
        Link inertias.
    step : float
        Largest RK4 step the integrator takes [s].
    dt : float
        The user's step [s] (named in the message).
    name : str
        Argument name used in messages.

    Returns
    -------
    numpy.ndarray
        ``K`` unchanged.
    """
    lim = stiffness_limit(q, arm, step)
    bad = np.nonzero(K.max(axis=1) > lim)[0]
    if bad.size:
        i = int(bad[0])
        remedy = _step_remedy(dt, lim[i], float(K[i].max()))
        raise ValueError(
            f"{name}[{i}] = {K[i].tolist()} N m/rad is beyond the validity of the flexible-joint "
            f"impact model at dt = {dt:g} s: the joint spring's period 2 pi sqrt(m/k) must span "
            f">= {STEPS_PER_PERIOD} integration steps, so k <= {lim[i]:.4g} N m/rad here "
            f"(case(s) {_fmt_cases(bad)}); {remedy}the rigid-arm limit "
            f"(fixed_arm=True or a two-body impact with the effective mass)")
    return K


#: Names of the motor-side conventions (:class:`~ppamsafety.impact.engine.JointModel`).
JOINT_MODELS = {"frozen-equilibrium": eng.JointModel.FROZEN_EQUILIBRIUM,
                "flexible-joint": eng.JointModel.FLEXIBLE_JOINT,
                "rigid": eng.JointModel.RIGID}
#: Largest motor-side inertia accepted [kg m^2] (a 10 kg flywheel of 1 m radius: far
#: beyond any arm drive; larger values only approach the constant-speed motor side).
MAX_MOTOR_INERTIA = 1.0e2


def resolve_joint_model(joint_model, name: str = "joint_model") -> "eng.JointModel":
    """``joint_model`` as a :class:`~ppamsafety.impact.engine.JointModel`.

    Parameters
    ----------
    joint_model : JointModel or str
        A member, or one of the names of :data:`JOINT_MODELS`
        (``"frozen-equilibrium"``, ``"flexible-joint"``, ``"rigid"``).
    name : str
        Argument name used in error messages.

    Returns
    -------
    JointModel
    """
    if isinstance(joint_model, eng.JointModel):
        return joint_model
    if isinstance(joint_model, str):
        check_choice(name, joint_model, tuple(JOINT_MODELS))
        return JOINT_MODELS[joint_model]
    raise InvalidTypeError(f"{name} must be a JointModel or one of "
                           f"{', '.join(map(repr, JOINT_MODELS))}, got {describe(joint_model)}")


def flexible_stiffness_limit(q, motor_inertia, arm, step: float) -> np.ndarray:
    """Largest joint stiffness [N m/rad] an RK4 step resolves for the flexible-joint model.

    The highest natural frequency of links (H(q)) and motor sides (B) coupled
    by springs K_i obeys omega^2 <= sum_i K_i (1/B_i + 1/lambda_min(H))
    (Rayleigh quotient and Cauchy-Schwarz on each spring's stretch); with
    equal stiffnesses k on the joints with B_i > 0 the step then spans at
    least :data:`STEPS_PER_PERIOD` steps of the period when
    k <= (2 pi / (STEPS_PER_PERIOD step))^2 / sum_i (1/B_i + 1/lambda_min(H)).
    Joints with B_i = 0 load no spring and set no limit (infinite if both are 0).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad].
    motor_inertia : array_like, shape (..., 2)
        Motor-side inertias B [kg m^2], >= 0, broadcast against ``q``.
    arm : ArmParameters
        Link inertias.
    step : float
        Largest integration step [s].

    Returns
    -------
    numpy.ndarray, shape (...)
        Stiffness limit per case [N m/rad] (``inf`` where both B_i are 0).
    """
    q = as_float_array("q", q, shape_tail=(2,))
    B = as_float_array("motor_inertia", motor_inertia, shape_tail=(2,))
    check_range_array("motor_inertia", B, 0.0, MAX_MOTOR_INERTIA, unit="kg m^2")
    step = check_range("step", step, 0.0, math.inf, lo_open=True, unit="s")
    lam = np.linalg.eigvalsh(dyn.inertia_matrix(q, arm))[..., 0]
    q, B = np.broadcast_arrays(q, B)
    lam = np.broadcast_to(lam, q.shape[:-1])
    with np.errstate(divide="ignore"):
        s = np.where(B > 0, 1.0 / np.where(B > 0, B, 1.0) + 1.0 / lam[..., None], 0.0).sum(-1)
        return np.where(s > 0, (2.0 * math.pi / (STEPS_PER_PERIOD * step)) ** 2
                        / np.where(s > 0, s, 1.0), np.inf)


def check_flexible_stiffness(K: np.ndarray, q: np.ndarray, B: np.ndarray, arm, step: float,
                             dt: float, name: str = "stiffness") -> np.ndarray:
    """Refuse flexible-joint stiffnesses the step cannot resolve (:func:`flexible_stiffness_limit`).

    Parameters
    ----------
    K : numpy.ndarray, shape (N, 2)
        Joint stiffnesses [N m/rad], finite and non-negative.
    q : numpy.ndarray, shape (N, 2)
        Joint angles [rad].
    B : numpy.ndarray, shape (N, 2)
        Motor-side inertias [kg m^2], >= 0.
    arm : ArmParameters
        Link inertias.
    step : float
        Largest RK4 step the integrator takes [s].
    dt : float
        The user's step [s] (named in the message).
    name : str
        Argument name used in messages.

    Returns
    -------
    numpy.ndarray
        ``K`` unchanged.
    """
    lim = flexible_stiffness_limit(q, B, arm, step)
    kk = np.where(B > 0, K, 0.0).max(axis=1)
    bad = np.nonzero(kk > lim)[0]
    if bad.size:
        i = int(bad[0])
        remedy = _step_remedy(dt, lim[i], kk[i])
        raise ValueError(
            f"{name}[{i}] = {K[i].tolist()} N m/rad with motor_inertia = {B[i].tolist()} kg m^2 "
            f"is beyond the resolution of the flexible-joint impact model at dt = {dt:g} s: the "
            f"spring's period must span >= {STEPS_PER_PERIOD} integration steps, so k <= "
            f"{lim[i]:.4g} N m/rad here (case(s) {_fmt_cases(bad)}); {remedy}joint_model "
            f"'rigid', the exact limit k -> infinity")
    return K


def check_pass_through(hm: HeadContactModel, closing_speed) -> None:
    """Refuse cases whose closing speed would drive the tool through the head model.

    The engine starts the head centre at distance ``radius`` from the tool
    point; the free head on a rigid arm (reduced mass m_h, the largest
    possible) must stop before it: the closed-form maximum penetration
    :func:`~ppamsafety.impact.contact.max_penetration` at the case's closing
    speed must stay below the radius.

    Parameters
    ----------
    hm : HeadContactModel
        The head model.
    closing_speed : array_like, shape (N,)
        Closing speed of tool and head along the impact direction [m/s]
        (cases with speed <= 0 are not checked).
    """
    v = np.atleast_1d(np.asarray(closing_speed, dtype=float))
    pos = np.nonzero(v > 0)[0]
    if pos.size == 0:
        return
    # max_penetration grows strictly with the speed: if the fastest case stops clear of the
    # centre (with a relative margin far above rounding), every case does; else find the first
    vmax = float(v[pos].max())
    if vmax <= 1e3 and max_penetration(hm.mass, vmax, hm.stiffness, hm.exponent,
                                       hm.damping) < hm.radius * (1.0 - 1e-9):
        return
    for i in pos:
        if v[i] > 1e3:
            raise ValueError(f"case {int(i)}: closing speed {v[i]:.4g} m/s of tool and head "
                             f"(qd, head_velocity) exceeds 1000 m/s")
        dmax = max_penetration(hm.mass, float(v[i]), hm.stiffness, hm.exponent, hm.damping)
        if not dmax < hm.radius:
            raise ValueError(
                f"case {int(i)}: at the closing speed {v[i]:.4g} m/s the tool would pass "
                f"through the head model {hm.name!r} (maximum penetration {dmax:.3g} m >= "
                f"radius {hm.radius:g} m); use a stiffer head model or a lower speed (qd)")


def _rows(name, arr, n, ref_name):
    """Broadcast a (2,) or (m, 2) array to (n, 2); rows must be 1 or n."""
    a = np.atleast_2d(arr)
    if a.ndim != 2:
        raise ValueError(f"{name} must have shape (2,) or (N, 2), got shape {arr.shape}")
    if a.shape[0] not in (1, n):
        check_same_rows(ref_name, np.empty((n, 2)), name, a)
    return np.ascontiguousarray(np.broadcast_to(a, (n, 2)))


def _unit(v, name):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(n == 0):
        i = int(np.nonzero(n.reshape(-1) == 0)[0][0])
        where = f"[{i}]" if v.ndim > 1 else ""
        raise ValueError(f"{name}{where} = {v.reshape(-1, 2)[i].tolist()} is a zero vector; "
                         f"it must give a direction (any non-zero length)")
    return v / n


def effective_mass(q, direction, arm, *, motor_inertia=None) -> np.ndarray:
    """Apparent mass of the arm's links at the tool along ``direction`` [kg].

    m_eff = 1 / (u^T J H^-1 J^T u): the mass a point force along the unit
    vector u at the TCP feels when the joint springs have no time to act
    (impacts shorter than the arm's vibration periods).  With
    ``motor_inertia`` B, H is replaced by H + diag(B): the rigid arm whose
    motor sides are locked to the links (:attr:`JointModel.RIGID`).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad], |q| <= 2 pi (see :func:`check_angles`; outside
        the working area a ``UserWarning``).
    direction : array_like, shape (..., 2)
        Impact direction (normalised internally; non-zero), broadcast against ``q``.
    arm : ArmParameters
        Link inertias and kinematics.
    motor_inertia : array_like, shape (..., 2), optional
        Motor-side inertias B [kg m^2] added to the joints, each in
        [0, :data:`MAX_MOTOR_INERTIA`] (default 0: the links alone).

    Returns
    -------
    numpy.ndarray
        Effective mass [kg], shape of ``q`` and ``direction`` broadcast without the last axis.

    Raises
    ------
    ValueError
        For a singular direction (stretched or folded arm, u along which the
        tool cannot move: infinite apparent mass).
    """
    q = as_float_array("q", q, shape_tail=(2,))
    d = as_float_array("direction", direction, shape_tail=(2,))
    arm = check_arm(arm)
    check_angles("q", q, arm)
    u = _unit(d, "direction")
    try:
        q, u = np.broadcast_arrays(q, u)
    except ValueError:
        raise ValueError(f"direction (shape {d.shape}) does not broadcast against q "
                         f"(shape {q.shape})") from None
    H = dyn.inertia_matrix(q, arm)
    if motor_inertia is not None:
        B = as_float_array("motor_inertia", motor_inertia, shape_tail=(2,))
        check_range_array("motor_inertia", B, 0.0, MAX_MOTOR_INERTIA, unit="kg m^2")
        try:
            H = H + np.eye(2) * B[..., None, :]
        except ValueError:
            raise ValueError(f"motor_inertia (shape {B.shape}) does not broadcast against q "
                             f"(shape {q.shape})") from None
        q, u = np.broadcast_arrays(q, np.broadcast_to(u, H.shape[:-1]))
    J = geo.jacobian(q, arm)
    Hinv = np.linalg.inv(H)
    M = J @ Hinv @ np.swapaxes(J, -1, -2)
    inv_m = np.einsum("...i,...ij,...j->...", u, M, u)
    scale = np.linalg.eigvalsh(M)[..., -1]
    if np.any(inv_m <= 1e-12 * scale):
        raise ValueError("direction: the tool cannot move along this direction at q (singular "
                         "arm configuration, q2 = 0 or pi): the effective mass is infinite")
    return check_finite_result("effective_mass", 1.0 / inv_m, "this q and direction")


class MissingHistoryError(KeyError, ValueError):
    """No history recorded for a case, or an unknown signal (a ``KeyError`` and a ``ValueError``)."""

    def __str__(self):
        return str(self.args[0]) if self.args else ""


@dataclass
class ImpactResult(Result):
    """Results of a batch of impacts.

    Attributes
    ----------
    summary : pandas.DataFrame
        One row per case: inputs (q1, q2, qd1, qd2 [rad, rad/s], K1, K2
        [N m/rad], ux, uy, tcp_speed [m/s]),
        :data:`~ppamsafety.impact.engine.SUMMARY_COLUMNS` (F_max [N], t_Fmax
        [s], HIC36, HIC15 and windows [s], delta_max [m], a_max_g [g],
        energies [J], contact_time [s], v_tcp0 [m/s], E_balance_error [-]),
        and the checks of the run: ``energy_ok`` (bool, |E_balance_error| <=
        :data:`ENERGY_TOL`) and ``status`` (``"ok"``, ``"at rest"`` for cases
        not simulated, or the reasons a case is flagged: ``"non-finite: ..."``,
        ``"tool reached the head centre"``, ``"energy balance error ..."``).
    histories : dict
        Case index -> DataFrame with :data:`~ppamsafety.impact.engine.HIST_COLUMNS`.
    head : HeadContactModel
        The head model used.
    dt, duration : float
        Integration step and simulated time [s].
    """

    summary: pd.DataFrame
    histories: dict = field(default_factory=dict)
    head: HeadContactModel | None = None
    dt: float = 2e-5
    duration: float = 0.05

    def to_pandas(self) -> pd.DataFrame:
        """The data as a pandas DataFrame (SI units).

        Returns
        -------
        pandas.DataFrame
            A copy of :attr:`summary`.
        """
        return self.summary.copy()

    def __len__(self) -> int:
        return len(self.summary)

    def history(self, index: int) -> pd.DataFrame:
        """Time history of case ``index`` (columns :data:`~ppamsafety.impact.engine.HIST_COLUMNS`).

        Parameters
        ----------
        index : int
            Case index (row of :attr:`summary`) whose history was recorded
            (``history=`` argument of :func:`simulate_impacts`).

        Returns
        -------
        pandas.DataFrame
            One row per integration step.

        Raises
        ------
        TypeError
            If ``index`` is not an integer.
        KeyError
            If no history was recorded for ``index`` (:class:`MissingHistoryError`,
            also a ``ValueError``).
        """
        i = check_int("index", index)
        if i not in self.histories:
            raise MissingHistoryError(f"index = {i}: no history recorded for this case; "
                                      f"recorded: {sorted(self.histories)}")
        return self.histories[i]

    def signal(self, name: str, index: int) -> np.ndarray:
        """One history signal by name, e.g. ``signal("F", 0)`` (SI units, see
        :data:`~ppamsafety.impact.engine.HIST`).

        Parameters
        ----------
        name : str
            A column of :data:`~ppamsafety.impact.engine.HIST_COLUMNS`.
        index : int
            Case index whose history was recorded.

        Returns
        -------
        numpy.ndarray
            The signal at every step.
        """
        check_str("name", name)
        if name not in eng.HIST_COLUMNS:
            raise MissingHistoryError(f"name = {name!r} is not a history signal; signals: "
                                      f"{', '.join(eng.HIST_COLUMNS)}")
        return self.history(index)[name].to_numpy()

    def signals(self, *names: str, index: int) -> np.ndarray:
        """Several history signals by name as columns of an array, shape (nsteps + 1, k).

        Parameters
        ----------
        *names : str
            Columns of :data:`~ppamsafety.impact.engine.HIST_COLUMNS` (at least one).
        index : int
            Case index whose history was recorded.

        Returns
        -------
        numpy.ndarray, shape (nsteps + 1, len(names))
        """
        if not names:
            raise ValueError("names: give at least one signal name; signals: "
                             f"{', '.join(eng.HIST_COLUMNS)}")
        return np.stack([self.signal(n, index) for n in names], axis=1)

    def worst(self, metric: str = "HIC36") -> pd.Series:
        """Row of the case with the largest ``metric``.

        Parameters
        ----------
        metric : str
            A numeric column of :attr:`summary` (e.g. ``"HIC36"``, ``"F_max"``).

        Returns
        -------
        pandas.Series
            The summary row; cases whose ``metric`` is NaN are ignored.

        Raises
        ------
        ValueError
            For an unknown or non-numeric column, or if no case has a finite value.
        """
        cols = [c for c in self.summary.columns
                if pd.api.types.is_numeric_dtype(self.summary[c])
                and not pd.api.types.is_bool_dtype(self.summary[c])]
        check_choice("metric", metric, cols)
        vals = self.summary[metric]
        if not np.any(np.isfinite(vals.to_numpy(dtype=float))):
            raise ValueError(f"metric = {metric!r}: no case has a finite value "
                             f"({len(vals)} cases)")
        return self.summary.loc[vals.idxmax()]

    def plot(self, index=None, **kwargs):
        """The figure (drawn by :mod:`ppamsafety.plots`), a matplotlib Figure.

        Parameters
        ----------
        index : int, optional
            Case whose time history is plotted (default: the first with a
            history).
        **kwargs
            Passed to :func:`ppamsafety.plots.impact.plot_impact_history`.

        Returns
        -------
        matplotlib.figure.Figure
        """
        if index is None:
            if not self.histories:
                raise MissingHistoryError("index: no history was recorded (pass history=True "
                                          "or a list of case indices to simulate_impacts)")
            index = next(iter(self.histories))
        return plot_impact_history(self.history(index), head=self.head, **kwargs)


def _history_indices(history, n: int) -> np.ndarray:
    """``history`` (bool, None or a sequence of case indices) as unique int64 indices."""
    if history is None or isinstance(history, (bool, np.bool_)):
        return np.arange(n) if history else np.array([], dtype=np.int64)
    if isinstance(history, (str, bytes, dict, set, frozenset)) or not (
            isinstance(history, (list, tuple, range, np.ndarray))):
        raise InvalidTypeError(f"history must be True, False or a sequence of case indices, "
                               f"got {describe(history)}")
    items = list(np.asarray(history, dtype=object).ravel()) if isinstance(history, np.ndarray) \
        else list(history)
    idx = [check_int(f"history[{j}]", x, 0, max(n - 1, 0)) for j, x in enumerate(items)]
    if n == 0 and idx:
        raise ValueError(f"history = {idx}: there are no cases")
    return np.array(list(dict.fromkeys(idx)), dtype=np.int64)


def _check_run(df, sel, hm, stacklevel, vals=None):
    """Post-run checks: energy balance, non-finite values, pass-through; columns + warnings.

    ``vals``: the summary rows (n, NSUM) of ``df`` if at hand (saves reading them back)."""
    n = len(df)
    cols = eng.SUMMARY_COLUMNS
    vals = df[cols].to_numpy() if vals is None else vals
    act = np.zeros(n, dtype=bool)
    act[sel] = True
    nonfinite = ~np.isfinite(vals) & act[:, None]
    through = act & ~(vals[:, eng.R_DMAX] < hm.radius)
    err = vals[:, eng.R_EBAL]
    energy_ok = ~act | (np.abs(err) <= ENERGY_TOL)
    flagged = np.nonzero(nonfinite.any(axis=1) | through | ~energy_ok)[0]
    status = np.where(act, "ok", "at rest").astype(object)
    for i in flagged:
        reasons = []
        if nonfinite[i].any():
            reasons.append("non-finite: " + ", ".join(c for c, b in zip(cols, nonfinite[i]) if b))
        if through[i]:
            reasons.append("tool reached the head centre")
        if not energy_ok[i]:
            reasons.append(f"energy balance error {err[i]:.3g}")
        status[i] = "; ".join(reasons)
    df["energy_ok"] = energy_ok
    df["status"] = status
    if flagged.size:
        allbad = nonfinite.any(axis=1)
        if allbad[sel].all():
            i = int(flagged[0])
            raise ValueError(f"every simulated case failed (case {i}: {status[i]}); check the "
                             f"inputs (stiffness, dt, head model)")
        i = int(flagged[0])
        warnings.warn(
            f"impact results flagged for case(s) {_fmt_cases(flagged)}: {status[i]} (case {i}); "
            f"see the summary columns 'status' and 'energy_ok' (energy tolerance "
            f"|E_balance_error| <= {ENERGY_TOL:g})", UserWarning, stacklevel=stacklevel)
    return df


def simulate_impacts(arm, q, qd, stiffness, *, head: HeadContactModel | str | None = None,
                     direction=None, head_velocity=None, fixed_arm: bool = False,
                     dt: float = 2e-5, duration: float = 0.05, history=False,
                     integrator: str = "fixed", joint_model="frozen-equilibrium",
                     motor_inertia=None) -> ImpactResult:
    """Simulate impacts of the flexible-joint arm with a free head (thesis §6.3.2).

    Parameters
    ----------
    arm : ArmParameters
        Link inertias (plant) and kinematics.
    q : array_like, shape (N, 2) or (2,)
        Link angles [rad] at the impact instant.  |q| > 2 pi is refused
        (with a hint when the values are degrees); angles outside the working
        area (``arm.geometry.q1_min..q1_max``, ``q2_min..q2_max``) give a
        ``UserWarning``.
    qd : array_like, shape (N, 2) or (2,)
        Link angular velocities [rad/s], |qd| <= 1000 rad/s.
    stiffness : array_like, shape (N, 2) or (2,)
        Joint stiffnesses K1, K2 [N m/rad] (constant during the impact), >= 0
        and at most :func:`stiffness_limit` (frozen equilibrium) or
        :func:`flexible_stiffness_limit` (flexible joint) for the integration
        step; not used by the rigid model (which also accepts ``np.inf``).
    head : HeadContactModel or str, keyword-only
        Head model or its name (default ``"thesis-frontal"``; see
        :func:`~ppamsafety.impact.head.head_model_names`).
    direction : array_like, shape (N, 2) or (2,), optional
        Vector from the tool point to the head centre (normalised; non-zero);
        default the TCP velocity direction relative to the head (the worst
        case of fig. 6.2).
    head_velocity : array_like, shape (N, 2) or (2,), optional
        Initial head velocity [m/s] (default at rest), |v| <= 1000 m/s.
    fixed_arm : bool
        Treat the arm as rigid and fixed (the head moves into the tool; stored
        in the case rows as :class:`~ppamsafety.impact.engine.ArmMode`).
    dt : float
        Fixed RK4 step [s] in [1e-8, 1e-3] (default 20 us; halving the step
        changes F_max and HIC by less than 2e-4 relative, see tests).
    duration : float
        Simulated time [s] in [1e-4, 10], at least ``dt``; duration / dt <=
        :data:`MAX_STEPS`.
    history : bool or sequence of int
        Record time histories for all cases (True) or for the given case
        indices (each in [0, N - 1]; duplicates are recorded once).
    integrator : {"fixed", "dense"}
        ``"fixed"``: RK4 with step ``dt`` in contact (the reference engine).
        ``"dense"``: RK4 with step 8 ``dt`` in contact and the force on the
        ``dt`` grid from cubic Hermite interpolation
        (:func:`~ppamsafety.impact.engine.impact_batch_dense`), about 3.5x
        faster; F_max, HIC36 and HIC15 within 2e-4 relative of the fixed
        engine and of solve_ivp at rtol 1e-10 (tests/test_impact_dense.py;
        measured 6e-5 on 1000 random impacts).  Cases with a recorded history,
        cases whose stiffness its free-flight step (DENSE_FREE_STRIDE x
        ``dt``) cannot resolve (:func:`stiffness_limit`), and the
        ``"flexible-joint"`` and ``"rigid"`` conventions always use
        ``"fixed"``.
    joint_model : {"frozen-equilibrium", "flexible-joint", "rigid"} or JointModel
        What holds the motor side of the joint springs
        (:class:`~ppamsafety.impact.engine.JointModel`): ``"frozen-equilibrium"``
        (default; pressures held, the PPAM's own physics: the spring pulls
        towards q(t0); as K -> infinity it clamps the link), ``"flexible-joint"``
        (Spong / De Luca and Book: a motor-side inertia ``motor_inertia``
        moving with the link at t0; as K -> infinity the rigid arm) or
        ``"rigid"`` (that limit exactly: the free arm of inertia H + diag(B),
        K unused).  Not combinable with ``fixed_arm``.
    motor_inertia : array_like, shape (N, 2) or (2,), optional
        Motor-side inertias B1, B2 [kg m^2] reflected to the joints, each in
        [0, :data:`MAX_MOTOR_INERTIA`] (default 0: no inertia behind the
        spring, the joint is then free).  Only for ``"flexible-joint"`` and
        ``"rigid"``.

    Returns
    -------
    ImpactResult
        Cases whose tool and head are both at rest are skipped (zero force,
        ``status`` ``"at rest"``).

    Raises
    ------
    TypeError
        For arguments of the wrong kind (naming the argument).
    ValueError
        For values out of range or inconsistent: arrays of shapes (2,) or
        (N, 2) broadcast against each other (1 or N rows; otherwise e.g.
        "qd has 4 rows, q has 3"); angles |q| > 2 pi; stiffness beyond
        :func:`stiffness_limit` (or :func:`flexible_stiffness_limit`) at the
        largest RK4 step (FREE_STRIDE x dt,
        :data:`~ppamsafety.impact.engine.FREE_STRIDE`, for ``"fixed"``;
        DENSE_FREE_STRIDE x dt for ``"dense"``); ``motor_inertia``
        given for the frozen equilibrium, or a joint model other than
        the frozen equilibrium with ``fixed_arm``; a head model through
        which the tool would pass at a case's closing speed (maximum
        penetration of the free head on a rigid arm,
        :func:`~ppamsafety.impact.contact.max_penetration`, >= radius); or
        when every simulated case gives non-finite results.

    Warns
    -----
    UserWarning
        Angles outside the working area; tool or head speed above
        :data:`PLAUSIBLE_SPEED` (10 m/s); and after the run, cases flagged in
        ``status``: non-finite summary values, delta_max >= head radius (tool
        reached the head centre), or |E_balance_error| > :data:`ENERGY_TOL`
        (1e-3).
    """
    return _simulate_impacts(arm, q, qd, stiffness, head=head, direction=direction,
                             head_velocity=head_velocity, fixed_arm=fixed_arm, dt=dt,
                             duration=duration, history=history, integrator=integrator,
                             joint_model=joint_model, motor_inertia=motor_inertia,
                             warn_area=True, stacklevel=4)


def _simulate_impacts(arm, q, qd, stiffness, *, head, direction, head_velocity, fixed_arm, dt,
                      duration, history, integrator, warn_area, stacklevel,
                      joint_model="frozen-equilibrium", motor_inertia=None):
    """:func:`simulate_impacts`; ``warn_area=False`` for states of a simulated closed-loop
    record (their working-area excursions are the controller's, not a user's mistake)."""
    integrator = check_choice("integrator", integrator, ("fixed", "dense"))
    prep = _prepare_impacts(arm, q, qd, stiffness, head=head, direction=direction,
                            head_velocity=head_velocity, fixed_arm=fixed_arm, dt=dt,
                            duration=duration, history=history, warn_area=warn_area,
                            stacklevel=stacklevel + 1, joint_model=joint_model,
                            motor_inertia=motor_inertia)
    n = prep.cases.shape[0]
    SUM = np.zeros((n, eng.NSUM))
    HIST = np.zeros((prep.hist_idx.size, prep.nsteps + 1, eng.NHIST))
    SUM[prep.sel] = _run_cases(prep, prep.sel, integrator, HIST)
    df = _summary_frame(prep, np.arange(n), SUM, stacklevel=stacklevel)
    hists = {int(i): eng.HIST.frame(HIST[j]) for j, i in enumerate(prep.hist_idx)}
    return ImpactResult(df, hists, prep.head, prep.dt, prep.duration)


@dataclass
class _Prepared:
    """Validated, packed impact cases (:func:`_prepare_impacts`), ready for the kernels."""

    q: np.ndarray
    qd: np.ndarray
    K: np.ndarray
    u: np.ndarray
    speed: np.ndarray
    cases: np.ndarray
    sel: np.ndarray
    hist_idx: np.ndarray
    hist_of: np.ndarray
    hp: np.ndarray
    P: np.ndarray
    head: HeadContactModel
    dt: float
    duration: float
    nsteps: int
    w36: int
    w15: int
    arm: object
    fixed_arm: bool
    joint_model: "eng.JointModel" = eng.JointModel.FROZEN_EQUILIBRIUM
    B: np.ndarray | None = None


def _check_cases_size(n: int, ref: str) -> None:
    check_size(f"{n:,} impact cases ({ref} has {n:,} rows)", n * BYTES_PER_CASE,
               remedy=f"simulate them in batches of at most {MAX_BYTES // BYTES_PER_CASE:,} "
                      f"cases")


def _prepare_impacts(arm, q, qd, stiffness, *, head, direction, head_velocity, fixed_arm, dt,
                     duration, history, warn_area, stacklevel,
                     joint_model="frozen-equilibrium", motor_inertia=None):
    """Validate the inputs of :func:`simulate_impacts` and pack the kernel rows (no run)."""
    arm = check_arm(arm)
    rows = [np.shape(a)[0] for a in (q, qd, stiffness, direction, head_velocity, motor_inertia)
            if isinstance(a, np.ndarray) and a.ndim == 2]
    if rows:                              # sized before the arrays are checked or copied
        _check_cases_size(max(rows), "the largest array")
    q = as_float_array("q", q, shape_tail=(2,), ndim=(1, 2))
    qd = as_float_array("qd", qd, shape_tail=(2,), ndim=(1, 2))
    jm = resolve_joint_model(joint_model)
    rigid = jm == eng.JointModel.RIGID
    K = as_float_array("stiffness", stiffness, shape_tail=(2,), ndim=(1, 2),
                       allow_nonfinite=rigid)
    if rigid and np.any(np.isnan(K) | (K == -np.inf)):
        raise ValueError(f"stiffness = {K.tolist()} N m/rad contains NaN or -inf; the rigid "
                         f"model accepts any stiffness >= 0 including inf (it is not used)")
    hm = resolve_head(head)
    d = None if direction is None else as_float_array("direction", direction, shape_tail=(2,),
                                                      ndim=(1, 2))
    vh = None if head_velocity is None else as_float_array(
        "head_velocity", head_velocity, shape_tail=(2,), ndim=(1, 2))
    fixed_arm = check_bool("fixed_arm", fixed_arm)
    frozen = jm == eng.JointModel.FROZEN_EQUILIBRIUM
    Bm = None if motor_inertia is None else as_float_array(
        "motor_inertia", motor_inertia, shape_tail=(2,), ndim=(1, 2))
    if frozen and Bm is not None:
        raise ValueError(f"motor_inertia = {Bm.tolist()} kg m^2 is only used by joint_model "
                         f"'flexible-joint' or 'rigid'; the frozen equilibrium holds the motor "
                         f"side at q(t0) (omit motor_inertia, or choose another joint_model)")
    if fixed_arm and not frozen:
        raise ValueError(f"fixed_arm = True holds the arm still, so joint_model = "
                         f"{jm.name.lower().replace('_', '-')!r} has no meaning; use "
                         f"joint_model 'frozen-equilibrium' (the default) with fixed_arm")
    dt = check_range("dt", dt, *DT_RANGE, unit="s")
    duration = check_range("duration", duration, 1e-4, 10.0, unit="s")
    if duration < dt:
        raise ValueError(f"duration = {duration:g} s is shorter than dt = {dt:g} s")
    nsteps = int(math.ceil(duration / dt - 1e-9))
    if nsteps > MAX_STEPS:
        raise ValueError(f"duration / dt = {duration:g} s / {dt:g} s = {nsteps} steps exceeds "
                         f"{MAX_STEPS}; use a larger dt or a shorter duration")
    # ---- shapes: (2,) or (N, 2), rows 1 or N ----
    named = [(nm, a) for nm, a in (("q", q), ("qd", qd), ("stiffness", K), ("direction", d),
                                     ("head_velocity", vh), ("motor_inertia", Bm))
             if a is not None]
    n = max(a.shape[0] if a.ndim == 2 else 1 for _, a in named)
    if q.ndim == 2 and q.shape[0] == 0:
        n = 0
    ref = next(nm for nm, a in named if (a.shape[0] if a.ndim == 2 else 1) == n)
    _check_cases_size(n, ref)
    q = _rows("q", q, n, ref)
    qd = _rows("qd", qd, n, ref)
    K = _rows("stiffness", K, n, ref)
    vh = np.zeros((n, 2)) if vh is None else _rows("head_velocity", vh, n, ref)
    B = np.zeros((n, 2)) if Bm is None else _rows("motor_inertia", Bm, n, ref)
    # ---- ranges and physical plausibility ----
    if warn_area:
        check_angles("q", q, arm, stacklevel=stacklevel)
    elif np.any(np.abs(q) > MAX_ANGLE):
        check_angles("q", q, arm)
    check_range_array("qd", qd, -MAX_JOINT_SPEED, MAX_JOINT_SPEED, unit="rad/s")
    check_range_array("stiffness", K, 0.0, math.inf, unit="N m/rad")   # inf: rigid only
    check_range_array("head_velocity", vh, -MAX_HEAD_SPEED, MAX_HEAD_SPEED, unit="m/s")
    check_range_array("motor_inertia", B, 0.0, MAX_MOTOR_INERTIA, unit="kg m^2")
    # the fixed engine's largest RK4 step (free flight) must resolve the springs; the dense
    # integrator takes longer steps and hands the cases it cannot resolve to the fixed engine
    # (:func:`_run_cases`)
    if not fixed_arm and n and frozen:
        check_stiffness(K, q, arm, eng.FREE_STRIDE * dt, dt)
    elif jm == eng.JointModel.FLEXIBLE_JOINT and n:
        check_flexible_stiffness(K, q, B, arm, eng.FREE_STRIDE * dt, dt)
    hist_idx = _history_indices(history, n)
    if hist_idx.size * (nsteps + 1) * eng.NHIST * 8 > MAX_HISTORY_BYTES:
        raise ValueError(f"history: {hist_idx.size} histories of {nsteps + 1} steps need "
                         f"{hist_idx.size * (nsteps + 1) * eng.NHIST * 8 / 1e9:.3g} GB (limit "
                         f"{MAX_HISTORY_BYTES / 1e9:g} GB); record fewer cases or use a larger dt")
    vt = np.einsum("nij,nj->ni", geo.jacobian(q, arm), qd)
    speed = np.linalg.norm(vt, axis=1)
    if d is None:
        rel = vt - vh
        nrm = np.linalg.norm(rel, axis=1)
        u = np.where(nrm[:, None] > 0, rel / np.where(nrm > 0, nrm, 1.0)[:, None], [1.0, 0.0])
    else:
        u = _rows("direction", _unit(d, "direction"), n, ref)
    hspeed = np.linalg.norm(vh, axis=1)
    for nm, sp, what in (("qd", speed, "tool speed"), ("head_velocity", hspeed, "head speed")):
        bad = np.nonzero(sp > MAX_SPEED)[0]
        if bad.size:
            i = int(bad[0])
            src = (f"qd[{i}] = {np.round(qd[i], 4).tolist()} rad/s at q = "
                   f"{np.round(np.degrees(q[i]), 2).tolist()} deg" if nm == "qd" else
                   f"head_velocity[{i}] = {np.round(vh[i], 4).tolist()} m/s")
            raise ValueError(f"{nm}: case(s) {_fmt_cases(bad)}: {src} gives a {what} of "
                             f"{sp[i]:.4g} m/s, physically impossible for this arm (allowed: at "
                             f"most {MAX_SPEED:g} m/s; plausible: below {PLAUSIBLE_SPEED:g} m/s)"
                             f"{'; qd is in rad/s (deg/s x pi/180)' if nm == 'qd' else ''}")
    fast = np.nonzero((speed > PLAUSIBLE_SPEED) | (hspeed > PLAUSIBLE_SPEED))[0]
    if fast.size:
        warnings.warn(f"case(s) {_fmt_cases(fast)}: tool speed {speed[fast[0]]:.3g} m/s or head "
                      f"speed above the plausible maximum {PLAUSIBLE_SPEED:g} m/s for this arm "
                      f"(check the units of qd: rad/s)", UserWarning, stacklevel=stacklevel - 1)
    v_close = np.einsum("ni,ni->n", (0.0 if fixed_arm else vt) - vh, u)
    check_pass_through(hm, v_close)
    active = (np.linalg.norm(vt - vh, axis=1) > 0) if not fixed_arm else \
        (np.linalg.norm(vh, axis=1) > 0)
    mode = eng.ArmMode.FIXED if fixed_arm else eng.ArmMode.FLEXIBLE
    cases = eng.pack_cases(n, q=q, qd=0.0 if fixed_arm else qd, K=K, u=u, v_head=vh,
                           arm_mode=int(mode), joint_model=int(jm), B=B)
    hist_of = np.full(n, -1, dtype=np.int64)
    hist_of[hist_idx] = np.arange(hist_idx.size)
    sel = np.nonzero(active)[0]
    w36 = int(math.floor(0.036 / dt * (1 + 1e-9)))
    w15 = int(math.floor(0.015 / dt * (1 + 1e-9)))
    return _Prepared(q=q, qd=qd, K=K, u=u, speed=speed, cases=cases, sel=sel,
                     hist_idx=hist_idx, hist_of=hist_of, hp=eng.pack_head(hm),
                     P=np.array(packing.pack(arm)), head=hm, dt=float(dt),
                     duration=float(duration), nsteps=nsteps, w36=w36, w15=w15,
                     arm=arm, fixed_arm=fixed_arm, joint_model=jm, B=B)


def _run_cases(prep: _Prepared, idx, integrator: str, HIST=None) -> np.ndarray:
    """Summary rows (len(idx), NSUM) of the active cases ``idx`` of ``prep``.

    ``"dense"`` runs :func:`~ppamsafety.impact.engine.impact_batch_dense` except
    for cases with a recorded history (into ``HIST``, indexed by
    ``prep.hist_of``) and cases whose joint stiffness exceeds
    :func:`stiffness_limit` at the dense integrator's free-flight step
    (DENSE_FREE_STRIDE x dt, five times the fixed engine's), which take the
    fixed-step engine.  A case's row depends only on its own case row (never
    on the other cases of the call).
    """
    idx = np.asarray(idx, dtype=np.int64)
    cases = prep.cases[idx]
    hist_of = prep.hist_of[idx]
    if HIST is None:
        HIST = np.zeros((0, prep.nsteps + 1, eng.NHIST))
        hist_of = np.full(idx.size, -1, dtype=np.int64)
    out = np.zeros((idx.size, eng.NSUM))
    args = (prep.P, prep.hp, prep.dt, prep.nsteps, prep.w36, prep.w15)
    if integrator == "dense":
        # the dense integrator is written for the frozen equilibrium (and the fixed arm)
        dense = (hist_of < 0) & (prep.joint_model == eng.JointModel.FROZEN_EQUILIBRIUM)
        if not prep.fixed_arm and idx.size:
            # the dense integrator's free-flight steps must resolve the joint springs
            klim = stiffness_limit(prep.q[idx], prep.arm, eng.DENSE_FREE_STRIDE * prep.dt)
            dense &= prep.K[idx].max(axis=1) <= klim
        od = np.zeros((int(dense.sum()), eng.NSUM))
        eng.impact_batch_dense(np.ascontiguousarray(cases[dense]), *args, od)
        out[dense] = od
        of = np.zeros((int((~dense).sum()), eng.NSUM))
        eng.impact_batch(np.ascontiguousarray(cases[~dense]), *args, of, HIST,
                         np.ascontiguousarray(hist_of[~dense]))
        out[~dense] = of
    else:
        eng.impact_batch(np.ascontiguousarray(cases), *args, out, HIST,
                         np.ascontiguousarray(hist_of))
    return out


def _summary_frame(prep: _Prepared, rows, SUM, *, stacklevel: int) -> pd.DataFrame:
    """The summary DataFrame of the cases ``rows`` of ``prep`` (SUM: their summary rows,
    zero for cases at rest), with the post-run checks (:func:`_check_run`)."""
    rows = np.asarray(rows, dtype=np.int64)
    SUM = np.asarray(SUM, dtype=float).reshape(rows.size, eng.NSUM)
    data = np.empty((rows.size, len(_INPUT_COLUMNS) + eng.NSUM))       # one block: one copy
    data[:, 0:2], data[:, 2:4], data[:, 4:6] = prep.q[rows], prep.qd[rows], prep.K[rows]
    data[:, 6:8], data[:, 8] = prep.u[rows], prep.speed[rows]
    data[:, len(_INPUT_COLUMNS):] = SUM
    df = pd.DataFrame(data, columns=_INPUT_COLUMNS + list(eng.SUMMARY_COLUMNS))
    if prep.joint_model != eng.JointModel.FROZEN_EQUILIBRIUM:
        # the frozen equilibrium keeps its historical columns
        df.insert(6, "joint_model", prep.joint_model.name.lower().replace("_", "-"))
        df.insert(7, "B1", prep.B[rows, 0])
        df.insert(8, "B2", prep.B[rows, 1])
    active = np.zeros(prep.cases.shape[0], dtype=bool)
    active[prep.sel] = True
    return _check_run(df, np.nonzero(active[rows])[0], prep.head, stacklevel=stacklevel + 1,
                      vals=SUM)


#: Input columns of the impact summary, before :data:`~ppamsafety.impact.engine.SUMMARY_COLUMNS`.
_INPUT_COLUMNS = ["q1", "q2", "qd1", "qd2", "K1", "K2", "ux", "uy", "tcp_speed"]
