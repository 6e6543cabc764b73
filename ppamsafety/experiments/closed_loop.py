"""Closed-loop simulation: plant + sensors + controller at 1 kHz.

Each control period: read the sensors at t_k, run the controller, convert
Delta p to valve set values (Delta-p approach, clip to [0, p_max], invert the
static valve model with the controller's belief), then integrate the plant
over the period with the set values held (``substeps`` RK4 steps), tracking
encoder edges inside each step for the timing board.

The whole loop is one compiled kernel; :func:`run_batch` runs many variants
(parameters, controllers, references, sensor settings) in one call without
per-step Python overhead.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..results import Result, layout_units
from .._jit import nogil_kernel, run_threaded
from .._validation import UnknownNameError, check_int, check_range, check_size, did_you_mean
from ..control import CONTROLLER_CLASSES
from ..control.dispatch import NINT, NSCRATCH, NSTATE, controller_step
from ..control.estimation import (ESTIMATOR_INTERNALS, ESTIMATOR_PARAMS, ESTIMATOR_SCRATCH,
                                  ESTIMATOR_STATE, estimator_step)
from ..control.sensors import (N_Q, N_QD, NSENSOR, SENSOR_NOISE, SensorConfig, pressure_read,
                               sensor_init, sensor_read, sensor_reset, sensor_track_joints)
from ..layouts import Field, Layout
from ..plant import layout as lay
from ..plant import packing
from ..plant.geometry import tcp_jacobian, tcp_position
from ..plant.model import (NWORK, NX, X_P, X_Q, X_QD, effect_state_length, effects_init, rk4_step,
                           valve_delay, check_valve_step, rest_state)
from ..plant.pneumatics import delta_p_to_set_values
from ..plots.control import plot_experiment
from .case import ExperimentCase, as_cases
from .interaction import EXTERNAL_INPUT, external_joint_torque, external_rows
from .trajectories import REF_COLUMNS, REFERENCE_ROW, Reference


#: One row of the closed-loop log, written by ``_run_batch`` once per control period.
LOG = Layout("closed-loop log", [
    Field("t", 1, "s", "sample time k dt"),
    Field("q", 2, "rad", "true joint angles"),
    Field("qd", 2, "rad/s", "true joint velocities"),
    Field("p", 4, "Pa", "true gauge pressures of the four muscle groups"),
    Field("q_meas", 2, "rad", "measured angles (encoder, noise)", columns=("q1_meas", "q2_meas")),
    Field("qd_meas", 2, "rad/s", "measured velocities (timing board, noise)",
          columns=("qd1_meas", "qd2_meas")),
    Field("u", 4, "Pa", "valve set values (Delta-p approach (3.7), inverted (3.12))"),
    Field("dp", 2, "Pa", "controller output Delta p per joint"),
    Field("x", 1, "m", "true TCP x"),
    Field("y", 1, "m", "true TCP y"),
    Field("xd", 1, "m/s", "true TCP x velocity"),
    Field("yd", 1, "m/s", "true TCP y velocity"),
    Field("internals", NINT, "-", "controller internals (named per kind: INTERNAL_NAMES)",
          columns=tuple(f"int{i}" for i in range(NINT))),
])
(L_T, L_Q, L_QD, L_P, L_QM, L_QDM, L_U, L_DP, L_X, L_Y, L_XD, L_YD, L_INT) = LOG.offsets(
    "t", "q", "qd", "p", "q_meas", "qd_meas", "u", "dp", "x", "y", "xd", "yd", "internals")
LOG_COLUMNS = LOG.columns()
NLOG = LOG.size
#: Names of the internal log columns per controller kind (from each kind's INTERNALS layout).
# placeholder names of internal columns a kind does not use (dropped by ExperimentResult); not
# ``startswith("int")``, which also dropped the PID's "integral1", "integral2"
_UNNAMED = frozenset(LOG.field("internals").column_names())
INTERNAL_NAMES = {kind: cls.INTERNALS.columns() for kind, cls in CONTROLLER_CLASSES.items()
                  if cls.INTERNALS.size}

#: The interaction log, one row per control period beside :data:`LOG` (which keeps
#: its nominal width): the applied external TCP force and the force estimators' internals.
#: Only cases with an external input or an estimator carry it (``ExperimentResult.interaction``).
INTERACTION_LOG = Layout("closed-loop interaction log", [
    Field("f_ext", 2, "N", "applied external TCP force at the sample (world x, y)",
          columns=("Fx_ext", "Fy_ext")),
    Field("estimator", ESTIMATOR_INTERNALS.size, "-",
          "force-estimator internals (ESTIMATOR_INTERNALS)",
          columns=tuple(ESTIMATOR_INTERNALS.columns())),
])
IL_F, IL_EST = INTERACTION_LOG.offsets("f_ext", "estimator")
NEST = ESTIMATOR_INTERNALS.size
_NES, _NESCR = ESTIMATOR_STATE.size, ESTIMATOR_SCRATCH.size
NILOG = INTERACTION_LOG.size
_EXT_NAMES = tuple(INTERACTION_LOG.field("f_ext").column_names())
_EST_NAMES = tuple(ESTIMATOR_INTERNALS.columns())

#: Joint speed at which the closed loop counts as diverged [rad/s]: ``_run_batch`` stops a run
#: when |qd1| or |qd2| reaches it or an angle becomes
#: non-finite.  The real arm's joints never exceed a few rad/s (Table 6.1 peaks < 5 rad/s), so
#: 1000 rad/s is far beyond anything physical but still well inside float range.
DIVERGENCE_VELOCITY = 1.0e3

#: Columns of the runner's per-case table of declared controller sizes (``_controller_rows``).
Z_PARAMS, Z_STATE, Z_INTERNALS, Z_SCRATCH = 0, 1, 2, 3


@nogil_kernel
def _run_batch(first, last, X0, REFS, ref_idx, PP, PM, KIND, CP, CSIZE, SCFG, NOISE, noise_idx,
               dt, substeps, LOG, EXT, ext_idx, EP, PE, est_on, ILOG, diverged):
    """Closed loop of the cases first <= b < last (sets diverged[b]); CSIZE[b] = declared
    (params, state, internals, scratch).  Releases the GIL: :func:`run_batch` runs parts
    of a batch side by side in threads (every case writes only its own rows).

    Interaction: EXT[ext_idx[b]] holds case b's external-input rows
    (``EXTERNAL_INPUT``; ext_idx < 0: none, the plant gets the zero torque as
    before); est_on[b] runs the force estimator with parameters EP[b] and
    model row PE[b]; ILOG (``INTERACTION_LOG``) receives both.
    """
    n = LOG.shape[1]
    h = dt / substeps
    x = np.empty(NX)
    work = np.empty(NWORK)
    tau0 = np.zeros(2)
    S_buf = np.empty(NSTATE)
    st = np.empty(NSENSOR)
    qm = np.empty(2)
    qdm = np.empty(2)
    pmeas = np.empty(4)
    dp = np.empty(2)
    u = np.empty(4)
    internals = np.empty(NINT)
    scratch_buf = np.empty(NSCRATCH)
    tau_e = np.zeros(2)
    fest = np.zeros(NEST)
    ES = np.empty(_NES)
    escr = np.empty(_NESCR)
    for b in range(first, last):
        diverged[b] = False
        x[:] = X0[b]
        S_buf[:] = 0.0
        sensor_reset(st)
        internals[:] = 0.0
        Pp, Pm, cfg, R = PP[b], PM[b], SCFG[b], REFS[ref_idx[b]]
        z = np.zeros(effect_state_length(Pp))     # plant effect state (empty: effects off)
        effects_init(z, Pp)
        # every row exactly as wide as the kind declares (as in Controller.step)
        C = CP[b, :CSIZE[b, Z_PARAMS]]
        S = S_buf[:CSIZE[b, Z_STATE]]
        ints = internals[:CSIZE[b, Z_INTERNALS]]
        scratch = scratch_buf[:CSIZE[b, Z_SCRATCH]]
        noise = NOISE[noise_idx[b]]
        has_ext = ext_idx[b] >= 0
        XR = EXT[max(ext_idx[b], 0)]
        est = est_on[b] != 0
        fest[:] = 0.0
        sensor_init(x[X_Q], x[X_Q + 1], cfg, st)
        for k in range(n):
            t = k * dt
            for j in range(2):
                a, w = sensor_read(j, x[X_Q + j], x[X_QD + j], t, cfg, st)
                qm[j] = a + noise[k, N_Q + j]
                qdm[j] = w + noise[k, N_QD + j]
            pressure_read(x, X_P, cfg, pmeas)      # sensor faults (off: a copy)
            if est:
                estimator_step(EP[b], ES, PE[b], k, dt, qm, qdm, pmeas, fest, escr)
                ILOG[b, k, IL_EST:IL_EST + NEST] = fest
            controller_step(KIND[b], C, S, Pm, k, dt, qm, qdm, pmeas, R[k], fest, dp,
                            ints, scratch)
            delta_p_to_set_values(dp[0], dp[1], Pm, u)
            # element by element: a view of the row or of x costs two atomic
            # reference-count updates per sample
            LOG[b, k, L_T] = t
            for i in range(2):
                LOG[b, k, L_Q + i] = x[X_Q + i]
                LOG[b, k, L_QD + i] = x[X_QD + i]
                LOG[b, k, L_QM + i] = qm[i]
                LOG[b, k, L_QDM + i] = qdm[i]
                LOG[b, k, L_DP + i] = dp[i]
            for i in range(4):
                LOG[b, k, L_P + i] = x[X_P + i]
                LOG[b, k, L_U + i] = u[i]
            LOG[b, k, L_X], LOG[b, k, L_Y] = tcp_position(x[X_Q], x[X_Q + 1], Pp)
            j11, j12, j21, j22 = tcp_jacobian(x[X_Q], x[X_Q + 1], Pp)
            LOG[b, k, L_XD] = j11 * x[X_QD] + j12 * x[X_QD + 1]
            LOG[b, k, L_YD] = j21 * x[X_QD] + j22 * x[X_QD + 1]
            for i in range(NINT):
                LOG[b, k, L_INT + i] = internals[i]
            valve_delay(z, u, Pp)          # valve dead time: the plant gets u[k - d] (off: none)
            for i in range(substeps):
                q_old0, q_old1 = x[X_Q], x[X_Q + 1]
                if has_ext:
                    fx, fy = external_joint_torque(XR[k], x[X_Q], x[X_Q + 1], x[X_QD],
                                                   x[X_QD + 1], Pp, tau_e)
                    if i == 0:
                        ILOG[b, k, IL_F], ILOG[b, k, IL_F + 1] = fx, fy
                    rk4_step(x, z, u, tau_e, h, Pp, work)
                else:
                    rk4_step(x, z, u, tau0, h, Pp, work)
                sensor_track_joints(q_old0, q_old1, x[X_Q], x[X_Q + 1], t + i * h, h, cfg,
                                    st)
            if not (np.isfinite(x[X_Q]) and np.isfinite(x[X_Q + 1])
                    and abs(x[X_QD]) < DIVERGENCE_VELOCITY
                    and abs(x[X_QD + 1]) < DIVERGENCE_VELOCITY):
                diverged[b] = True
                LOG[b, k + 1:, :] = np.nan
                ILOG[b, k + 1:, :] = np.nan
                break


@dataclass
class ExperimentResult(Result):
    """One closed-loop run.

    Attributes
    ----------
    name : str
        Experiment name.
    controller : dict
        Controller description (``Controller.describe()``), incl. its kind.
    reference : Reference
    log : numpy.ndarray, shape (n, NLOG)
        Logged signals (columns :data:`LOG_COLUMNS`; internals named per
        controller kind in :meth:`to_pandas`).
    diverged : bool
        True if the closed loop diverged: the runner stopped because an
        angle became non-finite or a joint speed reached
        :data:`DIVERGENCE_VELOCITY` (1000 rad/s), or a logged signal is
        non-finite.  The log is NaN from then on.
    meta : dict
        Free-form metadata of the case; runs of
        :func:`~.catalog.run_thesis_experiment` carry ``variant`` (the
        :class:`~.catalog.ControllerVariant`), ``label``, ``family``,
        ``controller_family``, ``ki_bar``, ``lambda_s`` and ``experiment``.
    interaction : numpy.ndarray or None, shape (n, NILOG)
        The interaction log (:data:`INTERACTION_LOG`: applied TCP force,
        force-estimator internals) of a run with an external input or an
        estimator; None otherwise.
    interaction_names : tuple of str
        The columns of ``interaction`` that were written (readable by
        :meth:`signal`).
    divergence_reason : str
        Why the run was flagged as diverged ("" if it was not), e.g.
        ``"joint speed |qd1| exceeded 1000 rad/s ..."``.
    diverged_at : float
        Time [s] of the first sample that is no longer valid (NaN if the run
        did not diverge).
    """

    name: str
    controller: dict
    reference: Reference
    log: np.ndarray
    diverged: bool = False
    meta: dict = field(default_factory=dict)
    interaction: np.ndarray | None = None
    interaction_names: tuple = ()
    divergence_reason: str = ""
    diverged_at: float = np.nan

    @property
    def estimator_log(self) -> np.ndarray | None:
        """The force estimators' internals per sample, shape (n, 8) (columns
        ``Fx_rls, Fy_rls, Fx_mo, Fy_mo, r1, r2, yf1, yf2``), or None without estimator."""
        if self.interaction is None or _EST_NAMES[0] not in self.interaction_names:
            return None
        return self.interaction[:, INTERACTION_LOG.slice("estimator")]

    def _log_names(self) -> list:
        names = list(LOG_COLUMNS)
        internal = INTERNAL_NAMES.get(self.controller.get("kind"), [])
        first = LOG_COLUMNS.index("int0")
        for i, nm in enumerate(internal):
            names[first + i] = nm
        return names

    def signal_names(self) -> list:
        """Names accepted by :meth:`signal`: logged signals, controller internals, reference."""
        return ([c for c in self._log_names() if c not in _UNNAMED] + list(self.interaction_names)
                + list(REF_COLUMNS))

    def signal(self, name: str) -> np.ndarray:
        """One signal by name, shape (n,), SI units.

        Names are those of :meth:`to_pandas`: ``t``, ``q1``, ``q2``, ``qd1``,
        ``qd2``, ``p1``..``p4``, ``q1_meas``, ..., ``u1``..``u4``, ``dp1``,
        ``dp2``, ``x``, ``y``, ``xd``, ``yd``, the controller's internals
        (e.g. ``s1`` for PSMC), the reference columns (``q1_d``, ``x_d``, ...)
        and, for runs with an external input or a force estimator,
        ``Fx_ext``, ``Fy_ext`` [N] and the estimates ``Fx_rls``, ``Fy_rls``,
        ``Fx_mo``, ``Fy_mo`` [N], ``r1``, ``r2``, ``yf1``, ``yf2`` [N m].


        Parameters
        ----------
        name : str
            Signal name (see :meth:`signal_names`).

        Returns
        -------
        numpy.ndarray, shape (n,)

        Raises
        ------
        UnknownNameError
            A ``KeyError`` and a ``ValueError``, for an unknown name (the message lists
            the allowed ones).
        """
        names = self._log_names()
        if isinstance(name, str) and name in names and name not in _UNNAMED:
            return self.log[:, names.index(name)]
        if isinstance(name, str) and name in self.interaction_names:
            return self.interaction[:, INTERACTION_LOG.column_index(name)]
        if isinstance(name, str) and name in REF_COLUMNS:
            return self.reference.signal(name)
        raise UnknownNameError(f"unknown signal {name!r}"
                               f"{did_you_mean(name, self.signal_names())}; choose from "
                               f"{self.signal_names()}")

    def signals(self, *names: str) -> np.ndarray:
        """Several signals by name as columns, shape (n, len(names)).

        Parameters
        ----------
        *names : str
            Signal names (see :meth:`signal`); at least one.

        Returns
        -------
        numpy.ndarray, shape (n, len(names))
        """
        if not names:
            raise ValueError("signals: give at least one signal name")
        return np.stack([self.signal(n) for n in names], axis=1)

    def to_pandas(self) -> pd.DataFrame:
        """All signals as a DataFrame (SI units), reference columns included."""
        df = pd.DataFrame(self.log, columns=self._log_names())
        df = df[[c for c in df.columns if c not in _UNNAMED]]
        ref = pd.DataFrame(self.reference.data, columns=REF_COLUMNS)
        parts = [df, ref]
        if self.interaction_names:
            parts.insert(1, pd.DataFrame({c: self.signal(c) for c in self.interaction_names}))
        return pd.concat(parts, axis=1)

    def column_units(self) -> dict:
        """The units of :meth:`to_pandas`' columns (from the declared layouts of the log, the
        controller's internals, the interaction log and the reference row)."""
        cls = CONTROLLER_CLASSES.get(self.controller.get("kind"))
        lays = [LOG, INTERACTION_LOG, ESTIMATOR_INTERNALS, REFERENCE_ROW]
        units = layout_units(*lays, *([cls.INTERNALS] if cls is not None else []))
        return {c: u for c, u in units.items() if c not in _UNNAMED}

    @property
    def t(self) -> np.ndarray:
        """Sample times [s]."""
        return self.log[:, 0]

    def tracking_error(self) -> np.ndarray:
        """Task-space position error ||r_d - r|| per sample [m]."""
        return np.hypot(self.signal("x_d") - self.signal("x"),
                        self.signal("y_d") - self.signal("y"))

    def tcp_speed(self) -> np.ndarray:
        """True TCP speed per sample [m/s]."""
        return np.hypot(self.signal("xd"), self.signal("yd"))

    def plot(self, **kwargs):
        """The figure (drawn by :mod:`ppamsafety.plots`), a matplotlib Figure.

        Parameters
        ----------
        **kwargs
            Passed to :func:`ppamsafety.plots.control.plot_experiment`
            (``title``, ``t_range``).
        """
        return plot_experiment(self, **kwargs)


