"""Optional plant effects: where the simulated truth differs from the nominal arm.

:class:`Effects` collects the optional, cited deviations of the *plant* (the
arm the simulator integrates) from the nominal parameter set that the
controllers believe in.  Every field defaults to "off" (``0`` for the payload,
``None`` for an override = use the nominal value), and with every effect off
the packed plant row is bitwise the nominal one.

Which view sees what
--------------------
``ArmParameters.effects`` is read by exactly one function,
:func:`ppamsafety.plant.layout.pack` *without* a ``dynamics`` argument -- the
**plant truth** row that the simulators integrate (``plant.model.simulate``,
the closed loop, the impact models) and that the plant-level NumPy helpers
(``plant.dynamics.inertia_matrix(q, arm)``, ``plant.model.rest_state`` ...)
evaluate.  Every *belief* row -- ``pack(arm, dynamics)`` with explicit
rigid-body parameters, i.e. ``controller_view`` (Table 3.1 gravity model),
``model_view`` (Table 3.5) and the controllers' own rows -- and every Python
read of ``arm.valves`` / ``arm.pneumatics`` / ``arm.model`` keeps the
nominal values.  So with an effect on, the plant deviates from what the
controllers know, as a real arm deviates from its identified model.

=======================  =====================================  ==========================
field                    plant row slots it changes             source / allowed range
=======================  =====================================  ==========================
payload_mass             theta1, theta3..theta6 (B.5)           point mass M at A_L, §2.3.3.5
                                                                (2.19); [0, 5] kg
friction_coulomb         coulomb (3.30)                         Table 3.5; [0, 10] N m
friction_viscous         viscous (3.30)                         Table 3.5; [0, 10] N m s/rad
valve_offset             v1 (3.12)                              §3.5.1.2, Table B.2;
                                                                [-0.5, 0.5] bar
valve_gain               v2 (3.12)                              Table B.2; [0.5, 1.5]
valve_time_constant      tv (3.2)                               §3.5.2; [1 ms, 10 s] or inf
polytropic_n             n_poly (3.3)                           §3.3: [1, 1.4]
=======================  =====================================  ==========================

Ranges.  Payload: the arm holds about 2 kg everywhere in its working area
and more away from its edges (§2.3.3.5, fig. 2.15); 5 kg, twice its own mass
(~2.5 kg), bounds what it could hold anywhere.  Valve offset and gain: the
ranges of :class:`~ppamsafety.params.valves.Valve` (deviations "as high as
0.1 bar" are common, §3.5.1.2).  Valve time constant: at least 1 ms, the
1 kHz control period -- the thesis chose that period because "very fast
sampling times are useless because of the slow dynamics of the pneumatic
valves" (§2.4.1), so a faster valve is outside the modelled physics;
``math.inf`` is a closed valve as in ``Valve``.  The integrator adds its own
bound: :func:`ppamsafety.plant.model.simulate` rejects a row whose valve time
constant is below its RK4 step ``h = dt/substeps`` (h/T <= 1 keeps the valve
lag well inside RK4's stability interval h/T < 2.78 and accurate to about 2 %
per step).  Polytropic exponent: between isothermal (n = 1) and isentropic
(n = 1.4 for dry air, §3.3 after (3.3)).  Friction: non-negative (a
dissipative model, (3.30)); 10 N m / 10 N m s/rad are far above the
identified c = (0.030, 0.071) N m, b = (0.83, 0.004) N m s/rad (Table 3.5)
and bound typos, not physics.

Not here (they need the closed-loop runner, or the Preisach operator): valve
dead time, sensor faults, muscle hysteresis (3.35).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from .._validation import check_range
from ..units import BAR

#: Payload mass range [kg] (§2.3.3.5, see the module docstring).
PAYLOAD_MASS_MAX = 5.0
#: Friction coefficient upper bounds (N m, N m s/rad); typo guards, see the module docstring.
FRICTION_MAX = 10.0
#: Valve offset range [Pa] (as :class:`~ppamsafety.params.valves.Valve`).
VALVE_OFFSET_MAX = 0.5 * BAR
#: Valve gain range [-] (as :class:`~ppamsafety.params.valves.Valve`).
VALVE_GAIN_RANGE = (0.5, 1.5)
#: Smallest valve time constant [s]: the 1 kHz control period (§2.4.1).
VALVE_TIME_CONSTANT_MIN = 1e-3
#: Largest finite valve time constant [s] (as ``Valve``).
VALVE_TIME_CONSTANT_MAX = 10.0
#: Polytropic exponent range: isothermal .. isentropic (§3.3).
POLYTROPIC_RANGE = (1.0, 1.4)


def _vector(name, value, n, check):
    """``None`` or a tuple of ``n`` validated floats."""
    if value is None:
        return None
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__"):
        raise TypeError(f"Effects.{name} must be None or a sequence of {n} numbers, "
                        f"got {value!r}")
    if len(value) != n:
        raise ValueError(f"Effects.{name} must have {n} entries, got {len(value)}: {value!r}")
    return tuple(check(f"Effects.{name}[{i}]", v) for i, v in enumerate(value))


@dataclass(frozen=True)
class Effects:
    """Optional plant effects, all off by default (see the module docstring).

    Attributes
    ----------
    payload_mass : float
        Point mass M at the load point A_L (Table 2.2: L_L = 300 mm along,
        d_L = 30 mm perpendicular to link 2, (A.21)) [kg]; 0 = no payload.
        Folded into the plant's base parameters (B.5) at pack time.
    friction_coulomb : tuple of 2 float or None
        Plant Coulomb friction c_j (3.30) [N m]; None = ``arm.links.coulomb``.
    friction_viscous : tuple of 2 float or None
        Plant viscous friction b_j (3.30) [N m s/rad]; None = ``arm.links.viscous``.
    valve_offset : tuple of 4 float or None
        Plant static valve offsets v1_i (3.12) [Pa]; None = ``arm.valves``.
    valve_gain : tuple of 4 float or None
        Plant static valve gains v2_i (3.12) [-]; None = ``arm.valves``.
    valve_time_constant : tuple of 4 float or None
        Plant valve time constants T_i (3.2) [s] (``math.inf``: closed);
        None = ``arm.valves``.
    polytropic_n : float or None
        Plant polytropic exponent n (3.3) [-]; None = ``arm.pneumatics``.
    """

    payload_mass: float = 0.0
    friction_coulomb: tuple | None = None
    friction_viscous: tuple | None = None
    valve_offset: tuple | None = None
    valve_gain: tuple | None = None
    valve_time_constant: tuple | None = None
    polytropic_n: float | None = None

    def __post_init__(self):
        def fric(unit):
            return lambda n, v: check_range(n, v, 0.0, FRICTION_MAX, unit=unit)

        def lag(n, v):
            if isinstance(v, (int, float)) and not isinstance(v, bool) and v == math.inf:
                return math.inf
            return check_range(n, v, VALVE_TIME_CONSTANT_MIN, VALVE_TIME_CONSTANT_MAX, unit="s")

        if isinstance(self.payload_mass, bool):
            raise TypeError(f"Effects.payload_mass must be a number [kg], got {self.payload_mass!r}")
        object.__setattr__(self, "payload_mass", check_range(
            "Effects.payload_mass", self.payload_mass, 0.0, PAYLOAD_MASS_MAX, unit="kg"))
        for name, n, check in (
                ("friction_coulomb", 2, fric("N m")), ("friction_viscous", 2, fric("N m s/rad")),
                ("valve_offset", 4, lambda n_, v: check_range(
                    n_, v, -VALVE_OFFSET_MAX, VALVE_OFFSET_MAX, unit="Pa")),
                ("valve_gain", 4, lambda n_, v: check_range(n_, v, *VALVE_GAIN_RANGE)),
                ("valve_time_constant", 4, lag)):
            object.__setattr__(self, name, _vector(name, getattr(self, name), n, check))
        if self.polytropic_n is not None:
            if isinstance(self.polytropic_n, bool):
                raise TypeError(f"Effects.polytropic_n must be None or a number, "
                                f"got {self.polytropic_n!r}")
            object.__setattr__(self, "polytropic_n", check_range(
                "Effects.polytropic_n", self.polytropic_n, *POLYTROPIC_RANGE))

    @property
    def any(self) -> bool:
        """True if at least one effect is on."""
        return self != Effects()

    def enabled(self) -> tuple:
        """Names of the effects that are on (fields differing from the default)."""
        off = Effects()
        return tuple(f for f in self.__dataclass_fields__ if getattr(self, f) != getattr(off, f))

    def replace(self, **changes) -> "Effects":
        """Return a copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            New values of fields of :class:`Effects`, by field name (as for
            :func:`dataclasses.replace`); the copy is checked like a newly
            constructed object.
        """
        return replace(self, **changes)


__all__ = ["Effects", "PAYLOAD_MASS_MAX", "FRICTION_MAX", "VALVE_OFFSET_MAX",
           "VALVE_GAIN_RANGE", "VALVE_TIME_CONSTANT_MIN", "VALVE_TIME_CONSTANT_MAX",
           "POLYTROPIC_RANGE"]
