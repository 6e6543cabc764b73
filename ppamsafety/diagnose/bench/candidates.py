"""The library of candidate effects on a test bench (one actuator: force, pressure, contraction).

Each candidate is one :class:`MuscleCandidate` of :data:`MUSCLE_LIBRARY`: how it builds its
columns on a record, its battery draw, the gates it needs and the experiments that separate
it from its look-alikes; the design, the gates, the battery and the confounded groups read it.

The names are fixed (:data:`~.candidates.ACTUATOR_VOCABULARY`).  Every
candidate extends the nominal force law (3.9)
``F_nom = p (a0/eps + a1 + a2 eps + a3 eps^2 + a4 eps^3)`` by a term linear
in its parameters, ``F = F_nom + C phi`` with columns C [N per unit of phi]
computed from the *measured* pressure and contraction history, so it is
fitted by linear regression on the force residual
(:mod:`~ppamsafety.diagnose.core.linear_selection`).
The columns that hold the force function are computed on the contraction made
monotone between reversals (``eps_monotone``, the Preisach input of
:func:`~.design.monotone_contraction`) and on a smoothed pressure
(:func:`~.design.smooth_pressure`), not on the measured ones: the residual
carries the sensors' noise as ``-n_p f(eps) - p f'(eps) d_eps``, and columns
built on the noisy signals would fit part of it (errors in variables: at a
fixed contraction a force gain and a refitted level, at one pressure level a
force gain and a pressure offset, would "explain" that noise):

======================  ==============================================  ============================
name                    extension (columns)                             parameters
======================  ==============================================  ============================
actuator_friction       ``-c s - b v``: s = direction of motion (+1     c [N] (Coulomb); b [N s/m],
                        contracting, -1 extending, held at rest),       or [N s] without l0
                        v = l0 d eps/dt [m/s]                           (viscous, only when the
                                                                        speed varies enough)
hysteresis              ``delta F_nom (W[eps_s] - W_fit(eps_s))``,      delta [-] (3.35)
                        (3.34)-(3.35), Preisach operator of §3.6
                        (:mod:`ppamsafety.hysteresis`) along the
                        measured contraction
force_law_refit         ``p (da0/eps + da1 + da2 eps + ...)``: the      a0..a4 [N/Pa] (refitted; the
                        coefficients of (3.9) that are nonzero in the   nominal ones for the terms
                        nominal law, and a1 always (a cylinder: A)      not freed)
force_sensor_offset     ``o``: the load cell reads F + o                o [N]
force_sensor_gain       ``g F_nom``: the load cell reads (1 + g) F      g [-] (first order: the
                                                                        other effects' forces are
                                                                        read (1 + g) x too)
pressure_sensor_offset  ``-o f(eps)``: the transducer reads p + o, so   o [Pa]
                        the law is evaluated at a pressure o too high
======================  ==============================================  ============================

Sensor faults are the first thing an experimenter checks.
A **pressure-sensor gain** is not a candidate of its own: reading (1 + g_p) p
makes the nominal force p f(eps) (1 + g_p) x too large, exactly the column of a
force-sensor gain g = -g_p / (1 + g_p) (both scale p f(eps)); the separating
experiment of that pair names both sensors.  A force-sensor gain is in turn
**nested** in the refitted law (a uniform scale of its coefficients): the two
can never be told apart on one record, the diagnosis reports them as
confounded (:data:`SEPARATING`: a dead-weight check of the load cell, a
reference gauge) and names neither.  At one pressure level (a pressure sweep
excepted) the offsets are nearly in the refit's span too: the pipeline then
keeps them below "high".

Signatures (what a reviewer looks for in the residual, ``where`` table):
friction jumps by 2c at every reversal of the motion and is independent of
the history and of the pressure; hysteresis has memory (after a reversal
the force moves gradually from one branch to the other, nested minor loops
close), and scales with the force, hence with the pressure; a wrong force
law is a smooth function of the contraction, proportional to the pressure,
the same in both directions of motion.

Plausible bounds (rule 3 of the naming rule; the 95 % interval must lie in
the bounds widened by half their width on each side, and the dissipative
parameters c and delta must not be significantly negative -- b may, within
its bounds: it is a small correction estimated from the speed changes): c in [0, 0.2 max
|F_nom|] ("a few %" of the force is typical of a tester, 20 % is not a
working actuator); b in [0, 0.2 max |F_nom| / max |v|]; delta in [0, 0.5]
(the thesis found 0.139 and 0.299, §3.6.5; the range of
:func:`ppamsafety.hysteresis.tensile.simulate_tensile_test`); the refitted
law's change of the force function at the 10/50/90 % quantiles of the
measured contraction within +-50 % of the nominal force function there;
offsets within 20 % of the largest nominal force (pressure: of the largest
pressure) and a gain within +-20 % (the cylinder library's
:data:`~.friction.OFFSET_MAX_FRACTION` and :data:`~.friction.GAIN_MAX`).

Physical ranges (the admissibility gate before "high", :mod:`.gates`): c, b
and delta >= 0 and delta <= 1 (the factor of (3.35) stays positive), a gain
> -1 (a load cell that reads nothing is broken, not miscalibrated), and a
refitted force function positive at the quantile nodes (a muscle pulls).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ...hysteresis import EPS_MAX, preisach_response, scaled_input, w_fit
from ..core.battery import logu, sgn
from ..core.candidate import Candidate, Library, register_library
from ..core.criteria import _normal_quantile
from ..core.parameter import Parameter, physically_admissible
from ..core.result import Estimate
from .friction import GAIN_MAX, OFFSET_MAX_FRACTION
from .friction import separating_experiment as friction_separating

#: Largest hysteresis scale that keeps the factor 1 + delta (W - W_fit) of (3.35) positive.
DELTA_PHYSICAL_MAX = 1.0
#: Text for a confounded group no entry of :data:`SEPARATING` covers.
SEPARATING_DEFAULT = ("record more loops over a wider range (several pressures, contraction "
                      "amplitudes and speeds) and check the sensors against references (dead "
                      "weights on the load cell, a reference gauge, both sensors read with the "
                      "muscle vented at 0 bar)")
#: Largest Coulomb friction, fraction of max |F_nom| (module docstring).
FRICTION_MAX_FRACTION = 0.2
#: Range of the hysteresis scale delta (thesis §3.6.5: 0.139, 0.299).
DELTA_BOUNDS = (0.0, 0.5)
#: Largest relative change of the force function accepted from a refit.
REFIT_MAX_RELATIVE = 0.5
#: Contraction span (5-95 %) in contraction noise levels below which only a1 is refitted.
REFIT_MIN_SPAN_SIGMAS = 50.0
#: Fastest/slowest run speed below which viscous friction is not separable from Coulomb.
VISCOUS_SPEED_RATIO = 1.25
#: Contraction range of the battery's force-law changes' least-squares projection [-].
LAW_FIT_RANGE = (0.03, 0.30)


@dataclass(frozen=True, eq=False)
class MuscleCandidate(Candidate):
    """A candidate effect of a muscle test-bench record: what every kind's candidate carries
    (:class:`~ppamsafety.diagnose.core.candidate.Candidate`: its name, its battery ``draw``,
    the gates it ``needs``, its ``separating`` experiments) and how it builds its columns.

    Attributes
    ----------
    name : str
        The name written in ``diagnosis.json`` (:data:`ACTUATOR_VOCABULARY`).
    build : callable
        ``build(ctx) -> (Extension or None, why)``: its columns and parameters on one record
        (:func:`build_extensions`: the parameters' units, bounds and physical ranges, which
        scale with the record's force, pressure and speed), or None and the reason it does
        not apply to the record.
    sensor_fault : bool
        An error of the measurement rather than of the muscle.
    draw : callable, keyword-only
        ``draw(rng, law, protocol) -> (effects, truth)``: the battery's draw on a muscle of
        force law ``law`` (5 coefficients [N/Pa]) under the scenario's ``protocol`` (the
        options of :func:`~.synthesize.synthesize_actuator`): the generator's effects that
        hide it and its true parameters (in the sensors' frame before any gain is applied,
        :func:`~.scenarios.measured_truth`).
    needs : tuple of str, keyword-only
        Gates of :data:`~.gates.MUSCLE_RULE` that apply to it: ``reversals`` (a history
        effect, shows at the reversals of the motion: none on a pressure sweep),
        ``pressure_levels`` (told from its look-alikes only at several pressures).
    separating : mapping, keyword-only
        Look-alike -> the experiment that separates the two on a muscle record
        (:data:`SEPARATING`, :func:`separating_experiment`).
    """

    build: object = field(default=None, repr=False)
    sensor_fault: bool = False

    def __post_init__(self):
        super().__post_init__()
        if not callable(self.build):
            raise TypeError(f"candidate {self.name!r}: build must be callable")


#: The muscle bench's candidate library (the record kind ``"muscle"`` of
#: :func:`ppamsafety.diagnose.core.candidate.library`), in registration order.
MUSCLE_LIBRARY = register_library(Library("muscle", MuscleCandidate))
register = MUSCLE_LIBRARY.register


@dataclass(frozen=True, eq=False)
class Extension:
    """One candidate's extension on one record.

    Attributes
    ----------
    name : str
        From :data:`~.candidates.ACTUATOR_VOCABULARY`.
    columns : numpy.ndarray, shape (N, k)
        Force per unit of each coefficient [N / unit].
    parameters : tuple of Parameter
        Reported parameters (physical, SI).
    nominal : numpy.ndarray, shape (len(parameters),)
        Their values in the nominal model.
    T : numpy.ndarray, shape (len(parameters), k)
        Reported values = nominal + T phi.
    signature : str
        Where and how it shows.
    check : callable or None
        ``check(phi, cov) -> bool`` replacing the per-parameter bounds rule
        (the refitted law is checked on the force function, see the module
        docstring); None: every parameter's interval inside its widened
        bounds.
    note : str
        A remark on how the extension was built (e.g. viscous part left out).
    shift : callable or None
        ``shift(phi, cov) -> bool``: the fit moved away from the nominal model
        (replacing "some parameter's interval excludes its nominal value").
    nonnegative : tuple of str
        Parameters that must not be significantly negative (95 % interval
        reaching 0): dissipation, a friction or a hysteresis loop that gives
        energy back is not physical.
    physical : callable or None
        ``physical(phi, cov) -> bool`` replacing the per-parameter physical
        ranges of :meth:`physically_admissible` (the refitted law: its force
        function positive at the quantile nodes).
    per_force : numpy.ndarray, shape (N,), or None
        For an effect proportional to the muscle's force (hysteresis: ``W -
        W_fit``), its column per newton of that force; :meth:`on_force` rebuilds
        the column on a better estimate of the force than the nominal law.
    """

    name: str
    columns: np.ndarray = field(repr=False)
    parameters: tuple
    nominal: np.ndarray
    T: np.ndarray
    signature: str
    check: object = field(default=None, repr=False)
    note: str = ""
    shift: object = field(default=None, repr=False)
    nonnegative: tuple = ()
    physical: object = field(default=None, repr=False)
    per_force: object = field(default=None, repr=False)

    def on_force(self, force) -> "Extension":
        """The same extension with its column rebuilt on ``force`` [N] (see ``per_force``).

        Parameters
        ----------
        force : numpy.ndarray, shape (N,)
            The muscle's force as the record reads it (e.g. the nominal law with the fitted
            law and gain corrections).
        """
        if self.per_force is None:
            raise ValueError(f"{self.name}: its column is not proportional to the force")
        return replace(self, columns=(np.asarray(force, float) * self.per_force)[:, None])

    @property
    def k(self) -> int:
        """Number of fitted coefficients."""
        return self.columns.shape[1]

    def values(self, phi, cov, confidence: float = 0.95) -> dict:
        """Reported parameters with delta-method (here exact, linear) intervals.

        Parameters
        ----------
        phi : numpy.ndarray, shape (k,)
            This extension's coefficients.
        cov : numpy.ndarray, shape (k, k)
            Their covariance.
        confidence : float
            Level of the intervals.

        Returns
        -------
        dict
            parameter name -> :class:`~ppamsafety.diagnose.core.result.Estimate`.
        """
        z = _normal_quantile(0.5 + confidence / 2)
        v = self.nominal + self.T @ phi
        se = np.sqrt(np.maximum(np.diag(self.T @ cov @ self.T.T), 0.0))
        return {p.name: Estimate(value=float(v[i]), unit=p.unit, ci_low=float(v[i] - z * se[i]),
                                 ci_high=float(v[i] + z * se[i]), std_error=float(se[i]),
                                 nominal=float(self.nominal[i]))
                for i, p in enumerate(self.parameters)}

    def moved(self, phi, cov) -> bool:
        """True if the fit differs significantly (95 %) from the nominal model.

        Parameters
        ----------
        phi : numpy.ndarray, shape (k,)
            This extension's coefficients.
        cov : numpy.ndarray, shape (k, k)
            Their covariance.
        """
        if self.shift is not None:
            return bool(self.shift(phi, cov))
        return any(p.moved for p in self.values(phi, cov).values())

    def physically_admissible(self, phi, cov) -> bool:
        """The fit is physically possible: the admissibility gate before "high".

        Every parameter that moved (its 95 % interval excludes the nominal
        value) has its interval inside the parameter's physical range, and no
        other parameter lies significantly outside it
        (:func:`~ppamsafety.diagnose.core.parameter.physically_admissible`).

        Parameters
        ----------
        phi : numpy.ndarray, shape (k,)
            This extension's coefficients.
        cov : numpy.ndarray, shape (k, k)
            Their covariance.
        """
        if self.physical is not None:
            return bool(self.physical(phi, cov))
        tab = self.values(phi, cov)
        moved = [n for n, d in tab.items() if d.moved]
        return physically_admissible(self.parameters, tab, moved)

    def admissible(self, phi, cov) -> bool:
        """Rule 3: the fitted parameters are determined and physically possible.

        Parameters
        ----------
        phi : numpy.ndarray, shape (k,)
            This extension's coefficients.
        cov : numpy.ndarray, shape (k, k)
            Their covariance.
        """
        if self.check is not None:
            return bool(self.check(phi, cov))
        tab = self.values(phi, cov)
        if any(tab[n].ci_high < 0 for n in self.nonnegative):
            return False
        return all(tab[p.name].ci_low >= p.lo - 0.5 * (p.hi - p.lo)
                   and tab[p.name].ci_high <= p.hi + 0.5 * (p.hi - p.lo)
                   for p in self.parameters)


def _friction(ctx):
    s = ctx["direction"].astype(float)
    if not np.any(s != 0):
        return None, "no motion detected: friction is not identifiable from this record"
    fmax = FRICTION_MAX_FRACTION * float(np.max(np.abs(ctx["f_nom"])))
    v = ctx["speed"]
    vunit = ctx["speed_unit"]
    bunit = "N s/m" if vunit == "m/s" else "N s"
    moving = s != 0
    vmax = float(np.max(np.abs(v[moving]))) if moving.any() else 0.0
    note = ""
    use_visc = vmax > 0 and ctx["speed_ratio"] >= VISCOUS_SPEED_RATIO
    if vmax > 0 and not use_visc:
        note = (f"friction: every run of the motion had about the same speed (fastest/slowest "
                f"{ctx['speed_ratio']:.2f} < {VISCOUS_SPEED_RATIO}), so a viscous part is not "
                f"separable from the Coulomb part; fitted Coulomb only (c includes b |v|)")
    params = [Parameter("c", "N", 0.0, fmax, "Coulomb friction opposing the motion",
                        phys_lo=0.0)]
    cols = [-s]
    if use_visc:
        params.append(Parameter("b", bunit, 0.0, fmax / vmax,
                                f"viscous friction (force per unit speed, speed in {vunit})",
                                phys_lo=0.0))
        cols.append(-v)
    k = len(cols)
    return Extension(
        "actuator_friction", np.column_stack(cols), tuple(params), np.zeros(k), np.eye(k),
        "a force opposing the motion: jumps by 2c at every reversal, the same at every pressure "
        "and contraction, independent of the history", note=note,
        nonnegative=("c",)), ""


def _hysteresis(ctx):
    s = ctx["direction"]
    moving = np.flatnonzero(s != 0)
    if moving.size == 0:
        return None, "no motion detected: hysteresis is not identifiable from this record"
    eps_s = scaled_input(ctx["eps_monotone"], EPS_MAX)
    # unknown history before the record: the memory starts at the saturation the first
    # motion leaves (contracting first: from the stretched muscle, eps_s = -1; §3.6.6)
    initial = "negative" if s[moving[0]] > 0 else "positive"
    W = preisach_response(eps_s, initial=initial, clip=True)
    a, b = w_fit()
    shape = W - (a * eps_s + b)
    col = ctx["f_smooth"] * shape
    lo, hi = DELTA_BOUNDS
    return Extension(
        "hysteresis", col[:, None],
        (Parameter("delta", "-", lo, hi, "hysteresis scale of (3.35) (thesis 0.139 for 25 "
                                         "fibres, 0.299 for 40, §3.6.5)",
                   phys_lo=0.0, phys_hi=DELTA_PHYSICAL_MAX),),
        np.zeros(1), np.eye(1),
        "memory: after a reversal the force moves gradually from one branch to the other, "
        "minor loops are nested; proportional to the force (and so to the pressure)",
        note=f"hysteresis: Preisach memory started from {initial} saturation (eps_max = "
             f"{EPS_MAX}, (3.34)), input: the contraction made monotone between reversals",
        nonnegative=("delta",), per_force=shape), ""


def _refit(ctx):
    a = ctx["a"]
    eps, p = ctx["eps_monotone"], ctx["p_smooth"]
    free = [j for j in range(5) if a[j] != 0.0 or j == 1]
    if 0 in free and np.any(eps <= 0):
        free.remove(0)
    narrow = ctx["eps_span_sigmas"] < REFIT_MIN_SPAN_SIGMAS
    if narrow:
        # (nearly) fixed contraction: only the force function's value there is
        # identifiable; freeing its slope would fit the contraction noise that the
        # columns share with the residual (errors in variables)
        free = [1]
    basis = {0: lambda e: 1.0 / e, 1: lambda e: np.ones_like(e), 2: lambda e: e,
             3: lambda e: e ** 2, 4: lambda e: e ** 3}
    cols = np.column_stack([p * basis[j](eps) for j in free])
    T = np.zeros((5, len(free)))
    for i, j in enumerate(free):
        T[j, i] = 1.0
    q = np.quantile(eps, [0.1, 0.5, 0.9])
    G = np.column_stack([basis[j](q) for j in free])
    f_q = sum(a[j] * basis[j](q) for j in range(5) if not (j == 0 and np.any(q <= 0)))
    z = _normal_quantile(0.975)
    lim = 2 * REFIT_MAX_RELATIVE        # the +-50 % band widened by half its width

    def check(phi, cov):
        if np.any(np.abs(f_q) == 0):
            return False
        d = G @ phi
        se = np.sqrt(np.maximum(np.diag(G @ cov @ G.T), 0.0))
        return bool(np.all(np.abs(d) + z * se <= lim * np.abs(f_q)))

    def shift(phi, cov):
        d = G @ phi
        se = np.sqrt(np.maximum(np.diag(G @ cov @ G.T), 0.0))
        return bool(np.any(np.abs(d) > z * se))

    def physical(phi, cov):
        # a muscle pulls: the refitted force function stays positive at the nodes
        d = G @ phi
        se = np.sqrt(np.maximum(np.diag(G @ cov @ G.T), 0.0))
        return bool(np.all(f_q + d - z * se > 0.0))

    params = tuple(Parameter(f"a{j}", "N/Pa", -1.0, 1.0, f"coefficient a{j} of (3.9)")
                   for j in range(5))
    return Extension(
        "force_law_refit", cols, params, np.asarray(a, float), T,
        "a smooth function of the contraction, proportional to the pressure, the same in both "
        "directions of motion", check=check, shift=shift, physical=physical,
        note=f"force_law_refit: coefficients a{', a'.join(map(str, free))} refitted"
             + (f" (the contraction spans fewer than {REFIT_MIN_SPAN_SIGMAS:g} noise levels: "
                f"only the force function's level is identifiable)" if narrow else "")), ""


def force_function(a, eps) -> np.ndarray:
    """The force function f(eps) = a0/eps + a1 + a2 eps + a3 eps^2 + a4 eps^3 of (3.9) [N/Pa].

    Parameters
    ----------
    a : array_like, shape (5,)
        Coefficients [N/Pa].
    eps : numpy.ndarray
        Contraction [-] (> 0 where a0 != 0).
    """
    a = np.asarray(a, float)
    inv = a[0] / eps if a[0] != 0.0 else 0.0
    return inv + a[1] + eps * (a[2] + eps * (a[3] + eps * a[4]))


def _force_offset(ctx):
    fmax = float(np.max(np.abs(ctx["f_nom"])))
    lim = OFFSET_MAX_FRACTION * fmax
    return Extension(
        "force_sensor_offset", np.ones((ctx["eps"].size, 1)),
        (Parameter("o", "N", -lim, lim, "load-cell zero error: it reads F + o"),),
        np.zeros(1), np.eye(1),
        "a constant force at every pressure, contraction and direction of motion"), ""


def _force_gain(ctx):
    return Extension(
        "force_sensor_gain", np.asarray(ctx["f_smooth"], float)[:, None],
        (Parameter("g", "-", -GAIN_MAX, GAIN_MAX, "load-cell gain error: it reads (1 + g) F "
                   "(a pressure-sensor gain g_p gives the same column, g = -g_p/(1 + g_p))",
                   phys_lo=-1.0),),
        np.zeros(1), np.eye(1),
        "a force proportional to the nominal force p f(eps), in both directions of motion "
        "(a pressure-sensor gain looks the same)",
        note="force_sensor_gain: a pressure-sensor gain g_p is the same column on a muscle "
             "record (g = -g_p/(1 + g_p): both scale p f(eps)); the force gain is nested in "
             "force_law_refit (a uniform scale of its coefficients)"), ""


def _pressure_offset(ctx):
    eps = ctx["eps_monotone"]
    if ctx["a"][0] != 0.0 and np.any(eps <= 0):
        return None, "pressure_sensor_offset: the force function is not defined at eps <= 0"
    f = force_function(ctx["a"], eps)
    pmax = float(np.max(np.abs(ctx["pressure"])))
    lim = OFFSET_MAX_FRACTION * max(pmax, 1.0)
    return Extension(
        "pressure_sensor_offset", -f[:, None],
        (Parameter("o", "Pa", -lim, lim, "pressure-sensor zero error: it reads p + o"),),
        np.zeros(1), np.eye(1),
        "a force -o f(eps): the same at every pressure, a function of the contraction only, "
        "in both directions of motion"), ""


# ----------------------------------------------------------------------------- the library
# Each candidate: its columns (``build``), its battery draw (the synthesizer's effects that
# hide it, magnitudes log-uniform from below a typical detection limit to the top of the
# plausible range), the gates it needs, the experiments that separate it from a look-alike.

def law_change(a, s0: float, s1: float) -> np.ndarray:
    """Coefficient changes [N/Pa] of a force function off by the relative amount
    ``s0 + s1 (eps - 0.15) / 0.1`` (least squares over :data:`LAW_FIT_RANGE`).

    Parameters
    ----------
    a : array_like, shape (5,)
        Nominal coefficients [N/Pa].
    s0, s1 : float
        Relative level and tilt of the change.
    """
    e = np.linspace(*LAW_FIT_RANGE, 200)
    target = force_function(a, e) * (s0 + s1 * (e - 0.15) / 0.1)
    B = np.column_stack([1.0 / e, np.ones_like(e), e, e ** 2, e ** 3])
    sc = np.sqrt(np.sum(B ** 2, axis=0))
    coef, *_ = np.linalg.lstsq(B / sc, target, rcond=None)
    return coef / sc


def _draw_friction(rng, law, protocol):
    c = logu(rng, 0.2, 30.0)
    fx, tr = {"friction_coulomb": c}, {"c": c, "b": 0.0}
    if protocol["cycles"] >= 2 and rng.random() < 0.3:
        b = logu(rng, 200.0, 2.0e4)
        fx["friction_viscous"] = b
        tr["b"] = b
    return fx, tr


register(MuscleCandidate("actuator_friction", build=_friction, draw=_draw_friction,
                         needs=("reversals",)))


def _draw_hysteresis(rng, law, protocol):
    d = logu(rng, 0.003, 0.3)
    return {"hysteresis_delta": d}, {"delta": d}


register(MuscleCandidate(
    "hysteresis", build=_hysteresis, draw=_draw_hysteresis, needs=("reversals",),
    separating={"actuator_friction":
                "loops of several amplitudes and speeds: friction jumps by 2c at every reversal "
                "whatever the amplitude, hysteresis moves gradually from branch to branch and "
                "scales with the force"}))


def _draw_refit(rng, law, protocol):
    s0 = sgn(rng) * logu(rng, 0.002, 0.08)
    # a pure scale (30 %) is a force-sensor gain on the record: confounded by construction
    s1 = sgn(rng) * logu(rng, 0.002, 0.05) if rng.random() < 0.7 else 0.0
    da = law_change(law, s0, s1)
    return {"force_law_delta": tuple(float(x) for x in da)}, {
        f"a{j}": float(law[j] + da[j]) for j in range(5)}


register(MuscleCandidate(
    "force_law_refit", build=_refit, draw=_draw_refit, needs=("pressure_levels",),
    separating={"hysteresis":
                "cycle the contraction at each pressure: hysteresis shows as a loop between "
                "contracting and extending, a wrong force law does not"}))


def _draw_force_offset(rng, law, protocol):
    o = sgn(rng) * logu(rng, 0.1, 40.0)
    return {"force_sensor_offset": o}, {"o": o}


register(MuscleCandidate(
    "force_sensor_offset", build=_force_offset, sensor_fault=True, draw=_draw_force_offset,
    needs=("pressure_levels",),
    separating={"force_law_refit":
                "record at several pressures (a constant force and one proportional to the "
                "pressure are then distinct), and read the load cell unloaded with the muscle "
                "vented"}))


def _draw_force_gain(rng, law, protocol):
    g = sgn(rng) * logu(rng, 5e-4, 0.08)
    if rng.random() < 0.5:
        # a pressure-sensor gain: the same column, g = 1/(1 + g_p) - 1
        return {"pressure_sensor_gain": g}, {"g": 1.0 / (1.0 + g) - 1.0}
    return {"force_sensor_gain": g}, {"g": g}


register(MuscleCandidate(
    "force_sensor_gain", build=_force_gain, sensor_fault=True, draw=_draw_force_gain,
    separating={"force_law_refit":
                "a dead-weight check of the load cell (known masses hung from it: a gain error "
                "scales their reading) and a calibrated reference gauge on the muscle's "
                "pressure port (a pressure-sensor gain is the same column as a force gain on a "
                "muscle record: both scale p f(eps)); if both sensors read true, the force law "
                "itself is off"}))


def _draw_pressure_offset(rng, law, protocol):
    o = sgn(rng) * logu(rng, 30.0, 2.0e4)
    return {"pressure_sensor_offset": o}, {"o": o}


register(MuscleCandidate(
    "pressure_sensor_offset", build=_pressure_offset, sensor_fault=True,
    draw=_draw_pressure_offset, needs=("pressure_levels",),
    separating={"force_sensor_offset":
                "vent the muscle and read both sensors at 0 bar with the load cell unloaded: a "
                "load-cell zero error shows in the force, a pressure-sensor zero error in the "
                "pressure",
                "force_law_refit": "record at several pressures and read the pressure sensor "
                                   "with the muscle vented (0 bar)"}))

#: Fixed vocabulary of effect names on a tester (actuator records): the library's names.
ACTUATOR_VOCABULARY = tuple(MUSCLE_LIBRARY)
#: The sensor faults of the library.
SENSOR_FAULTS = tuple(n for n, c in MUSCLE_LIBRARY.items() if c.sensor_fault)
#: Candidate -> its column builder (``MuscleCandidate.build``).
BUILDERS = {n: c.build for n, c in MUSCLE_LIBRARY.items()}
#: The experiment that separates the members of a confounded group on a muscle record
#: (the candidates' ``separating``; looked up by :func:`separating_experiment`).
SEPARATING = MUSCLE_LIBRARY.separating_table()


def separating_experiment(members) -> str:
    """The experiment that would separate the members of a confounded group on a muscle record.

    Parameters
    ----------
    members : iterable of str
        Candidate names.
    """
    return friction_separating(members, table=SEPARATING, default=SEPARATING_DEFAULT)


def build_extensions(ctx: dict, names=None) -> tuple:
    """The extensions of the candidates ``names`` on one record.

    Parameters
    ----------
    ctx : dict
        The record's arrays: ``eps`` [-], ``pressure`` [Pa], ``f_nom`` [N]
        (the nominal law at the measured p and eps), ``f_smooth`` [N] (the same
        at ``eps_monotone``), ``direction`` (+1/-1/0), ``speed`` and
        ``speed_unit``, ``a`` (the nominal coefficients, N/Pa), ``eps_monotone``
        (the contraction made monotone between reversals: the Preisach input and
        the argument of every force-function column), ``p_smooth`` [Pa] (the
        pressure of those columns, :func:`~.design.smooth_pressure`), ``speed_ratio``
        (fastest/slowest run), ``eps_span_sigmas`` (contraction span in noise
        levels), ``one_level`` (one pressure level).
    names : sequence of str, optional
        Subset of :data:`~.candidates.ACTUATOR_VOCABULARY` (default all).

    Returns
    -------
    dict
        name -> :class:`Extension` for the applicable candidates.
    list of str
        Notes (candidates left out and why, choices made).
    """
    if names is None:
        names = ACTUATOR_VOCABULARY
    bad = [n for n in names if n not in ACTUATOR_VOCABULARY]
    if bad:
        raise ValueError(f"candidates = {list(names)}: unknown name(s) {bad}; allowed on an "
                         f"actuator record: {list(ACTUATOR_VOCABULARY)}")
    out, notes = {}, []
    for n in names:
        ext, why = BUILDERS[n](ctx)
        if ext is None:
            notes.append(why)
            continue
        if not np.all(np.isfinite(ext.columns)) or not np.any(ext.columns != 0):
            notes.append(f"{n}: its columns vanish or are not finite on this record; left out")
            continue
        out[n] = ext
        if ext.note:
            notes.append(ext.note)
    return out, notes


__all__ = ["Extension", "MuscleCandidate", "MUSCLE_LIBRARY", "law_change", "LAW_FIT_RANGE",
           "build_extensions", "BUILDERS", "ACTUATOR_VOCABULARY", "SENSOR_FAULTS",
           "SEPARATING", "SEPARATING_DEFAULT", "separating_experiment", "force_function",
           "DELTA_PHYSICAL_MAX", "FRICTION_MAX_FRACTION",
           "DELTA_BOUNDS", "REFIT_MAX_RELATIVE", "REFIT_MIN_SPAN_SIGMAS", "VISCOUS_SPEED_RATIO"]
