"""Disturbance-aware corrections of the explicit and passive filters, in closed-loop simulation."""

import numpy as np
import pytest
from quadcosim.estimators import CORRECTIONS, score
from quadcosim.estimators.corrections import NEW_FOR_EXPLICIT
from quadcosim.fmus.IMU.variables import LAB_GYRO_BIAS
from quadcosim.orchestrator import Fault

from quadcosim import scenarios

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
    # from then on the bias follows the gyro as a first-order lag of rate rest_gain: of the largest
    # component (0.02 rad/s) exp(-rest_gain (8 s - rest_time)) is left (1.05e-2 rad/s measured)
    left = max(np.abs(LAB_GYRO_BIAS)) * np.exp(-CORRECTIONS["rest_gain"] * (8.0 - started))
    assert error == pytest.approx(left, rel=0.05)


def _spinning_and_shaken(n=20000, dt=1e-3, shake=3.0):
    """A body turning at 1 rad/s about a tilted axis while shaken along the inertial x axis at
    2 Hz (``shake`` m/s^2): true attitude and perfect gyro, accelerometer and magnetometer."""
    from quadcosim.estimators import layout, quaternions
    from quadcosim.fmus import vehicle

    t = np.arange(n) * dt
    rate = np.array([0.6, 0.0, 0.8])
    q, r = np.array([1.0, 0.0, 0.0, 0.0]), np.empty((3, 3))
    truth, acc, mag = np.empty((n, 4)), np.empty((n, 3)), np.empty((n, 3))
    for k in range(n):
        quaternions._integrate(q, *rate, dt, layout.EXP)
        truth[k] = q
        quaternions.rotation(q, r)
        linear = np.array([shake * np.sin(2 * np.pi * 2.0 * t[k]), 0.0, 0.0])
        acc[k] = r.T @ (linear - np.array([0.0, 0.0, vehicle.GRAVITY]))
        mag[k] = r.T @ np.array(vehicle.EARTH_FIELD)
    return truth, np.tile(rate, (n, 1)), acc, mag


@pytest.mark.parametrize("estimator", ["explicit", "passive"])
def test_the_lowpass_in_the_gyro_frame_filters_linear_acceleration_without_lagging_the_rotation(estimator):
    from quadcosim.estimators import estimate

    inclination = {}
    for shake in (0.0, 3.0):
        truth, gyro, acc, mag = _spinning_and_shaken(shake=shake)
        gains = {"kP": 1.0, "kI": 0.0, "acc_lowpass": [0.0, 1.0]}
        errors = estimate(estimator, gyro=gyro, acc=acc, mag=mag, dt=1e-3, gains=gains, ry="triad",
                          corrections={"heading_only": True}, q0=truth[0], outputs=(), reference=truth,
                          scored=np.arange(len(truth)) >= 5000)["errors"]
        inclination[shake] = errors["inclination_rmse_deg"]
    print(f"{estimator}: inclination RMSE (deg) without / with the low-pass: still {inclination[0.0]}, "
          f"shaken {inclination[3.0]}")
    # the low-pass adds no lag while the body turns at 1 rad/s (the 0.034 deg of both: the
    # correction uses the attitude of the sample before)
    assert abs(inclination[0.0][1] - inclination[0.0][0]) < 1e-9  # measured 2.4e-11 deg
    # shaken at 3 m/s^2, 2 Hz: the low-pass takes most of the linear acceleration out
    assert inclination[3.0][1] < 0.1 * inclination[3.0][0]


def test_magnetic_reference_tracking_accepts_the_motor_field_and_halves_the_error_of_a_faulted_flight():
    """The acceptance case: non-stationary flight, noise, gyro bias, the motor field uncompensated,
    20 uT on the magnetometer for 5 s, Mahony's gains with a bias estimate, with and without the corrections."""
    # the gains the corrections were first judged with (the defaults before the cross-validation on real
    # recordings lowered kP and kI: those leave a 0.02 rad/s bias unlearnt in a flight without rest)
    gains = {"k1": 1.0, "k2": 1.0, "kP": 1.0, "kI": 0.01}
    # the corrections it was judged with: those of CORRECTIONS before the recommended filter's own were added
    judged = {k: v for k, v in CORRECTIONS.items() if k not in NEW_FOR_EXPLICIT}
    tracked = ",".join(f"{k}={v}" for k, v in judged.items())
    untracked = ",".join(f"{k}={0.0 if k == 'mag_reference_time' else v}" for k, v in judged.items())
    errors, weights = {}, {}
    for label, corrections in (("off", "off"), ("on", tracked), ("on, no tracking", untracked)):
        result = _flight(corrections, True, duration=20.0, **gains)
        errors[label] = score(result["Quaternion_estim.q_est"], result["Quadrotor.q"], result.time >= 2.0)
        weights[label] = result["Quaternion_estim.mag_weight"][result.time >= FAULT[1] + 2.0].mean()
    ratio = errors["on"]["total_rmse_deg"] / errors["off"]["total_rmse_deg"]
    print({k: round(v["total_rmse_deg"], 3) for k, v in errors.items()}, f"on / off {ratio:.3f}",
          {k: round(v, 3) for k, v in weights.items()})
    assert ratio < 0.5  # 0.445 measured
    # after the fault: without tracking, the motor field (|m| 10-16 % over the configured field)
    # keeps the magnetometer's weight low (0.29 measured), with it the field is accepted (0.66)
    assert weights["on"] > 0.6 and weights["on, no tracking"] < 0.35
