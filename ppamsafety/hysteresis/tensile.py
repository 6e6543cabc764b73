"""Simulated tensile test of a PPAM and the least-squares fit of delta (thesis §3.6.1, §3.6.5).

The test (§3.6.1).  The muscle is mounted in a tensile testing machine that
imposes the force ``F(t) = A sin(omega t) + B`` with A = 1400 N, B = 750 N,
omega = 2 pi/500 rad/s, at a gauge pressure held as constant as possible by a
servo valve; the contraction is the response (force controlled).  The
thesis fits delta by least squares on the 1.5 bar records (§3.6.5:
delta ~ 0.299 for 40 fibres, ~ 0.139 for 25 fibres).

Simulation (:func:`simulate_tensile_test`).  Force law of the model (3.35)
with the nominal f_fit of (3.9) (default: Table B.1 group 1)::

    F = p f_fit(eps) (1 + delta (W[eps_s] - W_fit(eps_s))),  f_fit = max(0, a0/eps + ... + a4 eps^3)

At every sample the contraction eps solving this for the imposed force is
found by bisection, with the Preisach memory of the previous samples (the
input taken monotone between samples, :func:`~.memory.advance` without
writing), and then committed to the memory.  A muscle cannot push: while the
imposed force is <= 0 it sits at full contraction eps_full (where f_fit
crosses zero) and carries no force, so the recorded force is max(F, 0).
The memory starts from negative saturation (eps = 0, the stretched muscle,
as the thesis requires: the muscle is first brought to an extreme, §3.6.6).
Optional seeded Gaussian noise is added to the recorded force.

Fit (:func:`fit_delta`).  Given W along the recorded contraction (the memory
depends on eps only), the model is linear in delta::

    F_i - p f_i = delta * a_i,   a_i = p f_i (W_i - W_fit(eps_s,i))

so the least-squares delta is sum(a r)/sum(a^2) (closed form), with standard
error sigma_r / sqrt(sum a^2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..plots.identify import plot_delta_fit
from ..results import Result
from .._jit import kernel, leaf
from .._validation import (as_float_array, check_int, check_nonnegative, check_positive,
                           check_range)
from ..params.muscles import TABLE_B1_N_PER_BAR
from ..units import BAR
from .everett import THESIS_WEIGHT, PreisachWeight, check_weight
from .force import EPS_MAX, scaled_contraction, scaled_input
from .memory import MAX_DEPTH, advance, initial_memory
from .preisach import preisach_response, w_fit

#: Imposed force of the tensile test, F = A sin(omega t) + B (thesis §3.6.1).
TENSILE_AMPLITUDE = 1400.0            # N
TENSILE_OFFSET = 750.0                # N
TENSILE_OMEGA = 2.0 * math.pi / 500.0  # rad/s
#: Gauge pressure of the records delta was fitted on (§3.6.5: "measurements taken at p = 1.5 bar").
TENSILE_PRESSURE = 1.5 * BAR          # Pa
#: Default nominal force law: Table B.1 group 1, a0..a4 in N/Pa (= m^2).
DEFAULT_FORCE_LAW = tuple(c / BAR for c in TABLE_B1_N_PER_BAR[0])

_EPS_LO = 1e-9     # lower bracket of the contraction solve (a0/eps is huge there)


def _check_coefficients(force_law) -> np.ndarray:
    coef = as_float_array("force_law", force_law)
    if coef.shape != (5,):
        raise ValueError(f"force_law must be 5 coefficients a0..a4 in N/Pa (eq. 3.9), got "
                         f"shape {coef.shape}")
    if coef[0] <= 0.0:
        raise ValueError(f"force_law a0 = {coef[0]:g} m^2 must be > 0 (the 1/eps term pulls)")
    return coef


def full_contraction(force_law=DEFAULT_FORCE_LAW) -> float:
    """eps_full: the smallest contraction > 0 where the force law (3.9) reaches zero.

    Parameters
    ----------
    force_law : sequence of 5 float
        a0..a4 of (3.9) in N/Pa (= m^2), a0 > 0.

    Returns
    -------
    float
        eps_full, dimensionless.

    Raises
    ------
    ValueError
        If the polynomial has no zero in (0, 1).
    """
    a = _check_coefficients(force_law)
    roots = np.roots(a[::-1])          # eps * f = a0 + a1 eps + ... + a4 eps^4
    real = np.sort(roots[(np.abs(roots.imag) < 1e-12) & (roots.real > 0) & (roots.real < 1)]
                   .real)
    if real.size == 0:
        raise ValueError("force_law has no zero contraction in (0, 1): a muscle force law "
                         "must vanish at full contraction")
    return float(real[0])


def force_law_value(eps, force_law=DEFAULT_FORCE_LAW) -> np.ndarray:
    """f_fit(eps) = max(0, a0/eps + a1 + a2 eps + a3 eps^2 + a4 eps^3) [N/Pa], 0 beyond eps_full.

    Parameters
    ----------
    eps : array_like
        Contraction, dimensionless, > 0.
    force_law : sequence of 5 float
        a0..a4 of (3.9) in N/Pa.
    """
    a = _check_coefficients(force_law)
    e = as_float_array("eps", eps)
    if e.size and e.min() <= 0.0:
        raise ValueError(f"eps must be > 0 (the force law has a0/eps), got min {e.min():g}")
    f = a[0] / e + a[1] + e * (a[2] + e * (a[3] + e * a[4]))
    return np.where(e >= full_contraction(a), 0.0, np.maximum(f, 0.0))


@leaf
def _f(e, a, e_full):
    if e >= e_full:
        return 0.0
    v = a[0] / e + a[1] + e * (a[2] + e * (a[3] + e * a[4]))
    return v if v > 0.0 else 0.0


@kernel
def _tensile(force, p, a, e_full, e_max, delta, wa, wb, z, cap, c, d, inv_z, eps_out, w_out):
    for i in range(force.size):
        target = force[i]
        if target <= 0.0:
            e = e_full
        else:
            lo = _EPS_LO
            hi = e_full
            for _ in range(200):
                mid = 0.5 * (lo + hi)
                if mid <= lo or mid >= hi:
                    break
                es = scaled_contraction(mid, e_max)
                w = advance(z, np.int64(0), cap, es, c, d, inv_z, np.bool_(False))
                g = p * _f(mid, a, e_full) * (1.0 + delta * (w - (wa * es + wb))) - target
                if g > 0.0:
                    lo = mid          # muscle pulls harder than imposed: contracts further
                else:
                    hi = mid
            e = 0.5 * (lo + hi)
        eps_out[i] = e
        w_out[i] = advance(z, np.int64(0), cap, scaled_contraction(e, e_max), c, d, inv_z,
                           np.bool_(True))


def simulate_tensile_test(delta: float, *, pressure: float = TENSILE_PRESSURE,
                          force_law=DEFAULT_FORCE_LAW, amplitude: float = TENSILE_AMPLITUDE,
                          offset: float = TENSILE_OFFSET, omega: float = TENSILE_OMEGA,
                          periods: float = 1.0, samples_per_period: int = 2000,
                          noise_std: float = 0.0, seed=None, eps_max: float = EPS_MAX,
                          weight: PreisachWeight = THESIS_WEIGHT):
    """Force-controlled tensile test of a hysteretic PPAM (model (3.35)), §3.6.1.

    Parameters
    ----------
    delta : float
        True hysteresis scale of the simulated muscle, in [0, 0.5].
    pressure : float, keyword-only
        Constant gauge pressure [Pa], > 0; default 1.5 bar.
    force_law : sequence of 5 float, keyword-only
        Nominal f_fit: a0..a4 of (3.9) in N/Pa; default Table B.1 group 1.
    amplitude, offset : float, keyword-only
        A and B of the imposed force A sin(omega t) + B [N]; defaults 1400 N, 750 N.
    omega : float, keyword-only
        Angular frequency [rad/s], > 0; default 2 pi/500 rad/s.  (The model
        is rate independent: omega only sets the time axis.)
    periods : float, keyword-only
        Length of the record in periods, (0, 100].
    samples_per_period : int, keyword-only
        Samples per period, 16..10^6.
    noise_std : float, keyword-only
        Standard deviation of Gaussian noise added to the recorded force [N], >= 0.
    seed : int or numpy.random.Generator, optional, keyword-only
        Seed of the noise.
    eps_max : float, keyword-only
        eps_max of (3.34), default 0.35.
    weight : PreisachWeight, keyword-only
        Preisach weight (default thesis (3.33)).

    Returns
    -------
    pandas.DataFrame
        Columns ``t`` [s], ``force_command`` [N], ``force`` (recorded:
        max(command, 0) + noise) [N], ``eps`` (contraction, dimensionless),
        ``eps_s`` (3.34), ``W`` (Preisach output).  ``attrs`` holds
        ``delta``, ``pressure`` [Pa], ``force_law`` and ``eps_max``.
    """
    delta = check_range("delta", delta, 0.0, 0.5)
    p = check_positive("pressure", pressure, unit="Pa")
    a = _check_coefficients(force_law)
    amplitude = check_nonnegative("amplitude", amplitude, unit="N")
    offset = check_range("offset", offset, -1e6, 1e6, unit="N")
    omega = check_positive("omega", omega, unit="rad/s")
    periods = check_range("periods", periods, 0.0, 100.0, lo_open=True)
    spp = check_int("samples_per_period", samples_per_period, 16, 1_000_000)
    noise_std = check_nonnegative("noise_std", noise_std, unit="N")
    e_max = check_range("eps_max", eps_max, 0.0, 1.0, lo_open=True)
    w = check_weight(weight)
    e_full = full_contraction(a)
    n = int(round(periods * spp)) + 1
    t = np.arange(n) * (2.0 * math.pi / omega) / spp
    cmd = amplitude * np.sin(omega * t) + offset
    slope, intercept = w_fit(weight=w)
    z = initial_memory("negative", weight=w)
    eps = np.empty(n)
    wv = np.empty(n)
    _tensile(cmd, p, a, e_full, e_max, delta, slope, intercept, z, MAX_DEPTH, w.c, w.d,
             w.inv_z, eps, wv)
    force = np.maximum(cmd, 0.0)
    if noise_std > 0.0:
        rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        force = force + rng.normal(0.0, noise_std, n)
    df = pd.DataFrame({"t": t, "force_command": cmd, "force": force, "eps": eps,
                       "eps_s": scaled_input(eps, e_max), "W": wv})
    df.attrs.update(delta=delta, pressure=p, force_law=tuple(a), eps_max=e_max)
    return df


@dataclass(frozen=True)
class DeltaFit(Result):
    """Result of :func:`fit_delta`.

    Attributes
    ----------
    delta : float
        Least-squares hysteresis scale, dimensionless.
    std_error : float
        Its standard error (from the residual scatter), dimensionless.
    rms_residual : float
        RMS force residual of the fitted model [N].
    rms_residual_nominal : float
        RMS force residual of the model without hysteresis (delta = 0) [N].
    n_samples : int
        Samples used.
    record : pandas.DataFrame
        The record and both models in time order: ``eps`` [-], ``force`` (measured),
        ``force_nominal`` (the force law, no hysteresis) and ``force_fit`` (with the
        fitted hysteresis) [N].
    """

    delta: float
    std_error: float
    rms_residual: float
    rms_residual_nominal: float
    n_samples: int
    record: pd.DataFrame = field(default=None, repr=False)

    def to_pandas(self) -> pd.DataFrame:
        """One row: ``delta``, ``std_error`` [-], ``rms_residual``, ``rms_residual_nominal``
        [N], ``n_samples``."""
        return pd.DataFrame([{"delta": self.delta, "std_error": self.std_error,
                              "rms_residual": self.rms_residual,
                              "rms_residual_nominal": self.rms_residual_nominal,
                              "n_samples": self.n_samples}])

    def plot(self):
        """The record's force against contraction with both models, and the residuals."""
        if self.record is None:
            raise ValueError("this DeltaFit holds no record to draw: make it with fit_delta()")
        return plot_delta_fit(self.record, delta=self.delta, std_error=self.std_error)


