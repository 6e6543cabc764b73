"""The as-built arm: the library fitted jointly to every printed measurement of the thesis
(Tables 5.2, 6.1, fig. 3.1, §5.3.5).

The thesis prints few numbers about its real arm, but they are real data:

* Table 5.2 (§5.3.4): mean and maximum of ||r_d - r|| for ten controller variants on three
  circles (60 numbers);
* Table 6.1 (§6.3.3): HIC and F_max of the worst of four impact instants of the step and the
  trajectory switch of the same ten variants (40 numbers);
* fig. 3.1 (§3.5.1.6): the RMS angle errors 2.47 deg (q1) and 2.06 deg (q2) of static gravity
  compensation over a sawtooth of set angles (2 numbers);
* §5.3.5's statements about the step and the switch: PSMC responds smoothly and slowly where
  PID is violent, a larger lambda slows the response, and Ki = 12 buys its tracking with "a
  slightly oscillatory step response" (fig. 5.19).

:func:`fit_as_built` fits a vector theta of effect magnitudes (plant effects of
:class:`~ppamsafety.params.effects.Effects` and sensor faults of
:class:`~ppamsafety.control.sensors.SensorConfig`) to all the numbers at once and reports
which directions of theta the numbers can identify at all.

Measurements and their uncertainty
----------------------------------
Every number is compared as a log ratio ln(simulated / printed), divided by its standard
uncertainty ``sigma_log = sqrt(rep^2 + (print_step / sqrt(12) / value)^2)``: the rounding of the
printed value (uniform over one printed step) and a relative run-to-run reproducibility ``rep``
of the real arm.  The thesis gives no repeat measurements, so ``rep`` is **our assumption**,
one per kind (:data:`REPRODUCIBILITY`):

* tracking statistics 10 %, as :data:`~ppamsafety.thesis_fits.summary_fit.REPRODUCIBILITY`
  (the three lambda rows of one Ki, which the thesis says hardly differ, spread by up to
  10 % in Table 5.2);
* F_max 12 % and HIC 25 %: the thesis computed both from the recorded states with its impact
  model (§6.3.3), so they inherit a 10 % reproducibility of the TCP speed at impact through
  F_max ~ v^1.2 and HIC ~ v^2.5 (a Hertz contact, force exponent 3/2: F_max ~ v^(6/5),
  HIC ~ v^(5/2));
* the sawtooth RMS errors 15 %: the thesis does not give the set-angle sequence of fig. 3.1;
  ours (:data:`~ppamsafety.diagnose.arm.synthesize.SAWTOOTH_Q1_DEG`) is a choice, and a
  static error that depends on the set angle changes its RMS with the sequence.

The qualitative statements carry no magnitude, so they do not enter chi2: they are
constraints, tested on the nominal and the fitted plant (:func:`statement_checks`).

What the simulation measures
----------------------------
Each printed number is simulated as the thesis measured it: Table 5.2 and fig. 3.1 from the
*measured* angles (encoder quantisation, encoder offset, noise: the thesis' numbers are
encoder readings), Table 6.1 from the impact model at the four heuristic instants of the
true state (as :mod:`ppamsafety.sections.safety`: the thesis fed recorded states to its model,
and at impact speeds of 0.3-3 m/s the sensors resolve them to better than 1 %).  The circles
are evaluated over a shorter window than the thesis' 40 s (:class:`Design`: one period of
each circle after a 4 s warm-up), which is the steady state of a periodic response at a
third of the cost.

Candidate effects (:data:`CANDIDATES`)
--------------------------------------
Each candidate has a magnitude axis theta: 0 is the nominal arm, 1 the largest plausible
magnitude (:class:`~ppamsafety.params.effects.MagnitudeAxis`, with its reason); a signed
effect (an encoder offset) runs from -1 to 1.  The default set is what these numbers can
speak to: the valve time constant and dead time (tracking lag, overshoot, impact speed),
Coulomb friction (stick-slip in tracking, a dead band at rest), muscle hysteresis (the
sawtooth pattern of fig. 3.1), a payload (gravity-compensation error at rest, impact mass),
the encoder offsets (a static angle error seen only by the sawtooth) and the velocity noise of
the timing board (the Ki = 12 limit cycle).  A pressure-sensor offset acts on these
controllers only through the valves, which regulate on the same sensor (§2.4.3): it is the
valve offset (``valve_offset_delta``), a candidate you can add.

Fit
---
1. *Sensitivities.*  The nominal plant and every candidate at theta = ``step`` (one batched
   closed-loop run per experiment, :func:`~ppamsafety.experiments.closed_loop.run_batch`)
   give the whitened sensitivity matrix J (m x K, per unit theta; a secant, not a
   derivative, so that a threshold effect such as friction registers).
2. *Identifiability.*  Singular values of J (normalised by the largest), numerical rank
   (above :data:`RANK_TOL`), condition number, |cos| between columns (confounded at
   :data:`CONFOUNDED_COS`), the weakest direction, and a subset chosen by QR with column
   pivoting (the classical subset selection): at most ``rank`` candidates, each fitted when
   its column, after removing what the already chosen columns explain, keeps at least
   :data:`RANK_TOL` of the largest column's norm.  The other candidates stay at nominal and
   are reported as confounded or unseen.
3. *Levenberg-Marquardt to convergence* on the chosen subset (:func:`levenberg_marquardt`):
   minimise ``chi2 + sum (theta / PRIOR_SD)^2`` (a prior towards the nominal arm: the end of
   an axis is a two-sigma deviation, ``PRIOR_SD`` = 0.5) inside the axis bounds, by bounded
   linear least-squares steps within a trust region; after each step one evaluation, a
   Broyden update of J, the trust region doubled on success; after a failure on an updated
   J, and before convergence is declared, J is measured afresh by finite differences
   (:data:`PROBE`, all probes in one batch).  Converged when, with a fresh J, the projected
   gradient times the probe step is at most :data:`GTOL` in every theta, or the bounded
   Gauss-Newton step is at most :data:`XTOL`, or the model's steps failed until its trust
   region shrank below :data:`XTOL`; a budget of :data:`MAX_EVALUATIONS` points stops it
   otherwise (reported as not converged).
4. *Intervals.*  95 % intervals from the posterior covariance
   ``s2 (J^T J + I / PRIOR_SD^2)^-1``, scaled by the residual variance s2 = max(1, chi2 /
   (m - k)) as in :mod:`ppamsafety.thesis_fits.summary_fit`, clipped to the axis.
5. *The gap that remains*: chi2 and the geometric-mean ratio per source, the part of the
   remaining residual that *no* candidate can reach (the component outside the span of all
   columns of J, linearised): a large part there means the library lacks the effect; and per
   source the direction in theta that would lower its own chi2 (``pull``): sources pulling
   a candidate in opposite directions are a tug of war no magnitude of it resolves.

Axis ranges.  theta runs from 0 (nominal) to 1 (the axis' largest plausible magnitude); an
encoder offset from -1 to 1; the valve time constant and the Coulomb friction may also lie
*below* their identified values (:data:`BELOW_NOMINAL`: down to half the time constant, a
tenth of the friction), since an identified value is uncertain both ways.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import scipy.linalg
from scipy.optimize import lsq_linear

from .._validation import check_int, check_range
from ..control import GravityCompensation, SensorConfig
from ..control.reference import REFERENCE_ROW
from ..experiments.case import ExperimentCase
from ..experiments.catalog import STEP_TIMES, SWITCH_TIME, thesis_reference, thesis_variants
from ..experiments.closed_loop import run_batch
from ..experiments.conclusions import (evaluate_conclusions, ki12_step_oscillatory,
                                        lambda_slows_recovery, pid_violent_psmc_smooth)
from ..experiments.metrics import response_table
from ..experiments.thesis_data import table_5_2
from ..experiments.trajectories import Reference
from ..impact.instants import evaluate_experiment
from ..impact.thesis_data import table_6_1_long
from ..params import thesis_arm
from ..params.effects import Effects, MagnitudeAxis
from ..params.sensors import TABLE_3_2_VARIANCES
from ..plant import geometry as geo
from ..plots.diagnose import plot_as_built, plot_identifiability
from ..results import Result
from .summary_fit import axis as effect_axis
from ..diagnose.arm.synthesize import plant_with, sawtooth_set_angles

#: Relative run-to-run reproducibility per kind of measurement (our assumptions, module
#: docstring) [-].
REPRODUCIBILITY = {"tracking": 0.10, "F_max": 0.12, "HIC": 0.25, "sawtooth_rms": 0.15}
#: Printed step per kind of measurement (SI): 0.1 mm (Table 5.2, 4 decimals in m), 1 N and
#: 0.01 (Table 6.1), 0.01 deg (§3.5.1.6).
PRINT_STEP = {"tracking": 1e-4, "F_max": 1.0, "HIC": 0.01, "sawtooth_rms": math.radians(0.01)}
#: RMS angle errors of the gravity-compensation sawtooth, §3.5.1.6 (fig. 3.1) [deg].
FIG_3_1_RMS_DEG = (2.47, 2.06)
#: Singular values (and pivoted-QR diagonals) below this fraction of the largest count as 0.
RANK_TOL = 0.05
#: |cosine| between two sensitivity columns at or above which two effects are confounded.
CONFOUNDED_COS = 0.95
#: Prior standard deviation of theta around the nominal arm (an axis end is two sigma) [-].
PRIOR_SD = 0.5
#: Seed of the sensor noise of the velocity-noise candidate (common random numbers: every
#: plant of a fit sees the same draws).
NOISE_SEED = 20
#: Largest |encoder offset| of the sensor-fault candidates [rad]: 3 deg, more than the 2.47 deg
#: RMS of fig. 3.1 it would have to explain on its own.
ENCODER_OFFSET_FULL = math.radians(3.0)
#: Sources of the measurements, in report order.
SOURCES = ("Table 5.2 mean", "Table 5.2 max", "Table 6.1 HIC", "Table 6.1 F_max",
           "fig. 3.1 RMS")

#: Magnitude axes of the sensor-fault candidates (not plant effects: they live in
#: :class:`~ppamsafety.control.sensors.SensorConfig`).
SENSOR_AXES = (
    MagnitudeAxis("encoder_offset_q1", "rad", 0.0, ENCODER_OFFSET_FULL,
                  "a wrong index reference of the q1 encoder (§2.4.5.1), up to 3 deg "
                  "(theta in [-1, 1])"),
    MagnitudeAxis("encoder_offset_q2", "rad", 0.0, ENCODER_OFFSET_FULL,
                  "a wrong index reference of the q2 encoder (§2.4.5.1), up to 3 deg "
                  "(theta in [-1, 1])"),
    MagnitudeAxis("velocity_noise", "x Table 3.2", 0.0, 1.0,
                  "velocity noise up to the Table 3.2 standard deviations, measured on the "
                  "arm (§3.5.2.5)"),
)
#: Sensor axes whose theta is signed (range [-1, 1]).
SIGNED = ("encoder_offset_q1", "encoder_offset_q2")
#: Axes on which theta may go below 0, i.e. below the identified value (lower theta bound):
#: the valve time constants of §3.5.2 to half their value (theta -0.25 on the 1 -> 3x axis;
#: a fitted time constant is uncertain both ways) and the Coulomb friction of Table 3.5 to a
#: tenth (theta -0.1 on the 1 -> 10x axis).  The other effects are zero when nominal.
BELOW_NOMINAL = {"valve_time_constant_factor": -0.25, "friction_coulomb_factor": -0.1}
#: The default candidates (module docstring: what these numbers can speak to).
CANDIDATES = ("valve_time_constant_factor", "valve_dead_time", "friction_coulomb_factor",
              "hysteresis_delta", "payload_mass", "encoder_offset_q1", "encoder_offset_q2",
              "velocity_noise")
#: Secant step of the sensitivities per candidate (theta units).
STEP = 0.5
#: Control period of every simulated experiment [s] (the dead time is whole periods of it).
CONTROL_PERIOD = 1e-3
#: Finite-difference step of the Jacobians of the fit (theta units; a quantised axis, the
#: dead time in whole control periods, is probed by a whole number of its quanta): a few
#: hundredths of an axis, because the simulated statistics are rough at the percent level.
PROBE = 0.05
#: Step tolerance of the fit (theta units): converged when, with a fresh Jacobian, the bounded
#: Gauss-Newton step moves no theta by more than this, or the steps the model proposes fail
#: until its trust region is smaller than this.  Below it the objective is rough (moving a
#: theta by 0.002 changes chi2 by about 10 at the fitted point: the statistics are a maximum
#: over a window and impacts at one sample), so a smaller step resolves noise, not a minimum.
XTOL = 0.02
#: Gradient tolerance of the fit (chi2 + prior per probe step): converged when no theta,
#: moved by one probe step along the projected gradient, lowers chi2 + prior by more than
#: this to first order -- the roughness of chi2 at that scale (see :data:`XTOL`).
GTOL = 10.0
#: Evaluated points after which the fit stops unconverged (trial steps and Jacobian probes).
MAX_EVALUATIONS = 60


def candidate_axis(name: str) -> MagnitudeAxis:
    """The magnitude axis of candidate ``name`` (a plant effect or a sensor fault).

    Parameters
    ----------
    name : str
        An axis of :meth:`Effects.axes() <ppamsafety.params.effects.Effects.axes>` or of
        :data:`SENSOR_AXES`.

    Returns
    -------
    MagnitudeAxis
    """
    if not isinstance(name, str):
        raise TypeError(f"candidate name must be a str, got {name!r}")
    for a in SENSOR_AXES:
        if a.name == name:
            return a
    try:
        return effect_axis(name)
    except ValueError:
        raise ValueError(f"unknown candidate {name!r}; allowed: plant effect axes "
                         f"{[a.name for a in Effects.axes()]} and sensor axes "
                         f"{[a.name for a in SENSOR_AXES]}") from None


def theta_bounds(name: str) -> tuple:
    """Bounds of theta on the axis of candidate ``name``: (-1, 1) for an encoder offset,
    (:data:`BELOW_NOMINAL`, 1) for an effect that may lie below its identified value, else
    (0, 1).

    Parameters
    ----------
    name : str
        A candidate (:func:`candidate_axis`).

    Returns
    -------
    tuple of float
    """
    candidate_axis(name)
    if name in SIGNED:
        return (-1.0, 1.0)
    return (BELOW_NOMINAL.get(name, 0.0), 1.0)


def candidate_probe(name: str, probe: float = PROBE) -> float:
    """Finite-difference step of the fit's Jacobians on the axis of candidate ``name``.

    ``probe`` for a continuous axis; for the valve dead time, which the plant applies in
    whole control periods of :data:`CONTROL_PERIOD`, the smallest whole number of periods
    at least ``probe`` long (in theta units), so that every probe moves the plant by exactly
    its step.

    Parameters
    ----------
    name : str
        A candidate (:func:`candidate_axis`).
    probe : float
        The step of a continuous axis (theta units), in (0, 1].

    Returns
    -------
    float
    """
    ax = candidate_axis(name)
    probe = check_range("probe", probe, 0.0, 1.0, lo_open=True)
    if name == "valve_dead_time":
        q = CONTROL_PERIOD / abs(ax.full - ax.nominal)
        return math.ceil(probe / q - 1e-9) * q
    return probe


def as_built_setup(arm, thetas: dict):
    """The plant truth and the sensors with the candidates at ``thetas``.

    Parameters
    ----------
    arm : ArmParameters
        The nominal arm (the controllers keep it).
    thetas : dict
        Candidate name -> theta (in :func:`theta_bounds`).

    Returns
    -------
    plant : ArmParameters
    sensors : SensorConfig
    """
    if not isinstance(thetas, dict):
        raise TypeError(f"thetas must be a dict {{candidate: theta}}, got "
                        f"{type(thetas).__name__}")
    plant_th, offs, vn = {}, [0.0, 0.0], 0.0
    for name, th in thetas.items():
        lo, hi = theta_bounds(name)
        th = check_range(f"thetas[{name!r}]", th, lo, hi)
        v = candidate_axis(name).value(th)
        if name == "encoder_offset_q1":
            offs[0] = v
        elif name == "encoder_offset_q2":
            offs[1] = v
        elif name == "velocity_noise":
            vn = v
        elif th != 0.0:
            plant_th[name] = v
    plant = _plant(arm, plant_th)
    opts = {}
    if offs != [0.0, 0.0]:
        opts["encoder_offset"] = tuple(offs)
    if vn > 0.0:
        var = np.asarray(TABLE_3_2_VARIANCES, float)
        opts.update(noise=True, seed=NOISE_SEED,
                    noise_variances=(0.0, 0.0, vn ** 2 * var[2], vn ** 2 * var[3]))
    return plant, SensorConfig.for_arm(arm, **opts)


def _plant(arm, values: dict, *, dt: float = None):
    """The plant truth with plant-effect axes at physical magnitudes ``{axis: value}``."""
    dt = CONTROL_PERIOD if dt is None else dt
    eff, rel = {}, {}
    for name, v in values.items():
        if name == "valve_dead_time":
            k = int(round(v / dt))
            if k:
                eff["valve_dead_time"] = (k,) * 4
        elif name == "hysteresis_delta":
            eff["hysteresis_delta"] = (float(v),) * 4
        else:
            rel[name] = v
    plant = plant_with(arm, rel)[0] if rel else arm
    return plant.replace(effects=plant.effects.replace(**eff)) if eff else plant


@dataclass(frozen=True)
class Design:
    """What is simulated for one plant.

    Attributes
    ----------
    variants : tuple of str or None
        Thesis variant labels (None: all ten of Table 6.1).
    periods : tuple of float
        Circle periods [s] (of Table 5.2).
    warmup : float
        Warm-up before each circle's window [s].
    windows : tuple of float
        Evaluation window per period [s].
    step_duration, switch_duration : float
        Length of the step and switch runs [s].
    sawtooth_levels : int or None
        Levels of the sawtooth (None: the whole default sawtooth of
        :func:`~ppamsafety.diagnose.arm.synthesize.sawtooth_set_angles`; an int keeps the
        first levels).
    impacts : bool
        Evaluate Table 6.1 (the head impacts).
    """

    variants: tuple | None = None
    periods: tuple = (5.0, 10.0, 20.0)
    warmup: float = 4.0
    windows: tuple = (5.0, 10.0, 20.0)
    step_duration: float = 12.0
    switch_duration: float = 15.0
    sawtooth_levels: int | None = None
    impacts: bool = True

    def __post_init__(self):
        if self.variants is not None:
            known = {v.label for v in thesis_variants()}
            bad = [v for v in self.variants if v not in known]
            if not self.variants or bad:
                raise ValueError(f"Design.variants: {bad or 'empty'} — allowed: thesis variant "
                                 f"labels {sorted(known)}")
        if len(self.windows) != len(self.periods) or not self.periods:
            raise ValueError(f"Design.windows {self.windows!r} must give one window per period "
                             f"{self.periods!r}")
        allowed = set(table_5_2().period_s)
        if any(P not in allowed for P in self.periods):
            raise ValueError(f"Design.periods {self.periods!r}: allowed {sorted(allowed)} s")
        for w in self.windows:
            check_range("Design.windows", w, 0.5, 60.0, unit="s")
        check_range("Design.warmup", self.warmup, 0.0, 60.0, unit="s")
        check_range("Design.step_duration", self.step_duration, STEP_TIMES[0] + 1.0, 60.0,
                    unit="s")
        check_range("Design.switch_duration", self.switch_duration, SWITCH_TIME + 1.0, 60.0,
                    unit="s")
        if self.sawtooth_levels is not None:
            check_int("Design.sawtooth_levels", self.sawtooth_levels, 3, 1000)

    @classmethod
    def quick(cls) -> "Design":
        """A design for smoke tests: short windows and runs, a 4-level sawtooth."""
        return cls(warmup=1.0, windows=(5.0, 5.0, 5.0), step_duration=9.0,
                   switch_duration=10.0, sawtooth_levels=4)

    def variant_list(self) -> list:
        """The :class:`~ppamsafety.experiments.catalog.ControllerVariant` s simulated."""
        vs = thesis_variants()
        return vs if self.variants is None else [v for v in vs if v.label in self.variants]

    @property
    def complete(self) -> bool:
        """All ten variants and the three periods: the thesis' conclusions can be tested."""
        return self.variants is None and tuple(sorted(self.periods)) == (5.0, 10.0, 20.0)


