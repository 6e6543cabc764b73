"""ISO/TS 15066:2016 Annex A body-model values for the head (power and force limiting).

ISO/TS 15066:2016 "Robots and robotic devices -- Collaborative robots" is a
*technical specification*, not a standard: its Annex A (informative) gives
biomechanical limits per body region for quasi-static contact (clamping) and
transient contact (free impact), an effective spring constant K and an
effective mass m_H per region, and a two-body energy-transfer model.  Its
pressure limits are the 75th percentile of pain-onset pressures measured on
100 healthy adults at 29 body locations in a single study (University of
Mainz); its force limits come from a literature review (188 sources) on the
lowest energy transfer giving a minor injury (AIS 1, e.g. a bruise).  The TS
itself says further studies may change the values.

Values used here (SI units inside; the TS quotes N, N/cm^2, N/mm, kg):

=================  =======  ==========  ==========  ======  ========
region             F_qs [N] p_qs        K [N/mm]    m_H     transient
                            [N/cm^2]                [kg]    factor
=================  =======  ==========  ==========  ======  ========
skull/forehead     130      130 (1)     150         4.4     2 (*)
face               65       110 (3)     75          4.4     2 (*)
=================  =======  ==========  ==========  ======  ========

(1) middle of forehead (body location 1; the temple, location 2, is 110);
(3) masticatory muscle (body location 3).

Confirmation status (searched 2026-11 in the stored public pages; the TS text
itself is not available here):

* confirmed: K = 150 N/mm (skull/forehead) and 75 N/mm (face) (Table A.2/A.3
  as reproduced by a cobot-safety reference page); the robot effective mass
  m_R = M/2 + m_L (Annex A.4) and the transient force multiplier 2
  ("at least 2x quasi-static", Table A.2 footnote) as used by a public ISO
  10218-2:2025 Annex A PFL calculator; the Mainz pain study as the origin of
  the pressure values (quoted German translation of the TS);
* **not confirmed** (taken from our reading of ISO/TS 15066:2016 Table A.2 and
  A.3, flagged in :attr:`BodyRegion.unconfirmed`): the force limits 130 N and
  65 N, the pressures 130 and 110 N/cm^2, the head effective mass 4.4 kg, and
  -- important -- whether Table A.2 gives a transient multiplier for the head
  at all.  Our reading is that it does **not** (transient contact with the
  head regions is "not applicable"), so the factor 2 applied here follows the
  issue's brief and the other body regions; every verdict is also given
  against the quasi-static force (factor 1), the conservative reading.

Two-body model of Annex A (implemented in :mod:`ppamsafety.impact.pfl`):
E = F^2/(2k) = A^2 p^2/(2k), E = mu v_rel^2 / 2 with
mu = (1/m_H + 1/m_R)^-1, hence v_rel,max = F_max / sqrt(mu k).
"""

from __future__ import annotations

from dataclasses import dataclass

from .._validation import check_range, check_str

#: Citation of the Annex used by every value of this module.
SOURCE = "ISO/TS 15066:2016, Annex A (informative), Tables A.2 and A.3"

#: Total moving mass of the thesis arm [kg]: "its total mass of around 2.5 kg" (thesis §6.3.5;
#: links about 1.5 kg and just over 1 kg, §3.5).
THESIS_ARM_MASS = 2.5


