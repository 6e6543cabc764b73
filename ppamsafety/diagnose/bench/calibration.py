"""Calibration of the campaign diagnosis' confidence on synthetic campaigns.

The principle: a printed confidence is a promise, so ``"high"`` must
mean that at least 97 % of the effects named "high" are really there.  This
module measures it for bench campaigns of a cylinder: :func:`random_scenario`
draws a campaign from a seed (a Coulomb friction always -- a real seal has
one -- and each other library effect with a probability, magnitudes
log-uniform over plausible ranges; sensor faults; out-of-library structure:
stroke-to-stroke scatter, correlated force ripple, a time-based transient after
the reversals, random per-record offsets; 1 to 7 pressure levels, 4 to 10
cycles, sometimes several speeds), :func:`run_campaign_calibration` diagnoses each
campaign blind and scores every named effect (:data:`CAMPAIGN_BATTERY` on the one battery
runner of every record kind, :func:`~..core.battery.run_battery`), :func:`campaign_calibration_table`
gives the precision per claimed level.  The thresholds of the confidence rule
(:data:`~.campaign.STABILITY_HIGH`, :data:`~.campaign.P_HIGH`,
:data:`~.campaign.GAIN_HIGH`) were set on seeds 0-99 (:data:`CAMPAIGN_TUNING`);
the report measures them on other seeds.

Scoring: a named effect is *right* when the scenario hid it (any magnitude);
``coulomb_pressure`` and ``coulomb_pressure2`` both claim "the Coulomb level
grows with the pressure" and are right when either was hidden;
``stroke_profile`` claims "the force depends on the rod position" and is right
when either profile was hidden (``stroke_profile_pressure`` only when its own
claim, a profile growing with the pressure, was hidden).
A confounded group is scored apart: *right* when it holds a hidden member.
"""

from __future__ import annotations

import math
import time
import warnings

import numpy as np
import pandas as pd

from ..._validation import check_seed
from ...data.measured import MeasuredDataWarning
from ..core.battery import HIGH_PRECISION, Battery, logu, run_battery, sgn, wilson_low
from .campaign import diagnose_campaign
from .cylinder_synth import LIBRARY_NAME, synthesize_cylinder

#: Seeds the confidence thresholds were chosen on (never used to measure them).
CAMPAIGN_TUNING = range(0, 100)
#: Seeds of the measurement in the report (first 1000 of them at most).
CAMPAIGN_MEASURE = range(1000, 2000)
#: The pressure law of the Coulomb level: naming either term is right when the friction
#: grows with the pressure (c1 p or c2 p^2 hidden), the claim each makes.
PRESSURE_FAMILY = ("coulomb_pressure", "coulomb_pressure2")