def thesis_measurements(design: Design | None = None) -> pd.DataFrame:
    """Every printed measurement of the real arm the design simulates, with its uncertainty.

    Parameters
    ----------
    design : Design, optional
        Keeps the cells of its variants and periods (default all).

    Returns
    -------
    pandas.DataFrame
        One row per number: ``key`` (unique), ``source`` (:data:`SOURCES`), ``experiment``
        (``circle5`` ..., ``step``, ``switch``, ``sawtooth``), ``variant`` (label; "" for
        the sawtooth), ``statistic``, ``value`` (SI: m, -, N, rad), ``unit``, ``print_step``,
        ``reproducibility`` and ``sigma_log`` (module docstring).
    """
    design = Design() if design is None else design
    if not isinstance(design, Design):
        raise TypeError(f"design must be a Design, got {type(design).__name__}")
    labels = [v.label for v in design.variant_list()]
    rows = []

    def add(source, experiment, variant, statistic, value, unit, kind):
        step = PRINT_STEP[kind]
        rep = REPRODUCIBILITY[kind]
        rows.append({"key": f"{source}|{experiment}|{variant}", "source": source,
                     "experiment": experiment, "variant": variant, "statistic": statistic,
                     "value": float(value), "unit": unit, "print_step": step,
                     "reproducibility": rep,
                     "sigma_log": math.sqrt(rep ** 2 + (step / math.sqrt(12.0) / value) ** 2)})

    t52 = table_5_2()
    for P in design.periods:
        for lab in labels:
            r = t52[(t52.variant == lab) & (t52.period_s == P)].iloc[0]
            add("Table 5.2 mean", f"circle{P:g}", lab, "mean", r.thesis_mean_m, "m", "tracking")
            add("Table 5.2 max", f"circle{P:g}", lab, "max", r.thesis_max_m, "m", "tracking")
    if design.impacts:
        t61 = table_6_1_long()
        by = {(v.family.value, v.ki_bar, v.lambda_s): v.label for v in thesis_variants()}
        for r in t61.itertuples():
            lab = _label_of(by, r.controller_family, r.ki_bar, r.lambda_s)
            if lab in labels:
                add("Table 6.1 HIC", r.experiment, lab, "HIC36", r.HIC_thesis, "-", "HIC")
                add("Table 6.1 F_max", r.experiment, lab, "F_max", r.Fmax_thesis, "N", "F_max")
    for j, v in enumerate(FIG_3_1_RMS_DEG):
        add("fig. 3.1 RMS", "sawtooth", f"q{j + 1}", f"rms_q{j + 1}", math.radians(v), "rad",
            "sawtooth_rms")
    return pd.DataFrame(rows)


