"""Pleated pneumatic artificial muscle (PPAM) groups.

Source: thesis §2.2 (PPAM), §2.3.3.1 (muscle parameters: l0 = 6 cm, l0/R = 6,
n_m = 4, 3, 4, 3), §2.3.2.4 (design contraction limits 5 % and 30 %),
eq. (3.9) and Table B.1 (force-law coefficients, identified per group).

The force law of one muscle is (3.9)::

    F = p (a0/eps + a1 + a2 eps + a3 eps^2 + a4 eps^3)

with p the gauge pressure.  Table B.1 gives the coefficients in N/bar; they
are stored here in N/Pa (= m^2), converted at the boundary.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from .._validation import (InvalidTypeError, check_instance, check_int, check_range, check_str,
                           check_vector)
from ..units import BAR, CM


#: Largest contraction a PPAM reaches: "up to 40% of the muscle's maximum length"
#: (thesis §2.2).  Upper bound of ``MuscleSet.eps_max`` and of every contraction in
#: the working area (checked by ArmParameters).
MAX_CONTRACTION = 0.4


@dataclass(frozen=True)
class MuscleGroup:
    """One series arrangement of ``n_muscles`` identical PPAMs.

    Attributes
    ----------
    name : str
        Label, e.g. ``"group 1 (joint 1, top)"``.
    n_muscles : int
        Number of PPAMs in series, n_m.
    coefficients : tuple of 5 float
        (a0, a1, a2, a3, a4) of the force law (3.9) in N/Pa (= m^2).
    l0 : float
        Uncontracted membrane length of one muscle [m].
    slenderness : float
        l0/R, dimensionless.  R = l0/slenderness is the minimum radius, used to
        anchor the volume function (see :mod:`ppamsafety.plant.muscle`).

    Ranges: ``n_muscles`` in [1, 20], ``l0`` in (0, 1] m, ``slenderness`` in
    [1, 50] (thesis: 4/3 muscles of 6 cm, l0/R = 6, §2.3.3.1), a0 >= 0.
    """

    name: str
    n_muscles: int
    coefficients: tuple
    l0: float = 6.0 * CM
    slenderness: float = 6.0

    def __post_init__(self):
        check_str("MuscleGroup.name", self.name)
        group = f" (group {self.name!r})"
        object.__setattr__(self, "n_muscles",
                           check_int(f"MuscleGroup.n_muscles{group}", self.n_muscles, 1, 20))
        coeffs = check_vector(f"MuscleGroup.coefficients{group}", self.coefficients, 5,
                              unit="m^2")
        object.__setattr__(self, "coefficients", coeffs)
        if coeffs[0] < 0:
            raise ValueError(f"MuscleGroup.coefficients[0] (a0){group} = {coeffs[0]:g} m^2 is "
                             "outside [0, inf): the 1/eps term must pull")
        object.__setattr__(self, "l0", check_range(f"MuscleGroup.l0{group}", self.l0, 0.0, 1.0,
                                                   lo_open=True, unit="m"))
        object.__setattr__(self, "slenderness", check_range(
            f"MuscleGroup.slenderness{group}", self.slenderness, 1.0, 50.0))

    @classmethod
    def from_newton_per_bar(cls, name: str, n_muscles: int, coefficients_n_per_bar,
                            **kwargs) -> "MuscleGroup":
        """Build a group from Table B.1-style coefficients in N/bar.

        Parameters
        ----------
        name : str
            Label of the group.
        n_muscles : int
            Number of PPAMs in series, n_m.
        coefficients_n_per_bar : sequence of 5 float
            (a0, a1, a2, a3, a4) of the force law (3.9) in N/bar; divided by
            ``BAR`` = 1e5 Pa to give N/Pa.
        **kwargs
            Further :class:`MuscleGroup` fields (``l0`` [m], ``slenderness``).
        """
        c = check_vector("coefficients_n_per_bar", coefficients_n_per_bar, 5, unit="N/bar")
        return cls(name=name, n_muscles=n_muscles, coefficients=tuple(x / BAR for x in c),
                   **kwargs)

    @property
    def radius(self) -> float:
        """Minimum (uncontracted) radius R = l0/slenderness [m]."""
        return self.l0 / self.slenderness


@dataclass(frozen=True)
class MuscleSet:
    """The four muscle groups of the arm and the design contraction limits.

    Attributes
    ----------
    groups : tuple of 4 MuscleGroup
        Groups 1 (joint 1 top), 2 (joint 1 bottom), 3 (joint 2 top),
        4 (joint 2 bottom), fig. 2.7.
    eps_min : float
        Minimum contraction of the top groups 1 and 3 at their longest length
        in the working area (2.14).  Dimensionless (0.05 = 5 %).
    eps_max : float
        Maximum contraction of the bottom groups 2 and 4 at their shortest
        length in the working area (A.36), (A.38); at most
        :data:`MAX_CONTRACTION` = 0.4 (§2.2).
    """

    groups: tuple
    eps_min: float = 0.05
    eps_max: float = 0.30

    def __post_init__(self):
        if not isinstance(self.groups, (tuple, list)):
            raise InvalidTypeError(f"MuscleSet.groups must be a tuple of 4 MuscleGroup, "
                                   f"got {type(self.groups).__name__}")
        if len(self.groups) != 4:
            raise ValueError(f"MuscleSet.groups must have 4 MuscleGroup, got {len(self.groups)}")
        for i, g in enumerate(self.groups):
            check_instance(f"MuscleSet.groups[{i}]", g, MuscleGroup)
        object.__setattr__(self, "groups", tuple(self.groups))
        object.__setattr__(self, "eps_min", check_range("MuscleSet.eps_min", self.eps_min, 0.0,
                                                        0.4, lo_open=True, hi_open=True))
        object.__setattr__(self, "eps_max", check_range("MuscleSet.eps_max", self.eps_max, 0.0,
                                                        MAX_CONTRACTION, lo_open=True))
        if not self.eps_min < self.eps_max:
            raise ValueError(f"MuscleSet: eps_min = {self.eps_min:g} must be smaller than "
                             f"eps_max = {self.eps_max:g}")

    def replace(self, **changes) -> "MuscleSet":
        """Return a copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            New values of fields of :class:`MuscleSet`, by field name (as for
            :func:`dataclasses.replace`); the copy is checked like a newly
            constructed object.
        """
        return replace(self, **changes)


#: Table B.1, coefficients a0..a4 per group in N/bar (as printed).
TABLE_B1_N_PER_BAR = (
    (8.16906, 295.069, -1586.59, 3623.1, -5728.79),
    (62.7708, -671.791, 5792.52, -20984.8, 24787.8),
    (28.2623, -16.2374, 678.514, -3595.7, 3216.48),
    (8.15986, 174.709, -490.279, -1182.38, 1905.53),
)


def thesis_muscles() -> MuscleSet:
    """The muscle groups of the thesis arm (§2.3.3.1, Table B.1)."""
    names = ("group 1 (joint 1, top)", "group 2 (joint 1, bottom)",
             "group 3 (joint 2, top)", "group 4 (joint 2, bottom)")
    n_m = (4, 3, 4, 3)
    groups = tuple(MuscleGroup.from_newton_per_bar(nm, n, c)
                   for nm, n, c in zip(names, n_m, TABLE_B1_N_PER_BAR))
    return MuscleSet(groups=groups, eps_min=0.05, eps_max=0.30)


__all__ = ["MuscleGroup", "MuscleSet", "thesis_muscles",
           "TABLE_B1_N_PER_BAR", "MAX_CONTRACTION"]
