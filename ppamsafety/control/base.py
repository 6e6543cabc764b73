"""Common machinery of the discrete-time controllers.

Every controller is a small object with explicit state: ``pack()`` gives its
parameter vector, ``state`` its internal state (a numpy array), ``reset()``
clears it, and ``step(...)`` computes one 1 kHz control update in Python
(for inspection and tests).  The closed-loop runner calls the very same
compiled step functions (:mod:`ppamsafety.control.dispatch`), so a controller
behaves identically in a single step and inside a batched simulation.

All controllers output a pressure difference Delta p per joint [Pa]
(Delta-p approach (3.7)); the runner turns it into valve set values.

Reference vector layout (per sample, 12 values): q_d (2), qd_d (2),
qdd_d (2), qddd_d (2) [rad, rad/s, ...], r_d (2), rd_d (2) [m, m/s].
"""

from __future__ import annotations

import numpy as np

from .._validation import as_float_array, check_range

KIND_GC, KIND_PID, KIND_PSMC_JOINT, KIND_PSMC_TASK, KIND_SMC = 0, 1, 2, 3, 4
NSTATE = 8        #: controller state length
NINT = 8          #: controller internals logged per step
NREF = 12         #: reference vector length
NSCRATCH = 32     #: scratch floats a controller step may use


def pair(name: str, value, *, lo: float = 0.0, hi: float = np.inf, unit: str = "") -> tuple:
    """A per-joint value pair; a scalar is used for both joints."""
    v = np.broadcast_to(np.asarray(value, dtype=float), (2,))
    return tuple(check_range(f"{name}[{j}]", v[j], lo, hi, unit=unit) for j in range(2))


class Controller:
    """Base class: explicit state, ``reset`` and a Python-level ``step``."""

    kind: int = -1
    name: str = "controller"

    def __init__(self):
        self.state = np.zeros(NSTATE)
        self.internals = np.zeros(NINT)
        self._k = 0

    # -- to be provided by subclasses ----------------------------------------
    def pack(self) -> np.ndarray:
        """Parameter vector for the compiled step function."""
        raise NotImplementedError

    def model_row(self, arm) -> np.ndarray:
        """Packed arm parameters the controller believes in (its model)."""
        from ..plant.layout import controller_view
        return controller_view(arm)

    def describe(self) -> dict:
        """Parameters as a flat dict (for result tables)."""
        return {"controller": self.name}

    # -- common ---------------------------------------------------------------
    def initial_state(self) -> np.ndarray:
        """Internal state at the start of an experiment."""
        return np.zeros(NSTATE)

    def reset(self) -> None:
        """Forget all history (integrators, proxy state)."""
        self.state = self.initial_state()
        self.internals = np.zeros(NINT)
        self._k = 0

    def step(self, arm, q_meas, qd_meas, p_meas, ref, *, dt: float = 1e-3) -> np.ndarray:
        """One control update; returns Delta p per joint [Pa] (incl. feedforward).

        Parameters
        ----------
        arm : ArmParameters
            Used for the controller's model (:meth:`model_row`).
        q_meas, qd_meas : array_like, shape (2,)
            Measured joint angles [rad] and velocities [rad/s].
        p_meas : array_like, shape (4,)
            Measured gauge pressures [Pa].
        ref : array_like, shape (12,)
            Reference (see module docstring).
        dt : float
            Control period [s].
        """
        from .dispatch import controller_step

        check_range("dt", dt, 1e-6, 1.0, unit="s")
        qm = as_float_array("q_meas", q_meas, shape_tail=(2,)).reshape(2)
        qdm = as_float_array("qd_meas", qd_meas, shape_tail=(2,)).reshape(2)
        pm = as_float_array("p_meas", p_meas, shape_tail=(4,)).reshape(4)
        r = as_float_array("ref", ref, shape_tail=(NREF,)).reshape(NREF)
        out = np.zeros(2)
        controller_step(self.kind, self.pack(), self.state, self.model_row(arm), self._k, dt,
                        qm, qdm, pm, r, out, self.internals, np.zeros(NSCRATCH))
        self._k += 1
        return out
