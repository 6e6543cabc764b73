"""Discrete-time controllers (1 kHz) and sensor models.

Controllers: :class:`PID`, :class:`JointPSMC`, :class:`TaskPSMC`,
:class:`SlidingModeControl`, :class:`GravityCompensation`; sensors:
:class:`SensorConfig`.
"""

from .base import Controller
from .gravity import GravityCompensation
from .pid import PID
from .psmc import JointPSMC, TaskPSMC
from .sensors import SensorConfig
from .smc import SlidingModeControl

__all__ = ["Controller", "GravityCompensation", "PID", "JointPSMC", "TaskPSMC",
           "SlidingModeControl", "SensorConfig"]
