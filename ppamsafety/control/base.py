"""Common machinery of the discrete-time controllers.

Every controller is a small object with explicit state: ``pack()`` gives its
parameter row, ``state`` its internal state (a numpy array), ``reset()``
clears it, and ``step(...)`` computes one 1 kHz control update in Python
(for inspection and tests).  The closed-loop runner calls the very same
compiled step functions (:mod:`ppamsafety.control.dispatch`) with rows of
exactly the same width, so a controller behaves identically in a single step
and inside a batched simulation.

Each controller class declares its flat arrays once, as
:class:`~ppamsafety.layouts.Layout` s:

* ``PARAMS`` -- the packed parameter row (gains, limits, flag codes);
* ``STATE`` -- the state carried from one sample to the next;
* ``INTERNALS`` -- the signals logged per step (their column names are the
  names of the closed-loop log's internal columns);
* ``SCRATCH`` -- the work memory one step may use.

:mod:`ppamsafety.control.dispatch` sizes every buffer from the maximum of
these declarations.

All controllers output a pressure difference Delta p per joint [Pa]
(Delta-p approach (3.7)); the runner turns it into valve set values.

Reference row (per sample, 12 values, declared in :mod:`.reference`): q_d (2), qd_d (2), qdd_d (2),
qddd_d (2) [rad, rad/s, ...], r_d (2), rd_d (2) [m, m/s].  Kernels index it
with the ``R_*`` constants below.
"""

from __future__ import annotations

import numbers

import numpy as np

from .._jit import kernel_array
from .._validation import (InvalidTypeError, as_float_array, describe, check_finite_result, check_instance, check_range,
                           check_range_array, check_shape, check_vector)
from ..layouts import Layout
from ..params.arm import ArmParameters
from ..plant.packing import controller_view
from .dispatch import EMPTY, controller_step
from .estimation import ESTIMATOR_INTERNALS
from .reference import NREF, R_Q


#: Largest |angle| accepted by :meth:`Controller.step` [rad] (one turn: the joints of the
#: arm cannot turn further, §2.2).
ANGLE_MAX = 2 * np.pi
#: Largest |joint velocity| accepted by :meth:`Controller.step` [rad/s]: the divergence
#: threshold of the closed loop (:data:`ppamsafety.experiments.closed_loop.DIVERGENCE_VELOCITY`).
VELOCITY_MAX = 1.0e3
#: Gauge pressures accepted by :meth:`Controller.step`: [-P_ATM_MAX, PRESSURE_MAX] [Pa]
#: (no gauge pressure below vacuum; 100 bar is far above any PPAM supply).
P_ATM_MAX = 1.01325e5
PRESSURE_MAX = 1.0e7
#: Largest |entry| of a reference row accepted by :meth:`Controller.step` (SI units).
REF_MAX = 1.0e9

def pair(name: str, value, *, lo: float = 0.0, hi: float = np.inf, unit: str = "",
         lo_open: bool = False) -> tuple:
    """A per-joint value pair; a scalar is used for both joints.

    Parameters
    ----------
    name : str
        Argument name for error messages (entries are named ``name[j]``).
    value : float or sequence of 2 float
        One value for both joints, or one per joint.
    lo, hi : float
        Allowed interval ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``); inf
        and NaN are always refused.
    unit : str
        Unit for the messages.
    lo_open : bool
        Exclude ``lo`` itself.

    Returns
    -------
    tuple of 2 float
        The values per joint.

    Raises
    ------
    TypeError
        For a value that is neither a real number nor a sequence of two.
    ValueError
        For a sequence of another length or an entry outside the interval.
    """
    if isinstance(value, numbers.Real) or (isinstance(value, np.ndarray) and value.ndim == 0):
        v = check_range(name, value, lo, hi, lo_open=lo_open, unit=unit)
        return (v, v)
    if not isinstance(value, (list, tuple, np.ndarray)):
        u = f" [{unit}]" if unit else ""
        raise InvalidTypeError(f"{name} must be a real number or a pair of real numbers (one "
                               f"per joint){u}, got {describe(value)}")
    return check_vector(name, value, 2, lo, hi, lo_open=lo_open, unit=unit)


