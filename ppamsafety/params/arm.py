"""The complete arm parameter set: plant truth plus the controllers' model.

:func:`thesis_arm` assembles the cited sub-sets:

========================  ==============================================
field                     source
========================  ==============================================
geometry                  Tables 2.1, 2.2, eqs. (2.6)-(2.7)
muscles                   §2.3.3.1, Table B.1
valves                    Table B.2 + documented time constants
pneumatics                §3.3 + calibrated mean pressures (§6.3.3)
links (plant)             physically consistent reconciliation
model (controllers)       identified Table 3.5 (dynamic, with friction)
model_gravity             identified Table 3.1 (static gravity)
========================  ==============================================

The plant is what the simulator integrates; ``model`` and ``model_gravity``
are what the controllers believe (gravity compensation (3.18)-(3.19), the
sliding-mode controller's feedback linearisation).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

from .._validation import check_range
from .effects import Effects
from .geometry import ArmGeometry, thesis_geometry
from .inertia import (BaseParameters, LinkInertia, derive_physical_links, identified_dynamic,
                      identified_static_gravity)
from .muscles import MuscleSet, thesis_muscles
from .pneumatics import PneumaticParams, thesis_pneumatics
from .valves import ValveSet, thesis_valves


@dataclass(frozen=True)
class ArmParameters:
    """Everything needed to simulate the pneumatic arm.

    Attributes
    ----------
    geometry : ArmGeometry
    muscles : MuscleSet
    valves : ValveSet
    pneumatics : PneumaticParams
    links : LinkInertia
        Physical mass properties used by the plant.
    model : BaseParameters
        Identified dynamics used by model-based controllers.
    model_gravity : BaseParameters
        Identified gravity terms used by the static gravity compensation.
    gravity : float
        Gravitational acceleration along -y [m/s^2] (0 for a horizontal arm).
    friction_velocity : float
        Velocity scale of the smooth Coulomb friction c tanh(qdot/v_s)
        [rad/s].  A fixed-step integrator cannot resolve an ideal sign
        function; 0.01 rad/s is below the encoder velocity dead band
        (0.025 rad/s, §2.4.5.3).
    effects : Effects
        Optional plant effects (payload, truth-vs-model friction, valves,
        polytropic exponent), all off by default.  Read only by the plant
        truth row ``plant.layout.pack(arm)``, never by the controllers' views
        (see :mod:`ppamsafety.params.effects`).
    """

    geometry: ArmGeometry
    muscles: MuscleSet
    valves: ValveSet
    pneumatics: PneumaticParams
    links: LinkInertia
    model: BaseParameters
    model_gravity: BaseParameters
    gravity: float = 9.81
    friction_velocity: float = 0.01
    effects: Effects = Effects()

    def __post_init__(self):
        for name, cls in (("geometry", ArmGeometry), ("muscles", MuscleSet), ("valves", ValveSet),
                          ("pneumatics", PneumaticParams), ("links", LinkInertia),
                          ("model", BaseParameters), ("model_gravity", BaseParameters)):
            if not isinstance(getattr(self, name), cls):
                raise ValueError(f"ArmParameters.{name} must be a {cls.__name__}")
        check_range("ArmParameters.gravity", self.gravity, 0.0, 30.0, unit="m/s^2")
        check_range("ArmParameters.friction_velocity", self.friction_velocity, 1e-5, 1.0,
                    unit="rad/s")
        if not isinstance(self.effects, Effects):
            raise TypeError(f"ArmParameters.effects must be an Effects, got {self.effects!r}")

    def replace(self, **changes) -> "ArmParameters":
        """Return a copy with some fields changed (validated again)."""
        return replace(self, **changes)

    @property
    def plant_base(self) -> BaseParameters:
        """Base parameters (B.5) of the physical plant links."""
        return self.links.base_parameters(self.geometry.L1)


@lru_cache(maxsize=1)
def thesis_arm() -> ArmParameters:
    """The thesis arm with a physically consistent plant (see module doc)."""
    geometry = thesis_geometry()
    return ArmParameters(
        geometry=geometry, muscles=thesis_muscles(), valves=thesis_valves(),
        pneumatics=thesis_pneumatics(),
        links=derive_physical_links(L1=geometry.L1).links,
        model=identified_dynamic(), model_gravity=identified_static_gravity())


__all__ = ["ArmParameters", "thesis_arm"]
