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

* tracking statistics 10 %, as :data:`~ppamsafety.diagnose.arm.summary_fit.REPRODUCIBILITY`
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
3. *Levenberg-Marquardt with Broyden updates* on the chosen subset: minimise
   ``chi2 + sum (theta / PRIOR_SD)^2`` (a prior towards the nominal arm: the end of an axis is
   a two-sigma deviation, ``PRIOR_SD`` = 0.5) inside the axis bounds, by bounded linear
   least-squares steps within a trust region; after each step one batched evaluation, the
   secant update of J (Broyden) and the trust region halved on failure, doubled on success.
4. *Intervals.*  95 % intervals from the posterior covariance
   ``s2 (J^T J + I / PRIOR_SD^2)^-1``, scaled by the residual variance s2 = max(1, chi2 /
   (m - k)) as in :mod:`ppamsafety.diagnose.arm.summary_fit`, clipped to the axis.
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

from ..._validation import check_int, check_range
from ...control import GravityCompensation, SensorConfig
from ...control.reference import REFERENCE_ROW
from ...experiments.case import ExperimentCase
from ...experiments.catalog import STEP_TIMES, SWITCH_TIME, thesis_reference, thesis_variants
from ...experiments.closed_loop import run_batch
from ...experiments.conclusions import (evaluate_conclusions, ki12_step_oscillatory,
                                        lambda_slows_recovery, pid_violent_psmc_smooth)
from ...experiments.metrics import response_table
from ...experiments.thesis_data import table_5_2
from ...experiments.trajectories import Reference
from ...impact.instants import evaluate_experiment
from ...impact.thesis_data import table_6_1_long
from ...params import thesis_arm
from ...params.effects import Effects, MagnitudeAxis
from ...params.sensors import TABLE_3_2_VARIANCES
from ...plant import geometry as geo
from ...plots.diagnose import plot_as_built
from .summary_fit import axis as effect_axis
from .synthesize import plant_with, sawtooth_set_angles

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


def _plant(arm, values: dict, *, dt: float = 1e-3):
    """The plant truth with plant-effect axes at physical magnitudes ``{axis: value}``."""
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


def evaluate_plants(arm, setups: list, design: Design, *, head=None,
                    thetas: list | None = None) -> list:
    """Simulate every measurement of ``design`` for several (plant, sensors) at once.

    One batched closed-loop run per experiment (circle per period, step, switch, sawtooth)
    over all setups and variants; impacts per run.

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

    Returns
    -------
    list of PlantEvaluation
    """
    if not isinstance(design, Design):
        raise TypeError(f"design must be a Design, got {type(design).__name__}")
    if not setups:
        raise ValueError("setups must not be empty")
    thetas = [{}] * len(setups) if thetas is None else thetas
    vs = design.variant_list()
    nv = len(vs)
    vals = [dict() for _ in setups]
    err_rows = [[] for _ in setups]
    bad = [False] * len(setups)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)          # divergence: NaN statistics
        for P, win in zip(design.periods, design.windows):
            name = f"circle{P:g}"
            ref = thesis_reference(arm, name, duration=design.warmup + win)
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
        for name, dur in (("step", design.step_duration), ("switch", design.switch_duration)):
            ref = thesis_reference(arm, name, duration=dur)
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
        ref, win = sawtooth_reference(arm, design.sawtooth_levels)
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
class Identifiability:
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
    """The Levenberg-Marquardt/Broyden iterations of :func:`lm_broyden`.

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
        The (Broyden-updated) sensitivity matrix at the end.
    history : pandas.DataFrame
        One row per evaluated step: iteration, accepted, chi2, objective, radius, thetas.
    evaluations : int
        Points evaluated after the sensitivities.
    best_index : int
        Index (into the evaluated points, 0 = start) of the best point.
    """

    theta: np.ndarray
    objective: float
    chi2: float
    residual: np.ndarray
    jacobian: np.ndarray
    history: pd.DataFrame
    evaluations: int
    best_index: int


def _objective(r, theta, prior_sd):
    rr = np.where(np.isfinite(r), r, 0.0)
    return float(np.sum(rr ** 2) + np.sum((theta / prior_sd) ** 2)), float(np.sum(rr ** 2))


