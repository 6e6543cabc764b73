""":func:`diagnose` and its result, :class:`Diagnosis` (issue 10 items 2-5).

Pipeline for an arm record (open loop, or closed loop with the set values
logged): noise level from the data (:mod:`.noise`), block residuals per
subsystem (:mod:`.residuals`), forward selection over the candidate library
with refit (:mod:`.selection`), then one batched rollout of the nominal
model and of the model after each accepted effect (the gap shrinking, as
RMS per channel and as figures).  The JSON schema written by
:meth:`Diagnosis.write` is documented in ``docs/diagnose.md``.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .._validation import check_bool, check_int, check_range

#: Schema version of ``diagnosis.json``.
SCHEMA_VERSION = 1
JSON_NAME, MD_NAME = "diagnosis.json", "diagnosis.md"
FIG_REPLAY, FIG_BLOCKS = "diagnosis_replay.png", "diagnosis_blocks.png"
#: BIC weight at or above which a named effect is reported with confidence "high".
HIGH_CONFIDENCE = 0.95
#: Replay channels (full simulation vs measured).
REPLAY_CHANNELS = ("q1", "q2", "qd1", "qd2", "p1", "p2", "p3", "p4")
REPLAY_UNITS = ("rad", "rad", "rad/s", "rad/s", "Pa", "Pa", "Pa", "Pa")


def _num(x):
    x = float(x)
    return x if math.isfinite(x) else None


def _clean(obj):
    """JSON-safe copy (numpy scalars to Python, non-finite to None)."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return _num(obj)
    return obj


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """Result of :func:`diagnose`.

    Attributes
    ----------
    source : str
        The record diagnosed.
    effects : list of dict
        Named effects in the order found: ``name``, ``parameters``
        ({name: {value, unit, ci_low, ci_high, std_error, nominal}}),
        ``evidence`` (delta_bic, lr_stat, lr_df, p_value, cv_gain,
        evidence_ratio_log10, subsystem_rho), ``confidence`` (BIC weight) and
        ``confidence_level`` ("high"/"low").
    partial : list of dict
        Significant effects that did not bring their subsystem down to the
        noise: fitted, reported, **not named**.
    unexplained : bool
        True if some channel's residual stays above ``rho_max`` x its noise.
    unexplained_channels : list of str
    residual_rms : dict
        Per channel (replay q, qd, p and block p, tau): before, after, noise, unit.
    where : pandas.DataFrame
        Operating regions where the final block residual is significant.
    steps : list
        :class:`~ppamsafety.diagnose.selection.Step` rankings.
    replay : dict
        ``t``, ``measured``, ``before``, ``after`` arrays (N, 8) for the figures.
    settings : dict
    timings : dict
        Wall times [s] of the stages.
    notes : tuple of str
    blocks : dict
        ``t`` and whitened block residuals ``before``/``after`` (nb, 6) for the figures.
    kind : str
        ``"arm"`` or ``"actuator"`` (a test-bench record,
        :mod:`ppamsafety.diagnose.actuator`: ``replay`` then holds ``t``,
        ``eps``, ``pressure``, ``direction`` and the forces ``measured``,
        ``before`` (nominal law), ``after`` (diagnosed), each (N,)).
    subsystems : dict
        Extra subsystem checks: ``"forces"`` (static records with F1..F4,
        :func:`ppamsafety.diagnose.static.force_residuals`).
    """

    source: str
    effects: list
    partial: list
    unexplained: bool
    unexplained_channels: list
    residual_rms: dict
    where: pd.DataFrame = field(repr=False)
    steps: list = field(repr=False)
    replay: dict = field(repr=False)
    settings: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    notes: tuple = ()
    blocks: dict = field(default_factory=dict, repr=False)
    kind: str = "arm"
    subsystems: dict = field(default_factory=dict, repr=False)

    @property
    def names(self) -> tuple:
        """Names of the named effects, in order."""
        return tuple(e["name"] for e in self.effects)

    def to_pandas(self) -> pd.DataFrame:
        """One row per (effect, parameter) of named and partial effects."""
        rows = []
        for status, lst in (("named", self.effects), ("partial", self.partial)):
            for e in lst:
                for pn, p in e["parameters"].items():
                    rows.append({"effect": e["name"], "status": status, "parameter": pn, **p,
                                 "confidence": e["confidence"]})
        cols = ["effect", "status", "parameter", "value", "unit", "ci_low", "ci_high",
                "std_error", "nominal", "confidence"]
        return pd.DataFrame(rows, columns=cols)

    def ranking(self) -> pd.DataFrame:
        """Every candidate tried at every step (criterion, tests, eligibility)."""
        rows = []
        for i, s in enumerate(self.steps):
            for r in s.table:
                rows.append({"step": i + 1, "model": "+".join(s.current) or "nominal", **r,
                             "chosen": r["name"] == s.chosen})
        return pd.DataFrame(rows)

    def to_dict(self) -> dict:
        """The ``diagnosis.json`` content (schema in ``docs/diagnose.md``)."""
        from .. import __version__

        def eff(e):
            return {k: e[k] for k in ("name", "parameters", "evidence", "confidence",
                                      "confidence_level", "subsystem")}

        return _clean({
            "schema_version": SCHEMA_VERSION, "tool": "ppamsafety", "version": __version__,
            "source": self.source, "kind": self.kind,
            "effects": [eff(e) for e in self.effects],
            "partial": [eff(e) for e in self.partial],
            "unexplained": self.unexplained,
            "unexplained_channels": self.unexplained_channels,
            "residual_rms": self.residual_rms,
            "where": self.where.to_dict(orient="records"),
            "ranking": self.ranking().to_dict(orient="records"),
            "forces": self._forces_dict(),
            "settings": self.settings, "timings_s": self.timings, "notes": list(self.notes)})

    def _forces_dict(self):
        f = self.subsystems.get("forces")
        if f is None:
            return None
        return {"unit": "N", "muscles": ["F1", "F2", "F3", "F4"],
                "noise_of_rest_point_mean": list(f["sigma"]),
                "rho_before": list(f["rho_before"]), "rho_after": list(f["rho_after"]),
                "delta_forces": f["delta_forces"], "delta_forces_std_error": f["delta_forces_se"],
                "delta_per_muscle": list(f["delta_per_muscle"])}

    def plot(self):
        """Measured vs before vs after (full simulation) for q, qd, p; a matplotlib Figure.

        For an actuator record: measured, nominal and diagnosed force against
        the contraction (the loops) and against time.
        """
        if self.kind == "actuator":
            from ..report.diagnose_figures import actuator_force_figure

            return actuator_force_figure(self)
        from matplotlib.figure import Figure

        r = self.replay
        t = r["t"]
        step = max(1, t.size // 4000)
        fig = Figure(figsize=(11, 9), layout="constrained")
        axs = fig.subplots(4, 2, sharex=True)
        for k, ax in enumerate(axs.T.ravel()):
            scale = 1e-5 if REPLAY_UNITS[k] == "Pa" else 1.0
            unit = "bar" if REPLAY_UNITS[k] == "Pa" else REPLAY_UNITS[k]
            mk = dict(marker="o", ms=3, ls="none") if r.get("static") else {}
            ax.plot(t[::step], r["measured"][::step, k] * scale, color="0.6", lw=0.8,
                    label="measured", **mk)
            ax.plot(t[::step], r["before"][::step, k] * scale, "C3", lw=0.9,
                    label="model before", **(dict(mk, marker="s", mfc="none") if mk else {}))
            ax.plot(t[::step], r["after"][::step, k] * scale, color="C0", lw=0.9,
                    label="model after", **(dict(mk, marker="x") if mk else {"ls": "--"}))
            rr = self.residual_rms.get(REPLAY_CHANNELS[k])
            if rr is not None:
                ax.set_title(f"{REPLAY_CHANNELS[k]}: RMS error {rr['before']:.3g} -> "
                             f"{rr['after']:.3g} {REPLAY_UNITS[k]}", fontsize=8)
            ax.set_ylabel(f"{REPLAY_CHANNELS[k]} [{unit}]", fontsize=8)
        axs[0, 0].legend(fontsize=7)
        axs[-1, 0].set_xlabel("t [s]")
        axs[-1, 1].set_xlabel("t [s]")
        found = ", ".join(self.names) or "nothing named"
        fig.suptitle(f"{self.source}: {found}" + ("; UNEXPLAINED residual remains"
                                                  if self.unexplained else ""), fontsize=9)
        return fig

    def plot_blocks(self):
        """Whitened block residuals per subsystem channel, before and after; a Figure."""
        if self.kind == "actuator":
            from ..report.diagnose_figures import actuator_residual_figure

            return actuator_residual_figure(self)
        from matplotlib.figure import Figure

        from .residuals import CHANNELS

        b = self.blocks
        fig = Figure(figsize=(11, 7), layout="constrained")
        axs = fig.subplots(3, 2, sharex=True)
        for c, ax in enumerate(axs.T.ravel()):
            ax.plot(b["t"], b["before"][:, c], ".", ms=2, color="C3", label="before")
            ax.plot(b["t"], b["after"][:, c], ".", ms=2, color="C0", label="after")
            ax.axhspan(-2, 2, color="0.9", zorder=0)
            ax.set_ylabel(f"{CHANNELS[c]} / noise", fontsize=8)
        axs[0, 0].legend(fontsize=7)
        fig.suptitle("block residuals divided by their noise level (grey band: +-2)", fontsize=9)
        return fig

    def report_markdown(self) -> str:
        """The readable report (Markdown) that :meth:`write` saves as ``diagnosis.md``."""
        L = [f"# Diagnosis of `{self.source}`", ""]
        if self.effects:
            L.append("Named effects, in the order found:")
            L.append("")
            for e in self.effects:
                L.append(f"* **{e['name']}** (confidence {e['confidence']:.3f}, "
                         f"{e['confidence_level']}; Delta BIC "
                         f"{e['evidence']['delta_bic']:.1f}, p = "
                         f"{e['evidence']['p_value']:.2g})")
                for pn, p in e["parameters"].items():
                    L.append(f"    * {pn} = {p['value']:.5g} {p['unit']} "
                             f"[{p['ci_low']:.5g}, {p['ci_high']:.5g}] (nominal "
                             f"{p['nominal']:.5g})")
        else:
            L.append("No effect is named.")
        if self.partial:
            L += ["", "Significant but not named (their subsystem stays above the noise):"]
            L += [f"* {e['name']}" for e in self.partial]
        L += ["", f"**Unexplained:** {'yes' if self.unexplained else 'no'}"
              + (f" (channels {', '.join(self.unexplained_channels)})"
                 if self.unexplained else ""), ""]
        L += ["## Residual RMS per channel", "", "| channel | unit | before | after | noise |",
              "|---|---|---|---|---|"]
        for ch, r in self.residual_rms.items():
            L.append(f"| {ch} | {r['unit']} | {r['before']:.4g} | {r['after']:.4g} | "
                     f"{r['noise']:.4g} |")
        L += ["", f"![measured vs before vs after]({FIG_REPLAY})", "",
              f"![block residuals]({FIG_BLOCKS})", "", "## Ranking", ""]
        rk = self.ranking()
        if len(rk):
            cols = ["step", "model", "name", "k", "delta_bic", "p_value", "cv_gain",
                    "bic_weight", "in_bounds", "eligible", "chosen"]
            L.append(_md_table(rk[cols]))
        sig = self.where[self.where["significant"]] if len(self.where) else self.where
        L += ["", "## Where the final residual is significant", ""]
        L.append(_md_table(sig) if len(sig) else "Nowhere.")
        L += ["", "## Settings", "", "```", json.dumps(_clean(self.settings), indent=1), "```"]
        if self.notes:
            L += ["", "## Notes", ""] + [f"* {n}" for n in self.notes]
        return "\n".join(L) + "\n"

    def write(self, outdir, *, overwrite: bool = False) -> list:
        """Write ``diagnosis.json``, ``diagnosis.md`` and the figures into ``outdir``.

        Through :class:`ppamsafety.output.OutputFolder` (kind ``"diagnose"``).

        Parameters
        ----------
        outdir : path-like
            Output folder (created if missing).
        overwrite : bool, keyword-only
            Replace a previous ppamsafety diagnosis in ``outdir``.

        Returns
        -------
        list of pathlib.Path
        """
        from ..output import OutputFolder

        check_bool("overwrite", overwrite)
        text = json.dumps(self.to_dict(), indent=1, allow_nan=False, ensure_ascii=False) + "\n"
        md = self.report_markdown()
        figs = {FIG_REPLAY: self.plot(), FIG_BLOCKS: self.plot_blocks()}
        folder = OutputFolder(outdir, kind="diagnose", overwrite=overwrite)
        with folder as st:
            (st / JSON_NAME).write_text(text, encoding="utf-8")
            (st / MD_NAME).write_text(md, encoding="utf-8")
            for name, fig in figs.items():
                fig.savefig(st / name, dpi=100)
        return [folder.path / f for f in folder.written]


def _md_table(df: pd.DataFrame) -> str:
    """A pandas frame as a Markdown table (numbers to 4 significant digits)."""
    def cell(v):
        if isinstance(v, (float, np.floating)):
            return f"{v:.4g}"
        return str(v)
    head = "| " + " | ".join(map(str, df.columns)) + " |"
    rule = "|" + "---|" * len(df.columns)
    body = ["| " + " | ".join(cell(v) for v in row) + " |" for row in df.itertuples(index=False)]
    return "\n".join([head, rule] + body)


def _where(prob, e, feats, rho_max):
    """Operating regions of significant residual (see :func:`diagnose`)."""
    from scipy import stats

    from .residuals import CHANNELS

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
    from dataclasses import replace

    from ..plant import layout as lay
    from .candidates import REGISTRY
    from .residuals import row_from_mu

    over = {}
    for n in fit.names:
        c = REGISTRY[n]
        if c.columns is not None and c.plant_effect is not None:
            vals = np.array([p["value"] for p in params[n].values()])
            over.update(c.plant_effect(vals, arm))
    if "hysteresis_delta" in over and over["hysteresis_delta"][0] <= 0.0:
        over.pop("hysteresis_delta")
    base = arm.replace(effects=replace(arm.effects, **over)) if over else arm
    return row_from_mu(lay.pack(base), fit.mu)


def diagnose(data, *, arm=None, candidates=None, block_seconds: float = 0.05,
             alpha: float = 0.01, rho_max: float = 1.5, experiment: str | None = None,
             seed: int = 0, bootstrap: int | None = None) -> Diagnosis:
    """Diagnose a measured arm record against the model (module docstring).

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

    Notes
    -----
    An actuator record (``data.kind == "actuator"``, a test bench) is
    diagnosed against its nominal force law by
    :func:`ppamsafety.diagnose.actuator.diagnose_actuator` (``arm``,
    ``block_seconds``, ``seed`` and ``bootstrap`` do not apply; its confidence
    is the BIC weight; ``candidates`` from the tester vocabulary).
    """
    from ..data.measured import MeasuredData

    if isinstance(data, MeasuredData) and data.kind == "actuator":
        from .actuator import diagnose_actuator

        return diagnose_actuator(data, candidates=candidates, alpha=alpha, rho_max=rho_max,
                                 experiment=experiment)
    from ..params import thesis_arm
    from ..params.arm import ArmParameters
    from ..plant import layout as lay
    from .candidates import REGISTRY
    from .residuals import (CHANNEL_UNITS, CHANNELS, SUBSYSTEM, arm_record, block_system,
                            channel_noise, model_vector, noise_draws, replay)
    from .selection import (bootstrap_frequency, fit_model, forward_selection, make_problem,
                            parameter_table)

    t0 = time.perf_counter()
    arm = thesis_arm() if arm is None else arm
    if not isinstance(arm, ArmParameters):
        raise TypeError(f"arm must be an ArmParameters, got {type(arm).__name__}")
    check_range("alpha", alpha, 0.0, 0.5, lo_open=True)
    check_range("rho_max", rho_max, 1.0, 100.0)
    if experiment is not None and experiment != data.experiment:
        raise ValueError(f"experiment = {experiment!r} does not match the record's metadata "
                         f"experiment = {data.experiment!r}")
    from .selection import BOOTSTRAP_REPLICATES

    bootstrap = BOOTSTRAP_REPLICATES if bootstrap is None else check_int("bootstrap", bootstrap,
                                                                         0, 10000)
    static = data.experiment == "static-sawtooth"
    row0 = lay.pack(arm)
    mu0 = model_vector(row0)
    if static:
        from .static import (STATIC_CANDIDATES, force_residuals, static_equilibria,
                             static_floor, static_noise, static_noise_draws, static_record,
                             static_system)

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
                             "static": static},
                     settings=settings, timings=timings, notes=tuple(notes),
                     blocks={"t": bs.features["t"], "before": nominal.e, "after": fit.e},
                     subsystems=extra)


__all__ = ["Diagnosis", "diagnose", "SCHEMA_VERSION", "HIGH_CONFIDENCE", "JSON_NAME"]
