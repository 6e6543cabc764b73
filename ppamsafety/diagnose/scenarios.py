"""The randomized scenario battery: does the diagnosis keep its promises on data it never saw?

A printed confidence is a promise.  This module measures it.  A seeded sampler
(:func:`random_scenario`) draws a scenario: a record kind (open loop, closed
loop under any thesis reference and controller family, the static sawtooth, a
muscle on a test bench), its sampling and length, 0-3 effects of the library
with magnitudes log-uniform over their plausible ranges, and sometimes a
perturbation the library does not hold (a geometry or link-inertia error, an
encoder or velocity-sensor gain, encoder backlash, a valve nonlinearity,
coloured noise, outliers).  :func:`run_scenario` synthesizes the record,
diagnoses it blind (default options) and scores every claim against the truth;
:data:`ARM_BATTERY` is its battery for the one runner of every record kind
(:func:`~.core.battery.run_battery`, in parallel processes); :func:`scores` and
:func:`calibration_table` summarise them.

A second battery (``random_scenario(seed, declared=True)``) draws arms that declare
effects of their own in their ``[effects]`` (:data:`DECLARED_DRAWS`: a payload,
friction, valve offsets/gains, valve time constants, a polytropic exponent, muscle
hysteresis, a valve dead time, a joint torque bias; 1-4 kinds), and with probability
:data:`P_DECLARED_CHANGE` hides a change of one of them; the record is made with that arm
and diagnosed against it, so a declared effect is the nominal model and only a change of
it is a right name.  Its seeds (:data:`DECLARED_TUNING_SEEDS`,
:data:`DECLARED_MEASURE_SEEDS`) are its own.

Scoring (what the targets of ``docs/diagnose.md`` count)
--------------------------------------------------------
* A named effect (any confidence) is *right* when the scenario hid it.  A
  confounded group is not a claim and is scored apart (*right* when it holds a
  hidden member).
* Each hidden effect is compared with the record's own **detection limit**
  (:mod:`ppamsafety.diagnose.arm.detection`): its *ratio* is the largest
  change of one of its parameters over that parameter's limit.  Effects below
  their limit are "too small to see on this record" -- the diagnosis says so
  -- and the recall targets count the scenarios whose hidden effects are all
  above their limit; the rest are reported separately.
* Interval coverage: for every right name, each parameter's reported 95 %
  interval against its true value (the nominal value for a parameter the
  scenario did not change), and the fit's own interval before it was widened
  (:mod:`.core.omitted`) for comparison.
* Out of library: the *irreducible gap* (:func:`irreducible_gap`) is the part
  of the perturbation's signature in the block residuals that no combination of
  the library can reproduce, as the residual-to-noise ratio it alone leaves
  (sqrt(1 + gamma^2)); "above noise" means >= :data:`GAP_ABOVE_NOISE`.
"""

from __future__ import annotations

import argparse
import json
import lzma
import math
import os
import time
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from .._validation import check_int
from ..data.measured import MeasuredDataWarning
from ..output import atomic_write, check_new_file
from ..experiments.catalog import thesis_variants
from ..params import thesis_arm
from ..plant import packing
from .arm.candidates import REGISTRY, default_candidates
from .bench import scenarios as bench_scenarios
from .core.battery import (HIGH_PRECISION, P_COUNT, P_PERTURBATION, Battery, coverage_entry,
                           logu, run_battery, sgn, wilson_low)
from .core.solve import lstsq
from .arm.residuals import arm_record, block_system, model_vector
from .arm.selection import _directions, make_problem
from .arm.static import static_record, static_system
from .diagnosis import diagnose
from .synthesize import synthesize

#: Seeds of the battery of arms that declare effects of their own
#: (``random_scenario(seed, declared=True)``): tuning (the replay's threshold and any rule
#: set for declared effects) and measurement, never overlapping each other or the above.
DECLARED_TUNING_SEEDS = range(10000, 11000)
DECLARED_MEASURE_SEEDS = range(20000, 22000)
#: Scenarios of the shipped measurement of that battery (its first seeds).
DECLARED_MEASURE_COUNT = 1600
#: Residual/noise ratio that the irreducible part of an out-of-library perturbation must
#: leave on some channel to count as "above noise" (the diagnosis flags a channel above its
#: ``rho_max`` = 1.5).
GAP_ABOVE_NOISE = 1.75
#: Record kinds and their probabilities.
KINDS = {"open-loop": 0.35, "closed-loop": 0.40, "static-sawtooth": 0.25}

_ARM = thesis_arm()


# ----------------------------------------------------------------------------- library draws
# A candidate's draw (a hidden effect) and its ``declare`` (an arm that declares it) are the
# candidate's (:mod:`.arm.candidates`): the tables below are read from the library.

#: Library candidate -> its draw (``Candidate.draw``: magnitudes log-uniform from below a
#: typical detection limit to the top of the plausible range).
LIBRARY_DRAWS = REGISTRY.draws()

# ----------------------------------------------------------------------------- declared effects
#: The order in which the declared-effect battery's shipped seeds draw the declarable
#: candidates; a candidate with a ``declare`` that is not listed comes after them, in the
#: library's order (so a new one keeps every shipped scenario).
DECLARED_ORDER = ("payload", "joint_friction", "valve_offset_gain", "valve_lag",
                  "polytropic_exponent", "hysteresis", "valve_dead_time", "joint_torque_bias")
#: Declarable candidate -> its ``declare`` draw (an arm's declared effects, over the ranges an
#: arm file accepts where an arm can still make its records), and the library candidate a
#: hidden change of it is named as (None: outside the default library).
DECLARED_DRAWS = {n: (REGISTRY[n].declare, n if REGISTRY[n].default else None)
                  for n in DECLARED_ORDER + tuple(n for n in REGISTRY if n not in DECLARED_ORDER)
                  if n in REGISTRY and REGISTRY[n].declare is not None}