class Controller:
    """Base class: declared layouts, explicit state, ``reset`` and a Python-level ``step``.

    Subclasses set ``kind`` (a :class:`ControllerKind`), ``PARAMS``, ``STATE``,
    ``INTERNALS`` (:class:`~ppamsafety.layouts.Layout`) and ``SCRATCH`` (int,
    number of work floats one step uses), and implement :meth:`pack`.
    """

    kind: int = -1
    name: str = "controller"
    #: True for a controller that reads the loop's force estimate (``f_est`` of :meth:`step`).
    needs_estimator: bool = False
    PARAMS: Layout = EMPTY
    STATE: Layout = EMPTY
    INTERNALS: Layout = EMPTY
    SCRATCH: int = 0

    def __init__(self):
        self.state = self.initial_state()
        self.internals = np.zeros(self.INTERNALS.size)
        self._k = 0

    # -- to be provided by subclasses ----------------------------------------
    def pack(self) -> np.ndarray:
        """Parameter row for the compiled step function (layout ``PARAMS``)."""
        raise NotImplementedError

    def model_row(self, arm) -> np.ndarray:
        """Packed arm parameters the controller believes in (its model).

        Parameters
        ----------
        arm : ArmParameters
            The arm whose controller view (:func:`~ppamsafety.plant.packing.controller_view`)
            is packed.

        Returns
        -------
        numpy.ndarray
            The model row (layout ``PLANT``).
        """
        return controller_view(arm)

    def describe(self) -> dict:
        """Parameters as a flat dict (for result tables)."""
        return {"controller": self.name}

    # -- common ---------------------------------------------------------------
    def initial_state(self) -> np.ndarray:
        """Internal state at the start of an experiment (layout ``STATE``)."""
        return self.STATE.empty()

    def reset(self) -> None:
        """Forget all history (integrators, proxy state)."""
        self.state = self.initial_state()
        self.internals = np.zeros(self.INTERNALS.size)
        self._k = 0

    def step(self, arm, q_meas, qd_meas, p_meas, ref, *, dt: float = 1e-3,
             f_est=None) -> np.ndarray:
        """One control update; returns Delta p per joint [Pa] (incl. feedforward).

        The compiled step function receives the same rows as in the
        closed-loop runner: the parameter row of exactly ``PARAMS.size``
        slots, the state of ``STATE.size``, internals of ``INTERNALS.size``
        and a scratch buffer of ``SCRATCH`` floats.

        Parameters
        ----------
        arm : ArmParameters
            Used for the controller's model (:meth:`model_row`).
        q_meas, qd_meas : array_like, shape (2,)
            Measured joint angles [rad] and velocities [rad/s].
        p_meas : array_like, shape (4,)
            Measured gauge pressures [Pa].
        ref : array_like, shape (12,)
            Reference row (see module docstring).
        dt : float
            Control period [s], in [1e-6, 1] s.
        f_est : array_like, optional
            The loop's force-estimator internals row
            (:data:`~ppamsafety.control.estimation.ESTIMATOR_INTERNALS`, as
            the runner passes it); read only by controllers with
            ``needs_estimator`` (admittance).  Default zeros.

        Returns
        -------
        numpy.ndarray, shape (2,)
            Delta p per joint [Pa].

        Raises
        ------
        TypeError, ValueError
            For an argument of the wrong type, shape, a non-finite value or
            a ``dt`` out of range (the message names the argument).
        """
        check_instance("arm", arm, ArmParameters)
        dt = check_range("dt", dt, 1e-6, 1.0, unit="s")
        qm = check_range_array("q_meas", check_shape(
            "q_meas", as_float_array("q_meas", q_meas), (2,)), -ANGLE_MAX, ANGLE_MAX, unit="rad")
        qdm = check_range_array("qd_meas", check_shape(
            "qd_meas", as_float_array("qd_meas", qd_meas), (2,)), -VELOCITY_MAX, VELOCITY_MAX,
            unit="rad/s")
        pm = check_range_array("p_meas", check_shape(
            "p_meas", as_float_array("p_meas", p_meas), (4,)), -P_ATM_MAX, PRESSURE_MAX, unit="Pa")
        r = check_shape("ref", as_float_array("ref", ref), (NREF,))
        check_range_array("ref", r[R_Q:R_Q + 2], -ANGLE_MAX, ANGLE_MAX, unit="rad")
        check_range_array("ref", r, -REF_MAX, REF_MAX)
        fe = (np.zeros(ESTIMATOR_INTERNALS.size) if f_est is None else as_float_array(
            "f_est", f_est, shape_tail=(ESTIMATOR_INTERNALS.size,)).reshape(-1))
        out = np.zeros(2)
        # every row as the closed loop passes it (writable, C-contiguous float64; the cached
        # rows are read-only): another type would compile controller_step again, about 11 s
        controller_step(int(self.kind), kernel_array(self.pack()), self.state,
                        kernel_array(self.model_row(arm)), self._k, dt, kernel_array(qm),
                        kernel_array(qdm), kernel_array(pm), kernel_array(r), kernel_array(fe),
                        out, self.internals, np.zeros(self.SCRATCH))
        self._k += 1
        return check_finite_result(f"{type(self).__name__}.step output Delta p", out,
                                   f"q_meas = {qm.tolist()}, qd_meas = {qdm.tolist()}, "
                                   f"p_meas = {pm.tolist()}")
