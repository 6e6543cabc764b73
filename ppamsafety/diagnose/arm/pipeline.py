"""The diagnosis of an arm record, :func:`diagnose_arm`.

Pipeline for an arm record (open loop, or closed loop with the set values
logged): noise level from the data (:mod:`ppamsafety.diagnose.core.noise`), block residuals per
subsystem (:mod:`.residuals`), forward selection over the candidate library
with refit (:mod:`.selection`), then the rollout of the nominal model and of
the fitted one (the gap shrinking, as RMS per channel and as figures).  The
result is a :class:`~ppamsafety.diagnose.core.result.Diagnosis`.

The model under test is the arm given, its declared effects included
(:mod:`.residuals`); the "after" rollout is the model whose block residuals the
gates judged (:func:`after_row`), and "explained" needs both at the noise: every
block channel at most ``rho_max`` and every replay channel's RMS over its sample
noise at most :data:`REPLAY_RHO` (:data:`REPLAY_RHO_STATIC` for the rest angles
of a sawtooth).
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np
import pandas as pd

from ..._validation import check_int, check_range, check_seed
from ...params import thesis_arm
from ...params.arm import ArmParameters
from ...params.effects import VALVE_DEAD_TIME_MAX
from ...plant import layout as lay
from ...plant import packing
from ..core.omitted import HINT_P
from ..core.pipeline import STAGES, Steps, run_steps
from ..core.regions import region_rows, terciles, time_segments
from ..core.result import ConfoundedGroup, Diagnosis, Effect
from .candidates import REGISTRY, SensorFault, default_candidates, separating_experiment
from .detection import detection_limits, omitted
from ..core.gates import HIGH_WEIGHT, level
from .gates import ARM_RULE, gates, moved_parameters
from .residuals import (CHANNELS, CHANNEL_UNITS, PRESSURE_GAIN_COLUMNS, SUBSYSTEM, ArmRecord,
                        Columns, arm_record, block_system, changed_delays, channel_noise,
                        coulomb_velocity, declared_delays, model_vector, noise_draws, replay,
                        row_from_mu)
from .selection import (BOOTSTRAP_REPLICATES, CONSTANCY_ALPHA, STABILITY_PAIRS,
                        STABILITY_THRESHOLD, at_model, bootstrap_frequency, fit_model,
                        forward_selection,
                        hac_covariance, in_bounds, make_problem, parameter_table,
                        compensating, profiled_shift, refit, region_consistency,
                        stability_selection)
from .replay_limit import REPLAY_CALIBRATED_SECONDS, start_spread, widened_limit
from .subsets import MAX_SIZE, search
from .static import (force_residuals, static_equilibria, static_floor,
                     static_noise, static_noise_draws, static_record, static_system)

#: Largest replay RMS over the sample noise of a channel of an open- or closed-loop record
#: at which the fitted model still reproduces it ("unexplained" above).  Calibrated on the
#: tuning seeds of both arm batteries: 1.25 x the largest ratio of a model the diagnosis
#: got right (:func:`ppamsafety.diagnose.scenarios.replay_limits` on the shipped tuning rows,
#: ``REPLAY_TUNING_FILE``; ``docs/diagnose.md``).
REPLAY_RHO = 2.0
#: The same for a static-sawtooth record (rest angles and pressures; the quasi-static
#: continuation of the model does not replay the transitions' overshoot and minor loops).
REPLAY_RHO_STATIC = 3.2
#: Replay channels (full simulation vs measured).
REPLAY_CHANNELS = ("q1", "q2", "qd1", "qd2", "p1", "p2", "p3", "p4")
REPLAY_UNITS = ("rad", "rad", "rad/s", "rad/s", "Pa", "Pa", "Pa", "Pa")


def _block_regions(e, feats, rho_max):
    """Operating regions of significant residual (see :func:`diagnose`)."""
    rows = []
    for c, ch in enumerate(CHANNELS):
        j = 0 if c in (0, 1, 4) else 1
        pch = feats["p"][:, c] if c < 4 else feats["p"][:, 2 * j:2 * j + 2].mean(axis=1)
        groups = {
            "velocity sign": {"qd > 0": feats["qd"][:, j] > 0, "qd < 0": feats["qd"][:, j] <= 0},
            "pressure level": terciles(pch, "p"),
            "configuration": terciles(feats["q"][:, j], f"q{j + 1}"),
            "time segment": time_segments(feats["t"]),
        }
        rows += region_rows(e[:, c], groups, ch, rho_max)
    return pd.DataFrame(rows)


def after_row(arm, fit, params) -> np.ndarray:
    """The plant row of the model with every fitted plant effect (for the "after" rollout).

    It is the model whose block residuals the selection and the gates judged: the arm under
    test with its declared effects, changed by the fit.  Effects that are directions of the
    model vector are written back with
    :func:`~ppamsafety.diagnose.arm.residuals.row_from_mu`; effects with their
    own regression columns (hysteresis, a torque bias) through their ``plant_effect``
    (:class:`~ppamsafety.params.effects.Effects` overrides of the declared ones, e.g. the
    fitted delta, clipped to the plant's range [0, 1]); a changed dead time as the plant's
    ``valve_dead_time`` (the declared one per valve changed by the fitted shift).  Sensor
    faults are not plant effects: :func:`sensor_fault` applies them to the simulated
    measurements.

    Parameters
    ----------
    arm : ArmParameters
        The model under test (with its declared effects).
    fit : ppamsafety.diagnose.arm.selection._Fit
        The final fit.
    params : dict
        :func:`~ppamsafety.diagnose.arm.selection.parameter_table` of ``fit``.

    Returns
    -------
    numpy.ndarray, shape (NP,)
    """

    over = {}
    for n in fit.names:
        c = REGISTRY[n]
        if c.columns is not None and c.plant_effect is not None:
            vals = np.array([p.value for p in params[n].values()])
            over.update(c.plant_effect(vals, arm))
        if c.grid:
            d = [min(x, VALVE_DEAD_TIME_MAX) for x in changed_delays(declared_delays(arm),
                                                                     fit.shift)]
            over["valve_dead_time"] = tuple(d) if any(d) else None
    if "joint_torque_bias" in over:
        over["joint_torque_bias"] = tuple(float(np.clip(b, -20.0, 20.0))
                                          for b in over["joint_torque_bias"])
    base = arm.replace(effects=replace(arm.effects, **over)) if over else arm
    return row_from_mu(packing.pack(base), fit.mu)



def sensor_fault(fit, params) -> SensorFault:
    """The fitted sensor faults of ``fit`` (zero when none was fitted).

    Parameters
    ----------
    fit : ppamsafety.diagnose.arm.selection._Fit
    params : dict
        :func:`~ppamsafety.diagnose.arm.selection.parameter_table` of ``fit``.
    """
    out = SensorFault()
    for n in fit.names:
        c = REGISTRY[n]
        if c.sensor_effect is not None:
            out = out + c.sensor_effect(np.array([p.value for p in params[n].values()]))
    return out


def _limit_ratio(e, limits) -> float:
    """The largest change of a parameter of named effect ``e`` over its detection limit."""
    lim = limits.get(e.name, {})
    best = 0.0
    for p, d in e.parameters.items():
        L = lim.get(p, {}).get("limit", math.inf)
        if L > 0 and math.isfinite(L):
            best = max(best, abs(d.value - d.nominal) / L)
    return best


def _entry(name, params, rho, sub, bootstrap, freq):
    """The :class:`Effect` of a named (or partial) effect and the largest residual ratio of its
    subsystem."""
    subsystem = REGISTRY[name].subsystem
    sub_rho = {CHANNELS[c]: float(rho[c]) for c in SUBSYSTEM[subsystem]}
    ev = dict(sub.evidence.get(name, {}))
    ev["inclusion_probability"] = sub.inclusion.get(name, 0.0)
    ev["subsystem_rho"] = sub_rho
    if freq is not None:
        ev["stability_frequency"] = freq.get(name, 0.0)
    if bootstrap is not None:
        ev["bootstrap_frequency"] = bootstrap.get(name, 0.0)
    return Effect(name=name, subsystem=subsystem, parameters=params[name], evidence=ev,
                  confidence=sub.inclusion.get(name, 0.0)), max(sub_rho.values())


def _confounded_group(fprob, fit, name, members, params, rho, sub, freq):
    """The :class:`ConfoundedGroup` of a member of the final model that look-alikes can
    replace."""
    others = [n for n in fit.names if n != name]
    interp = {name: params[name]}
    for m in members[1:]:
        try:
            f = fit_model(fprob, others + [m])
            interp[m] = parameter_table(fprob, f)[m]
        except (ValueError, np.linalg.LinAlgError) as exc:   # pragma: no cover - reported
            interp[m] = {"error": str(exc)}
    seps = []
    for i, a in enumerate(members):
        for b in members[i + 1:]:
            e = separating_experiment(a, b)
            if e not in seps:
                seps.append(e)
    dbic = dict(sub.lookalikes.get(name, []))
    return ConfoundedGroup(
        members=tuple(members), interpretations=interp,
        evidence={m: {"inclusion_probability": sub.inclusion.get(m, 0.0),
                      "delta_bic_vs_best": dbic.get(m, 0.0),
                      **({"stability_frequency": freq.get(m, 0.0)} if freq is not None else {})}
                  for m in members},
        separating_experiment="; ".join(seps),
        subsystem_rho={CHANNELS[c]: float(rho[c]) for c in range(len(CHANNELS))})


#: Encoder offset above which the encoder columns are re-linearised at the estimate [rad]
#: (the first-order error of the columns is about the offset squared over a radian).
ENCODER_REFINE = 2e-3


def _system(rec, arm, static, block_seconds, noise, *, q_offset):
    """The block (or rest-point) system of ``rec`` with the angles corrected by ``q_offset``."""
    if static:
        return static_system(replace(rec, q=rec.q - q_offset), arm)
    r = ArmRecord(rec.t, rec.q - q_offset, rec.qd, rec.p, rec.u, rec.dt, rec.source, rec.rows)
    return block_system(r, arm, block_seconds=block_seconds, velocity_noise=noise["qd"])


def _rescaled_gain(prob, bs, g):
    """``prob`` with the torque columns of the pressure gains divided by (1 + g): the
    coefficient of the torque columns is g / (1 + g), so at the estimate the column per unit
    g is the original over (1 + g) (the pressure columns are exact in g already)."""
    col = bs.extra[PRESSURE_GAIN_COLUMNS]
    scaled = Columns(col.Y / (1.0 + np.asarray(g))[None, None, :], col.X)
    nbs = replace(prob.bs, extra={**prob.bs.extra, PRESSURE_GAIN_COLUMNS: scaled})
    return replace(prob, bs=nbs, _memo={}, _xcache=prob._xcache)


class ArmSteps(Steps):
    """The steps of :func:`diagnose_arm` for one arm record (:mod:`..core.pipeline`).

    Built with :func:`diagnose_arm`'s arguments (validated here); the stages keep the state
    on the instance.

    Parameters
    ----------
    data, arm, candidates, block_seconds, alpha, rho_max : object
        As :func:`diagnose_arm`.
    experiment, seed, bootstrap, stability, detection : object
        As :func:`diagnose_arm`.
    """

    def __init__(self, data, *, arm=None, candidates=None, block_seconds: float = 0.05,
                 alpha: float = 0.01, rho_max: float = 1.5, experiment: str | None = None,
                 seed: int = 0, bootstrap: int | None = None, stability: int | None = None,
                 detection: bool = True):
        arm = thesis_arm() if arm is None else arm
        if not isinstance(arm, ArmParameters):
            raise TypeError(f"arm must be an ArmParameters, got {type(arm).__name__}")
        check_range("alpha", alpha, 0.0, 0.5, lo_open=True)
        check_range("rho_max", rho_max, 1.0, 100.0)
        self.seed = check_seed("seed", seed)
        if experiment is not None and experiment != data.experiment:
            raise ValueError(f"experiment = {experiment!r} does not match the record's metadata "
                             f"experiment = {data.experiment!r}")
        self.bootstrap = (BOOTSTRAP_REPLICATES if bootstrap is None
                          else check_int("bootstrap", bootstrap, 0, 10000))
        self.pairs = (STABILITY_PAIRS if stability is None
                      else check_int("stability", stability, 0, 10000))
        self.data, self.arm, self.candidates = data, arm, candidates
        self.block_seconds, self.alpha, self.rho_max = block_seconds, alpha, rho_max
        self.detect = detection
        self.static = data.experiment == "static-sawtooth"

    def design(self):
        """The record (or its rest points), its noise, the block system and the noise draws."""
        data, arm, seed, block_seconds = self.data, self.arm, self.seed, self.block_seconds
        candidates = self.candidates
        self.row0 = packing.pack(arm)
        self.mu0 = model_vector(self.row0)
        if self.static:
            rec, notes = static_record(data)
            noise = static_noise(rec)
            bs = static_system(rec, arm)
            draws = static_noise_draws(rec, arm, noise, seed=seed)
            prob = make_problem(bs, self.mu0, draws, arm, floor=static_floor(rec, arm))
            if candidates is None:
                candidates = list(default_candidates(static=True))
                if rec.u is None:
                    candidates = [c for c in candidates if c != "valve_offset_gain"]
        else:
            rec, notes = arm_record(data)
            noise = channel_noise(rec)
            bs = block_system(rec, arm, block_seconds=block_seconds, velocity_noise=noise["qd"])
            draws = noise_draws(rec, arm, noise, block_seconds=block_seconds, seed=seed,
                                velocity_noise=True)
            prob = make_problem(bs, self.mu0, draws, arm)
            if candidates is None:
                candidates = list(default_candidates())
        self.candidates = list(candidates)
        self.notes = list(data.notes) + notes
        self.rec, self.noise, self.bs, self.draws, self.prob = rec, noise, bs, draws, prob

    def selection(self):
        """Forward selection, every small subset, the look-alikes, and the sensor faults
        re-linearised at the estimate."""
        prob, candidates, alpha, notes = self.prob, self.candidates, self.alpha, self.notes
        arm, rec, noise, bs = self.arm, self.rec, self.noise, self.bs
        self.nominal = fit_model(prob, [])
        gfit, self.steps, gprob = forward_selection(prob, candidates, alpha=alpha)
        # every small subset of the library, from the Gram matrices: the forward path is greedy
        grid_names = [c for c in candidates if REGISTRY[c].grid]
        if grid_names and grid_names[0] not in gfit.names:
            shift = profiled_shift(prob, grid_names) or 0
        else:
            shift = int(gfit.shift)
        # opt-in candidates left out are tried as look-alikes of the names (never named)
        self.shadows = [n for n, c in REGISTRY.items() if not c.default and n not in candidates
                        and (c.at_rest or not self.static)]
        sub = search(gprob, candidates, greedy=gfit.names, shift=shift, alpha=alpha,
                     shadows=self.shadows)
        if set(sub.names) != set(gfit.names):
            notes.append(f"the search over every subset of up to {MAX_SIZE} effects found a "
                         f"better model than the forward path: "
                         f"{' + '.join(sub.names) or 'nominal'} (BIC {sub.bic:.1f}) instead of "
                         f"{' + '.join(gfit.names) or 'nominal'} (BIC {sub.greedy_bic:.1f})")
            fit, fprob = refit(prob, sub.names, prob=gprob,
                               shift=shift if any(REGISTRY[n].grid for n in sub.names) else None)
        else:
            fit, fprob = gfit, gprob
        # first-order sensor faults to their fixed point (Gauss-Newton): the encoder offset's
        # columns are the derivative at the measured angles, a pressure gain's torque columns
        # are exact in g / (1 + g); re-linearise at the estimate
        enc_shift, gain = np.zeros(2), None
        for _ in range(3):
            changed = False
            if "pressure_sensor_gain" in fit.names:
                g = fit.phi[fit.slices["pressure_sensor_gain"]].copy()
                if gain is None or np.max(np.abs(g - gain)) > 1e-4:
                    gain, changed = g, True
            if "encoder_offset" in fit.names:
                o = fit.phi[fit.slices["encoder_offset"]]
                if np.max(np.abs(o)) > ENCODER_REFINE:
                    enc_shift = enc_shift + o
                    bs = _system(rec, arm, self.static, self.block_seconds, noise,
                                 q_offset=enc_shift)
                    changed = True
            if not changed:
                break
            base = make_problem(bs, self.mu0, self.draws, arm, floor=prob.floor)
            if gain is not None:
                base = _rescaled_gain(base, bs, gain)
            fit, fprob = refit(base, fit.names, prob=at_model(base, fit.mu),
                               shift=fit.shift if any(REGISTRY[n].grid for n in fit.names)
                               else None)
        self.gfit, self.sub, self.fit, self.fprob = gfit, sub, fit, fprob
        self.enc_shift, self.bs = enc_shift, bs

    def stability(self):
        """The moving-block bootstrap and the stability selection."""
        self.freq, self.boot_info = (None, {})
        if self.bootstrap:
            self.freq, self.boot_info = bootstrap_frequency(
                self.prob, self.candidates, replicates=self.bootstrap, seed=self.seed,
                alpha=self.alpha)
        self.stab = None
        if self.pairs:
            self.stab = stability_selection(self.prob, self.candidates, pairs=self.pairs,
                                            seed=self.seed, alpha=self.alpha,
                                            reference=self.fit.mu)

    def covariance(self):
        """The HAC covariance of the block scores of the final fit."""
        self.rho = self.fit.rho()
        self.hac = hac_covariance(self.fprob, self.fit) if self.fit.names else None

    def intervals(self):
        """The gates' parameter table (the fit's own intervals) and the reported one."""
        fprob, fit, hac = self.fprob, self.fit, self.hac
        # the gates judge the fit's own intervals; the reported ones also cover what adding an
        # effect the record holds a hint of would do to the named ones (core.omitted)
        params = parameter_table(fprob, fit, cov=hac) if fit.names else {}
        reported = (parameter_table(fprob, fit, cov=hac, omitted=omitted(
            fprob, fit, self.candidates, shadows=self.shadows)) if fit.names else {})
        for table in (params, reported):
            if "encoder_offset" in table and np.any(self.enc_shift):
                table["encoder_offset"] = {k: d.shifted(float(self.enc_shift[j])) for j, (k, d)
                                           in enumerate(table["encoder_offset"].items())}
        self.params, self.reported = params, reported

    def explained(self):
        """The replay of the fitted model, the residual against the noise, and each member
        of the fit named, partial or confounded."""
        rec, arm, noise, fit, params = self.rec, self.arm, self.noise, self.fit, self.params
        static, rho, rho_max, notes = self.static, self.rho, self.rho_max, self.notes
        row_after = after_row(arm, fit, params)
        fault = sensor_fault(fit, params)
        rr = {}
        forces = None
        spread = seconds = None
        if static:
            Q, Pm = static_equilibria(rec, np.array([self.row0, row_after]))
            qm, pm = rec.means(rec.q), rec.means(rec.p)
            meas = np.concatenate([qm, np.zeros_like(qm), pm], axis=1)
            before = np.concatenate([Q[0], np.zeros_like(qm), Pm[0]], axis=1)
            # the model's rest angles and pressures are true ones: measured through the fitted
            # sensor faults, as the record was (an encoder offset shifts the angles read)
            after = fault.measure(np.concatenate([Q[1], np.zeros_like(qm), Pm[1]], axis=1))
            t_rep = self.bs.features["t"]
            sig_replay = np.concatenate([noise["q"], np.zeros(2), noise["p"]])
            forces = force_residuals(rec, arm, noise, delta=lay.PLANT.read(row_after,
                                                                           "hysteresis_delta"))
            if forces is not None:
                for k in range(4):
                    rr[f"F{k + 1}"] = {"unit": "N", "before": float(np.sqrt(np.mean(
                        forces["residual_before"][:, k] ** 2))), "after": float(np.sqrt(np.mean(
                            forces["residual_after"][:, k] ** 2))),
                        "noise": float(forces["sigma"][k])}
        else:
            seconds = len(rec) * rec.dt
            try:
                x0_after = fault.true_state(rec.x0())
                X0 = replay(rec, np.array([self.row0]), shifts=[0])
                X1 = replay(rec, np.array([row_after]), shifts=[0], x0=x0_after)
                before, after = X0[0], fault.measure(X1[0])
                if seconds < REPLAY_CALIBRATED_SECONDS:
                    # a record shorter than the calibration's: its noisy starting state's share
                    spread = start_spread(rec, row_after, x0_after, np.concatenate(
                        [noise["q"], noise["qd"], noise["p"]]), measure=fault.measure,
                        seed=self.seed)
            except ValueError as exc:
                # a model with every fitted effect (partial ones too: e.g. a negative payload
                # absorbing an error outside the library) may leave the model's valid range
                X = replay(rec, np.array([self.row0]), shifts=[0])
                before, after = X[0], X[0]
                notes.append(f"the model with every fitted effect could not be simulated "
                             f"({exc}); 'after' repeats 'before'")
            meas = np.concatenate([rec.q, rec.qd, rec.p], axis=1)
            t_rep = rec.t
            sig_replay = np.concatenate([noise["q"], noise["qd"], noise["p"]])
        for k, ch in enumerate(REPLAY_CHANNELS):
            if static and ch in ("qd1", "qd2"):
                continue
            rr[ch] = {"unit": REPLAY_UNITS[k],
                      "before": float(np.sqrt(np.mean((before[:, k] - meas[:, k]) ** 2))),
                      "after": float(np.sqrt(np.mean((after[:, k] - meas[:, k]) ** 2))),
                      "noise": float(sig_replay[k])}
        # the fitted model's replay against the measured record: "explained" also needs it at
        # the noise (:data:`REPLAY_RHO`); a replay that is not finite is not at the noise
        replay_rho = {ch: rr[ch]["after"] / rr[ch]["noise"] for ch in REPLAY_CHANNELS
                      if ch in rr and rr[ch]["noise"] > 0}
        replay_limit = REPLAY_RHO_STATIC if static else REPLAY_RHO
        channel_limits = {ch: replay_limit if spread is None else widened_limit(
            replay_limit, spread[REPLAY_CHANNELS.index(ch)], seconds) for ch in replay_rho}
        replay_bad = [f"replay {ch}" for ch, v in replay_rho.items()
                      if not (math.isfinite(v) and v <= channel_limits[ch])]
        self.sfreq = None if self.stab is None else self.stab.frequency
        effects, partial, confounded = [], [], []
        if static and rec.u is None:
            rho[:4] = 0.0                       # no valve equations without set values
        bad = [CHANNELS[c] for c in range(6) if rho[c] > rho_max] + replay_bad
        unexplained = bool(bad)
        chosen = [s.chosen for s in self.steps if s.chosen is not None]
        for n in chosen:
            if n not in fit.names:
                notes.append(f"{n}: chosen by the forward path but not in the final model "
                             f"(redundant once the other effects were in)")
        order = [n for n in chosen if n in fit.names] + [n for n in fit.names if n not in chosen]
        grouped = set()
        for n in order:
            if n in grouped:
                continue
            entry, sub_max = _entry(n, params, rho, self.sub, self.freq, self.sfreq)
            if not moved_parameters(n, entry.parameters):
                # significant in the selection's test, but with the block correlations (the
                # HAC interval) every parameter's interval still holds its nominal value: the
                # record does not show that the effect is there (measured on the scenario
                # battery: 21 of 23 such names were wrong, most an encoder offset beside a
                # pressure gain)
                notes.append(f"{n}: every parameter's 95 % interval holds its nominal value; "
                             f"reported as partial, not named")
                partial.append(entry)
                continue
            alts = [a for a, _ in self.sub.lookalikes.get(n, [])]
            if alts:
                members = [n] + alts
                grouped.update(members)
                confounded.append(_confounded_group(self.fprob, fit, n, members, params, rho,
                                                    self.sub, self.sfreq))
                continue
            if not in_bounds(self.fprob, fit, n):
                # admissible in its subset, but the final fit moved it out of the plausible
                # range: it stands in for something else
                notes.append(f"{n}: its parameters left the plausible range in the final fit; "
                             f"reported as partial, not named")
                partial.append(entry)
                continue
            (effects if sub_max <= rho_max else partial).append(entry)
        self.rr, self.forces, self.meas, self.before, self.after = rr, forces, meas, before, after
        self.t_rep, self.replay_rho, self.replay_limit = t_rep, replay_rho, replay_limit
        self.channel_limits, self.spread = channel_limits, spread
        self.replay_bad, self.bad, self.unexplained = replay_bad, bad, unexplained
        self.effects, self.partial, self.confounded = effects, partial, confounded

    def detection(self):
        """The smallest change of every candidate this record would detect."""
        self.limits = (detection_limits(self.fprob, self.fit, self.candidates, alpha=self.alpha,
                                        shadows=self.shadows) if self.detect else {})

    def consistency(self):
        """Named effects that cancel each other, and the constancy of each across regions."""
        self.comp = compensating(self.fprob, self.fit)
        self.cons = {e.name: region_consistency(self.fprob, self.fit, e.name)
                     for e in self.effects}
        self.bad_subsystems = {ch for n, c in self.cons.items() if min(c.values(), default=1.0)
                               < CONSTANCY_ALPHA for ch in SUBSYSTEM[REGISTRY[n].subsystem]}

    def gates(self):
        """The arm's rule for "high" (:data:`~.gates.ARM_RULE`) on every named effect; the
        reported intervals replace the gates' own."""
        stab, sfreq, comp, reported = self.stab, self.sfreq, self.comp, self.reported
        judged = []
        for e in self.effects:
            c = self.cons[e.name]
            own = min(c.values(), default=1.0)
            if self.bad_subsystems & set(SUBSYSTEM[REGISTRY[e.name].subsystem]):
                own = min(own, 0.0)
            ev = {**e.evidence, "region_consistency_p": c,
                  "limit_ratio": _limit_ratio(e, self.limits)}
            if e.name in comp:
                ev["compensates"] = list(comp[e.name])
            g = gates(e.name, e.parameters, weight=e.confidence,
                      stability=None if sfreq is None else sfreq.get(e.name, 0.0),
                      stability_threshold=STABILITY_THRESHOLD if stab is None
                      else stab.threshold,
                      rho=self.rho, unexplained=self.unexplained, confounded=False,
                      consistency=own, blocks=self.bs.nb,
                      clear=ev["limit_ratio"] if self.detect else math.inf,
                      compensating=e.name in comp)
            judged.append(replace(e, evidence=ev, gates=g, confidence_level=level(g),
                                  parameters=reported[e.name]))
        self.effects = judged
        self.partial = [replace(e, confidence_level="low", gates={},
                                parameters=reported[e.name]) for e in self.partial]
        self.confounded = [replace(g, interpretations={**g.interpretations,
                                                       g.members[0]: reported[g.members[0]]})
                           for g in self.confounded]

    def regions(self):
        """The block residual ratios before and after, and where the final one is
        significant."""
        static, rec, rr, rho, notes = self.static, self.rec, self.rr, self.rho, self.notes
        nrho = self.nominal.rho()
        units = ("Pa/s",) * 4 + ("N m",) * 2 if static else CHANNEL_UNITS
        for c, ch in enumerate(CHANNELS):
            if static and c < 4 and rec.u is None:
                continue
            rr[f"block_{ch}"] = {"unit": f"{units[c]} / noise (block residual ratio)",
                                 "before": float(nrho[c]), "after": float(rho[c]), "noise": 1.0}
        where = _block_regions(self.fit.e, self.bs.features, self.rho_max)
        if static:
            where["region"] = where["region"].replace(
                {"velocity sign": "direction of approach"})
            where["group"] = where["group"].str.replace("qd > 0", "angle rose").str.replace(
                "qd < 0", "angle fell or held")
        blocks_bad = [b for b in self.bad if not b.startswith("replay ")]
        if blocks_bad:
            notes.append(f"residual above {self.rho_max} x the noise on {', '.join(blocks_bad)}: "
                         f"no effect of the library explains it (see 'where')")
        if self.replay_bad:
            notes.append(f"the replay of the fitted model stays above the noise on "
                         f"{', '.join(b[7:] for b in self.replay_bad)} (RMS over the noise "
                         f"{', '.join(f'{self.replay_rho[b[7:]]:.3g}' for b in self.replay_bad)}"
                         f" > {', '.join(f'{self.channel_limits[b[7:]]:.3g}' for b in self.replay_bad)}"
                         f"): the model under test with the fitted effects does not reproduce "
                         f"the record")
        for g in self.confounded:
            notes.append(f"{' and '.join(g.members)} explain the same part of the residual on "
                         f"this record: none is named; to separate them: "
                         f"{g.separating_experiment}")
        self.where = where

    def result(self, seconds: dict) -> Diagnosis:
        """The :class:`~ppamsafety.diagnose.core.result.Diagnosis` (settings and timings).
        Parameters
        ----------
        seconds : dict
            Stage -> wall time [s] (:func:`~ppamsafety.diagnose.core.pipeline.run_steps`).
        """
        t0 = time.perf_counter()
        static, rec, data, stab, sub = self.static, self.rec, self.data, self.stab, self.sub
        settings = {"block_seconds": None if static else self.block_seconds,
                    "alpha": self.alpha, "rho_max": self.rho_max,
                    "criterion": "forward selection then the best of every subset of up to "
                                 f"{MAX_SIZE} effects by BIC (known noise level) whose members "
                                 "are each significant (LR test p < alpha/K), predictive (2-fold "
                                 "CV gain) and admissible (intervals inside widened plausible "
                                 "bounds, not significantly outside the physical range); "
                                 "look-alikes within BIC 6 reported as confounded, not named",
                    "subsets": {"evaluated": sub.evaluated, "best": list(sub.names),
                                "forward_path": list(self.gfit.names), "top": sub.ranking},
                    "replay": {"rho": self.replay_rho, "limit": self.replay_limit,
                               "limits": self.channel_limits,
                               "start_spread": None if self.spread is None else dict(zip(
                                   REPLAY_CHANNELS, (float(v) for v in self.spread))),
                               "calibrated_seconds": REPLAY_CALIBRATED_SECONDS,
                               "statistic": "RMS(after - measured) / sample noise per replay "
                                            "channel; at the noise when every one is <= its "
                                            "limit (the calibrated limit, widened on a record "
                                            "shorter than calibrated_seconds by the start_spread "
                                            "share of its noisy starting state)",
                               "at_noise": not self.replay_bad},
                    "high_confidence": {"inclusion_probability": HIGH_WEIGHT,
                                        "rho_high": ARM_RULE.rho_factor,
                                        "stability_threshold": STABILITY_THRESHOLD
                                        if stab is None else stab.threshold,
                                        "gates": list(ARM_RULE.gates)},
                    "candidates": list(self.candidates),
                    "blocks": int(self.bs.nb), "samples": int(len(rec.t)),
                    "dt_s": None if static else rec.dt,
                    "rows": None if static else list(rec.rows), "seed": self.seed,
                    "noise_estimate": {k: [float(x) for x in v] for k, v in self.noise.items()
                                       if v is not None},
                    "noise_method": "robust second difference: 1.4826 "
                                    "MAD(x[k+1]-2x[k]+x[k-1])/sqrt(6)",
                    "block_noise": {ch: float(s) for ch, s in zip(CHANNELS, self.fprob.sigma)},
                    "coulomb_velocity": None if static else [
                        float(v) for v in coulomb_velocity(self.arm, self.noise["qd"])],
                    "intervals": "95 %, delta method on the HAC (Newey-West) covariance of the "
                                 "block scores; the union with the intervals of the fit plus "
                                 "each candidate the record holds a hint of (LR p < "
                                 f"{HINT_P}; the fit's own as ci_*_noise); cut at the physical "
                                 "range (raw interval kept)",
                    "bootstrap": self.boot_info,
                    "data": {"kind": data.kind, "experiment": data.experiment,
                             "description": data.meta.get("description", "")}}
        if static:
            settings["rest_points"] = int(rec.m)
            settings["residuals"] = ("rest points (window means): torque balance tau(p, q) = "
                                     "G(q) [N m], static valve 0 = a + b u - kappa p [Pa/s]; "
                                     "angles: quasi-static equilibria of the model")
        late = sum(seconds[s] for s in STAGES[3:])
        timings = {"residuals_and_noise": seconds["design"], "selection": seconds["selection"],
                   "stability_and_bootstrap": seconds["stability"], "gates_and_rollout": late,
                   "total": sum(seconds.values()) + time.perf_counter() - t0}
        extra = {}
        if self.forces is not None:
            extra["forces"] = self.forces
        return Diagnosis(source=data.source, effects=self.effects, partial=self.partial,
                         unexplained=self.unexplained, unexplained_channels=self.bad,
                         residual_rms=self.rr, where=self.where, steps=self.steps,
                         replay={"t": self.t_rep, "measured": self.meas, "before": self.before,
                                 "after": self.after, "static": static,
                                 "channels": REPLAY_CHANNELS, "units": REPLAY_UNITS},
                         settings=settings, timings=timings, notes=tuple(self.notes),
                         blocks={"t": self.bs.features["t"], "before": self.nominal.e,
                                 "after": self.fit.e, "channels": CHANNELS},
                         subsystems=extra, confounded=self.confounded,
                         stability={} if stab is None else stab.to_dict(),
                         detection_limits=self.limits)