#: ``Effects`` field an arm declares -> the library candidate that names a change of it
#: (``Candidate.declares``).
DECLARED_CANDIDATE = {f: n for n, c in REGISTRY.items() for f in c.declares}
#: Probabilities of 1, 2, 3, 4 declared effect kinds in an arm of that battery.
P_DECLARED_COUNT = (0.35, 0.35, 0.2, 0.1)
#: Probability that a scenario of that battery hides a change of one of its declared effects.
P_DECLARED_CHANGE = 0.4


def declared_arm(sc, arm=None):
    """The arm of a scenario: ``arm`` (default the thesis arm) with the scenario's declared
    effects (:attr:`Scenario.declared`).

    Parameters
    ----------
    sc : Scenario
    arm : ArmParameters, optional
    """
    arm = _arm_of(arm)
    if not sc.declared:
        return arm
    fx = {k: tuple(v) if isinstance(v, list) else v for k, v in sc.declared.items()}
    return arm.replace(effects=replace(arm.effects, **fx),
                       name=f"{arm.name or 'arm'} with declared {', '.join(sorted(fx))}")


# ----------------------------------------------------------------------------- perturbations

_GEOMETRY_FIELDS = ("X11", "Y11", "X21", "Y21", "L12", "d12", "L22", "L32", "L42", "L33", "L43",
                    "L1")
_LINK_FIELDS = ("m1", "m2", "LG1", "LG2", "IG1", "IG2")


def _perturbation(rng, arm) -> dict:
    kind = str(rng.choice(["geometry", "link", "encoder_gain", "velocity_sensor_gain",
                           "encoder_backlash", "valve_nonlinearity", "noise_correlation_time",
                           "outlier_rate", "joint_torque_bias"]))
    if kind == "joint_torque_bias":                 # opt-in, so outside the default library
        return REGISTRY["joint_torque_bias"].draw(rng, arm)[0]
    if kind == "geometry":
        f = str(rng.choice(_GEOMETRY_FIELDS))
        v = getattr(arm.geometry, f)
        scale = abs(v) if v != 0 else 0.01
        return {f"geometry.{f}": v + sgn(rng) * logu(rng, 0.005, 0.05) * scale}
    if kind == "link":
        f = str(rng.choice(_LINK_FIELDS))
        v = getattr(arm.links, f)
        return {f"link.{f}": v * (1.0 + sgn(rng) * logu(rng, 0.03, 0.3))}
    if kind == "encoder_gain":
        return {kind: tuple(sgn(rng) * logu(rng, 0.002, 0.05) for _ in range(2))}
    if kind == "velocity_sensor_gain":
        return {kind: tuple(sgn(rng) * logu(rng, 0.01, 0.2) for _ in range(2))}
    if kind == "encoder_backlash":
        return {kind: tuple(logu(rng, 5e-4, 0.01) for _ in range(2))}
    if kind == "valve_nonlinearity":
        return {kind: sgn(rng) * logu(rng, 0.03, 0.4)}
    if kind == "noise_correlation_time":
        return {kind: logu(rng, 0.003, 0.05)}
    return {"outlier_rate": logu(rng, 3e-4, 5e-3)}


# ----------------------------------------------------------------------------- scenarios

@dataclass(frozen=True)
class Scenario:
    """One draw of the battery (module docstring).

    Attributes
    ----------
    seed : int
    kind : str
        ``"open-loop"``, ``"closed-loop"`` or ``"static-sawtooth"``.
    duration : float or None
        Record length [s] (None: the whole sawtooth).
    dt : float
        Sample time [s].
    reference, controller : str or None
        Closed loop: the thesis experiment and controller variant.
    hidden : dict
        Library candidate -> the ``synthesize`` effects that hide it.
    truth : dict
        Library candidate -> {parameter: true value}.
    perturbation : dict
        Out-of-library ``synthesize`` effects (empty for none).
    declared : dict
        Effects the scenario's arm declares (``Effects`` field -> value; empty: the arm as
        given), :func:`declared_arm`.
    """

    seed: int
    kind: str
    duration: float | None
    dt: float
    reference: str | None = None
    controller: str | None = None
    hidden: dict = field(default_factory=dict)
    truth: dict = field(default_factory=dict)
    perturbation: dict = field(default_factory=dict)
    declared: dict = field(default_factory=dict)

    @property
    def effects(self) -> dict:
        """Every ``synthesize`` effect of the scenario."""
        out = {}
        for fx in self.hidden.values():
            out.update(fx)
        out.update(self.perturbation)
        return out


