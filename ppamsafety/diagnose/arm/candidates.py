"""The library of candidate effects: what each one is, its parameters, its signature, its fit.

Each :class:`Candidate` is one physical effect the model may be missing,
with a fixed name from :data:`VOCABULARY` (the ``name`` written in
``diagnosis.json``), its parameters (unit, bounds, meaning), the signature
it leaves (which subsystem residual of :mod:`ppamsafety.diagnose.arm.residuals`
it shows in, and the operating-region pattern), and a **model extension**
fitted by regression: either directions in the model vector mu (the
extension is ``mu = mu0 + D phi``, so the block residual changes by
``X D phi``, linear in phi) or a profiled grid parameter (dead time) that
changes X itself.  Every extension maps back to a plant row
(:func:`ppamsafety.diagnose.arm.residuals.row_from_mu`) so that its effect on
the full simulation can be shown by a batched rollout.

Adding a candidate = one :func:`register` call of one object (see the entries
at the end of this module): besides its parameters and columns it carries
its battery draw (``draw``; ``declare`` for an arm that declares it), the
gates it needs and the experiments that separate it from its look-alikes
(:class:`ppamsafety.diagnose.core.candidate.Candidate`), which the battery
(:mod:`ppamsafety.diagnose.scenarios`) and :func:`separating_experiment` read.
An effect that is not a direction of mu (hysteresis) brings its own
regression columns, built with the block system (``Candidate.columns``).

Arm library (open/closed-loop arm records)
------------------------------------------
=====================  ==========  =================================================
name                   subsystem   parameters
=====================  ==========  =================================================
valve_offset_gain      pressure    v1_1..v1_4 [Pa], v2_1..v2_4 [-]  (3.12)
valve_lag              pressure    T_1..T_4 [s]  (3.2)
valve_dead_time        pressure    d [s], common to the four valves (or the change
                                   of the declared one per valve)
polytropic_exponent    pressure    n [-]  (3.3)
joint_friction         torque      c1, c2 [N m], b1, b2 [N m s/rad]  (3.30)
payload                torque      M [kg] at the load point A_L (2.19), (A.21)
hysteresis             torque      delta [-] (3.35), shared by the 4 groups
joint_torque_bias      torque      b1, b2 [N m]: a constant torque per joint
pressure_sensor_offset both        o_1..o_4 [Pa]: p_m = (1 + g) p + o, per channel
pressure_sensor_gain   both        g_1..g_4 [-]
encoder_offset         both        o_q1, o_q2 [rad]: q_m = q + o, per joint
=====================  ==========  =================================================

Sensor faults (the last three) are the first thing an experimenter checks.  They are
columns of their own (:func:`ppamsafety.diagnose.arm.residuals.sensor_columns`,
:func:`~ppamsafety.diagnose.arm.residuals.encoder_columns`) and show in *both*
subsystems, which is what tells them from a plant effect: a pressure-sensor offset looks
like a valve offset in the pressure residual, but also gives a torque error proportional
to the muscle's lever arm; a valve offset gives none.  Where a record cannot tell a fault
from a plant effect, the selection reports them as confounded
(:mod:`ppamsafety.diagnose.arm.selection`) with the experiment that separates them
(:data:`SEPARATING_EXPERIMENTS`).

Every parameter has a plausible range (the naming rule's bounds) and a physical range
(``Parameter.phys_lo``/``phys_hi``: a fit outside it is a symptom, not an effect).

Declared effects.  The nominal model is the arm under test with its declared
``[effects]`` (:mod:`ppamsafety.diagnose.arm.residuals`).  A candidate's
coefficients are the *change* from the declared value, and its reported
parameters are absolute with the declared value as ``nominal``
(:meth:`Candidate.values`): a declared delta of 0.3 fitted to 0.2 reports
``delta = 0.2`` (nominal 0.3); friction on top of a declared friction reports
the total; a dead time other than the declared one reports the new dead time.
A candidate is therefore named only where the record asks for a change from
the declared value.  With four declared deltas that differ, the hysteresis
candidate changes them by one common amount and reports their mean.

Names on a tester (actuator records) have their own vocabulary and library:
:mod:`ppamsafety.diagnose.bench.candidates`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...params import thesis_arm
from ...params.effects import Effects
from ...plant.packing import payload_theta
from ..core.battery import logu, sgn
from ..core.candidate import Candidate as CoreCandidate
from ..core.candidate import Library, register_library
from ..core.parameter import Parameter
from .residuals import (ENCODER_OFFSET_COLUMNS, HYSTERESIS_COLUMNS, MU_A, MU_B, MU_COUL, MU_K,
                        MU_N, MU_THETA, MU_VISC, NMU, PRESSURE_GAIN_COLUMNS,
                        PRESSURE_OFFSET_COLUMNS, TORQUE_BIAS_COLUMNS, declared_delays,
                        declared_hysteresis, declared_torque_bias)
from .synthesize import plant_vector

#: Fixed vocabulary of effect names on an arm (the ``name`` field of ``diagnosis.json``).
VOCABULARY = ("hysteresis", "joint_friction", "valve_offset_gain", "valve_lag",
              "valve_dead_time", "payload", "polytropic_exponent", "joint_torque_bias",
              "pressure_sensor_offset", "pressure_sensor_gain", "encoder_offset")
#: The sensor faults of the library: not plant effects but errors of the measurement.
SENSOR_FAULTS = ("pressure_sensor_offset", "pressure_sensor_gain", "encoder_offset")
#: Largest valve dead time searched [s] (the grid is every sample up to it).
DEAD_TIME_MAX = 0.06


@dataclass(frozen=True, eq=False)
class Candidate(CoreCandidate):
    """A candidate effect of an arm record (see the module docstring): what every kind's
    candidate carries (:class:`~ppamsafety.diagnose.core.candidate.Candidate`: its name, its
    battery ``draw``, the gates it ``needs``, its ``separating`` experiments) and the arm's
    own fields.

    Attributes
    ----------
    name : str
        From :data:`VOCABULARY`.
    subsystem : str
        ``"pressure"`` or ``"torque"``: the block-residual channels it changes.
    parameters : tuple of Parameter
        Reported parameters (physical).
    signature : str
        Where and how it shows (for the report and the reviewer).
    directions : callable or None
        ``directions(mu0, arm) -> (NMU, k)``: the directions of mu it frees.
    physical : callable
        ``physical(mu, phi, shift_seconds) -> (len(parameters),)``: the
        reported values from the fitted model vector, this candidate's own
        coefficients phi and the dead time.
    grid : bool
        True for the profiled dead-time parameter (no linear coefficients).
    plant_effect : callable or None
        ``plant_effect(values, arm) -> dict`` of :class:`~ppamsafety.params.effects.Effects`
        overrides reproducing the effect (for rehearsal), None if not a plant effect.
    columns : str or None
        Key of :attr:`ppamsafety.diagnose.arm.residuals.BlockSystem.extra`: regression
        columns (nb, 6, k) added to the *prediction* of the block residual
        (prediction = X mu + columns phi), for an effect that is not a
        direction of mu (hysteresis: a torque proportional to the Preisach
        output of the measured contraction history).  ``directions`` must
        then be None; the k coefficients are this candidate's phi.
    sensor_effect : callable or None
        ``sensor_effect(values) -> SensorFault``: a sensor fault (the measurement, not the
        plant, is wrong), applied to the simulated measurements of the "after" rollout.
    at_rest : bool
        The effect shows at rest (a static-sawtooth record can reveal it: no friction,
        lag, dead time or volume term).
    default : bool
        In the default library (:func:`default_candidates`); False: opt in by name.
    declared : callable or None
        ``declared(arm, dt) -> (len(parameters),)``: the values the arm declares for the
        parameters that the model vector mu does not carry (a payload, the hysteresis
        delta, a torque bias, the dead time [s] at sample time ``dt``).  The fitted
        coefficients are the *change* from them, and the reported values are
        ``physical(...) + declared(arm, dt)`` (:meth:`values`); None: the model vector
        carries the declared value already (valves, friction, polytropic exponent) or the
        arm cannot declare it (sensor faults).
    draw : callable or None, keyword-only
        ``draw(rng, arm, dt) -> (effects, truth)``: the battery's draw of a hidden effect on
        ``arm`` for a record sampled every ``dt`` [s]: the :func:`~ppamsafety.diagnose.
        synthesize` effects that hide it (its injection into the plant or the measurement)
        and its true parameter values.  Magnitudes log-uniform from below a typical
        detection limit to the top of the plausible range; a declared value is changed
        around (``_changed``).
    declare : callable or None, keyword-only
        ``declare(rng, arm) -> dict``: the declared-effect battery's draw of an arm that
        declares this effect (:class:`~ppamsafety.params.effects.Effects` overrides, within
        what an arm file accepts and an arm can still make its records); None: no arm
        declares it in that battery.
    declares : tuple of str, keyword-only
        The :class:`~ppamsafety.params.effects.Effects` fields whose declared values it
        changes (a hidden change of one of them is this candidate's name).
    needs, separating : keyword-only
        See :class:`~ppamsafety.diagnose.core.candidate.Candidate`; the separating
        experiments of a pair are read by :func:`separating_experiment`.
    """

    subsystem: str
    parameters: tuple
    signature: str
    physical: object
    directions: object = None
    grid: bool = False
    plant_effect: object = field(default=None, repr=False)
    columns: str | None = None
    sensor_effect: object = field(default=None, repr=False)
    at_rest: bool = False
    default: bool = True
    declared: object = field(default=None, repr=False)
    declare: object = field(default=None, repr=False, kw_only=True)
    declares: tuple = field(default=(), kw_only=True)

    def values(self, mu, phi, shift_seconds, arm, dt) -> np.ndarray:
        """The reported parameter values: :attr:`physical` plus what the arm declares.

        Parameters
        ----------
        mu : numpy.ndarray
            Fitted model vector.
        phi : numpy.ndarray
            This candidate's coefficients (the change from the declared model).
        shift_seconds : float
            Change of the dead time [s].
        arm : ArmParameters
            The model under test.
        dt : float
            Sample time of the record [s].
        """
        v = np.asarray(self.physical(mu, phi, shift_seconds), dtype=float)
        return v if self.declared is None else v + np.asarray(self.declared(arm, dt), float)

    @property
    def is_sensor_fault(self) -> bool:
        """True for an error of the measurement rather than of the plant."""
        return self.sensor_effect is not None

    @property
    def n_params(self) -> int:
        """Number of fitted parameters (the count charged by the criterion)."""
        return len(self.parameters)


def identity_values(mu, phi, shift):
    """``Candidate.physical`` of a candidate whose reported values are its coefficients.

    Parameters
    ----------
    mu : numpy.ndarray
        Model vector (unused).
    phi : numpy.ndarray
        The candidate's coefficients.
    shift : float
        Dead time [s] (unused).
    """
    return np.asarray(phi, dtype=float)


#: The arm's candidate library (the record kind ``"arm"`` of
#: :func:`ppamsafety.diagnose.core.candidate.library`), in registration order.
REGISTRY = register_library(Library("arm", Candidate, VOCABULARY))


def register(candidate: Candidate) -> Candidate:
    """Add ``candidate`` to the library (its name must be in a vocabulary and new).

    Parameters
    ----------
    candidate : Candidate
    """
    if isinstance(candidate, Candidate) and candidate.subsystem not in ("pressure", "torque",
                                                                        "both"):
        raise ValueError(f"candidate {candidate.name!r}: subsystem {candidate.subsystem!r} is "
                         f"not 'pressure', 'torque' or 'both'")
    return REGISTRY.register(candidate)


def default_candidates(*, static: bool = False) -> tuple:
    """Names of the default library (registry order): every candidate with ``default``; for
    a static record only those that show at rest (``at_rest``).

    ``joint_torque_bias`` is opt-in (``candidates=[..., "joint_torque_bias"]``): on the
    excitations of an arm record its constant torque is nearly a combination of a payload
    and an encoder offset (a pose-independent torque against gravity's cosine and its
    slope), and in the library by default it absorbed what those and several
    out-of-library errors left (measured on the scenario battery).

    Parameters
    ----------
    static : bool, keyword-only
        A static-sawtooth record.
    """
    return tuple(n for n, c in REGISTRY.items() if c.default and (c.at_rest or not static))


def library(names=None) -> tuple:
    """The registered candidates (all, or those named), in registry order.

    Parameters
    ----------
    names : sequence of str, optional
        Subset of names; unknown names raise ValueError.
    """
    if names is None:
        return tuple(REGISTRY.values())
    bad = [n for n in names if n not in REGISTRY]
    if bad:
        raise ValueError(f"unknown candidate(s) {bad}; registered: {list(REGISTRY)}")
    return tuple(REGISTRY[n] for n in names)


# --------------------------------------------------------------------------- entries

def _kappa(mu):
    return np.array([mu[MU_K + 3 * i] for i in range(4)])


def _dirs_offset_gain(mu0, arm=None):
    D = np.zeros((NMU, 8))
    for i in range(4):
        D[MU_A + 3 * i, i] = 1.0
        D[MU_B + 3 * i, 4 + i] = 1.0
    return D


def _phys_offset_gain(mu, phi, shift):
    k = _kappa(mu)
    return np.concatenate([[mu[MU_A + 3 * i] / k[i] for i in range(4)],
                           [mu[MU_B + 3 * i] / k[i] for i in range(4)]])


def _dirs_lag(mu0, arm=None):
    # T changes with v1, v2 fixed: (a, b, kappa) = kappa (v1, v2, 1)
    D = np.zeros((NMU, 4))
    k = _kappa(mu0)
    for i in range(4):
        D[MU_A + 3 * i, i] = mu0[MU_A + 3 * i] / k[i]
        D[MU_B + 3 * i, i] = mu0[MU_B + 3 * i] / k[i]
        D[MU_K + 3 * i, i] = 1.0
    return D


def _dirs_poly(mu0, arm=None):
    D = np.zeros((NMU, 1))
    D[MU_N, 0] = 1.0
    return D


def _dirs_friction(mu0, arm=None):
    D = np.zeros((NMU, 4))
    D[MU_COUL, 0] = D[MU_COUL + 1, 1] = D[MU_VISC, 2] = D[MU_VISC + 1, 3] = 1.0
    return D


def _dirs_payload(mu0, arm=None):
    g = (thesis_arm() if arm is None else arm).geometry
    D = np.zeros((NMU, 1))
    D[MU_THETA:MU_THETA + 6, 0] = payload_theta(1.0, g.L1, g.LL, g.dL)
    return D


BAR = 1e5


# ----------------------------------------------------------------------------- battery draws
# Each candidate's ``draw`` returns (synthesize effects, true parameter values); ``declare``
# an arm's declared effects.  The shipped batteries reproduce only while every draw consumes
# the generator in the same order.

def _some(rng, n):
    """A non-empty random subset of range(n) as a bool mask."""
    m = rng.random(n) < 0.5
    if not m.any():
        m[rng.integers(n)] = True
    return m


def _signed_some(rng, x, lo, hi):
    """``x`` with a non-empty random subset of its entries set to +- a magnitude log-uniform
    in [lo, hi] (each entry: its sign, then its magnitude)."""
    on = _some(rng, x.size)
    x[on] = [sgn(rng) * logu(rng, lo, hi) for _ in range(int(on.sum()))]
    return x


def _changed(rng, declared, lo, hi, small, large):
    """A hidden change of a declared value: ``declared`` +- a magnitude log-uniform in
    [small, large], kept inside [lo, hi] (the sign that fits when one does not)."""
    step = logu(rng, small, large)
    up = sgn(rng) > 0
    if declared + step > hi:
        up = False
    elif declared - step < lo:
        up = True
    return float(min(max(declared + step if up else declared - step, lo), hi))


def _draw_valve_offset_gain(rng, arm, dt=1e-3):
    v1 = plant_vector(arm, "valve_offset")
    v2 = plant_vector(arm, "valve_gain")
    on = _some(rng, 4)
    v1[on] += [sgn(rng) * logu(rng, 200.0, 3.0e4) for _ in range(int(on.sum()))]
    fx = {"valve_offset": tuple(v1)}
    if rng.random() < 0.5:
        on_g = _some(rng, 4)
        v2[on_g] *= [1.0 + sgn(rng) * logu(rng, 0.002, 0.15) for _ in range(int(on_g.sum()))]
        fx["valve_gain"] = tuple(v2)
    return fx, {**{f"v1_{i + 1}": v1[i] for i in range(4)},
                **{f"v2_{i + 1}": v2[i] for i in range(4)}}


def _declare_valves(rng, arm):
    # within the Table B.2 spread
    fx = {}
    if rng.random() < 0.6:
        fx["valve_offset"] = tuple(v + sgn(rng) * logu(rng, 200.0, 1.0e4)
                                   for v in plant_vector(arm, "valve_offset"))
    if rng.random() < 0.6 or not fx:
        fx["valve_gain"] = tuple(v * (1.0 + sgn(rng) * logu(rng, 0.005, 0.1))
                                 for v in plant_vector(arm, "valve_gain"))
    return fx


register(Candidate(
    "valve_offset_gain", "pressure",
    tuple(Parameter(f"v1_{i}", "Pa", -0.5 * BAR, 0.5 * BAR, f"static offset of valve {i} (3.12)",
                    phys_lo=-3 * BAR, phys_hi=3 * BAR)
          for i in range(1, 5)) +
    tuple(Parameter(f"v2_{i}", "-", 0.5, 1.5, f"static gain of valve {i} (3.12)", phys_lo=0.0)
          for i in range(1, 5)),
    "pressure residual of the valve(s) concerned; a bias that follows the set value "
    "(offset: constant drift rate; gain: proportional to u), independent of the motion",
    _phys_offset_gain, _dirs_offset_gain,
    plant_effect=lambda v, arm: {"valve_offset": tuple(v[:4]), "valve_gain": tuple(v[4:])},
    at_rest=True, draw=_draw_valve_offset_gain, declare=_declare_valves,
    declares=("valve_offset", "valve_gain")))


def _draw_valve_lag(rng, arm, dt=1e-3):
    T = plant_vector(arm, "valve_time_constant")
    on = _some(rng, 4)
    f = [(logu(rng, 1.05, 3.0) if rng.random() < 0.7 else 1.0 / logu(rng, 1.05, 2.0))
         for _ in range(int(on.sum()))]
    T[on] *= f
    return {"valve_time_constant": tuple(T)}, {f"T_{i + 1}": T[i] for i in range(4)}


def _declare_lag(rng, arm):
    # valves up to twice slower
    f = logu(rng, 0.6, 2.0)
    return {"valve_time_constant": tuple(T * f * logu(rng, 0.9, 1.1)
                                         for T in plant_vector(arm, "valve_time_constant"))}


register(Candidate(
    "valve_lag", "pressure",
    tuple(Parameter(f"T_{i}", "s", 5e-3, 1.0, f"time constant of valve {i} (3.2); "
                    f"plausible range of a proportional pressure valve (thesis 45-60 ms)",
                    phys_lo=0.0)
          for i in range(1, 5)),
    "pressure residual proportional to the valve error v1 + v2 u - p: largest when the set "
    "value moves fast (phase lag), zero in steady state",
    lambda mu, phi, shift: 1.0 / _kappa(mu), _dirs_lag,
    plant_effect=lambda v, arm: {"valve_time_constant": tuple(v)},
    draw=_draw_valve_lag, declare=_declare_lag, declares=("valve_time_constant",)))


def _draw_dead_time(rng, arm, dt=1e-3):
    # a declared dead time counts control periods, one per sample of the record (dt)
    d0 = arm.effects.valve_dead_time
    if d0 is None:
        d = logu(rng, 0.002, 0.05)
    else:
        d = _changed(rng, dt * float(np.mean(d0)), 0.0, 0.08, 0.002, 0.03)
    return {"valve_dead_time": d}, {"d": d}


def _declare_dead_time(rng, arm):
    # up to three 10 ms frames
    return {"valve_dead_time": (int(rng.integers(1, 31)),) * 4}


register(Candidate(
    "valve_dead_time", "pressure",
    (Parameter("d", "s", 0.0, DEAD_TIME_MAX, "pure delay of all four valves", phys_lo=0.0),),
    "pressure residual like a lag but with the shape of the set value's derivative "
    "delayed: the set value acts d later on all valves",
    lambda mu, phi, shift: np.array([shift]), None, grid=True,
    plant_effect=None,
    declared=lambda arm, dt: np.array([float(np.mean(declared_delays(arm))) * dt]),
    draw=_draw_dead_time, declare=_declare_dead_time, declares=("valve_dead_time",)))


def _draw_polytropic(rng, arm, dt=1e-3):
    if arm.effects.polytropic_n is None:
        n = float(rng.uniform(1.0, 1.38))
    else:
        n = _changed(rng, arm.effects.polytropic_n, 1.0, 1.4, 0.02, 0.3)
    return {"polytropic_n": n}, {"n": n}


def _declare_polytropic(rng, arm):
    return {"polytropic_n": float(rng.uniform(1.0, 1.4))}


register(Candidate(
    "polytropic_exponent", "pressure",
    (Parameter("n", "-", 1.0, 1.4, "polytropic exponent (3.3): isothermal 1 to isentropic 1.4",
               phys_lo=1.0, phys_hi=1.4),),
    "pressure residual proportional to the volume-change term (P_atm + p) m_tau qd / V: "
    "changes sign with the velocity of the joint, zero at rest",
    lambda mu, phi, shift: np.array([mu[MU_N]]), _dirs_poly,
    plant_effect=lambda v, arm: {"polytropic_n": float(v[0])},
    draw=_draw_polytropic, declare=_declare_polytropic, declares=("polytropic_n",)))


def _draw_friction(rng, arm, dt=1e-3):
    c = plant_vector(arm, "friction_coulomb")
    b = plant_vector(arm, "friction_viscous")
    on = _some(rng, 2)
    c[on] = [logu(rng, 0.02, 1.5) for _ in range(int(on.sum()))]
    fx = {"friction_coulomb": tuple(c)}
    if rng.random() < 0.3:
        on_b = _some(rng, 2)
        b[on_b] = b[on_b] + np.array([logu(rng, 0.02, 1.0) for _ in range(int(on_b.sum()))])
        fx["friction_viscous"] = tuple(b)
    return fx, {"c1": c[0], "c2": c[1], "b1": b[0], "b2": b[1]}


def _declare_friction(rng, arm):
    # up to a stiff bearing
    fx = {"friction_coulomb": tuple(logu(rng, 0.02, 1.0) for _ in range(2))}
    if rng.random() < 0.5:
        fx["friction_viscous"] = tuple(b * logu(rng, 1.0, 3.0)
                                       for b in plant_vector(arm, "friction_viscous"))
    return fx


register(Candidate(
    "joint_friction", "torque",
    (Parameter("c1", "N m", 0.0, 10.0, "Coulomb friction of joint 1 (3.30)", phys_lo=0.0),
     Parameter("c2", "N m", 0.0, 10.0, "Coulomb friction of joint 2 (3.30)", phys_lo=0.0),
     Parameter("b1", "N m s/rad", 0.0, 10.0, "viscous friction of joint 1 (3.30)",
               phys_lo=0.0),
     Parameter("b2", "N m s/rad", 0.0, 10.0, "viscous friction of joint 2 (3.30)",
               phys_lo=0.0)),
    "torque residual that opposes the motion: its sign follows the velocity sign "
    "(Coulomb) and its size the speed (viscous); no configuration dependence",
    lambda mu, phi, shift: np.array([mu[MU_COUL], mu[MU_COUL + 1], mu[MU_VISC],
                                     mu[MU_VISC + 1]]),
    _dirs_friction,
    plant_effect=lambda v, arm: {"friction_coulomb": (float(v[0]), float(v[1])),
                                 "friction_viscous": (float(v[2]), float(v[3]))},
    draw=_draw_friction, declare=_declare_friction,
    declares=("friction_coulomb", "friction_viscous")))


def _draw_payload(rng, arm, dt=1e-3):
    m0 = arm.effects.payload_mass
    m = logu(rng, 0.01, 2.0) if m0 == 0.0 else _changed(rng, m0, 0.0, 2.5, 0.01, 1.0)
    return {"payload_mass": m}, {"M": m}


def _declare_payload(rng, arm):
    # a payload the valves can hold
    return {"payload_mass": logu(rng, 0.05, 1.5)}



def _payload_candidate():
    return Candidate(
        "payload", "torque",
        (Parameter("M", "kg", 0.0, 5.0, "point mass at the load point A_L (2.19)",
                   phys_lo=0.0),),
        "torque residual of both joints with the gravity shape (cos of the link angles, "
        "largest with the forearm horizontal) plus inertia; independent of the velocity sign",
        identity_values, _dirs_payload,
        plant_effect=lambda v, arm: {"payload_mass": float(v[0])}, at_rest=True,
        declared=lambda arm, dt: np.array([arm.effects.payload_mass]),
        draw=_draw_payload, declare=_declare_payload, declares=("payload_mass",))


register(_payload_candidate())


def _maybe_register_hysteresis():
    """Hysteresis (3.35): one delta shared by the four muscle groups.

    The plant multiplies the force of group k in the joint torques by
    ``1 + delta_k (W_k - W_fit(eps_s,k))`` (:mod:`ppamsafety.plant.model`),
    so the torque of joint j gains ``sum_k delta_k p_k m_tau,k (W_k - W_fit)``:
    linear in delta given the Preisach output W_k of the *measured*
    contraction history (contractions from the measured q through the
    geometry).  The columns are built by
    :func:`ppamsafety.diagnose.arm.residuals.hysteresis_signature` with the
    plant's own operator (:func:`ppamsafety.plant.model.hysteresis_factors`
    with delta = 1).

    Parameterisation: one delta for all four groups.  The arm's four muscle
    groups are the same 25-fibre muscles (thesis §3.6.5 fits one delta =
    0.139 for them), so one parameter is the physical hypothesis and the
    criterion charges k = 1.  Four deltas would cost 3 more parameters in BIC
    for a difference the thesis gives no reason to expect, and the two
    antagonists of a joint move in opposite directions, so their columns are
    strongly (negatively) correlated in a torque residual: per-muscle deltas
    are poorly determined from torques alone.  A muscle whose delta differs
    shows as a residual left over (``partial`` / unexplained).
    """
    if "hysteresis_delta" not in Effects.__dataclass_fields__:
        return
    register(Candidate(
        "hysteresis", "torque",
        (Parameter("delta", "-", 0.0, 1.0, "hysteresis scale delta of (3.35), one value for "
                   "the four muscle groups (thesis §3.6.5: 0.139 for the arm's 25-fibre "
                   "muscles)", phys_lo=0.0, phys_hi=1.0),),
        "torque (and muscle-force) residual that depends on the direction of the last "
        "contraction change: force below the model while a muscle contracts, above while it "
        "extends (§3.5.1.6, fig. 3.2); rising angles settle low, falling ones high",
        identity_values, None, columns=HYSTERESIS_COLUMNS,
        plant_effect=_hysteresis_effect, at_rest=True,
        declared=lambda arm, dt: np.array([float(np.mean(declared_hysteresis(arm)))]),
        draw=_draw_hysteresis, declare=_declare_hysteresis, declares=("hysteresis_delta",),
        separating={"joint_friction": "a quasi-static sawtooth (§3.5.1.6): hysteresis keeps its "
                                      "loop at rest, friction needs motion"}))


def _draw_hysteresis(rng, arm, dt=1e-3):
    d0 = arm.effects.hysteresis_delta
    if d0 is None:
        d = logu(rng, 0.005, 0.3)
        return {"hysteresis_delta": d}, {"delta": d}
    # a change common to the groups (the candidate's hypothesis), from their declared mean
    m0 = float(np.mean(d0))
    d = _changed(rng, m0, max(m0 - min(d0), 0.0), min(0.8, 1.0 - max(d0) + m0), 0.005, 0.2)
    return {"hysteresis_delta": tuple(float(x) + d - m0 for x in d0)}, {"delta": d}


def _declare_hysteresis(rng, arm):
    # the 25/40-fibre hysteresis and beyond
    d = logu(rng, 0.03, 0.5)
    if rng.random() < 0.25:                         # groups of different muscles
        return {"hysteresis_delta": tuple(d * logu(rng, 0.7, 1.3) for _ in range(4))}
    return {"hysteresis_delta": (d,) * 4}


def _hysteresis_effect(v, arm) -> dict:
    """The plant's hysteresis of a fitted delta ``v[0]``: the change from the arm's declared
    mean added to every group's declared delta, each clipped to the plant's [0, 1]; none
    when every group comes out at or below 0."""
    d = np.clip(declared_hysteresis(arm) + (float(v[0]) - float(np.mean(
        declared_hysteresis(arm)))), 0.0, 1.0)
    return {"hysteresis_delta": None if np.all(d <= 0.0) else tuple(float(x) for x in d)}


_maybe_register_hysteresis()


@dataclass(frozen=True)
class SensorFault:
    """Errors of the measurement: ``p_m = (1 + gain) p + offset``, ``q_m = q + q_offset``.

    Attributes
    ----------
    p_offset : tuple of 4 float
        Pressure-sensor offsets [Pa].
    p_gain : tuple of 4 float
        Pressure-sensor gain errors [-].
    q_offset : tuple of 2 float
        Encoder offsets [rad].
    """

    p_offset: tuple = (0.0,) * 4
    p_gain: tuple = (0.0,) * 4
    q_offset: tuple = (0.0,) * 2

    def __add__(self, other: "SensorFault") -> "SensorFault":
        return SensorFault(tuple(np.add(self.p_offset, other.p_offset)),
                           tuple(np.add(self.p_gain, other.p_gain)),
                           tuple(np.add(self.q_offset, other.q_offset)))

    def measure(self, x) -> np.ndarray:
        """Measured [q, qd, p] (..., 8) of true states ``x`` (..., 8).

        Parameters
        ----------
        x : array_like, shape (..., 8)
            True states [q, qd, p] (rad, rad/s, Pa gauge).
        """
        x = np.array(x, dtype=float)
        x[..., :2] += np.asarray(self.q_offset)
        x[..., 4:8] = x[..., 4:8] * (1.0 + np.asarray(self.p_gain)) + np.asarray(self.p_offset)
        return x

    def true_state(self, x) -> np.ndarray:
        """True states of measured ones (the inverse of :meth:`measure`).

        Parameters
        ----------
        x : array_like, shape (..., 8)
            Measured [q, qd, p] (rad, rad/s, Pa gauge).
        """
        x = np.array(x, dtype=float)
        x[..., :2] -= np.asarray(self.q_offset)
        x[..., 4:8] = (x[..., 4:8] - np.asarray(self.p_offset)) / (1.0 + np.asarray(self.p_gain))
        return x


#: Separating experiment of a pair without an entry above.
DEFAULT_SEPARATION = ("an experiment that moves the two apart: excite the arm where their "
                      "signatures differ (other poses, speeds, pressures), or measure one of "
                      "them directly")


def separating_experiment(a: str, b: str) -> str:
    """The experiment that tells candidates ``a`` and ``b`` apart (the ``separating`` of one of
    them, :data:`SEPARATING_EXPERIMENTS`; :data:`DEFAULT_SEPARATION` for another pair).

    Parameters
    ----------
    a, b : str
        Candidate names.
    """
    return SEPARATING_EXPERIMENTS.get(tuple(sorted((a, b))), DEFAULT_SEPARATION)


def _draw_torque_bias(rng, arm, dt=1e-3):
    b = _signed_some(rng, np.zeros(2) if arm.effects.joint_torque_bias is None else np.array(
        arm.effects.joint_torque_bias, float), 0.01, 2.0)
    return {"joint_torque_bias": tuple(b)}, {"b1": b[0], "b2": b[1]}


def _declare_torque_bias(rng, arm):
    # a cable's drag
    return {"joint_torque_bias": tuple(sgn(rng) * logu(rng, 0.02, 1.0) for _ in range(2))}


register(Candidate(
    "joint_torque_bias", "torque",
    (Parameter("b1", "N m", -20.0, 20.0, "constant torque at joint 1 the model lacks "
               "(Effects.joint_torque_bias): a cable, a spring, a miscalibrated gravity term"),
     Parameter("b2", "N m", -20.0, 20.0, "constant torque at joint 2")),
    "torque residual of one or both joints that is constant: independent of the pose, the "
    "velocity and the pressures",
    identity_values, None, columns=TORQUE_BIAS_COLUMNS,
    plant_effect=lambda v, arm: {"joint_torque_bias": (float(v[0]), float(v[1]))},
    at_rest=True, default=False, declared=lambda arm, dt: declared_torque_bias(arm),
    draw=_draw_torque_bias, declare=_declare_torque_bias, declares=("joint_torque_bias",),
    separating={"payload": "repeat the record with the load removed (or weighed): a payload "
                           "changes with it, a bias does not"}))


def _draw_p_offset(rng, arm, dt=1e-3):
    o = _signed_some(rng, np.zeros(4), 100.0, 2.0e4)
    return {"pressure_sensor_offset": tuple(o)}, {f"o_{i + 1}": o[i] for i in range(4)}


register(Candidate(
    "pressure_sensor_offset", "both",
    tuple(Parameter(f"o_{i}", "Pa", -0.5 * BAR, 0.5 * BAR,
                    f"offset of pressure sensor {i}: p_m = p + o (at 0 bar gauge it reads o)",
                    phys_lo=-1.0 * BAR, phys_hi=1.0 * BAR) for i in range(1, 5)),
    "pressure residual like a valve offset (a constant drift rate kappa o) *and* a torque "
    "residual o m_tau(q) of the muscle's joint, following its lever arm",
    identity_values, None, columns=PRESSURE_OFFSET_COLUMNS,
    sensor_effect=lambda v: SensorFault(p_offset=tuple(float(x) for x in v)), at_rest=True,
    draw=_draw_p_offset,
    separating={"valve_offset_gain":
                "vent the muscles (valves closed to atmosphere) and read the pressure sensors: "
                "a sensor offset reads non-zero at 0 bar gauge; or check against a reference "
                "gauge"}))


def _draw_p_gain(rng, arm, dt=1e-3):
    g = _signed_some(rng, np.zeros(4), 5e-4, 0.1)
    return {"pressure_sensor_gain": tuple(g)}, {f"g_{i + 1}": g[i] for i in range(4)}


register(Candidate(
    "pressure_sensor_gain", "both",
    tuple(Parameter(f"g_{i}", "-", -0.3, 0.3,
                    f"gain error of pressure sensor {i}: p_m = (1 + g) p", phys_lo=-0.9)
          for i in range(1, 5)),
    "pressure residual proportional to the valve's drive (a + b u) and a torque residual "
    "g p m_tau(q): like a stronger or weaker muscle in the torques, but not in the valves",
    identity_values, None, columns=PRESSURE_GAIN_COLUMNS,
    sensor_effect=lambda v: SensorFault(p_gain=tuple(float(x) for x in v)), at_rest=True,
    draw=_draw_p_gain,
    separating={"valve_offset_gain": "compare the pressure sensors with a reference gauge at "
                                     "two or more pressures",
                "pressure_sensor_offset": "calibrate the pressure sensors against a reference "
                                          "gauge at two or more pressures"}))


def _draw_encoder_offset(rng, arm, dt=1e-3):
    o = _signed_some(rng, np.zeros(2), 2e-4, 0.08)
    return {"encoder_offset": tuple(o)}, {"o_q1": o[0], "o_q2": o[1]}


register(Candidate(
    "encoder_offset", "both",
    (Parameter("o_q1", "rad", -0.1745, 0.1745, "offset of the joint 1 encoder: q_m = q + o "
               "(plausible +-10 deg)", phys_lo=-math.pi, phys_hi=math.pi),
     Parameter("o_q2", "rad", -0.1745, 0.1745, "offset of the joint 2 encoder",
               phys_lo=-math.pi, phys_hi=math.pi)),
    "torque residual that follows the slope of gravity and of the lever arms with the pose "
    "(the model evaluated at the wrong angle), and a small pressure residual through the "
    "muscle volumes",
    identity_values, None, columns=ENCODER_OFFSET_COLUMNS,
    sensor_effect=lambda v: SensorFault(q_offset=tuple(float(x) for x in v)), at_rest=True,
    draw=_draw_encoder_offset,
    separating={"payload": "hold the arm at a known reference pose (a mechanical stop or a "
                           "level) and read the encoders; weigh the load",
                "joint_torque_bias": "read the encoders at a known reference pose (a "
                                     "mechanical stop or a level)"}))

#: The experiment that separates a sensor fault from the plant effect it can look like on a
#: record, keyed by the (sorted) pair of candidate names: the candidates' ``separating``.
SEPARATING_EXPERIMENTS = {tuple(sorted(k)): v for k, v in REGISTRY.separating_table().items()}

__all__ = ["Candidate", "Parameter", "REGISTRY", "register", "library", "default_candidates",
           "VOCABULARY",
           "DEAD_TIME_MAX", "HYSTERESIS_COLUMNS", "SENSOR_FAULTS", "SensorFault",
           "SEPARATING_EXPERIMENTS", "separating_experiment", "identity_values"]
