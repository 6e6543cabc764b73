"""From a closed-loop experiment to impact cases (thesis §6.3.2-6.3.3).

For an impact at t0 the arm model starts from the link angles and velocities
of the experiment at t0, with the joint stiffnesses (2.18) computed from the
pressures at t0 (assumed constant during the impact).  The thesis evaluated
only four instants per experiment (largest TCP speed, largest |qd1|, largest
|qd2|, largest ||qd||) and kept the worst; :func:`evaluate_experiment` can
evaluate those or every sample of the record.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .._validation import (InvalidTypeError, check_choice, check_instance, check_int,
                           check_nonnegative, describe)
from ..plant import geometry as geo
from ..plant.pneumatics import joint_stiffness
from .model import ImpactResults, _simulate_impacts, check_arm, resolve_head, simulate_impacts  # noqa: F401

HEURISTICS = ("max TCP speed", "max |qd1|", "max |qd2|", "max ||qd||")


def _check_result(result):
    from ..experiments.closed_loop import ExperimentResult
    return check_instance("result", result, ExperimentResult)


def impact_states(result, arm) -> pd.DataFrame:
    """Per-sample impact initial conditions of an :class:`ExperimentResult`.

    Parameters
    ----------
    result : ExperimentResult
        The closed-loop record, read by signal name
        (:meth:`ExperimentResult.signal`).
    arm : ArmParameters
        The arm (kinematics and the joint stiffness model 2.18).

    Returns
    -------
    pandas.DataFrame
        Columns: t [s], q1, q2 [rad], qd1, qd2 [rad/s], K1, K2 [N m/rad]
        (2.18 with the simulated pressures), tcp_speed [m/s]; samples after a
        divergence (NaN state) are left out.
    """
    result = _check_result(result)
    arm = check_arm(arm)
    ok = np.all(np.isfinite(result.signals("q1", "q2", "qd1", "qd2", "p1", "p2", "p3", "p4")),
                axis=1)
    q = result.signals("q1", "q2")[ok]
    qd = result.signals("qd1", "qd2")[ok]
    p = result.signals("p1", "p2", "p3", "p4")[ok]
    K = joint_stiffness(q, p, arm)
    v = np.einsum("nij,nj->ni", geo.jacobian(q, arm), qd)
    return pd.DataFrame({"t": result.t[ok], "q1": q[:, 0], "q2": q[:, 1], "qd1": qd[:, 0],
                         "qd2": qd[:, 1], "K1": K[:, 0], "K2": K[:, 1],
                         "tcp_speed": np.linalg.norm(v, axis=1)})


def heuristic_instants(states: pd.DataFrame) -> dict:
    """Row indices of the four impact instants of §6.3.3 (name -> index).

    Parameters
    ----------
    states : pandas.DataFrame
        Impact states as returned by :func:`impact_states` (columns
        ``tcp_speed``, ``qd1``, ``qd2`` used; at least one row, finite).

    Returns
    -------
    dict
        :data:`HEURISTICS` name -> row position in ``states``.
    """
    if not isinstance(states, pd.DataFrame):
        raise InvalidTypeError(f"states must be a pandas DataFrame (impact_states), got "
                               f"{describe(states)}")
    missing = [c for c in ("tcp_speed", "qd1", "qd2") if c not in states.columns]
    if missing:
        raise ValueError(f"states lacks the column(s) {missing} (see impact_states)")
    if len(states) == 0:
        raise ValueError("states has no rows: no impact instant to choose")
    try:
        vals = states[["tcp_speed", "qd1", "qd2"]].to_numpy(dtype=float)
    except (TypeError, ValueError):
        raise InvalidTypeError("states columns tcp_speed, qd1, qd2 must be numeric") from None
    if not np.all(np.isfinite(vals)):
        raise ValueError("states contains NaN or inf in tcp_speed, qd1 or qd2")
    qd = vals[:, 1:]
    return {HEURISTICS[0]: int(np.argmax(states["tcp_speed"].to_numpy())),
            HEURISTICS[1]: int(np.argmax(np.abs(qd[:, 0]))),
            HEURISTICS[2]: int(np.argmax(np.abs(qd[:, 1]))),
            HEURISTICS[3]: int(np.argmax(np.linalg.norm(qd, axis=1)))}


def evaluate_experiment(result, arm, *, instants: str = "heuristic", every: int = 1,
                        head=None, dt: float = 2e-5, duration: float = 0.05,
                        min_speed: float = 0.0, history=False) -> ImpactResults:
    """Simulate head impacts at instants of an experiment.

    Parameters
    ----------
    result : ExperimentResult
        The closed-loop record.
    arm : ArmParameters
        The arm.
    instants : {"heuristic", "all"}, keyword-only
        The four instants of §6.3.3, or every ``every``-th sample.
    every : int
        Sample stride for ``instants="all"`` (1 = every control period, 1 ms).
    head : HeadContactModel or str, optional
        Head model or its name (default ``"thesis-frontal"``).
    dt : float
        Impact integration step [s] (see :func:`simulate_impacts`).
    duration : float
        Simulated time of each impact [s].
    min_speed : float
        With ``"all"``, instants whose TCP speed is below this [m/s] (>= 0)
        are left out, e.g. 1e-4 to skip the arm at rest.
    history : bool or sequence of int
        Passed to :func:`simulate_impacts` (indices into the evaluated rows).

    Returns
    -------
    ImpactResults
        Summary with an extra column ``t0`` (impact instant) and, for the
        heuristic, ``instant`` (its name).
    """
    result = _check_result(result)
    arm = check_arm(arm)
    check_choice("instants", instants, ("heuristic", "all"))
    every = check_int("every", every, 1, 10 ** 6)
    head = resolve_head(head)
    min_speed = check_nonnegative("min_speed", min_speed, unit="m/s")
    st = impact_states(result, arm)
    if len(st) == 0:
        raise ValueError(f"result {result.name!r} has no finite sample to evaluate")
    if instants == "heuristic":
        h = heuristic_instants(st)
        idx = np.array(list(h.values()))
        names = list(h.keys())
    else:
        idx = np.arange(0, len(st), every)
        idx = idx[st["tcp_speed"].to_numpy()[idx] >= min_speed] if min_speed > 0 else idx
        names = None
    sub = st.iloc[idx]
    res = _simulate_impacts(arm, sub[["q1", "q2"]].to_numpy(), sub[["qd1", "qd2"]].to_numpy(),
                            sub[["K1", "K2"]].to_numpy(), head=head, direction=None,
                            head_velocity=None, fixed_arm=False, dt=dt, duration=duration,
                            history=history, integrator="fixed", warn_area=False,
                            stacklevel=4)
    res.summary.insert(0, "t0", sub["t"].to_numpy())
    if names is not None:
        res.summary.insert(0, "instant", names)
    return res


@dataclass
class WorstInstants:
    """Result of :func:`worst_instant`: the worst impacts of an experiment, found exactly.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per candidate instant (the rows :func:`evaluate_experiment`
        with ``instants="all"`` would simulate): ``t0`` [s], ``tcp_speed``
        [m/s], ``F_bound`` [N] and ``HIC36_bound`` (rigorous upper bounds,
        :func:`~ppamsafety.impact.bounds.impact_bounds`), ``simulated``
        (bool) and, for simulated rows only, ``F_max`` [N], ``HIC36``,
        ``HIC15`` (NaN where the instant was pruned: its bounds are below the
        worst simulated values, so it cannot be the worst).
    worst_F, worst_HIC : pandas.Series
        Summary row (as :func:`simulate_impacts`, plus ``t0``) of the instant
        with the largest F_max / HIC36 (the earliest on ties), identical to
        that instant's row in the full scan.
    n_simulated, n_pruned : int
        Instants simulated and pruned.
    """

    table: pd.DataFrame
    worst_F: pd.Series
    worst_HIC: pd.Series
    n_simulated: int
    n_pruned: int


def worst_instant(result, arm, *, every: int = 1, head=None, dt: float = 2e-5,
                  duration: float = 0.05, min_speed: float = 0.0,
                  chunk: int = 32) -> WorstInstants:
    """Worst F_max and HIC36 over every instant of an experiment, with pruning.

    Same answer as ``evaluate_experiment(result, arm, instants="all", ...)``
    followed by ``idxmax`` (same instants, same values to the last digit: the
    worst instants are simulated by the same engine with the same inputs),
    but only the instants that could be the worst are simulated.  Method:
    a rigorous upper bound on F_max and on HIC36 of every instant
    (:func:`~ppamsafety.impact.bounds.impact_bounds`); instants are simulated
    in batches in descending order of the F bound until the next bound is
    below the largest simulated F_max, then likewise for HIC36.  An instant
    is skipped only if its bound is strictly below a simulated value, so the
    maximum (and, on exact ties, the earliest maximising instant) is kept.

    Parameters
    ----------
    result : ExperimentResult
        The closed-loop record.
    arm : ArmParameters
    every : int, keyword-only
        Sample stride (1 = every control period).
    head : HeadContactModel or str, optional
        Head model (default ``"thesis-frontal"``).
    dt, duration : float
        Impact integration step and length [s].
    min_speed : float
        Instants whose TCP speed is below this [m/s] are not candidates.
    chunk : int
        Impacts simulated per compiled batch call (>= 1).

    Returns
    -------
    WorstInstants
    """
    from .bounds import impact_bounds

    every = check_int("every", every, 1, 10 ** 6)
    chunk = check_int("chunk", chunk, 1, 10 ** 6)
    hm = resolve_head(head)
    st = impact_states(result, arm)
    idx = np.arange(0, len(st), every)
    idx = idx[st["tcp_speed"].to_numpy()[idx] >= min_speed] if min_speed > 0 else idx
    sub = st.iloc[idx].reset_index(drop=True)
    q, qd, K = (sub[["q1", "q2"]].to_numpy(), sub[["qd1", "qd2"]].to_numpy(),
                sub[["K1", "K2"]].to_numpy())
    n = len(sub)
    fb, hb = impact_bounds(arm, q, qd, head=hm, duration=duration)
    frames = []
    simulated = np.zeros(n, bool)
    best = {"F_max": -np.inf, "HIC36": -np.inf}
    for metric, bound in (("F_max", fb), ("HIC36", hb)):
        order = np.argsort(-bound, kind="stable")
        pos = 0
        while pos < n:
            take = []
            while pos < n and len(take) < chunk and not bound[order[pos]] < best[metric]:
                if not simulated[order[pos]]:
                    take.append(order[pos])
                pos += 1
            if not take:
                break
            take = np.array(take)
            res = _simulate_impacts(arm, q[take], qd[take], K[take], head=hm, direction=None,
                                    head_velocity=None, fixed_arm=False, dt=dt,
                                    duration=duration, history=False, integrator="fixed",
                                    warn_area=False, stacklevel=4)
            s = res.summary
            frames.append(s.set_axis(take, axis=0))     # keep each column's dtype
            simulated[take] = True
            for m in best:
                best[m] = max(best[m], float(s[m].max()))
    full = pd.concat(frames).sort_index()
    done = full.index.to_numpy()
    full.insert(0, "t0", sub["t"].to_numpy()[done])
    table = pd.DataFrame({"t0": sub["t"].to_numpy(), "tcp_speed": sub["tcp_speed"].to_numpy(),
                          "F_bound": fb, "HIC36_bound": hb, "simulated": simulated})
    for c in ("F_max", "HIC36", "HIC15"):
        table[c] = np.nan
        table.loc[done, c] = full[c].to_numpy()
    return WorstInstants(table=table, worst_F=full.loc[full["F_max"].idxmax()],
                         worst_HIC=full.loc[full["HIC36"].idxmax()],
                         n_simulated=int(simulated.sum()), n_pruned=int(n - simulated.sum()))
