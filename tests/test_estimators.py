"""Estimators: batch equals streaming, gain batches, agreement with ahrs, and the analyses."""

import numpy as np
import pytest

import scenarios
from estimators import analysis, core, estimate
from fmus import vehicle


def synthetic(n=3000, dt=1e-3, seed=0):
    """A tumbling body: true quaternions, and noisy gyro, accelerometer and magnetometer."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    rates = np.column_stack([0.5 * np.sin(1.3 * t), 0.4 * np.cos(0.7 * t), 0.3 * np.sin(0.5 * t + 1)])
    q, r = np.array([0.9, 0.1, -0.2, 0.3]) / np.linalg.norm([0.9, 0.1, -0.2, 0.3]), np.empty((3, 3))
    truth, acc, mag = np.empty((n, 4)), np.empty((n, 3)), np.empty((n, 3))
    for k in range(n):
        core._integrate(q, *rates[k], dt, core.EXP)
        truth[k] = q
        core.rotation(q, r)
        acc[k] = r.T @ [0.0, 0.0, -vehicle.GRAVITY]
        mag[k] = r.T @ np.array(vehicle.EARTH_FIELD)
    gyro = rates + [0.02, -0.01, 0.015] + 0.01 * rng.standard_normal((n, 3))
    return truth, acc + 0.05 * rng.standard_normal((n, 3)), gyro, mag + 5e-7 * rng.standard_normal((n, 3))


def angle(q1, q2):
    """Rotation angle between unit quaternions, accurate near zero (no arccos)."""
    difference = np.minimum(np.linalg.norm(q1 - q2, axis=-1), np.linalg.norm(q1 + q2, axis=-1))
    return 4 * np.arcsin(np.clip(difference / 2, 0, 1))


@pytest.mark.parametrize("kind, options", [
    ("linear", {"k": 0.05}), ("explicit", {"kI": 0.3}), ("passive", {"ry": "reel"}), ("passive", {"ry": "triad"}),
])
def test_batch_path_equals_streaming_block(kind, options):
    result, _ = scenarios.run("tp", {"estimator": kind, "noise": True, "bias": True, "duration": 1.0,
                                     "flight": "nonstationary", "feedback": "estimate", **options})
    tp = scenarios.get("tp")
    gains = __import__("scenarios.tp", fromlist=["estimator_gains"]).estimator_gains(tp.parse(
        {"estimator": kind, **options}))
    batch = estimate(kind, result["IMU.acc"], result["IMU.gyro"], result["IMU.magneto"], 1e-3, gains,
                     R_reel=result["IMU.R_reel"], ry=options.get("ry", "reel"),
                     q0=(1, 0, 0, 0))
    streamed = result["Quaternion_estim.q_est"]
    print(f"{kind} {options}: largest |batch - streaming| = {np.abs(batch['q'][0] - streamed).max():.3g}")
    assert np.abs(batch["q"][0] - streamed).max() <= 1e-12
    assert np.abs(batch["b"][0] - result["Quaternion_estim.b_est"]).max() <= 1e-12


def test_a_batch_of_gain_sets_equals_separate_runs():
    _, acc, gyro, mag = synthetic()
    kp, ki = np.array([0.1, 1.0, 3.0, 10.0]), np.array([0.0, 0.1, 0.5, 2.0])
    together = estimate("explicit", acc, gyro, mag, 1e-3, {"kP": kp, "kI": ki, "k1": 1.0, "k2": 0.5})
    for g in range(4):
        alone = estimate("explicit", acc, gyro, mag, 1e-3, {"kP": kp[g], "kI": ki[g], "k1": 1.0, "k2": 0.5})
        assert np.array_equal(together["q"][g], alone["q"][0])
        assert np.array_equal(together["b"][g], alone["b"][0])


def test_explicit_filter_agrees_with_ahrs_mahony():
    """Gyro and accelerometer only (k2 = 0), Euler discretisation, frames converted: ahrs
    expects +g along the up direction at rest, so it is given -acc."""
    ahrs = pytest.importorskip("ahrs")
    truth, acc, gyro, mag = synthetic()
    dt, kp, ki = 1e-3, 1.5, 0.4
    ours = estimate("explicit", acc, gyro, mag, dt, {"k1": 1.0, "k2": 0.0, "kP": kp, "kI": ki},
                    q0=truth[0], discretisation="euler")["q"][0]
    mahony = ahrs.filters.Mahony(k_P=kp, k_I=ki, frequency=1 / dt)
    q = truth[0].copy()
    theirs = np.empty_like(ours)
    for n in range(len(acc)):
        q = mahony.updateIMU(q, gyr=gyro[n], acc=-acc[n], dt=dt)
        theirs[n] = q
    print(f"explicit against ahrs Mahony: largest angle {angle(ours, theirs).max():.3g} rad")
    assert angle(ours, theirs).max() < 1e-9


def test_unknown_or_negative_gain_is_refused():
    _, acc, gyro, mag = synthetic(10)
    with pytest.raises(ValueError, match="no gain 'k3'"):
        estimate("explicit", acc, gyro, mag, 1e-3, {"k3": 1.0})
    with pytest.raises(ValueError, match="kP = -1.0 must be finite and non-negative"):
        estimate("passive", acc, gyro, mag, 1e-3, {"kP": -1.0})
    with pytest.raises(ValueError, match="option k=-0.1 must be at least"):
        scenarios.run("tp", {"k": -0.1})


# ---------------------------------------------------------------- analyses
def test_linear_transfer_functions_and_variance():
    dt, k = 0.01, 0.5
    import control

    tf = analysis.linear_transfer_functions(k, dt)
    assert control.dcgain(tf["gyro_bias"]) == pytest.approx(1 / k)  # steady error b / k
    assert control.dcgain(tf["angle_noise"]) == pytest.approx(1.0)
    assert analysis.linear_bandwidth(k) == pytest.approx(k, rel=0.01)
    sg, sa = 2e-3, 3e-3
    phi = 1 - k * dt
    exact = dt**2 * (sg**2 + k**2 * sa**2) / (1 - phi**2)
    assert analysis.linear_error_variance(k, dt, sg, sa)[0] == pytest.approx(exact, rel=1e-9)
    assert analysis.linear_optimal_gain(dt, sg, sa) == pytest.approx(sg / sa, rel=0.01)


def test_passive_poles_and_damping():
    p = analysis.passive_poles(1.0, 1.0)
    assert p["damping"] == pytest.approx(0.5) and p["natural_frequency"] == pytest.approx(1.0)
    assert np.allclose(sorted(p["poles"].real), [-0.5, -0.5])