def random_scenario(seed: int) -> dict:
    """A random campaign: hidden effects, nuisances and protocol options (module docstring).

    Parameters
    ----------
    seed : int
        Seed of the draw (and of the campaign's noise).

    Returns
    -------
    dict
        ``effects``, ``nuisance``, ``options`` (of
        :func:`~.cylinder_synth.synthesize_cylinder`), ``seed``.
    """
    seed = check_seed("seed", seed)
    rng = np.random.default_rng([seed, 20])
    fx = {"coulomb": logu(rng, 1.0, 10.0)}
    draws = [("coulomb_pressure", 0.6, lambda: logu(rng, 2e-6, 1.5e-5)),
             ("coulomb_pressure2", 0.2, lambda: logu(rng, 5e-12, 4e-11)),
             ("presliding", 0.5, lambda: logu(rng, 5e-5, 1.5e-3)),
             ("stribeck", 0.25, lambda: logu(rng, 0.5, 5.0)),
             ("stroke_profile", 0.3, lambda: logu(rng, 0.1, 1.5)),
             ("stroke_profile_pressure", 0.2, lambda: logu(rng, 0.2, 4.0)),
             ("friction_drift", 0.3, lambda: sgn(rng) * logu(rng, 0.002, 0.02)),
             ("force_sensor_offset", 0.3, lambda: sgn(rng) * logu(rng, 0.3, 3.0)),
             ("pressure_sensor_offset", 0.15, lambda: sgn(rng) * logu(rng, 500.0, 5000.0)),
             ("force_sensor_gain", 0.15, lambda: sgn(rng) * logu(rng, 0.005, 0.05)),
             ("pressure_sensor_gain", 0.1, lambda: sgn(rng) * logu(rng, 0.005, 0.05)),
             ("area_error", 0.15, lambda: sgn(rng) * logu(rng, 0.005, 0.08))]
    for name, prob, draw in draws:
        if rng.uniform() < prob:
            fx[name] = draw()
    protocol = "varied-speed" if rng.uniform() < 0.3 else "fixed-speed"
    if protocol == "varied-speed" and rng.uniform() < 0.6:
        fx["viscous"] = logu(rng, 20.0, 300.0)
    nz = {"stroke_scatter": logu(rng, 0.05, 0.4), "ripple": logu(rng, 0.03, 0.3)}
    if rng.uniform() < 0.3:
        nz["slow_transient"] = logu(rng, 0.3, 2.0)
    if rng.uniform() < 0.2:
        nz["record_offset"] = logu(rng, 0.2, 2.0)
    levels = [(1e5, 3e5, 5e5, 7e5), (1e5, 2e5, 3e5, 4e5, 5e5, 6e5, 7e5), (2e5, 4e5, 6e5),
              (1e5, 4e5), (3e5,)][int(rng.choice(5, p=[0.35, 0.15, 0.25, 0.15, 0.10]))]
    opts = {"pressures": levels, "cycles": int(rng.integers(4, 11)), "protocol": protocol}
    return {"seed": seed, "effects": fx, "nuisance": nz, "options": opts}


def score(scenario: dict, dg) -> list:
    """One row per named effect and confounded group of a diagnosis (module docstring).

    Parameters
    ----------
    scenario : dict
        From :func:`random_scenario`.
    dg : BenchDiagnosis
        Its diagnosis.

    Returns
    -------
    list of dict
        ``seed``, ``kind`` ("named"/"confounded"), ``name``, ``level``, ``right``.
    """
    truth = {LIBRARY_NAME[k] for k in scenario["effects"] if k in LIBRARY_NAME}
    if truth & set(PRESSURE_FAMILY):
        truth |= set(PRESSURE_FAMILY)
    if "stroke_profile_pressure" in truth:
        truth.add("stroke_profile")
    rows = []
    for e in dg.effects:
        ev = e.evidence
        rows.append({"seed": scenario["seed"], "kind": "named", "name": e.name,
                     "level": e.confidence_level, "right": e.name in truth,
                     "cv_gain": ev["cv_gain"], "p_value": ev["p_value"],
                     "stability": ev["stability_frequency"], "setting": ev["setting"],
                     "at_edge": bool(ev.get("at_grid_edge", False))})
    for g in dg.confounded:
        rows.append({"seed": scenario["seed"], "kind": "confounded",
                     "name": "|".join(g.members), "level": "confounded",
                     "right": bool(truth & set(g.members))})
    return rows


#: Columns of the second table of :func:`run_campaign_calibration` (one row per scenario), also when no
#: scenario ran: a table without columns is a CSV file no reader can parse.
RUN_COLUMNS = ("seed", "hidden", "named", "high", "missed", "wrong_high", "records", "rho_after",
               "seconds")


def _campaign_row(seed, diagnose_options=None) -> dict:
    """Synthesize, diagnose blind and score the campaign of ``seed`` (the row of
    :data:`CAMPAIGN_BATTERY`): the scenario's :data:`RUN_COLUMNS` and its :func:`score`
    rows under ``names``."""
    sc = random_scenario(seed)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeasuredDataWarning)
        camp = synthesize_cylinder(sc["effects"], seed=sc["seed"], nuisance=sc["nuisance"],
                                   **sc["options"])
        dg = diagnose_campaign(camp, **(diagnose_options or {}))
    r = score(sc, dg)
    truth = sorted({LIBRARY_NAME[k] for k in sc["effects"] if k in LIBRARY_NAME})
    named = set(dg.names) | {m for g in dg.confounded for m in g.members}
    return {"seed": seed, "hidden": "+".join(truth),
            "named": "+".join(dg.names),
            "high": "+".join(e.name for e in dg.effects if e.high),
            "missed": "+".join(t for t in truth if t not in named),
            "wrong_high": "+".join(x["name"] for x in r if x["level"] == "high"
                                   and not x["right"]),
            "records": len(camp), "rho_after": dg.residual_rms["block_force"]["after"],
            "seconds": time.perf_counter() - t0, "names": r}


