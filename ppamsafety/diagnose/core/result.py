"""The result of a diagnosis, :class:`Diagnosis`, for every record kind.

The arm pipeline (:mod:`ppamsafety.diagnose.arm.pipeline`) and the test-bench
pipeline (:mod:`ppamsafety.diagnose.bench.pipeline`) both return one.  The JSON
schema written by :meth:`Diagnosis.write` is documented in ``docs/diagnose.md``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..._validation import check_bool
from ..._version import __version__
from ...output import OutputFolder
from ...plots.diagnose import (actuator_force_figure, actuator_residual_figure, arm_blocks_figure,
                               arm_replay_figure)

#: Schema version of ``diagnosis.json``.
SCHEMA_VERSION = 1
JSON_NAME, MD_NAME = "diagnosis.json", "diagnosis.md"
FIG_REPLAY, FIG_BLOCKS = "diagnosis_replay.png", "diagnosis_blocks.png"


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
    """Result of :func:`ppamsafety.diagnose.diagnose`.

    Attributes
    ----------
    source : str
        The record diagnosed.
    effects : list of dict
        Named effects in the order found: ``name``, ``parameters``
        ({name: {value, unit, ci_low, ci_high, std_error, nominal, ci_low_noise,
        ci_high_noise, widened_by}}: the reported 95 % interval, the fit's own, and the
        candidates that widened it, :mod:`.omitted`),
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
        :class:`~ppamsafety.diagnose.core.criteria.Step` rankings.
    replay : dict
        ``t``, ``measured``, ``before``, ``after`` arrays (N, 8) for the figures,
        with their ``channels`` and ``units``.
    settings : dict
    timings : dict
        Wall times [s] of the stages.
    notes : tuple of str
    blocks : dict
        ``t`` and whitened block residuals ``before``/``after`` (nb, 6) for the figures,
        with their ``channels``.
    kind : str
        ``"arm"`` or ``"actuator"`` (a test-bench record,
        :mod:`ppamsafety.diagnose.bench.pipeline`: ``replay`` then holds ``t``,
        ``eps``, ``pressure``, ``direction`` and the forces ``measured``,
        ``before`` (nominal law), ``after`` (diagnosed), each (N,)).
    subsystems : dict
        Extra subsystem checks: ``"forces"`` (static records with F1..F4,
        :func:`ppamsafety.diagnose.arm.static.force_residuals`).
    confounded : list of dict
        Groups of candidates the record cannot tell apart (each explains the same part of
        the residual): ``members``, ``interpretations`` (member -> its parameters if it
        were the cause), ``evidence``, ``separating_experiment``.  Never named.
    stability : dict
        The stability selection (``diagnosis.json`` key ``stability``: pairs, threshold,
        frequencies and the bound on the expected number of false selections); empty
        when it was not run.
    detection_limits : dict
        Per candidate and parameter, the smallest change this record would detect
        (:mod:`ppamsafety.diagnose.arm.detection`); empty when not computed.
    warnings : tuple of str
        What a reader must know before reading the names (a record diagnosed on purpose
        against another arm than the one it came from); first in ``diagnosis.md`` and in
        the command's summary.
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
    confounded: list = field(default_factory=list)
    stability: dict = field(default_factory=dict, repr=False)
    detection_limits: dict = field(default_factory=dict, repr=False)
    warnings: tuple = ()

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
                                 "widened_by": ", ".join(p["widened_by"]),
                                 "confidence": e["confidence"]})
        cols = ["effect", "status", "parameter", "value", "unit", "ci_low", "ci_high",
                "ci_low_noise", "ci_high_noise", "widened_by", "std_error", "nominal",
                "confidence"]
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
        def eff(e):
            return {k: e[k] for k in ("name", "parameters", "evidence", "confidence",
                                      "confidence_level", "subsystem", "gates") if k in e}

        return _clean({
            "schema_version": SCHEMA_VERSION, "tool": "ppamsafety", "version": __version__,
            "source": self.source, "kind": self.kind, "warnings": list(self.warnings),
            "effects": [eff(e) for e in self.effects],
            "partial": [eff(e) for e in self.partial],
            "unexplained": self.unexplained,
            "unexplained_channels": self.unexplained_channels,
            "residual_rms": self.residual_rms,
            "where": self.where.to_dict(orient="records"),
            "ranking": self.ranking().to_dict(orient="records"),
            "forces": self._forces_dict(),
            "confounded": self.confounded,
            "stability": self.stability or None,
            "detection_limits": self.detection_limits or None,
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
            return actuator_force_figure(self)
        return arm_replay_figure(self)

    def plot_blocks(self):
        """Whitened block residuals per subsystem channel, before and after; a Figure."""
        if self.kind == "actuator":
            return actuator_residual_figure(self)
        return arm_blocks_figure(self)

    def report_markdown(self) -> str:
        """The readable report (Markdown) that :meth:`write` saves as ``diagnosis.md``."""
        L = [f"# Diagnosis of `{self.source}`", ""]
        for w in self.warnings:
            L += [f"> **Warning:** {w}", ""]
        if self.effects:
            L.append("Named effects, in the order found:")
            L.append("")
            for e in self.effects:
                failed = [g for g, ok in e.get("gates", {}).items() if not ok]
                why = (f" (gates not passed: {', '.join(failed)})"
                       if e["confidence_level"] != "high" and failed else "")
                L.append(f"* **{e['name']}** (inclusion probability {e['confidence']:.3f}; "
                         f"confidence {e['confidence_level']}{why}; Delta BIC "
                         f"{e['evidence']['delta_bic']:.1f}, p = "
                         f"{e['evidence']['p_value']:.2g})")
                for pn, p in e["parameters"].items():
                    wide = (f"; widened for {', '.join(p['widened_by'])}, the fit's own "
                            f"[{p['ci_low_noise']:.5g}, {p['ci_high_noise']:.5g}]"
                            if p["widened_by"] else "")
                    L.append(f"    * {pn} = {p['value']:.5g} {p['unit']} "
                             f"[{p['ci_low']:.5g}, {p['ci_high']:.5g}] (nominal "
                             f"{p['nominal']:.5g}{wide})")
        else:
            L.append("No effect is named.")
        if self.partial:
            L += ["", "Significant but not named (their subsystem stays above the noise):"]
            L += [f"* {e['name']}" for e in self.partial]
        if self.confounded:
            L += ["", "Confounded (not named: this record cannot tell them apart):", ""]
            for g in self.confounded:
                L.append(f"* {' / '.join(g['members'])}: {g['separating_experiment']}")
        if self.detection_limits and not self.effects:
            L += ["", "Nothing is named.  Smallest changes this record would have detected "
                      "(90 % power):", ""]
            for n, ps in self.detection_limits.items():
                L.append(f"* {n}: " + "; ".join(f"{k} {v['limit']:.3g} {v['unit']}"
                                                 for k, v in ps.items()))
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

    def write(self, outdir, *, overwrite: bool = False, replace_kind: bool = False) -> list:
        """Write ``diagnosis.json``, ``diagnosis.md`` and the figures into ``outdir``.

        Through :class:`ppamsafety.output.OutputFolder` (kind ``"diagnose"``).

        Parameters
        ----------
        outdir : path-like
            Output folder (created if missing).
        overwrite : bool, keyword-only
            Replace a previous ppamsafety diagnosis in ``outdir``.
        replace_kind : bool, keyword-only
            Allow replacing a previous ppamsafety output of another kind (refused by
            default, even with ``overwrite``).

        Returns
        -------
        list of pathlib.Path
        """
        check_bool("overwrite", overwrite)
        check_bool("replace_kind", replace_kind)
        text = json.dumps(self.to_dict(), indent=1, allow_nan=False, ensure_ascii=False) + "\n"
        md = self.report_markdown()
        figs = {FIG_REPLAY: self.plot(), FIG_BLOCKS: self.plot_blocks()}
        folder = OutputFolder(outdir, kind="diagnose", overwrite=overwrite,
                              replace_kind=replace_kind)
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


__all__ = ["Diagnosis", "SCHEMA_VERSION", "JSON_NAME", "MD_NAME"]
