"""The arm's joint sensors as hardware: encoders, the timing board and their noise.

Source: thesis §2.4.5 (Agilent HEDM-6540 encoders, 2000 slots read x4: 8000 counts per
turn; velocity by inter-pulse timing with a 2 MHz clock and a 16-bit counter, readings
below 0.025 rad/s treated as zero, §2.4.5.3) and Table 3.2 (measured noise variances of
the first excitation signal).

This is *what the arm carries*: an arm file describes it (``[sensors]``), and the
simulated measurement (:class:`ppamsafety.control.sensors.SensorConfig`, which also
switches models on and off, seeds the noise and adds sensor faults) is built from it by
``SensorConfig.for_arm(arm)``.  With the thesis hardware (the default) every
simulation is bitwise what it was before the arm carried its sensors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from .._validation import check_int, check_range, check_vector

#: Encoder resolution of the thesis arm [rad]: 2000 slots with x4 decoding (§2.4.5.1).
THESIS_ENCODER_RESOLUTION = 2 * math.pi / 8000
#: Table 3.2, first excitation signal: variances of q1, q2 [rad^2].
TABLE_3_2_ANGLE_VARIANCES = (3.46e-6, 2.59e-6)
#: Table 3.2, first excitation signal: variances of qd1, qd2 [rad^2/s^2].
TABLE_3_2_VELOCITY_VARIANCES = (1.63e-4, 2.32e-5)
#: Table 3.2, first excitation signal: variances of q1, q2 [rad^2], qd1, qd2 [rad^2/s^2].
TABLE_3_2_VARIANCES = TABLE_3_2_ANGLE_VARIANCES + TABLE_3_2_VELOCITY_VARIANCES


@dataclass(frozen=True)
class SensorHardware:
    """Joint sensors of the arm (thesis §2.4.5, Table 3.2).

    Attributes
    ----------
    encoder_resolution : float
        Angle per encoder count [rad] (2 pi / 8000), in (0, pi/2].
    clock_hz : float
        Clock of the inter-pulse timing board [Hz] (2 MHz), in (0, 1e12].
    counter_bits : int
        Width of the pulse-interval counter (16), in [4, 32].
    dead_band : float
        Velocities below this magnitude read zero [rad/s] (0.025), in [0, 1000].
    angle_noise_variances : tuple of 2 float
        Variances of the measured q1, q2 [rad^2] (Table 3.2), each in [0, 1].
    velocity_noise_variances : tuple of 2 float
        Variances of the measured qd1, qd2 [rad^2/s^2] (Table 3.2), each in [0, 1e6].

    Notes
    -----
    The ranges are those of :class:`ppamsafety.control.sensors.SensorConfig`.
    """

    encoder_resolution: float = THESIS_ENCODER_RESOLUTION
    clock_hz: float = 2.0e6
    counter_bits: int = 16
    dead_band: float = 0.025
    angle_noise_variances: tuple = TABLE_3_2_ANGLE_VARIANCES
    velocity_noise_variances: tuple = TABLE_3_2_VELOCITY_VARIANCES

    def __post_init__(self):
        def put(name, value):
            object.__setattr__(self, name, value)
        put("encoder_resolution", check_range("SensorHardware.encoder_resolution",
                                              self.encoder_resolution, 0.0, math.pi / 2,
                                              lo_open=True, unit="rad"))
        put("clock_hz", check_range("SensorHardware.clock_hz", self.clock_hz, 0.0, 1e12,
                                    lo_open=True, unit="Hz"))
        put("counter_bits", check_int("SensorHardware.counter_bits", self.counter_bits, 4, 32))
        put("dead_band", check_range("SensorHardware.dead_band", self.dead_band, 0.0, 1e3,
                                     unit="rad/s"))
        put("angle_noise_variances", check_vector("SensorHardware.angle_noise_variances",
                                                  self.angle_noise_variances, 2, 0.0, 1.0,
                                                  unit="rad^2"))
        put("velocity_noise_variances", check_vector(
            "SensorHardware.velocity_noise_variances", self.velocity_noise_variances, 2, 0.0,
            1e6, unit="rad^2/s^2"))

    @property
    def noise_variances(self) -> tuple:
        """(q1, q2, qd1, qd2) variances as :class:`~ppamsafety.control.sensors.SensorConfig`
        takes them [rad^2, rad^2/s^2]."""
        return self.angle_noise_variances + self.velocity_noise_variances

    def replace(self, **changes) -> "SensorHardware":
        """Return a copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            New values of fields of :class:`SensorHardware`, by field name (as for
            :func:`dataclasses.replace`); the copy is checked like a newly
            constructed object.
        """
        return replace(self, **changes)


def thesis_sensors() -> SensorHardware:
    """The joint sensors of the thesis arm (§2.4.5, Table 3.2)."""
    return SensorHardware()


__all__ = ["SensorHardware", "thesis_sensors", "THESIS_ENCODER_RESOLUTION",
           "TABLE_3_2_ANGLE_VARIANCES", "TABLE_3_2_VELOCITY_VARIANCES"]
