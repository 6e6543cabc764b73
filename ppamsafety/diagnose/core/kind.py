"""A record kind is an adapter: what the front door and the engine need from it, and the
registry the front door loops over.

:func:`ppamsafety.diagnose.diagnose` knows no record kind.  It checks what every kind
shares (the record's type, the seed, the experiment hint, the arm a record names), then asks
every registered :class:`RecordKind` whether it takes the record (:meth:`RecordKind.accepts`;
exactly one must), lets that kind refuse the options that do not apply to it
(:meth:`RecordKind.check_options`) and hands the record to :meth:`RecordKind.diagnose`.

A kind holds, besides: its rule for "high" (:class:`~.gates.HighRule`) and its candidate
library (:class:`~.candidate.Library`, one object per candidate; its battery of scenarios, a :class:`~.battery.Battery`, lives above the
front door, in :mod:`ppamsafety.diagnose.scenarios` and the kinds' ``scenarios``).  The
recipe for a new kind is in ``docs/architecture.md``; the muscle test bench
(:class:`ppamsafety.diagnose.bench.kind.MuscleKind`) is its worked example.
"""

from __future__ import annotations

#: The registered kinds, in registration order (:func:`register_kind`).
_KINDS: list = []


class RecordKind:
    """Interface of a record kind (subclass it and :func:`register_kind` an instance).

    Attributes
    ----------
    name : str
        What the kind is called in messages ("arm record", "muscle test-bench record" ...).
    rule : HighRule
        Its gates and thresholds for "high".
    library : Library or None
        Its candidate library (:mod:`.candidate`; None: the kind lists its names itself,
        :meth:`candidates`).
    refused : dict
        Front-door option -> the message (naming the option and why it does not apply) it
        is refused with when given (not None), never silently ignored.
    """

    name: str = ""
    rule = None
    library = None
    refused: dict = {}

    def accepts(self, data) -> bool:
        """True for a record (or campaign) of this kind.

        Parameters
        ----------
        data : MeasuredData or Campaign
        """
        raise NotImplementedError

    def candidates(self) -> tuple:
        """The names of the kind's candidate library, in its order."""
        if self.library is None:
            raise NotImplementedError
        return tuple(self.library)

    def check_options(self, options: dict) -> None:
        """Refuse, with a ValueError naming it, an option that does not apply to this kind.

        Parameters
        ----------
        options : dict
            The front door's options (None: not given).
        """
        for opt, why in self.refused.items():
            if options.get(opt) is not None:
                raise ValueError(why)

    def diagnose(self, data, **options):
        """The :class:`~.result.Diagnosis` of a record of this kind.

        Parameters
        ----------
        data : MeasuredData or Campaign
        **options
            Every front-door option; the kind takes those that apply to it.
        """
        raise NotImplementedError


def register_kind(kind: RecordKind) -> RecordKind:
    """Add a record kind to the registry the front door loops over (once per class).

    Parameters
    ----------
    kind : RecordKind
    """
    if not isinstance(kind, RecordKind):
        raise TypeError(f"kind: {kind!r} is not a RecordKind")
    if any(type(k) is type(kind) for k in _KINDS):
        raise ValueError(f"kind: {type(kind).__name__} is registered already")
    _KINDS.append(kind)
    return kind


def registered() -> tuple:
    """The registered record kinds, in registration order."""
    return tuple(_KINDS)


def kind_of(data) -> RecordKind:
    """The one registered kind that accepts ``data``.

    Parameters
    ----------
    data : MeasuredData or Campaign

    Raises
    ------
    ValueError
        When no kind, or more than one, accepts it.
    """
    found = [k for k in _KINDS if k.accepts(data)]
    if len(found) != 1:
        names = ", ".join(k.name for k in found) or "none"
        raise ValueError(f"data: {len(found)} record kinds accept this record ({names}); "
                         f"registered: {', '.join(k.name for k in _KINDS)}")
    return found[0]


__all__ = ["RecordKind", "register_kind", "registered", "kind_of"]
