"""Optional plant effects: where the simulated truth differs from the nominal arm.

:class:`Effects` collects the optional, cited deviations of the *plant* (the
arm the simulator integrates) from the nominal parameter set that the
controllers believe in.  Every field defaults to "off" (``0`` for the payload,
``None`` for an override = use the nominal value), and with every effect off
the packed plant row is bitwise the nominal one.

Which view sees what
--------------------
``ArmParameters.effects`` is read by exactly one function,
:func:`ppamsafety.plant.packing.pack` *without* a ``dynamics`` argument -- the
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
hysteresis_delta         hysteresis_* and the effect state z    §3.6, (3.31)-(3.35);
                         (Preisach memory per muscle group)     delta in [0, 1]
hysteresis_initial       hysteresis_initial (memory rows)       §3.6.6: "negative"
valve_dead_time          dead_time_* and a delay line in z      §4.2.4; [0, 100] periods
joint_torque_bias        torque_bias_* (read by plant_rhs and   a constant disturbance
                         the static equilibria)                 torque; [-20, 20] N m
=======================  =====================================  ==========================

Each field is declared with its :class:`EffectKind` (how it reaches the simulation:
folded into parameters, read by the kernels, with state, or an option of another effect)
and, where the diagnosis fits it to summary statistics, its :class:`MagnitudeAxis`.

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

Muscle hysteresis (thesis §3.6).  The thesis model omits the hysteresis of
the PPAM force-contraction characteristic (§3.6.1, figs. 3.7-3.9); its
static validation (§3.5.1.6, figs. 3.1-3.2) shows the consequence: with
gravity compensation, rising angles settle below and falling angles above
their set points.  With ``hysteresis_delta`` set, the plant's muscle force of
group k becomes (3.35)::

    F_k = p_k l0^2 f_fit,k(eps_k) (1 + delta_k (W_k[eps_s,k] - W_fit(eps_s,k)))
    eps_s = 2 eps / eps_max - 1,   eps_max = 0.35                       (3.34)

with W the Preisach operator of weight (3.33) (c = -0.1, d = -1,
:mod:`ppamsafety.hysteresis`), one memory per muscle group, and W_fit its
least-squares line through the major loop (fig. 3.12).  *Identification of
f_fit*: the thesis writes f_t0^fit, the least-squares fit of the measured
force function of one muscle at 1.5 bar; in this plant f_fit,k is the
identified force polynomial of group k (Table B.1, (3.9)), i.e. the
"average" model the controllers also use, which is exactly the role (3.31)
gives f_t0^fit (the hysteresis-free least-squares fit the error e[eps] is
measured against).  delta: 0.139 for the arm's 25-fibre muscles (§3.6.5,
fitted at 1.5 bar, :data:`~ppamsafety.hysteresis.DELTA_25_FIBRES`), 0.299 for
the 40-fibre test muscle.  Range [0, 1]: any Preisach output stays inside the
major loop, where |W - W_fit| <= 0.32 (measured on 2000 samples), so the
factor stays >= 0.68 > 0.  ``hysteresis_initial`` is the memory at t = 0:
``"negative"`` (default: negative saturation, the muscle brought to its
smallest contraction first, as the thesis requires, §3.6.6),
``"positive"``, or per group a past input history (see :class:`Effects`).  The factor multiplies only the muscle forces in the
joint torques, not the volume derivative dV/dq = m_tau of the pressure
dynamics (geometric, (3.5)); see :mod:`ppamsafety.plant.model`.

Valve dead time.  A transport delay of the set value by a whole number of
control periods per valve (the plant sees u_i[k - d_i]); delays in the
control switching are the cause of chattering (§4.2.4, fig. 4.5).  Range
[0, 100] periods (0.1 s at 1 kHz, far above any proportional valve's
response delay: a typo guard).  Before t = 0 the valves are taken to have
received the first set value (the arm was at rest with it).

Not here: sensor faults (encoder and pressure-sensor offsets and gains) are
errors of the measurement, not of the plant; they live in
:class:`ppamsafety.control.sensors.SensorConfig`.
"""

from __future__ import annotations

import math
import enum
from dataclasses import dataclass, field, fields, replace

import numpy as np

from .._validation import check_int, check_range
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
#: Range of the hysteresis scale delta of (3.35) (see the module docstring).
HYSTERESIS_DELTA_RANGE = (0.0, 1.0)
#: Largest valve dead time [control periods] (typo guard, see the module docstring).
VALVE_DEAD_TIME_MAX = 100
#: Largest |constant joint torque| of ``Effects.joint_torque_bias`` [N m]: about twice the
#: gravity torque of the thesis arm's shoulder at full reach (a typo guard, not physics).
JOINT_TORQUE_BIAS_MAX = 20.0
#: Named initial Preisach memories (§3.6.6; :func:`ppamsafety.hysteresis.initial_memory`).
HYSTERESIS_INITIAL_NAMES = ("negative", "positive")