def fit_delta(eps, force, pressure, *, force_law=DEFAULT_FORCE_LAW, eps_max: float = EPS_MAX,
              initial="negative", weight: PreisachWeight = THESIS_WEIGHT) -> DeltaFit:
    """Least-squares delta of (3.35) from a tensile-test record (§3.6.5).

    Parameters
    ----------
    eps : array_like, 1-D
        Contraction record in time order, dimensionless, each > 0.
    force : array_like, 1-D
        Measured muscle force at the same samples [N].
    pressure : float or array_like
        Gauge pressure [Pa], > 0 (one value or one per sample).
    force_law : sequence of 5 float, keyword-only
        Nominal f_fit: a0..a4 of (3.9) in N/Pa (default Table B.1 group 1).
    eps_max : float, keyword-only
        eps_max of (3.34), default 0.35.
    initial : keyword-only
        Initial Preisach memory (see :func:`~.preisach.preisach_response`);
        default negative saturation.
    weight : PreisachWeight, keyword-only
        Preisach weight (default thesis (3.33)).

    Returns
    -------
    DeltaFit

    Raises
    ------
    ValueError
        For mismatched lengths, non-finite values, eps <= 0, pressure <= 0,
        or a record on which delta is not identifiable (sum a^2 = 0).
    """
    e = as_float_array("eps", eps)
    f = as_float_array("force", force)
    if e.ndim != 1 or f.shape != e.shape or e.size < 2:
        raise ValueError(f"eps and force must be 1-D of equal length >= 2, got shapes "
                         f"{e.shape} and {f.shape}")
    p = as_float_array("pressure", pressure)
    if p.ndim > 1 or (p.ndim == 1 and p.shape != e.shape):
        raise ValueError(f"pressure must be a scalar or have shape {e.shape}, got {p.shape}")
    if p.min() <= 0.0:
        raise ValueError(f"pressure must be > 0 Pa, got min {p.min():g} Pa")
    w = check_weight(weight)
    e_max = check_range("eps_max", eps_max, 0.0, 1.0, lo_open=True)
    nominal = p * force_law_value(e, force_law)
    es = scaled_input(e, e_max)
    wv = preisach_response(es, initial=initial, weight=w)
    slope, intercept = w_fit(weight=w)
    a = nominal * (wv - (slope * es + intercept))
    r = f - nominal
    saa = float(a @ a)
    if not saa > 0.0:
        raise ValueError("delta is not identifiable from this record (the hysteresis term "
                         "vanishes at every sample)")
    delta = float(a @ r) / saa
    res = r - delta * a
    n = e.size
    sigma = math.sqrt(float(res @ res) / (n - 1))
    return DeltaFit(delta=delta, std_error=sigma / math.sqrt(saa),
                    rms_residual=math.sqrt(float(res @ res) / n),
                    rms_residual_nominal=math.sqrt(float(r @ r) / n), n_samples=n,
                    record=pd.DataFrame({"eps": e, "force": f, "force_nominal": nominal,
                                         "force_fit": nominal + delta * a}))


__all__ = ["DEFAULT_FORCE_LAW", "DeltaFit", "TENSILE_AMPLITUDE", "TENSILE_OFFSET",
           "TENSILE_OMEGA", "TENSILE_PRESSURE", "fit_delta", "force_law_value",
           "full_contraction", "simulate_tensile_test"]
