"""Reference trajectories of the thesis experiments (§5.3.4).

A :class:`Reference` holds, per 1 kHz sample, the joint reference and its
first three derivatives and the task-space reference and its velocity: one
row of the declared layout :data:`~ppamsafety.control.reference.REFERENCE_ROW`
(``"reference row"``), declared with the controllers that read it.  Task-space paths are converted
to joint space with the elbow-up inverse kinematics; joint derivatives are
obtained by differentiating on a grid 8x finer than the control period
(second-order central differences), separately on each smooth segment so a
deliberate discontinuity (trajectory switch, step) is not smeared.

Choices the thesis leaves open (documented here, used by the experiments):

* circle centre (0.44, 0.18) m, radius 0.10 m (diameter 20 cm as in §5.3.4),
  counter-clockwise from the rightmost point.  This centre keeps the whole
  circle at least 8 deg inside the working area and statically holdable with
  the Delta-p approach (checked in the tests);
* trajectory switch: a 3.333 s circle switched at t = 7.5 s to a 10 s circle
  with the same centre; both phases run from t = 0, so the desired point
  jumps by half a turn (a 20 cm jump, the worst case);
* step: q1_d = 30 deg, 70 deg at t = 2 s, back to 30 deg at t = 7 s;
  q2_d = -80 deg (fig. 5.17).

Another arm (:func:`experiment_references`): the thesis placed these references inside its
arm's working area 20 <= q1 <= 105 deg, -130 <= q2 <= -30 deg (2.6)-(2.7), and gives no other
rule for them (§5.3.4, §3.5.1.6).  For an arm with another working area each joint angle of a
reference sits at the same *fraction* of that arm's range as in the thesis (the step's q1_d
at 10/85 and 50/85 of the range of q1, its q2_d at the middle of the range of q2; the circle's
centre at the joint angles of the thesis centre, fractions 0.49 and 0.52, mapped and placed with
the arm's own kinematics; the radius stays 10 cm, the experiment's size; the sawtooth's levels
likewise), so every reference lies inside the working area by the thesis' own share of the
range.  The thesis arm keeps exactly the thesis values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from .._validation import (MAX_BYTES, as_float_array, check_finite, check_increasing,
                           check_instance, check_range, check_shape, check_size,
                           check_str, check_vector, did_you_mean, UnknownNameError)
from ..control.reference import (NREF, R_Q_D, R_QD_D, R_QDD_D, R_QDDD_D,  # noqa: F401
                                 R_R_D, R_RD_D, REF_COLUMNS, REFERENCE_ROW)
from ..params import thesis_arm
from ..params.arm import ArmParameters
from ..plant import geometry as geo
from ..units import DEG

CIRCLE_CENTER = (0.44, 0.18)
CIRCLE_RADIUS = 0.10
#: The step of fig. 5.17 on the thesis arm: q1_d low, high, and q2_d [rad].
STEP_LOW, STEP_HIGH, STEP_Q2 = 30 * DEG, 70 * DEG, -80 * DEG
#: One tooth of the static sawtooth's set angles on the thesis arm [deg] (the text does not
#: give the sequence of fig. 3.1; our choice: both joints up and down together in 10 deg steps
#: over the part of the working area the thesis arm can hold).
SAWTOOTH_Q1_DEG = (30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 70.0, 60.0, 50.0, 40.0)
SAWTOOTH_Q2_DEG = (-95.0, -85.0, -75.0, -65.0, -55.0, -45.0, -55.0, -65.0, -75.0, -85.0)
#: Largest tool speed of a reference [m/s]: physically impossible for this arm beyond it
#: (the value of :data:`ppamsafety.impact.model.MAX_SPEED`, 15 times the thesis' fastest
#: impacts; the thesis circles move the tool at 0.03-0.13 m/s).
MAX_TOOL_SPEED = 30.0


@dataclass(frozen=True)
class Reference:
    """A sampled reference: ``t`` (n,) [s] and ``data`` (n, :data:`NREF`).

    Each row of ``data`` is a :data:`REFERENCE_ROW` (columns
    :data:`REF_COLUMNS`); read a column with :meth:`signal`.

    Parameters
    ----------
    name : str
        Name of the reference (default experiment name).
    t : array_like, shape (n,)
        Sample times [s] (n >= 1, finite).
    data : array_like, shape (n, NREF)
        Reference rows (finite, SI units).
    dt : float
        Sample period [s], in [1e-5, 0.1].

    Raises
    ------
    TypeError, ValueError
        For a field of the wrong type or shape, or non-finite values.
    """

    name: str
    t: np.ndarray
    data: np.ndarray
    dt: float

    def __post_init__(self):
        check_str("Reference.name", self.name)
        t = as_float_array("Reference.t", self.t, ndim=1)
        data = as_float_array("Reference.data", self.data, ndim=2)
        if data.shape != (t.size, NREF):
            raise ValueError(f"Reference.data must have shape (len(t), {NREF}) = "
                             f"({t.size}, {NREF}), got {data.shape}")
        if t.size == 0:
            raise ValueError("Reference.t must have at least one sample")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "data", data)
        object.__setattr__(self, "dt", check_range("Reference.dt", self.dt, 1e-5, 0.1,
                                                   unit="s"))

    def signal(self, name: str) -> np.ndarray:
        """One reference column by name, shape (n,), SI units.

        Parameters
        ----------
        name : str
            A column of :data:`REF_COLUMNS`: ``q1_d``, ``q2_d`` [rad],
            ``qd1_d``, ``qd2_d`` [rad/s], ``qdd1_d``, ``qdd2_d`` [rad/s^2],
            ``qddd1_d``, ``qddd2_d`` [rad/s^3], ``x_d``, ``y_d`` [m],
            ``xd_d``, ``yd_d`` [m/s].

        Raises
        ------
        UnknownNameError
            A ``KeyError`` and a ``ValueError``, for a name that is not a reference column.
        """
        if not (isinstance(name, str) and name in REF_COLUMNS):
            raise UnknownNameError(f"unknown reference signal {name!r}"
                                   f"{did_you_mean(name, list(REF_COLUMNS))}; choose from "
                                   f"{REF_COLUMNS}")
        return self.data[:, REFERENCE_ROW.column_index(name)]

    def field(self, name: str) -> np.ndarray:
        """One field of :data:`REFERENCE_ROW` for every sample, e.g. ``"r_d"`` -> (n, 2).

        Parameters
        ----------
        name : str
            A field of :data:`REFERENCE_ROW`: ``q_d``, ``qd_d``, ``qdd_d``,
            ``qddd_d``, ``r_d``, ``rd_d``.

        Returns
        -------
        numpy.ndarray, shape (n, 2)
        """
        return self.data[:, REFERENCE_ROW.slice(name)]

    @property
    def n_steps(self) -> int:
        """Number of samples."""
        return self.t.size

    @property
    def duration(self) -> float:
        """Length [s]."""
        return self.t.size * self.dt

    def to_pandas(self) -> pd.DataFrame:
        """The data as a pandas DataFrame (SI units)."""
        df = pd.DataFrame(self.data, columns=REF_COLUMNS)
        df.insert(0, "t", self.t)
        return df


def _derivatives(q, h):
    """q (m, 2) on a grid of spacing h -> first three derivatives (2nd order)."""
    d1 = np.gradient(q, h, axis=0)
    d2 = np.gradient(d1, h, axis=0)
    d3 = np.gradient(d2, h, axis=0)
    return d1, d2, d3


#: Bytes per reference sample of a smooth path, counting the oversampled working arrays of
#: :func:`_segment` (8 sub-samples of time, path, speed, angles and three derivatives).
_SEGMENT_BYTES = 8 * (NREF + 8 * 14)


def check_reference_size(duration: float, dt: float, per_sample: float = _SEGMENT_BYTES) -> int:
    """Number of samples ``round(duration / dt)``; refuse a reference too large to build.

    Parameters
    ----------
    duration : float
        Length [s].
    dt : float
        Sample period [s].
    per_sample : float
        Memory per sample while it is built [bytes].

    Returns
    -------
    int
        The number of samples.
    """
    n = duration / dt
    check_size(f"duration = {duration:g} s at dt = {dt:g} s ({n:.3g} samples) for the "
               f"reference", n * per_sample,
               remedy=f"use a duration of at most {MAX_BYTES / per_sample * dt:.4g} s at this dt "
                      f"or a larger dt")
    return int(round(n))


def _segment(arm, path, t0, t1, dt, oversample=8):
    """Reference rows for samples k*dt in [t0, t1) of a smooth task-space ``path``."""
    k0 = int(np.ceil(t0 / dt - 1e-9))
    k1 = int(np.ceil(t1 / dt - 1e-9))
    if k1 <= k0:
        return np.empty((0, NREF))
    check_reference_size(t1 - t0, dt, 8 * (NREF + oversample * 14))
    h = dt / oversample
    tf = np.arange(k0 * dt - 3 * h, (k1 - 1) * dt + 3.5 * h, h)
    r, rd = path(tf)
    q = geo.inverse_kinematics(r, arm)
    q = np.unwrap(q, axis=0)
    d1, d2, d3 = _derivatives(q, h)
    idx = 3 + oversample * np.arange(k1 - k0)
    rows = REFERENCE_ROW.empty(k1 - k0)
    rows[:, REFERENCE_ROW.slice("q_d")] = q[idx]
    rows[:, REFERENCE_ROW.slice("qd_d")] = d1[idx]
    rows[:, REFERENCE_ROW.slice("qdd_d")] = d2[idx]
    rows[:, REFERENCE_ROW.slice("qddd_d")] = d3[idx]
    rows[:, REFERENCE_ROW.slice("r_d")] = r[idx]
    rows[:, REFERENCE_ROW.slice("rd_d")] = rd[idx]
    return rows


def _arm(arm):
    return check_instance("arm", arm, ArmParameters)


def _dt(dt) -> float:
    return check_range("dt", dt, 1e-5, 0.1, unit="s")


def check_in_working_area(name: str, q, arm, *, index: bool = True) -> np.ndarray:
    """Refuse joint angles outside the working area (2.6)-(2.7) of ``arm``.

    The simulated arm has no mechanical stops, so a reference beyond them
    would drive an arm that cannot exist; every reference built here is
    therefore kept inside the working area.  A value that is outside as
    radians but inside once converted from degrees gets a hint
    (``did you mean np.radians(30)?``).

    Parameters
    ----------
    name : str
        Argument name for the message.
    q : numpy.ndarray, shape (..., 2)
        Joint angles [rad] (finite).
    arm : ArmParameters
        Its ``geometry`` gives the limits q1_min..q1_max, q2_min..q2_max.
    index : bool, keyword-only
        Name the offending entry as ``name[i, j]`` (else just ``name``).

    Returns
    -------
    numpy.ndarray
        ``q`` unchanged.

    Raises
    ------
    ValueError
        Naming the first offending entry, its value, the allowed interval
        (rad and deg) and, where it fits, the degrees hint.
    """
    g = arm.geometry
    lims = ((g.q1_min, g.q1_max), (g.q2_min, g.q2_max))
    tol = 1e-9
    for j, (lo, hi) in enumerate(lims):
        col = q[..., j]
        bad = np.argwhere((col < lo - tol) | (col > hi + tol))
        if bad.size:
            idx = tuple(int(i) for i in bad[0])
            v = float(col[idx])
            where = f"{name}[{', '.join(map(str, idx + (j,)))}]" if index else name
            hint = ""
            if lo <= np.radians(v) <= hi:
                hint = (f"; did you mean np.radians({v:g}) = {np.radians(v):.4g} rad? Angles are "
                        f"in radians")
            raise ValueError(
                f"{where} = {v:g} rad ({np.degrees(v):.4g} deg) is outside the working area of "
                f"joint {j + 1}: [{lo:.4g}, {hi:.4g}] rad = [{np.degrees(lo):.4g}, "
                f"{np.degrees(hi):.4g}] deg (2.6)-(2.7){hint}")
    return q


def working_area_keys(arm, joint: int) -> str:
    """The arm file's keys of the working area of ``joint`` (1 or 2) with their values [deg].

    Parameters
    ----------
    arm : ArmParameters
    joint : {1, 2}

    Returns
    -------
    str
        e.g. ``"geometry.q1_min = 40 deg, geometry.q1_max = 100 deg"``.
    """
    g = arm.geometry
    lo, hi = (g.q1_min, g.q1_max) if joint == 1 else (g.q2_min, g.q2_max)
    return (f"geometry.q{joint}_min = {np.degrees(lo):.6g} deg, geometry.q{joint}_max = "
            f"{np.degrees(hi):.6g} deg")


def _area(arm) -> tuple:
    g = arm.geometry
    return ((g.q1_min, g.q1_max), (g.q2_min, g.q2_max))


@dataclass(frozen=True)
class ExperimentReferences:
    """Where the experiments of the catalogue run on one arm (joint angles and the circle).

    Built by :func:`experiment_references` (module docstring: the construction).

    Attributes
    ----------
    step_low, step_high : float
        q1_d of the step before and after the up-step [rad] (thesis: 30, 70 deg).
    step_q2 : float
        q2_d of the step [rad] (thesis: -80 deg).
    circle_center : tuple of 2 float
        Centre (x, y) of the circles and of the trajectory switch [m] (thesis arm: (0.44,
        0.18) m, our choice).
    circle_radius : float
        Radius [m] (10 cm: the thesis' 20 cm diameter, §5.3.4).
    sawtooth_q1, sawtooth_q2 : tuple of float
        One tooth of the static sawtooth's set angles [rad] (:data:`SAWTOOTH_Q1_DEG`).
    thesis : bool
        True: the thesis arm's working area, the thesis values exactly; False: derived from
        the arm's working area.
    given : tuple of str
        The step levels given instead (:meth:`with_step`), as ``"name = value unit"``.
    """

    step_low: float
    step_high: float
    step_q2: float
    circle_center: tuple
    circle_radius: float
    sawtooth_q1: tuple
    sawtooth_q2: tuple
    thesis: bool
    given: tuple = ()

    def with_step(self, arm, *, low=None, high=None, q2=None,
                  names=("step_low", "step_high", "step_q2"), unit: str = "rad"):
        """A copy with the step moved; each level checked against the arm's working area.

        Parameters
        ----------
        arm : ArmParameters
            The arm (its working area).
        low, high, q2 : float, optional, keyword-only
            New q1_d before/after the up-step and q2_d, in ``unit`` (None: keep).
        names : tuple of 3 str, keyword-only
            The names of the three values for the messages (a study's keys).
        unit : {"rad", "deg"}, keyword-only
            Unit of the values.

        Returns
        -------
        ExperimentReferences

        Raises
        ------
        ValueError
            For a level outside the working area (naming the value and the arm's keys), or
            ``low == high``.
        """
        unit = check_str("unit", unit)
        if unit not in ("rad", "deg"):
            raise ValueError(f"unit = {unit!r}: allowed 'rad', 'deg'")
        f = DEG if unit == "deg" else 1.0
        vals, given = {}, []
        for nm, j, v, cur in ((names[0], 1, low, self.step_low), (names[1], 1, high, self.step_high),
                              (names[2], 2, q2, self.step_q2)):
            if v is None:
                vals[nm] = cur
                continue
            x = check_finite(nm, v, unit=unit) * f
            lo, hi = _area(arm)[j - 1]
            if not lo - 1e-9 <= x <= hi + 1e-9:
                raise ValueError(f"{nm} = {v:g} {unit} is outside the working area of joint {j} "
                                 f"of the arm ({working_area_keys(arm, j)})")
            vals[nm] = x
            given.append(f"{nm} = {v:g} {unit}")
        lo_, hi_, q2_ = (vals[n] for n in names)
        if lo_ == hi_:
            raise ValueError(f"{names[0]} = {names[1]} = {np.degrees(lo_):g} deg: the reference "
                             f"would not step")
        return replace(self, step_low=lo_, step_high=hi_, step_q2=q2_, thesis=self.thesis and (
            (lo_, hi_, q2_) == (STEP_LOW, STEP_HIGH, STEP_Q2)), given=self.given + tuple(given))

    def sawtooth_levels(self, teeth: int) -> np.ndarray:
        """The sawtooth's set angles [rad], one row (q1_d, q2_d) per level.

        Parameters
        ----------
        teeth : int
            Teeth of :attr:`sawtooth_q1` / :attr:`sawtooth_q2`; the last level closes the
            sawtooth at the start level.

        Returns
        -------
        numpy.ndarray, shape (10 teeth + 1, 2)
        """
        q1 = self.sawtooth_q1 * teeth + self.sawtooth_q1[:1]
        q2 = self.sawtooth_q2 * teeth + self.sawtooth_q2[:1]
        return np.stack([q1, q2], 1)

    @property
    def origin(self) -> str:
        """Where the references come from, in words."""
        return ("the thesis' references" if self.thesis else
                "derived from the arm's working area: the thesis' references at the same "
                "fractions of each joint's range")

    def describe(self, which: str = "all") -> str:
        """The references in words, with units, e.g. for an output's header.

        Parameters
        ----------
        which : {"all", "step", "circle", "sawtooth"}
        """
        src = self.origin
        step = (f"step q1_d {np.degrees(self.step_low):.4g} -> {np.degrees(self.step_high):.4g}"
                f" -> {np.degrees(self.step_low):.4g} deg, q2_d "
                f"{np.degrees(self.step_q2):.4g} deg")
        circ = (f"circle centre ({self.circle_center[0]:.4g}, {self.circle_center[1]:.4g}) m, "
                f"radius {self.circle_radius:.4g} m")
        saw = (f"sawtooth q1_d {min(np.degrees(self.sawtooth_q1)):.4g} .. "
               f"{max(np.degrees(self.sawtooth_q1)):.4g} deg, q2_d "
               f"{min(np.degrees(self.sawtooth_q2)):.4g} .. "
               f"{max(np.degrees(self.sawtooth_q2)):.4g} deg")
        if self.given:
            step += f" (given: {', '.join(self.given)})"
        parts = {"step": step, "circle": circ, "sawtooth": saw}
        if which == "all":
            return f"{step}; {circ}; {saw} ({src})"
        if which not in parts:
            raise ValueError(f"which = {which!r}: allowed 'all', 'step', 'circle', 'sawtooth'")
        return f"{parts[which]} ({src})"


def _mapped(q_thesis, j, area, thesis_area) -> float:
    """A thesis joint angle at the same fraction of joint ``j``'s range of ``area``."""
    (a, b), (ta, tb) = area[j], thesis_area[j]
    return float(a + (q_thesis - ta) / (tb - ta) * (b - a))


def arm_pose(arm, q) -> np.ndarray:
    """A pose chosen on the thesis arm, at the same fractions of ``arm``'s joint ranges.

    The construction of :func:`experiment_references` for any pose of an experiment (e.g. a
    hold configuration or a waypoint): unchanged on the thesis arm's working area.

    Parameters
    ----------
    arm : ArmParameters
    q : array_like, shape (2,)
        Joint angles on the thesis arm [rad].

    Returns
    -------
    numpy.ndarray, shape (2,)
        Joint angles on ``arm`` [rad].
    """
    _arm(arm)
    q = np.asarray(check_vector("q", q, 2, -math.pi, math.pi, unit="rad"), dtype=float)
    tarea, area = _area(thesis_arm()), _area(arm)
    if np.allclose(area, tarea, rtol=0.0, atol=1e-12):
        return q.copy()
    return np.array([_mapped(q[0], 0, area, tarea), _mapped(q[1], 1, area, tarea)])


def experiment_references(arm) -> ExperimentReferences:
    """The references of the catalogue's experiments on ``arm`` (module docstring).

    The thesis arm's working area gives the thesis values exactly; another working area the
    thesis values at the same fractions of each joint's range (the circle's centre through
    the joint angles of the thesis centre and the arm's own kinematics).

    Parameters
    ----------
    arm : ArmParameters

    Returns
    -------
    ExperimentReferences
    """
    _arm(arm)
    tarm = thesis_arm()
    tarea = _area(tarm)
    area = _area(arm)
    if np.allclose(area, tarea, rtol=0.0, atol=1e-12):
        area = tarea                    # the thesis' area written in degrees: the same area
    if area == tarea and (arm.geometry.L1, arm.geometry.L2) == (tarm.geometry.L1,
                                                                 tarm.geometry.L2):
        return ExperimentReferences(STEP_LOW, STEP_HIGH, STEP_Q2, CIRCLE_CENTER, CIRCLE_RADIUS,
                                    tuple(np.radians(SAWTOOTH_Q1_DEG)),
                                    tuple(np.radians(SAWTOOTH_Q2_DEG)), True)
    if area == tarea:
        low, high, q2 = STEP_LOW, STEP_HIGH, STEP_Q2
        s1, s2 = tuple(np.radians(SAWTOOTH_Q1_DEG)), tuple(np.radians(SAWTOOTH_Q2_DEG))
    else:
        low, high = (_mapped(v, 0, area, tarea) for v in (STEP_LOW, STEP_HIGH))
        q2 = _mapped(STEP_Q2, 1, area, tarea)
        s1 = tuple(_mapped(v, 0, area, tarea) for v in np.radians(SAWTOOTH_Q1_DEG))
        s2 = tuple(_mapped(v, 1, area, tarea) for v in np.radians(SAWTOOTH_Q2_DEG))
    qc = geo.inverse_kinematics(np.array([CIRCLE_CENTER]), tarm)[0]
    qc = np.array([_mapped(qc[0], 0, area, tarea), _mapped(qc[1], 1, area, tarea)])
    c = geo.forward_kinematics(qc[None, :], arm)[0]
    return ExperimentReferences(low, high, q2, (float(c[0]), float(c[1])), CIRCLE_RADIUS, s1, s2,
                                False)


def circle_path(*, period: float, center=CIRCLE_CENTER, radius: float = CIRCLE_RADIUS,
                phase: float = 0.0):
    """Callable t -> (r, rdot) of a circle traversed counter-clockwise.

    Parameters
    ----------
    period : float, keyword-only
        Time of one turn [s], in (0, 1e4], and long enough that the tool moves at most
        :data:`MAX_TOOL_SPEED` (2 pi radius / period).
    center : sequence of 2 float
        Centre (x, y) [m], each in [-1, 1] (the arm reaches 0.61 m).
    radius : float
        Radius [m], in (0, 1].
    phase : float
        Angle of the start point on the circle [rad] (0: rightmost point),
        in [-1e3, 1e3].

    Returns
    -------
    callable
        ``path(t)`` -> ``(r, rd)``, positions [m] and velocities [m/s] of
        shape ``t.shape + (2,)``.
    """
    period = check_range("period", period, 0.0, 1e4, lo_open=True, unit="s")
    c = np.asarray(check_vector("center", center, 2, -1.0, 1.0, unit="m"))
    radius = check_range("radius", radius, 0.0, 1.0, lo_open=True, unit="m")
    phase = check_range("phase", phase, -1e3, 1e3, unit="rad")
    w = 2 * np.pi / period
    if radius * w > MAX_TOOL_SPEED:
        raise ValueError(f"period = {period:g} s with radius = {radius:g} m moves the tool at "
                         f"{radius * w:.4g} m/s, physically impossible for this arm (at most "
                         f"{MAX_TOOL_SPEED:g} m/s): period >= "
                         f"{2 * np.pi * radius / MAX_TOOL_SPEED:.3g} s; the thesis circles take "
                         f"5, 10 and 20 s")

    def path(t):
        ang = phase + w * np.asarray(t)
        r = c + radius * np.stack([np.cos(ang), np.sin(ang)], -1)
        rd = radius * w * np.stack([-np.sin(ang), np.cos(ang)], -1)
        return r, rd
    return path


def _circle_segment(arm, t0, t1, dt, what, **circle):
    """``_segment`` of a circle; unreachable or out-of-area circles refused naming ``what``."""
    refs = experiment_references(arm)
    circle = {"center": refs.circle_center, "radius": refs.circle_radius, **circle}
    path = circle_path(**circle)                # validates center and radius first
    c = circle
    own = (tuple(np.asarray(c["center"], dtype=float)) == tuple(refs.circle_center)
           and float(c["radius"]) == refs.circle_radius)
    desc = (f"center={tuple(round(float(x), 6) for x in c['center'])!r} m, "
            f"radius={float(c['radius']):.6g} m")
    if own and not refs.thesis:
        desc += (" (derived from the arm's working area: "
                 f"{working_area_keys(arm, 1)}, {working_area_keys(arm, 2)})")
    if t1 > t0:             # its size first: a long circle is too large, not out of reach
        check_reference_size(t1 - t0, dt, 8 * (NREF + 8 * 14))
    try:
        rows = _segment(arm, path, t0, t1, dt)
    except ValueError as exc:
        raise ValueError(f"{what}: the circle ({desc}) leaves the reach of the arm: "
                         f"{exc}") from None
    try:
        check_in_working_area("q_d", rows[:, REFERENCE_ROW.slice("q_d")], arm)
    except ValueError as exc:
        raise ValueError(f"{what}: the circle ({desc}) leaves the working area of the arm; "
                         f"the arm's working area cannot hold this circle: choose another "
                         f"center or radius, or widen the working area: {exc}") from None
    return rows


def circle(arm, *, period: float, duration: float, dt: float = 1e-3, **kwargs) -> Reference:
    """Circle tracking (§5.3.4): diameter 20 cm, period ``period`` [s].

    Parameters
    ----------
    arm : ArmParameters
        The arm (inverse kinematics, working area).
    period : float, keyword-only
        Time of one turn [s], in (0, 1e4].
    duration : float, keyword-only
        Length of the reference [s], in (0, 1e5]; at least one sample.
    dt : float, keyword-only
        Sample period [s], in [1e-5, 0.1].
    **kwargs
        ``center``, ``radius``, ``phase`` of :func:`circle_path` (default centre and radius:
        :func:`experiment_references` of the arm).

    Returns
    -------
    Reference

    Raises
    ------
    ValueError
        For an argument out of range, or a circle that leaves the reach or
        the working area of the arm (naming ``center`` / ``radius``).
    """
    _arm(arm)
    period = check_range("period", period, 0.0, 1e4, lo_open=True, unit="s")
    duration = check_range("duration", duration, 0.0, 1e5, lo_open=True, unit="s")
    dt = _dt(dt)
    unknown = sorted(set(kwargs) - {"center", "radius", "phase"})
    if unknown:
        raise TypeError(f"circle: unexpected keyword argument(s) {unknown}; allowed: center, "
                        f"radius, phase")
    data = _circle_segment(arm, 0.0, duration, dt, "circle", period=period, **kwargs)
    if data.shape[0] == 0:
        raise ValueError(f"duration = {duration:g} s is shorter than one sample dt = {dt:g} s")
    return Reference(f"circle P={period:g} s", np.arange(data.shape[0]) * dt, data, dt)


def trajectory_switch(arm, *, period_before: float = 10.0 / 3.0, period_after: float = 10.0,
                      t_switch: float = 7.5, duration: float = 15.0, dt: float = 1e-3,
                      **kwargs) -> Reference:
    """Discontinuous switch between two circles (fig. 5.15).

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    period_before, period_after : float, keyword-only
        Circle periods before and after the switch [s], in (0, 1e4].
    t_switch : float, keyword-only
        Switch time [s], strictly inside (0, duration).
    duration : float, keyword-only
        Length [s], in (0, 1e5].
    dt : float, keyword-only
        Sample period [s], in [1e-5, 0.1].
    **kwargs
        ``center``, ``radius`` of both circles (:func:`circle_path`; default
        :func:`experiment_references` of the arm).

    Returns
    -------
    Reference
    """
    _arm(arm)
    unknown = sorted(set(kwargs) - {"center", "radius"})
    if unknown:
        raise TypeError(f"trajectory_switch: unexpected keyword argument(s) {unknown}; allowed: "
                        f"center, radius")
    period_before = check_range("period_before", period_before, 0.0, 1e4, lo_open=True,
                                unit="s")
    period_after = check_range("period_after", period_after, 0.0, 1e4, lo_open=True, unit="s")
    duration = check_range("duration", duration, 0.0, 1e5, lo_open=True, unit="s")
    dt = _dt(dt)
    t_switch = check_range("t_switch", t_switch, 0.0, math.inf, lo_open=True, unit="s")
    if duration <= t_switch:
        raise ValueError(f"duration = {duration:g} s is too short: the switch comes at t_switch = "
                         f"{t_switch:g} s, so the record must be longer than {t_switch:g} s")
    check_reference_size(duration, dt)
    a = _circle_segment(arm, 0.0, t_switch, dt, "trajectory_switch (before)",
                        period=period_before, **kwargs)
    b = _circle_segment(arm, t_switch, duration, dt, "trajectory_switch (after)",
                        period=period_after, **kwargs)
    data = np.concatenate([a, b])
    return Reference("trajectory switch", np.arange(data.shape[0]) * dt, data, dt)


def joint_steps(arm, *, q_levels, t_changes, duration: float, dt: float = 1e-3,
                name: str = "joint steps") -> Reference:
    """Piecewise-constant joint reference: ``q_levels`` (m+1, 2) switched at ``t_changes`` (m,).

    Parameters
    ----------
    arm : ArmParameters
        The arm (forward kinematics, working area).
    q_levels : array_like, shape (m + 1, 2), keyword-only
        Joint angles [rad] of each level; every level must lie inside the
        working area (a value in degrees gets a ``np.radians`` hint).
    t_changes : array_like, shape (m,), keyword-only
        Times of the changes [s], strictly increasing and strictly inside
        (0, duration): a change at or after the end would never happen, a
        change at 0 would skip a level.
    duration : float, keyword-only
        Length [s], in (0, 1e5]; at least one sample.
    dt : float, keyword-only
        Sample period [s], in [1e-5, 0.1].
    name : str, keyword-only
        Name of the reference.

    Returns
    -------
    Reference
        Velocities, accelerations and jerks are zero (steps).
    """
    _arm(arm)
    lv = as_float_array("q_levels", q_levels, ndim=2)
    check_shape("q_levels", lv, (None, 2))
    tc = as_float_array("t_changes", t_changes, ndim=(0, 1)).reshape(-1)
    duration = check_range("duration", duration, 0.0, 1e5, lo_open=True, unit="s")
    dt = _dt(dt)
    name = check_str("name", name)
    if lv.shape[0] != tc.size + 1:
        raise ValueError(f"joint_steps: q_levels has {lv.shape[0]} levels and t_changes "
                         f"{tc.size} change times; need one more level than change times")
    check_increasing("t_changes", tc)
    if tc.size and (tc[0] <= 0.0 or tc[-1] >= duration):
        i = 0 if tc[0] <= 0.0 else tc.size - 1
        raise ValueError(f"t_changes[{i}] = {tc[i]:g} s is outside (0, duration) = "
                         f"(0, {duration:g}) s: the change would never take effect")
    check_in_working_area("q_levels", lv, arm)
    n = check_reference_size(duration, dt, 8 * (NREF + 4))
    if n < 1:
        raise ValueError(f"duration = {duration:g} s is shorter than one sample dt = {dt:g} s")
    t = np.arange(n) * dt
    seg = np.searchsorted(tc, t, side="right")
    q = lv[seg]
    data = REFERENCE_ROW.empty(n)
    data[:, REFERENCE_ROW.slice("q_d")] = q
    data[:, REFERENCE_ROW.slice("r_d")] = geo.forward_kinematics(q, arm)
    return Reference(name, t, data, dt)


def step(arm, *, low=None, high=None, q2=None, t_up: float = 2.0,
         t_down: float = 7.0, duration: float = 12.0, dt: float = 1e-3) -> Reference:
    """Step response experiment of fig. 5.17: q1_d 30 -> 70 -> 30 deg, q2_d = -80 deg.

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    low, high : float, optional, keyword-only
        q1_d before/after the up-step [rad], different, inside the working area (degrees
        are refused with a hint); default :func:`experiment_references` of the arm (the
        thesis arm: 30 deg, 70 deg).
    q2 : float, optional, keyword-only
        q2_d [rad], inside the working area; default likewise (the thesis arm: -80 deg).
    t_up : float, keyword-only
        Time of the up-step [s], strictly inside (0, duration).
    t_down : float, keyword-only
        Time of the down-step [s], after ``t_up``.  At or after
        ``duration`` the down-step lies beyond the record and is left out
        (a shortened run of the 12 s experiment).
    duration : float, keyword-only
        Length [s], in (0, 1e5].
    dt : float, keyword-only
        Sample period [s], in [1e-5, 0.1].

    Returns
    -------
    Reference

    Raises
    ------
    ValueError
        For ``t_down <= t_up`` (no step would be seen), ``low == high``, a
        ``t_up`` outside (0, duration) or angles outside the working area.
    """
    _arm(arm)
    refs = experiment_references(arm)
    low = refs.step_low if low is None else check_finite("low", low, unit="rad")
    high = refs.step_high if high is None else check_finite("high", high, unit="rad")
    q2 = refs.step_q2 if q2 is None else check_finite("q2", q2, unit="rad")
    t_up = check_finite("t_up", t_up, unit="s")
    t_down = check_finite("t_down", t_down, unit="s")
    duration = check_range("duration", duration, 0.0, 1e5, lo_open=True, unit="s")
    if t_down <= t_up:
        raise ValueError(f"t_down = {t_down:g} s must come after t_up = {t_up:g} s (steps in "
                         f"the wrong order give no step at all)")
    t_up = check_range("t_up", t_up, 0.0, math.inf, lo_open=True, unit="s")
    if duration <= t_up:
        raise ValueError(f"duration = {duration:g} s is too short: the up-step comes at t_up = "
                         f"{t_up:g} s, so the record must be longer than {t_up:g} s")
    if low == high:
        raise ValueError(f"low = high = {low:g} rad: the reference would not step")
    mid1, mid2 = (0.5 * (a + b) for a, b in _area(arm))
    for nm, v in (("low", low), ("high", high), ("q2", q2)):
        q = np.array([[v, mid2]]) if nm != "q2" else np.array([[mid1, v]])
        check_in_working_area(nm, q, arm, index=False)
    levels, changes = [[low, q2], [high, q2], [low, q2]], [t_up, t_down]
    if t_down >= duration:
        levels, changes = levels[:2], changes[:1]
    return joint_steps(arm, q_levels=levels, t_changes=changes, duration=duration, dt=dt,
                       name="step")
