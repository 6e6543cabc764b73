"""The discrepancy workflow on a test bench: one muscle's force against its nominal law.

Thesis §3.5.1.6 localised the muscle hysteresis by comparing the measured
muscle force with the force the law (3.9) predicts from the measured
pressure and contraction.  :func:`diagnose_actuator` does that for an
actuator record (``kind = "actuator"``, ``docs/measured_data.md``):

1. **the design** (:mod:`.design`): the residual ``r = F - p f(eps)``, the
   direction of motion, the noise level (strided for correlated noise, made
   local) and the whitened columns of every applicable candidate
   (:mod:`.candidates`: friction, hysteresis, a refitted law and the sensor
   faults);
2. **the naming rule** (:mod:`.selection`): forward selection with refit
   under the arm's rules plus rule 5 (effect size), then a backward pass;
3. **look-alikes** (:mod:`.confounded`): a member of the final model that an
   outside candidate explains as well is reported with it as *confounded*,
   with the experiment that separates them -- never named;
4. **stability** (:mod:`.stability`): the naming rule rerun on halves of the
   record's loops;
5. **named / partial / unexplained**: named when the final residual RMS is
   <= ``rho_max`` x the noise, otherwise partial (fitted, reported, not
   named) and the record is unexplained; **confidence** "high" only through
   every gate of :mod:`.gates`;
6. **detection limits** (:mod:`.detection`) of every candidate, and **where**
   the final residual is significant: per direction of motion, pressure
   level, contraction level and time segment.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pandas as pd

from ..._validation import check_int, check_range
from ..core.linear_selection import hac_covariance_linear
from ..core.omitted import HINT_P, widened_interval
from ..core.regions import region_rows, terciles, time_segments
from ..core.result import Diagnosis
from .candidates import ACTUATOR_VOCABULARY
from .confounded import confounded_groups
from .consistency import time_consistency
from .design import (AMBIGUOUS_SIGMAS, LOCAL_WINDOW, NOISE_PLATEAU, PRESSURE_LEVELS_RATIO,
                     REVERSAL_SIGMAS,
                     ActuatorRecord, actuator_design, actuator_record, contraction_rate,
                     motion_direction, residual_noise)
from .detection import detection_limits, limit_ratio, omitted
from ..core.gates import level
from .gates import MIN_REVERSALS_HIGH, MUSCLE_RULE, PRESSURE_EFFECTS, gates
from .selection import MIN_EFFECT_RMS, relinearised, select
from .stability import (PAIRS, THRESHOLD, half_sample_covariance, inflated_covariance,
                        stability_selection)


def _sample_regions(e, feats, rho_max):
    """Operating regions of significant residual (same columns as the arm's table)."""
    d = feats["direction"]
    groups = {
        "direction of motion": {"contracting (d eps/dt > 0)": d > 0,
                                "extending (d eps/dt < 0)": d < 0, "before any motion": d == 0},
        "pressure level": terciles(feats["pressure"], "p", scale=1e-5, unit="bar",
                                   merge_equal=True),
        "contraction level": terciles(feats["eps"], "eps", scale=100.0, unit="%",
                                      merge_equal=True),
        "time segment": time_segments(feats["t"], digits=4),
    }
    return pd.DataFrame(region_rows(e, groups, "force", rho_max))


def _widened(params: dict, ext, sl: slice, k: int, left_out: dict) -> dict:
    """``params`` (:meth:`Extension.values`) with every interval widened by
    :func:`~ppamsafety.diagnose.core.omitted.widened_interval` (the fit's own kept as
    ``ci_low_noise``/``ci_high_noise``)."""
    for i, d in enumerate(params.values()):
        g = np.zeros(k)
        g[sl] = ext.T[i]
        lo, hi, by = widened_interval(d["value"], d["std_error"], g, left_out)
        d.update(ci_low_noise=d["ci_low"], ci_high_noise=d["ci_high"], ci_low=float(lo),
                 ci_high=float(hi), widened_by=list(by))
    return params


def diagnose_actuator(data, *, candidates=None, alpha: float = 0.01, rho_max: float = 1.5,
                      experiment: str | None = None, seed: int = 0,
                      stability: int | None = None, detection: bool = True):
    """Diagnose a muscle's test-bench record against its nominal force law.

    See the module docstring; the result has the arm's schema
    (``docs/diagnose.md``, tester keys documented there).

    Parameters
    ----------
    data : MeasuredData
        ``kind = "actuator"`` record (:func:`ppamsafety.data.load_measured`).
    candidates : sequence of str, optional, keyword-only
        Subset of :data:`~.candidates.ACTUATOR_VOCABULARY` (default all).
    alpha : float, keyword-only
        Level of the likelihood-ratio test (Bonferroni-divided per step), in (0, 0.5].
    rho_max : float, keyword-only
        Largest residual/noise RMS ratio of an explained record, in [1, 100].
    experiment : str, optional, keyword-only
        Hint that must agree with the metadata when given.
    seed : int, keyword-only
        Seed of the random splits of the stability check.
    stability : int, optional, keyword-only
        Complementary pairs of the stability check (:mod:`.stability`; default
        :data:`~.stability.PAIRS`; 0: none -- then no effect reaches "high").
    detection : bool, keyword-only
        Compute the detection limits of the record (:mod:`.detection`).

    Returns
    -------
    Diagnosis
    """
    t0 = time.perf_counter()
    check_range("alpha", alpha, 0.0, 0.5, lo_open=True)
    check_range("rho_max", rho_max, 1.0, 100.0)
    seed = check_int("seed", seed, 0)
    pairs = PAIRS if stability is None else check_int("stability", stability, 0, 10000)
    if candidates is not None:
        if isinstance(candidates, str) or not all(isinstance(c, str) for c in candidates):
            raise TypeError(f"candidates must be a sequence of names, got {candidates!r}")
        bad = [c for c in candidates if c not in ACTUATOR_VOCABULARY]
        if bad:
            raise ValueError(f"candidates = {list(candidates)}: {bad} not in the tester "
                             f"vocabulary {list(ACTUATOR_VOCABULARY)}")
    des = actuator_design(data, candidates)
    if experiment is not None and experiment != data.experiment:
        raise ValueError(f"experiment = {experiment!r} does not match the record's metadata "
                         f"experiment = {data.experiment!r}")
    rec, exts = des.rec, des.extensions
    notes = list(des.notes)
    turns = des.turns
    if turns < MIN_REVERSALS_HIGH:
        notes.append(f"only {turns} reversal(s) of the motion (< {MIN_REVERSALS_HIGH}): "
                     f"hysteresis and friction, which show at reversals, are hard to tell from "
                     f"a slow drift on this record and are reported with low confidence at most")
    t1 = time.perf_counter()
    sel = select(des, alpha=alpha)
    # the hysteresis multiplies the muscle's force: rebuilt on the law as fitted
    des, fit = relinearised(des, sel.fit)
    steps, nominal = sel.steps, sel.nominal
    if set(sel.forward) != set(fit.names):
        notes.append(f"the search over every subset found a better model than the forward "
                     f"path: {' + '.join(fit.names)} instead of "
                     f"{' + '.join(sel.forward) or 'nominal'}")
    for pr in sel.pruned:
        notes.append(f"{pr['name']}: chosen on the way, dropped by the backward pass (LR "
                     f"p = {pr['p_value']:.2g} given the later effects): they explain its part")
    groups = confounded_groups(des, fit, alpha=alpha)
    grouped = {m for g in groups for m in g["members"]}
    t2 = time.perf_counter()
    stab = stability_selection(des, alpha=alpha, pairs=pairs, seed=seed) if pairs else None
    tb = time.perf_counter()
    rho = fit.rho()
    unexplained = bool(rho > rho_max)
    rowof = {s.chosen: next(x for x in s.table if x["name"] == s.chosen)
             for s in steps if s.chosen is not None}
    # intervals from the HAC covariance: a residual correlated over neighbouring samples (a
    # model slightly off, coloured noise) widens them
    cov = hac_covariance_linear(np.concatenate([des.columns[n] for n in fit.names], axis=1),
                                fit.e) if fit.names else fit.cov
    # ... and raised to the spread of the fits on complementary halves of the loops, which
    # sees what differs from loop to loop (errors in the contraction, a model slightly off)
    if pairs and fit.names:
        cov = inflated_covariance(cov, half_sample_covariance(des, fit.names, pairs=pairs,
                                                              seed=seed))
    effects, partial = [], []
    # the reported intervals also cover what adding a candidate the record holds a hint of
    # would do to the named ones (core.omitted); the gates judge the fit's own
    left_out = omitted(des, fit)
    for name in fit.names:
        if name in grouped:
            continue
        sl = fit.slices[name]
        params = _widened(exts[name].values(fit.phi[sl], cov[sl, sl]), exts[name], sl,
                          fit.phi.size, left_out)
        # evidence: the member against the final model without it
        ev = dict(sel.subsets.evidence[name])
        ev["evidence_ratio_log10"] = rowof.get(name, {}).get("evidence_ratio_log10")
        ev["inclusion_probability"] = sel.subsets.inclusion.get(name, 0.0)
        ev["subsystem_rho"] = {"force": rho}
        if stab is not None:
            ev["stability_frequency"] = stab.frequency.get(name, 0.0)
        entry = {"name": name, "subsystem": "force", "parameters": params, "evidence": ev,
                 "confidence": sel.subsets.inclusion.get(name, 0.0),
                 "signature": exts[name].signature}
        (effects if rho <= rho_max else partial).append(entry)
    if des.one_level and set(fit.names) & set(PRESSURE_EFFECTS):
        notes.append("the pressure takes essentially one level (95th/5th percentile ratio < "
                     f"{PRESSURE_LEVELS_RATIO}): a refitted force law, a force-sensor offset and "
                     "a pressure-sensor offset are then nearly the same column and are reported "
                     "with low confidence at most; record several pressures to separate them")
    limits = detection_limits(des, fit.names, alpha=alpha) if detection else {}
    for e in effects:
        sl = fit.slices[e["name"]]
        e["evidence"]["limit_ratio"] = (limit_ratio(des, fit.names, e["name"],
                                                    max(e["evidence"]["lr_stat"], 0.0),
                                                    alpha=alpha) if detection else None)
        e["evidence"]["time_consistency_p"] = cons = time_consistency(des, fit.names,
                                                                       e["name"])
        g = gates(e["name"], exts[e["name"]], fit.phi[sl], cov[sl, sl],
                  weight=e["confidence"],
                  stability=None if stab is None else stab.frequency.get(e["name"], 0.0),
                  stability_threshold=THRESHOLD if stab is None else stab.threshold,
                  rho=rho, m=des.m, unexplained=unexplained, turns=turns,
                  one_level=des.one_level, consistency=cons,
                  clear=math.inf if not detection else e["evidence"]["limit_ratio"])
        e["gates"] = g
        e["confidence_level"] = level(g)
    for e in partial:
        e["confidence_level"] = "low"
        e["gates"] = {}
    for g in groups:
        notes.append(f"{' and '.join(g['members'])} explain the same part of the residual on "
                     f"this record: none is named; to separate them: "
                     f"{g['separating_experiment']}")
    # the diagnosed force on every sample (the fit's coefficients, all samples)
    f_nom = des.f_nom
    f_after = f_nom.copy()
    for n in fit.names:
        f_after += exts[n].columns @ fit.phi[fit.slices[n]]
    sig = des.sig
    r = des.r
    e_all_before = r / sig
    e_all_after = (rec.force - f_after) / sig
    rr = {"force": {"unit": "N", "before": float(np.sqrt(np.mean(r ** 2))),
                    "after": float(np.sqrt(np.mean((rec.force - f_after) ** 2))),
                    "noise": float(np.sqrt(np.mean(sig ** 2)))},
          "block_force": {"unit": "N / noise (residual ratio, samples used by the statistics)",
                          "before": nominal.rho(), "after": rho, "noise": 1.0}}
    idx = des.idx
    feats = {"t": rec.t[idx], "direction": des.direction[idx], "pressure": rec.pressure[idx],
             "eps": rec.eps[idx]}
    where = _sample_regions(fit.e, feats, rho_max)
    bad = ["force"] if unexplained else []
    if unexplained:
        sigw = where[where["significant"]]
        worst = sigw.reindex(sigw["z"].abs().sort_values(ascending=False).index).head(3)
        where_txt = "; ".join(f"{r_.region}: {r_.group} (mean {r_.mean:+.2f} noise)"
                              for r_ in worst.itertuples()) or "everywhere"
        notes.append(f"force residual {rho:.2f} x the noise (> {rho_max}): no effect of the "
                     f"tester library explains it; largest where {where_txt}")
    t3 = time.perf_counter()
    settings = {"kind": "actuator", "alpha": alpha, "rho_max": rho_max,
                "criterion": "BIC (known noise level), LR test p < alpha/K, 2-fold CV gain, "
                             "parameters inside widened bounds (dissipative ones not < 0), "
                             f"effect RMS >= {MIN_EFFECT_RMS} x noise; then a backward pass; "
                             "look-alikes (a member whose LR test given an outside candidate "
                             "is not significant) reported as confounded, not named",
                "min_effect_rms": MIN_EFFECT_RMS, "rho_high": MUSCLE_RULE.rho_high(des.m),
                "high_confidence": {"rho_high_factor": MUSCLE_RULE.rho_factor,
                                    "gates": list(MUSCLE_RULE.gates),
                                    "clear_ratio": MUSCLE_RULE.clear_ratio,
                                    "stability_threshold": THRESHOLD if stab is None
                                    else stab.threshold,
                                    "min_reversals": MIN_REVERSALS_HIGH},
                "candidates": list(ACTUATOR_VOCABULARY if candidates is None else candidates),
                "candidates_applicable": list(exts), "samples": int(len(rec)),
                "samples_used": int(des.m), "stride": int(des.stride),
                "dt_s_median": float(np.median(np.diff(rec.t))), "rows": list(rec.rows),
                "seed": seed, "model": list(fit.names), "pruned": sel.pruned,
                "forward_path": list(sel.forward),
                "subsets": None if sel.subsets is None else {
                    "evaluated": sel.subsets.evaluated, "top": sel.subsets.ranking},
                "noise_estimate": {"force_residual_N": float(des.sigma),
                                   "force_residual_local_N": [float(sig.min()),
                                                              float(np.median(sig)),
                                                              float(sig.max())],
                                   "by_stride_N": {str(k): float(v)
                                                   for k, v in des.estimates.items()},
                                   "contraction": float(des.sigma_eps)},
                "intervals": "95 %, on the HAC (Newey-West) covariance of the whitened "
                             "equations in time order, each variance raised to the "
                             "half-sample variance of the fits on complementary halves of "
                             "the loops where that is larger; reported as the union with "
                             "the intervals of the fit plus each candidate the record holds "
                             f"a hint of (LR p < {HINT_P}; the fit's own as ci_*_noise)",
                "noise_method": "robust interpolation residual: 1.4826 MAD(x[k] - (w x[k-1] + "
                                "(1-w) x[k+1]))/sqrt(1 + w^2 + (1-w)^2); per sample: rolling "
                                f"median over {LOCAL_WINDOW} samples (local_N: min, median, "
                                "max)",
                "reversal_threshold": float(des.threshold), "reversals": turns,
                "pressure_one_level": bool(des.one_level),
                "speed_ratio": float(des.ctx["speed_ratio"]),
                "contraction_span": float(np.ptp(rec.eps)),
                "speed_unit": des.ctx["speed_unit"],
                "force_law": {"a": [float(x) for x in rec.a],
                              "l0": float(rec.l0) if math.isfinite(rec.l0) else None,
                              "name": data.meta["force_law"].get("name", "")},
                "data": {"kind": data.kind, "experiment": data.experiment,
                         "description": data.meta.get("description", "")}}
    timings = {"residuals_and_noise": t1 - t0, "selection": t2 - t1, "stability": tb - t2,
               "detection_limits": t3 - tb, "total": time.perf_counter() - t0}
    return Diagnosis(source=data.source, effects=effects, partial=partial,
                     unexplained=unexplained, unexplained_channels=bad, residual_rms=rr,
                     where=where, steps=steps,
                     replay={"t": rec.t, "eps": rec.eps, "pressure": rec.pressure,
                             "direction": des.direction, "measured": rec.force,
                             "before": f_nom, "after": f_after},
                     settings=settings, timings=timings, notes=tuple(notes),
                     blocks={"t": rec.t, "before": e_all_before[:, None],
                             "after": e_all_after[:, None], "eps": rec.eps},
                     kind="actuator", confounded=groups,
                     stability={} if stab is None else stab.to_dict(),
                     detection_limits=limits)


__all__ = ["ActuatorRecord", "actuator_record", "motion_direction", "contraction_rate",
           "residual_noise", "diagnose_actuator", "REVERSAL_SIGMAS", "NOISE_PLATEAU",
           "AMBIGUOUS_SIGMAS"]
