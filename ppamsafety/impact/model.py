"""Public interface of the impact simulation: cases in, results out.

:func:`simulate_impacts` runs a batch of impacts of the flexible-joint arm
with a head model in one compiled call (:mod:`ppamsafety.impact.engine`) and
returns an :class:`ImpactResults` with a summary DataFrame (HIC36, HIC15 and
their windows, F_max and its time, penetration, energies) and optional time
histories.  :func:`effective_mass` gives the arm's apparent mass at the tool
along a direction, the quantity that decides the impact force (§6.3.4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .._validation import as_float_array, check_range
from ..params.head import HeadContactModel, head_model
from ..plant import dynamics as dyn
from ..plant import geometry as geo
from ..plant import layout as lay
from . import engine as eng


def _unit(v, name):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(n == 0):
        raise ValueError(f"{name} contains a zero vector")
    return v / n


def effective_mass(q, direction, arm) -> np.ndarray:
    """Apparent mass of the arm's links at the tool along ``direction`` [kg].

    m_eff = 1 / (u^T J H^-1 J^T u): the mass a point force along the unit
    vector u at the TCP feels when the joint springs have no time to act
    (impacts shorter than the arm's vibration periods).

    Parameters
    ----------
    q : array_like, shape (..., 2)
        Joint angles [rad].
    direction : array_like, shape (..., 2)
        Impact direction (normalised internally).
    arm : ArmParameters
    """
    q = as_float_array("q", q, shape_tail=(2,))
    u = _unit(as_float_array("direction", direction, shape_tail=(2,)), "direction")
    J = geo.jacobian(q, arm)
    Hinv = np.linalg.inv(dyn.inertia_matrix(q, arm))
    M = J @ Hinv @ np.swapaxes(J, -1, -2)
    return 1.0 / np.einsum("...i,...ij,...j->...", u, M, u)


@dataclass
class ImpactResults:
    """Results of a batch of impacts.

    Attributes
    ----------
    summary : pandas.DataFrame
        One row per case: inputs (q1, q2, qd1, qd2 [rad, rad/s], K1, K2
        [N m/rad], ux, uy) and :data:`~ppamsafety.impact.engine.SUMMARY_COLUMNS`
        (F_max [N], t_Fmax [s], HIC36, HIC15 and windows [s], delta_max [m],
        a_max_g [g], energies [J], contact_time [s], v_tcp0 [m/s],
        E_balance_error [-]).
    histories : dict
        Case index -> DataFrame with :data:`~ppamsafety.impact.engine.HIST_COLUMNS`.
    head : HeadContactModel
    dt, duration : float
        Integration step and simulated time [s].
    """

    summary: pd.DataFrame
    histories: dict = field(default_factory=dict)
    head: HeadContactModel | None = None
    dt: float = 2e-5
    duration: float = 0.05

    def to_pandas(self) -> pd.DataFrame:
        """The data as a pandas DataFrame (SI units)."""
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

        Raises
        ------
        KeyError
            If no history was recorded for ``index``.
        """
        try:
            return self.histories[index]
        except (KeyError, TypeError):
            raise KeyError(f"index = {index!r}: no history recorded for this case; recorded: "
                           f"{sorted(self.histories)}") from None

    def signal(self, name: str, index: int) -> np.ndarray:
        """One history signal by name, e.g. ``signal("F", 0)`` (SI units, see
        :data:`~ppamsafety.impact.engine.HIST`).

        Parameters
        ----------
        name : str
            A column of :data:`~ppamsafety.impact.engine.HIST_COLUMNS`.
        index : int
            Case index whose history was recorded.
        """
        if name not in eng.HIST_COLUMNS:
            raise KeyError(f"name = {name!r} is not a history signal; signals: "
                           f"{', '.join(eng.HIST_COLUMNS)}")
        return self.history(index)[name].to_numpy()

    def signals(self, *names: str, index: int) -> np.ndarray:
        """Several history signals by name as columns of an array, shape (nsteps + 1, k)."""
        return np.stack([self.signal(n, index) for n in names], axis=1)

    def worst(self, metric: str = "HIC36") -> pd.Series:
        """Row of the case with the largest ``metric``."""
        return self.summary.loc[self.summary[metric].idxmax()]

    def plot(self, index=None, **kwargs):
        """Plot with :mod:`ppamsafety.report`; returns a matplotlib Figure.

        Parameters
        ----------
        index : int, optional
            Case whose time history is plotted (default: the first with a
            history).
        **kwargs
            Passed to :func:`ppamsafety.report.impact_figures.plot_impact_history`.
        """
        from ..report.impact_figures import plot_impact_history
        i = index if index is not None else next(iter(self.histories))
        return plot_impact_history(self.histories[i], head=self.head, **kwargs)


def simulate_impacts(arm, q, qd, stiffness, *, head: HeadContactModel | str | None = None,
                     direction=None, head_velocity=None, fixed_arm: bool = False,
                     dt: float = 2e-5, duration: float = 0.05, history=False,
                     integrator: str = "fixed") -> ImpactResults:
    """Simulate impacts of the flexible-joint arm with a free head (thesis §6.3.2).

    Parameters
    ----------
    arm : ArmParameters
        Link inertias (plant) and kinematics.
    q, qd : array_like, shape (N, 2) or (2,)
        Link angles [rad] and angular velocities [rad/s] at the impact instant.
    stiffness : array_like, shape (N, 2) or (2,)
        Joint stiffnesses K1, K2 [N m/rad] (constant during the impact).
    head : HeadContactModel or str, keyword-only
        Head model or its name (default ``"thesis-frontal"``).
    direction : array_like, shape (N, 2) or (2,), optional
        Unit vector from the tool point to the head centre; default the TCP
        velocity direction (the worst case of fig. 6.2).
    head_velocity : array_like, optional
        Initial head velocity [m/s] (default at rest).
    fixed_arm : bool
        Treat the arm as rigid and fixed (the head moves into the tool; stored
        in the case rows as :class:`~ppamsafety.impact.engine.ArmMode`).
    dt, duration : float
        Fixed RK4 step and simulated time [s] (default 20 us, 50 ms; halving
        the step changes F_max and HIC by less than 2e-4 relative, see tests).
    history : bool or sequence of int
        Record time histories for all cases (True) or for the given indices.
    integrator : {"fixed", "dense"}
        ``"fixed"``: RK4 with step ``dt`` in contact (the reference engine).
        ``"dense"``: RK4 with step 8 ``dt`` in contact and the force on the
        ``dt`` grid from cubic Hermite interpolation
        (:func:`~ppamsafety.impact.engine.impact_batch_dense`), about 3.5x
        faster; F_max, HIC36 and HIC15 within 2e-4 relative of the fixed
        engine and of solve_ivp at rtol 1e-10 (tests/test_impact_dense.py;
        measured 6e-5 on 1000 random impacts).  Cases with a recorded history
        always use ``"fixed"``.

    Returns
    -------
    ImpactResults
        Cases whose tool and head are both at rest are skipped (zero force).
    """
    hm = head_model() if head is None else (head_model(head) if isinstance(head, str) else head)
    if not isinstance(hm, HeadContactModel):
        raise ValueError("head must be a HeadContactModel or a model name")
    if not isinstance(fixed_arm, (bool, np.bool_)):
        raise TypeError(f"fixed_arm = {fixed_arm!r} must be True or False")
    check_range("dt", dt, 1e-8, 1e-3, unit="s")
    check_range("duration", duration, 1e-4, 10.0, unit="s")
    if integrator not in ("fixed", "dense"):
        raise ValueError(f"integrator = {integrator!r} must be 'fixed' or 'dense'")
    q = np.atleast_2d(as_float_array("q", q, shape_tail=(2,)))
    n = q.shape[0]
    qd = np.broadcast_to(as_float_array("qd", qd, shape_tail=(2,)), (n, 2))
    K = np.broadcast_to(as_float_array("stiffness", stiffness, shape_tail=(2,)), (n, 2))
    if np.any(K < 0):
        raise ValueError("stiffness must be non-negative [N m/rad]")
    vh = np.zeros((n, 2)) if head_velocity is None else np.broadcast_to(
        as_float_array("head_velocity", head_velocity, shape_tail=(2,)), (n, 2))
    vt = np.einsum("nij,nj->ni", geo.jacobian(q, arm), qd)
    if direction is None:
        speed = np.linalg.norm(vt, axis=1)
        rel = vt - vh
        nrm = np.linalg.norm(rel, axis=1)
        u = np.where(nrm[:, None] > 0, rel / np.where(nrm > 0, nrm, 1.0)[:, None], [1.0, 0.0])
    else:
        u = np.broadcast_to(_unit(as_float_array("direction", direction, shape_tail=(2,)),
                                  "direction"), (n, 2))
        speed = np.linalg.norm(vt, axis=1)
    active = (np.linalg.norm(vt - vh, axis=1) > 0) if not fixed_arm else \
        (np.linalg.norm(vh, axis=1) > 0)
    mode = eng.ArmMode.FIXED if fixed_arm else eng.ArmMode.FLEXIBLE
    cases = eng.pack_cases(n, q=q, qd=0.0 if fixed_arm else qd, K=K, u=u, v_head=vh,
                           arm_mode=int(mode))
    nsteps = int(math.ceil(duration / dt - 1e-9))
    if history is True:
        hist_idx = np.arange(n)
    elif history is False or history is None:
        hist_idx = np.array([], dtype=np.int64)
    else:
        hist_idx = np.asarray(history, dtype=np.int64)
        if np.any((hist_idx < 0) | (hist_idx >= n)):
            raise ValueError(f"history indices must be in [0, {n - 1}]")
    hist_of = np.full(n, -1, dtype=np.int64)
    hist_of[hist_idx] = np.arange(hist_idx.size)
    hp = eng.pack_head(hm)
    SUM = np.zeros((n, eng.NSUM))
    HIST = np.zeros((hist_idx.size, nsteps + 1, eng.NHIST))
    sel = np.nonzero(active)[0]
    w36 = int(math.floor(0.036 / dt * (1 + 1e-9)))
    w15 = int(math.floor(0.015 / dt * (1 + 1e-9)))
    out = np.zeros((sel.size, eng.NSUM))
    P = np.array(lay.pack(arm))
    if integrator == "dense":
        dense = hist_of[sel] < 0
        od = np.zeros((int(dense.sum()), eng.NSUM))
        eng.impact_batch_dense(np.ascontiguousarray(cases[sel][dense]), P, hp, float(dt), nsteps,
                               w36, w15, od)
        out[dense] = od
        sel_f = sel[~dense]
        of = np.zeros((sel_f.size, eng.NSUM))
        eng.impact_batch(np.ascontiguousarray(cases[sel_f]), P, hp, float(dt), nsteps, w36, w15,
                         of, HIST, np.ascontiguousarray(hist_of[sel_f]))
        out[~dense] = of
    else:
        eng.impact_batch(np.ascontiguousarray(cases[sel]), P, hp, float(dt), nsteps, w36, w15,
                         out, HIST, np.ascontiguousarray(hist_of[sel]))
    SUM[sel] = out
    df = pd.DataFrame({"q1": q[:, 0], "q2": q[:, 1], "qd1": qd[:, 0], "qd2": qd[:, 1],
                       "K1": K[:, 0], "K2": K[:, 1], "ux": u[:, 0], "uy": u[:, 1],
                       "tcp_speed": speed})
    df = pd.concat([df, eng.SUMMARY.frame(SUM)], axis=1)
    hists = {int(i): eng.HIST.frame(HIST[j]) for j, i in enumerate(hist_idx)}
    return ImpactResults(df, hists, hm, float(dt), float(duration))