def _label_of(by, fam, ki, lam):
    for (f, k, lm), lab in by.items():
        if f == fam and _same(k, ki) and _same(lm, lam):
            return lab
    return None


def _same(a, b):
    return (pd.isna(a) and pd.isna(b)) or (not pd.isna(a) and not pd.isna(b) and a == b)


def sawtooth_reference(arm, levels: int | None = None, *, dt: float = 1e-3):
    """The gravity-compensation sawtooth of §3.5.1.6 as a closed-loop reference.

    Parameters
    ----------
    arm : ArmParameters
        The arm (for the TCP columns).
    levels : int, optional
        Keep the first ``levels`` levels (default the whole default sawtooth).
    dt : float, keyword-only
        Sample time [s].

    Returns
    -------
    reference : Reference
    windows : numpy.ndarray of int, shape (m, 2)
        First and one-past-last sample of each data window.
    """
    t, q, win = sawtooth_set_angles(dt=dt)
    if levels is not None:
        levels = check_int("levels", levels, 3, len(win))
        win = win[:levels]
        t, q = t[:win[-1, 1]], q[:win[-1, 1]]
    qd = np.gradient(q, dt, axis=0)
    data = REFERENCE_ROW.empty(t.size)
    data[:, REFERENCE_ROW.slice("q_d")] = q
    data[:, REFERENCE_ROW.slice("qd_d")] = qd
    data[:, REFERENCE_ROW.slice("qdd_d")] = np.gradient(qd, dt, axis=0)
    data[:, REFERENCE_ROW.slice("r_d")] = geo.forward_kinematics(q, arm)
    data[:, REFERENCE_ROW.slice("rd_d")] = np.einsum("nij,nj->ni", geo.jacobian(q, arm), qd)
    return Reference("gravity-compensation sawtooth", t, data, dt), win


@dataclass(eq=False)
class PlantEvaluation:
    """Everything the design measures on one plant (one point theta).

    Attributes
    ----------
    thetas : dict
        Candidate -> theta.
    values : pandas.Series
        Simulated value per measurement key (SI; NaN: diverged or not simulated).
    errors : pandas.DataFrame
        Tracking errors per variant and period (columns of
        :mod:`ppamsafety.experiments.conclusions`: ``variant``, ``family``, ``lambda_s``,
        ``period_s``, ``mean_m``, ``max_m``).
    step, switch : pandas.DataFrame
        :func:`~ppamsafety.experiments.metrics.response_table` with ``family``, ``lambda_s``.
    impacts : pandas.DataFrame
        experiment, variant, HIC36, F_max (worst of the four instants).
    sawtooth_rms_deg : tuple of float
        Measured RMS angle errors of the sawtooth (q1, q2) [deg].
    diverged : bool
        A run of this plant diverged.
    """

    thetas: dict
    values: pd.Series
    errors: pd.DataFrame
    step: pd.DataFrame
    switch: pd.DataFrame
    impacts: pd.DataFrame
    sawtooth_rms_deg: tuple
    diverged: bool = False


def _meta(v, experiment):
    return {"label": v.label, "experiment": experiment, "family": v.group,
            "lambda_s": v.lambda_s, "ki_bar": v.ki_bar, "controller_family": v.family.value,
            "variant": v}


def _measured_error(r, arm) -> np.ndarray:
    """||r_d - r_measured|| per sample [m]: the tracking error the encoders report."""
    q = r.signals("q1_meas", "q2_meas")
    xy = geo.forward_kinematics(q, arm)
    return np.hypot(r.signal("x_d") - xy[:, 0], r.signal("y_d") - xy[:, 1])


