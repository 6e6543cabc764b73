"""Named, cited, immutable parameter sets (validated on construction).

Arm files (TOML): ``ArmParameters.to_toml()`` / ``ArmParameters.from_toml()`` /
``ArmParameters.from_file()`` (the data checks); the format is
:mod:`ppamsafety.params.arm_file`.  Commands read a file with
:func:`ppamsafety.design.load_arm`, which adds the checks that need the arm's physics
(``ppamsafety.params.load_arm``, the former front door, makes the data checks only).
"""

from .arm import ArmParameters, is_thesis_arm, load_arm, thesis_arm
from .geometry import ArmGeometry, thesis_geometry
from .inertia import (BaseParameters, LinkInertia, derive_physical_links, identified_dynamic,
                      identified_static_gravity)
from .muscles import MuscleGroup, MuscleSet, thesis_muscles
from .pneumatics import PneumaticParams, thesis_pneumatics
from .sensors import SensorHardware, thesis_sensors
from .valves import Valve, ValveSet, thesis_valves

__all__ = ["ArmParameters", "thesis_arm", "is_thesis_arm", "load_arm", "SensorHardware", "thesis_sensors", "ArmGeometry", "thesis_geometry", "BaseParameters",
           "LinkInertia", "derive_physical_links", "identified_dynamic",
           "identified_static_gravity", "MuscleGroup", "MuscleSet", "thesis_muscles",
           "PneumaticParams", "thesis_pneumatics", "Valve", "ValveSet", "thesis_valves"]
