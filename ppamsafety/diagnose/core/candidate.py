"""A candidate is one object: everything the diagnosis, its generator, its battery and its
gates know about one effect the diagnosis can name.

Every record kind has a library of candidates (:class:`Library`, registered on import under
the kind's name, :func:`library`).  A candidate of any kind carries, besides what its kind
needs to build its columns and report its parameters (the arm's
:class:`~ppamsafety.diagnose.arm.candidates.Candidate`, the muscle bench's
:class:`~ppamsafety.diagnose.bench.candidates.MuscleCandidate`):

``draw``
    How the battery draws it: ``draw(rng, ...) -> (effects, truth)``, the generator's
    effects that hide it in a synthetic record (its injection into the plant or the
    record: the keys the kind's generator accepts) and its true parameter values
    ``{parameter: value}``.  The arguments after ``rng`` are the kind's (the arm: the arm
    and the sample time; the muscle bench: the force law and the protocol).  The battery's
    seeds reproduce only while each draw consumes the generator in the same order.
``needs``
    The gates of its kind's rule (:class:`~.gates.HighRule`) that apply to it by name: a
    gate named here is a condition on the record this candidate needs before it can be
    "high" (the muscle bench's ``reversals``, ``pressure_levels``).
``separating``
    The experiment that tells it from each look-alike, ``{other candidate: text}``; a pair
    is written on one of its two members (:meth:`Library.separating_table`).

So a new candidate is one object and its test: the kind's selection, gates, detection
limits, report, generator draws and separating experiments read it from the library.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType

#: The libraries of the record kinds, by kind name (:func:`library`).
_LIBRARIES: dict = {}


@dataclass(frozen=True, eq=False)
class Candidate:
    """What every record kind's candidate carries (see the module docstring).

    Attributes
    ----------
    name : str
        The name written in ``diagnosis.json``.
    draw : callable or None, keyword-only
        ``draw(rng, ...) -> (effects, truth)``: the battery's draw (None: not drawn).
    needs : tuple of str, keyword-only
        Gates of the kind's rule that apply to this candidate by name.
    separating : mapping, keyword-only
        Other candidate name -> the experiment that separates the two.
    """

    name: str
    draw: object = field(default=None, repr=False, kw_only=True)
    needs: tuple = field(default=(), kw_only=True)
    separating: object = field(default_factory=dict, repr=False, kw_only=True)

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise TypeError(f"candidate name must be a non-empty str, got {self.name!r}")
        if self.draw is not None and not callable(self.draw):
            raise TypeError(f"candidate {self.name!r}: draw must be callable or None, got "
                            f"{type(self.draw).__name__}")
        needs = tuple(self.needs)
        if not all(isinstance(n, str) for n in needs):
            raise TypeError(f"candidate {self.name!r}: needs must be gate names (str), got "
                            f"{self.needs!r}")
        object.__setattr__(self, "needs", needs)
        sep = dict(self.separating)
        if self.name in sep or not all(isinstance(k, str) and isinstance(v, str) and v
                                       for k, v in sep.items()):
            raise ValueError(f"candidate {self.name!r}: separating must map other candidate "
                             f"names to a non-empty text, got {self.separating!r}")
        object.__setattr__(self, "separating", MappingProxyType(sep))


class Library(dict):
    """A record kind's candidates, name -> candidate, in registration order.

    A ``dict`` (the selection and the report read it as one) that only :meth:`register`
    fills.

    Parameters
    ----------
    kind : str
        The record kind's name (the key of :func:`library`).
    cls : type
        The kind's candidate class (a subclass of :class:`Candidate`).
    vocabulary : tuple of str, optional
        The fixed names the kind may write (None: any name).
    """

    def __init__(self, kind: str, cls=Candidate, vocabulary=None):
        super().__init__()
        if not (isinstance(cls, type) and issubclass(cls, Candidate)):
            raise TypeError(f"cls must be a subclass of Candidate, got {cls!r}")
        self.kind = kind
        self.cls = cls
        self.vocabulary = None if vocabulary is None else tuple(vocabulary)

    def register(self, candidate):
        """Add ``candidate`` (of the library's class, with a new name from its vocabulary).

        Parameters
        ----------
        candidate : Candidate
        """
        if not isinstance(candidate, self.cls):
            raise TypeError(f"candidate must be a {self.cls.__name__}, got "
                            f"{type(candidate).__name__}")
        if self.vocabulary is not None and candidate.name not in self.vocabulary:
            raise ValueError(f"candidate name {candidate.name!r} is not in the vocabulary "
                             f"{self.vocabulary}")
        if candidate.name in self:
            raise ValueError(f"candidate {candidate.name!r} is already registered")
        self[candidate.name] = candidate
        return candidate

    def draws(self) -> dict:
        """Name -> the battery's draw, for every candidate that has one (registry order)."""
        return {n: c.draw for n, c in self.items() if c.draw is not None}

    def needing(self, gate: str) -> tuple:
        """Names of the candidates a gate applies to (``gate in needs``), registry order.

        Parameters
        ----------
        gate : str
        """
        return tuple(n for n, c in self.items() if gate in c.needs)

    def separating_table(self) -> dict:
        """Every pair's separating experiment, ``frozenset({a, b}) -> text``, in registry order
        of the pair's members (the earlier member first, then the later one)."""
        pairs = {}
        for n, c in self.items():
            for other, text in c.separating.items():
                key = frozenset((n, other))
                if key in pairs:
                    raise ValueError(f"{self.kind}: the separating experiment of {sorted(key)} "
                                     f"is written twice")
                pairs[key] = text
        order = {n: i for i, n in enumerate(self)}

        def rank(key):
            return sorted(order.get(m, len(order)) for m in key)

        return dict(sorted(pairs.items(), key=lambda kv: rank(kv[0])))


def register_library(lib: Library) -> Library:
    """Register a record kind's candidate library under its kind's name.

    Parameters
    ----------
    lib : Library
    """
    if not isinstance(lib, Library):
        raise TypeError(f"lib must be a Library, got {type(lib).__name__}")
    if lib.kind in _LIBRARIES:
        raise ValueError(f"a candidate library of kind {lib.kind!r} is registered already")
    _LIBRARIES[lib.kind] = lib
    return lib


def library(kind: str) -> Library:
    """The candidate library of a record kind.

    Parameters
    ----------
    kind : str
        A registered kind's name (:func:`libraries`).
    """
    if kind not in _LIBRARIES:
        raise ValueError(f"kind: no candidate library {kind!r}; registered: "
                         f"{sorted(_LIBRARIES)}")
    return _LIBRARIES[kind]


def libraries() -> dict:
    """Kind name -> its candidate library, every registered one."""
    return dict(_LIBRARIES)


__all__ = ["Candidate", "Library", "register_library", "library", "libraries"]