def diagnose_arm(data, *, arm=None, candidates=None, block_seconds: float = 0.05,
                 alpha: float = 0.01, rho_max: float = 1.5, experiment: str | None = None,
                 seed: int = 0, bootstrap: int | None = None, stability: int | None = None,
                 detection: bool = True) -> Diagnosis:
    """Diagnose a measured arm record against the model (module docstring).

    The front door :func:`ppamsafety.diagnose.diagnose` validates its arguments and calls
    this for arm records.

    Parameters
    ----------
    data : MeasuredData
        Arm record (:func:`ppamsafety.data.load_measured`): open or closed
        loop with q, qd, p, u; or a static sawtooth (§3.5.1.6) with q, p
        (u and F1..F4 optional), see :mod:`ppamsafety.diagnose.arm.static`.
    arm : ArmParameters, optional, keyword-only
        The model under test, its declared effects included (default the thesis arm).
    candidates : sequence of str, optional, keyword-only
        Library subset (default all registered).
    block_seconds : float, keyword-only
        Block length of the subsystem residuals [s].
    alpha : float, keyword-only
        Level of the likelihood-ratio test (Bonferroni-divided per step).
    rho_max : float, keyword-only
        Largest residual/noise RMS ratio of an explained block channel.
    experiment : str, optional, keyword-only
        Hint for records whose metadata lacks it (must agree when both given).
    seed : int, keyword-only
        Seed of the Monte Carlo noise propagation, the stability selection and the
        bootstrap.
    bootstrap : int, optional, keyword-only
        Replicates of the moving-block bootstrap of the selection
        (:func:`~ppamsafety.diagnose.arm.selection.bootstrap_frequency`); default
        :data:`~ppamsafety.diagnose.arm.selection.BOOTSTRAP_REPLICATES` (0: none).
        Each named effect's evidence then carries ``bootstrap_frequency``.
    stability : int, optional, keyword-only
        Complementary pairs of the stability selection
        (:func:`~ppamsafety.diagnose.arm.selection.stability_selection`); default
        :data:`~ppamsafety.diagnose.arm.selection.STABILITY_PAIRS`; 0: none (then no
        effect can be "high": the stability gate fails).
    detection : bool, keyword-only
        Compute the detection limits of the record (:mod:`.detection`).

    Returns
    -------
    Diagnosis

    """
    return run_steps(ArmSteps(data, arm=arm, candidates=candidates, block_seconds=block_seconds,
                              alpha=alpha, rho_max=rho_max, experiment=experiment, seed=seed,
                              bootstrap=bootstrap, stability=stability, detection=detection))


__all__ = ["diagnose_arm", "ArmSteps", "after_row", "sensor_fault", "REPLAY_CHANNELS", "REPLAY_UNITS"]
