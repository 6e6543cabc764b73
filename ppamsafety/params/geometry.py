"""Arm geometry: link lengths, muscle attachment points and the working area.

Source: thesis §2.3, Table 2.1 (attachment points), Table 2.2 (load point,
link lengths), eqs. (2.6)-(2.7) (working area), fig. 2.9 / A.1 (definitions).
All lengths are stored in metres and angles in radians; the thesis values in
millimetres and degrees are converted here, at the boundary.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from functools import lru_cache

import numpy as np

from .._validation import check_range
from ..units import DEG, MM

#: Geometry fields that place each muscle group's two attachment points (groups 1..4).
GROUP_FIELDS = {1: ("X11", "Y11", "L12", "d12"), 2: ("X21", "Y21", "L22", "d22"),
                3: ("L1", "L32", "d32", "L33", "d33"), 4: ("L1", "L42", "d42", "L43", "d43")}

#: Smallest admissible muscle group length (attachment point distance) anywhere in the
#: working area [m].  At zero length the direction of the pull and the lever arm
#: (A.1)-(A.4) are undefined (division by zero); 1 mm is far below any real
#: PPAM (l0 = 6 cm, §2.3.3.1), so this check only refuses degenerate geometry.
MIN_GROUP_LENGTH = 1.0e-3


@dataclass(frozen=True)
class ArmGeometry:
    """Kinematic and attachment-point geometry of the 2-DOF PPAM arm.

    Coordinates follow fig. 2.9 of the thesis: origin O at joint 1, joint 2 at
    S = L1 (cos q1, sin q1).  ``Lxy`` is the distance of attachment point
    ``A_xy`` along link ``y`` and ``dxy`` its perpendicular offset (sign
    convention of eqs. (A.13)-(A.22)).  Muscle groups 1 and 2 drive joint 1,
    groups 3 and 4 drive joint 2.

    Attributes
    ----------
    X11, Y11, X21, Y21 : float
        Base attachment coordinates of groups 1 and 2 [m] (A11 = (-X11, Y11),
        A21 = (X21, -Y21)).
    L12, d12, L22, d22, L32, d32, L42, d42 : float
        Attachment points on the upper arm (link "2" in the thesis' point
        naming) [m].
    L33, d33, L43, d43 : float
        Attachment points on the forearm [m].
    L1, L2 : float
        Link lengths O-S and S-TCP [m].
    LL, dL : float
        Load point A_L on the forearm (Table 2.2) [m].
    q1_min, q1_max, q2_min, q2_max : float
        Working area (2.6)-(2.7) [rad], inside (-pi, pi), min < max.

    Notes
    -----
    Every field is converted to float on construction; wrong types raise
    ``TypeError`` naming ``ArmGeometry.<field>``.  Ranges: offsets ``d*`` in
    [-0.5, 0.5] m, lengths in [0, 5] m (``L1``, ``L2`` > 0) -- an order of
    magnitude around the thesis arm (Tables 2.1, 2.2).  A geometry in which a
    muscle group's attachment points come closer than
    :data:`MIN_GROUP_LENGTH` anywhere in the working area is refused; whether
    the muscles fit (positive connection lengths) is checked by
    :class:`~ppamsafety.params.ArmParameters`, which knows the muscles.
    """

    X11: float
    Y11: float
    X21: float
    Y21: float
    L12: float
    d12: float
    L22: float
    d22: float
    L32: float
    d32: float
    L42: float
    d42: float
    L33: float
    d33: float
    L43: float
    d43: float
    L1: float
    L2: float
    LL: float
    dL: float
    q1_min: float
    q1_max: float
    q2_min: float
    q2_max: float

    def __post_init__(self):
        for f in fields(self):
            name = f.name
            v = getattr(self, name)
            label = f"ArmGeometry.{name}"
            if name.startswith("q"):
                # joint angles are modulo 2 pi: an interval must lie inside (-pi, pi)
                v = check_range(label, v, -math.pi, math.pi, lo_open=True, hi_open=True,
                                unit="rad")
            elif name.startswith("d"):
                v = check_range(label, v, -0.5, 0.5, unit="m")
            elif name in ("L1", "L2"):
                v = check_range(label, v, 0.0, 5.0, lo_open=True, unit="m")
            else:
                v = check_range(label, v, 0.0, 5.0, unit="m")
            object.__setattr__(self, name, v)
        for j in (1, 2):
            lo, hi = getattr(self, f"q{j}_min"), getattr(self, f"q{j}_max")
            if not lo < hi:
                raise ValueError(f"ArmGeometry: q{j}_min = {lo:g} rad must be smaller than "
                                 f"q{j}_max = {hi:g} rad (working area (2.6)-(2.7))")
        ranges = group_length_range(self)
        for k, (dmin, _) in enumerate(ranges):
            if not dmin > MIN_GROUP_LENGTH:
                flds = ", ".join(f"ArmGeometry.{n}" for n in GROUP_FIELDS[k + 1])
                raise ValueError(
                    f"ArmGeometry: muscle group {k + 1} has length {dmin:.3g} m somewhere in the "
                    f"working area (its two attachment points coincide); must stay above "
                    f"{MIN_GROUP_LENGTH:g} m.  Fields involved: {flds} and the working area "
                    f"q{1 if k < 2 else 2}_min/max")

    def replace(self, **changes) -> "ArmGeometry":
        """Return a copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            New values of fields of :class:`ArmGeometry`, by field name (as for
            :func:`dataclasses.replace`); the copy is checked like a newly
            constructed object.
        """
        return replace(self, **changes)


def group_lengths(geometry: ArmGeometry, q1, q2) -> np.ndarray:
    """Muscle group lengths d_1..d_4 (A.31)-(A.34) [m] at q1, q2 [rad] (numpy), shape (..., 4).

    Same attachment points (A.13)-(A.20) as the compiled
    :func:`ppamsafety.plant.geometry.group_points` (a test checks they agree); kept
    here in plain numpy so that parameter sets can be checked without the kernels.

    Parameters
    ----------
    geometry : ArmGeometry
        Attachment points and link length L1 [m].
    q1, q2 : array_like
        Joint angles [rad]; broadcast against each other.
    """
    g = geometry
    q1, q2 = np.broadcast_arrays(np.asarray(q1, float), np.asarray(q2, float))
    c1, s1, c12, s12 = np.cos(q1), np.sin(q1), np.cos(q1 + q2), np.sin(q1 + q2)
    sx, sy = g.L1 * c1, g.L1 * s1
    pts = (
        ((-g.X11, g.Y11), (c1 * g.L12 - s1 * g.d12, s1 * g.L12 + c1 * g.d12)),
        ((g.X21, -g.Y21), (c1 * g.L22 + s1 * g.d22, s1 * g.L22 - c1 * g.d22)),
        ((c1 * g.L32 - s1 * g.d32, s1 * g.L32 + c1 * g.d32),
         (sx + c12 * g.L33 - s12 * g.d33, sy + s12 * g.L33 + c12 * g.d33)),
        ((c1 * g.L42 + s1 * g.d42, s1 * g.L42 - c1 * g.d42),
         (sx + c12 * g.L43 + s12 * g.d43, sy + s12 * g.L43 - c12 * g.d43)),
    )
    return np.stack([np.hypot(bx - ax, by - ay) for (ax, ay), (bx, by) in pts], axis=-1)


@lru_cache(maxsize=128)
def group_length_range(geometry: ArmGeometry, n: int = 721) -> tuple:
    """(min, max) length of each muscle group over the working area [m], 4 pairs.

    Groups 1-2 depend on q1 only, groups 3-4 on q2 only (the relative angle), so
    one grid of ``n`` points per joint range suffices (the extremes of these
    smooth functions are found to about 1e-6 relative; used for validation).
    """
    g = geometry
    q1 = np.linspace(g.q1_min, g.q1_max, n)
    q2 = np.linspace(g.q2_min, g.q2_max, n)
    d1 = group_lengths(g, q1, 0.5 * (g.q2_min + g.q2_max))
    d2 = group_lengths(g, 0.5 * (g.q1_min + g.q1_max), q2)
    return tuple((float(d[:, k].min()), float(d[:, k].max()))
                 for k, d in ((0, d1), (1, d1), (2, d2), (3, d2)))


def thesis_geometry() -> ArmGeometry:
    """The arm as built (thesis Table 2.1, Table 2.2, eqs. (2.6)-(2.7))."""
    return ArmGeometry(
        X11=39.0 * MM, Y11=19.3 * MM, X21=26.7 * MM, Y21=24.1 * MM,
        L12=315.0 * MM, d12=30.0 * MM, L22=217.5 * MM, d22=30.0 * MM,
        L32=334.8 * MM, d32=19.0 * MM, L42=270.0 * MM, d42=0.0 * MM,
        L33=285.0 * MM, d33=30.0 * MM, L43=285.0 * MM, d43=30.0 * MM,
        L1=300.0 * MM, L2=310.0 * MM, LL=300.0 * MM, dL=30.0 * MM,
        q1_min=20.0 * DEG, q1_max=105.0 * DEG, q2_min=-130.0 * DEG, q2_max=-30.0 * DEG,
    )


__all__ = ["ArmGeometry", "thesis_geometry", "group_lengths", "group_length_range",
           "GROUP_FIELDS", "MIN_GROUP_LENGTH"]
