"""Known external forces on the TCP in the closed loop: a force profile and a "hand".

A person pushing the end-effector is modelled as a world-frame TCP force

    f(t) = f_profile(t) + a(t) (K_h (r_h(t) - r(t)) - B_h rdot(t))

with ``f_profile`` given per control sample (``ExperimentCase.external_force``)
and an optional spring-damper :class:`Hand` (stiffness K_h [N/m], damping B_h
[N s/m]) that pulls the TCP r toward a moving target r_h(t) while it is
engaged (a(t) = 1) and lets go when a(t) = 0.  The hand acts on the *true*
TCP position and velocity (plant truth).  The closed loop applies the joint
torque tau_ext = J^T(q) f (virtual work) to the plant; f and J are evaluated
at the state at the start of every RK4 step and held over its four stages
(with the default ``substeps = 1``: held over the 1 ms control period, the
same zero-order hold as the valve set values).  Each sample of the external
input is a row of the declared layout :data:`EXTERNAL_INPUT`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._jit import leaf
from .._validation import as_float_array, check_range
from ..layouts import Field, Layout
from ..plant.geometry import tcp_jacobian, tcp_position

EXTERNAL_INPUT = Layout("closed-loop external input", [
    Field("f", 2, "N", "prescribed TCP force profile (world x, y)", columns=("fx", "fy")),
    Field("r_hand", 2, "m", "hand target position r_h (world x, y)",
          columns=("x_hand", "y_hand")),
    Field("k_hand", 1, "N/m", "hand stiffness K_h (0 when the hand is not engaged)"),
    Field("b_hand", 1, "N s/m", "hand damping B_h (0 when the hand is not engaged)"),
])
XI_F, XI_RH, XI_K, XI_B = EXTERNAL_INPUT.offsets("f", "r_hand", "k_hand", "b_hand")


@leaf
def external_joint_torque(row, q1, q2, w1, w2, P, tau):
    """Write tau = J^T f (2) [N m] for external-input ``row`` at the true state; return f.

    Parameters
    ----------
    row : numpy.ndarray
        One ``EXTERNAL_INPUT`` row.
    q1, q2 : float
        True joint angles [rad].
    w1, w2 : float
        True joint velocities [rad/s].
    P : numpy.ndarray
        Plant row (geometry).
    tau : numpy.ndarray, shape (2,)
        Written: joint torques [N m].
    """
    x, y = tcp_position(q1, q2, P)
    j11, j12, j21, j22 = tcp_jacobian(q1, q2, P)
    vx = j11 * w1 + j12 * w2
    vy = j21 * w1 + j22 * w2
    kh, bh = row[XI_K], row[XI_B]
    fx = row[XI_F] + kh * (row[XI_RH] - x) - bh * vx
    fy = row[XI_F + 1] + kh * (row[XI_RH + 1] - y) - bh * vy
    tau[0] = j11 * fx + j21 * fy
    tau[1] = j12 * fx + j22 * fy
    return fx, fy


@dataclass(frozen=True, eq=False)
class Hand:
    """A spring-damper hand pulling the TCP toward a moving target while engaged.

    Parameters
    ----------
    target : array_like, shape (n, 2)
        Target position r_h per control sample [m] (world frame).
    engaged : array_like of bool, shape (n,)
        Whether the hand holds the TCP at each sample (False: released, no force).
    stiffness : float
        K_h [N/m], > 0 (default 200 N/m: a relaxed arm; with ~10 N pushes the
        TCP lags its target by ~5 cm).
    damping : float
        B_h [N s/m], >= 0 (default 20 N s/m).
    """

    target: np.ndarray
    engaged: np.ndarray
    stiffness: float = 200.0
    damping: float = 20.0

    def __post_init__(self):
        tg = as_float_array("Hand.target", self.target, shape_tail=(2,))
        if tg.ndim != 2:
            raise ValueError(f"Hand.target must have shape (n, 2), got {tg.shape}")
        en = np.asarray(self.engaged)
        if en.dtype != bool or en.shape != (tg.shape[0],):
            raise ValueError(f"Hand.engaged must be a bool array of shape ({tg.shape[0]},), got "
                             f"dtype {en.dtype} shape {en.shape}")
        object.__setattr__(self, "target", tg)
        object.__setattr__(self, "engaged", en)
        object.__setattr__(self, "stiffness", check_range("Hand.stiffness", self.stiffness, 0.0,
                                                          1e6, lo_open=True, unit="N/m"))
        object.__setattr__(self, "damping", check_range("Hand.damping", self.damping, 0.0, 1e5,
                                                        unit="N s/m"))

    def __len__(self) -> int:
        return self.target.shape[0]


def external_rows(n: int, force=None, hand: Hand | None = None) -> np.ndarray:
    """The (n, ``EXTERNAL_INPUT.size``) rows of a case's external input.

    Parameters
    ----------
    n : int
        Number of control samples.
    force : array_like, shape (n, 2), optional
        Force profile [N] (default zero).
    hand : Hand, optional
        Spring-damper hand (default none).
    """
    rows = EXTERNAL_INPUT.empty(n)
    if force is not None:
        rows[:, EXTERNAL_INPUT.slice("f")] = force
    if hand is not None:
        on = hand.engaged.astype(float)
        rows[:, EXTERNAL_INPUT.slice("r_hand")] = hand.target
        rows[:, XI_K] = on * hand.stiffness
        rows[:, XI_B] = on * hand.damping
    return rows


def piecewise_targets(t, waypoints, times) -> np.ndarray:
    """Targets moving linearly between ``waypoints`` (m, 2) [m] at ``times`` (m,) [s].

    Before ``times[0]`` the first waypoint, after ``times[-1]`` the last.

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times [s].
    waypoints : array_like, shape (m, 2)
        Positions [m].
    times : array_like, shape (m,)
        Increasing times at which the waypoints are reached [s].
    """
    t = as_float_array("t", t).reshape(-1)
    w = as_float_array("waypoints", waypoints, shape_tail=(2,))
    tm = as_float_array("times", times).reshape(-1)
    if w.ndim != 2 or tm.size != w.shape[0] or np.any(np.diff(tm) <= 0):
        raise ValueError("piecewise_targets: need m waypoints (m, 2) and m increasing times")
    return np.stack([np.interp(t, tm, w[:, 0]), np.interp(t, tm, w[:, 1])], axis=1)


__all__ = ["EXTERNAL_INPUT", "Hand", "external_rows", "external_joint_torque",
           "piecewise_targets"]