def _controller_rows(arm, controller):
    """Kind code, parameter row (exactly ``PARAMS.size`` wide, checked), declared sizes
    (params, state, internals, scratch) and model row of ``controller``."""
    cls = CONTROLLER_CLASSES.get(controller.kind)
    if cls is None or not isinstance(controller, cls):
        raise TypeError(f"controller = {controller!r} is not one of the controller classes "
                        f"{[c.__name__ for c in CONTROLLER_CLASSES.values()]}")
    C = np.asarray(controller.pack(), dtype=float)
    if C.shape != (cls.PARAMS.size,):
        raise ValueError(f"{cls.__name__}.pack() gave shape {C.shape}, its layout "
                         f"{cls.PARAMS.name!r} declares ({cls.PARAMS.size},)")
    sizes = [0, 0, 0, 0]
    sizes[Z_PARAMS], sizes[Z_STATE] = cls.PARAMS.size, cls.STATE.size
    sizes[Z_INTERNALS], sizes[Z_SCRATCH] = cls.INTERNALS.size, cls.SCRATCH
    return int(controller.kind), C, sizes, controller.model_row(arm)


def _check_valves(row, dt: float, substeps: int, name: str) -> None:
    """:func:`~ppamsafety.plant.model.check_valve_step` for one case, naming it and the fix."""
    h = dt / substeps
    try:
        check_valve_step(row, h)
    except ValueError as exc:
        t_min = float(np.min(lay.PLANT.read(row, "tv")))
        need = int(np.ceil(dt / t_min - 1e-12))
        raise ValueError(f"run_batch: case {name!r}: substeps = {substeps} gives an integration "
                         f"step h = dt/substeps = {h:g} s longer than the fastest valve time "
                         f"constant {t_min:g} s; use substeps >= {need} ({exc})") from None


