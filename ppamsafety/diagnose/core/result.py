"""The result of a diagnosis, :class:`Diagnosis`, for every record kind.

The arm pipeline (:mod:`ppamsafety.diagnose.arm.pipeline`) and the test-bench
pipeline (:mod:`ppamsafety.diagnose.bench.pipeline`) both return one.  The JSON
schema written by :meth:`Diagnosis.write` is documented in ``docs/diagnose.md``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from ..._validation import check_bool
from ..._version import __version__
from ...output import OutputFolder
from ...results import Result
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


@dataclass(frozen=True)
class Estimate:
    """A fitted parameter of a named effect: value, SI unit and reported 95 % interval.

    Attributes
    ----------
    value : float
        The estimate, in ``unit``.
    unit : str
        SI unit (``"-"`` for a dimensionless one).
    ci_low, ci_high : float
        The reported 95 % interval (NaN for a setting the fit does not estimate, e.g. the
        number of knots of a profile).
    std_error : float
        Its standard error.
    nominal : float
        The value of the model under test (the change is ``value - nominal``).
    note : str, optional
        What the number is when it is derived from another (a look-alike's reading).
    ci_low_noise, ci_high_noise : float, optional
        The fit's own interval when the reported one was widened for omitted candidates
        (:mod:`.omitted`); None when the interval was not widened.
    widened_by : tuple of str, optional
        The candidates that widened the interval (None with ``ci_*_noise``).
    ci_low_raw, ci_high_raw : float, optional
        The interval before it was cut at the physical range (None when it was not cut).
    """

    value: float
    unit: str
    ci_low: float
    ci_high: float
    std_error: float
    nominal: float
    note: str | None = None
    ci_low_noise: float | None = None
    ci_high_noise: float | None = None
    widened_by: tuple | None = None
    ci_low_raw: float | None = None
    ci_high_raw: float | None = None

    @property
    def moved(self) -> bool:
        """The reported interval excludes the nominal value."""
        return not self.ci_low <= self.nominal <= self.ci_high

    @property
    def raw_interval(self) -> tuple:
        """``(low, high)`` before the cut at the physical range."""
        return (self.ci_low if self.ci_low_raw is None else self.ci_low_raw,
                self.ci_high if self.ci_high_raw is None else self.ci_high_raw)

    def widened(self, ci_low: float, ci_high: float, by) -> "Estimate":
        """This estimate with the reported interval ``[ci_low, ci_high]``, widened for the
        candidates ``by``; its own interval is kept as ``ci_*_noise``.

        Parameters
        ----------
        ci_low, ci_high : float
            The widened interval, in ``unit``.
        by : iterable of str
            The candidates that widened it.
        """
        return replace(self, ci_low_noise=self.ci_low, ci_high_noise=self.ci_high,
                       ci_low=float(ci_low), ci_high=float(ci_high), widened_by=tuple(by))

    def cut(self, lo: float, hi: float) -> "Estimate":
        """This estimate with its intervals intersected with the physical range
        ``[lo, hi]`` (prior knowledge); a reported interval that was cut keeps its raw
        bounds as ``ci_*_raw``.

        Parameters
        ----------
        lo, hi : float
            The physical range, in ``unit``.
        """
        out = self
        if self.ci_low < lo or self.ci_high > hi:
            out = replace(out, ci_low_raw=self.ci_low, ci_high_raw=self.ci_high,
                          ci_low=float(min(max(self.ci_low, lo), hi)),
                          ci_high=float(max(min(self.ci_high, hi), lo)))
        if self.ci_low_noise is not None:       # cut the same way: still inside
            out = replace(out, ci_low_noise=float(min(max(self.ci_low_noise, lo), hi)),
                          ci_high_noise=float(max(min(self.ci_high_noise, hi), lo)))
        return out

    def shifted(self, offset: float) -> "Estimate":
        """This estimate with ``offset`` added to the value and every interval bound (a
        linearisation point the columns were built at).

        Parameters
        ----------
        offset : float
            In ``unit``.
        """
        def add(x):
            return None if x is None else x + offset
        return replace(self, value=self.value + offset, ci_low=self.ci_low + offset,
                       ci_high=self.ci_high + offset, ci_low_noise=add(self.ci_low_noise),
                       ci_high_noise=add(self.ci_high_noise), ci_low_raw=add(self.ci_low_raw),
                       ci_high_raw=add(self.ci_high_raw))

    def to_dict(self) -> dict:
        """The parameter's entry of ``diagnosis.json`` (``docs/diagnose.md``)."""
        d = {"value": self.value, "unit": self.unit, "ci_low": self.ci_low,
             "ci_high": self.ci_high, "std_error": self.std_error, "nominal": self.nominal}
        if self.note is not None:
            d["note"] = self.note
        if self.widened_by is not None:
            d.update(ci_low_noise=self.ci_low_noise, ci_high_noise=self.ci_high_noise,
                     widened_by=list(self.widened_by))
        if self.ci_low_raw is not None:
            d.update(ci_low_raw=self.ci_low_raw, ci_high_raw=self.ci_high_raw)
        return d


def _parameters_dict(table) -> dict:
    """A parameter table ({name: Estimate}, or ``{"error": message}`` of a fit that failed)
    as ``diagnosis.json`` writes it."""
    return {k: v.to_dict() if isinstance(v, Estimate) else v for k, v in table.items()}


@dataclass(frozen=True)
class Effect:
    """A fitted effect of a diagnosis: named, or partial (fitted, reported, not named).

    Attributes
    ----------
    name : str
        The candidate's name.
    subsystem : str
        The subsystem whose residual it explains (``"force"`` on a test bench).
    parameters : dict
        Parameter name -> :class:`Estimate`.
    evidence : dict
        The statistics behind the name, by name (``delta_bic``, ``lr_stat``, ``p_value``,
        ``cv_gain``, ``inclusion_probability``, ``subsystem_rho``, ``limit_ratio``, ...;
        ``docs/diagnose.md`` lists them per record kind).
    confidence : float
        The inclusion probability (BIC weight; a campaign: the stability frequency).
    confidence_level : str
        ``"high"`` when every gate passed, else ``"low"``.
    gates : dict, optional
        Gate name -> passed (empty for a partial effect; None where the kind does not
        report its gates).
    signature : str
        What the effect looks like in the residual (not written to ``diagnosis.json``).
    """

    name: str
    subsystem: str
    parameters: dict
    evidence: dict
    confidence: float
    confidence_level: str = "low"
    gates: dict | None = None
    signature: str = ""

    @property
    def high(self) -> bool:
        """The effect is named with high confidence."""
        return self.confidence_level == "high"

    def confidence_text(self) -> str:
        """How sure the effect is, in words: its inclusion probability (a number) and the
        confidence level of the gates ("high" only when every gate passes; the gates not
        passed are listed), so that a probability near 1 beside "low" reads as what it is."""
        failed = [g for g, ok in (self.gates or {}).items() if not ok]
        why = (f" (gates not passed: {', '.join(failed)})"
               if not self.high and failed else "")
        return (f"inclusion probability {self.confidence:.3f}; "
                f"confidence {self.confidence_level}{why}")

    def to_dict(self) -> dict:
        """The effect's entry of ``diagnosis.json`` (``docs/diagnose.md``)."""
        d = {"name": self.name, "parameters": _parameters_dict(self.parameters),
             "evidence": self.evidence, "confidence": self.confidence,
             "confidence_level": self.confidence_level, "subsystem": self.subsystem}
        if self.gates is not None:
            d["gates"] = self.gates
        return d


@dataclass(frozen=True)
class ConfoundedGroup:
    """Candidates a record cannot tell apart: each explains the same part of the residual.

    Never named.

    Attributes
    ----------
    members : tuple of str
        The members (those of the final model first).
    interpretations : dict
        Member -> its parameter table ({name: :class:`Estimate`}) if it were the cause, or
        ``{"error": message}`` when that fit failed.
    evidence : dict
        The statistics that make them look-alikes, by name.
    separating_experiment : str
        The experiment that would tell them apart.
    subsystem_rho : dict, optional
        An arm record's residual ratio per block channel.
    signature : str, optional
        What each member looks like (a test bench).
    """

    members: tuple
    interpretations: dict
    evidence: dict
    separating_experiment: str
    subsystem_rho: dict | None = None
    signature: str | None = None

    def to_dict(self) -> dict:
        """The group's entry of ``diagnosis.json`` (``docs/diagnose.md``)."""
        d = {"members": list(self.members),
             "interpretations": {m: _parameters_dict(t) for m, t in self.interpretations.items()},
             "evidence": self.evidence, "separating_experiment": self.separating_experiment}
        if self.subsystem_rho is not None:
            d["subsystem_rho"] = self.subsystem_rho
        if self.signature is not None:
            d["signature"] = self.signature
        return d


@dataclass(frozen=True, eq=False)
class Diagnosis(Result):
    """Result of :func:`ppamsafety.diagnose.diagnose`.

    On the result protocol (:class:`ppamsafety.results.Result`): :meth:`to_pandas` (the
    parameters of the named and partial effects), :meth:`plot` (the replay) and
    :meth:`figures` (the replay and the block residuals), and a file format of its own:
    :meth:`to_dict` is ``diagnosis.json`` (schema in ``docs/diagnose.md``) and :meth:`write`
    writes it with ``diagnosis.md`` and the figures.

    Attributes
    ----------
    source : str
        The record diagnosed.
    effects : list of Effect
        Named effects in the order found (:class:`Effect`: its parameters as
        :class:`Estimate` -- the reported 95 % interval, the fit's own, and the candidates
        that widened it, :mod:`.omitted` --, its evidence, confidence and gates).
    partial : list of Effect
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
    confounded : list of ConfoundedGroup
        Groups of candidates the record cannot tell apart (each explains the same part of
        the residual), with each member's parameters if it were the cause and the
        experiment that separates them.  Never named.
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
        return tuple(e.name for e in self.effects)

    def to_pandas(self) -> pd.DataFrame:
        """One row per (effect, parameter) of named and partial effects."""
        rows = []
        for status, lst in (("named", self.effects), ("partial", self.partial)):
            for e in lst:
                for pn, p in e.parameters.items():
                    rows.append({"effect": e.name, "status": status, "parameter": pn,
                                 **p.to_dict(), "widened_by": ", ".join(p.widened_by or ()),
                                 "confidence": e.confidence})
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
        return _clean({
            "schema_version": SCHEMA_VERSION, "tool": "ppamsafety", "version": __version__,
            "source": self.source, "kind": self.kind, "warnings": list(self.warnings),
            "effects": [e.to_dict() for e in self.effects],
            "partial": [e.to_dict() for e in self.partial],
            "unexplained": self.unexplained,
            "unexplained_channels": self.unexplained_channels,
            "residual_rms": self.residual_rms,
            "where": self.where.to_dict(orient="records"),
            "ranking": self.ranking().to_dict(orient="records"),
            "forces": self._forces_dict(),
            "confounded": [g.to_dict() for g in self.confounded],
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

    def figures(self) -> dict:
        """``{name: Figure}``: the replay (:meth:`plot`) and the block residuals
        (:meth:`plot_blocks`), under the names of their PNG files in :meth:`write`."""
        return {FIG_REPLAY[:-4]: self.plot(), FIG_BLOCKS[:-4]: self.plot_blocks()}

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
                L.append(f"* **{e.name}** ({e.confidence_text()}; Delta BIC "
                         f"{e.evidence['delta_bic']:.1f}, p = "
                         f"{e.evidence['p_value']:.2g})")
                for pn, p in e.parameters.items():
                    wide = (f"; widened for {', '.join(p.widened_by)}, the fit's own "
                            f"[{p.ci_low_noise:.5g}, {p.ci_high_noise:.5g}]"
                            if p.widened_by else "")
                    L.append(f"    * {pn} = {p.value:.5g} {p.unit} "
                             f"[{p.ci_low:.5g}, {p.ci_high:.5g}] (nominal "
                             f"{p.nominal:.5g}{wide})")
        else:
            L.append("No effect is named.")
        if self.partial:
            L += ["", "Significant but not named (their subsystem stays above the noise):"]
            L += [f"* {e.name}" for e in self.partial]
        if self.confounded:
            L += ["", "Confounded (not named: this record cannot tell them apart):", ""]
            for g in self.confounded:
                L.append(f"* {' / '.join(g.members)}: {g.separating_experiment}")
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
        figs = {f"{k}.png": fig for k, fig in self.figures().items()}
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


__all__ = ["Diagnosis", "Effect", "Estimate", "ConfoundedGroup", "SCHEMA_VERSION", "JSON_NAME",
           "MD_NAME"]
