"""The arm record kind: open loop, closed loop and the static sawtooth (§3.5.1.6).

The adapter the front door (:func:`ppamsafety.diagnose.diagnose`) finds an arm record by
(:class:`ArmKind`, registered on import), and what only an arm record has: the arm it names
(metadata ``[arm]``) checked against the model under test (:func:`other_arm`).
"""

from __future__ import annotations

from dataclasses import replace

from ...data.measured import MeasuredData
from ...params import thesis_arm
from ...params.arm_file import arm_fingerprint
from ..core.kind import RecordKind, register_kind
from .candidates import REGISTRY
from .gates import ARM_RULE
from .pipeline import diagnose_arm


def _label(name, sha256) -> str:
    return f"'{name or 'unnamed arm'}' (sha256 {sha256[:16]})"


def other_arm(data, arm) -> str | None:
    """The mismatch between the arm a record names and the arm it is diagnosed against.

    Parameters
    ----------
    data : MeasuredData or Campaign
        The record; an arm record may name the arm it came from (metadata ``[arm]``: its
        ``name`` and ``sha256``, :func:`ppamsafety.params.arm_file.arm_fingerprint`).
    arm : ArmParameters or None
        The model under test (None: the thesis arm).

    Returns
    -------
    str or None
        None when the record names no arm or the same one; else a sentence naming both
        arms (name and fingerprint).
    """
    made = data.meta.get("arm") if isinstance(data, MeasuredData) else None
    if made is None:
        return None
    used = thesis_arm() if arm is None else arm
    fp = arm_fingerprint(used)
    if made["sha256"] == fp:
        return None
    return (f"the record came from arm {_label(made.get('name'), made['sha256'])} but is "
            f"diagnosed against arm {_label(used.name, fp)}")


def assumed_arm_note(arm, *, given: bool) -> str:
    """The note of a record that names no arm: which arm it is diagnosed against.

    Parameters
    ----------
    arm : ArmParameters
        The model under test.
    given : bool
        Whether the caller gave it (else it is the thesis arm, the default).
    """
    how = "given" if given else "the default: give the record's arm with --arm FILE (arm=)"
    return (f"arm: the record names no arm (no [arm] in its metadata); it is diagnosed against "
            f"arm {_label(arm.name, arm_fingerprint(arm))} ({how})")


class ArmKind(RecordKind):
    """Arm records (:func:`~.pipeline.diagnose_arm`)."""

    name = "arm record"
    rule = ARM_RULE
    library = REGISTRY

    def accepts(self, data) -> bool:
        """True for an arm record (not a test-bench record, not a cylinder).

        Parameters
        ----------
        data : MeasuredData or Campaign
        """
        return (isinstance(data, MeasuredData) and data.kind != "actuator"
                and data.actuator_type != "cylinder")

    def diagnose(self, data, *, arm=None, candidates=None, block_seconds=0.05, alpha=0.01,
                 rho_max=1.5, experiment=None, seed=0, bootstrap=None, stability=None,
                 mismatch=None, **_):
        """:func:`~.pipeline.diagnose_arm`, and the arm the record names in its settings and
        notes.

        Parameters
        ----------
        data : MeasuredData
        arm, candidates, block_seconds, alpha, rho_max, experiment, seed, bootstrap, stability
            As :func:`ppamsafety.diagnose.diagnose` (checked there).
        mismatch : str, optional
            :func:`other_arm` of the record, allowed by the caller.
        **_
            Front-door options of other kinds (none is given: :meth:`check_options`).
        """
        dg = diagnose_arm(data, arm=arm, candidates=candidates, block_seconds=block_seconds,
                          alpha=alpha, rho_max=rho_max, experiment=experiment, seed=seed,
                          bootstrap=bootstrap, stability=stability)
        made = data.meta.get("arm")
        used = thesis_arm() if arm is None else arm
        fp = arm_fingerprint(used)
        if made is None:
            return replace(dg, notes=(*dg.notes, assumed_arm_note(used, given=arm is not None)))
        warnings = dg.warnings
        if mismatch is None:
            note = (f"arm: the record came from the arm it is diagnosed against, "
                    f"{_label(used.name, fp)}")
        else:
            note = (f"arm: {mismatch} (allowed on purpose): every difference between the two "
                    f"arms is reported as a missing effect")
            warnings = (note[5:],) + tuple(warnings)
        return replace(dg, notes=(*dg.notes, note), warnings=warnings,
                       settings={**dg.settings, "arm": {"record": dict(made), "model": {
                           "name": used.name, "sha256": fp}, "same": mismatch is None}})


ARM = register_kind(ArmKind())

__all__ = ["ArmKind", "ARM", "other_arm", "assumed_arm_note"]
