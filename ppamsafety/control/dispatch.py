"""One compiled entry point for every controller kind, and the buffer sizes of the runner.

The sizes of the buffers the closed-loop runner and :meth:`Controller.step`
hand to a step function are computed here from the rows every controller
law declares (:data:`DECLARED`: parameters, state, internals, scratch), never
written as literals: a buffer cannot be smaller than a declared need.  The
controller classes read their declarations from :data:`DECLARED`.
"""

from __future__ import annotations

from typing import NamedTuple

from .._jit import step_kernel
from ..layouts import Layout
from .kinds import (KIND_ADMITTANCE, KIND_GC, KIND_PID, KIND_PSMC_JOINT, KIND_PSMC_TASK, KIND_SMC,
                    ControllerKind)
from .laws.admittance import (ADMITTANCE_INTERNALS, ADMITTANCE_PARAMS, ADMITTANCE_SCRATCH,
                              ADMITTANCE_STATE, admittance_step)
from .laws.gravity import GC_PARAMS, GC_SCRATCH, gc_step
from .laws.pid import PID_INTERNALS, PID_PARAMS, PID_STATE, pid_step
from .laws.psmc import (JOINT_PSMC_INTERNALS, JOINT_PSMC_PARAMS, JOINT_PSMC_STATE,
                        TASK_PSMC_INTERNALS, TASK_PSMC_PARAMS, TASK_PSMC_SCRATCH, TASK_PSMC_STATE,
                        psmc_joint_step, psmc_task_step)
from .laws.smc import SMC_INTERNALS, SMC_PARAMS, SMC_SCRATCH, smc_step

#: An empty layout, for a law without state or internals.
EMPTY = Layout("empty", [], register=False)


class Declared(NamedTuple):
    """The rows one controller kind's law declares (:mod:`ppamsafety.control.laws`).

    Parameters
    ----------
    params : Layout
        The packed parameter row (gains, limits, flag codes).
    state : Layout
        The state carried from one sample to the next.
    internals : Layout
        The signals logged per step (the closed-loop log's internal columns).
    scratch : int
        Number of work floats one step may use.
    """

    params: Layout      #: packed parameter row (gains, limits, flag codes)
    state: Layout       #: state carried from one sample to the next
    internals: Layout   #: signals logged per step
    scratch: int        #: work floats one step may use


#: What the law of every kind declares; the controller classes take theirs from here.
DECLARED = {
    KIND_GC: Declared(GC_PARAMS, EMPTY, EMPTY, GC_SCRATCH.size),
    KIND_PID: Declared(PID_PARAMS, PID_STATE, PID_INTERNALS, GC_SCRATCH.size),
    KIND_PSMC_JOINT: Declared(JOINT_PSMC_PARAMS, JOINT_PSMC_STATE, JOINT_PSMC_INTERNALS,
                              GC_SCRATCH.size),
    KIND_PSMC_TASK: Declared(TASK_PSMC_PARAMS, TASK_PSMC_STATE, TASK_PSMC_INTERNALS,
                             TASK_PSMC_SCRATCH.size),
    KIND_SMC: Declared(SMC_PARAMS, EMPTY, SMC_INTERNALS, SMC_SCRATCH.size),
    KIND_ADMITTANCE: Declared(ADMITTANCE_PARAMS, ADMITTANCE_STATE, ADMITTANCE_INTERNALS,
                              ADMITTANCE_SCRATCH.size),
}
assert set(DECLARED) == set(ControllerKind), "a controller kind has no law"

#: Widest parameter row of any kind (width of the runner's padded parameter table).
CONTROLLER_ROW_WIDTH = max(d.params.size for d in DECLARED.values())
#: Longest controller state of any kind.
NSTATE = max(d.state.size for d in DECLARED.values())
#: Most internals any kind logs (width of the log's internal columns).
NINT = max(d.internals.size for d in DECLARED.values())
#: Largest scratch need of any kind.
NSCRATCH = max(d.scratch for d in DECLARED.values())


def declared_sizes(kind) -> tuple:
    """(parameter, state, internals, scratch) sizes declared by controller ``kind``.

    Parameters
    ----------
    kind : ControllerKind or int
        The controller kind.
    """
    d = DECLARED[ControllerKind(kind)]
    return d.params.size, d.state.size, d.internals.size, d.scratch


@step_kernel
def controller_step(kind, C, S, Pm, k, dt, qm, qdm, pm, ref, fest, dp, internals, scratch):
    """Compute Delta p (2) [Pa] for controller ``kind`` at sample ``k``.

    Compiled; the arguments are not checked (:meth:`Controller.step` checks
    them).  Every array is a flat float64 row; the layouts named below are
    those the law of ``kind`` declares (:data:`DECLARED`).  The runner
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