@dataclass(frozen=True)
class BodyRegion:
    """ISO/TS 15066 Annex A limits and body-model values of one body region.

    Attributes
    ----------
    name : str
        Region label.
    force_quasi_static : float
        Maximum permissible quasi-static contact force F_qs [N], in (0, 1e4].
    pressure_quasi_static : float
        Maximum permissible quasi-static pressure p_qs [Pa], in (0, 1e8]
        (1 N/cm^2 = 1e4 Pa).
    transient_factor : float
        Multiplier of F_qs and p_qs for transient contact [-], in [1, 10].
    spring_constant : float
        Effective spring constant K of the region [N/m], in (0, 1e9].
    effective_mass : float
        Effective mass m_H of the body region [kg], in (0, 200].
    source : str
        Citation (table, clause).
    unconfirmed : tuple of str
        Names of the fields whose values could not be confirmed against a
        stored source (see the module docstring).

    Notes
    -----
    The transient limits are :attr:`force_transient` = factor x F_qs and
    :attr:`pressure_transient` = factor x p_qs.
    """

    name: str
    force_quasi_static: float
    pressure_quasi_static: float
    transient_factor: float
    spring_constant: float
    effective_mass: float
    source: str = SOURCE
    unconfirmed: tuple = ()

    def __post_init__(self):
        check_str("BodyRegion.name", self.name, allow_empty=False)
        check_str("BodyRegion.source", self.source)
        for field, lo, hi, lo_open, unit in (
                ("force_quasi_static", 0.0, 1e4, True, "N"),
                ("pressure_quasi_static", 0.0, 1e8, True, "Pa"),
                ("transient_factor", 1.0, 10.0, False, "-"),
                ("spring_constant", 0.0, 1e9, True, "N/m"),
                ("effective_mass", 0.0, 200.0, True, "kg")):
            object.__setattr__(self, field, check_range(
                f"BodyRegion.{field} (region {self.name!r})", getattr(self, field), lo, hi,
                lo_open=lo_open, unit=unit))
        if isinstance(self.unconfirmed, (str, bytes)) or not hasattr(self.unconfirmed, "__iter__"):
            raise TypeError(f"BodyRegion.unconfirmed must be a tuple of field names, got "
                            f"{self.unconfirmed!r}")
        unc = tuple(self.unconfirmed)
        fields = {"force_quasi_static", "pressure_quasi_static", "transient_factor",
                  "spring_constant", "effective_mass"}
        bad = [u for u in unc if u not in fields]
        if bad:
            raise ValueError(f"BodyRegion.unconfirmed = {unc!r}: {bad} are not fields; allowed "
                             f"{sorted(fields)}")
        object.__setattr__(self, "unconfirmed", unc)

    @property
    def force_transient(self) -> float:
        """Maximum permissible transient contact force [N]: factor x F_qs."""
        return self.transient_factor * self.force_quasi_static

    @property
    def pressure_transient(self) -> float:
        """Maximum permissible transient pressure [Pa]: factor x p_qs."""
        return self.transient_factor * self.pressure_quasi_static


#: N/cm^2 in Pa.
N_PER_CM2 = 1.0e4
#: N/mm in N/m.
N_PER_MM = 1.0e3

SKULL_FOREHEAD = BodyRegion(
    name="skull/forehead", force_quasi_static=130.0, pressure_quasi_static=130.0 * N_PER_CM2,
    transient_factor=2.0, spring_constant=150.0 * N_PER_MM, effective_mass=4.4,
    source=f"{SOURCE}: body region 1 skull and forehead (location 1, middle of forehead)",
    unconfirmed=("force_quasi_static", "pressure_quasi_static", "transient_factor",
                 "effective_mass"))

FACE = BodyRegion(
    name="face", force_quasi_static=65.0, pressure_quasi_static=110.0 * N_PER_CM2,
    transient_factor=2.0, spring_constant=75.0 * N_PER_MM, effective_mass=4.4,
    source=f"{SOURCE}: body region 2 face (location 3, masticatory muscle)",
    unconfirmed=("force_quasi_static", "pressure_quasi_static", "transient_factor",
                 "effective_mass"))

_REGIONS = {r.name: r for r in (SKULL_FOREHEAD, FACE)}


def body_region(name: str) -> BodyRegion:
    """A named head region of ISO/TS 15066 Annex A: one of :func:`body_region_names`.

    Parameters
    ----------
    name : str
        ``"skull/forehead"`` or ``"face"``.

    Returns
    -------
    BodyRegion
    """
    check_str("name", name)
    if name not in _REGIONS:
        raise ValueError(f"name = {name!r}: unknown body region; choose from {sorted(_REGIONS)}")
    return _REGIONS[name]


def body_region_names() -> list:
    """Names accepted by :func:`body_region`."""
    return sorted(_REGIONS)


__all__ = ["BodyRegion", "SKULL_FOREHEAD", "FACE", "body_region", "body_region_names",
           "THESIS_ARM_MASS", "SOURCE", "N_PER_CM2", "N_PER_MM"]
