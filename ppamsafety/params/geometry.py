"""Arm geometry: link lengths, muscle attachment points and the working area.

Source: thesis §2.3, Table 2.1 (attachment points), Table 2.2 (load point,
link lengths), eqs. (2.6)-(2.7) (working area), fig. 2.9 / A.1 (definitions).
All lengths are stored in metres and angles in radians; the thesis values in
millimetres and degrees are converted here, at the boundary.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

from .._validation import check_range, check_nonnegative
from ..units import DEG, MM


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
        Working area (2.6)-(2.7) [rad].
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
            if name.startswith("q"):
                check_range(f"ArmGeometry.{name}", v, -3.2, 3.2, unit="rad")
            elif name.startswith("d"):
                check_range(f"ArmGeometry.{name}", v, -0.5, 0.5, unit="m")
            elif name in ("L1", "L2"):
                check_range(f"ArmGeometry.{name}", v, 0.0, 5.0, lo_open=True, unit="m")
            else:
                check_range(f"ArmGeometry.{name}", v, 0.0, 5.0, unit="m")
        if not self.q1_min < self.q1_max:
            raise ValueError("ArmGeometry: q1_min must be smaller than q1_max")
        if not self.q2_min < self.q2_max:
            raise ValueError("ArmGeometry: q2_min must be smaller than q2_max")
        check_nonnegative("ArmGeometry.L33", self.L33, unit="m")

    def replace(self, **changes) -> "ArmGeometry":
        """Return a copy with some fields changed (validated again)."""
        return replace(self, **changes)


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


__all__ = ["ArmGeometry", "thesis_geometry"]