def random_scenario(seed: int, *, arm=None, declared: bool = False) -> Scenario:
    """A random scenario (module docstring), fully determined by ``seed`` (and the arm).

    Parameters
    ----------
    seed : int
    arm : ArmParameters, optional, keyword-only
        The nominal arm (default the thesis arm): hidden magnitudes are drawn around its
        values.
    declared : bool, keyword-only
        Draw an arm that declares effects of its own (:data:`DECLARED_DRAWS`: 1-4 kinds,
        :data:`P_DECLARED_COUNT`) on top of ``arm``, and with probability
        :data:`P_DECLARED_CHANGE` hide a change of one of them; the diagnosis is run
        against that arm.
    """
    seed = check_int("seed", seed, 0)
    arm = _arm_of(arm)
    decl = {}
    if declared:
        rd = np.random.default_rng([seed, 28])
        count = 1 + int(rd.choice(len(P_DECLARED_COUNT), p=P_DECLARED_COUNT))
        kinds = [str(k) for k in rd.choice(list(DECLARED_DRAWS), size=count, replace=False)]
        for k in kinds:
            decl.update(DECLARED_DRAWS[k][0](rd, arm))
        arm = arm.replace(effects=replace(arm.effects, **decl))
    rng = np.random.default_rng([seed, 19])
    kind = str(rng.choice(list(KINDS), p=list(KINDS.values())))
    reference = controller = None
    if kind == "open-loop":
        dt = float(rng.choice([5e-4, 1e-3, 2e-3]))
        duration = float(rng.uniform(8.0, 40.0))
    elif kind == "closed-loop":
        dt = 1e-3
        reference = str(rng.choice(["step", "switch", "circle5", "circle10", "circle20"]))
        controller = str(rng.choice([v.label for v in thesis_variants()]))
        duration = float(rng.uniform(10.0, 30.0))
    else:
        dt = float(rng.choice([1e-3, 2e-3]))
        duration = None if rng.random() < 0.5 else float(rng.uniform(45.0, 105.0))
    pool = [n for n in default_candidates(static=kind == "static-sawtooth") if n in LIBRARY_DRAWS]
    count = int(rng.choice(len(P_COUNT), p=P_COUNT))
    names = [str(x) for x in rng.choice(pool, size=count, replace=False)]
    if declared and rd.random() < P_DECLARED_CHANGE:
        # a hidden change of a declared effect on top (one the record can show)
        own = [DECLARED_DRAWS[k][1] for k in kinds if DECLARED_DRAWS[k][1] in pool]
        if own:
            n = str(rd.choice(own))
            if n not in names:
                names = [n] + names[1:] if names else [n]
    hidden, truth = {}, {}
    for n in names:
        fx, tr = LIBRARY_DRAWS[n](rng, arm, dt)
        hidden[n], truth[n] = fx, tr
    pert = _perturbation(rng, arm) if rng.random() < P_PERTURBATION else {}
    return Scenario(seed=seed, kind=kind, duration=duration, dt=dt, reference=reference,
                    controller=controller, hidden=hidden, truth=truth, perturbation=pert,
                    declared=decl)


def record_of(sc: Scenario, *, with_perturbation: bool = True, arm=None):
    """The synthetic record of a scenario (``synthesize`` with its effects and options).

    Parameters
    ----------
    sc : Scenario
    with_perturbation : bool, keyword-only
        False: the same record without the out-of-library perturbation (the twin of
        :func:`irreducible_gap`).
    arm : ArmParameters, optional, keyword-only
        The nominal arm (default the thesis arm).
    """
    fx = {}
    for h in sc.hidden.values():
        fx.update(h)
    if with_perturbation:
        fx.update(sc.perturbation)
    kw = dict(experiment=sc.kind, effects=fx, seed=sc.seed, duration=sc.duration, dt=sc.dt,
              arm=declared_arm(sc, arm))
    if sc.kind == "closed-loop":
        kw.update(reference=sc.reference, controller=sc.controller)
    return synthesize(**kw)


def _arm_of(arm):
    return _ARM if arm is None else arm


def irreducible_gap(sc: Scenario, record, noise_levels, *, arm=None) -> float:
    """Residual-to-noise ratio that the library cannot remove from the perturbation's signature.

    The perturbation's signature is the difference of the block residuals (at the
    nominal model) of the record and of its twin without the perturbation (same
    seed).  Its part orthogonal to every library column (all candidates at once,
    at the nominal model, whitened by the diagnosis' block noise levels) is what no
    diagnosis can explain; the function returns ``max_c sqrt(1 + gamma_c^2)``,
    gamma_c the RMS of that part on channel c in noise units.

    Parameters
    ----------
    sc : Scenario
    record : MeasuredData
        The scenario's record.
    noise_levels : array_like, shape (6,)
        Block noise levels of the diagnosis (``settings["block_noise"]``).
    arm : ArmParameters, optional, keyword-only
        The nominal arm (default the thesis arm).
    """
    twin = record_of(sc, with_perturbation=False, arm=arm)
    arm = declared_arm(sc, arm)
    mu0 = model_vector(packing.pack(arm))

    def system(data):
        if sc.kind == "static-sawtooth":
            rec, _ = static_record(data)
            return static_system(rec, arm)
        rec, _ = arm_record(data)
        return block_system(rec, arm)

    b1, b0 = system(record), system(twin)
    nb = min(b1.nb, b0.nb)
    d = (b1.y[:nb] - b1.X[:nb] @ mu0) - (b0.y[:nb] - b0.X[:nb] @ mu0)
    sig = np.asarray(noise_levels, dtype=float)
    dz = d / sig
    cands = default_candidates(static=sc.kind == "static-sawtooth")
    lin = [c for c in cands if not REGISTRY[c].grid]
    prob = make_problem(b1, mu0, (np.zeros((1, b1.nb, 6)), np.zeros((1, b1.nb, 6, mu0.size))),
                        arm)
    D, _, _, E = _directions(prob, lin)
    P = (b1.X @ D)
    if E is not None:
        P = P + E
    Z = (P / sig[None, :, None])[:nb].reshape(nb * 6, -1)
    keep = np.sqrt(np.sum(Z ** 2, axis=0)) > 0
    Z = Z[:, keep] / np.sqrt(np.sum(Z[:, keep] ** 2, axis=0))
    r = (dz.ravel() - Z @ lstsq(Z, dz.ravel())).reshape(nb, 6)
    gamma = np.sqrt(np.mean(r ** 2, axis=0))
    if sc.kind == "static-sawtooth" and "valve_offset_gain" not in cands:
        gamma[:4] = 0.0
    return float(np.max(np.sqrt(1.0 + gamma ** 2)))


def _ratio(name, truth, limits, key="limit_named"):
    """Largest |true - nominal| / limit over the parameters of a hidden effect."""
    lim = limits.get(name, {})
    best = 0.0
    for p, v in truth.items():
        d = lim.get(p)
        if d is None or not np.isfinite(d[key]) or d[key] <= 0:
            continue
        nominal = d["nominal"] if np.isfinite(d.get("nominal", np.nan)) else 0.0
        best = max(best, abs(v - nominal) / d[key])
    return best