def lm_broyden(evaluate, theta0, r0, J0, *, lower, upper, prior_sd: float = PRIOR_SD,
               iterations: int = 4, radius: float = 0.5, max_radius: float = 0.5) -> FitPath:
    """Bounded Levenberg-Marquardt steps on a secant model with Broyden updates.

    Minimises ``||r(theta)||^2 + ||theta / prior_sd||^2`` for ``lower <= theta <= upper``.
    Each step solves the linearised problem within the trust region ``|dtheta|_inf <=
    radius`` by bounded least squares, evaluates the point (one call of ``evaluate``),
    updates J by Broyden's rank-one secant formula, and halves the radius on failure,
    doubles it (up to ``max_radius``) on success.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(theta) -> r``: whitened residuals (NaN for a failed point).
    theta0 : array_like, shape (k,)
        Start (the nominal arm: zeros).
    r0 : array_like, shape (m,)
        Residuals at ``theta0``.
    J0 : array_like, shape (m, k)
        Secant sensitivities at ``theta0``.
    lower, upper : array_like, shape (k,), keyword-only
        Bounds of theta.
    prior_sd : float, keyword-only
        Prior standard deviation of theta around 0.
    iterations : int, keyword-only
        Evaluated steps.
    radius : float, keyword-only
        Initial trust radius (theta units).
    max_radius : float, keyword-only
        Largest trust radius (the secant model is trusted over at most this step).

    Returns
    -------
    FitPath
    """

    th = np.asarray(theta0, float).copy()
    r = np.asarray(r0, float).copy()
    J = np.asarray(J0, float).copy()
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    k = th.size
    if J.shape != (r.size, k):
        raise ValueError(f"J0 must have shape ({r.size}, {k}), got {J.shape}")
    prior_sd = check_range("prior_sd", prior_sd, 0.0, 1e6, lo_open=True)
    iterations = check_int("iterations", iterations, 0, 100)
    ok = np.isfinite(r)
    obj, chi2 = _objective(r, th, prior_sd)
    hist = [{"iteration": 0, "accepted": True, "chi2": chi2, "objective": obj,
             "radius": radius, "theta": th.tolist()}]
    best_i = 0
    for it in range(1, iterations + 1):
        A = np.vstack([J[ok], np.eye(k) / prior_sd])
        b = np.concatenate([J[ok] @ th - r[ok], np.zeros(k)])
        lo = np.maximum(lower, th - radius)
        hi = np.minimum(upper, th + radius)
        hi = np.where(hi <= lo, lo + 1e-12, hi)
        new = lsq_linear(A, b, bounds=(lo, hi)).x
        s = new - th
        if np.max(np.abs(s)) < 1e-4:
            break
        rn = np.asarray(evaluate(new), float)
        okn = np.isfinite(rn) & ok
        on, cn = _objective(np.where(okn, rn, np.nan), new, prior_sd)
        if okn.sum() == ok.sum():
            y = np.where(ok, rn - r, 0.0)
            J = J + np.outer(y - J @ s, s) / float(s @ s)
        accepted = bool(okn.sum() == ok.sum() and on < obj)
        hist.append({"iteration": it, "accepted": accepted, "chi2": cn, "objective": on,
                     "radius": radius, "theta": new.tolist()})
        if accepted:
            th, r, obj, chi2 = new, rn, on, cn
            best_i = it
            radius = min(max_radius, 2 * radius)
        else:
            radius *= 0.5
    return FitPath(theta=th, objective=obj, chi2=chi2, residual=r, jacobian=J,
                   history=pd.DataFrame(hist), evaluations=len(hist) - 1, best_index=best_i)


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
class AsBuiltFit:
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
                 iterations: int = 4, prior_sd: float = PRIOR_SD, head=None,
                 rank_tol: float = RANK_TOL) -> AsBuiltFit:
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
    iterations : int, keyword-only
        Levenberg-Marquardt steps (each one batched evaluation).
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
    meas = check_measurements(thesis_measurements(design) if measurements is None
                              else measurements).reset_index(drop=True)
    m = len(meas)
    # 1. sensitivities: the nominal arm and every candidate at theta = step, one batch
    pts = [{}] + [{n: step} for n in names]
    evs = evaluate_plants(arm, [as_built_setup(arm, p) for p in pts], design, head=head,
                          thetas=pts)
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
    cache = {}

    def evaluate(theta):
        th = {n: float(v) for n, v in zip(sel, theta)}
        e = evaluate_plants(arm, [as_built_setup(arm, th)], design, head=head,
                            thetas=[th])[0]
        cache[tuple(np.round(theta, 12))] = e
        return whitened_residuals(e.values, meas)

    # 2.-3. Levenberg-Marquardt with Broyden updates on the identifiable subset
    path = lm_broyden(evaluate, np.zeros(len(sel)), r0, Jz[:, si], lower=lower, upper=upper,
                      prior_sd=prior_sd, iterations=iterations)
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
           "lm_broyden", "posterior_intervals", "AsBuiltFit", "statement_checks",
           "fit_as_built", "simulated_measurements"]
