"""The controller kinds: the code that selects a controller's compiled step function."""

from __future__ import annotations

from enum import IntEnum


class ControllerKind(IntEnum):
    """Code of a controller kind, selecting its compiled step function."""

    GC = 0
    PID = 1
    PSMC_JOINT = 2
    PSMC_TASK = 3
    SMC = 4
    ADMITTANCE = 5


KIND_GC, KIND_PID, KIND_PSMC_JOINT, KIND_PSMC_TASK, KIND_SMC, KIND_ADMITTANCE = (
    ControllerKind.GC, ControllerKind.PID, ControllerKind.PSMC_JOINT, ControllerKind.PSMC_TASK,
    ControllerKind.SMC, ControllerKind.ADMITTANCE)


__all__ = ["ControllerKind", "KIND_GC", "KIND_PID", "KIND_PSMC_JOINT", "KIND_PSMC_TASK",
           "KIND_SMC", "KIND_ADMITTANCE"]
