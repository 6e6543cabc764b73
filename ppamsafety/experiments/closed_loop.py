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

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .._jit import kernel
from .._validation import check_int, check_range
from ..control.base import KIND_PID, KIND_PSMC_JOINT, KIND_PSMC_TASK, KIND_SMC, NINT, NSCRATCH
from ..control.base import NSTATE
from ..control.dispatch import controller_step
from ..control.sensors import (NSENSOR, SensorConfig, initial_sensor_state, sensor_init,
                               sensor_read, sensor_track)
from ..plant import layout as lay
from ..plant.geometry import tcp_jacobian, tcp_position
from ..plant.model import NWORK, NX, effect_state_length, rk4_step
from ..plant.pneumatics import delta_p_to_set_values
from .case import ExperimentCase, as_cases
from .trajectories import REF_COLUMNS, Reference

LOG_COLUMNS = (["t", "q1", "q2", "qd1", "qd2", "p1", "p2", "p3", "p4", "q1_meas", "q2_meas",
                "qd1_meas", "qd2_meas", "u1", "u2", "u3", "u4", "dp1", "dp2", "x", "y", "xd",
                "yd"] + [f"int{i}" for i in range(NINT)])
NLOG = len(LOG_COLUMNS)
INTERNAL_NAMES = {
    KIND_PID: ["pid1", "pid2", "integral1", "integral2"],
    KIND_PSMC_JOINT: ["dp_psmc1", "dp_psmc2", "s1", "s2", "on_surface1", "on_surface2",
                      "a1", "a2"],
    KIND_PSMC_TASK: ["fx", "fy", "sx", "sy", "on_surface", "f_star_norm", "ax", "ay"],
    KIND_SMC: ["s1", "s2", "a11", "a22", "b1", "b2", "u_smc1", "u_smc2"],
}


@kernel
def _run_batch(X0, REFS, ref_idx, PP, PM, KIND, CP, SCFG, NOISE, noise_idx, dt, substeps, LOG):
    nb = X0.shape[0]
    n = LOG.shape[1]
    h = dt / substeps
    x = np.empty(NX)
    work = np.empty(NWORK)
    tau0 = np.zeros(2)
    S = np.empty(NSTATE)
    st = np.empty(NSENSOR)
    qm = np.empty(2)
    qdm = np.empty(2)
    dp = np.empty(2)
    u = np.empty(4)
    internals = np.empty(NINT)
    scratch = np.empty(NSCRATCH)
    diverged = np.zeros(nb, dtype=np.bool_)
    for b in range(nb):
        x[:] = X0[b]
        S[:] = 0.0
        st[:] = 0.0
        st[2:6] = -1.0e9
        internals[:] = 0.0
        Pp, Pm, cfg, C, R = PP[b], PM[b], SCFG[b], CP[b], REFS[ref_idx[b]]
        z = np.zeros(effect_state_length(Pp))     # plant effect state (empty: effects off)
        noise = NOISE[noise_idx[b]]
        sensor_init(x[0], x[1], cfg, st)
        for k in range(n):
            t = k * dt
            for j in range(2):
                a, w = sensor_read(j, x[j], x[2 + j], t, cfg, st)
                qm[j] = a + noise[k, j]
                qdm[j] = w + noise[k, 2 + j]
            controller_step(KIND[b], C, S, Pm, k, dt, qm, qdm, x[4:8], R[k], dp, internals,
                            scratch)
            delta_p_to_set_values(dp[0], dp[1], Pm, u)
            row = LOG[b, k]
            row[0] = t
            row[1:9] = x
            row[9:11] = qm
            row[11:13] = qdm
            row[13:17] = u
            row[17:19] = dp
            row[19], row[20] = tcp_position(x[0], x[1], Pp)
            j11, j12, j21, j22 = tcp_jacobian(x[0], x[1], Pp)
            row[21] = j11 * x[2] + j12 * x[3]
            row[22] = j21 * x[2] + j22 * x[3]
            row[23:23 + NINT] = internals
            for i in range(substeps):
                q_old0, q_old1 = x[0], x[1]
                rk4_step(x, z, u, tau0, h, Pp, work)
                sensor_track(0, q_old0, x[0], t + i * h, h, cfg, st)
                sensor_track(1, q_old1, x[1], t + i * h, h, cfg, st)
            if not (np.isfinite(x[0]) and np.isfinite(x[1]) and abs(x[2]) < 1e3
                    and abs(x[3]) < 1e3):
                diverged[b] = True
                LOG[b, k + 1:, :] = np.nan
                break
    return diverged


