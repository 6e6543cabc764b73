"""Unit conversion constants.

Everything inside :mod:`ppamsafety` is SI (m, kg, s, rad, Pa, N).  The thesis
quotes bar, mm and degrees; convert **at the boundary** where a parameter is
defined, by multiplying with the constants below::

    >>> from ppamsafety.units import BAR, MM, DEG
    >>> 3 * BAR          # 3 bar in Pa
    300000.0
    >>> 315.0 * MM       # 315 mm in m
    0.315
"""

import math

#: One bar in pascal (the thesis uses 1 bar = 100 kPa).
BAR = 1.0e5
#: One millimetre in metre.
MM = 1.0e-3
#: One centimetre in metre.
CM = 1.0e-2
#: One degree in radian.
DEG = math.pi / 180.0
#: Standard gravity in m/s^2 (3rd CGPM, 1901; exact by definition), the unit
#: "g" of head accelerations and of the HIC.  The arm's own gravitational
#: acceleration is a plant parameter (:attr:`ArmParameters.gravity`, the
#: thesis's 9.81 m/s^2) and is not this constant.
G0 = 9.80665
#: Standard atmospheric pressure in Pa (the thesis uses 1.013 bar).
P_ATM = 1.013 * BAR


# ----------------------------------------------------------------------------- unit names
#: The units a parameter file accepts for each SI unit the toolkit uses, with the factor
#: that converts a value in that unit to SI (``value_si = value * factor``).  Files written
#: by the toolkit always use the SI spelling (the first key); a user's file may use any of
#: these, e.g. ``l0 = {value = 60, unit = "mm"}``.  Spellings are compared after removing
#: spaces, ``*``, ``·`` and ``^`` (``"kg m^2"`` = ``"kg*m2"``), case-sensitively (``mPa``
#: is not ``MPa``).  No other unit is guessed or parsed: an unknown unit is an error that
#: lists these.
UNIT_ALIASES = {
    "m": {"m": 1.0, "mm": MM, "cm": CM},
    "rad": {"rad": 1.0, "deg": DEG},
    "rad/s": {"rad/s": 1.0, "deg/s": DEG},
    "kg": {"kg": 1.0, "g": 1.0e-3},
    "s": {"s": 1.0, "ms": 1.0e-3},
    "Pa": {"Pa": 1.0, "kPa": 1.0e3, "MPa": 1.0e6, "bar": BAR, "mbar": 1.0e-3 * BAR,
           "N/cm^2": 1.0e4, "N/mm^2": 1.0e6},
    "N": {"N": 1.0, "kN": 1.0e3},
    "N/m": {"N/m": 1.0, "N/mm": 1.0e3, "kN/m": 1.0e3},
    "m/s": {"m/s": 1.0, "mm/s": 1.0e-3},
    "N m/rad": {"N m/rad": 1.0, "Nm/rad": 1.0},
    "Hz": {"Hz": 1.0, "kHz": 1.0e3, "MHz": 1.0e6},
    "m/s^2": {"m/s^2": 1.0},
    "N/Pa": {"N/Pa": 1.0, "m^2": 1.0, "N/bar": 1.0 / BAR},
    "N m": {"N m": 1.0},
    "N m s/rad": {"N m s/rad": 1.0},
    "kg m": {"kg m": 1.0},
    "kg m^2": {"kg m^2": 1.0},
    "rad^2": {"rad^2": 1.0},
    "rad^2/s^2": {"rad^2/s^2": 1.0},
}


def _unit_key(unit: str) -> str:
    return "".join(c for c in unit if c not in " *·^")


def si_factor(unit, si_unit: str, *, name: str = "unit") -> float:
    """Factor converting a value given in ``unit`` to the SI unit ``si_unit``.

    Parameters
    ----------
    unit : str
        The unit a file gives (one of ``UNIT_ALIASES[si_unit]``, spelled with or
        without spaces, ``*`` and ``^``).
    si_unit : str
        The SI unit of the quantity (a key of :data:`UNIT_ALIASES`).
    name : str
        What to call the unit in an error message (e.g. the dotted key).

    Returns
    -------
    float
        ``value_si = value * factor``.

    Raises
    ------
    TypeError
        If ``unit`` is not a string.
    ValueError
        If ``unit`` is not accepted for ``si_unit`` (the message lists what is).
    """
    if not isinstance(unit, str):
        raise TypeError(f"{name} must be a unit string such as {si_unit!r}, got {unit!r}")
    accepted = UNIT_ALIASES.get(si_unit, {si_unit: 1.0})
    key = _unit_key(unit)
    for spelling, factor in accepted.items():
        if _unit_key(spelling) == key:
            return factor
    raise ValueError(f"{name} = {unit!r} is not a unit of this quantity: give {si_unit!r} (SI)"
                     + (f" or one of {[u for u in accepted if u != si_unit]}"
                        if len(accepted) > 1 else ""))
