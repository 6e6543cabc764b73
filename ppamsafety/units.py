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