def run_batch(cases, *, dt: float = 1e-3, substeps: int = 1, threads: int | None = None) -> list:
    """Run many closed-loop experiments of equal length in one compiled call.

    The cases run side by side on every core (``threads``): each thread runs a part of
    the batch in the compiled loop; the results do not depend on the number of threads.

    Parameters
    ----------
    cases : sequence of ExperimentCase
        The runs (plant, controller, reference, sensors, initial state,
        name, metadata; see :class:`~.case.ExperimentCase`).  Dicts with
        the same keys are still accepted for one release (converted with
        :meth:`ExperimentCase.from_dict`, which rejects unknown keys) and
        raise a ``DeprecationWarning``.
    dt : float
        Control period [s], in [1e-5, 0.1].
    substeps : int
        RK4 steps per control period, in [1, 1000].  The integration step
        h = dt/substeps must not exceed any valve time constant of the
        plants (:func:`~ppamsafety.plant.model.check_valve_step`, as in
        :func:`~ppamsafety.plant.model.simulate`); a faster valve is refused
        with the number of substeps it needs, never chosen silently, so the
        same call always integrates the same way.
    threads : int, optional
        Threads the cases are shared among, >= 1 (default every core this process may use,
        :func:`ppamsafety._jit.default_threads`; never more than the cases).

    Returns
    -------
    list of ExperimentResult
        In the order of ``cases``.  A run that diverged has ``diverged``
        set, with ``divergence_reason`` and ``diverged_at``, and raises a
        ``UserWarning`` naming the case.

    Raises
    ------
    TypeError
        For a case that is neither an ExperimentCase nor a dict, or a
        field of the wrong type.
    ValueError
        For references of different lengths or sample periods, a bad dict
        key, or a valve time constant shorter than dt/substeps.
    """
    dt = check_range("dt", dt, 1e-5, 0.1, unit="s")
    substeps = check_int("substeps", substeps, 1, 1000)
    if threads is not None:
        threads = check_int("threads", threads, 1, 1024)
    if isinstance(cases, (ExperimentCase, str, bytes)) or not hasattr(cases, "__iter__"):
        raise TypeError(f"cases must be a sequence of ExperimentCase, got "
                        f"{type(cases).__name__}")
    cases = as_cases(cases)
    if not cases:
        return []
    n = cases[0].reference.n_steps
    check_size(f"run_batch: {len(cases)} case(s) of {n} samples (reference "
               f"{cases[0].reference.name!r}, dt = {dt:g} s)",
               8.0 * n * (len(cases) * (NLOG + NILOG) + SENSOR_NOISE.size * (len(cases) + 1)),
               remedy="run fewer cases at once or shorten the reference")
    refs, ref_ids, noises, noise_ids = [], [], [], []
    X0, PP, PM, KIND, CPs, CSIZE, SC = [], [], [], [], [], [], []
    exts, ext_ids, EPs, PEs, est_on = [], [], [], [], []
    for c in cases:
        ref = c.reference
        if ref.n_steps != n:
            raise ValueError(f"run_batch: all references must have the same number of samples; "
                             f"case {c.name!r} has {ref.n_steps}, the first case {n}")
        if abs(ref.dt - dt) > 1e-12:
            raise ValueError(f"run_batch: case {c.name!r}: reference sampled at {ref.dt} s but "
                             f"dt = {dt} s")
        key = id(ref)
        ids = [id(r) for r in refs]
        if key not in ids:
            refs.append(ref)
            ids.append(key)
        ref_ids.append(ids.index(key))
        sens = c.sensors
        if sens.noise:
            noises.append(sens.noise_samples(n))
            noise_ids.append(len(noises) - 1)
        else:
            noise_ids.append(-1)
        arm = c.arm
        x0 = c.x0
        if x0 is None:
            try:
                x0 = rest_state(ref.field("q_d")[0], arm)[0]
            except ValueError as exc:
                q0 = np.degrees(ref.field("q_d")[0])
                raise ValueError(
                    f"run_batch: case {c.name!r}: the reference {ref.name!r} starts at q_d = "
                    f"({q0[0]:.4g}, {q0[1]:.4g}) deg, where the arm cannot be at rest (the "
                    f"default initial state): {exc}; start the reference where the arm can "
                    f"hold itself, or give the case an initial state x0") from None
        X0.append(np.asarray(x0, dtype=float))
        PP.append(packing.pack(arm))
        _check_valves(PP[-1], dt, substeps, c.name)
        kind, C, sizes, Pm = _controller_rows(arm, c.controller)
        KIND.append(kind)
        CPs.append(C)
        CSIZE.append(sizes)
        PM.append(Pm)
        SC.append(sens.pack())
        if c.has_external_input:
            exts.append(external_rows(n, c.external_force, c.hand))
            ext_ids.append(len(exts) - 1)
        else:
            ext_ids.append(-1)
        if c.estimator is not None:
            c.estimator.check_period(dt)
            EPs.append(c.estimator.pack())
            PEs.append(c.estimator.model_row(arm))
            est_on.append(1)
        else:
            EPs.append(np.zeros(ESTIMATOR_PARAMS.size))
            PEs.append(Pm)
            est_on.append(0)
    if not exts:
        exts.append(np.zeros((1, EXTERNAL_INPUT.size)))
    noises.append(np.zeros((n, SENSOR_NOISE.size)))
    noise_ids = [i if i >= 0 else len(noises) - 1 for i in noise_ids]
    ncp = max(c.size for c in CPs)
    CP = np.zeros((len(cases), ncp))
    for i, c in enumerate(CPs):
        CP[i, :c.size] = c
    LOG = np.empty((len(cases), n, NLOG))
    # only as long as the run when some case writes it (never written otherwise)
    any_inter = any(c.has_external_input or c.estimator is not None for c in cases)
    ILOG = np.zeros((len(cases), n if any_inter else 1, NILOG))
    args = (np.array(X0), np.array([r.data for r in refs]), np.array(ref_ids, dtype=np.int64),
            np.array(PP), np.array(PM), np.array(KIND, dtype=np.int64), CP,
            np.array(CSIZE, dtype=np.int64), np.array(SC), np.array(noises),
            np.array(noise_ids, dtype=np.int64), float(dt), substeps, LOG, np.array(exts),
            np.array(ext_ids, dtype=np.int64), np.array(EPs), np.array(PEs),
            np.array(est_on, dtype=np.int64), ILOG)
    diverged = np.zeros(len(cases), dtype=np.bool_)
    run_threaded(lambda first, last: _run_batch(first, last, *args, diverged), len(cases),
                 threads)
    out = []
    for i, c in enumerate(cases):
        desc = {**c.controller.describe(), "kind": int(c.controller.kind)}
        names = (_EXT_NAMES if c.has_external_input else ()) + \
            (_EST_NAMES if c.estimator is not None else ())
        div, reason, t_div = divergence(LOG[i], bool(diverged[i]), dt)
        if div:
            warnings.warn(f"run_batch: case {i} {c.name!r} diverged: {reason}", UserWarning,
                          stacklevel=2)
        out.append(ExperimentResult(c.name, desc, c.reference, LOG[i], div, dict(c.meta),
                                    ILOG[i] if names else None, names,
                                    divergence_reason=reason, diverged_at=t_div))
    return out


