"""Pneumatic operating point: mean pressures, limits, polytropic exponent.

Sources: thesis §3.3 (polytropic coupling (3.3)-(3.6), n = 1.4 isentropic
limit, P_atm), §3.3.1 (Delta-p approach (3.7)), §2.2.2 (3 bar working limit,
PPAM tolerates 4 bar).

The mean pressures p_m are not given in the thesis.  They are calibrated by
:func:`ppamsafety.plant.pneumatics.calibrate_mean_pressures` so that the joint
stiffness (2.18) at the step-response impact configuration q = (50 deg,
-80 deg), with static gravity-compensation pressures, is K1 = 43 Nm/rad and
K2 = 27 Nm/rad (thesis §6.3.3).  The values stored in :func:`thesis_pneumatics`
are the output of that calibration for the thesis arm; a test re-runs the
calibration and checks they agree.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from .._validation import check_range, check_vector
from ..units import BAR, P_ATM


@dataclass(frozen=True)
class PneumaticParams:
    """Pressure operating point and gas model.

    Attributes
    ----------
    p_mean : tuple of 2 float
        Mean gauge pressure p_m of the antagonistic pair of joint 1 and 2 [Pa].
    p_max : float
        Maximum gauge pressure; commanded pressures are clipped to
        [0, p_max] [Pa].
    p_atm : float
        Atmospheric pressure [Pa].
    polytropic_n : float
        Polytropic exponent n of (3.3), 1 (isothermal) to 1.4 (isentropic
        air); up to 1.67 (monatomic gas) is accepted.

    Ranges: ``p_max`` in (0, 6] bar (PPAMs tolerate 4 bar, §2.2.2; 6 bar
    is the industrial supply), ``p_mean`` in [0, p_max], ``p_atm`` in
    [0.5, 1.5] bar.
    """

    p_mean: tuple
    p_max: float = 3.0 * BAR
    p_atm: float = P_ATM
    polytropic_n: float = 1.4

    def __post_init__(self):
        object.__setattr__(self, "p_max", check_range("PneumaticParams.p_max", self.p_max, 0.0,
                                                      6.0 * BAR, lo_open=True, unit="Pa"))
        object.__setattr__(self, "p_mean", check_vector("PneumaticParams.p_mean", self.p_mean, 2,
                                                        0.0, self.p_max, unit="Pa"))
        object.__setattr__(self, "p_atm", check_range("PneumaticParams.p_atm", self.p_atm,
                                                      0.5 * BAR, 1.5 * BAR, unit="Pa"))
        object.__setattr__(self, "polytropic_n", check_range("PneumaticParams.polytropic_n",
                                                             self.polytropic_n, 1.0, 1.67))

    def replace(self, **changes) -> "PneumaticParams":
        """Return a copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            New values of fields of :class:`PneumaticParams`, by field name (as for
            :func:`dataclasses.replace`); the copy is checked like a newly
            constructed object.
        """
        return replace(self, **changes)


#: Calibrated mean pressures [Pa] (output of calibrate_mean_pressures, see module doc).
CALIBRATED_P_MEAN = (1.658 * BAR, 1.762 * BAR)


def thesis_pneumatics() -> PneumaticParams:
    """Operating point of the thesis arm with calibrated mean pressures."""
    return PneumaticParams(p_mean=CALIBRATED_P_MEAN)


__all__ = ["PneumaticParams", "thesis_pneumatics", "CALIBRATED_P_MEAN"]