@dataclass(frozen=True)
class DesignReferences:
    """The references a :class:`Design` runs, made once for all the plants of a fit.

    Attributes
    ----------
    circles : dict
        Period [s] -> circle reference (warm-up plus window).
    step, switch : Reference
    sawtooth : Reference
    sawtooth_windows : numpy.ndarray of int, shape (m, 2)
        Data windows of the sawtooth (:func:`sawtooth_reference`).
    """

    circles: dict
    step: Reference
    switch: Reference
    sawtooth: Reference
    sawtooth_windows: np.ndarray

    @classmethod
    def of(cls, arm, design: "Design") -> "DesignReferences":
        """The references of ``design`` for the nominal ``arm``.

        Parameters
        ----------
        arm : ArmParameters
            The nominal arm (the references' kinematics).
        design : Design
            What is simulated.

        Returns
        -------
        DesignReferences
        """
        if not isinstance(design, Design):
            raise TypeError(f"design must be a Design, got {type(design).__name__}")
        saw, win = sawtooth_reference(arm, design.sawtooth_levels)
        return cls(circles={P: thesis_reference(arm, f"circle{P:g}", duration=design.warmup + w)
                            for P, w in zip(design.periods, design.windows)},
                   step=thesis_reference(arm, "step", duration=design.step_duration),
                   switch=thesis_reference(arm, "switch", duration=design.switch_duration),
                   sawtooth=saw, sawtooth_windows=win)


def evaluate_plants(arm, setups: list, design: Design, *, head=None,
                    thetas: list | None = None, references: DesignReferences | None = None
                    ) -> list:
    """Simulate every measurement of ``design`` for several (plant, sensors) at once.

    One batched closed-loop run per experiment (circle per period, step, switch, sawtooth)
    over all setups and variants, on every core
    (:func:`~ppamsafety.experiments.closed_loop.run_batch`); impacts per run.

    Parameters
    ----------
    arm : ArmParameters
        The nominal arm (references, controllers, kinematics of the measured error).
    setups : list of (ArmParameters, SensorConfig)
        Plant truth and sensors of each point (:func:`as_built_setup`).
    design : Design
    head : HeadContactModel or str, optional, keyword-only
        Head of the impacts (default ``thesis-frontal``).
    thetas : list of dict, optional, keyword-only
        The thetas of each setup (stored in the result).
    references : DesignReferences, optional, keyword-only
        The references of ``design`` for ``arm`` (default: made here); a fit that evaluates
        many plants makes them once.

    Returns
    -------
    list of PlantEvaluation
    """
    if not isinstance(design, Design):
        raise TypeError(f"design must be a Design, got {type(design).__name__}")
    if not setups:
        raise ValueError("setups must not be empty")
    refs = DesignReferences.of(arm, design) if references is None else references
    if not isinstance(refs, DesignReferences):
        raise TypeError(f"references must be a DesignReferences, got {type(refs).__name__}")
    thetas = [{}] * len(setups) if thetas is None else thetas
    vs = design.variant_list()
    nv = len(vs)
    vals = [dict() for _ in setups]
    err_rows = [[] for _ in setups]
    bad = [False] * len(setups)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)          # divergence: NaN statistics
        for P in design.periods:
            name = f"circle{P:g}"
            ref = refs.circles[P]
            res = run_batch([ExperimentCase(pl, v.controller, ref, sensors=s,
                                            meta=_meta(v, name))
                             for pl, s in setups for v in vs])
            m = ref.t >= design.warmup
            for i, r in enumerate(res):
                k, v = divmod(i, nv)
                e = _measured_error(r, arm)[m]
                ok = not r.diverged and np.all(np.isfinite(e))
                bad[k] |= not ok
                mean, mx = (float(e.mean()), float(e.max())) if ok else (np.nan, np.nan)
                vals[k][f"Table 5.2 mean|{name}|{vs[v].label}"] = mean
                vals[k][f"Table 5.2 max|{name}|{vs[v].label}"] = mx
                err_rows[k].append({"variant": vs[v].label, "family": vs[v].group,
                                    "lambda_s": vs[v].lambda_s, "period_s": P, "mean_m": mean,
                                    "max_m": mx})
        runs, tables = {}, {}
        for name, ref in (("step", refs.step), ("switch", refs.switch)):
            res = run_batch([ExperimentCase(pl, v.controller, ref, sensors=s,
                                            meta=_meta(v, name))
                             for pl, s in setups for v in vs])
            runs[name] = res
            tables[name] = []
            for k in range(len(setups)):
                rr = res[k * nv:(k + 1) * nv]
                bad[k] |= any(r.diverged for r in rr)
                t = response_table(rr, experiment=name)
                t.insert(1, "family", [v.group for v in vs])
                t.insert(2, "lambda_s", [v.lambda_s for v in vs])
                tables[name].append(t)
        imp = [[] for _ in setups]
        if design.impacts:
            for name in ("step", "switch"):
                for i, r in enumerate(runs[name]):
                    k, v = divmod(i, nv)
                    if r.diverged:
                        hic = fmax = np.nan
                    else:
                        ev = evaluate_experiment(r, setups[k][0], head=head).summary
                        hic, fmax = float(ev.HIC36.max()), float(ev.F_max.max())
                    vals[k][f"Table 6.1 HIC|{name}|{vs[v].label}"] = hic
                    vals[k][f"Table 6.1 F_max|{name}|{vs[v].label}"] = fmax
                    imp[k].append({"experiment": name, "variant": vs[v].label, "HIC36": hic,
                                   "F_max": fmax})
        ref, win = refs.sawtooth, refs.sawtooth_windows
        res = run_batch([ExperimentCase(pl, GravityCompensation(at="desired"), ref, sensors=s,
                                        name="sawtooth") for pl, s in setups])
        idx = np.concatenate([np.arange(a, b) for a, b in win])
        saw = []
        for k, r in enumerate(res):
            e = (r.signals("q1_meas", "q2_meas") - r.signals("q1_d", "q2_d"))[idx]
            rms = np.sqrt(np.mean(e ** 2, axis=0)) if not r.diverged else np.full(2, np.nan)
            bad[k] |= bool(r.diverged)
            vals[k]["fig. 3.1 RMS|sawtooth|q1"] = float(rms[0])
            vals[k]["fig. 3.1 RMS|sawtooth|q2"] = float(rms[1])
            saw.append(tuple(float(x) for x in np.degrees(rms)))
    return [PlantEvaluation(thetas=dict(thetas[k]), values=pd.Series(vals[k], dtype=float),
                            errors=pd.DataFrame(err_rows[k]), step=tables["step"][k],
                            switch=tables["switch"][k],
                            impacts=pd.DataFrame(imp[k], columns=["experiment", "variant",
                                                                  "HIC36", "F_max"]),
                            sawtooth_rms_deg=saw[k], diverged=bad[k])
            for k in range(len(setups))]