def divergence(log: np.ndarray, stopped: bool, dt: float) -> tuple:
    """Whether a logged run diverged, why, and from when (computed from the log).

    Parameters
    ----------
    log : numpy.ndarray, shape (n, NLOG)
        The run's log as written by the kernel (rows after a stop are NaN).
    stopped : bool
        The kernel's flag: it stopped the run because, after the control
        period starting at some sample k, an angle was non-finite or
        |qd| >= :data:`DIVERGENCE_VELOCITY`.
    dt : float
        Control period [s].

    Returns
    -------
    diverged : bool
        ``stopped``, or any logged value non-finite.
    reason : str
        Human-readable cause with the time ("" if not diverged).
    diverged_at : float
        Time of the first invalid sample [s] (NaN if not diverged).
    """
    if not stopped and np.isfinite(log.sum()):
        # fast path: a NaN or an infinity makes the sum non-finite (a sum that overflows
        # from finite values only takes the exact path below)
        return False, "", np.nan
    finite = np.isfinite(log)
    bad_rows = np.nonzero(~finite.all(axis=1))[0]
    n = log.shape[0]
    if not stopped and bad_rows.size == 0:
        return False, "", np.nan
    k = int(bad_rows[0]) if bad_rows.size else n
    if k < n and finite[k].any():
        # a partly non-finite row: the kernel did not stop here, a signal went bad first
        names = [c for c, ok in zip(LOG_COLUMNS, finite[k]) if not ok]
        return True, (f"non-finite {', '.join(names[:4])}{' ...' if len(names) > 4 else ''} "
                      f"at t = {k * dt:.6g} s"), k * dt
    last = log[k - 1] if k >= 1 else None
    span = f"between t = {(k - 1) * dt:.6g} s and t = {k * dt:.6g} s"
    if last is None:
        return True, "non-finite state at t = 0 s", 0.0
    qd = last[L_QD:L_QD + 2]
    j = int(np.argmax(np.abs(qd)))
    return True, (f"joint speed reached {DIVERGENCE_VELOCITY:g} rad/s or an angle became "
                  f"non-finite {span} (last logged |qd{j + 1}| = {abs(qd[j]):.4g} rad/s, "
                  f"q = ({last[L_Q]:.4g}, {last[L_Q + 1]:.4g}) rad)"), k * dt


