"""Joint sensors: incremental encoders and the inter-pulse-timing velocity board.

Thesis §2.4.5:

* Encoders (Agilent HEDM-6540, 2000 slots, x4 decoding): the angle is known
  in steps of 2 pi/8000 rad = 0.045 deg; the reading is the count times the
  resolution.
* Velocity by inter-pulse timing (§2.4.5.3): a 2 MHz clock counts the time
  between the last two encoder edges, N_c; the velocity is
  Delta_q/(N_c T_c) with the sign of the last edge.  The 16-bit counter
  saturates at N_c,max = 2^16 - 1 (omega_min = 1.37 deg/s), the control
  board treats |omega| < 0.025 rad/s as zero (dead band), and the reading is
  held until the next edge arrives.
* Optional measurement noise with the variances of Table 3.2 (first
  excitation signal), drawn from a seeded generator so runs are repeatable.
* Optional sensor faults (issue 9), errors of the measurement, not of the
  plant: an encoder offset per joint (a wrong absolute reference: the
  incremental encoders only know angles relative to the index pulse passed
  in the initialisation procedure, §2.4.5.1), so the measured angle is
  quantised(q) + offset; and an offset and gain per pressure sensor
  (Sensortechnics HCX005D6V, 0.5-4.5 V over 5 bar, transformed by the glue
  electronics, §2.4.2, §2.4.6), so the measured pressure is
  gain p + offset.  The measured pressures go to the controllers (SMC uses
  them); the log keeps the true pressures.  On the real arm the valves
  regulate with the same sensors' signal (§2.4.3); that side of a
  pressure-sensor fault is a plant-truth valve offset/gain
  (``Effects.valve_offset`` / ``valve_gain``, (3.12)) and is set there if
  wanted.  With every fault at its default (offset 0, gain 1) the packed
  flag is ``SensorFaults.OFF`` and the kernels skip the arithmetic (bitwise
  nominal).

In the closed loop the plant is integrated in sub-steps; the encoder edge
times inside a sub-step are found by linear interpolation of the angle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from .._jit import kernel, step_kernel
from .._validation import check_bool, check_int, check_range, check_vector
from ..layouts import Field, Layout, check_flag
from ..params.sensors import SensorHardware, TABLE_3_2_VARIANCES  # noqa: F401 (re-exported)
from ..units import BAR


class EncoderMode(IntEnum):
    """Angle measurement: exact angle or encoder quantisation."""

    OFF = 0
    ON = 1


class SensorFaults(IntEnum):
    """Sensor faults: off (ideal calibration) or on (offsets/gains applied)."""

    OFF = 0
    ON = 1


class VelocitySource(IntEnum):
    """Velocity measurement: exact velocity or the inter-pulse-timing board."""

    IDEAL = 0
    IPT = 1


#: Largest pressure-sensor offset fault [Pa] (as the valve offsets, §3.5.1.2).
PRESSURE_OFFSET_MAX = 0.5 * BAR
#: Range of the pressure-sensor gain fault [-] (as the valve gains).
PRESSURE_GAIN_RANGE = (0.5, 1.5)

#: Time of an edge never seen [s] (far in the past: the counter has overflowed).
T_NEVER = -1.0e9

#: Sensor state of both joints (per joint j: offset + j).
SENSOR_STATE = Layout("sensor state", [
    Field("count", 2, "-", "encoder counts"),
    Field("t_last", 2, "s", "time of the last encoder edge", default=T_NEVER),
    Field("t_prev", 2, "s", "time of the second-to-last encoder edge", default=T_NEVER),
    Field("direction", 2, "-", "sign of the last edge (+1/-1)"),
    Field("reading", 2, "rad/s", "velocity reading held by the timing board"),
    Field("n_pulse", 2, "-", "number of edges seen"),
])
S_COUNT, S_TLAST, S_TPREV, S_DIR, S_READ, S_NPULSE = SENSOR_STATE.offsets(
    "count", "t_last", "t_prev", "direction", "reading", "n_pulse")
NSENSOR = SENSOR_STATE.size

#: Packed sensor configuration (:meth:`SensorConfig.pack`).
SENSOR_CONFIG = Layout("sensor configuration", [
    Field("resolution", 1, "rad", "encoder resolution (2 pi / 8000)"),
    Field("clock_period", 1, "s", "timing-board clock period T_c = 1/clock_hz"),
    Field("n_max", 1, "-", "largest pulse-interval count 2^bits - 1"),
    Field("dead_band", 1, "rad/s", "velocities below this read zero"),
    Field("encoder", 1, "code", "EncoderMode: quantise the angles"),
    Field("velocity", 1, "code", "VelocitySource: ideal or inter-pulse timing"),
    Field("faults", 1, "code", "SensorFaults: apply the offsets and gains below"),
    Field("encoder_offset", 2, "rad", "offset added to the measured angles (index error, "
          "§2.4.5.1)"),
    Field("pressure_offset", 4, "Pa", "offset of the measured gauge pressures (§2.4.2)"),
    Field("pressure_gain", 4, "-", "gain of the measured gauge pressures (§2.4.2)",
          default=1.0),
])
C_RES, C_TC, C_NMAX, C_DEAD, C_ENC, C_VEL = SENSOR_CONFIG.offsets(
    "resolution", "clock_period", "n_max", "dead_band", "encoder", "velocity")
C_FAULTS, C_QOFF, C_POFF, C_PGAIN = SENSOR_CONFIG.offsets(
    "faults", "encoder_offset", "pressure_offset", "pressure_gain")
NSCFG = SENSOR_CONFIG.size

#: One sample of measurement noise (:meth:`SensorConfig.noise_samples` rows).
SENSOR_NOISE = Layout("sensor noise sample", [
    Field("q", 2, "rad", "noise added to the measured angles"),
    Field("qd", 2, "rad/s", "noise added to the measured velocities"),
])
N_Q, N_QD = SENSOR_NOISE.offsets("q", "qd")


@dataclass(frozen=True)
class SensorConfig:
    """Sensor models of the arm; each effect can be switched off.

    Attributes
    ----------
    encoder : bool
        Quantise the measured angles to ``resolution`` (else exact angles).
    velocity : str
        ``"ipt"`` (inter-pulse timing board) or ``"ideal"`` (true velocity).
    noise : bool
        Add zero-mean Gaussian noise with ``noise_variances`` to q and qd.
    seed : int
        Seed of the noise generator, in [0, 2^63 - 1].
    resolution : float
        Encoder resolution [rad] (2 pi / 8000), in (0, pi/2].
    clock_hz : float
        Timing-board clock [Hz] (2 MHz), in (0, 1e12].
    counter_bits : int
        Width of the pulse-interval counter (16), in [4, 32].
    dead_band : float
        Velocities below this magnitude read zero [rad/s] (0.025), in [0, 1000].
    noise_variances : tuple of 4 float
        Variances of q1, q2 [rad^2] and qd1, qd2 [rad^2/s^2] (Table 3.2).
    encoder_offset : tuple of 2 float
        Sensor fault: offset added to the measured angles [rad], in
        [-pi, pi] (a wrong index reference, §2.4.5.1); default (0, 0).
    pressure_offset : tuple of 4 float
        Sensor fault: offset of the measured gauge pressures [Pa], in
        [-0.5, 0.5] bar (§2.4.2; the valves' own offsets reach 0.1 bar,
        §3.5.1.2); default zeros.
    pressure_gain : tuple of 4 float
        Sensor fault: gain of the measured gauge pressures [-], in [0.5, 1.5];
        default ones.  Measured pressure = gain p + offset.

    Raises
    ------
    TypeError, ValueError
        For a field of the wrong type or out of range (naming the field).
    """

    encoder: bool = True
    velocity: str = "ipt"
    noise: bool = False
    seed: int = 0
    resolution: float = 2 * math.pi / 8000
    clock_hz: float = 2.0e6
    counter_bits: int = 16
    dead_band: float = 0.025
    noise_variances: tuple = TABLE_3_2_VARIANCES
    encoder_offset: tuple = (0.0, 0.0)
    pressure_offset: tuple = (0.0, 0.0, 0.0, 0.0)
    pressure_gain: tuple = (1.0, 1.0, 1.0, 1.0)

    def __post_init__(self):
        def put(name, value):
            object.__setattr__(self, name, value)
        put("encoder", check_bool("SensorConfig.encoder", self.encoder))
        code = check_flag(VelocitySource, self.velocity, "SensorConfig.velocity")
        put("velocity", VelocitySource(code).name.lower())
        put("noise", check_bool("SensorConfig.noise", self.noise))
        put("seed", check_int("SensorConfig.seed", self.seed, 0, 2 ** 63 - 1))
        # at most a quarter turn per encoder step, at most 1 THz clock
        put("resolution", check_range("SensorConfig.resolution", self.resolution, 0.0,
                                      math.pi / 2, lo_open=True, unit="rad"))
        put("clock_hz", check_range("SensorConfig.clock_hz", self.clock_hz, 0.0, 1e12,
                                    lo_open=True, unit="Hz"))
        put("counter_bits", check_int("SensorConfig.counter_bits", self.counter_bits, 4, 32))
        put("dead_band", check_range("SensorConfig.dead_band", self.dead_band, 0.0, 1e3,
                                     unit="rad/s"))
        # standard deviations of at most 1 rad and 1000 rad/s
        put("noise_variances", check_vector("SensorConfig.noise_variances",
                                            self.noise_variances, 4, 0.0, 1e6))
        for name, n, lo, hi, unit in (
                ("encoder_offset", 2, -math.pi, math.pi, "rad"),
                ("pressure_offset", 4, -PRESSURE_OFFSET_MAX, PRESSURE_OFFSET_MAX, "Pa"),
                ("pressure_gain", 4, PRESSURE_GAIN_RANGE[0], PRESSURE_GAIN_RANGE[1], "")):
            put(name, check_vector(f"SensorConfig.{name}", getattr(self, name), n, lo, hi,
                                   unit=unit))

    @property
    def faults(self) -> bool:
        """True if a sensor fault is set (an offset != 0 or a gain != 1)."""
        return (any(v != 0.0 for v in self.encoder_offset + self.pressure_offset)
                or any(v != 1.0 for v in self.pressure_gain))

    @classmethod
    def for_arm(cls, arm, **options) -> "SensorConfig":
        """The sensor models of the hardware ``arm`` carries (``arm.sensors``).

        Parameters
        ----------
        arm : ppamsafety.params.ArmParameters
            Its :class:`~ppamsafety.params.sensors.SensorHardware` gives
            ``resolution``, ``clock_hz``, ``counter_bits``, ``dead_band`` and
            ``noise_variances`` (the thesis arm: the defaults of this class).
        **options
            Other fields of :class:`SensorConfig` (``encoder``, ``velocity``,
            ``noise``, ``seed``, faults), or hardware fields to override.

        Returns
        -------
        SensorConfig
        """
        hw = getattr(arm, "sensors", None)
        if not isinstance(hw, SensorHardware):
            raise TypeError(f"arm must be an ArmParameters (with .sensors), got "
                            f"{type(arm).__name__}")
        kw = dict(resolution=hw.encoder_resolution, clock_hz=hw.clock_hz,
                  counter_bits=hw.counter_bits, dead_band=hw.dead_band,
                  noise_variances=hw.noise_variances)
        kw.update(options)
        return cls(**kw)

    @classmethod
    def ideal(cls) -> "SensorConfig":
        """Exact angles and velocities, no noise."""
        return cls(encoder=False, velocity="ideal", noise=False)

    @property
    def min_velocity(self) -> float:
        """Smallest non-zero velocity the timing board can report [rad/s]."""
        return self.resolution * self.clock_hz / (2 ** self.counter_bits - 1)

    def pack(self) -> np.ndarray:
        """Configuration row for the kernels (layout ``SENSOR_CONFIG``)."""
        return SENSOR_CONFIG.pack(
            resolution=self.resolution, clock_period=1.0 / self.clock_hz,
            n_max=2.0 ** self.counter_bits - 1, dead_band=self.dead_band,
            encoder=int(EncoderMode.ON if self.encoder else EncoderMode.OFF),
            velocity=check_flag(VelocitySource, self.velocity, "SensorConfig.velocity"),
            faults=int(SensorFaults.ON if self.faults else SensorFaults.OFF),
            encoder_offset=self.encoder_offset, pressure_offset=self.pressure_offset,
            pressure_gain=self.pressure_gain)

    def noise_samples(self, n_steps: int) -> np.ndarray:
        """Noise to add to (q1, q2, qd1, qd2) at each of ``n_steps`` samples, shape (n, 4).

        Columns: layout ``SENSOR_NOISE``.

        Parameters
        ----------
        n_steps : int
            Number of samples, in [0, 1e9].

        Returns
        -------
        numpy.ndarray, shape (n_steps, 4)
            Zeros if ``noise`` is off.
        """
        n_steps = check_int("n_steps", n_steps, 0, 10 ** 9)
        if not self.noise:
            return np.zeros((n_steps, 4))
        rng = np.random.default_rng(self.seed)
        return rng.normal(size=(n_steps, 4)) * np.sqrt(np.asarray(self.noise_variances))


def initial_sensor_state(q0) -> np.ndarray:
    """Sensor state (``SENSOR_STATE``) for an arm at rest in ``q0``: no pulses seen yet.

    The counts are set by :func:`sensor_init`.

    Parameters
    ----------
    q0 : array_like, shape (2,)
        Initial angles [rad] (unused: the counts are set by :func:`sensor_init`).

    Returns
    -------
    numpy.ndarray
        The empty sensor state.
    """
    return SENSOR_STATE.empty()


@kernel
def sensor_reset(st):
    """Reset the sensor state ``st`` in place: no pulses seen (see :func:`initial_sensor_state`).

    Parameters
    ----------
    st : numpy.ndarray
        Sensor state (layout ``SENSOR_STATE``), overwritten.
    """
    st[:] = 0.0
    for j in range(2):
        st[S_TLAST + j] = T_NEVER
        st[S_TPREV + j] = T_NEVER


@kernel
def encoder_count(q, res):
    """Encoder count of angle ``q`` [rad] (floor of q/resolution).

    Parameters
    ----------
    q : float
        Joint angle [rad].
    res : float
        Encoder resolution [rad] (2 pi/8000), > 0.

    Returns
    -------
    float
        floor(q/res), an integer count stored as a float.
    """
    return math.floor(q / res)


@kernel
def sensor_init(q1, q2, cfg, st):
    """Set the counts of the sensor state ``st`` to the angles (q1, q2).

    Parameters
    ----------
    q1, q2 : float
        Joint angles [rad].
    cfg : numpy.ndarray
        Sensor configuration row (layout ``SENSOR_CONFIG``; the resolution
        [rad] is read).
    st : numpy.ndarray
        Sensor state of both joints (layout ``SENSOR_STATE``); its ``count``
        field is written, the rest is left as it is.
    """
    st[S_COUNT] = encoder_count(q1, cfg[C_RES])
    st[S_COUNT + 1] = encoder_count(q2, cfg[C_RES])


@step_kernel
def sensor_track(j, q_old, q_new, t_old, h, cfg, st):
    """Register the encoder edges of joint ``j`` while q moves q_old -> q_new in [t_old, t_old + h].

    Edge times are linearly interpolated inside the interval.  Updates the
    count, the last two edge times, the direction and the held velocity
    reading of the timing board.

    Parameters
    ----------
    j : int
        Joint index, 0 or 1.
    q_old, q_new : float
        Angle of joint ``j`` at the start and end of the sub-step [rad].
    t_old : float
        Time at the start of the sub-step [s].
    h : float
        Sub-step length [s], > 0.
    cfg : numpy.ndarray
        Sensor configuration row (layout ``SENSOR_CONFIG``: resolution
        [rad], clock period T_c [s], N_c,max, dead band [rad/s]).
    st : numpy.ndarray
        Sensor state of both joints (layout ``SENSOR_STATE``, per joint
        ``offset + j``), updated in place when an edge is crossed.
    """
    res = cfg[C_RES]
    c_new = encoder_count(q_new, res)
    c_old = st[S_COUNT + j]
    if c_new == c_old:
        return
    d = 1.0 if c_new > c_old else -1.0
    dq = q_new - q_old
    # last and second-to-last crossed levels
    lvl_last = c_new * res if d > 0 else (c_new + 1.0) * res
    t_last = t_old + h * (lvl_last - q_old) / dq
    m = abs(c_new - c_old)
    if m >= 2:
        t_prev = t_old + h * (lvl_last - d * res - q_old) / dq
    else:
        t_prev = st[S_TLAST + j]
    st[S_COUNT + j] = c_new
    st[S_TPREV + j] = t_prev
    st[S_TLAST + j] = t_last
    st[S_DIR + j] = d
    st[S_NPULSE + j] += m
    nc = float(math.floor((t_last - t_prev) / cfg[C_TC] + 0.5))
    nc = min(max(nc, 1.0), cfg[C_NMAX])
    w = res / (nc * cfg[C_TC])
    st[S_READ + j] = d * w if w >= cfg[C_DEAD] else 0.0


@step_kernel
def sensor_track_joints(q1_old, q2_old, q1_new, q2_new, t_old, h, cfg, st):
    """:func:`sensor_track` of joint 1, then of joint 2, over one sub-step.

    The joint index is not a compile-time constant here, so one compiled
    :func:`sensor_track` serves both joints (numba compiles a kernel once per distinct
    constant argument).

    Parameters
    ----------
    q1_old, q2_old : float
        Angles of joints 1 and 2 at the start of the sub-step [rad].
    q1_new, q2_new : float
        Their angles at the end of the sub-step [rad].
    t_old : float
        Time at the start of the sub-step [s].
    h : float
        Sub-step length [s], > 0.
    cfg : numpy.ndarray
        Sensor configuration row (layout ``SENSOR_CONFIG``).
    st : numpy.ndarray
        Sensor state of both joints (layout ``SENSOR_STATE``), updated in place.
    """
    for j in range(2):
        sensor_track(j, q1_old if j == 0 else q2_old, q1_new if j == 0 else q2_new, t_old, h,
                     cfg, st)


@step_kernel
def sensor_read(j, q_true, qd_true, t, cfg, st):
    """Measured (angle, velocity) of joint ``j`` at sample time ``t``.

    Noise (:meth:`SensorConfig.noise_samples`) is not added here.

    Parameters
    ----------
    j : int
        Joint index, 0 or 1.
    q_true, qd_true : float
        True angle [rad] and velocity [rad/s] of joint ``j``, returned when
        the encoder / velocity board is off.
    t : float
        Sample time [s] (for the counter-overflow test of the timing board).
    cfg : numpy.ndarray
        Sensor configuration row (layout ``SENSOR_CONFIG``), read only.
    st : numpy.ndarray
        Sensor state of both joints (layout ``SENSOR_STATE``), read only.

    Returns
    -------
    tuple of float
        Measured angle [rad] (with the encoder-offset fault, if on) and
        velocity [rad/s].
    """
    qm = st[S_COUNT + j] * cfg[C_RES] if int(cfg[C_ENC]) == EncoderMode.ON else q_true
    if int(cfg[C_FAULTS]) == SensorFaults.ON:
        qm = qm + cfg[C_QOFF + j]
    if int(cfg[C_VEL]) != VelocitySource.IPT:
        return qm, qd_true
    # counter overflow: no edge for N_max clock periods -> minimum velocity, dead-banded
    if t - st[S_TLAST + j] > cfg[C_NMAX] * cfg[C_TC]:
        w = cfg[C_RES] / (cfg[C_NMAX] * cfg[C_TC])
        return qm, st[S_DIR + j] * w if w >= cfg[C_DEAD] else 0.0
    return qm, st[S_READ + j]


@step_kernel
def pressure_read(p, po, cfg, out):
    """Measured gauge pressures (4) [Pa] of true pressures ``p[po:po + 4]`` into ``out``.

    ``gain_i p_i + offset_i`` with the sensor faults on, else a copy.  The pressures are
    given as an array and an offset (the plant state and the offset of its pressures), not
    as a view: a view costs two atomic reference-count updates per call in compiled code.

    Parameters
    ----------
    p : float64[:]
        Holds the true gauge pressures (4) [Pa] from ``po``.
    po : int
        Offset of the pressures in ``p``.
    cfg : float64[:]
        Sensor configuration row (``SENSOR_CONFIG``).
    out : float64[:]
        Measured pressures (4) [Pa], written.
    """
    if int(cfg[C_FAULTS]) == SensorFaults.ON:
        for i in range(4):
            out[i] = cfg[C_PGAIN + i] * p[po + i] + cfg[C_POFF + i]
    else:
        for i in range(4):
            out[i] = p[po + i]