def _history(name, value):
    """A validated past-input history of the scaled contraction (tuple of floats)."""
    try:
        h = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a sequence of numbers, got {value!r}") from None
    if h.ndim != 1 or h.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D history, got shape {h.shape}")
    if not np.all(np.isfinite(h)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if h.min() < -1.0 or h.max() > 1.0:
        raise ValueError(f"{name} must lie in [-1, 1], got values in [{h.min():g}, {h.max():g}]")
    if h[0] not in (-1.0, 1.0):
        raise ValueError(f"{name} must start at a saturation value -1 or +1, got {h[0]!r}")
    return tuple(float(v) for v in h)


def _hysteresis_initial(value):
    """Normalise ``Effects.hysteresis_initial``: a name or 4 histories (tuple of tuples)."""
    name = "Effects.hysteresis_initial"
    if isinstance(value, str):
        if value not in HYSTERESIS_INITIAL_NAMES:
            raise ValueError(f"{name} = {value!r} is not one of {HYSTERESIS_INITIAL_NAMES} "
                             f"or past-input histories")
        return value
    if not hasattr(value, "__len__"):
        raise TypeError(f"{name} must be 'negative', 'positive' or a sequence, got {value!r}")
    items = list(value)
    if items and all(isinstance(v, (int, float, np.number)) for v in items):
        h = _history(name, items)               # one history for all four groups
        return (h,) * 4
    if len(items) != 4:
        raise ValueError(f"{name} must give one history for all groups or "
                         f"one per muscle group (4), got {len(items)} entries")
    return tuple(_history(f"{name}[{k}]", v) for k, v in enumerate(items))


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


class EffectKind(enum.Enum):
    """How an effect reaches the simulation: what adding one of its kind touches.

    ``docs/architecture.md`` has a recipe ("files you will touch") per kind.
    """

    #: Folded into the plant row's *parameters* when the arm is packed (payload into theta,
    #: an override of friction, valves, polytropic exponent); the kernels are untouched.
    PARAMETER = "parameter"
    #: Stateless, read by the kernels at every evaluation from the row's effect section
    #: (the joint torque bias).
    KERNEL = "kernel"
    #: Carries memory between steps in the effect state z (hysteresis, valve dead time).
    STATE = "state"
    #: Not an effect: an option of another one (``Effects.option_of(name)``).
    OPTION = "option"


@dataclass(frozen=True)
class MagnitudeAxis:
    """An effect's magnitude axis theta in [0, 1], from the nominal plant to its largest
    plausible magnitude (the fit of effects to summary statistics,
    :mod:`ppamsafety.thesis_fits.summary_fit`).

    Attributes
    ----------
    name : str
        Axis name: the ``Effects`` field, or its relative form (``friction_coulomb_factor``:
        a multiple of the nominal value; ``valve_offset_delta``: an offset added to it),
        as :func:`ppamsafety.diagnose.arm.synthesize.plant_with` reads it.
    unit : str
        Unit of the physical magnitude.
    nominal, full : float
        Physical magnitude at theta = 0 and theta = 1.
    reason : str
        Why ``full`` is the largest plausible magnitude.
    """

    name: str
    unit: str
    nominal: float
    full: float
    reason: str

    def value(self, theta: float) -> float:
        """Physical magnitude at ``theta``.

        Parameters
        ----------
        theta : float
            Position on the axis, in [0, 1].

        Returns
        -------
        float
        """
        return self.nominal + theta * (self.full - self.nominal)


def _effect(default, kind: EffectKind, *, length: int = 1, unit: str = "", axis=None,
            option_of: str | None = None):
    """A field of :class:`Effects` with what the rest of the toolkit reads about it."""
    return field(default=default, metadata={"kind": kind, "length": length, "unit": unit,
                                            "axis": axis, "option_of": option_of})


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
    hysteresis_delta : tuple of 4 float or None
        Scale delta_k of the muscle force hysteresis (3.35) per muscle group,
        in [0, 1] [-]; None = no hysteresis.  Thesis: 0.139 for the arm's
        25-fibre muscles (``(DELTA_25_FIBRES,) * 4``), 0.299 for 40 fibres.
    hysteresis_initial : str or sequence
        Preisach memory of each group at t = 0 (only used with
        ``hysteresis_delta``): ``"negative"`` (default, negative saturation,
        §3.6.6), ``"positive"``, one past-input history of the scaled
        contraction eps_s (a sequence in [-1, 1] starting at -1 or +1, e.g.
        ``(-1, 0.3, -0.2)``) for all groups, or four such histories, one per
        group (a saved memory row becomes a history with
        :func:`ppamsafety.hysteresis.memory.history_of_memory`).  Stored as four tuples.
    hysteresis_exact_stages : bool
        Evaluate the Preisach output exactly (``preisach_peek``) in every
        RK4 stage instead of by the secant of the last step (default False:
        4x fewer Everett evaluations, error O(h^2) in the stage forces; see
        :mod:`ppamsafety.plant.model`).  For checks of the fast scheme.
    valve_dead_time : tuple of 4 int or None
        Transport delay of the set value of each valve, in whole control
        periods (input samples of ``plant.model.simulate``), in [0, 100];
        None = no dead time.
    joint_torque_bias : tuple of 2 float or None
        A constant joint torque per joint [N m], in [-20, 20], added to the muscle
        torques of the plant (a disturbance the model lacks: a cable's drag, a spring,
        an offset load); the static equilibria of the plant truth include it.  None =
        none.

    Every field carries its :class:`EffectKind` (``Effects.kind(name)``), its length, its
    unit and, where the diagnosis fits it to summary statistics, its
    :class:`MagnitudeAxis` (``Effects.axes()``).
    """

    payload_mass: float = _effect(0.0, EffectKind.PARAMETER, unit="kg", axis=MagnitudeAxis(
        "payload_mass", "kg", 0.0, 1.0, "an object of up to 1 kg held at A_L (the arm holds "
        "~2 kg, §2.3.3.5)"))
    friction_coulomb: tuple | None = _effect(None, EffectKind.PARAMETER, length=2, unit="N m",
                                             axis=MagnitudeAxis(
        "friction_coulomb_factor", "x nominal", 1.0, 10.0, "Coulomb friction up to 10x "
        "Table 3.5 (a worn or over-tightened bearing)"))
    friction_viscous: tuple | None = _effect(None, EffectKind.PARAMETER, length=2,
                                             unit="N m s/rad", axis=MagnitudeAxis(
        "friction_viscous_factor", "x nominal", 1.0, 4.0, "viscous friction up to 4x "
        "Table 3.5"))
    valve_offset: tuple | None = _effect(None, EffectKind.PARAMETER, length=4, unit="Pa",
                                         axis=MagnitudeAxis(
        "valve_offset_delta", "Pa", 0.0, 10000.0, "static valve offset +0.1 bar on every "
        "valve, the deviations 'as high as 0.1 bar' of §3.5.1.2"))
    valve_gain: tuple | None = _effect(None, EffectKind.PARAMETER, length=4, axis=MagnitudeAxis(
        "valve_gain_factor", "x nominal", 1.0, 0.7, "static valve gain down to 0.7x "
        "(inside the 0.5-1.5 range of Effects)"))
    valve_time_constant: tuple | None = _effect(None, EffectKind.PARAMETER, length=4, unit="s",
                                                axis=MagnitudeAxis(
        "valve_time_constant_factor", "x nominal", 1.0, 3.0, "valve time constant up to 3x "
        "(45/60 ms -> 135/180 ms: a long tube, a slow valve)"))
    polytropic_n: float | None = _effect(None, EffectKind.PARAMETER, axis=MagnitudeAxis(
        "polytropic_n", "-", 1.4, 1.0, "isentropic -> isothermal (§3.3)"))
    hysteresis_delta: tuple | None = _effect(None, EffectKind.STATE, length=4,
                                             axis=MagnitudeAxis(
        "hysteresis_delta", "-", 0.0, 0.3, "muscle hysteresis up to the 40-fibre value "
        "0.299 (§3.6.5; 25 fibres: 0.139)"))
    hysteresis_initial: object = _effect("negative", EffectKind.OPTION,
                                         option_of="hysteresis_delta")
    hysteresis_exact_stages: bool = _effect(False, EffectKind.OPTION,
                                            option_of="hysteresis_delta")
    valve_dead_time: tuple | None = _effect(None, EffectKind.STATE, length=4,
                                            unit="control periods", axis=MagnitudeAxis(
        "valve_dead_time", "s", 0.0, 0.03, "transport delay up to 30 ms (three 10 ms "
        "fieldbus frames, §4.2.4)"))
    # no magnitude axis: the Table 5.2 fit (diagnose_cases) covers the effects it covered
    # when the bias was added; a bias would need an axis of its own there
    joint_torque_bias: tuple | None = _effect(None, EffectKind.KERNEL, length=2, unit="N m")

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
        object.__setattr__(self, "hysteresis_delta", _vector(
            "hysteresis_delta", self.hysteresis_delta, 4,
            lambda n, v: check_range(n, v, *HYSTERESIS_DELTA_RANGE)))
        object.__setattr__(self, "hysteresis_initial",
                           _hysteresis_initial(self.hysteresis_initial))
        if not isinstance(self.hysteresis_exact_stages, (bool, np.bool_)):
            raise TypeError(f"Effects.hysteresis_exact_stages must be a bool, "
                            f"got {self.hysteresis_exact_stages!r}")
        object.__setattr__(self, "valve_dead_time", _vector(
            "valve_dead_time", self.valve_dead_time, 4,
            lambda n, v: check_int(n, v, 0, VALVE_DEAD_TIME_MAX)))
        object.__setattr__(self, "joint_torque_bias", _vector(
            "joint_torque_bias", self.joint_torque_bias, 2,
            lambda n, v: check_range(n, v, -JOINT_TORQUE_BIAS_MAX, JOINT_TORQUE_BIAS_MAX,
                                     unit="N m")))

    @property
    def hysteresis(self) -> bool:
        """True if the muscle force hysteresis (3.35) is on."""
        return self.hysteresis_delta is not None

    @property
    def any(self) -> bool:
        """True if at least one effect is on."""
        return bool(self.enabled())

    def enabled(self) -> tuple:
        """Names of the effects that are on (fields differing from the default).

        Options (:attr:`EffectKind.OPTION`, e.g. ``hysteresis_initial``) are not
        effects: they are never listed (and are ignored while their effect is off).
        """
        off = Effects()
        return tuple(f for f in self.names() if getattr(self, f) != getattr(off, f))

    @classmethod
    def names(cls, kind: EffectKind | None = None) -> tuple:
        """The effect fields, in declaration order: all (no options), or those of ``kind``.

        Parameters
        ----------
        kind : EffectKind, optional
            Only the effects of this kind (``EffectKind.OPTION``: the options).

        Returns
        -------
        tuple of str
        """
        if kind is not None and not isinstance(kind, EffectKind):
            raise TypeError(f"kind must be an EffectKind or None, got {kind!r}")
        return tuple(f.name for f in fields(cls)
                     if (f.metadata["kind"] is not EffectKind.OPTION if kind is None
                         else f.metadata["kind"] is kind))

    @classmethod
    def kind(cls, name: str) -> EffectKind:
        """The :class:`EffectKind` of field ``name``.

        Parameters
        ----------
        name : str
            A field of :class:`Effects`.

        Returns
        -------
        EffectKind
        """
        return cls._field(name).metadata["kind"]

    @classmethod
    def length(cls, name: str) -> int:
        """Number of values of field ``name`` (1 for a scalar, 2 per joint, 4 per group).

        Parameters
        ----------
        name : str
            A field of :class:`Effects`.

        Returns
        -------
        int
        """
        return cls._field(name).metadata["length"]

    @classmethod
    def option_of(cls, name: str) -> str | None:
        """The effect that option ``name`` belongs to (None for an effect).

        Parameters
        ----------
        name : str
            A field of :class:`Effects`.

        Returns
        -------
        str or None
        """
        return cls._field(name).metadata["option_of"]

    @classmethod
    def axis(cls, name: str):
        """The :class:`MagnitudeAxis` field ``name`` declares, or None.

        Parameters
        ----------
        name : str
            A field of :class:`Effects`.

        Returns
        -------
        MagnitudeAxis or None
        """
        return cls._field(name).metadata["axis"]

    @classmethod
    def axes(cls) -> tuple:
        """The :class:`MagnitudeAxis` of every effect that has one, in declaration order.

        Returns
        -------
        tuple of MagnitudeAxis
        """
        return tuple(f.metadata["axis"] for f in fields(cls) if f.metadata["axis"] is not None)

    @classmethod
    def _field(cls, name):
        for f in fields(cls):
            if f.name == name:
                return f
        raise ValueError(f"unknown effect {name!r}; Effects fields: "
                         f"{[f.name for f in fields(cls)]}")

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


__all__ = ["Effects", "EffectKind", "MagnitudeAxis", "JOINT_TORQUE_BIAS_MAX", "PAYLOAD_MASS_MAX", "FRICTION_MAX", "VALVE_OFFSET_MAX",
           "VALVE_GAIN_RANGE", "VALVE_TIME_CONSTANT_MIN", "VALVE_TIME_CONSTANT_MAX",
           "POLYTROPIC_RANGE", "HYSTERESIS_DELTA_RANGE", "HYSTERESIS_INITIAL_NAMES",
           "VALVE_DEAD_TIME_MAX"]