def run(arm, controller, reference: Reference, *, sensors: SensorConfig | None = None,
        x0=None, dt: float = 1e-3, substeps: int = 1, name: str | None = None) -> ExperimentResult:
    """Run one closed-loop experiment.

    Parameters
    ----------
    arm : ArmParameters
        The plant.
    controller : Controller
        The controller (PID, JointPSMC, TaskPSMC, SlidingModeControl,
        GravityCompensation).
    reference : Reference
        The reference; its length sets the run's length.
    sensors : SensorConfig, optional
        Sensor models (default realistic encoders and timing board).
    x0 : array_like, shape (8,), optional
        Initial state (default: at rest at the reference's first angles).
    dt : float
        Control period [s], in [1e-5, 0.1].
    substeps : int
        RK4 steps per control period (see :func:`run_batch`).
    name : str, optional
        Experiment name (default the reference's name).

    Returns
    -------
    ExperimentResult
        With ``diverged``, ``divergence_reason`` and ``diverged_at`` (a
        ``UserWarning`` is raised for a diverged run).

    Raises
    ------
    TypeError, ValueError
        For a bad argument (see :class:`~.case.ExperimentCase` and
        :func:`run_batch`).
    """
    case = ExperimentCase(arm, controller, reference, sensors=sensors, x0=x0, name=name)
    return run_batch([case], dt=dt, substeps=substeps)[0]
