""":func:`diagnose`: the front door of the discrepancy workflow, for every record kind.

It checks the record and hands it to the pipeline of its kind:

* an arm record (open loop, closed loop, static sawtooth) to
  :func:`ppamsafety.diagnose.arm.pipeline.diagnose_arm`;
* an actuator record of a muscle on a test bench to
  :func:`ppamsafety.diagnose.bench.pipeline.diagnose_actuator`;
* a pneumatic cylinder on a bench -- one record or a campaign of several
  (:class:`~ppamsafety.data.campaign.Campaign`) -- to
  :func:`ppamsafety.diagnose.bench.campaign.diagnose_campaign`.

Both return a :class:`~ppamsafety.diagnose.core.result.Diagnosis`.
"""

from __future__ import annotations

from dataclasses import replace

from threadpoolctl import threadpool_limits

from ..data.campaign import Campaign
from .._validation import check_instance, check_int, check_seed, did_you_mean
from ..data.measured import MeasuredData
from ..params import thesis_arm
from ..params.arm_file import arm_fingerprint
from .arm.pipeline import diagnose_arm
from .bench.campaign import diagnose_campaign
from .bench.pipeline import diagnose_actuator
from .core.result import HIGH_CONFIDENCE, JSON_NAME, SCHEMA_VERSION, Diagnosis


def diagnose(data, *, arm=None, candidates=None, block_seconds: float = 0.05,
             alpha: float = 0.01, rho_max: float = 1.5, experiment: str | None = None,
             seed: int = 0, bootstrap: int | None = None,
             stability: int | None = None) -> Diagnosis:
    """Diagnose a measured record against the model: which effect is missing, and where.

    Parameters
    ----------
    data : MeasuredData or Campaign
        The record (:func:`ppamsafety.data.load_measured`), or a bench campaign
        (:func:`ppamsafety.data.load_campaign`; a cylinder record alone is a
        campaign of one).  Arm records: open
        or closed loop with q, qd, p, u; or a static sawtooth (§3.5.1.6) with
        q, p (u and F1..F4 optional), see :mod:`ppamsafety.diagnose.arm.static`.
        An actuator record (``data.kind == "actuator"``, a test bench) is
        diagnosed against its nominal force law.
    arm : ArmParameters, optional, keyword-only
        The current model (default the thesis arm; arm records only).
    candidates : sequence of str, optional, keyword-only
        Library subset (default all registered; for an actuator record, from the
        tester vocabulary).
    block_seconds : float, keyword-only
        Block length of the subsystem residuals [s] (arm records only).
    alpha : float, keyword-only
        Level of the likelihood-ratio test (Bonferroni-divided per step).
    rho_max : float, keyword-only
        Largest residual/noise RMS ratio of an explained channel.
    experiment : str, optional, keyword-only
        Hint for records whose metadata lacks it (must agree when both given).
    seed : int, keyword-only
        Seed of the Monte Carlo noise propagation and of the bootstrap (arm records).
    bootstrap : int, optional, keyword-only
        Replicates of the moving-block bootstrap of the selection
        (:func:`~ppamsafety.diagnose.arm.selection.bootstrap_frequency`); default
        :data:`~ppamsafety.diagnose.arm.selection.BOOTSTRAP_REPLICATES`, 0: none
        (arm records).  Each named effect's evidence then carries
        ``bootstrap_frequency``.
    stability : int, optional, keyword-only
        Complementary pairs of the stability selection (arm records; default
        :data:`~ppamsafety.diagnose.arm.selection.STABILITY_PAIRS`, 0: none -- then no
        effect reaches "high").  Each named effect's evidence carries
        ``stability_frequency``; ``diagnosis.json`` key ``stability`` holds the bound on
        the expected number of false selections.

    Returns
    -------
    Diagnosis
        When an arm record names the arm it came from (metadata ``[arm]``, written by
        :func:`~ppamsafety.diagnose.synthesize`), ``settings["arm"]`` holds both
        fingerprints and a note starting ``"arm: "`` says whether they agree.

    Notes
    -----
    For an actuator record ``arm``, ``block_seconds``, ``seed``, ``bootstrap`` and
    ``stability`` do not apply and its confidence is the BIC weight.
    """
    with threadpool_limits(limits=1, user_api="blas"):
        # thousands of small products: a multi-threaded BLAS spends more time synchronising
        # its threads than computing (measured: 4.3 s instead of 8.4 s for a 23 s record)
        return _diagnose(data, arm=arm, candidates=candidates, block_seconds=block_seconds,
                         alpha=alpha, rho_max=rho_max, experiment=experiment, seed=seed,
                         bootstrap=bootstrap, stability=stability)


def _diagnose(data, *, arm, candidates, block_seconds, alpha, rho_max, experiment, seed,
              bootstrap, stability):
    check_instance("data", data, (MeasuredData, Campaign))
    seed = check_seed("seed", seed)
    if bootstrap is not None:
        check_int("bootstrap", bootstrap, 0, 10000)
    if stability is not None:
        check_int("stability", stability, 0, 10000)
    recs = data.records if isinstance(data, Campaign) else (data,)
    if experiment is not None:
        exps = sorted({r.experiment for r in recs})
        if exps != [experiment]:
            raise ValueError(f"experiment = {experiment!r} does not match the experiment "
                             f"{', '.join(map(repr, exps))} of the record's metadata"
                             f"{did_you_mean(experiment, exps)}")
    if isinstance(data, Campaign) or data.kind == "actuator":
        # what applies to arm records only is refused rather than silently ignored
        if arm is not None:
            raise ValueError("arm applies to arm records; an actuator record (a test bench) is "
                             "diagnosed against its own nominal force law (leave arm out)")
    if isinstance(data, Campaign) or data.actuator_type == "cylinder":
        return diagnose_campaign(data, candidates=candidates, alpha=alpha, rho_max=rho_max)
    if data.kind == "actuator":
        return diagnose_actuator(data, candidates=candidates, alpha=alpha, rho_max=rho_max,
                                 experiment=experiment)
    dg = diagnose_arm(data, arm=arm, candidates=candidates, block_seconds=block_seconds,
                      alpha=alpha, rho_max=rho_max, experiment=experiment, seed=seed,
                      bootstrap=bootstrap, stability=stability)
    made = data.meta.get("arm") if isinstance(data, MeasuredData) else None
    if made is None:
        return dg
    used = thesis_arm() if arm is None else arm
    fp = arm_fingerprint(used)
    label = f"'{used.name or 'unnamed arm'}' (sha256 {fp[:12]})"
    rec = f"'{made.get('name') or 'unnamed arm'}' (sha256 {made['sha256'][:12]})"
    note = (f"arm: the record came from the arm it is diagnosed against, {label}"
            if made["sha256"] == fp else
            f"arm: the record came from arm {rec} but is diagnosed against arm {label}: a "
            f"difference between the two arms is reported as a missing effect")
    return replace(dg, notes=(*dg.notes, note),
                   settings={**dg.settings, "arm": {"record": dict(made), "model": {
                       "name": used.name, "sha256": fp}}})


__all__ = ["Diagnosis", "diagnose", "SCHEMA_VERSION", "HIGH_CONFIDENCE", "JSON_NAME"]
