"""IMU FMU: exact readings at known attitudes, and the statistics of its noise."""

import numpy as np
import pytest
from quadcosim.fmus import vehicle
from quadcosim.fmus.IMU.variables import ACC_NOISE_DENSITY, GYRO_NOISE_DENSITY, MAG_NOISE_DENSITY
from quadcosim.orchestrator.fmu import FMUInstance

from tests.helpers import rotation

ACC = [f"acc_{a}" for a in "xyz"]
GYRO = [f"gyro_{a}" for a in "xyz"]
MAG = [f"magneto_{a}" for a in "xyz"]
REEL = [f"R_reel_{i}{j}" for i in range(1, 4) for j in range(1, 4)]
INPUTS = ["q0", "q1", "q2", "q3", "omega_x", "omega_y", "omega_z", "f_x", "f_y", "f_z",
          "b_d_x", "b_d_y", "b_d_z"]
ROTORS = ["omega_r1", "omega_r2", "omega_r3", "omega_r4"]
SOFT_IRON = np.array([[1.05, 0.02, -0.01], [0.02, 0.97, 0.03], [-0.01, 0.03, 1.01]])
HARD_IRON = np.array([3e-6, -2e-6, 5e-6])


def quaternion(roll, pitch, yaw):
    cr, sr, cp, sp, cy, sy = (np.cos(roll / 2), np.sin(roll / 2), np.cos(pitch / 2), np.sin(pitch / 2),
                              np.cos(yaw / 2), np.sin(yaw / 2))
    return np.array([cy * cp * cr + sy * sp * sr, cy * cp * sr - sy * sp * cr,
                     cy * sp * cr + sy * cp * sr, sy * cp * cr - cy * sp * sr])


@pytest.mark.parametrize("attitude", [(0, 0, 0), (0.3, -0.2, 1.0), (-1.2, 0.7, -2.5), (0.0, 1.5, 3.0)])
def test_noise_free_readings_at_known_attitudes(attitude):
    params = {"noise_enabled": False, "bias_enabled": True, "b_a_x": 0.1, "b_a_y": -0.05, "b_a_z": 0.02}
    params |= {f"A_{i + 1}{j + 1}": SOFT_IRON[i, j] for i in range(3) for j in range(3)}
    params |= {f"b_s_{a}": HARD_IRON[k] for k, a in enumerate("xyz")}
    fmu = FMUInstance("IMU", params)
    q = quaternion(*attitude)
    omega, f, b_d = np.array([0.1, -0.2, 0.3]), np.array([0.5, -0.4, -9.7]), np.array([1e-6, 2e-6, -3e-6])
    fmu.set(INPUTS, np.concatenate([q, omega, f, b_d]))
    R = rotation(q)
    m_I = np.array(vehicle.EARTH_FIELD)
    assert np.allclose(fmu.get(ACC), f + [0.1, -0.05, 0.02], rtol=1e-15, atol=1e-15)
    assert np.allclose(fmu.get(GYRO), omega + [0.02, -0.01, 0.015], rtol=1e-15, atol=1e-15)
    assert np.allclose(fmu.get(MAG), SOFT_IRON @ R.T @ m_I + HARD_IRON + b_d, rtol=1e-14, atol=1e-20)
    assert np.allclose(fmu.get(REEL), R.ravel(), rtol=0, atol=1e-15)
    # the roll and pitch of the lab's linear estimator are readable off a level accelerometer
    fmu.close()


def noise_stream(seed, samples, h=1e-3, rate=1000.0, outputs=ACC + GYRO + MAG):
    fmu = FMUInstance("IMU", {"seed": seed, "sample_rate": rate, "mag_sample_rate": rate, "bias_enabled": False})
    level = np.array([1, 0, 0, 0, 0, 0, 0, 0, 0, -vehicle.GRAVITY, 0, 0, 0], dtype=float)
    steps = int(round(samples / (rate * h)))
    values = np.empty((steps, len(outputs)))
    for k in range(steps):
        fmu.set(INPUTS, level)
        values[k] = fmu.get(outputs)
        fmu.step(k * h, h)
    fmu.close()
    return values


def test_noise_standard_deviation_and_mean():
    rate = 1000.0
    values = noise_stream(7, 100_000, rate=rate)
    clean = np.concatenate([[0, 0, -vehicle.GRAVITY], [0, 0, 0], np.array(vehicle.EARTH_FIELD)])
    noise = values - clean
    expected = np.repeat([ACC_NOISE_DENSITY, GYRO_NOISE_DENSITY, MAG_NOISE_DENSITY], 3) * np.sqrt(rate)
    std = noise.std(axis=0)
    assert np.all(np.abs(std / expected - 1) < 0.03), std / expected
    # mean within 4 standard errors of zero
    assert np.all(np.abs(noise.mean(axis=0)) < 4 * expected / np.sqrt(len(noise)))
    # channels are uncorrelated
    corr = np.corrcoef(noise.T)
    assert np.abs(corr - np.eye(9)).max() < 0.02


