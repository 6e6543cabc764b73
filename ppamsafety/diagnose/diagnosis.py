""":func:`diagnose`: the front door of the discrepancy workflow, for every record kind.

It checks what every kind shares and hands the record to the one registered record kind
(:mod:`ppamsafety.diagnose.core.kind`) that accepts it; the kinds registered here:

* an arm record (open loop, closed loop, static sawtooth),
  :class:`ppamsafety.diagnose.arm.kind.ArmKind`;
* an actuator record of a muscle on a test bench,
  :class:`ppamsafety.diagnose.bench.kind.MuscleKind`;
* a pneumatic cylinder on a bench -- one record or a campaign of several
  (:class:`~ppamsafety.data.campaign.Campaign`) --
  :class:`ppamsafety.diagnose.bench.kind.CampaignKind`.

Each returns a :class:`~ppamsafety.diagnose.core.result.Diagnosis`.
"""

from __future__ import annotations

from threadpoolctl import threadpool_limits

from ..data.campaign import Campaign
from .._validation import check_bool, check_instance, check_int, check_seed, did_you_mean
from ..data.measured import MeasuredData
from ..params.arm import ArmParameters
from .arm.kind import other_arm
from .bench import kind as _bench_kinds  # noqa: F401  (registers the bench kinds)
from .core.gates import HIGH_WEIGHT
from .core.kind import kind_of
from .core.result import JSON_NAME, SCHEMA_VERSION, Diagnosis


def diagnose(data, *, arm=None, candidates=None, block_seconds: float = 0.05,
             alpha: float = 0.01, rho_max: float = 1.5, experiment: str | None = None,
             seed: int = 0, bootstrap: int | None = None,
             stability: int | None = None, allow_other_arm: bool = False) -> Diagnosis:
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
        The model under test, its declared effects included (default the thesis arm; arm
        records only).  A record that names the arm it came from (metadata ``[arm]``, as
        :func:`~ppamsafety.diagnose.synthesize` writes it) must be diagnosed against that
        arm, or with ``allow_other_arm``.
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
    allow_other_arm : bool, keyword-only
        Diagnose a record against another arm than the one it names, on purpose: every
        difference between the two arms is then reported as a missing effect, and the
        mismatch stands first in ``Diagnosis.warnings`` (the top of ``diagnosis.md``).

    Returns
    -------
    Diagnosis
        When an arm record names the arm it came from, ``settings["arm"]`` holds both
        fingerprints and a note starting ``"arm: "`` says whether they agree.

    Raises
    ------
    ValueError
        When the record names another arm (name and fingerprint, :func:`other_arm`) than
        ``arm`` and ``allow_other_arm`` is not given.

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
                         bootstrap=bootstrap, stability=stability,
                         allow_other_arm=allow_other_arm)


def _diagnose(data, *, arm, candidates, block_seconds, alpha, rho_max, experiment, seed,
              bootstrap, stability, allow_other_arm):
    check_instance("data", data, (MeasuredData, Campaign))
    allow_other_arm = check_bool("allow_other_arm", allow_other_arm)
    if arm is not None:
        check_instance("arm", arm, ArmParameters)
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
    kind = kind_of(data)
    options = dict(arm=arm, candidates=candidates, block_seconds=block_seconds, alpha=alpha,
                   rho_max=rho_max, experiment=experiment, seed=seed, bootstrap=bootstrap,
                   stability=stability)
    # what applies to some kinds only is refused rather than silently ignored
    kind.check_options(options)
    mismatch = other_arm(data, arm)
    if mismatch is not None and not allow_other_arm:
        raise ValueError(f"{mismatch}: diagnose the record against the arm it came from "
                         f"(arm=load_arm(FILE), the arm file whose fingerprint it names), or "
                         f"give allow_other_arm=True to compare the two arms on purpose")
    return kind.diagnose(data, mismatch=mismatch, **options)


__all__ = ["Diagnosis", "diagnose", "other_arm", "SCHEMA_VERSION", "HIGH_WEIGHT",
           "JSON_NAME"]