def run_scenario(sc: Scenario, *, gap: bool = True, arm=None) -> dict:
    """Synthesize, diagnose blind and score one scenario (one row of the battery).

    Parameters
    ----------
    sc : Scenario
    gap : bool, keyword-only
        Compute the irreducible gap of an out-of-library perturbation.
    arm : ArmParameters, optional, keyword-only
        The nominal arm (default the thesis arm).

    Returns
    -------
    dict
        The scenario, what was claimed, and the scores (keys in :func:`scores`).
    """
    row = {"seed": sc.seed, "kind": sc.kind, "reference": sc.reference,
           "controller": sc.controller, "dt": sc.dt, "duration": sc.duration,
           "hidden": tuple(sorted(sc.hidden)), "perturbation": ";".join(
               f"{k}={v}" for k, v in sc.perturbation.items()), "error": "",
           "stage": ""}
    if sc.declared:
        row["declared"] = ";".join(f"{k}={v}" for k, v in sc.declared.items())
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeasuredDataWarning)
        try:
            # a drawn plant that cannot make the record (no rest state within the pressure
            # range, a closed loop that diverges) is not a scenario: reported, not scored
            rec = record_of(sc, arm=arm)
        except (ValueError, FloatingPointError, np.linalg.LinAlgError) as exc:
            row.update(error=f"{type(exc).__name__}: {exc}", stage="record",
                       seconds=time.perf_counter() - t0)
            return row
        try:
            dg = diagnose(rec, seed=sc.seed, arm=declared_arm(sc, arm))
        except Exception as exc:      # a diagnosis that fails on a valid record is scored
            row.update(error=f"{type(exc).__name__}: {exc}", stage="diagnose",
                       seconds=time.perf_counter() - t0)
            return row
    hidden = set(sc.hidden)
    row.update({
        "named": dg.names,
        "high": tuple(e.name for e in dg.effects if e.high),
        "low": tuple(e.name for e in dg.effects if not e.high),
        "partial": tuple(e.name for e in dg.partial),
        "confounded": tuple(tuple(g.members) for g in dg.confounded),
        "unexplained": bool(dg.unexplained),
        "rho_before": max(v["before"] for k, v in dg.residual_rms.items()
                          if k.startswith("block_")),
        "rho_after": max(v["after"] for k, v in dg.residual_rms.items()
                         if k.startswith("block_")),
        "ratios": {h: _ratio(h, sc.truth[h], dg.detection_limits) for h in sc.hidden},
        "ratios_detected": {h: _ratio(h, sc.truth[h], dg.detection_limits, "limit")
                            for h in sc.hidden},
        "gates": {e.name: e.gates or {} for e in dg.effects},
        "named_ratios": {e.name: e.evidence.get("limit_ratio") for e in dg.effects},
        "stability_bound": (dg.stability or {}).get("expected_false_selections_bound"),
        "replay_rho": dict(dg.settings.get("replay", {}).get("rho", {})),
    })
    cover = []
    for e in dg.effects:
        if e.name not in hidden:
            continue
        for p, d in e.parameters.items():
            true = sc.truth[e.name].get(p)
            if true is None:
                continue
            cover.append(coverage_entry(e.name, p, true, d, e.confidence_level))
    row["coverage"] = cover
    row["gap"] = (irreducible_gap(sc, rec, list(dg.settings["block_noise"].values()), arm=arm)
                  if gap and sc.perturbation else None)
    row["seconds"] = time.perf_counter() - t0
    return row


def _arm_row(seed, arm=None, declared=False):
    """The row of ``random_scenario(seed)`` (the arm's :class:`~.core.battery.Battery`)."""
    return run_scenario(random_scenario(seed, arm=arm, declared=bool(declared)), arm=arm)


#: Seeds the gates were set on (never used to measure them): 0-299 set the thresholds; a
#: first measurement on 1000-1999 showed two kinds of wrong names (an encoder offset whose
#: interval held zero, and one that a constant joint torque explains as well), which set the
#: "moved" rule of naming and the look-alikes outside the library, so those seeds are
#: tuning seeds now.  A second measurement on 2000-2999 met every target but interval
#: coverage; the hint level of the widened intervals (:mod:`.core.omitted`) was chosen on
#: 2000-2299, so those seeds are tuning seeds too.
#: Its measurement seeds (the report and ``docs/diagnose.md``) are 3000-4999.  Options of
#: :func:`~.core.battery.run_battery`: ``arm`` (the nominal arm, default the thesis arm) and
#: ``declared`` (arms that declare effects of their own, :func:`random_scenario`).
ARM_BATTERY = Battery(kind="arm", tuning=range(0, 3000), measure=range(3000, 5000),
                      run=_arm_row, error_row={"stage": "battery"}, processes=None)


# ----------------------------------------------------------------------------- stored results

#: The battery's measured results shipped with the package (JSON lines, xz): written by
#: ``python -m ppamsafety.diagnose.scenarios`` (see its README).
RESULTS_FILE = Path(__file__).resolve().parent / "calibration_data" / "arm_battery.jsonl.xz"
#: The muscle bench battery's measured results (:mod:`.bench.scenarios`, same row keys):
#: ``python -m ppamsafety.diagnose.scenarios --kind bench``.
BENCH_RESULTS_FILE = RESULTS_FILE.with_name("bench_battery.jsonl.xz")
#: The battery of arms with declared effects (``--kind declared``).
DECLARED_RESULTS_FILE = RESULTS_FILE.with_name("arm_declared_battery.jsonl.xz")
#: Tuning rows the replay's thresholds were set on (:func:`replay_limits`): thesis-arm seeds
#: 0-299 and declared-effect seeds 10000-10299, run with the replay gate off.
REPLAY_TUNING_FILE = RESULTS_FILE.with_name("replay_tuning.jsonl.xz")
#: The replay threshold is this multiple of the largest replay ratio of a right model on the
#: tuning rows (:func:`replay_limits`).
REPLAY_MARGIN = 1.25
#: Columns that hold Python containers (tuples, dicts, lists) in a results table.
_CONTAINERS = ("hidden", "named", "high", "low", "partial", "confounded", "ratios",
               "ratios_detected", "gates", "named_ratios", "coverage", "replay_rho")