def whitened_residuals(values: pd.Series, measurements: pd.DataFrame) -> np.ndarray:
    """ln(simulated / printed) / sigma_log per measurement (order of ``measurements``).

    A simulated value that is missing, not finite or not positive gives NaN.

    Parameters
    ----------
    values : pandas.Series
        Simulated value per key.
    measurements : pandas.DataFrame
        :func:`thesis_measurements` format.

    Returns
    -------
    numpy.ndarray, shape (m,)
    """
    sim = values.reindex(measurements.key).to_numpy(dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.log(sim / measurements.value.to_numpy(float)) / measurements.sigma_log.to_numpy()
    return np.where(np.isfinite(r), r, np.nan)


def check_measurements(measurements) -> pd.DataFrame:
    """Validate a measurement table (:func:`thesis_measurements` format).

    Parameters
    ----------
    measurements : pandas.DataFrame

    Returns
    -------
    pandas.DataFrame
        The table.

    Raises
    ------
    TypeError, ValueError
        Not a DataFrame, a missing column, duplicate keys, a value or sigma that is not
        positive and finite.
    """
    if not isinstance(measurements, pd.DataFrame):
        raise TypeError(f"measurements must be a pandas DataFrame (thesis_measurements "
                        f"format), got {type(measurements).__name__}")
    need = ["key", "source", "experiment", "variant", "statistic", "unit", "value",
            "sigma_log"]
    missing = [c for c in need if c not in measurements.columns]
    if missing:
        raise ValueError(f"measurements lacks the column(s) {missing}; needs {need}")
    if measurements.key.duplicated().any():
        raise ValueError(f"measurements: duplicate keys "
                         f"{measurements.key[measurements.key.duplicated()].tolist()[:3]}")
    for c in ("value", "sigma_log"):
        v = pd.to_numeric(measurements[c], errors="coerce").to_numpy(float)
        if not np.all(np.isfinite(v) & (v > 0)):
            raise ValueError(f"measurements.{c} must be positive and finite, got "
                             f"{measurements[c][~(np.isfinite(v) & (v > 0))].tolist()[:3]}")
    if len(measurements) < 2:
        raise ValueError(f"measurements must hold at least 2 numbers, got {len(measurements)}")
    return measurements


# ----------------------------------------------------------------------------------------
# identifiability


@dataclass(eq=False)
class Identifiability(Result):
    """What the sensitivity matrix J (whitened, per unit theta) says the data can identify.

    Attributes
    ----------
    names : tuple of str
        Candidates (columns of J).
    sensitivity : numpy.ndarray, shape (m, K)
    column_norm : numpy.ndarray, shape (K,)
        Change of the whitened residual vector per unit theta (a norm of 1 moves chi2 by
        about 1 at theta = 1).
    singular_values : numpy.ndarray
        Of J, divided by the largest.
    rank : int
        Singular values above :data:`RANK_TOL`.
    condition : float
    weakest_direction : dict
        Candidate -> loading of the right singular vector of the smallest singular value.
    cosines : pandas.DataFrame
        |cos| between the columns.
    confounded : list of tuple
        (a, b, |cos|) with |cos| >= :data:`CONFOUNDED_COS`.
    selected : tuple of str
        The identifiable subset: the first ``rank`` pivots of a QR with column pivoting whose
        pivot ratio reaches :data:`RANK_TOL`.
    pivot_ratio : dict
        Candidate -> |R_kk| / |R_00| in pivot order (the part of its column the earlier
        pivots do not explain, relative to the first).
    """

    names: tuple
    sensitivity: np.ndarray
    column_norm: np.ndarray
    singular_values: np.ndarray
    rank: int
    condition: float
    weakest_direction: dict
    cosines: pd.DataFrame
    confounded: list
    selected: tuple
    pivot_ratio: dict

    def to_pandas(self) -> pd.DataFrame:
        """One row per candidate: column norm, pivot ratio, selected, most confounded with."""
        rows = []
        for k, n in enumerate(self.names):
            c = self.cosines.loc[n].drop(n)
            rows.append({"candidate": n, "column_norm": float(self.column_norm[k]),
                         "pivot_ratio": float(self.pivot_ratio.get(n, 0.0)),
                         "selected": n in self.selected,
                         "most_like": c.idxmax() if len(c) else "",
                         "abs_cos": float(c.max()) if len(c) else float("nan"),
                         "weakest_loading": float(self.weakest_direction[n])})
        return pd.DataFrame(rows)

    def plot(self, *, rank_tol: float = RANK_TOL):
        """Column norms, singular values and |cos| between the candidates; a Figure.

        Parameters
        ----------
        rank_tol : float, keyword-only
            Rank threshold drawn (default :data:`RANK_TOL`).
        """
        return plot_identifiability(self.names, self.column_norm, self.cosines, self.selected,
                                    self.singular_values, rank_tol=rank_tol)


def identifiability(J, names, *, rank_tol: float = RANK_TOL,
                    confounded_cos: float = CONFOUNDED_COS) -> Identifiability:
    """Rank, condition, confounded pairs and the identifiable subset of a sensitivity matrix.

    Parameters
    ----------
    J : array_like, shape (m, K)
        Whitened sensitivities per unit theta (NaN rows are dropped).
    names : sequence of str
        Column names.
    rank_tol : float, keyword-only
        Relative threshold of the numerical rank and of the pivoted QR.
    confounded_cos : float, keyword-only
        |cos| of confounded pairs.

    Returns
    -------
    Identifiability
    """

    J = np.asarray(J, dtype=float)
    names = tuple(names)
    if J.ndim != 2 or J.shape[1] != len(names) or J.shape[1] == 0:
        raise ValueError(f"J must have shape (m, {len(names)}), got {J.shape}")
    rank_tol = check_range("rank_tol", rank_tol, 0.0, 1.0, lo_open=True)
    J = J[np.all(np.isfinite(J), axis=1)]
    norms = np.linalg.norm(J, axis=0)
    sv = np.linalg.svd(J, compute_uv=False) if J.size else np.zeros(len(names))
    _, _, Vt = np.linalg.svd(J, full_matrices=False)
    svn = sv / sv[0] if sv[0] > 0 else sv
    rank = int(np.sum(svn > rank_tol))
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf
    safe = np.maximum(norms, 1e-300)
    C = (J.T @ J) / np.outer(safe, safe)
    cos = pd.DataFrame(np.abs(C), index=list(names), columns=list(names))
    conf = [(a, b, float(abs(C[i, j]))) for i, a in enumerate(names)
            for j, b in enumerate(names) if j > i and abs(C[i, j]) >= confounded_cos]
    _, R, piv = scipy.linalg.qr(J, mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    ratio = d / d[0] if d.size and d[0] > 0 else np.zeros_like(d)
    pr = {names[p]: float(ratio[i]) for i, p in enumerate(piv[:len(d)])}
    selected = tuple(names[p] for i, p in enumerate(piv[:min(len(d), rank)])
                     if ratio[i] >= rank_tol)
    selected = tuple(n for n in names if n in selected)          # declaration order
    weakest = {n: float(Vt[-1, k]) for k, n in enumerate(names)}
    return Identifiability(names=names, sensitivity=J, column_norm=norms,
                           singular_values=svn, rank=rank, condition=cond,
                           weakest_direction=weakest, cosines=cos, confounded=conf,
                           selected=selected, pivot_ratio=pr)


# ----------------------------------------------------------------------------------------
# the fit


@dataclass(eq=False)
class FitPath:
    """The iterations of :func:`levenberg_marquardt` and how they ended.

    Attributes
    ----------
    theta : numpy.ndarray
        Best point (selected candidates).
    objective : float
        chi2 + prior at the best point.
    chi2 : float
        chi2 of the data at the best point.
    residual : numpy.ndarray
        Whitened residuals at the best point.
    jacobian : numpy.ndarray
        The sensitivity matrix at the end: a finite-difference Jacobian at the best point
        when ``jacobian_fresh`` (always so for a converged fit), else the Broyden-updated one.
    history : pandas.DataFrame
        One row per evaluated point: iteration, kind (``"start"``, ``"step"`` (a trial
        step) or ``"jacobian"`` (the finite-difference Jacobian at the current point, one
        row for its batch of probes)), accepted, chi2, objective, radius, theta.
    evaluations : int
        Points evaluated after the sensitivities (trial steps and Jacobian probes).
    best_index : int
        Row of ``history`` of the best point (0 = start).
    converged : bool
        A convergence criterion holds at the best point (with a fresh Jacobian).
    reason : str
        Which criterion holds (``"gradient"``, ``"step"``, ``"trust region"``), or why the
        fit stopped without (``"evaluation budget"``).
    gradient : numpy.ndarray
        d(chi2 + prior)/d theta at the best point from the final Jacobian, projected on the
        bounds (a component that points out of the box at an active bound is 0).
    gauss_newton_step : numpy.ndarray
        The step the final linear model takes to its bounded minimum (no trust region).
    jacobian_fresh : bool
        ``jacobian`` is a finite-difference Jacobian at the best point.
    """

    theta: np.ndarray
    objective: float
    chi2: float
    residual: np.ndarray
    jacobian: np.ndarray
    history: pd.DataFrame
    evaluations: int
    best_index: int
    converged: bool = False
    reason: str = ""
    gradient: np.ndarray = field(default_factory=lambda: np.zeros(0))
    gauss_newton_step: np.ndarray = field(default_factory=lambda: np.zeros(0))
    jacobian_fresh: bool = False


def _objective(r, theta, prior_sd):
    rr = np.where(np.isfinite(r), r, 0.0)
    return float(np.sum(rr ** 2) + np.sum((theta / prior_sd) ** 2)), float(np.sum(rr ** 2))


def _bounded_step(J, r, th, prior_sd, lo, hi):
    """The step s minimising ||r + J s||^2 + ||(th + s)/prior_sd||^2 for lo <= th + s <= hi."""
    k = th.size
    A = np.vstack([J, np.eye(k) / prior_sd])
    b = np.concatenate([J @ th - r, np.zeros(k)])
    hi = np.where(hi <= lo, lo + 1e-12, hi)
    return lsq_linear(A, b, bounds=(lo, hi)).x - th


def _projected_gradient(J, r, th, prior_sd, lower, upper):
    """d(chi2 + prior)/d theta, zero where an active bound stops the descent."""
    g = 2.0 * (J.T @ r + th / prior_sd ** 2)
    at_lo = (th <= lower + 1e-12) & (g > 0.0)
    at_hi = (th >= upper - 1e-12) & (g < 0.0)
    return np.where(at_lo | at_hi, 0.0, g)


def levenberg_marquardt(evaluate, theta0, r0, J0, *, lower, upper, probe,
                        prior_sd: float = PRIOR_SD, xtol: float = XTOL, gtol: float = GTOL,
                        max_evaluations: int = MAX_EVALUATIONS, radius: float = 0.5,
                        max_radius: float = 0.5) -> FitPath:
    """Bounded Levenberg-Marquardt to a stated convergence criterion.

    Minimises ``F(theta) = ||r(theta)||^2 + ||theta / prior_sd||^2`` for ``lower <= theta
    <= upper``.  Each iteration solves the linearised problem inside the trust region
    ``|dtheta|_inf <= radius`` by bounded linear least squares and evaluates the point; an
    accepted step (F lower) doubles the radius (up to ``max_radius``) and updates J by
    Broyden's rank-one secant formula.  When a step fails on a Broyden-updated J, the radius
    is halved and J is measured afresh by finite differences at the current point
    (``theta + probe_j e_j``, or minus where the upper bound is too close; all probes in one
    batch), as it is before convergence is declared; when a step fails on a fresh J, the
    radius becomes a quarter of that step.

    Convergence, tested only with a fresh finite-difference Jacobian at the current point:

    * *gradient*: every component of the projected gradient of F, times its probe step, is
      at most ``gtol`` (moving any theta by one probe step along the gradient lowers chi2 +
      prior by at most ``gtol`` to first order);
    * *step*: the bounded Gauss-Newton step of the linear model (no trust region) moves
      every theta by at most ``xtol``;
    * *trust region*: every step the fresh model proposed raised F, until the trust region
      shrank below ``xtol`` (a minimum at the resolution ``xtol``, though not one the linear
      model predicts: its gradient and Gauss-Newton step are reported).

    The fit also stops after ``max_evaluations`` evaluated points (reported as not
    converged).  A finite difference over a probe step of a few hundredths of an axis, not
    an infinitesimal one: the simulated statistics are rough at the percent level (a
    maximum over a window, the impact at the sample of the largest speed), which a smaller
    step would turn into noise.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(thetas) -> list of r``: whitened residuals (NaN for a failed number) of
        each point of the list ``thetas``, evaluated together (one batch).
    theta0 : array_like, shape (k,)
        Start (the nominal arm: zeros).
    r0 : array_like, shape (m,)
        Residuals at ``theta0``.
    J0 : array_like, shape (m, k)
        Sensitivities to start with (e.g. secants from ``theta0``).
    lower, upper : array_like, shape (k,), keyword-only
        Bounds of theta.
    probe : array_like, shape (k,), keyword-only
        Finite-difference steps of the Jacobian (theta units, > 0).
    prior_sd : float, keyword-only
        Prior standard deviation of theta around 0.
    xtol : float, keyword-only
        Step tolerance (theta units).
    gtol : float, keyword-only
        Gradient tolerance (chi2 + prior per probe step).
    max_evaluations : int, keyword-only
        Largest number of points evaluated (0: none; the start is returned).
    radius : float, keyword-only
        Initial trust radius (theta units).
    max_radius : float, keyword-only
        Largest trust radius.

    Returns
    -------
    FitPath
    """
    th = np.asarray(theta0, float).copy()
    r = np.asarray(r0, float).copy()
    J = np.asarray(J0, float).copy()
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    probe = np.asarray(probe, float)
    k = th.size
    if J.shape != (r.size, k):
        raise ValueError(f"J0 must have shape ({r.size}, {k}), got {J.shape}")
    if probe.shape != (k,) or not np.all(np.isfinite(probe) & (probe > 0)):
        raise ValueError(f"probe must hold {k} positive finite steps, got {probe!r}")
    prior_sd = check_range("prior_sd", prior_sd, 0.0, 1e6, lo_open=True)
    xtol = check_range("xtol", xtol, 0.0, 1.0, lo_open=True)
    gtol = check_range("gtol", gtol, 0.0, 1e12, lo_open=True)
    max_evaluations = check_int("max_evaluations", max_evaluations, 0, 10000)
    ok = np.isfinite(r)
    obj, chi2 = _objective(r, th, prior_sd)
    hist = [{"iteration": 0, "kind": "start", "accepted": True, "chi2": chi2, "objective": obj,
             "radius": radius, "theta": th.tolist()}]
    best_i, evals, it, fresh = 0, 0, 0, False
    reason = ""

    def refresh():
        """J by finite differences at th (one batch); False if the budget does not allow."""
        nonlocal J, fresh, evals
        if evals + k > max_evaluations:
            return False
        h = np.where(th + probe <= upper + 1e-12, probe, -probe)
        pts = [th + h[j] * np.eye(k)[j] for j in range(k)]
        R = np.asarray(evaluate(pts), float)
        evals += k
        Jn = (R - r).T / h
        J = np.where(np.isfinite(Jn), Jn, 0.0)
        fresh = True
        hist.append({"iteration": it, "kind": "jacobian", "accepted": False, "chi2": np.nan,
                     "objective": np.nan, "radius": radius, "theta": th.tolist()})
        return True

    while True:
        Jok, rok = J[ok], r[ok]
        if fresh:
            g = _projected_gradient(Jok, rok, th, prior_sd, lower, upper)
            s_gn = _bounded_step(Jok, rok, th, prior_sd, lower, upper)
            if np.max(np.abs(g) * probe) <= gtol:
                reason = "gradient"
                break
            if np.max(np.abs(s_gn)) <= xtol:
                reason = "step"
                break
        if evals >= max_evaluations:
            reason = "evaluation budget"
            break
        s = _bounded_step(Jok, rok, th, prior_sd, np.maximum(lower, th - radius),
                          np.minimum(upper, th + radius))
        if np.max(np.abs(s)) <= xtol:
            if not fresh:                  # a stale model proposes no move: measure J
                if not refresh():
                    reason = "evaluation budget"
                    break
                continue
            if radius <= xtol:             # a fresh model, and no decrease within xtol
                reason = "trust region"
                break
        it += 1
        new = th + s
        rn = np.asarray(evaluate([new])[0], float)
        evals += 1
        okn = np.isfinite(rn) & ok
        on, cn = _objective(np.where(okn, rn, np.nan), new, prior_sd)
        complete = okn.sum() == ok.sum()
        accepted = bool(complete and on < obj)
        hist.append({"iteration": it, "kind": "step", "accepted": accepted, "chi2": cn,
                     "objective": on, "radius": radius, "theta": new.tolist()})
        if accepted:
            if complete:
                y = np.where(ok, rn - r, 0.0)
                J = J + np.outer(y - J @ s, s) / float(s @ s)
            th, r, obj, chi2 = new, rn, on, cn
            best_i = len(hist) - 1
            radius = min(max_radius, 2.0 * radius)
            fresh = False
        elif fresh:
            # the model was measured at th: its step is wrong at this length, try a quarter
            radius = 0.25 * min(radius, float(np.max(np.abs(s))))
        else:
            radius *= 0.5
            if not refresh():
                reason = "evaluation budget"
                break
    if not fresh:
        # the final model is a Broyden update (the budget ran out): its gradient and step
        g = _projected_gradient(J[ok], r[ok], th, prior_sd, lower, upper)
        s_gn = _bounded_step(J[ok], r[ok], th, prior_sd, lower, upper)
    return FitPath(theta=th, objective=obj, chi2=chi2, residual=r, jacobian=J,
                   history=pd.DataFrame(hist), evaluations=evals, best_index=best_i,
                   converged=reason != "evaluation budget", reason=reason, gradient=g,
                   gauss_newton_step=s_gn, jacobian_fresh=fresh)


def posterior_intervals(J, theta, chi2, m, *, lower, upper, prior_sd: float = PRIOR_SD,
                        z: float = 1.96):
    """95 % intervals of theta from ``s2 (J^T J + I / prior_sd^2)^-1`` (module docstring).

    Parameters
    ----------
    J : array_like, shape (m_ok, k)
    theta : array_like, shape (k,)
    chi2 : float
        Data chi2 at theta.
    m : int
        Number of measurements.
    lower, upper : array_like, keyword-only
        Bounds (the intervals are clipped to them).
    prior_sd : float, keyword-only
    z : float, keyword-only
        Normal quantile (1.96: 95 %).

    Returns
    -------
    sd : numpy.ndarray
        Standard deviations of theta (scaled by s2).
    lo, hi : numpy.ndarray
        Interval ends.
    corr : numpy.ndarray
        Correlation matrix.
    s2 : float
    """
    J = np.asarray(J, float)
    J = J[np.all(np.isfinite(J), axis=1)]
    k = J.shape[1]
    s2 = max(1.0, float(chi2) / max(m - k, 1))
    C = s2 * np.linalg.inv(J.T @ J + np.eye(k) / prior_sd ** 2)
    sd = np.sqrt(np.diag(C))
    corr = C / np.outer(sd, sd)
    th = np.asarray(theta, float)
    return (sd, np.clip(th - z * sd, lower, upper), np.clip(th + z * sd, lower, upper), corr,
            s2)


@dataclass(eq=False)
class AsBuiltFit(Result):
    """Result of :func:`fit_as_built`.

    Attributes
    ----------
    measurements : pandas.DataFrame
        The printed numbers with their uncertainties (:func:`thesis_measurements`).
    design : Design
    candidates : tuple of str
    identifiability : Identifiability
        Of the sensitivities at the nominal arm.
    effects : pandas.DataFrame
        One row per candidate: fitted (bool), theta, value, unit, nominal value, 95 %
        interval in value units (``interval_low``, ``interval_high``) and in theta
        (``theta_low``, ``theta_high``, clipped to the axis), ``theta_sd``, the column norm of
        the sensitivity, why not fitted, the reason of the axis.
    correlation : pandas.DataFrame
        Correlation of the fitted thetas.
    path : FitPath
    nominal, as_built : PlantEvaluation
    cells : pandas.DataFrame
        Every measurement beside the nominal and the as-built simulation: key, source,
        experiment, variant, statistic, thesis, nominal, as_built, ratios, whitened residuals.
    gap : pandas.DataFrame
        Per source: numbers, chi2 nominal / as-built, geometric-mean ratio sim / thesis
        nominal / as-built, spread of ln ratio (sd) as-built.
    unreachable_fraction : float
        Part of the as-built chi2 outside the span of all candidate columns (linearised):
        what no candidate of the library can remove.
    pull : pandas.DataFrame
        Per source, the unit direction over the fitted candidates in which that source's
        chi2 falls fastest at the as-built point (``strength``: the gradient's norm); two
        sources with opposite signs on a candidate pull it in opposite directions.
    statements : pandas.DataFrame
        §5.3.5's step and switch statements on the nominal and the as-built plant.
    conclusions : dict
        ``{"nominal": [...], "as-built": [...]}``: conclusions (a)-(g) (None when the
        design is incomplete).
    s2 : float
        Residual variance factor of the intervals.
    step : float
        Secant step of the sensitivities (theta units).
    prior_sd : float
        Prior standard deviation of theta.
    wall_time_s : float
    metrics : dict
    """

    measurements: pd.DataFrame
    design: Design
    candidates: tuple
    identifiability: Identifiability
    effects: pd.DataFrame
    correlation: pd.DataFrame
    path: FitPath
    nominal: PlantEvaluation
    as_built: PlantEvaluation
    cells: pd.DataFrame
    gap: pd.DataFrame
    unreachable_fraction: float
    pull: pd.DataFrame
    statements: pd.DataFrame
    conclusions: dict | None
    s2: float
    step: float = STEP
    prior_sd: float = PRIOR_SD
    wall_time_s: float = 0.0
    metrics: dict = field(default_factory=dict)

    def to_pandas(self) -> pd.DataFrame:
        """The fitted effects (one row per candidate)."""
        return self.effects

    def thetas(self) -> dict:
        """Candidate -> fitted theta (0 for those not fitted)."""
        return dict(zip(self.effects.candidate, self.effects.theta))

    def plot(self):
        """Thesis vs nominal vs as-built per source and the fitted effects; a Figure."""
        return plot_as_built(self.cells, self.effects, sources=SOURCES)


def statement_checks(ev: PlantEvaluation) -> list:
    """§5.3.5's step and switch statements tested on one plant (conclusions (e), (f), (g)).

    Parameters
    ----------
    ev : PlantEvaluation
        A plant evaluated with all ten variants.

    Returns
    -------
    list of Conclusion
    """
    return [pid_violent_psmc_smooth(ev.step), lambda_slows_recovery(ev.step, ev.switch),
            ki12_step_oscillatory(ev.step)]


def _conclusions(ev: PlantEvaluation) -> list:
    return evaluate_conclusions(ev.errors, ev.step, ev.switch) + [ki12_step_oscillatory(ev.step)]


def _cells(meas, nom, built, r_nom, r_built) -> pd.DataFrame:
    out = meas[["key", "source", "experiment", "variant", "statistic", "unit"]].copy()
    out["thesis"] = meas.value.to_numpy()
    out["sigma_log"] = meas.sigma_log.to_numpy()
    out["nominal"] = nom.values.reindex(meas.key).to_numpy(float)
    out["as_built"] = built.values.reindex(meas.key).to_numpy(float)
    out["ratio_nominal"] = out.nominal / out.thesis
    out["ratio_as_built"] = out.as_built / out.thesis
    out["z_nominal"] = r_nom
    out["z_as_built"] = r_built
    return out


def _gap(cells) -> pd.DataFrame:
    rows = []
    for src in SOURCES:
        c = cells[cells.source == src]
        if not len(c):
            continue
        ln_n = np.log(c.ratio_nominal.to_numpy(float))
        ln_b = np.log(c.ratio_as_built.to_numpy(float))
        rows.append({"source": src, "numbers": len(c),
                     "chi2_nominal": float(np.nansum(c.z_nominal ** 2)),
                     "chi2_as_built": float(np.nansum(c.z_as_built ** 2)),
                     "ratio_nominal": float(np.exp(np.nanmean(ln_n))),
                     "ratio_as_built": float(np.exp(np.nanmean(ln_b))),
                     "ln_ratio_sd_as_built": float(np.nanstd(ln_b)),
                     "worst_as_built": c.key.iloc[int(np.nanargmax(np.abs(ln_b)))]})
    return pd.DataFrame(rows)


def _pull(cells, J, r, names) -> pd.DataFrame:
    """Per source, the direction in which its chi2 falls fastest at the as-built point:
    -J_s^T r_s over the fitted candidates, scaled to unit length (a tug of war when two
    sources point in opposite directions)."""
    rows = []
    src = cells.source.to_numpy()
    ok = np.isfinite(r) & np.all(np.isfinite(J), axis=1)
    for s in SOURCES:
        m = (src == s) & ok
        if not m.any():
            continue
        g = -(J[m].T @ r[m])
        n = float(np.linalg.norm(g))
        rows.append({"source": s, "strength": n,
                     **{c: float(g[k] / n) if n > 0 else 0.0 for k, c in enumerate(names)}})
    return pd.DataFrame(rows)


def _unreachable(J, r) -> float:
    ok = np.all(np.isfinite(J), axis=1) & np.isfinite(r)
    A, b = J[ok], r[ok]
    if not b.size or not np.any(b):
        return 0.0
    x, *_ = np.linalg.lstsq(A, b, rcond=None)
    out = b - A @ x
    return float(out @ out / (b @ b))


def fit_as_built(arm=None, *, candidates=CANDIDATES, design: Design | None = None,
                 measurements: pd.DataFrame | None = None, step: float = STEP,
                 max_evaluations: int = MAX_EVALUATIONS, xtol: float = XTOL,
                 gtol: float = GTOL, probe: float = PROBE, prior_sd: float = PRIOR_SD,
                 head=None, rank_tol: float = RANK_TOL) -> AsBuiltFit:
    """Fit the candidates jointly to every printed measurement (module docstring).

    Parameters
    ----------
    arm : ArmParameters, optional
        The nominal arm (default the thesis arm).
    candidates : sequence of str, keyword-only
        Candidate axes (:data:`CANDIDATES`, any plant effect axis, :data:`SENSOR_AXES`).
    design : Design, optional, keyword-only
        What is simulated (default :class:`Design`).
    measurements : pandas.DataFrame, optional, keyword-only
        The numbers to fit (default :func:`thesis_measurements` of ``design``); e.g. a
        synthetic thesis to check the machinery.
    step : float, keyword-only
        Secant step of the sensitivities (theta units), in (0, 1].
    max_evaluations : int, keyword-only
        Points the fit may evaluate after the sensitivities (trial steps and Jacobian
        probes) before it stops unconverged (:func:`levenberg_marquardt`).
    xtol, gtol : float, keyword-only
        Step and gradient tolerances of the fit (:data:`XTOL`, :data:`GTOL`).
    probe : float, keyword-only
        Finite-difference step of the fit's Jacobians (:func:`candidate_probe`).
    prior_sd : float, keyword-only
        Prior standard deviation of theta around the nominal arm.
    head : HeadContactModel or str, optional, keyword-only
        Head of the impacts (default ``thesis-frontal``).
    rank_tol : float, keyword-only
        Threshold of the identifiable subset.

    Returns
    -------
    AsBuiltFit
    """
    t0 = time.perf_counter()
    arm = thesis_arm() if arm is None else arm
    design = Design() if design is None else design
    if not isinstance(design, Design):
        raise TypeError(f"design must be a Design, got {type(design).__name__}")
    if isinstance(candidates, str) or not hasattr(candidates, "__iter__"):
        raise TypeError(f"candidates must be a sequence of names, got {candidates!r}")
    names = tuple(candidates)
    if not names or len(set(names)) != len(names):
        raise ValueError(f"candidates must be distinct names, at least one; got {names!r}")
    for n in names:
        candidate_axis(n)
    step = check_range("step", step, 0.0, 1.0, lo_open=True)
    max_evaluations = check_int("max_evaluations", max_evaluations, 0, 10000)
    meas = check_measurements(thesis_measurements(design) if measurements is None
                              else measurements).reset_index(drop=True)
    m = len(meas)
    refs = DesignReferences.of(arm, design)
    # 1. sensitivities: the nominal arm and every candidate at theta = step, one batch
    pts = [{}] + [{n: step} for n in names]
    evs = evaluate_plants(arm, [as_built_setup(arm, p) for p in pts], design, head=head,
                          thetas=pts, references=refs)
    R = np.array([whitened_residuals(e.values, meas) for e in evs])
    r0 = R[0]
    if not np.any(np.isfinite(r0)):
        raise ValueError("no measurement of the design was simulated on the nominal arm "
                         "(check that the measurement keys match the design)")
    J = (R[1:] - r0).T / step                                   # (m, K)
    ident = identifiability(np.where(np.isfinite(J), J, np.nan), names, rank_tol=rank_tol)
    ident_cos = CONFOUNDED_COS
    Jz = np.where(np.isfinite(J), J, 0.0)
    sel = ident.selected
    if not sel:
        raise ValueError(f"no candidate of {names} is identifiable from these measurements "
                         f"(numerical rank {ident.rank}, column norms "
                         f"{[round(float(v), 3) for v in ident.column_norm]})")
    si = [names.index(n) for n in sel]
    lower = np.array([theta_bounds(n)[0] for n in sel])
    upper = np.array([theta_bounds(n)[1] for n in sel])
    probes = np.array([candidate_probe(n, probe) for n in sel])
    cache = {}

    def evaluate(points):
        ths = [{n: float(v) for n, v in zip(sel, theta)} for theta in points]
        es = evaluate_plants(arm, [as_built_setup(arm, th) for th in ths], design, head=head,
                             thetas=ths, references=refs)
        for theta, e in zip(points, es):
            cache[tuple(np.round(theta, 12))] = e
        return [whitened_residuals(e.values, meas) for e in es]

    # 2.-3. bounded Levenberg-Marquardt on the identifiable subset, to convergence
    path = levenberg_marquardt(evaluate, np.zeros(len(sel)), r0, Jz[:, si], lower=lower,
                               upper=upper, probe=probes, prior_sd=prior_sd, xtol=xtol,
                               gtol=gtol, max_evaluations=max_evaluations)
    built = evs[0] if path.best_index == 0 else cache[tuple(np.round(path.theta, 12))]
    r_b = path.residual
    sd, lo, hi, corr, s2 = posterior_intervals(path.jacobian[np.isfinite(r_b)], path.theta,
                                               path.chi2, m, lower=lower, upper=upper,
                                               prior_sd=prior_sd)
    rows = []
    for k, n in enumerate(names):
        ax = candidate_axis(n)
        fitted = n in sel
        i = sel.index(n) if fitted else None
        th = float(path.theta[i]) if fitted else 0.0
        like = ident.cosines.loc[n, list(sel)] if sel else pd.Series(dtype=float)
        if fitted:
            why = ""
        elif ident.column_norm[k] < 1.0:
            why = "not seen: a full-scale change moves chi2 by less than 1"
        elif len(like) and like.max() >= ident_cos:
            why = (f"confounded with {like.idxmax()} (|cos| {like.max():.2f}): the data "
                   f"cannot tell them apart")
        else:
            why = (f"weakly determined: beyond the numerical rank {ident.rank}, its column "
                   f"keeps {ident.pivot_ratio.get(n, 0.0):.3f} of the largest after the "
                   f"fitted ones (threshold {rank_tol:g})")
        rows.append({"candidate": n, "fitted": fitted, "theta": th, "value": ax.value(th),
                     "unit": ax.unit, "nominal": ax.nominal,
                     "interval_low": ax.value(float(lo[i])) if fitted else np.nan,
                     "interval_high": ax.value(float(hi[i])) if fitted else np.nan,
                     "theta_sd": float(sd[i]) if fitted else np.nan,
                     "theta_low": float(lo[i]) if fitted else np.nan,
                     "theta_high": float(hi[i]) if fitted else np.nan,
                     "column_norm": float(ident.column_norm[k]),
                     "why_not_fitted": why, "axis_reason": ax.reason})
    effects = pd.DataFrame(rows)
    cells = _cells(meas, evs[0], built, r0, r_b)
    gap = _gap(cells)
    unreach = _unreachable(Jz, np.where(np.isfinite(r_b), r_b, np.nan))
    statements, concl = None, None
    if design.complete:
        sn, sb = statement_checks(evs[0]), statement_checks(built)
        statements = pd.DataFrame([{"": f"({a.key})", "statement": a.claim,
                                    "criterion": a.criterion,
                                    "nominal": "holds" if a.holds else "does not hold",
                                    "as-built": "holds" if b.holds else "does not hold",
                                    "evidence as-built": b.evidence}
                                   for a, b in zip(sn, sb)])
        concl = {"nominal": _conclusions(evs[0]), "as-built": _conclusions(built)}
    chi2_nom = float(np.nansum(r0 ** 2))
    metrics = {"measurements": m, "candidates": len(names), "selected": list(sel),
               "sensitivity_rank": ident.rank, "sensitivity_condition": ident.condition,
               "confounded_pairs": len(ident.confounded), "chi2_nominal": chi2_nom,
               "chi2_as_built": float(path.chi2),
               "chi2_per_number_nominal": chi2_nom / m,
               "chi2_per_number_as_built": float(path.chi2) / m,
               "unreachable_fraction": unreach, "evaluations": 1 + len(names) + path.evaluations,
               "fit_converged": bool(path.converged), "fit_convergence": path.reason,
               "fit_budget": int(max_evaluations),
               "fit_steps": int((path.history.kind == "step").sum()),
               "fit_jacobians": int((path.history.kind == "jacobian").sum()),
               "fit_gradient_max": float(np.max(np.abs(path.gradient) * probes)),
               "fit_gauss_newton_step_max": float(np.max(np.abs(path.gauss_newton_step))),
               "fitted": {r.candidate: float(r.value) for r in effects.itertuples() if r.fitted}}
    if concl is not None:
        metrics["conclusions"] = {lab: {c.key: bool(c.holds) for c in cs}
                                  for lab, cs in concl.items()}
    metrics["wall_time_s"] = time.perf_counter() - t0
    return AsBuiltFit(measurements=meas, design=design, candidates=names,
                      identifiability=ident, effects=effects,
                      correlation=pd.DataFrame(corr, index=list(sel), columns=list(sel)),
                      path=path, nominal=evs[0], as_built=built, cells=cells, gap=gap,
                      unreachable_fraction=unreach,
                      pull=_pull(cells, path.jacobian, r_b, sel),
                      statements=statements if statements is not None else pd.DataFrame(),
                      conclusions=concl, s2=s2, step=step, prior_sd=prior_sd,
                      wall_time_s=metrics["wall_time_s"],
                      metrics=metrics)


def simulated_measurements(arm, thetas: dict, design: Design | None = None, *,
                           head=None) -> pd.DataFrame:
    """A synthetic thesis: :func:`thesis_measurements` with the values simulated at ``thetas``.

    For checks of the machinery: :func:`fit_as_built` on this table must recover ``thetas``.

    Parameters
    ----------
    arm : ArmParameters
        The nominal arm.
    thetas : dict
        Candidate -> theta of the hidden truth.
    design : Design, optional
    head : HeadContactModel or str, optional, keyword-only

    Returns
    -------
    pandas.DataFrame
        The measurement table with ``value`` replaced and ``sigma_log`` kept.
    """
    design = Design() if design is None else design
    meas = thesis_measurements(design)
    ev = evaluate_plants(arm, [as_built_setup(arm, thetas)], design, head=head,
                         thetas=[thetas])[0]
    v = ev.values.reindex(meas.key).to_numpy(float)
    if not np.all(np.isfinite(v) & (v > 0)):
        raise ValueError(f"the plant at thetas = {thetas!r} gives no finite positive value "
                         f"for {meas.key[~(np.isfinite(v) & (v > 0))].tolist()[:3]}")
    return meas.assign(value=v)


__all__ = ["REPRODUCIBILITY", "PRINT_STEP", "FIG_3_1_RMS_DEG", "RANK_TOL", "CONFOUNDED_COS",
           "PRIOR_SD", "SENSOR_AXES", "CANDIDATES", "SOURCES", "STEP", "candidate_axis",
           "theta_bounds", "as_built_setup", "Design", "thesis_measurements",
           "sawtooth_reference", "PlantEvaluation", "evaluate_plants", "whitened_residuals",
           "check_measurements", "Identifiability", "identifiability", "FitPath",
           "levenberg_marquardt", "posterior_intervals", "candidate_probe", "DesignReferences",
           "PROBE", "XTOL", "GTOL", "MAX_EVALUATIONS", "CONTROL_PERIOD", "AsBuiltFit",
           "statement_checks", "fit_as_built", "simulated_measurements"]
