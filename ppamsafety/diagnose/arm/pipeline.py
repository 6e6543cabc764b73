"""The diagnosis of an arm record, :func:`diagnose_arm` (issue 10 items 2-5).

Pipeline for an arm record (open loop, or closed loop with the set values
logged): noise level from the data (:mod:`.noise`), block residuals per
subsystem (:mod:`.residuals`), forward selection over the candidate library
with refit (:mod:`.selection`), then one batched rollout of the nominal
model and of the model after each accepted effect (the gap shrinking, as
RMS per channel and as figures).  The result is a
:class:`~ppamsafety.diagnose.core.result.Diagnosis`.
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
from ...plant import packing
from ..core.result import HIGH_CONFIDENCE, Diagnosis
from .candidates import REGISTRY
from .residuals import (CHANNELS, row_from_mu, CHANNEL_UNITS, SUBSYSTEM, arm_record, block_system,
                        channel_noise, model_vector, noise_draws, replay)
from .selection import (bootstrap_frequency, fit_model, forward_selection, make_problem,
                        parameter_table, BOOTSTRAP_REPLICATES)
from .static import (STATIC_CANDIDATES, force_residuals, static_equilibria, static_floor,
                     static_noise, static_noise_draws, static_record, static_system)

#: Replay channels (full simulation vs measured).
REPLAY_CHANNELS = ("q1", "q2", "qd1", "qd2", "p1", "p2", "p3", "p4")
REPLAY_UNITS = ("rad", "rad", "rad/s", "rad/s", "Pa", "Pa", "Pa", "Pa")


def _where(prob, e, feats, rho_max):
    """Operating regions of significant residual (see :func:`diagnose`)."""
    from scipy import stats


    nb = e.shape[0]
    rows = []
    zcrit = stats.norm.isf(0.0005)
    for c, ch in enumerate(CHANNELS):
        j = 0 if c in (0, 1, 4) else 1
        pch = feats["p"][:, c] if c < 4 else feats["p"][:, 2 * j:2 * j + 2].mean(axis=1)
        groups = {
            "velocity sign": {"qd > 0": feats["qd"][:, j] > 0, "qd < 0": feats["qd"][:, j] <= 0},
            "pressure level": _terciles(pch, "p"),
            "configuration": _terciles(feats["q"][:, j], f"q{j + 1}"),
            "time segment": {f"t {a:.3g}-{b:.3g} s": m for a, b, m in _segments(feats["t"])},
        }
        for region, gs in groups.items():
            for g, m in gs.items():
                n = int(m.sum())
                if n == 0:
                    continue
                mean = float(e[m, c].mean())
                rms = float(np.sqrt(np.mean(e[m, c] ** 2)))
                z = mean * math.sqrt(n)
                rows.append({"channel": ch, "region": region, "group": g, "blocks": n,
                             "mean": mean, "rms": rms, "z": z,
                             "significant": bool(abs(z) > zcrit or rms > rho_max)})
    _ = nb
    return pd.DataFrame(rows)


def _terciles(x, name):
    a, b = np.quantile(x, [1 / 3, 2 / 3])
    return {f"{name} low (< {a:.3g})": x < a, f"{name} mid": (x >= a) & (x < b),
            f"{name} high (>= {b:.3g})": x >= b}


def _segments(t, n=8):
    edges = np.linspace(t.min(), t.max() + 1e-12, n + 1)
    return [(edges[i], edges[i + 1], (t >= edges[i]) & (t < edges[i + 1])) for i in range(n)]


def after_row(arm, fit, params) -> np.ndarray:
    """The plant row of the model with every fitted effect (for the "after" rollout).

    Effects that are directions of the model vector are written back with
    :func:`~ppamsafety.diagnose.residuals.row_from_mu`; effects with their
    own regression columns (hysteresis) through their ``plant_effect``
    (:class:`~ppamsafety.params.effects.Effects` overrides, e.g. the fitted
    delta, clipped to the plant's range [0, 1]).

    Parameters
    ----------
    arm : ArmParameters
        The nominal model.
    fit : ppamsafety.diagnose.selection.Fit
        The final fit.
    params : dict
        :func:`~ppamsafety.diagnose.selection.parameter_table` of ``fit``.

    Returns
    -------
    numpy.ndarray, shape (NP,)
    """

    over = {}
    for n in fit.names:
        c = REGISTRY[n]
        if c.columns is not None and c.plant_effect is not None:
            vals = np.array([p["value"] for p in params[n].values()])
            over.update(c.plant_effect(vals, arm))
    if "hysteresis_delta" in over and over["hysteresis_delta"][0] <= 0.0:
        over.pop("hysteresis_delta")
    base = arm.replace(effects=replace(arm.effects, **over)) if over else arm
    return row_from_mu(packing.pack(base), fit.mu)


def diagnose_arm(data, *, arm=None, candidates=None, block_seconds: float = 0.05,
             alpha: float = 0.01, rho_max: float = 1.5, experiment: str | None = None,
             seed: int = 0, bootstrap: int | None = None) -> Diagnosis:
    """Diagnose a measured arm record against the model (module docstring).

    The front door :func:`ppamsafety.diagnose.diagnose` validates its arguments and calls
    this for arm records.

    Parameters
    ----------
    data : MeasuredData
        Arm record (:func:`ppamsafety.data.load_measured`): open or closed
        loop with q, qd, p, u; or a static sawtooth (§3.5.1.6) with q, p
        (u and F1..F4 optional), see :mod:`ppamsafety.diagnose.static`.
    arm : ArmParameters, optional, keyword-only
        The current model (default the thesis arm).
    candidates : sequence of str, optional, keyword-only
        Library subset (default all registered).
    block_seconds : float, keyword-only
        Block length of the subsystem residuals [s].
    alpha : float, keyword-only
        Level of the likelihood-ratio test (Bonferroni-divided per step).
    rho_max : float, keyword-only
        Largest residual/noise RMS ratio of an explained channel.
    experiment : str, optional, keyword-only
        Hint for records whose metadata lacks it (must agree when both given).
    seed : int, keyword-only
        Seed of the Monte Carlo noise propagation and of the bootstrap.
    bootstrap : int, optional, keyword-only
        Replicates of the moving-block bootstrap of the selection
        (:func:`~ppamsafety.diagnose.selection.bootstrap_frequency`); default
        :data:`~ppamsafety.diagnose.selection.BOOTSTRAP_REPLICATES`, 0: none.
        Each named effect's evidence then carries ``bootstrap_frequency``.

    Returns
    -------
    Diagnosis

    """
    t0 = time.perf_counter()
    arm = thesis_arm() if arm is None else arm
    if not isinstance(arm, ArmParameters):
        raise TypeError(f"arm must be an ArmParameters, got {type(arm).__name__}")
    check_range("alpha", alpha, 0.0, 0.5, lo_open=True)
    check_range("rho_max", rho_max, 1.0, 100.0)
    seed = check_seed("seed", seed)
    if experiment is not None and experiment != data.experiment:
        raise ValueError(f"experiment = {experiment!r} does not match the record's metadata "
                         f"experiment = {data.experiment!r}")

    bootstrap = BOOTSTRAP_REPLICATES if bootstrap is None else check_int("bootstrap", bootstrap,
                                                                         0, 10000)
    static = data.experiment == "static-sawtooth"
    row0 = packing.pack(arm)
    mu0 = model_vector(row0)
    if static:
        rec, notes = static_record(data)
        noise = static_noise(rec)
        bs = static_system(rec, arm)
        prob = make_problem(bs, mu0, static_noise_draws(rec, arm, noise, seed=seed), arm,
                            floor=static_floor(rec, arm))
        if candidates is None:
            candidates = [c for c in STATIC_CANDIDATES if c in REGISTRY
                          and (c != "valve_offset_gain" or rec.u is not None)]
    else:
        rec, notes = arm_record(data)
        noise = channel_noise(rec)
        bs = block_system(rec, arm, block_seconds=block_seconds)
        prob = make_problem(bs, mu0, noise_draws(rec, arm, noise, block_seconds=block_seconds,
                                                 seed=seed), arm)
    notes = list(data.notes) + notes
    t1 = time.perf_counter()
    nominal = fit_model(prob, [])
    fit, steps, fprob = forward_selection(prob, candidates, alpha=alpha)
    t2 = time.perf_counter()
    freq, boot_info = ({}, {})
    if bootstrap:
        freq, boot_info = bootstrap_frequency(prob, candidates, replicates=bootstrap, seed=seed,
                                              alpha=alpha)
    tb = time.perf_counter()
    rho = fit.rho()
    params = parameter_table(fprob, fit) if fit.names else {}
    effects, partial = [], []
    for s in steps:
        if s.chosen is None:
            continue
        r = next(x for x in s.table if x["name"] == s.chosen)
        sub = REGISTRY[s.chosen].subsystem
        sub_rho = {CHANNELS[c]: float(rho[c]) for c in SUBSYSTEM[sub]}
        ev = {k: r[k] for k in ("delta_bic", "lr_stat", "lr_df", "p_value", "cv_gain")}
        ev["evidence_ratio_log10"] = r.get("evidence_ratio_log10")
        ev["subsystem_rho"] = sub_rho
        if bootstrap:
            ev["bootstrap_frequency"] = freq.get(s.chosen, 0.0)
        entry = {"name": s.chosen, "subsystem": sub, "parameters": params[s.chosen],
                 "evidence": ev, "confidence": r["bic_weight"]}
        (effects if max(sub_rho.values()) <= rho_max else partial).append(entry)
    if static and rec.u is None:
        rho[:4] = 0.0                       # no valve equations without set values
    bad = [CHANNELS[c] for c in range(6) if rho[c] > rho_max]
    row_after = after_row(arm, fit, params)
    rr = {}
    forces = None
    if static:
        Q, Pm = static_equilibria(rec, np.array([row0, row_after]))
        qm, pm = rec.means(rec.q), rec.means(rec.p)
        meas = np.concatenate([qm, np.zeros_like(qm), pm], axis=1)
        before = np.concatenate([Q[0], np.zeros_like(qm), Pm[0]], axis=1)
        after = np.concatenate([Q[1], np.zeros_like(qm), Pm[1]], axis=1)
        t_rep = bs.features["t"]
        sig_replay = np.concatenate([noise["q"], np.zeros(2), noise["p"]])
        delta = params.get("hysteresis", {}).get("delta", {}).get("value", 0.0)
        forces = force_residuals(rec, arm, noise, delta=max(delta, 0.0))
        if forces is not None:
            for k in range(4):
                rr[f"F{k + 1}"] = {"unit": "N", "before": float(np.sqrt(np.mean(
                    forces["residual_before"][:, k] ** 2))), "after": float(np.sqrt(np.mean(
                        forces["residual_after"][:, k] ** 2))), "noise": float(forces["sigma"][k])}
    else:
        try:
            X = replay(rec, np.array([row0, row_after]), shifts=[0, fit.shift])
            before, after = X[0], X[1]
        except ValueError as exc:
            # a model with every fitted effect (partial ones too: e.g. a negative payload
            # absorbing an error outside the library) may leave the model's valid range
            X = replay(rec, np.array([row0]), shifts=[0])
            before, after = X[0], X[0]
            notes.append(f"the model with every fitted effect could not be simulated ({exc}); "
                         f"'after' repeats 'before'")
        meas = np.concatenate([rec.q, rec.qd, rec.p], axis=1)
        t_rep = rec.t
        sig_replay = np.concatenate([noise["q"], noise["qd"], noise["p"]])
    t3 = time.perf_counter()
    for k, ch in enumerate(REPLAY_CHANNELS):
        if static and ch in ("qd1", "qd2"):
            continue
        rr[ch] = {"unit": REPLAY_UNITS[k],
                  "before": float(np.sqrt(np.mean((before[:, k] - meas[:, k]) ** 2))),
                  "after": float(np.sqrt(np.mean((after[:, k] - meas[:, k]) ** 2))),
                  "noise": float(sig_replay[k])}
    nrho = nominal.rho()
    units = ("Pa/s",) * 4 + ("N m",) * 2 if static else CHANNEL_UNITS
    for c, ch in enumerate(CHANNELS):
        if static and c < 4 and rec.u is None:
            continue
        rr[f"block_{ch}"] = {"unit": f"{units[c]} / noise (block residual ratio)",
                             "before": float(nrho[c]), "after": float(rho[c]), "noise": 1.0}
    unexplained = bool(bad)
    for e in effects:
        # "high" needs a decisive weight, a record explained everywhere (an unexplained
        # error elsewhere may leak into this subsystem) and a parameter interval that
        # excludes the nominal value
        moved = any(not (p["ci_low"] <= p["nominal"] <= p["ci_high"])
                    for p in e["parameters"].values()) or e["name"] == "valve_dead_time"
        named_ok = e["confidence"] >= HIGH_CONFIDENCE and not unexplained and moved
        e["confidence_level"] = "high" if named_ok else "low"
    for e in partial:
        e["confidence_level"] = "low"
    where = _where(fprob, fit.e, bs.features, rho_max)
    if static:
        where["region"] = where["region"].replace({"velocity sign": "direction of approach"})
        where["group"] = where["group"].str.replace("qd > 0", "angle rose").str.replace(
            "qd < 0", "angle fell or held")
    if unexplained:
        notes.append(f"residual above {rho_max} x the noise on {', '.join(bad)}: no effect of "
                     f"the library explains it (see 'where')")
    settings = {"block_seconds": None if static else block_seconds, "alpha": alpha,
                "rho_max": rho_max,
                "criterion": "BIC (known noise level), LR test p < alpha/K, 2-fold CV gain, "
                             "parameters inside widened bounds",
                "high_confidence": HIGH_CONFIDENCE, "candidates": list(
                    REGISTRY if candidates is None else candidates),
                "blocks": int(bs.nb), "samples": int(len(rec.t)),
                "dt_s": None if static else rec.dt,
                "rows": None if static else list(rec.rows), "seed": seed,
                "noise_estimate": {k: [float(x) for x in v] for k, v in noise.items()
                                   if v is not None},
                "noise_method": "robust second difference: 1.4826 MAD(x[k+1]-2x[k]+x[k-1])/sqrt(6)",
                "block_noise": {ch: float(s) for ch, s in zip(CHANNELS, fprob.sigma)},
                "bootstrap": boot_info,
                "data": {"kind": data.kind, "experiment": data.experiment,
                         "description": data.meta.get("description", "")}}
    if static:
        settings["rest_points"] = int(rec.m)
        settings["residuals"] = ("rest points (window means): torque balance tau(p, q) = G(q) "
                                 "[N m], static valve 0 = a + b u - kappa p [Pa/s]; angles: "
                                 "quasi-static equilibria of the model")
    timings = {"residuals_and_noise": t1 - t0, "selection": t2 - t1, "bootstrap": tb - t2,
               "rollout": t3 - tb, "total": time.perf_counter() - t0}
    extra = {}
    if forces is not None:
        extra["forces"] = forces
    return Diagnosis(source=data.source, effects=effects, partial=partial,
                     unexplained=unexplained, unexplained_channels=bad, residual_rms=rr,
                     where=where, steps=steps,
                     replay={"t": t_rep, "measured": meas, "before": before, "after": after,
                             "static": static, "channels": REPLAY_CHANNELS,
                             "units": REPLAY_UNITS},
                     settings=settings, timings=timings, notes=tuple(notes),
                     blocks={"t": bs.features["t"], "before": nominal.e, "after": fit.e,
                             "channels": CHANNELS},
                     subsystems=extra)


__all__ = ["diagnose_arm", "after_row", "REPLAY_CHANNELS", "REPLAY_UNITS"]
