"""Estimators: batch equals streaming, gain batches, agreement with ahrs, and the analyses."""

import numpy as np
import pytest
from quadcosim.estimators import analysis, estimate, filters, gain_grid, layout, parse_corrections, quaternions, score
from quadcosim.fmus import vehicle

from quadcosim import scenarios


def synthetic(n=3000, dt=1e-3, seed=0):
    """A tumbling body: true quaternions, and noisy gyro, accelerometer and magnetometer."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    rates = np.column_stack([0.5 * np.sin(1.3 * t), 0.4 * np.cos(0.7 * t), 0.3 * np.sin(0.5 * t + 1)])
    q, r = np.array([0.9, 0.1, -0.2, 0.3]) / np.linalg.norm([0.9, 0.1, -0.2, 0.3]), np.empty((3, 3))
    truth, acc, mag = np.empty((n, 4)), np.empty((n, 3)), np.empty((n, 3))
    for k in range(n):
        quaternions._integrate(q, *rates[k], dt, layout.EXP)
        truth[k] = q
        quaternions.rotation(q, r)
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
    ("explicit", {"kI": 0.3, "corrections": "on"}), ("passive", {"ry": "triad", "corrections": "on"}),
])
def test_batch_path_equals_streaming_block(kind, options):
    result, _ = scenarios.run("tp", {"estimator": kind, "noise": True, "bias": True, "duration": 1.0,
                                     "flight": "nonstationary", "feedback": "estimate", **options})
    tp = scenarios.get("tp")
    gains = __import__("quadcosim.scenarios.tp", fromlist=["estimator_gains"]).estimator_gains(tp.parse(
        {"estimator": kind, **options}))
    batch = estimate(kind, acc=result["IMU.acc"], gyro=result["IMU.gyro"], mag=result["IMU.magneto"], dt=1e-3,
                     gains=gains, R_reel=result["IMU.R_reel"], ry=options.get("ry", "reel"), q0=(1, 0, 0, 0),
                     corrections=parse_corrections(options.get("corrections", "off")) if kind != "linear" else None)
    streamed = result["Quaternion_estim.q_est"]
    print(f"{kind} {options}: largest |batch - streaming| = {np.abs(batch['q'][0] - streamed).max():.3g}")
    assert np.abs(batch["q"][0] - streamed).max() <= 1e-12
    assert np.abs(batch["b"][0] - result["Quaternion_estim.b_est"]).max() <= 1e-12


def test_a_batch_of_gain_sets_equals_separate_runs():
    _, acc, gyro, mag = synthetic()
    kp, ki = np.array([0.1, 1.0, 3.0, 10.0]), np.array([0.0, 0.1, 0.5, 2.0])
    together = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3,
                        gains={"kP": kp, "kI": ki, "k1": 1.0, "k2": 0.5})
    for g in range(4):
        alone = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3,
                         gains={"kP": kp[g], "kI": ki[g], "k1": 1.0, "k2": 0.5})
        assert np.array_equal(together["q"][g], alone["q"][0])
        assert np.array_equal(together["b"][g], alone["b"][0])


def test_explicit_filter_agrees_with_ahrs_mahony():
    """Gyro and accelerometer only (k2 = 0), Euler discretisation, frames converted: ahrs
    expects +g along the up direction at rest, so it is given -acc."""
    ahrs = pytest.importorskip("ahrs")
    truth, acc, gyro, mag = synthetic()
    dt, kp, ki = 1e-3, 1.5, 0.4
    ours = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=dt, gains={"k1": 1.0, "k2": 0.0, "kP": kp, "kI": ki},
                    q0=truth[0], discretisation="euler", corrections=False)["q"][0]
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
        estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, gains={"k3": 1.0})
    with pytest.raises(ValueError, match="kP = -1.0 must be finite and non-negative"):
        estimate("passive", acc=acc, gyro=gyro, mag=mag, dt=1e-3, gains={"kP": -1.0})
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


# ---------------------------------------------------------------- API
def test_gains_are_placed_by_name_whatever_the_dict_order():
    _, acc, gyro, mag = synthetic(500)
    forward = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, gains={"k1": 0.3, "k2": 0.7, "kP": 2.0,
                                                                                "kI": 0.1})
    backward = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, gains={"kI": 0.1, "kP": 2.0, "k2": 0.7,
                                                                                 "k1": 0.3})
    swapped = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, gains={"k1": 0.7, "k2": 0.3, "kP": 2.0,
                                                                                "kI": 0.1})
    assert np.array_equal(forward["q"], backward["q"])
    assert not np.allclose(forward["q"], swapped["q"])
    table = filters.gain_table("explicit", {"kI": 0.1, "kP": 2.0})[0]
    assert table[layout.KP] == 2.0 and table[layout.KI] == 0.1
    assert table[layout.K1] == filters.DEFAULT_GAINS["explicit"]["k1"]


def test_gain_grid_is_a_cartesian_product_and_reshapes_in_order():
    grid = gain_grid(kP=[0.5, 1.0, 2.0], kI=[0.0, 0.1])
    assert list(zip(grid["kP"], grid["kI"], strict=True))[:3] == [(0.5, 0.0), (0.5, 0.1), (1.0, 0.0)]
    truth, acc, gyro, mag = synthetic(1500)
    out = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, gains=grid, outputs=("q",), reference=truth)
    errors = out["errors"]["total_rmse_deg"].reshape(3, 2)
    alone = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, gains={"kP": 2.0, "kI": 0.1},
                     reference=truth)["errors"]["total_rmse_deg"][0]
    assert errors[2, 1] == alone
    assert set(out) == {"q", "errors"} and out["q"].shape == (6, 1500, 4)


def test_error_reduction_in_the_loop_equals_scoring_stored_estimates():
    truth, acc, gyro, mag = synthetic(2000)
    gains = gain_grid(kP=[0.3, 3.0], kI=[0.0, 0.5])
    moving = np.arange(2000) > 300
    reduced = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, gains=gains, outputs=(), reference=truth,
                       scored=moving)
    stored = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, gains=gains, outputs=("q",))
    scored = score(stored["q"], truth, moving)
    by_hand = np.degrees(np.sqrt((angle(stored["q"][:, moving], truth[moving]) ** 2).mean(axis=1)))
    print("total RMSE (deg):", reduced["errors"]["total_rmse_deg"])
    for key in ("total_rmse_deg", "inclination_rmse_deg", "heading_rmse_deg"):
        assert np.allclose(reduced["errors"][key], scored[key], rtol=1e-12, atol=0)
    assert np.allclose(reduced["errors"]["total_rmse_deg"], by_hand, rtol=1e-9)
    assert "q" not in reduced


def test_heading_alignment_removes_a_constant_frame_offset():
    truth, acc, gyro, mag = synthetic(2000)
    turned = np.empty_like(truth)
    offset = np.radians(30.0)
    rotation = np.array([np.cos(offset / 2), 0, 0, np.sin(offset / 2)])  # about NED's vertical
    for n in range(len(truth)):
        quaternions.quaternion_multiply(rotation, truth[n], turned[n])
    plain = score(turned, truth)
    aligned = score(turned, truth, align_heading=True)
    assert plain["total_rmse_deg"] == pytest.approx(30.0, abs=1e-9)
    assert plain["inclination_rmse_deg"] == pytest.approx(0.0, abs=1e-10)
    assert aligned["heading_offset_deg"] == pytest.approx(30.0, abs=1e-9)
    assert aligned["total_rmse_deg"] == pytest.approx(0.0, abs=1e-10)  # measured 8.8e-13


def test_triad_start_and_initial_function():
    truth, acc, gyro, mag = synthetic(5)
    clean_acc = acc.copy()
    r = np.empty((3, 3))
    quaternions.rotation(truth[0], r)
    clean_acc[0] = r.T @ [0.0, 0.0, -vehicle.GRAVITY]
    mag[0] = r.T @ np.array(vehicle.EARTH_FIELD)
    out = estimate("explicit", acc=clean_acc, gyro=gyro, mag=mag, dt=1e-3, initial="triad", gains={"kP": 0.0})
    identity = estimate("explicit", acc=clean_acc, gyro=gyro, mag=mag, dt=1e-3, gains={"kP": 0.0})
    from_function = estimate("explicit", acc=clean_acc, gyro=gyro, mag=mag, dt=1e-3, gains={"kP": 0.0},
                             initial=lambda g, a, m: truth[0])
    # kP = 0: the first output is the TRIAD attitude advanced by one sample of measured rate,
    # |omega_m| dt = 0.5 mrad here
    assert angle(out["q"][0, 0], truth[0]) < 1e-3
    assert angle(identity["q"][0, 0], truth[0]) > 0.5
    assert angle(from_function["q"][0, 0], out["q"][0, 0]) < 1e-12


def test_swapped_or_misscaled_sensors_are_refused():
    _, acc, gyro, mag = synthetic(100)
    with pytest.raises(ValueError, match="were acc and gyro swapped"):
        estimate("explicit", acc=gyro, gyro=acc, mag=mag, dt=1e-3)
    with pytest.raises(ValueError, match="Is acc in g"):
        estimate("explicit", acc=acc / 9.81, gyro=gyro, mag=mag, dt=1e-3)
    with pytest.raises(TypeError):
        estimate("explicit", acc, gyro, mag, 1e-3)
    with pytest.raises(ValueError, match="unknown output 'quaternion'"):
        estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, outputs=("quaternion",))


def test_references_set_the_inertial_frame():
    """The same motion seen in ENU (gravity and field given as ENU vectors) gives the same error."""
    truth, acc, gyro, mag = synthetic(3000)
    ned = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, reference=truth, initial="triad",
                   outputs=())["errors"]
    to_enu = np.array([0.0, np.sqrt(0.5), np.sqrt(0.5), 0.0])  # NED -> ENU: 180 deg about (1, 1, 0)
    truth_enu = np.empty_like(truth)
    for n in range(len(truth)):
        quaternions.quaternion_multiply(to_enu, truth[n], truth_enu[n])
    field = np.array(vehicle.EARTH_FIELD)
    enu = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, reference=truth_enu, initial="triad",
                   gravity=(0.0, 0.0, -vehicle.GRAVITY), earth_field=(field[1], field[0], -field[2]),
                   outputs=())["errors"]
    dip = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, reference=truth, initial="triad",
                   dip=vehicle.EARTH_FIELD_INCLINATION, outputs=())["errors"]
    print(f"NED {ned['total_rmse_deg'][0]:.6f} deg, ENU {enu['total_rmse_deg'][0]:.6f} deg")
    assert enu["total_rmse_deg"][0] == pytest.approx(ned["total_rmse_deg"][0], rel=1e-9)
    assert dip["total_rmse_deg"][0] == pytest.approx(ned["total_rmse_deg"][0], rel=1e-9)


# ---------------------------------------------------------------- published filters
@pytest.mark.parametrize("kind", ["vqf", "madgwick"])
def test_published_filters_in_the_closed_loop_equal_the_array_path(kind):
    result, metrics = scenarios.run("tp", {"estimator": kind, "noise": True, "bias": True, "duration": 1.0,
                                           "flight": "nonstationary", "feedback": "estimate"})
    batch = estimate(kind, acc=result["IMU.acc"], gyro=result["IMU.gyro"], mag=result["IMU.magneto"], dt=1e-3)
    difference = np.abs(batch["q"][0] - result["Quaternion_estim.q_est"]).max()
    print(f"{kind}: |batch - streaming| = {difference:.3g}, tp errors {metrics['rms_error_deg']} deg")
    assert difference <= 1e-12
    assert max(metrics["rms_error_deg"]) < {"vqf": 4.0, "madgwick": 2.5}[kind]  # both still converging at 1 s


@pytest.mark.parametrize("kind, bound", [("vqf", 4.5), ("madgwick", 1.5)])
def test_published_filters_are_turned_into_the_configured_frame(kind, bound):
    """Both packages use their own inertial frame; a wrong turn would show tens of degrees."""
    truth, acc, gyro, mag = synthetic(6000)
    errors = estimate(kind, acc=acc, gyro=gyro, mag=mag, dt=1e-3, initial="triad", reference=truth,
                      outputs=())["errors"]
    print(kind, {k: round(float(v[0]), 3) for k, v in errors.items()})
    assert errors["total_rmse_deg"][0] < bound


def test_samples_without_a_reference_are_not_scored():
    truth, acc, gyro, mag = synthetic(1000)
    occluded = truth.copy()
    occluded[200:400] = np.nan
    scored = np.ones(1000, dtype=bool)
    scored[200:400] = False
    with_nan = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, reference=occluded, outputs=())["errors"]
    masked = estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, reference=truth, scored=scored,
                      outputs=())["errors"]
    assert with_nan["total_rmse_deg"][0] == masked["total_rmse_deg"][0]