def test_seed_reproducibility():
    a, b, c = noise_stream(3, 2000), noise_stream(3, 2000), noise_stream(4, 2000)
    assert np.array_equal(a, b)
    assert not np.any(a == c)


def test_samples_do_not_depend_on_the_macro_step():
    fine = noise_stream(5, 500, h=0.5e-3)
    coarse = noise_stream(5, 500, h=1e-3)
    assert np.array_equal(fine[::2], coarse)


def drive(h, seconds, parameters, outputs=ACC + MAG):
    """Step the IMU at h with inputs that change at every instant (a turning, shaking body)."""
    fmu = FMUInstance("IMU", parameters)
    n = int(round(seconds / h))
    values = np.empty((n, len(outputs)))
    for k in range(n):
        t = k * h
        q = quaternion(0.3 * np.sin(2 * t), 0.1 * t, 0.5 * np.cos(t))
        fmu.set(INPUTS, np.concatenate([q, [0.1, 0.2, 0.3], [np.sin(7 * t), 0.0, -9.81],
                                        [1e-6 * np.sin(30 * t), 2e-6 * t, 0.0]]))
        values[k] = fmu.get(outputs)
        fmu.step(t, h)
    fmu.close()
    return values


def test_magnetometer_runs_at_its_own_rate_and_holds_its_samples(capsys):
    """Acceptance: the magnetometer's samples change only at its own rate (100 Hz by default)
    while the accelerometer samples at 1 kHz, and the samples do not depend on the macro step:
    0.5 ms and 1 ms steps give identical samples (noise on)."""
    params = {"seed": 9}
    coarse = drive(1e-3, 0.2, params)
    fine = drive(0.5e-3, 0.2, params)
    acc, mag = coarse[:, :3], coarse[:, 3:]
    changes = np.flatnonzero(np.any(np.diff(mag, axis=0) != 0, axis=1)) + 1  # rows where a new sample shows
    assert np.array_equal(changes, np.arange(10, 200, 10))  # every 10 ms, never in between
    assert np.all(np.any(np.diff(acc, axis=0) != 0, axis=1))  # a new accelerometer sample every 1 ms
    assert np.array_equal(fine[::2], coarse)  # identical, bit for bit, at every 1 ms instant
    with capsys.disabled():
        print(f"\nmagnetometer: {len(changes)} new samples in 0.2 s at 1 kHz stepping (100 Hz); "
              "0.5 ms and 1 ms macro steps give identical samples")
    # the held value is the sample at the instant: noise-free, it is the model at t_k
    clean = drive(1e-3, 0.05, {"noise_enabled": False})
    t_k = 0.02
    q = quaternion(0.3 * np.sin(2 * t_k), 0.1 * t_k, 0.5 * np.cos(t_k))
    expected = rotation(q).T @ np.array(vehicle.EARTH_FIELD) + [1e-6 * np.sin(30 * t_k), 2e-6 * t_k, 0.0]
    for row in range(20, 30):
        assert np.allclose(clean[row, 3:], expected, rtol=0, atol=1e-18)


def test_magnetometer_noise_follows_its_own_rate():
    """The magnetometer's white noise has standard deviation density * sqrt(mag_sample_rate)."""
    fmu = FMUInstance("IMU", {"seed": 4, "bias_enabled": False})
    level = np.array([1, 0, 0, 0, 0, 0, 0, 0, 0, -vehicle.GRAVITY, 0, 0, 0], dtype=float)
    samples = np.empty((20000, 3))
    for k in range(20000):  # 200 s at 100 Hz, read once per sample
        fmu.set(INPUTS, level)
        samples[k] = fmu.get(MAG)
        fmu.step(k * 1e-2, 1e-2)
    fmu.close()
    std = (samples - np.array(vehicle.EARTH_FIELD)).std(axis=0)
    assert np.all(np.abs(std / (MAG_NOISE_DENSITY * np.sqrt(100.0)) - 1) < 0.03), std


def test_rotor_vibration_is_a_once_per_revolution_acceleration():
    """vibration_amplitude at vibration_speed, per rotor, turning with it: with the four rotors at
    that speed from angle 0, the two counter-clockwise and two clockwise ones add along x_B and
    cancel along y_B: acc = f + 4 A (cos omega t, 0, 0). Off by default."""
    w, f = 480.0, np.array([0.2, -0.1, -9.8])
    t = np.arange(100) * 1e-3
    for extra, amplitude in (({}, 0.0), ({"vibration_amplitude": 0.5, "vibration_speed": w}, 0.5)):
        fmu = FMUInstance("IMU", {"noise_enabled": False, **extra})
        rows = []
        for k in range(100):
            fmu.set(INPUTS + ROTORS, np.concatenate([[1, 0, 0, 0, 0, 0, 0], f, [0, 0, 0], [w] * 4]))
            rows.append(fmu.get(ACC))
            fmu.step(k * 1e-3, 1e-3)
        fmu.close()
        rows = np.array(rows)
        assert np.allclose(rows[:, 0], f[0] + 4 * amplitude * np.cos(w * t), rtol=0, atol=1e-9)
        assert np.allclose(rows[:, 1:], f[1:], rtol=0, atol=1e-12)
