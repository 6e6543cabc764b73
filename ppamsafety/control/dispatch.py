"""One compiled entry point for every controller kind, and the buffer sizes of the runner.

The sizes of the buffers the closed-loop runner and :meth:`Controller.step`
hand to a step function are computed here from the layouts every controller
class declares (``PARAMS``, ``STATE``, ``INTERNALS``, ``SCRATCH``), never
written as literals: a buffer cannot be smaller than a declared need.
"""

from __future__ import annotations

from .._jit import kernel
from .admittance import AdmittancePSMC, admittance_step
from .base import (KIND_ADMITTANCE, KIND_GC, KIND_PID, KIND_PSMC_JOINT, KIND_PSMC_TASK, KIND_SMC,
                   ControllerKind)
from .gravity import GravityCompensation, gc_step
from .pid import PID, pid_step
from .psmc import JointPSMC, TaskPSMC, psmc_joint_step, psmc_task_step
from .smc import SlidingModeControl, smc_step

#: The controller class of every kind.
CONTROLLER_CLASSES = {KIND_GC: GravityCompensation, KIND_PID: PID,
                      KIND_PSMC_JOINT: JointPSMC, KIND_PSMC_TASK: TaskPSMC,
                      KIND_SMC: SlidingModeControl, KIND_ADMITTANCE: AdmittancePSMC}
assert set(CONTROLLER_CLASSES) == set(ControllerKind), "a controller kind has no class"

#: Widest parameter row of any kind (width of the runner's padded parameter table).
CONTROLLER_ROW_WIDTH = max(c.PARAMS.size for c in CONTROLLER_CLASSES.values())
#: Longest controller state of any kind.
NSTATE = max(c.STATE.size for c in CONTROLLER_CLASSES.values())
#: Most internals any kind logs (width of the log's internal columns).
NINT = max(c.INTERNALS.size for c in CONTROLLER_CLASSES.values())
#: Largest scratch need of any kind.
NSCRATCH = max(c.SCRATCH for c in CONTROLLER_CLASSES.values())


def declared_sizes(kind) -> tuple:
    """(parameter, state, internals, scratch) sizes declared by controller ``kind``.

    Parameters
    ----------
    kind : ControllerKind or int
        The controller kind.
    """
    c = CONTROLLER_CLASSES[ControllerKind(kind)]
    return c.PARAMS.size, c.STATE.size, c.INTERNALS.size, c.SCRATCH


@kernel
def controller_step(kind, C, S, Pm, k, dt, qm, qdm, pm, ref, fest, dp, internals, scratch):
    """Compute Delta p (2) [Pa] for controller ``kind`` at sample ``k``.

    Compiled; the arguments are not checked (:meth:`Controller.step` checks
    them).  Every array is a flat float64 row; the layouts named below are
    those the controller class of ``kind`` declares (``PARAMS``, ``STATE``,
    ``INTERNALS``, ``SCRATCH``, see :data:`CONTROLLER_CLASSES`).  The runner
    passes rows padded to :data:`CONTROLLER_ROW_WIDTH`, :data:`NSTATE`,
    :data:`NINT` and :data:`NSCRATCH`; a kind reads only its own prefix.

    Parameters
    ----------
    kind : int
        :class:`~ppamsafety.control.base.ControllerKind` code selecting the
        step function; an unknown code gives Delta p = 0.
    C : numpy.ndarray, shape (>= PARAMS.size,)
        The controller's packed parameter row (layout ``PARAMS`` of the
        kind, SI units), read only.
    S : numpy.ndarray, shape (>= STATE.size,)
        The controller's state (layout ``STATE``), updated in place.
    Pm : numpy.ndarray
        The controller's model row (layout ``PLANT`` of
        :mod:`ppamsafety.plant.layout`, its controller view), read only.
    k : int
        Sample index (0 at the start of the experiment); not read by the
        current kinds.
    dt : float
        Control period T [s].
    qm, qdm : numpy.ndarray, shape (2,)
        Measured joint angles [rad] and velocities [rad/s], read only.
    pm : numpy.ndarray, shape (4,)
        Measured gauge pressures of the four muscle groups [Pa], read only
        (used by the sliding mode control).
    ref : numpy.ndarray, shape (12,)
        Reference row (columns ``R_*`` of :mod:`ppamsafety.control.base`:
        q_d [rad], qd_d [rad/s], qdd_d [rad/s^2], qddd_d [rad/s^3], r_d [m],
        rd_d [m/s]), read only.
    fest : numpy.ndarray
        The loop's force-estimator internals (layout
        ``ESTIMATOR_INTERNALS`` of :mod:`ppamsafety.control.estimation`),
        read only, and only by the admittance kind.
    dp : numpy.ndarray, shape (2,)
        Output Delta p per joint [Pa] (feedback plus gravity
        compensation), written.
    internals : numpy.ndarray, shape (>= INTERNALS.size,)
        Logged internals of the kind (layout ``INTERNALS``), written.
    scratch : numpy.ndarray, shape (>= SCRATCH,)
        Work memory of the kind, overwritten.
    """
    if kind == KIND_PID:
        pid_step(C, S, Pm, dt, qm, qdm, ref, dp, internals, scratch)
    elif kind == KIND_PSMC_JOINT:
        psmc_joint_step(C, S, Pm, dt, qm, qdm, ref, dp, internals, scratch)
    elif kind == KIND_PSMC_TASK:
        psmc_task_step(C, S, Pm, dt, qm, qdm, ref, dp, internals, scratch)
    elif kind == KIND_SMC:
        smc_step(C, S, Pm, dt, qm, qdm, pm, ref, dp, internals, scratch)
    elif kind == KIND_ADMITTANCE:
        admittance_step(C, S, Pm, dt, qm, qdm, ref, fest, dp, internals, scratch)
    elif kind == KIND_GC:
        gc_step(C, Pm, qm, ref, dp, scratch)
    else:
        dp[0] = 0.0
        dp[1] = 0.0
