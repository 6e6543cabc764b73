"""Discrete-time controllers (1 kHz) and sensor models.

Controllers: :class:`PID`, :class:`JointPSMC`, :class:`TaskPSMC`,
:class:`SlidingModeControl`, :class:`GravityCompensation`, :class:`AdmittancePSMC`;
sensors: :class:`SensorConfig`.  Flags: :class:`ControllerKind`, :class:`GCMode`,
:class:`PIDDerivative`, :class:`SMCCoupling`.

Inside, from the bottom up: :mod:`.reference` and :mod:`.kinds` (what a law reads and
which law runs), :mod:`.laws` (each controller's declared rows and compiled step),
:mod:`.dispatch` (the one compiled entry point over every kind, the buffer sizes),
:mod:`.base` (the :class:`Controller` object and its Python-level ``step``), then one
module per controller class.
"""

from .admittance import AdmittancePSMC
from .base import Controller
from .gravity import GravityCompensation
from .kinds import (KIND_ADMITTANCE, KIND_GC, KIND_PID, KIND_PSMC_JOINT, KIND_PSMC_TASK, KIND_SMC,
                    ControllerKind)
from .laws.gravity import GCMode
from .laws.pid import PIDDerivative
from .laws.smc import SMCCoupling
from .pid import PID
from .psmc import JointPSMC, TaskPSMC
from .sensors import SensorConfig
from .smc import SlidingModeControl

#: The controller class of every kind.
CONTROLLER_CLASSES = {KIND_GC: GravityCompensation, KIND_PID: PID,
                      KIND_PSMC_JOINT: JointPSMC, KIND_PSMC_TASK: TaskPSMC,
                      KIND_SMC: SlidingModeControl, KIND_ADMITTANCE: AdmittancePSMC}

__all__ = ["Controller", "ControllerKind", "CONTROLLER_CLASSES", "GravityCompensation", "GCMode",
           "PID", "PIDDerivative", "JointPSMC", "TaskPSMC", "SlidingModeControl", "SMCCoupling",
           "AdmittancePSMC", "SensorConfig"]
