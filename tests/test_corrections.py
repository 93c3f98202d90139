"""Disturbance-aware corrections of the explicit and passive filters, in closed-loop simulation."""

import numpy as np
import pytest

import scenarios
from estimators import CORRECTIONS, score
from fmus.IMU.variables import LAB_GYRO_BIAS
from orchestrator import Fault

FAULT = (8.0, 13.0, 2e-5)  # s, s, T: 20 uT on the magnetometer's x axis


def _flight(corrections, fault, estimator="explicit", duration=14.0, **options):
    faults = [Fault("Quaternion_estim.magneto_x", "offset", *FAULT)] if fault else []
    result, _ = scenarios.run("tp", {"estimator": estimator, "flight": "nonstationary", "noise": True, "bias": True,
                                     "magnetic": True, "corrections": corrections, "duration": duration, "kI": 0.05,
                                     **options}, faults=faults)
    return result


def _during_fault(result):
    return (result.time >= FAULT[0]) & (result.time < FAULT[1])


@pytest.mark.parametrize("estimator, options", [("explicit", {}), ("passive", {"ry": "triad", "kP": 1.0,
                                                                               "kI": 0.05})])
def test_heading_only_keeps_a_magnetometer_fault_out_of_the_inclination(estimator, options):
    change = {}
    for corrections in ("off", "heading_only"):
        errors = []
        for fault in (False, True):
            result = _flight(corrections, fault, estimator, **options)
            window = result.time >= FAULT[0]
            errors.append(score(result["Quaternion_estim.q_est"], result["Quadrotor.q"], window))
        change[corrections != "off"] = abs(errors[1]["inclination_rmse_deg"] - errors[0]["inclination_rmse_deg"])
    print(f"{estimator}: inclination change with the fault, off {change[False]:.4f} deg, "
          f"heading only {change[True]:.2e} deg")
    # heading only: the fault reaches the tilt through the bias estimate alone (kI > 0), 0.006 / 0.02 deg measured
    assert change[True] < 0.03 and change[False] > 0.15


def test_magnetic_rejection_drops_the_magnetometer_during_a_norm_fault():
    result = _flight("mag_norm_tolerance,heading_only", True, magnetic=False)
    weight = result["Quaternion_estim.mag_weight"]
    norm = np.linalg.norm(result["IMU.magneto"], axis=1) / 4.7e-5
    faulted = _during_fault(result)
    expected = np.clip(1 - np.abs(norm - 1) / CORRECTIONS["mag_norm_tolerance"], 0, 1)
    print(f"magnetometer weight: {weight[~faulted].mean():.3f} outside the fault, {weight[faulted].mean():.3f} in it")
    clean = ~faulted & (result.time > 0.0)
    assert np.allclose(weight[clean], expected[clean], atol=1e-12, rtol=0)
    assert weight[faulted].mean() < 0.1 and weight[~faulted].mean() > 0.85


def test_accelerometer_weight_falls_when_the_specific_force_leaves_g():
    result = _flight("acc_tolerance=1", False, duration=6.0, magnetic=False)
    weight = result["Quaternion_estim.acc_weight"][1:]
    departure = np.abs(np.linalg.norm(result["IMU.acc"], axis=1) - 9.81)[1:]
    print(f"acc weight from {weight.min():.3f} to {weight.max():.3f}; |a|-g up to {departure.max():.2f} m/s^2")
    assert np.allclose(weight, np.clip(1 - departure / 1.0, 0, 1), atol=1e-9)
    assert weight.min() == 0.0 and weight.max() > 0.99


def test_bias_is_estimated_at_rest():
    """Hover fed by the ground truth; with kI = 0 only the rest detector can estimate the bias."""
    result, _ = scenarios.run("tp", {"estimator": "explicit", "flight": "hover", "noise": True, "bias": True,
                                     "kI": 0.0, "corrections": "on", "duration": 8.0})
    at_rest = result["Quaternion_estim.at_rest"]
    error = np.abs(result["Quaternion_estim.b_est"][-1] - np.array(LAB_GYRO_BIAS)).max()
    started = result.time[np.argmax(at_rest > 0)]
    print(f"rest detected from {started:.2f} s; final bias error {error:.2e} rad/s")
    assert started == pytest.approx(CORRECTIONS["rest_time"], abs=0.05)
    assert error < 1e-3