def _jsonable(v):
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, (np.bool_, bool)):
        return bool(v)
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (np.floating, float)):
        return float(v) if math.isfinite(float(v)) else None
    return v


def save_results(results: pd.DataFrame, path, *, overwrite: bool = False) -> Path:
    """Write a battery's rows as xz-compressed JSON lines (one scenario per line).

    Parameters
    ----------
    results : pandas.DataFrame
        :func:`~.core.battery.run_battery` of :data:`ARM_BATTERY`.
    path : path-like
        The file (``.jsonl.xz``); its folder must exist.
    overwrite : bool, keyword-only
        Replace an existing file.

    Returns
    -------
    pathlib.Path
    """
    rows = [_jsonable(r) for r in results.to_dict(orient="records")]

    def write(tmp):
        with lzma.open(tmp, "wt", encoding="utf-8") as fh:
            for r in rows:
                fh.write(json.dumps(r, allow_nan=False) + "\n")

    return atomic_write(path, write, overwrite=overwrite, name="battery results file")


def load_results(path=None) -> pd.DataFrame:
    """Read a battery's rows written by :func:`save_results` (default :data:`RESULTS_FILE`).

    Parameters
    ----------
    path : path-like, optional

    Returns
    -------
    pandas.DataFrame
        As :func:`~.core.battery.run_battery` (containers as tuples / dicts).
    """
    path = RESULTS_FILE if path is None else Path(path)
    if not path.is_file():
        raise ValueError(f"battery results file '{path}' does not exist")
    with lzma.open(path, "rt", encoding="utf-8") as fh:
        rows = [json.loads(line) for line in fh if line.strip()]
    df = pd.DataFrame(rows)
    for c in ("hidden", "named", "high", "low", "partial"):
        if c in df:
            df[c] = df[c].map(lambda v: tuple(v) if isinstance(v, list) else ())
    if "confounded" in df:
        df["confounded"] = df["confounded"].map(
            lambda v: tuple(tuple(g) for g in v) if isinstance(v, list) else ())
    for c in ("ratios", "ratios_detected", "gates", "named_ratios", "replay_rho"):
        if c in df:
            df[c] = df[c].map(lambda v: v if isinstance(v, dict) else {})
    if "coverage" in df:
        df["coverage"] = df["coverage"].map(lambda v: v if isinstance(v, list) else [])
    if "error" in df:
        df["error"] = df["error"].fillna("")
    for c in ("perturbation", "declared"):
        if c in df:
            df[c] = df[c].fillna("")
    return df


# ----------------------------------------------------------------------------- scores

def _ok(df):
    return df[df["error"].fillna("") == ""] if "error" in df else df


def _stage(df) -> pd.Series:
    """Where a row failed: "" (it did not), "record" (the drawn plant cannot make the
    record), "diagnose" or "battery" (the code under test failed).  Rows written before the
    stage was recorded read their error: the generator's errors name the record."""
    if "error" not in df:
        return pd.Series("", index=df.index)
    err = df["error"].fillna("")
    stage = df["stage"].fillna("") if "stage" in df else pd.Series("", index=df.index)
    old = (err != "") & (stage == "")
    guess = err.str.contains("rest_state|diverged|run_batch", regex=True)
    return stage.where(~old, guess.map({True: "record", False: "diagnose"}))


def failures(results: pd.DataFrame) -> dict:
    """Counts of the rows that are not scored: ``{"record": k, "diagnose": k, "battery": k}``.

    "record": the drawn plant could not make the record (e.g. the rest pose needs a
    pressure outside the valves' range); these are not scenarios.  "diagnose" and
    "battery": the diagnosis or the runner raised on a valid record -- a failure of the
    code under test, which :func:`scores` counts against it.

    Parameters
    ----------
    results : pandas.DataFrame
        :func:`~.core.battery.run_battery` of :data:`ARM_BATTERY` (or of the bench's).
    """
    st = _stage(results)
    return {k: int((st == k).sum()) for k in ("record", "diagnose", "battery")}


def _detectable(row) -> bool:
    return all(v >= 1.0 for v in row["ratios"].values())


