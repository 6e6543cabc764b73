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

from ..results import Result
from .._validation import (InvalidTypeError, check_bool, check_choice, check_instance,
                           check_int,
                           check_nonnegative, describe)
from ..experiments.closed_loop import ExperimentResult
from ..plant import geometry as geo
from ..plots.impact import plot_worst_instants
from ..plant.pneumatics import joint_stiffness
from . import engine as eng
from .bounds import impact_bounds
from .model import ImpactResult, _simulate_impacts, check_arm, resolve_head, simulate_impacts  # noqa: F401
from .model import _prepare_impacts, _run_cases, _summary_frame

HEURISTICS = ("max TCP speed", "max |qd1|", "max |qd2|", "max ||qd||")


def _check_result(result):
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
    st, p = _states(result, arm)
    K = joint_stiffness(st[["q1", "q2"]].to_numpy(), p, arm)
    st.insert(5, "K1", K[:, 0])
    st.insert(6, "K2", K[:, 1])
    return st


def _states(result, arm) -> tuple:
    """:func:`impact_states` without the stiffnesses, and the pressures (n, 4) [Pa] of its
    rows: the stiffness of the few rows an impact starts from is computed alone (the same
    numbers, row by row)."""
    ok = np.all(np.isfinite(result.signals("q1", "q2", "qd1", "qd2", "p1", "p2", "p3", "p4")),
                axis=1)
    q = result.signals("q1", "q2")[ok]
    qd = result.signals("qd1", "qd2")[ok]
    p = result.signals("p1", "p2", "p3", "p4")[ok]
    v = np.einsum("nij,nj->ni", geo.jacobian(q, arm), qd)
    return pd.DataFrame({"t": result.t[ok], "q1": q[:, 0], "q2": q[:, 1], "qd1": qd[:, 0],
                         "qd2": qd[:, 1], "tcp_speed": np.linalg.norm(v, axis=1)}), p


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
                        min_speed: float = 0.0, history=False) -> ImpactResult:
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
    ImpactResult
        Summary with an extra column ``t0`` (impact instant) and, for the
        heuristic, ``instant`` (its name).
    """
    result = _check_result(result)
    arm = check_arm(arm)
    check_choice("instants", instants, ("heuristic", "all"))
    every = check_int("every", every, 1, 10 ** 6)
    head = resolve_head(head)
    min_speed = check_nonnegative("min_speed", min_speed, unit="m/s")
    st, p = _states(result, arm)
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
    q0 = sub[["q1", "q2"]].to_numpy()
    res = _simulate_impacts(arm, q0, sub[["qd1", "qd2"]].to_numpy(),
                            joint_stiffness(q0, p[idx], arm), head=head, direction=None,
                            head_velocity=None, fixed_arm=False, dt=dt, duration=duration,
                            history=history, integrator="fixed", warn_area=False,
                            stacklevel=4)
    res.summary.insert(0, "t0", sub["t"].to_numpy())
    if names is not None:
        res.summary.insert(0, "instant", names)
    return res


#: Relative margin on the screening values of :func:`worst_instant`: an instant whose
#: dense-output F_max or HIC36 (engine.impact_batch_dense) times (1 + SCREEN_MARGIN) reaches
#: the best exact value is simulated exactly.  The dense integrator stays within 2e-4 of the
#: fixed-step engine (tests/test_impact_dense.py; at most 8e-5 measured on the Table 6.1
#: scans, always below it there), so the margin is 50x the largest deviation tolerated by
#: the tests; tests/test_bounds.py checks screen x (1 + margin) >= exact on random,
#: adversarial and scan states.
SCREEN_MARGIN = 1e-2


@dataclass
class WorstInstants(Result):
    """Result of :func:`worst_instant`: the worst impacts of an experiment, found exactly.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per candidate instant (the rows :func:`evaluate_experiment`
        with ``instants="all"`` would simulate): ``t0`` [s], ``tcp_speed``
        [m/s], ``F_bound`` [N] and ``HIC36_bound`` (rigorous upper bounds,
        :func:`~ppamsafety.impact.bounds.impact_bounds`), ``screened`` (bool)
        with ``F_screen`` [N] and ``HIC36_screen`` (the dense-output
        integrator's values, NaN where not screened), ``simulated`` (bool)
        and, for simulated rows only, ``F_max`` [N], ``HIC36``, ``HIC15``
        (NaN where the instant was pruned: its bounds, or its screening
        values times 1 + :data:`SCREEN_MARGIN`, are below the worst simulated
        values, so it cannot be the worst).
    worst_F, worst_HIC : pandas.Series
        Summary row (as :func:`simulate_impacts`, plus ``t0``) of the instant
        with the largest F_max / HIC36 (the earliest on ties), identical to
        that instant's row in the full scan.
    n_simulated, n_pruned : int
        Instants simulated (fixed-step engine) and pruned.
    n_screened : int
        Instants evaluated with the dense-output integrator.
    """

    table: pd.DataFrame
    worst_F: pd.Series
    worst_HIC: pd.Series
    n_simulated: int
    n_pruned: int
    n_screened: int = 0

    def to_pandas(self) -> pd.DataFrame:
        """The candidate instants (:attr:`table`): bounds, screening and exact values."""
        return self.table

    def column_units(self) -> dict:
        """The units of :attr:`table` (the attributes above)."""
        return {"t0": "s", "tcp_speed": "m/s", "F_bound": "N", "HIC36_bound": "-",
                "F_screen": "N", "HIC36_screen": "-", "F_max": "N", "HIC36": "-", "HIC15": "-"}

    def plot(self, **kwargs):
        """F_max and HIC36 over the impact instant: bounds, screening values and the
        simulated instants, the worst marked; a matplotlib Figure.

        Parameters
        ----------
        **kwargs
            Passed to :func:`ppamsafety.plots.impact.plot_worst_instants` (``title``).
        """
        return plot_worst_instants(self.table, worst_F=float(self.worst_F["t0"]),
                                   worst_HIC=float(self.worst_HIC["t0"]), **kwargs)


def worst_instant(result, arm, *, every: int = 1, head=None, dt: float = 2e-5,
                  duration: float = 0.05, min_speed: float = 0.0,
                  chunk: int = 256, screen: bool = True) -> WorstInstants:
    """Worst F_max and HIC36 over every instant of an experiment, with pruning.

    Same answer as ``evaluate_experiment(result, arm, instants="all", ...)``
    followed by ``idxmax`` (same instants, same values to the last digit: the
    worst instants are simulated by the same engine with the same inputs),
    but only the instants that could be the worst are simulated.  Method:

    1. a rigorous upper bound on F_max and on HIC36 of every instant
       (:func:`~ppamsafety.impact.bounds.impact_bounds`);
    2. with ``screen``, the instants whose bound reaches the best exact value
       found so far are evaluated in batches of ``chunk`` (in descending
       order of their bounds) with the dense-output integrator
       (:func:`~ppamsafety.impact.engine.impact_batch_dense`, about 3x
       cheaper); its values times 1 + :data:`SCREEN_MARGIN` replace the
       bounds;
    3. an instant whose bound (or screening value with margin) reaches the
       best exact value is simulated exactly (fixed-step engine, as the full
       scan); the loop ends when no instant can reach the best values.

    An instant is skipped only if its bound is strictly below a simulated
    value, so the maximum (and, on exact ties, the earliest maximising
    instant) is kept.

    Parameters
    ----------
    result : ExperimentResult
        The closed-loop record.
    arm : ArmParameters
        The arm (kinematics, link inertias, joint stiffness model).
    every : int, keyword-only
        Sample stride (1 = every control period).
    head : HeadContactModel or str, optional
        Head model (default ``"thesis-frontal"``).
    dt, duration : float
        Impact integration step and length [s].
    min_speed : float
        Instants whose TCP speed is below this [m/s] are not candidates.
    chunk : int
        Impacts screened (or, without ``screen``, simulated) per compiled
        batch call (>= 1).
    screen : bool
        Screen with the dense-output integrator before simulating exactly
        (False: every instant whose bound reaches the best is simulated).

    Returns
    -------
    WorstInstants
    """
    every = check_int("every", every, 1, 10 ** 6)
    chunk = check_int("chunk", chunk, 1, 10 ** 6)
    screen = check_bool("screen", screen)
    hm = resolve_head(head)
    st = impact_states(result, arm)
    idx = np.arange(0, len(st), every)
    idx = idx[st["tcp_speed"].to_numpy()[idx] >= min_speed] if min_speed > 0 else idx
    sub = st.iloc[idx].reset_index(drop=True)
    q, qd, K = (sub[["q1", "q2"]].to_numpy(), sub[["qd1", "qd2"]].to_numpy(),
                sub[["K1", "K2"]].to_numpy())
    n = len(sub)
    fb, hb = impact_bounds(arm, q, qd, head=hm, duration=duration)
    # the same validation and case rows as evaluate_experiment's single call
    prep = _prepare_impacts(arm, q, qd, K, head=hm, direction=None, head_velocity=None,
                            fixed_arm=False, dt=dt, duration=duration, history=False,
                            warn_area=False, stacklevel=3)
    SUM = np.zeros((n, eng.NSUM))          # cases at rest keep zero rows, as in the full scan
    active = np.zeros(n, bool)
    active[prep.sel] = True
    simulated = ~active                    # at rest: known exactly without running
    screened = np.zeros(n, bool)
    up = {"F_max": fb.astype(float), "HIC36": hb.astype(float)}
    col = {"F_max": eng.R_FMAX, "HIC36": eng.R_HIC36}
    scr = {m: np.full(n, np.nan) for m in col}
    best = {m: (0.0 if simulated.any() else -np.inf) for m in col}
    orders = {m: np.argsort(-up[m], kind="stable") for m in col}

    def exact(take):
        SUM[take] = _run_cases(prep, take, "fixed")
        simulated[take] = True
        for m, c in col.items():
            up[m][take] = SUM[take, c]
            best[m] = max(best[m], float(SUM[take, c].max()))

    def could_win():
        return ~simulated & ((up["F_max"] >= best["F_max"]) | (up["HIC36"] >= best["HIC36"]))

    while True:
        open_ = could_win()
        if not open_.any():
            break
        if not screen:
            take = _next_batch(orders, up, best, open_, chunk)
            exact(take)
            continue
        ready = open_ & screened
        if ready.any():
            cand = np.nonzero(ready)[0]
            if not all(np.isfinite(v) for v in best.values()):
                # first exact values: the best screened instant of each metric
                cand = np.unique([cand[np.argmax(up[m][cand])] for m in col])
            exact(cand)
            continue
        take = _next_batch(orders, up, best, open_, chunk)
        S = _run_cases(prep, take, "dense")
        screened[take] = True
        for m, c in col.items():
            scr[m][take] = S[:, c]
            up[m][take] = S[:, c] * (1.0 + SCREEN_MARGIN)
    done = np.nonzero(simulated)[0]
    full = _summary_frame(prep, done, SUM[done], stacklevel=3).set_axis(done, axis=0)
    full.insert(0, "t0", sub["t"].to_numpy()[done])
    table = pd.DataFrame({"t0": sub["t"].to_numpy(), "tcp_speed": sub["tcp_speed"].to_numpy(),
                          "F_bound": fb, "HIC36_bound": hb, "screened": screened,
                          "F_screen": scr["F_max"], "HIC36_screen": scr["HIC36"],
                          "simulated": simulated})
    for c in ("F_max", "HIC36", "HIC15"):
        table[c] = np.nan
        table.loc[done, c] = full[c].to_numpy()
    return WorstInstants(table=table, worst_F=full.loc[full["F_max"].idxmax()],
                         worst_HIC=full.loc[full["HIC36"].idxmax()],
                         n_simulated=int(simulated.sum()), n_pruned=int(n - simulated.sum()),
                         n_screened=int(screened.sum()))


def _next_batch(orders, up, best, open_, chunk):
    """Up to ``chunk`` open instants, alternately the next by descending F and HIC bound."""
    take = []
    seen = set()
    its = {m: iter(o[open_[o] & (up[m][o] >= best[m])]) for m, o in orders.items()}
    while len(take) < chunk and its:
        for m in list(its):
            for i in its[m]:
                if i not in seen:
                    seen.add(i)
                    take.append(i)
                    break
            else:
                del its[m]
    return np.array(sorted(take), dtype=np.int64)
