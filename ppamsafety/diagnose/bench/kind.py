"""The bench record kinds: a muscle on a tensile tester, a pneumatic cylinder campaign.

The adapters the front door (:func:`ppamsafety.diagnose.diagnose`) finds a bench record by,
registered on import.  :class:`MuscleKind` is the worked example of the recipe for a new
record kind (``docs/architecture.md``).
"""

from __future__ import annotations

from ...data.campaign import Campaign
from ...data.measured import MeasuredData
from ..core.kind import RecordKind, register_kind
from .campaign import CAMPAIGN_RULE, diagnose_campaign
from .candidates import MUSCLE_LIBRARY
from .friction import VOCABULARY
from .gates import MUSCLE_RULE
from .pipeline import diagnose_actuator

#: Why the model of an arm does not apply to a bench record.
_NO_ARM = ("arm applies to arm records; an actuator record (a test bench) is diagnosed against "
           "its own nominal force law (leave arm out)")


class MuscleKind(RecordKind):
    """A muscle's test-bench record (``kind == "actuator"``), :func:`~.pipeline.diagnose_actuator`.

    ``block_seconds``, ``seed``, ``bootstrap`` and ``stability`` do not apply (its
    confidence is the BIC weight) and are ignored; ``arm`` is refused.
    """

    name = "muscle test-bench record"
    rule = MUSCLE_RULE
    library = MUSCLE_LIBRARY
    refused = {"arm": _NO_ARM}

    def accepts(self, data) -> bool:
        """True for a muscle's test-bench record.

        Parameters
        ----------
        data : MeasuredData or Campaign
        """
        return (isinstance(data, MeasuredData) and data.kind == "actuator"
                and data.actuator_type != "cylinder")

    def diagnose(self, data, *, candidates=None, alpha=0.01, rho_max=1.5, experiment=None,
                 **_):
        """:func:`~.pipeline.diagnose_actuator` of the record.

        Parameters
        ----------
        data : MeasuredData
        candidates, alpha, rho_max, experiment
            As :func:`ppamsafety.diagnose.diagnose`.
        **_
            The arm's options (``arm`` is refused by :meth:`check_options`, the others
            do not apply).
        """
        return diagnose_actuator(data, candidates=candidates, alpha=alpha, rho_max=rho_max,
                                 experiment=experiment)


class CampaignKind(RecordKind):
    """A pneumatic cylinder on a bench: one record or a campaign of several,
    :func:`~.campaign.diagnose_campaign`."""

    name = "cylinder campaign"
    rule = CAMPAIGN_RULE
    refused = {"arm": _NO_ARM}

    def accepts(self, data) -> bool:
        """True for a campaign or one cylinder record.

        Parameters
        ----------
        data : MeasuredData or Campaign
        """
        return isinstance(data, Campaign) or (isinstance(data, MeasuredData)
                                              and data.actuator_type == "cylinder")

    def candidates(self) -> tuple:
        return tuple(VOCABULARY)

    def diagnose(self, data, *, candidates=None, alpha=0.01, rho_max=1.5, **_):
        """:func:`~.campaign.diagnose_campaign` of the campaign.

        Parameters
        ----------
        data : Campaign or MeasuredData
        candidates, alpha, rho_max
            As :func:`ppamsafety.diagnose.diagnose`.
        **_
            Options that do not apply (``arm`` is refused by :meth:`check_options`).
        """
        return diagnose_campaign(data, candidates=candidates, alpha=alpha, rho_max=rho_max)


MUSCLE = register_kind(MuscleKind())
CAMPAIGN = register_kind(CampaignKind())

__all__ = ["MuscleKind", "CampaignKind", "MUSCLE", "CAMPAIGN"]
