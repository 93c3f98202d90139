"""IMU FMU: exact readings at known attitudes, and the statistics of its noise."""

import numpy as np
import pytest

from fmus import vehicle
from fmus.IMU.variables import ACC_NOISE_DENSITY, GYRO_NOISE_DENSITY, MAG_NOISE_DENSITY
from orchestrator.fmu import FMUInstance
from tests.helpers import rotation

ACC = [f"acc_{a}" for a in "xyz"]
GYRO = [f"gyro_{a}" for a in "xyz"]
MAG = [f"magneto_{a}" for a in "xyz"]
REEL = [f"R_reel_{i}{j}" for i in range(1, 4) for j in range(1, 4)]
INPUTS = ["q0", "q1", "q2", "q3", "omega_x", "omega_y", "omega_z", "f_x", "f_y", "f_z",
          "b_d_x", "b_d_y", "b_d_z"]
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
    fmu = FMUInstance("IMU", {"seed": seed, "sample_rate": rate, "bias_enabled": False})
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