#: The cylinder campaign's battery for the one runner of every record kind
#: (:func:`~..core.battery.run_battery`); its option: ``diagnose_options``.
CAMPAIGN_BATTERY = Battery(kind="cylinder", tuning=CAMPAIGN_TUNING, measure=CAMPAIGN_MEASURE,
                           run=_campaign_row, processes=1)
#: Columns of the first table of :func:`run_campaign_calibration` (one row per claim).
NAME_COLUMNS = ("seed", "kind", "name", "level", "right", "cv_gain", "p_value", "stability",
                "setting", "at_edge")


def run_campaign_calibration(seeds, *, diagnose_options=None, processes: int = 1) -> tuple:
    """Synthesize and diagnose one random campaign per seed; score every name.

    Runs :data:`CAMPAIGN_BATTERY` through :func:`~..core.battery.run_battery`.

    Parameters
    ----------
    seeds : iterable of int
        Scenario seeds.
    diagnose_options : dict, optional, keyword-only
        Keyword options of :func:`~.campaign.diagnose_campaign`.
    processes : int, keyword-only
        Worker processes (1: in this process).

    Returns
    -------
    names : pandas.DataFrame
        :func:`score` rows.
    runs : pandas.DataFrame
        One row per scenario, sorted by seed: ``seed``, ``hidden`` (library names),
        ``named``, ``high``, ``missed``, ``rho_after``, ``seconds``.

    Raises
    ------
    RuntimeError
        When a campaign could not be synthesized or diagnosed (naming its seed).
    """
    seeds = list(seeds)
    if not seeds:
        return pd.DataFrame(columns=list(NAME_COLUMNS)), pd.DataFrame(columns=list(RUN_COLUMNS))
    res = run_battery(CAMPAIGN_BATTERY, seeds, processes=processes,
                      diagnose_options=diagnose_options)
    if "error" in res.columns:
        bad = res[res["error"].notna()]
        if len(bad):
            r = bad.iloc[0]
            raise RuntimeError(f"seed {int(r['seed'])}: the campaign failed: {r['error']}\n"
                               f"{r.get('traceback', '')}")
    names = [x for rows in res["names"] for x in rows]
    return pd.DataFrame(names, columns=list(NAME_COLUMNS)), \
        res[list(RUN_COLUMNS)].reset_index(drop=True)


def campaign_calibration_table(names: pd.DataFrame) -> pd.DataFrame:
    """Claimed level -> count, right, observed precision (and its 95 % Wilson lower bound).

    Parameters
    ----------
    names : pandas.DataFrame
        From :func:`run_campaign_calibration`.

    Returns
    -------
    pandas.DataFrame
        Index level (``high``, ``low``, ``confounded``).
    """
    if not isinstance(names, pd.DataFrame) or not {"level", "right"} <= set(names.columns):
        raise TypeError("names must be the first DataFrame of run_campaign_calibration()")
    out = []
    for lev in ("high", "low", "confounded"):
        g = names[names["level"] == lev]
        n, k = len(g), int(g["right"].sum())
        p = k / n if n else math.nan
        lo = wilson_low(k, n, z=1.959964)
        out.append({"level": lev, "count": n, "right": k, "precision": p,
                    "precision_wilson_low": lo,
                    "required": HIGH_PRECISION if lev == "high" else math.nan})
    return pd.DataFrame(out).set_index("level")


__all__ = ["random_scenario", "score", "run_campaign_calibration", "CAMPAIGN_BATTERY", "NAME_COLUMNS",
           "campaign_calibration_table", "RUN_COLUMNS",
           "CAMPAIGN_TUNING", "CAMPAIGN_MEASURE", "PRESSURE_FAMILY"]