def scores(results: pd.DataFrame) -> pd.DataFrame:
    """The battery's measures against their targets (``HIGH_PRECISION`` and the coverage band).

    Parameters
    ----------
    results : pandas.DataFrame
        :func:`~.core.battery.run_battery` of :data:`ARM_BATTERY`.

    Returns
    -------
    pandas.DataFrame
        One row per measure: ``measure``, ``count`` (scenarios or names it is
        measured on), ``hits``, ``value``, ``wilson_low``/``high`` bound, ``target``,
        ``met`` (None where there is no target, or no scenario or name to score it on).
    """
    df = _ok(results)
    rows = []
    fail = failures(results)

    def add(name, hits, n, target, better="higher", upper=None):
        v = hits / n if n else math.nan
        if better == "info":
            met, kind = None, ""
        elif upper is not None:
            met, kind = bool(target <= v <= upper), f"in [{target:g}, {upper:g}]"
        elif better == "higher":
            met, kind = bool(v >= target), ">="
        else:
            met, kind = bool(v <= target), "<="
        if not n:                   # nothing to score (e.g. a short battery): not "not met"
            met = None
        rows.append({"measure": name, "count": int(n), "hits": int(hits), "value": v,
                     "wilson_low": wilson_low(hits, n),
                     "target": math.nan if better == "info" else target,
                     "target_kind": kind, "met": met})

    clean = df[df["perturbation"] == ""]
    single = clean[clean["hidden"].map(len) == 1]
    s_det = single[single.apply(_detectable, axis=1)]
    add("single library effect above its detection limit: named right (and nothing else)",
        int(sum(set(r.named) == set(r.hidden) for r in s_det.itertuples())), len(s_det), 0.95)
    none = clean[clean["hidden"].map(len) == 0]
    add("nothing hidden: something named", int(sum(len(r.named) > 0 for r in none.itertuples())),
        len(none), 0.02, better="lower")
    pair = clean[clean["hidden"].map(len) == 2]
    p_det = pair[pair.apply(_detectable, axis=1)]
    add("two effects above their limits: both named, nothing else",
        int(sum(set(r.named) == set(r.hidden) for r in p_det.itertuples())), len(p_det), 0.85)
    right = clean[np.array([set(r.named) == set(r.hidden) for r in clean.itertuples()],
                           dtype=bool)]
    add("model right (exactly the hidden effects named, nothing out of library): flagged "
        "unexplained", int(sum(bool(r.unexplained) for r in right.itertuples())), len(right),
        0.02, better="lower")
    ool = df[df["perturbation"] != ""]
    ool0 = ool[ool["hidden"].map(len) == 0]
    add("out of library (nothing else hidden): no high-confidence name",
        int(sum(len(r.high) == 0 for r in ool0.itertuples())), len(ool0), 0.95)
    above = ool0[ool0["gap"].fillna(0.0) >= GAP_ABOVE_NOISE]
    add("out of library, irreducible gap above noise: flagged unexplained",
        int(sum(bool(r.unexplained) for r in above.itertuples())), len(above), 0.90)
    high_names = [(n, set(r.hidden)) for r in df.itertuples() for n in r.high]
    add("'high' names right (precision)", sum(n in h for n, h in high_names), len(high_names),
        HIGH_PRECISION)
    cov = [c for r in df.itertuples() for c in (r.coverage or [])]
    add("95 % intervals of right names covering the truth (as reported: widened for the "
        "effects the record hints at)", sum(c["covered"] for c in cov), len(cov), 0.90,
        upper=0.98)
    add("... the fit's own intervals (before widening; for comparison)",
        sum(c["covered_noise"] for c in cov), len(cov), 0.90, "info")
    cov = [c for r in df.itertuples() if set(r.named) == set(r.hidden) and not r.perturbation
           for c in (r.coverage or [])]
    add("... reported, where exactly the hidden effects were named (the model is right)",
        sum(c["covered"] for c in cov), len(cov), 0.90, upper=0.98)
    cov = [c for r in df.itertuples() for c in (r.coverage or []) if c["level"] == "high"]
    add("... reported, of 'high' names", sum(c["covered"] for c in cov), len(cov), 0.90,
        upper=0.98)
    made = len(df) + fail["diagnose"] + fail["battery"]
    add("valid records on which the diagnosis raised an error", fail["diagnose"] +
        fail["battery"], made, 0.0, better="lower")
    return pd.DataFrame(rows)


def declared_names(results: pd.DataFrame) -> dict:
    """What became of the effects the scenarios' arms declare (the battery of arms with
    declared effects).

    Parameters
    ----------
    results : pandas.DataFrame
        Rows of ``random_scenario(seed, declared=True)`` (``declared`` column).

    Returns
    -------
    dict
        ``changes``: hidden changes of a declared effect (no out-of-library perturbation),
        ``changes_above``: of those above their detection limit, ``changes_named``: of those
        named; ``high``: "high" names of an effect the arm declares, ``high_right``: of
        those a change the scenario hid; ``unchanged_named``: names (any level) of a
        declared effect the scenario did not change.
    """
    out = dict.fromkeys(("changes", "changes_above", "changes_named", "high", "high_right",
                         "unchanged_named"), 0)
    df = _ok(results)
    if "declared" not in df:
        return out
    for r in df.itertuples():
        decl = {DECLARED_CANDIDATE[k.split("=")[0]] for k in (r.declared or "").split(";")
                if k.split("=")[0] in DECLARED_CANDIDATE}
        out["high"] += sum(n in decl for n in r.high)
        out["high_right"] += sum(n in decl and n in r.hidden for n in r.high)
        out["unchanged_named"] += sum(n in decl and n not in r.hidden for n in r.named)
        if not r.perturbation:
            for h in r.hidden:
                if h in decl:
                    out["changes"] += 1
                    above = r.ratios.get(h, 0.0) >= 1.0
                    out["changes_above"] += above
                    out["changes_named"] += above and h in r.named
    return out


def replay_null(results: pd.DataFrame) -> pd.DataFrame:
    """The replay statistic of the models the diagnosis got right: its null distribution.

    A model is right when the scenario holds no out-of-library perturbation and exactly
    the hidden effects were named; its statistic is the largest replay RMS over the sample
    noise over the record's channels (``replay_rho``), what a correct model replayed on a
    noisy record leaves.

    Parameters
    ----------
    results : pandas.DataFrame
        Battery rows with ``replay_rho``.

    Returns
    -------
    pandas.DataFrame
        One row per record class (``dynamic``: open and closed loop; ``static``: the
        sawtooth): ``models`` (right models), ``median``, ``p95``, ``p99``, ``max``.
    """
    df = _ok(results)
    right = np.array([set(n) == set(h) for n, h in zip(df["named"], df["hidden"])], bool)
    df = df[(df["perturbation"] == "").to_numpy() & right]
    stat = df["replay_rho"].map(lambda d: max(d.values()) if isinstance(d, dict) and d
                                else math.nan)
    rows = []
    for cls, sel in (("dynamic", df["kind"] != "static-sawtooth"),
                     ("static", df["kind"] == "static-sawtooth")):
        x = stat[sel].dropna().to_numpy(float)
        q = np.quantile(x, [0.5, 0.95, 0.99]) if x.size else [math.nan] * 3
        rows.append({"records": cls, "models": int(x.size), "median": float(q[0]),
                     "p95": float(q[1]), "p99": float(q[2]),
                     "max": float(x.max()) if x.size else math.nan})
    return pd.DataFrame(rows)


