"""Named, cited, immutable parameter sets (validated on construction)."""

from .arm import ArmParameters, thesis_arm
from .geometry import ArmGeometry, thesis_geometry
from .inertia import (BaseParameters, LinkInertia, derive_physical_links, identified_dynamic,
                      identified_static_gravity)
from .muscles import MuscleGroup, MuscleSet, thesis_muscles
from .pneumatics import PneumaticParams, thesis_pneumatics
from .valves import Valve, ValveSet, thesis_valves

__all__ = ["ArmParameters", "thesis_arm", "ArmGeometry", "thesis_geometry", "BaseParameters",
           "LinkInertia", "derive_physical_links", "identified_dynamic",
           "identified_static_gravity", "MuscleGroup", "MuscleSet", "thesis_muscles",
           "PneumaticParams", "thesis_pneumatics", "Valve", "ValveSet", "thesis_valves"]
