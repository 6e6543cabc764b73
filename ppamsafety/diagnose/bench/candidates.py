"""The library of candidate effects on a test bench (one actuator: force, pressure, contraction).

The names are fixed (:data:`~.candidates.ACTUATOR_VOCABULARY`).  Every
candidate extends the nominal force law (3.9)
``F_nom = p (a0/eps + a1 + a2 eps + a3 eps^2 + a4 eps^3)`` by a term linear
in its parameters, ``F = F_nom + C phi`` with columns C [N per unit of phi]
computed from the *measured* pressure and contraction history, so it is
fitted by linear regression on the force residual (:mod:`.linear_selection`):

=================  ==============================================  =================================
name               extension (columns)                             parameters
=================  ==============================================  =================================
actuator_friction  ``-c s - b v``: s = direction of motion (+1     c [N] (Coulomb); b [N s/m], or
                   contracting, -1 extending, held at rest),       [N s] without l0 (viscous, only
                   v = l0 d eps/dt [m/s]                           when the speed varies enough)
hysteresis         ``delta F_nom (W[eps_s] - W_fit(eps_s))``,      delta [-] (3.35)
                   (3.34)-(3.35), Preisach operator of §3.6
                   (:mod:`ppamsafety.hysteresis`) along the
                   measured contraction
force_law_refit    ``p (da0/eps + da1 + da2 eps + ...)``: the      a0..a4 [N/Pa] (refitted; the
                   coefficients of (3.9) that are nonzero in the   nominal ones for the terms not
                   nominal law, and a1 always (a cylinder: A)      freed)
=================  ==============================================  =================================

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
measured contraction within +-50 % of the nominal force function there.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from ...hysteresis import EPS_MAX, preisach_response, scaled_input, w_fit
from ..core.parameter import Parameter

#: Fixed vocabulary of effect names on a tester (actuator records).
ACTUATOR_VOCABULARY = ("actuator_friction", "hysteresis", "force_law_refit")
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
            parameter name -> {value, unit, ci_low, ci_high, std_error, nominal}.
        """
        z = stats.norm.ppf(0.5 + confidence / 2)
        v = self.nominal + self.T @ phi
        se = np.sqrt(np.maximum(np.diag(self.T @ cov @ self.T.T), 0.0))
        return {p.name: {"value": float(v[i]), "unit": p.unit, "ci_low": float(v[i] - z * se[i]),
                         "ci_high": float(v[i] + z * se[i]), "std_error": float(se[i]),
                         "nominal": float(self.nominal[i])}
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
        return any(not (p["ci_low"] <= p["nominal"] <= p["ci_high"])
                   for p in self.values(phi, cov).values())

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
        if any(tab[n]["ci_high"] < 0 for n in self.nonnegative):
            return False
        return all(tab[p.name]["ci_low"] >= p.lo - 0.5 * (p.hi - p.lo)
                   and tab[p.name]["ci_high"] <= p.hi + 0.5 * (p.hi - p.lo)
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
    params = [Parameter("c", "N", 0.0, fmax, "Coulomb friction opposing the motion")]
    cols = [-s]
    if use_visc:
        params.append(Parameter("b", bunit, 0.0, fmax / vmax,
                                f"viscous friction (force per unit speed, speed in {vunit})"))
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
    col = ctx["f_nom"] * (W - (a * eps_s + b))
    lo, hi = DELTA_BOUNDS
    return Extension(
        "hysteresis", col[:, None],
        (Parameter("delta", "-", lo, hi, "hysteresis scale of (3.35) (thesis 0.139 for 25 "
                                         "fibres, 0.299 for 40, §3.6.5)"),),
        np.zeros(1), np.eye(1),
        "memory: after a reversal the force moves gradually from one branch to the other, "
        "minor loops are nested; proportional to the force (and so to the pressure)",
        note=f"hysteresis: Preisach memory started from {initial} saturation (eps_max = "
             f"{EPS_MAX}, (3.34)), input: the contraction made monotone between reversals",
        nonnegative=("delta",)), ""


def _refit(ctx):
    a = ctx["a"]
    eps, p = ctx["eps"], ctx["pressure"]
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
    z = stats.norm.ppf(0.975)
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

    params = tuple(Parameter(f"a{j}", "N/Pa", -1.0, 1.0, f"coefficient a{j} of (3.9)")
                   for j in range(5))
    return Extension(
        "force_law_refit", cols, params, np.asarray(a, float), T,
        "a smooth function of the contraction, proportional to the pressure, the same in both "
        "directions of motion", check=check, shift=shift,
        note=f"force_law_refit: coefficients a{', a'.join(map(str, free))} refitted"
             + (f" (the contraction spans fewer than {REFIT_MIN_SPAN_SIGMAS:g} noise levels: "
                f"only the force function's level is identifiable)" if narrow else "")), ""


BUILDERS = {"actuator_friction": _friction, "hysteresis": _hysteresis,
            "force_law_refit": _refit}


def build_extensions(ctx: dict, names=None) -> tuple:
    """The extensions of the candidates ``names`` on one record.

    Parameters
    ----------
    ctx : dict
        The record's arrays: ``eps`` [-], ``pressure`` [Pa], ``f_nom`` [N],
        ``direction`` (+1/-1/0), ``speed`` and ``speed_unit``, ``a`` (the
        nominal coefficients, N/Pa), ``eps_monotone`` (the Preisach input),
        ``speed_ratio`` (fastest/slowest run), ``eps_span_sigmas``
        (contraction span in noise levels).
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


__all__ = ["Extension", "build_extensions", "BUILDERS", "FRICTION_MAX_FRACTION",
           "DELTA_BOUNDS", "REFIT_MAX_RELATIVE", "REFIT_MIN_SPAN_SIGMAS", "VISCOUS_SPEED_RATIO"]
