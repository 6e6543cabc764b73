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
from dataclasses import replace

import numpy as np
import pandas as pd

from ..._validation import check_int, check_range
from ..core.linear_selection import hac_covariance_linear
from ..core.omitted import HINT_P, widened_interval
from ..core.pipeline import STAGES, Steps, run_steps
from ..core.regions import largest_regions, region_rows, terciles, time_segments
from ..core.result import Diagnosis, Effect
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
    out = {}
    for i, (n, d) in enumerate(params.items()):
        g = np.zeros(k)
        g[sl] = ext.T[i]
        out[n] = d.widened(*widened_interval(d.value, d.std_error, g, left_out))
    return out


class MuscleSteps(Steps):
    """The steps of :func:`diagnose_actuator` for one muscle record (:mod:`..core.pipeline`).

    Built with :func:`diagnose_actuator`'s arguments (validated here); the stages keep the
    state on the instance.

    Parameters
    ----------
    data, candidates, alpha, rho_max, experiment, seed, stability, detection : object
        As :func:`diagnose_actuator`.
    """

    def __init__(self, data, *, candidates=None, alpha: float = 0.01, rho_max: float = 1.5,
                 experiment: str | None = None, seed: int = 0, stability: int | None = None,
                 detection: bool = True):
        check_range("alpha", alpha, 0.0, 0.5, lo_open=True)
        check_range("rho_max", rho_max, 1.0, 100.0)
        self.seed = check_int("seed", seed, 0)
        self.pairs = PAIRS if stability is None else check_int("stability", stability, 0, 10000)
        if candidates is not None:
            if isinstance(candidates, str) or not all(isinstance(c, str) for c in candidates):
                raise TypeError(f"candidates must be a sequence of names, got {candidates!r}")
            bad = [c for c in candidates if c not in ACTUATOR_VOCABULARY]
            if bad:
                raise ValueError(f"candidates = {list(candidates)}: {bad} not in the tester "
                                 f"vocabulary {list(ACTUATOR_VOCABULARY)}")
        self.data, self.candidates, self.experiment = data, candidates, experiment
        self.alpha, self.rho_max, self.detect = alpha, rho_max, detection

    def design(self):
        """The residual against the nominal law, its noise, the motion and the columns."""
        data, experiment = self.data, self.experiment
        des = actuator_design(data, self.candidates)
        if experiment is not None and experiment != data.experiment:
            raise ValueError(f"experiment = {experiment!r} does not match the record's metadata "
                             f"experiment = {data.experiment!r}")
        self.notes = list(des.notes)
        self.turns = des.turns
        if self.turns < MIN_REVERSALS_HIGH:
            self.notes.append(
                f"only {self.turns} reversal(s) of the motion (< {MIN_REVERSALS_HIGH}): "
                f"hysteresis and friction, which show at reversals, are hard to tell from "
                f"a slow drift on this record and are reported with low confidence at most")
        # the record and the candidates' extensions as designed on the nominal law (the
        # selection may rebuild the design on the fitted law; these stay)
        self.des, self.rec, self.exts = des, des.rec, des.extensions

    def selection(self):
        """The naming rule, the law re-linearised at the fitted hysteresis, the look-alikes."""
        notes = self.notes
        self.sel = sel = select(self.des, alpha=self.alpha)
        # the hysteresis multiplies the muscle's force: rebuilt on the law as fitted
        self.des, self.fit = des, fit = relinearised(self.des, sel.fit)
        self.steps, self.nominal = sel.steps, sel.nominal
        if set(sel.forward) != set(fit.names):
            notes.append(f"the search over every subset found a better model than the forward "
                         f"path: {' + '.join(fit.names)} instead of "
                         f"{' + '.join(sel.forward) or 'nominal'}")
        for pr in sel.pruned:
            notes.append(f"{pr['name']}: chosen on the way, dropped by the backward pass (LR "
                         f"p = {pr['p_value']:.2g} given the later effects): they explain its "
                         f"part")
        self.groups = confounded_groups(des, fit, alpha=self.alpha)
        self.grouped = {m for g in self.groups for m in g.members}

    def stability(self):
        """The naming rule on complementary halves of the loops."""
        self.stab = (stability_selection(self.des, alpha=self.alpha, pairs=self.pairs,
                                         seed=self.seed) if self.pairs else None)

    def covariance(self):
        """HAC covariance of the final fit, raised to the half-sample spread."""
        des, fit, pairs = self.des, self.fit, self.pairs
        self.rho = fit.rho()
        self.unexplained = bool(self.rho > self.rho_max)
        # intervals from the HAC covariance: a residual correlated over neighbouring samples (a
        # model slightly off, coloured noise) widens them
        cov = hac_covariance_linear(np.concatenate([des.columns[n] for n in fit.names], axis=1),
                                    fit.e) if fit.names else fit.cov
        # ... and raised to the spread of the fits on complementary halves of the loops, which
        # sees what differs from loop to loop (errors in the contraction, a model slightly off)
        if pairs and fit.names:
            cov = inflated_covariance(cov, half_sample_covariance(des, fit.names, pairs=pairs,
                                                                  seed=self.seed))
        self.cov = cov

    def intervals(self):
        """Every member's parameters, intervals widened for the candidates the record holds a
        hint of (the gates judge the fit's own)."""
        des, fit, exts = self.des, self.fit, self.exts
        left_out = omitted(des, fit)
        self.params = {}
        for name in fit.names:
            if name in self.grouped:
                continue
            sl = fit.slices[name]
            self.params[name] = _widened(exts[name].values(fit.phi[sl], self.cov[sl, sl]),
                                         exts[name], sl, fit.phi.size, left_out)

    def explained(self):
        """Named when the final residual is at the noise, else partial."""
        sel, stab, rho, exts = self.sel, self.stab, self.rho, self.exts
        rowof = {s.chosen: next(x for x in s.table if x["name"] == s.chosen)
                 for s in self.steps if s.chosen is not None}
        self.effects, self.partial = [], []
        for name, params in self.params.items():
            # evidence: the member against the final model without it
            ev = dict(sel.subsets.evidence[name])
            ev["evidence_ratio_log10"] = rowof.get(name, {}).get("evidence_ratio_log10")
            ev["inclusion_probability"] = sel.subsets.inclusion.get(name, 0.0)
            ev["subsystem_rho"] = {"force": rho}
            if stab is not None:
                ev["stability_frequency"] = stab.frequency.get(name, 0.0)
            entry = Effect(name=name, subsystem="force", parameters=params, evidence=ev,
                           confidence=sel.subsets.inclusion.get(name, 0.0),
                           signature=exts[name].signature)
            (self.effects if rho <= self.rho_max else self.partial).append(entry)
        if self.des.one_level and set(self.fit.names) & set(PRESSURE_EFFECTS):
            self.notes.append(
                "the pressure takes essentially one level (95th/5th percentile ratio < "
                f"{PRESSURE_LEVELS_RATIO}): a refitted force law, a force-sensor offset and "
                "a pressure-sensor offset are then nearly the same column and are reported "
                "with low confidence at most; record several pressures to separate them")

    def detection(self):
        """The detection limits of the record and each named effect's change over its own."""
        des, fit = self.des, self.fit
        self.limits = detection_limits(des, fit.names, alpha=self.alpha) if self.detect else {}
        self.ratios = {e.name: limit_ratio(des, fit.names, e.name,
                                           max(e.evidence["lr_stat"], 0.0), alpha=self.alpha)
                       if self.detect else None for e in self.effects}

    def consistency(self):
        """The constancy of each named effect over time."""
        self.cons = {e.name: time_consistency(self.des, self.fit.names, e.name)
                     for e in self.effects}

    def gates(self):
        """The muscle's rule for "high" (:data:`~.gates.MUSCLE_RULE`) on every named effect."""
        des, fit, cov, stab = self.des, self.fit, self.cov, self.stab
        judged = []
        for e in self.effects:
            sl = fit.slices[e.name]
            ratio, cons = self.ratios[e.name], self.cons[e.name]
            ev = {**e.evidence, "limit_ratio": ratio, "time_consistency_p": cons}
            g = gates(e.name, self.exts[e.name], fit.phi[sl], cov[sl, sl],
                      weight=e.confidence,
                      stability=None if stab is None else stab.frequency.get(e.name, 0.0),
                      stability_threshold=THRESHOLD if stab is None else stab.threshold,
                      rho=self.rho, m=des.m, unexplained=self.unexplained, turns=self.turns,
                      one_level=des.one_level, consistency=cons,
                      clear=math.inf if not self.detect else ratio)
            judged.append(replace(e, evidence=ev, gates=g, confidence_level=level(g)))
        self.effects = judged
        self.partial = [replace(e, confidence_level="low", gates={}) for e in self.partial]
        for g in self.groups:
            self.notes.append(f"{' and '.join(g.members)} explain the same part of the residual "
                              f"on this record: none is named; to separate them: "
                              f"{g.separating_experiment}")

    def regions(self):
        """The diagnosed force on every sample and where the final residual is significant."""
        des, fit, rec, rho = self.des, self.fit, self.rec, self.rho
        # the diagnosed force on every sample (the fit's coefficients, all samples)
        f_after = des.f_nom.copy()
        for n in fit.names:
            f_after += self.exts[n].columns @ fit.phi[fit.slices[n]]
        sig, r = des.sig, des.r
        self.f_after = f_after
        self.e_all = (r / sig, (rec.force - f_after) / sig)
        self.rr = {"force": {"unit": "N", "before": float(np.sqrt(np.mean(r ** 2))),
                             "after": float(np.sqrt(np.mean((rec.force - f_after) ** 2))),
                             "noise": float(np.sqrt(np.mean(sig ** 2)))},
                   "block_force": {"unit": "N / noise (residual ratio, samples used by the "
                                           "statistics)",
                                   "before": self.nominal.rho(), "after": rho, "noise": 1.0}}
        idx = des.idx
        feats = {"t": rec.t[idx], "direction": des.direction[idx],
                 "pressure": rec.pressure[idx], "eps": rec.eps[idx]}
        self.where = where = _sample_regions(fit.e, feats, self.rho_max)
        if self.unexplained:
            worst = largest_regions(where)
            where_txt = "; ".join(f"{r_.region}: {r_.group} (mean {r_.mean:+.2f} noise)"
                                  for r_ in worst.itertuples()) or "everywhere"
            self.notes.append(f"force residual {rho:.2f} x the noise (> {self.rho_max}): no "
                              f"effect of the tester library explains it; largest where "
                              f"{where_txt}")

    def result(self, seconds: dict) -> Diagnosis:
        """The :class:`~ppamsafety.diagnose.core.result.Diagnosis` (settings and timings).
        Parameters
        ----------
        seconds : dict
            Stage -> wall time [s] (:func:`~ppamsafety.diagnose.core.pipeline.run_steps`).
        """
        t0 = time.perf_counter()
        des, fit, sel, stab, data = self.des, self.fit, self.sel, self.stab, self.data
        rec, sig, candidates = self.rec, des.sig, self.candidates
        settings = {"kind": "actuator", "alpha": self.alpha, "rho_max": self.rho_max,
                    "criterion": "BIC (known noise level), LR test p < alpha/K, 2-fold CV gain, "
                                 "parameters inside widened bounds (dissipative ones not < 0), "
                                 f"effect RMS >= {MIN_EFFECT_RMS} x noise; then a backward "
                                 "pass; look-alikes (a member whose LR test given an outside "
                                 "candidate is not significant) reported as confounded, not "
                                 "named",
                    "min_effect_rms": MIN_EFFECT_RMS, "rho_high": MUSCLE_RULE.rho_high(des.m),
                    "high_confidence": {"rho_high_factor": MUSCLE_RULE.rho_factor,
                                        "gates": list(MUSCLE_RULE.gates),
                                        "clear_ratio": MUSCLE_RULE.clear_ratio,
                                        "stability_threshold": THRESHOLD if stab is None
                                        else stab.threshold,
                                        "min_reversals": MIN_REVERSALS_HIGH},
                    "candidates": list(ACTUATOR_VOCABULARY if candidates is None
                                       else candidates),
                    "candidates_applicable": list(self.exts), "samples": int(len(rec)),
                    "samples_used": int(des.m), "stride": int(des.stride),
                    "dt_s_median": float(np.median(np.diff(rec.t))), "rows": list(rec.rows),
                    "seed": self.seed, "model": list(fit.names), "pruned": sel.pruned,
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
                    "noise_method": "robust interpolation residual: 1.4826 MAD(x[k] - (w x[k-1] "
                                    "+ (1-w) x[k+1]))/sqrt(1 + w^2 + (1-w)^2); per sample: "
                                    f"rolling median over {LOCAL_WINDOW} samples (local_N: min, "
                                    "median, max)",
                    "reversal_threshold": float(des.threshold), "reversals": self.turns,
                    "pressure_one_level": bool(des.one_level),
                    "speed_ratio": float(des.ctx["speed_ratio"]),
                    "contraction_span": float(np.ptp(rec.eps)),
                    "speed_unit": des.ctx["speed_unit"],
                    "force_law": {"a": [float(x) for x in rec.a],
                                  "l0": float(rec.l0) if math.isfinite(rec.l0) else None,
                                  "name": data.meta["force_law"].get("name", "")},
                    "data": {"kind": data.kind, "experiment": data.experiment,
                             "description": data.meta.get("description", "")}}
        late = sum(seconds[s] for s in STAGES[3:])
        timings = {"residuals_and_noise": seconds["design"], "selection": seconds["selection"],
                   "stability": seconds["stability"], "detection_limits": late,
                   "total": sum(seconds.values()) + time.perf_counter() - t0}
        before, after = self.e_all
        return Diagnosis(source=data.source, effects=self.effects, partial=self.partial,
                         unexplained=self.unexplained,
                         unexplained_channels=["force"] if self.unexplained else [],
                         residual_rms=self.rr, where=self.where, steps=self.steps,
                         replay={"t": rec.t, "eps": rec.eps, "pressure": rec.pressure,
                                 "direction": des.direction, "measured": rec.force,
                                 "before": des.f_nom, "after": self.f_after},
                         settings=settings, timings=timings, notes=tuple(self.notes),
                         blocks={"t": rec.t, "before": before[:, None],
                                 "after": after[:, None], "eps": rec.eps},
                         kind="actuator", confounded=self.groups,
                         stability={} if stab is None else stab.to_dict(),
                         detection_limits=self.limits)


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
    return run_steps(MuscleSteps(data, candidates=candidates, alpha=alpha, rho_max=rho_max,
                                 experiment=experiment, seed=seed, stability=stability,
                                 detection=detection))


__all__ = ["ActuatorRecord", "actuator_record", "motion_direction", "contraction_rate",
           "residual_noise", "diagnose_actuator", "MuscleSteps", "REVERSAL_SIGMAS", "NOISE_PLATEAU",
           "AMBIGUOUS_SIGMAS"]
