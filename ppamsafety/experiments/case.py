"""A typed closed-loop experiment case: what :func:`~.closed_loop.run_batch` runs.

An :class:`ExperimentCase` names the plant, the controller, the reference,
the sensor models and optionally the initial state of one closed-loop run.
Every field is checked when the case is built, so a wrong argument fails
there, with the field's name, instead of deep inside the compiled kernel::

    >>> from ppamsafety.params import thesis_arm
    >>> from ppamsafety.control import PID
    >>> from ppamsafety.experiments import trajectories as tr
    >>> arm = thesis_arm()
    >>> case = ExperimentCase(arm, PID(), tr.step(arm, duration=3.0))
    >>> case.name
    'step'
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, fields
from typing import Mapping

import numpy as np

from ..control.base import Controller
from ..control.estimation import ForceEstimator
from ..control.sensors import SensorConfig
from ..params.arm import ArmParameters
from .._validation import as_float_array, check_range_array, check_shape
from ..plant.model import NX
from .interaction import Hand

#: Largest initial joint speed accepted in ``ExperimentCase.x0`` [rad/s] (well above the
#: < 5 rad/s of the thesis experiments; the closed loop counts 1000 rad/s as divergence).
X0_SPEED_MAX = 100.0
from .trajectories import Reference


def _type_error(name: str, value, allowed: str) -> TypeError:
    return TypeError(f"ExperimentCase.{name} must be {allowed}, got {type(value).__name__} "
                     f"{value!r:.80}")


@dataclass(frozen=True, eq=False)
class ExperimentCase:
    """One closed-loop experiment to run.

    Parameters
    ----------
    arm : ArmParameters
        The plant (and, through the controller, its model).
    controller : Controller
        PID, joint / task PSMC, SMC or gravity compensation.
    reference : Reference
        The reference trajectory; its length sets the run's length.
    sensors : SensorConfig, optional
        Encoder and velocity-sensor models (default
        ``SensorConfig.for_arm(arm)``: realistic encoders and timing board of
        the arm's sensor hardware).
    x0 : array_like, shape (8,), optional
        Initial plant state (q1, q2 [rad], qd1, qd2 [rad/s], p1..p4 [Pa]);
        default None: at rest at the reference's first joint angles.
        Angles within +-2 pi, speeds within +-100 rad/s, pressures in
        [0, p_max] (the muscles cannot hold a vacuum or exceed the supply).
    name : str, optional
        Experiment name (default: the reference's name).
    meta : mapping, optional
        Free-form metadata copied to ``ExperimentResult.meta``.
    external_force : array_like, shape (n, 2), optional
        Known external force on the TCP per control sample [N] (world frame,
        n = reference length), held over each period; the plant receives
        tau_ext = J^T(q) f (see :mod:`~.interaction`).  Default None: no
        force, the nominal arithmetic untouched.
    hand : Hand, optional
        A spring-damper hand pulling the TCP (added to ``external_force``).
    estimator : ForceEstimator, optional
        External-force estimators (RLS and momentum observer, §5.4.2) run in
        the loop; their estimates are logged (``Fx_rls`` ... ``Fy_mo``).
        Default None: none, unless the controller needs one (admittance),
        which then gets ``ForceEstimator()``.

    Raises
    ------
    TypeError
        For a field of the wrong type (the message names the field).
    ValueError
        For an ``x0``, ``external_force`` or ``hand`` of the wrong shape,
        with non-finite values or out of range.
    """

    arm: ArmParameters
    controller: Controller
    reference: Reference
    sensors: SensorConfig | None = None
    x0: np.ndarray | None = None
    name: str | None = None
    meta: dict = field(default_factory=dict)
    external_force: np.ndarray | None = None
    hand: Hand | None = None
    estimator: ForceEstimator | None = None

    def __post_init__(self):
        if not isinstance(self.arm, ArmParameters):
            raise _type_error("arm", self.arm, "an ArmParameters")
        if not isinstance(self.controller, Controller):
            raise _type_error("controller", self.controller, "a Controller (PID, JointPSMC, "
                              "TaskPSMC, SlidingModeControl, GravityCompensation)")
        if not isinstance(self.reference, Reference):
            raise _type_error("reference", self.reference, "a Reference")
        if self.sensors is None:
            object.__setattr__(self, "sensors", SensorConfig.for_arm(self.arm))
        elif not isinstance(self.sensors, SensorConfig):
            raise _type_error("sensors", self.sensors, "a SensorConfig")
        if self.x0 is not None:
            x0 = check_shape("ExperimentCase.x0", as_float_array(
                "ExperimentCase.x0", self.x0, allow_nonfinite=True), (NX,))
            if not np.all(np.isfinite(x0)):
                raise ValueError(f"ExperimentCase.x0 must be finite, got {x0.tolist()}")
            check_range_array("ExperimentCase.x0[0:2] (q1, q2)", x0[0:2], -2 * np.pi, 2 * np.pi,
                              unit="rad")
            check_range_array("ExperimentCase.x0[2:4] (qd1, qd2)", x0[2:4], -X0_SPEED_MAX,
                              X0_SPEED_MAX, unit="rad/s")
            check_range_array("ExperimentCase.x0[4:8] (p1..p4)", x0[4:8], 0.0,
                              self.arm.pneumatics.p_max, unit="Pa")
            x0 = np.array(x0)
            x0.setflags(write=False)
            object.__setattr__(self, "x0", x0)
        if self.name is None:
            object.__setattr__(self, "name", self.reference.name)
        elif not isinstance(self.name, str):
            raise _type_error("name", self.name, "a str or None")
        if self.meta is None:
            object.__setattr__(self, "meta", {})
        elif not isinstance(self.meta, Mapping):
            raise _type_error("meta", self.meta, "a mapping (dict)")
        else:
            object.__setattr__(self, "meta", dict(self.meta))
        n = self.reference.n_steps
        if self.external_force is not None:
            try:
                f = np.array(self.external_force, dtype=float)
            except (TypeError, ValueError):
                raise ValueError(f"ExperimentCase.external_force must be ({n}, 2) numbers [N], "
                                 f"got {self.external_force!r:.80}") from None
            if f.shape != (n, 2):
                raise ValueError(f"ExperimentCase.external_force must have shape ({n}, 2) (one "
                                 f"TCP force per reference sample), got shape {f.shape}")
            if not np.all(np.isfinite(f)):
                raise ValueError("ExperimentCase.external_force must be finite")
            f.setflags(write=False)
            object.__setattr__(self, "external_force", f)
        if self.hand is not None:
            if not isinstance(self.hand, Hand):
                raise _type_error("hand", self.hand, "a Hand or None")
            if len(self.hand) != n:
                raise ValueError(f"ExperimentCase.hand has {len(self.hand)} samples, the "
                                 f"reference {n}")
        if self.estimator is None:
            if getattr(self.controller, "needs_estimator", False):
                object.__setattr__(self, "estimator", ForceEstimator())
        elif not isinstance(self.estimator, ForceEstimator):
            raise _type_error("estimator", self.estimator, "a ForceEstimator or None")
        if self.estimator is not None:
            self.estimator.check_period(self.reference.dt)

    @property
    def has_external_input(self) -> bool:
        """True when a force profile or a hand acts on the TCP."""
        return self.external_force is not None or self.hand is not None

    @classmethod
    def from_dict(cls, case: Mapping) -> "ExperimentCase":
        """A case from the old dict form (keys = the field names).

        Parameters
        ----------
        case : mapping
            Keys ``arm``, ``controller``, ``reference`` (required),
            ``sensors``, ``x0``, ``name``, ``meta``, ``external_force``,
            ``hand``, ``estimator`` (optional).

        Raises
        ------
        ValueError
            For an unknown or a missing required key (named in the message).
        """
        if not isinstance(case, Mapping):
            raise TypeError(f"an experiment case must be an ExperimentCase (or, deprecated, a "
                            f"dict), got {type(case).__name__}")
        names = [f.name for f in fields(cls)]
        unknown = [k for k in case if k not in names]
        if unknown:
            raise ValueError(f"experiment case has unknown key(s) {unknown}; allowed: {names}")
        missing = [k for k in ("arm", "controller", "reference") if k not in case]
        if missing:
            raise ValueError(f"experiment case lacks the required key(s) {missing}")
        return cls(**case)


def as_cases(cases) -> list:
    """Cases given as :class:`ExperimentCase` s (or deprecated dicts) -> list of ExperimentCase.

    Parameters
    ----------
    cases : iterable of ExperimentCase or dict
        A dict is converted with :meth:`ExperimentCase.from_dict` (one
        ``DeprecationWarning`` per call).
    """
    out, warned = [], False
    for i, c in enumerate(cases):
        if isinstance(c, ExperimentCase):
            out.append(c)
            continue
        if isinstance(c, Mapping):
            if not warned:
                warnings.warn("run_batch: dict cases are deprecated; pass ExperimentCase objects "
                              "(ppamsafety.experiments.ExperimentCase)", DeprecationWarning,
                              stacklevel=3)
                warned = True
            out.append(ExperimentCase.from_dict(c))
            continue
        raise TypeError(f"cases[{i}] must be an ExperimentCase, got {type(c).__name__}")
    return out


__all__ = ["ExperimentCase", "as_cases"]