@dataclass
class ExperimentResult:
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
        True if the state blew up (the log is NaN from then on).
    meta : dict
        Free-form metadata of the case; runs of
        :func:`~.catalog.run_thesis_experiment` carry ``variant`` (the
        :class:`~.catalog.ControllerVariant`), ``label``, ``family``,
        ``controller_family``, ``ki_bar``, ``lambda_s`` and ``experiment``.
    """

    name: str
    controller: dict
    reference: Reference
    log: np.ndarray
    diverged: bool = False
    meta: dict = field(default_factory=dict)

    def _log_names(self) -> list:
        names = list(LOG_COLUMNS)
        internal = INTERNAL_NAMES.get(self.controller.get("kind"), [])
        first = LOG_COLUMNS.index("int0")
        for i, nm in enumerate(internal):
            names[first + i] = nm
        return names

    def signal_names(self) -> list:
        """Names accepted by :meth:`signal`: logged signals, controller internals, reference."""
        return [c for c in self._log_names() if not c.startswith("int")] + list(REF_COLUMNS)

    def signal(self, name: str) -> np.ndarray:
        """One signal by name, shape (n,), SI units.

        Names are those of :meth:`to_pandas`: ``t``, ``q1``, ``q2``, ``qd1``,
        ``qd2``, ``p1``..``p4``, ``q1_meas``, ..., ``u1``..``u4``, ``dp1``,
        ``dp2``, ``x``, ``y``, ``xd``, ``yd``, the controller's internals
        (e.g. ``s1`` for PSMC) and the reference columns (``q1_d``, ``x_d``, ...).
        """
        names = self._log_names()
        if isinstance(name, str) and name in names and not name.startswith("int"):
            return self.log[:, names.index(name)]
        if isinstance(name, str) and name in REF_COLUMNS:
            return self.reference.signal(name)
        raise KeyError(f"unknown signal {name!r}; choose from {self.signal_names()}")

    def signals(self, *names: str) -> np.ndarray:
        """Several signals by name as columns, shape (n, len(names))."""
        return np.stack([self.signal(n) for n in names], axis=1)

    def to_pandas(self) -> pd.DataFrame:
        """All signals as a DataFrame (SI units), reference columns included."""
        df = pd.DataFrame(self.log, columns=self._log_names())
        df = df[[c for c in df.columns if not c.startswith("int")]]
        ref = pd.DataFrame(self.reference.data, columns=REF_COLUMNS)
        return pd.concat([df, ref], axis=1)

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
        """Plot with :mod:`ppamsafety.report`; returns a matplotlib Figure.

        Parameters
        ----------
        **kwargs
            Passed to :func:`ppamsafety.report.control_figures.plot_experiment`
            (``title``, ``t_range``).
        """
        from ..report.control_figures import plot_experiment
        return plot_experiment(self, **kwargs)


def _controller_rows(arm, controller):
    C = controller.pack()
    return controller.kind, C, controller.model_row(arm)


def run_batch(cases, *, dt: float = 1e-3, substeps: int = 1) -> list:
    """Run many closed-loop experiments of equal length in one compiled call.

    Parameters
    ----------
    cases : sequence of ExperimentCase
        The runs (plant, controller, reference, sensors, initial state,
        name, metadata; see :class:`~.case.ExperimentCase`).  Dicts with
        the same keys are still accepted for one release (converted with
        :meth:`ExperimentCase.from_dict`, which rejects unknown keys) and
        raise a ``DeprecationWarning``.
    dt : float
        Control period [s].
    substeps : int
        RK4 steps per control period.

    Returns
    -------
    list of ExperimentResult
        In the order of ``cases``.

    Raises
    ------
    TypeError
        For a case that is neither an ExperimentCase nor a dict, or a
        field of the wrong type.
    ValueError
        For references of different lengths or sample periods, or a bad
        dict key.
    """
    from ..plant.model import rest_state

    check_range("dt", dt, 1e-5, 0.1, unit="s")
    substeps = check_int("substeps", substeps, 1, 1000)
    cases = as_cases(cases)
    if not cases:
        return []
    n = cases[0].reference.n_steps
    refs, ref_ids, noises, noise_ids = [], [], [], []
    X0, PP, PM, KIND, CPs, SC = [], [], [], [], [], []
    for c in cases:
        ref = c.reference
        if ref.n_steps != n:
            raise ValueError("run_batch: all references must have the same number of samples")
        if abs(ref.dt - dt) > 1e-12:
            raise ValueError(f"run_batch: reference sampled at {ref.dt} s, controller at {dt} s")
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
            x0 = rest_state(ref.field("q_d")[0], arm)[0]
        X0.append(np.asarray(x0, dtype=float))
        PP.append(lay.pack(arm))
        kind, C, Pm = _controller_rows(arm, c.controller)
        KIND.append(kind)
        CPs.append(C)
        PM.append(Pm)
        SC.append(sens.pack())
    noises.append(np.zeros((n, 4)))
    noise_ids = [i if i >= 0 else len(noises) - 1 for i in noise_ids]
    ncp = max(c.size for c in CPs)
    CP = np.zeros((len(cases), ncp))
    for i, c in enumerate(CPs):
        CP[i, :c.size] = c
    LOG = np.empty((len(cases), n, NLOG))
    diverged = _run_batch(np.array(X0), np.array([r.data for r in refs]),
                          np.array(ref_ids, dtype=np.int64), np.array(PP), np.array(PM),
                          np.array(KIND, dtype=np.int64), CP, np.array(SC), np.array(noises),
                          np.array(noise_ids, dtype=np.int64), float(dt), substeps, LOG)
    out = []
    for i, c in enumerate(cases):
        desc = {**c.controller.describe(), "kind": c.controller.kind}
        out.append(ExperimentResult(c.name, desc, c.reference, LOG[i], bool(diverged[i]),
                                    dict(c.meta)))
    return out


def run(arm, controller, reference: Reference, *, sensors: SensorConfig | None = None,
        x0=None, dt: float = 1e-3, substeps: int = 1, name: str | None = None) -> ExperimentResult:
    """Run one closed-loop experiment.

    Parameters
    ----------
    arm : ArmParameters
        The plant.
    controller : Controller
    reference : Reference
    sensors : SensorConfig, optional
        Sensor models (default realistic encoders and timing board).
    x0 : array_like, shape (8,), optional
        Initial state (default: at rest at the reference's first angles).
    dt : float
        Control period [s].
    substeps : int
        RK4 steps per control period.
    name : str, optional
        Experiment name (default the reference's name).

    Returns
    -------
    ExperimentResult
    """
    case = ExperimentCase(arm, controller, reference, sensors=sensors, x0=x0, name=name)
    return run_batch([case], dt=dt, substeps=substeps)[0]
