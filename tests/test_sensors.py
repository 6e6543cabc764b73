"""Encoder quantisation and the inter-pulse-timing velocity board (thesis §2.4.5)."""

import math

import numpy as np
import pytest

from ppamsafety.control.sensors import (S_NPULSE, SensorConfig, initial_sensor_state,
                                        sensor_init, sensor_read, sensor_track)

CFG = SensorConfig()
RES = CFG.resolution


def _drive(q_of_t, t_end, h=2.5e-4, cfg=CFG):
    """Move joint 0 along q_of_t, tracking edges; return sample times and readings."""
    c = cfg.pack()
    st = initial_sensor_state([q_of_t(0.0), 0.0])
    sensor_init(q_of_t(0.0), 0.0, c, st)
    ts, qm, wm = [], [], []
    n = int(round(t_end / h))
    for i in range(n):
        t = i * h
        if i % int(round(1e-3 / h)) == 0:
            a, w = sensor_read(0, q_of_t(t), 0.0, t, c, st)
            ts.append(t)
            qm.append(a)
            wm.append(w)
        sensor_track(0, q_of_t(t), q_of_t(t + h), t, h, c, st)
    return np.array(ts), np.array(qm), np.array(wm), st


def test_resolution_is_0_045_degrees():
    assert math.degrees(CFG.resolution) == pytest.approx(0.045)
    assert math.degrees(CFG.min_velocity) == pytest.approx(1.373, abs=1e-3)   # §2.4.5.3


def test_encoder_quantises_to_counts():
    ts, qm, _, _ = _drive(lambda t: 0.3 + 0.7 * t, 0.2)
    q_true = 0.3 + 0.7 * ts
    assert np.all(q_true - qm >= -1e-12) and np.all(q_true - qm < RES)
    np.testing.assert_allclose(qm / RES, np.round(qm / RES), atol=1e-9)


@pytest.mark.parametrize("w", [0.1, 1.0, 5.0, -2.0])
def test_inter_pulse_velocity_accuracy(w):
    """Relative error below omega T_c / Delta q (2.26), plus one sub-step interpolation."""
    ts, _, wm, _ = _drive(lambda t: 0.3 + w * t, 0.2)
    settled = wm[ts > 0.05]
    bound = abs(w) / CFG.clock_hz / RES
    np.testing.assert_allclose(settled, w, rtol=bound + 1e-6)


def test_dead_band_reads_zero():
    """|omega| < 0.025 rad/s reads 0 (§2.4.5.3)."""
    _, _, wm, st = _drive(lambda t: 0.3 + 0.02 * t, 1.0)
    assert st[S_NPULSE] > 0 and np.all(wm == 0.0)


def test_reading_is_held_until_next_pulse_and_overflows_to_zero():
    """After the arm stops, the last reading is held, then the 16-bit counter overflow
    (65535 clock periods = 32.8 ms) makes it read zero."""
    def q(t):
        return 0.3 + 0.5 * min(t, 0.1)
    ts, _, wm, _ = _drive(q, 0.2)
    after = wm[ts > 0.1]
    t_after = ts[ts > 0.1]
    assert after[0] == pytest.approx(0.5, rel=1e-3)                     # held
    t_ovf = (2 ** 16 - 1) / CFG.clock_hz
    assert np.all(after[t_after > 0.1 + t_ovf + 2e-3] == 0.0)            # overflowed
    assert np.all(after[t_after < 0.1 + t_ovf - 2e-3] != 0.0)


def test_velocity_sign_follows_direction():
    ts, _, wm, _ = _drive(lambda t: 0.3 + 0.02 * math.sin(2 * math.pi * 2 * t), 1.0)
    w_true = 0.02 * 2 * math.pi * 2 * np.cos(2 * math.pi * 2 * ts)
    big = (np.abs(w_true) > 0.15) & (ts > 0.02)
    assert np.all(np.sign(wm[big]) == np.sign(w_true[big]))


def test_noise_is_seeded_and_has_table_3_2_variances():
    cfg = SensorConfig(noise=True, seed=7)
    a, b = cfg.noise_samples(200000), cfg.noise_samples(200000)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(a.var(axis=0), cfg.noise_variances, rtol=0.02)
    assert not np.array_equal(a, SensorConfig(noise=True, seed=8).noise_samples(200000))
    assert np.all(SensorConfig().noise_samples(10) == 0.0)


def test_ideal_sensors_are_exact():
    c = SensorConfig.ideal().pack()
    st = initial_sensor_state([0.3, 0.0])
    assert sensor_read(0, 0.30001, 0.123, 0.0, c, st) == (0.30001, 0.123)


def test_sensor_config_validation():
    with pytest.raises(ValueError, match="velocity"):
        SensorConfig(velocity="magic")
    with pytest.raises(ValueError, match="noise_variances"):
        SensorConfig(noise_variances=(1, 2))
