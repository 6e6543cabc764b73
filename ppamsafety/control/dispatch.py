"""One compiled entry point for every controller kind (used by the runner)."""

from __future__ import annotations

from .._jit import kernel
from .base import KIND_GC, KIND_PID, KIND_PSMC_JOINT, KIND_PSMC_TASK, KIND_SMC
from .gravity import gc_step
from .pid import pid_step
from .psmc import psmc_joint_step, psmc_task_step
from .smc import smc_step


@kernel
def controller_step(kind, C, S, Pm, k, dt, qm, qdm, pm, ref, dp, internals, scratch):
    """Compute Delta p (2) [Pa] for controller ``kind`` at sample ``k``.

    Parameters are the controller's packed vector ``C``, its state ``S``
    (updated in place), its model row ``Pm``, the measured angles,
    velocities and pressures, the reference row (12) and work arrays.
    """
    if kind == KIND_PID:
        pid_step(C, S, Pm, dt, qm, qdm, ref, dp, internals, scratch)
    elif kind == KIND_PSMC_JOINT:
        psmc_joint_step(C, S, Pm, dt, qm, qdm, ref, dp, internals, scratch)
    elif kind == KIND_PSMC_TASK:
        psmc_task_step(C, S, Pm, dt, qm, qdm, ref, dp, internals, scratch)
    elif kind == KIND_SMC:
        smc_step(C, S, Pm, dt, qm, qdm, pm, ref, dp, internals, scratch)
    elif kind == KIND_GC:
        gc_step(C, Pm, qm, ref, dp, scratch)
    else:
        dp[0] = 0.0
        dp[1] = 0.0
