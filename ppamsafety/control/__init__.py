"""Discrete-time controllers (1 kHz) and sensor models.

Controllers: :class:`PID`, :class:`JointPSMC`, :class:`TaskPSMC`,
:class:`SlidingModeControl`, :class:`GravityCompensation`; sensors:
:class:`SensorConfig`.  Flags: :class:`ControllerKind`, :class:`GCMode`,
:class:`PIDDerivative`, :class:`SMCCoupling`.
"""

from .base import Controller, ControllerKind
from .gravity import GCMode, GravityCompensation
from .pid import PID, PIDDerivative
from .psmc import JointPSMC, TaskPSMC
from .sensors import SensorConfig
from .smc import SlidingModeControl, SMCCoupling

__all__ = ["Controller", "ControllerKind", "GravityCompensation", "GCMode", "PID",
           "PIDDerivative", "JointPSMC", "TaskPSMC", "SlidingModeControl", "SMCCoupling",
           "SensorConfig"]
