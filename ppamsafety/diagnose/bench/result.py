"""The result of a bench-campaign diagnosis: :class:`BenchDiagnosis`.

A :class:`~ppamsafety.diagnose.core.result.Diagnosis` (same ``diagnosis.json``
schema, ``docs/diagnose.md``) with what a campaign adds: the **confounded**
groups (sensor faults and plant effects that give the same terms, each with
the experiment that would separate them), a per-record table (pressure, noise
levels, residual before/after) and the force-stroke curves for the figures.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import pandas as pd

from ...plots.bench import campaign_loops_figure, campaign_residual_figure
from ..core.result import Diagnosis, _clean, _md_table


@dataclass(frozen=True, eq=False)
class BenchDiagnosis(Diagnosis):
    """Result of :func:`~ppamsafety.diagnose.bench.campaign.diagnose_campaign`.

    Attributes
    ----------
    source, effects, partial, unexplained, unexplained_channels, residual_rms : object
        As :class:`~ppamsafety.diagnose.core.result.Diagnosis` (``source`` is the
        campaign's name; ``partial`` is empty: a campaign names effects even when a
        structure remains, ``unexplained`` says so).
    where, steps, replay, settings, timings, notes, blocks, kind, subsystems : object
        As :class:`~ppamsafety.diagnose.core.result.Diagnosis` (``replay`` and
        ``blocks`` are empty: the figures read :attr:`curves`).
    stability, detection_limits : dict
        As :class:`~ppamsafety.diagnose.core.result.Diagnosis` (a campaign reports its
        stability reruns in ``settings``; empty here).
    confounded : list of ConfoundedGroup
        As :class:`~ppamsafety.diagnose.core.result.Diagnosis`: groups selected as one
        (their terms coincide on this campaign).  Never named.
    warnings : tuple of str
        As :class:`~ppamsafety.diagnose.core.result.Diagnosis` (empty: a bench record
        names no arm).
    records : pandas.DataFrame
        One row per record: ``label``, ``pressure_Pa``, ``samples``,
        ``strokes``, ``sigma_sensor_N``, ``sigma_repeat_N``, ``rms_before_N``,
        ``rms_after_N``, ``rho_after`` (residual over the repeatability) and
        ``rho_left_out`` (the same for the model refitted without this record:
        leave-one-record-out, the test of the pressure law).
    curves : dict
        Per record (label -> dict of arrays ``x``, ``s``, ``t``, ``before``,
        ``after``, ``used``) for the figures.
    """

    records: pd.DataFrame = field(default_factory=pd.DataFrame, repr=False)
    curves: dict = field(default_factory=dict, repr=False)

    def to_dict(self) -> dict:
        """``diagnosis.json``: the Diagnosis keys plus ``confounded`` and ``records``."""
        d = super().to_dict()
        d["records"] = _clean(self.records.to_dict(orient="records"))
        return d

    def plot(self):
        """Force residual against the rod position per record, before and after (the loops)."""
        return campaign_loops_figure(self)

    def plot_blocks(self):
        """Residual over the repeatability level against time, per record."""
        return campaign_residual_figure(self)

    def report_markdown(self) -> str:
        """``diagnosis.md``: named effects, confounded groups, records, where, notes."""
        L = [f"# Bench campaign diagnosis of {self.source}", ""]
        if self.effects:
            L += ["| effect | confidence | parameters |", "|---|---|---|"]
            for e in self.effects:
                ps = "; ".join(f"{k} = {v.value:.4g} {v.unit}"
                               + (f" [{v.ci_low:.4g}, {v.ci_high:.4g}]"
                                  if v.ci_low == v.ci_low else "")
                               for k, v in e.parameters.items())
                L.append(f"| {e.name} | {e.confidence_level} "
                         f"({e.confidence:.2f}) | {ps} |")
        else:
            L.append("No effect is named.")
        if self.confounded:
            L += ["", "## Confounded (not named: the terms coincide on this campaign)", ""]
            for g in self.confounded:
                L.append(f"* {' / '.join(g.members)}: {g.separating_experiment}")
        L += ["", f"**Unexplained:** {'yes' if self.unexplained else 'no'}", "",
              "## Records", "", _md_table(self.records) if len(self.records) else "",
              "", "## Ranking", ""]
        rk = self.ranking()
        if len(rk):
            cols = [c for c in ("step", "model", "name", "variant", "k", "cv_gain", "p_value",
                                "in_bounds", "eligible", "chosen") if c in rk.columns]
            L.append(_md_table(rk[cols]))
        sig = self.where[self.where["significant"]] if len(self.where) else self.where
        L += ["", "## Where the final residual is significant", ""]
        L.append(_md_table(sig) if len(sig) else "Nowhere.")
        L += ["", "## Settings", "", "```", json.dumps(_clean(self.settings), indent=1), "```"]
        if self.notes:
            L += ["", "## Notes", ""] + [f"* {n}" for n in self.notes]
        return "\n".join(L) + "\n"


__all__ = ["BenchDiagnosis"]