def replay_limits(results: pd.DataFrame, *, margin: float = REPLAY_MARGIN) -> tuple:
    """The replay thresholds the rule gives on tuning rows: ``margin`` x the largest
    statistic of a right model (:func:`replay_null`), rounded down to 0.1.

    Parameters
    ----------
    results : pandas.DataFrame
        Tuning rows (:data:`REPLAY_TUNING_FILE`).
    margin : float, keyword-only

    Returns
    -------
    tuple of float
        (open and closed loop, static sawtooth): the values of
        :data:`ppamsafety.diagnose.arm.pipeline.REPLAY_RHO` and ``REPLAY_RHO_STATIC``.
    """
    null = replay_null(results).set_index("records")
    return tuple(math.floor(10 * margin * null.loc[c, "max"] + 1e-9) / 10
                 for c in ("dynamic", "static"))


def interval_widening(results: pd.DataFrame) -> dict:
    """How much the reported intervals of right names widened the fit's own.

    Parameters
    ----------
    results : pandas.DataFrame
        :func:`~.core.battery.run_battery` of :data:`ARM_BATTERY`.

    Returns
    -------
    dict
        ``parameters`` (count), ``widened`` (how many), ``median`` and ``p90`` of the
        width ratio reported / fit's own.
    """
    ratios = []
    for r in _ok(results).itertuples():
        for c in (r.coverage or []):
            own = c["ci_high_noise"] - c["ci_low_noise"]
            if own > 0:
                ratios.append((c["ci_high"] - c["ci_low"]) / own)
    ratios = np.asarray(ratios, dtype=float)
    if not ratios.size:
        return {"parameters": 0, "widened": 0, "median": math.nan, "p90": math.nan}
    return {"parameters": int(ratios.size), "widened": int(np.sum(ratios > 1.0 + 1e-9)),
            "median": float(np.median(ratios)), "p90": float(np.percentile(ratios, 90))}


def calibration_table(results: pd.DataFrame) -> pd.DataFrame:
    """Claimed level -> names, right, precision and its 95 % Wilson lower bound.

    Parameters
    ----------
    results : pandas.DataFrame
        :func:`~.core.battery.run_battery` of :data:`ARM_BATTERY`.
    """
    df = _ok(results)
    rows = []
    for level, col in (("high", "high"), ("low", "low")):
        names = [(n, set(r.hidden)) for r in df.itertuples() for n in getattr(r, col)]
        k = sum(n in h for n, h in names)
        rows.append({"claimed": level, "names": len(names), "right": k,
                     "precision": k / len(names) if names else math.nan,
                     "wilson_low": wilson_low(k, len(names)),
                     "required": HIGH_PRECISION if level == "high" else math.nan})
    groups = [(g, set(r.hidden)) for r in df.itertuples() for g in (r.confounded or ())]
    k = sum(bool(set(g) & h) for g, h in groups)
    rows.append({"claimed": "confounded (group holds a hidden member)", "names": len(groups),
                 "right": k, "precision": k / len(groups) if groups else math.nan,
                 "wilson_low": wilson_low(k, len(groups)), "required": math.nan})
    return pd.DataFrame(rows)


def by_effect(results: pd.DataFrame) -> pd.DataFrame:
    """Per library effect: hidden, above the limit, named (any / high), and 'high' precision.

    Parameters
    ----------
    results : pandas.DataFrame
    """
    df = _ok(results)
    rows = []
    seen = {n for r in df.itertuples() for n in (*r.hidden, *r.named)}
    # the arm's library in its order, then any other (the bench's) in alphabetical order
    names = [n for n in REGISTRY if n in seen] + sorted(seen - set(REGISTRY))
    for name in names:
        hid = [r for r in df.itertuples() if name in r.hidden]
        det = [r for r in hid if r.ratios.get(name, 0.0) >= 1.0]
        highs = [r for r in df.itertuples() if name in r.high]
        rows.append({"effect": name, "hidden": len(hid), "above_limit": len(det),
                     "named_when_above": sum(name in r.named for r in det),
                     "high_when_above": sum(name in r.high for r in det),
                     "confounded_when_hidden": sum(any(name in g for g in r.confounded)
                                                   for r in hid),
                     "named_when_below": sum(name in r.named for r in hid
                                             if r.ratios.get(name, 0.0) < 1.0),
                     "high_names": len(highs),
                     "high_right": sum(name in r.hidden for r in highs)})
    return pd.DataFrame(rows)


#: Edges of the bins of magnitude / detection limit of :func:`detection_curve`.
RATIO_BINS = (0.0, 0.25, 0.5, 1.0, 2.0, 4.0, 16.0, math.inf)


