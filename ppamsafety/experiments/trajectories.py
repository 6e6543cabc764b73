"""Reference trajectories of the thesis experiments (§5.3.4).

A :class:`Reference` holds, per 1 kHz sample, the joint reference and its
first three derivatives and the task-space reference and its velocity: one
row of the declared layout :data:`REFERENCE_ROW` (``"reference row"``), whose
offsets :data:`R_Q_D`, :data:`R_QD_D`, :data:`R_QDD_D`, :data:`R_QDDD_D`,
:data:`R_R_D`, :data:`R_RD_D` are the ones the controller kernels read.  Task-space paths are converted
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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .._validation import as_float_array, check_int, check_range
from ..layouts import Field, Layout
from ..plant import geometry as geo
from ..units import DEG

CIRCLE_CENTER = (0.44, 0.18)
CIRCLE_RADIUS = 0.10

#: One reference sample (thesis §5.3.4): joint reference and its first three
#: time derivatives (elbow-up inverse kinematics of the task-space path),
#: task-space reference of the tool centre point and its velocity.
REFERENCE_ROW = Layout("reference row", [
    Field("q_d", 2, "rad", "desired link angles q1_d, q2_d", columns=("q1_d", "q2_d")),
    Field("qd_d", 2, "rad/s", "desired joint velocities", columns=("qd1_d", "qd2_d")),
    Field("qdd_d", 2, "rad/s^2", "desired joint accelerations", columns=("qdd1_d", "qdd2_d")),
    Field("qddd_d", 2, "rad/s^3", "desired joint jerks", columns=("qddd1_d", "qddd2_d")),
    Field("r_d", 2, "m", "desired tool-centre-point position (x, y)", columns=("x_d", "y_d")),
    Field("rd_d", 2, "m/s", "desired tool-centre-point velocity", columns=("xd_d", "yd_d")),
])
#: Offsets of the fields of :data:`REFERENCE_ROW` (module constants for the kernels).
R_Q_D, R_QD_D, R_QDD_D, R_QDDD_D, R_R_D, R_RD_D = REFERENCE_ROW.offsets(
    "q_d", "qd_d", "qdd_d", "qddd_d", "r_d", "rd_d")
#: Length of a reference row.
NREF = REFERENCE_ROW.size
#: Column names of :attr:`Reference.data` (generated from :data:`REFERENCE_ROW`).
REF_COLUMNS = REFERENCE_ROW.columns()


@dataclass(frozen=True)
class Reference:
    """A sampled reference: ``t`` (n,) [s] and ``data`` (n, :data:`NREF`).

    Each row of ``data`` is a :data:`REFERENCE_ROW` (columns
    :data:`REF_COLUMNS`); read a column with :meth:`signal`.
    """

    name: str
    t: np.ndarray
    data: np.ndarray
    dt: float

    def __post_init__(self):
        if self.data.shape != (self.t.size, NREF):
            raise ValueError(f"Reference.data must have shape (len(t), {NREF}), got "
                             f"{self.data.shape}")

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
        KeyError
            For a name that is not a reference column.
        """
        if not (isinstance(name, str) and name in REF_COLUMNS):
            raise KeyError(f"unknown reference signal {name!r}; choose from {REF_COLUMNS}")
        return self.data[:, REFERENCE_ROW.column_index(name)]

    def field(self, name: str) -> np.ndarray:
        """One field of :data:`REFERENCE_ROW` for every sample, e.g. ``"r_d"`` -> (n, 2)."""
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


def _segment(arm, path, t0, t1, dt, oversample=8):
    """Reference rows for samples k*dt in [t0, t1) of a smooth task-space ``path``."""
    k0 = int(np.ceil(t0 / dt - 1e-9))
    k1 = int(np.ceil(t1 / dt - 1e-9))
    if k1 <= k0:
        return np.empty((0, NREF))
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


def circle_path(*, period: float, center=CIRCLE_CENTER, radius: float = CIRCLE_RADIUS,
                phase: float = 0.0):
    """Callable t -> (r, rdot) of a circle traversed counter-clockwise."""
    check_range("period", period, 0.0, 1e4, lo_open=True, unit="s")
    check_range("radius", radius, 0.0, 1.0, lo_open=True, unit="m")
    c = np.asarray(center, dtype=float)
    w = 2 * np.pi / period

    def path(t):
        ang = phase + w * np.asarray(t)
        r = c + radius * np.stack([np.cos(ang), np.sin(ang)], -1)
        rd = radius * w * np.stack([-np.sin(ang), np.cos(ang)], -1)
        return r, rd
    return path


def circle(arm, *, period: float, duration: float, dt: float = 1e-3, **kwargs) -> Reference:
    """Circle tracking (§5.3.4): diameter 20 cm, period ``period`` [s]."""
    check_range("duration", duration, 0.0, 1e5, lo_open=True, unit="s")
    data = _segment(arm, circle_path(period=period, **kwargs), 0.0, duration, dt)
    return Reference(f"circle P={period:g} s", np.arange(data.shape[0]) * dt, data, dt)


def trajectory_switch(arm, *, period_before: float = 10.0 / 3.0, period_after: float = 10.0,
                      t_switch: float = 7.5, duration: float = 15.0, dt: float = 1e-3) -> Reference:
    """Discontinuous switch between two circles (fig. 5.15)."""
    check_range("t_switch", t_switch, 0.0, duration, lo_open=True, hi_open=True, unit="s")
    a = _segment(arm, circle_path(period=period_before), 0.0, t_switch, dt)
    b = _segment(arm, circle_path(period=period_after), t_switch, duration, dt)
    data = np.concatenate([a, b])
    return Reference("trajectory switch", np.arange(data.shape[0]) * dt, data, dt)


def joint_steps(arm, *, q_levels, t_changes, duration: float, dt: float = 1e-3,
                name: str = "joint steps") -> Reference:
    """Piecewise-constant joint reference: ``q_levels`` (m+1, 2) switched at ``t_changes`` (m,)."""
    lv = as_float_array("q_levels", q_levels, shape_tail=(2,))
    tc = np.atleast_1d(as_float_array("t_changes", t_changes))
    if lv.shape[0] != tc.size + 1:
        raise ValueError("joint_steps: need one more level than change times")
    n = check_int("number of samples", int(round(duration / dt)), 1, 10 ** 9)
    t = np.arange(n) * dt
    seg = np.searchsorted(tc, t, side="right")
    q = lv[seg]
    data = REFERENCE_ROW.empty(n)
    data[:, REFERENCE_ROW.slice("q_d")] = q
    data[:, REFERENCE_ROW.slice("r_d")] = geo.forward_kinematics(q, arm)
    return Reference(name, t, data, dt)


def step(arm, *, low=30 * DEG, high=70 * DEG, q2=-80 * DEG, t_up: float = 2.0,
         t_down: float = 7.0, duration: float = 12.0, dt: float = 1e-3) -> Reference:
    """Step response experiment of fig. 5.17: q1_d 30 -> 70 -> 30 deg, q2_d = -80 deg."""
    return joint_steps(arm, q_levels=[[low, q2], [high, q2], [low, q2]],
                       t_changes=[t_up, t_down], duration=duration, dt=dt, name="step")