def detection_curve(results: pd.DataFrame, *, key: str = "ratios") -> pd.DataFrame:
    """How often a hidden effect is named, against its magnitude over its detection limit.

    Over every hidden library effect of the scenarios without an out-of-library
    perturbation; the limit is the record's own (``ratios``: the naming limit
    ``limit_named``; ``ratios_detected``: the detection limit ``limit``).  At a ratio
    of 1 the limit promises a named rate of 90 %.

    Parameters
    ----------
    results : pandas.DataFrame
        :func:`~.core.battery.run_battery` of :data:`ARM_BATTERY`.
    key : {"ratios", "ratios_detected"}, keyword-only

    Returns
    -------
    pandas.DataFrame
        ``ratio_from``, ``ratio_to``, ``effects``, ``named``, ``named_rate``, ``high``,
        ``high_rate``, ``confounded`` (held in a confounded group).
    """
    df = _ok(results)
    df = df[df["perturbation"] == ""]
    pts = [(v, n in r.named, n in r.high, any(n in g for g in (r.confounded or ())))
           for r in df.itertuples() for n, v in getattr(r, key).items()]
    rows = []
    for lo, hi in zip(RATIO_BINS[:-1], RATIO_BINS[1:]):
        sel = [p for p in pts if lo <= p[0] < hi]
        n = len(sel)
        rows.append({"ratio_from": lo, "ratio_to": hi, "effects": n,
                     "named": sum(p[1] for p in sel),
                     "named_rate": sum(p[1] for p in sel) / n if n else math.nan,
                     "high": sum(p[2] for p in sel),
                     "high_rate": sum(p[2] for p in sel) / n if n else math.nan,
                     "confounded": sum(p[3] for p in sel)})
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    """Run the battery on a range of seeds, write its rows, print its scores.

    ``python -m ppamsafety.diagnose.scenarios [--kind arm|declared|bench] [--seeds
    2000:3000] [--processes N] [--out FILE] [--overwrite]``; the default writes
    :data:`RESULTS_FILE` (``--kind declared``: arms with declared effects on
    :data:`DECLARED_MEASURE_SEEDS` into :data:`DECLARED_RESULTS_FILE`; ``--kind bench``: the
    muscle bench battery of :mod:`.bench.scenarios` on its measurement seeds into
    :data:`BENCH_RESULTS_FILE`), refused if it exists unless ``--overwrite``.  About 35 min
    for the 1000 arm scenarios on 2 cores, 5 min for the 300 bench scenarios.

    Parameters
    ----------
    argv : list of str, optional
    """
    ap = argparse.ArgumentParser(prog="python -m ppamsafety.diagnose.scenarios",
                                 description="the randomized scenario battery of the diagnosis")
    ap.add_argument("--kind", choices=("arm", "declared", "bench"), default="arm",
                    help="arm records (default), arm records of arms that declare effects, "
                         "or muscle test-bench records")
    ap.add_argument("--seeds", default=None,
                    help="first:last+1 (default the measurement seeds: arm "
                         f"{ARM_BATTERY.measure.start}:{ARM_BATTERY.measure.start + 1000}, "
                         "declared "
                         f"{DECLARED_MEASURE_SEEDS.start}:"
                         f"{DECLARED_MEASURE_SEEDS.start + DECLARED_MEASURE_COUNT}, bench "
                         f"{bench_scenarios.MUSCLE_BATTERY.measure.start}:"
                         f"{bench_scenarios.MUSCLE_BATTERY.measure.stop})")
    ap.add_argument("--processes", type=int, default=None,
                    help="worker processes (default: every core)")
    ap.add_argument("--out", default=None, help="results file (.jsonl.xz; default the "
                                                "shipped file of the kind)")
    ap.add_argument("--overwrite", action="store_true", help="replace an existing file")
    args = ap.parse_args(argv)
    bench = args.kind == "bench"
    if args.seeds is None:
        seeds = {"bench": bench_scenarios.MUSCLE_BATTERY.measure,
                 "arm": ARM_BATTERY.measure[:1000],
                 "declared": DECLARED_MEASURE_SEEDS[:DECLARED_MEASURE_COUNT]}[args.kind]
        args.seeds = f"{seeds.start}:{seeds.stop}"
    if args.out is None:
        args.out = str({"bench": BENCH_RESULTS_FILE, "arm": RESULTS_FILE,
                        "declared": DECLARED_RESULTS_FILE}[args.kind])
    try:
        a, b = (int(x) for x in args.seeds.split(":"))
    except ValueError:
        ap.error(f"--seeds {args.seeds!r}: give first:last+1, e.g. 2000:3000")
    check_new_file(args.out, overwrite=args.overwrite, name="--out")
    t0 = time.time()
    if bench:
        df = run_battery(bench_scenarios.MUSCLE_BATTERY, range(a, b),
                         processes=args.processes or (os.cpu_count() or 1), progress=True)
    else:
        df = run_battery(ARM_BATTERY, range(a, b), processes=args.processes, progress=True,
                         declared=args.kind == "declared")
    wall = time.time() - t0
    save_results(df, args.out, overwrite=args.overwrite)
    pd.set_option("display.width", 200)
    pd.set_option("display.max_columns", 20)
    fail = failures(df)
    print(f"{len(df)} scenarios in {wall:.0f} s; records the drawn plant could not make: "
          f"{fail['record']}; diagnosis failures: {fail['diagnose'] + fail['battery']}")
    for table in (scores(df), calibration_table(df), by_effect(df), detection_curve(df)):
        print(table.to_string())
    print(f"written: {args.out}")
    return 0


__all__ = ["Scenario", "random_scenario", "record_of", "run_scenario", "run_battery",
           "detection_curve", "RATIO_BINS",
           "save_results", "load_results", "RESULTS_FILE", "BENCH_RESULTS_FILE",
           "DECLARED_RESULTS_FILE", "DECLARED_TUNING_SEEDS", "DECLARED_MEASURE_SEEDS",
           "DECLARED_MEASURE_COUNT", "DECLARED_DRAWS", "declared_arm",
           "irreducible_gap", "scores", "failures", "calibration_table", "by_effect",
           "interval_widening", "LIBRARY_DRAWS", "replay_null", "replay_limits",
           "declared_names", "DECLARED_CANDIDATE",
           "REPLAY_TUNING_FILE", "REPLAY_MARGIN",
           "ARM_BATTERY", "HIGH_PRECISION", "GAP_ABOVE_NOISE"]


if __name__ == "__main__":
    raise SystemExit(main())
