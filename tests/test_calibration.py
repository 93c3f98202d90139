"""Static calibration, the motor-field model, the calibration file and the compensator, on
synthetic data with known parameters."""

import json

import numpy as np
import pytest
from quadcosim.calibration import (
    Calibration,
    CalibrationError,
    MagCompensator,
    MotorDynamics,
    StaticCalibration,
    Sweep,
    compensate,
    fit_dynamic,
    fit_static,
    order_study,
)
from quadcosim.fmus import vehicle

EARTH = np.array(vehicle.EARTH_FIELD)
NORM = vehicle.EARTH_FIELD_NORM
A_TRUE = np.array([[1.08, 0.04, -0.03], [0.04, 0.93, 0.05], [-0.03, 0.05, 1.01]])  # symmetric soft iron
B_TRUE = np.array([12e-6, -8e-6, 20e-6])  # T
NOISE = 0.32e-6  # T, the magnetometer's noise at 80 Hz


def rot_z(yaw):
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def sweep(n=2000, seed=0, A=A_TRUE, b=B_TRUE, noise=NOISE):
    rng = np.random.default_rng(seed)
    m = rng.normal(size=(n, 3))
    m *= NORM / np.linalg.norm(m, axis=1, keepdims=True)
    return m @ A.T + b + rng.normal(scale=noise, size=m.shape)


def test_static_fit_recovers_soft_and_hard_iron():
    fit = fit_static(sweep(), field_norm=NORM)
    error_A = np.abs(fit.A - A_TRUE).max()
    error_b = np.abs(fit.b_s - B_TRUE).max()
    print(f"max |A - A_true| = {error_A:.2e}, max |b_s - b_true| = {error_b * 1e6:.3f} uT, {fit.quality()}")
    assert error_A < 1.5e-3
    assert error_b < 0.05e-6
    assert np.allclose(fit.A, fit.A.T)
    assert fit.spread < 0.008  # the noise alone: 0.32 / 47 = 0.0068
    assert fit.rms == pytest.approx(NOISE, rel=0.1)
    assert fit.coverage == 1.0


def test_static_fit_convention_symmetric_and_unit_determinant():
    rotation = rot_z(0.4)
    fit = fit_static(sweep(A=A_TRUE @ rotation, noise=0.0))
    # A R and A fit the same ellipsoid: the fit returns the symmetric factor of A A^T, det 1
    target = A_TRUE / np.linalg.det(A_TRUE) ** (1 / 3)
    assert np.abs(fit.A - target).max() < 1e-8
    assert np.linalg.det(fit.A) == pytest.approx(1.0, abs=1e-12)


def test_heading_after_static_correction_over_a_full_yaw_turn():
    fit = fit_static(sweep(), field_norm=NORM)
    rng = np.random.default_rng(3)
    yaw = np.linspace(-np.pi, np.pi, 361)
    body = np.array([rot_z(y).T @ EARTH for y in yaw])
    raw = body @ A_TRUE.T + B_TRUE

    def heading_error(field):
        return np.degrees(np.angle(np.exp(1j * (np.arctan2(-field[:, 1], field[:, 0]) - yaw))))

    error = heading_error(fit.correct(raw))  # the calibration's own error, noise-free turn
    noisy = heading_error(fit.correct(raw + rng.normal(scale=NOISE, size=raw.shape)))
    raw_error = heading_error(raw)
    print(f"heading error over a yaw turn: max {np.abs(error).max():.3f} deg (noise-free readings), RMS "
          f"{np.sqrt((noisy**2).mean()):.3f} deg with noise; uncorrected max {np.abs(raw_error).max():.1f} deg")
    assert np.abs(error).max() < 0.15
    assert np.sqrt((noisy**2).mean()) < 1.0  # 0.32 uT on the 19.9 uT horizontal field: 0.92 deg
    assert np.abs(raw_error).max() > 40


def _heading_error(field, yaw):
    return np.degrees(np.angle(np.exp(1j * (np.arctan2(-field[:, 1], field[:, 0]) - yaw))))


def test_a_non_symmetric_soft_iron_leaves_its_rotation_as_a_heading_error():
    """A = P U (P symmetric, U a rotation of 3 deg about z): the ellipsoid sees P alone, so the
    corrected field keeps U, and a level yaw turn reads a constant heading error of 3 deg: the
    alignment a sweep of |m| cannot see (the module's convention)."""
    from scipy.linalg import polar

    A = A_TRUE @ rot_z(np.radians(3.0))
    _, P = polar(A, side="left")
    fit = fit_static(sweep(A=A, noise=0.0), field_norm=NORM)
    assert np.abs(fit.A - P).max() < 1e-8 and not np.allclose(A, A.T)
    yaw = np.linspace(-np.pi, np.pi, 361)
    raw = np.array([rot_z(y).T @ EARTH for y in yaw]) @ A.T + B_TRUE
    error = _heading_error(fit.correct(raw), yaw)
    print(f"non-symmetric soft iron: heading error {error.mean():.3f} deg (spread {np.ptp(error):.2e} deg)")
    # noise-free: the rotation comes out whole, to rounding (measured 1.3e-15 deg, spread 5.3e-14 deg)
    assert error.mean() == pytest.approx(-3.0, abs=1e-12) and np.ptp(error) < 1e-12


@pytest.mark.parametrize("noise", [0.0, NOISE, 10 * NOISE, 30 * NOISE])
def test_a_yaw_only_sweep_is_refused_whatever_the_noise_and_the_bounds(noise):
    """A sweep about z alone, as recorded (samples in order): refused, naming the axis it never
    turned off, at the magnetometer's noise and far above it, even with bounds=None."""
    yaw = np.linspace(0, 4 * np.pi, 3000)
    samples = np.array([rot_z(y).T @ EARTH for y in yaw]) @ A_TRUE.T + B_TRUE
    samples += np.random.default_rng(7).normal(scale=noise, size=samples.shape) if noise else 0.0
    with pytest.raises(CalibrationError, match="planar or single-axis sweep") as error:
        fit_static(samples, bounds=None)
    print(error.value)
    assert "along the sensor's z axis" in str(error.value)


@pytest.mark.parametrize("samples, message", [
    (sweep(20), "too few samples: 20 < 50"),
    (np.vstack([sweep(200)[:-1], [[np.nan, 0, 0]]]), "hold NaN or Inf (first at row 199)"),
    (np.array([rot_z(y).T @ EARTH for y in np.linspace(0, 6, 300)]) + B_TRUE, "planar or single-axis sweep"),
    (sweep(500) * 10, "fitted field radius"),
    (sweep(500, b=np.array([300e-6, 0, 0])), "hard-iron offset"),
    (sweep(500, A=np.diag([0.42, 0.42, 0.42**-2])), "soft-iron diagonal"),
    (sweep(500, A=np.array([[1.0, 0.9, 0.0], [0.9, 1.0, 0.0], [0.0, 0.0, 1.0]])), "soft-iron off-diagonal"),
    (sweep(500, noise=4e-6), "RMS residual"),
    (np.zeros((100, 2)), "(N, 3) array"),
])
def test_static_refusals_name_the_defect(samples, message):
    with pytest.raises(CalibrationError, match=None) as error:
        fit_static(samples)
    print(error.value)
    assert message in str(error.value)


# --- the paper's motor-field model on synthetic sweeps ---------------------------------

V_TRUE = np.array(vehicle.MOTOR_FIELD_DIRECTION)
V_TRUE = V_TRUE / np.linalg.norm(V_TRUE, axis=1, keepdims=True)
REFERENCE = A_TRUE @ EARTH + B_TRUE


def amplitude(c, u, n):
    """A current-like amplitude (T): ~ (c u)^2 with motor-dependent gain."""
    return vehicle.MOTOR_FIELD_GAIN[n] * 0.06 * (c * u) ** 2


def synthetic_set(seed, u0=12.0, points=40, repeats=25):
    rng = np.random.default_rng(seed)
    sweeps = []
    for n in range(4):
        c = np.repeat(np.linspace(0.05, 1.0, points), repeats)
        u = rng.uniform(u0 - 0.4, u0 + 0.4, size=c.shape)  # the battery drains across the set
        field = REFERENCE + amplitude(c, u, n)[:, None] * V_TRUE[n] + rng.normal(scale=NOISE, size=(len(c), 3))
        sweeps.append(Sweep(field, c, u))
    reference = REFERENCE + rng.normal(scale=NOISE / np.sqrt(1000), size=3)
    return reference, sweeps


def test_dynamic_fit_recovers_directions_within_a_degree():
    reference, sweeps = synthetic_set(1)
    model = fit_dynamic(reference, sweeps)
    angles = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", model.v, V_TRUE), -1, 1)))
    print(f"direction errors (deg): {np.round(angles, 4).tolist()}")
    assert (angles < 0.5).all()
    c = np.linspace(0.1, 1.0, 10)
    for n in range(4):
        predicted = model.amplitude(np.eye(4)[n] * c[:, None], np.full(10, 11.9))[:, n]
        assert np.allclose(predicted, amplitude(c, 11.9, n), rtol=0.02, atol=3 * NOISE)


def test_order_study_prefers_the_orders_that_describe_the_data():
    study = order_study([synthetic_set(1, u0=12.3), synthetic_set(2, u0=11.4)], range(1, 5), range(0, 2))
    print({f"I={i},J={j}": round(s * 1e9, 1) for (i, j), s in study["scores"].items()}, study["best"])
    # (c u)^2 = c^2 u^2 needs I >= 2 and J >= 1 (J = 1 represents u^2 nearly over 11 to 12.7 V)
    assert study["best"][0] >= 2 and study["best"][1] >= 1
    assert study["scores"][(1, 0)] > 3 * study["scores"][study["best"]]


def test_dynamic_fit_refusals():
    reference, sweeps = synthetic_set(1, points=2, repeats=1)
    with pytest.raises(CalibrationError, match="2 points cannot fit 8 coefficients"):
        fit_dynamic(reference, sweeps)
    with pytest.raises(CalibrationError, match="orders"):
        fit_dynamic(reference, sweeps, (0, 1))


# --- file and compensator ---------------------------------------------------------------

def calibration():
    reference, sweeps = synthetic_set(1)
    dynamics = MotorDynamics(rate=40.0, drag=0.5, limit=np.inf, exponent=1, freewheel=True,
                             gain=np.array([2e-5, 1.8e-5, 2.2e-5, 1.9e-5]))
    return Calibration(4, StaticCalibration(A_TRUE, B_TRUE, NORM), fit_dynamic(reference, sweeps), dynamics,
                       reference, {"origin": "synthetic"})


def test_calibration_file_round_trip(tmp_path):
    cal = calibration()
    path = cal.save(tmp_path / "cal.json")
    back = Calibration.load(path, motors=4, orders=(4, 1))
    assert np.array_equal(back.static.A, cal.static.A) and np.array_equal(back.static.b_s, cal.static.b_s)
    assert np.array_equal(back.field.v, cal.field.v) and np.array_equal(back.field.theta, cal.field.theta)
    assert back.field.orders == (4, 1) and back.notes == {"origin": "synthetic"}
    assert np.array_equal(back.dynamics.vector(), cal.dynamics.vector())
    assert np.array_equal(back.reference, cal.reference)


@pytest.mark.parametrize("edit, kwargs, message", [
    (lambda d: d.update(format="other"), {}, "not a magnetometer calibration"),
    (lambda d: d.update(version=7), {}, "version 7 is not supported"),
    (lambda d: d.pop("field"), {}, "missing key(s) field"),
    (lambda d: None, {"motors": 6}, "the file calibrates 4 motors; this vehicle has 6"),
    (lambda d: None, {"orders": (3, 1)}, "the file has orders I = 4, J = 1; (3, 1) were asked for"),
    (lambda d: d["field"].update(orders={"I": 3, "J": 1}), {}, "field.theta (orders I = 3, J = 1) must have shape"),
    (lambda d: d["field"]["v"].pop(), {}, "field.v must have shape (4, 3)"),
    (lambda d: d["static"].update(A=[[1, 0, 0], [0, 1, 0], [0, 0, "x"]]), {}, "static.A must be numbers"),
    (lambda d: d["dynamics"].update(exponent=2), {}, "dynamics.exponent must be 0 or 1"),
    (lambda d: d.update(motors=0), {}, "motors = 0 must be a positive integer"),
    (lambda d: d.update(notes=5), {}, "notes = 5 must be a JSON object"),
    (lambda d: d["static"].update(A=[[0, 0, 0]] * 3), {}, "static.A is singular (all zeros"),
    (lambda d: d["static"].update(field_norm=0.0), {}, "static.field_norm = 0.0 must be positive"),
    (lambda d: d["static"].update(field_norm=-4.7e-5), {}, "must be positive"),
    (lambda d: d["static"].update(A=[[[[[1.0]]]]]), {}, "static.A must have shape (3, 3)"),
])
def test_calibration_file_refusals(tmp_path, edit, kwargs, message):
    data = calibration().to_dict()
    edit(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(CalibrationError) as error:
        Calibration.load(path, **kwargs)
    print(error.value)
    assert message in str(error.value) and str(path) in str(error.value)


def test_calibration_file_not_json(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text("{ motors: 4")
    with pytest.raises(CalibrationError, match="not valid JSON"):
        Calibration.load(path)


def test_calibration_file_nested_too_deeply_or_not_utf8(tmp_path):
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(CalibrationError, match="nested too deeply"):
        Calibration.load(deep)
    latin = tmp_path / "latin.json"
    latin.write_bytes('{"notes": "étalonnage"}'.encode("latin-1"))
    with pytest.raises(CalibrationError, match=r"not UTF-8 text \(byte 0xe9 at offset 11\)"):
        Calibration.load(latin)


def test_static_fit_of_constant_samples_is_a_calibration_error():
    with pytest.raises(CalibrationError, match="the 200 samples are all equal"):
        fit_static(np.zeros((200, 3)))


def test_eq9_removes_the_modelled_field():
    cal = calibration()
    rng = np.random.default_rng(5)
    c = rng.uniform(0, 1, size=(200, 4))
    u = np.full(200, 11.8)
    raw = REFERENCE + cal.field.field(c, u)
    out = compensate(cal, np.arange(200) * 1e-3, raw, c, u, "metge")
    assert np.abs(out - np.linalg.solve(A_TRUE, REFERENCE - B_TRUE)).max() < 1e-12 * NORM
    static = compensate(cal, np.arange(200) * 1e-3, raw, c, u, "static")
    assert np.abs(static - np.linalg.solve(A_TRUE, (raw - B_TRUE).T).T).max() < 1e-12 * NORM


@pytest.mark.parametrize("mode", ["static", "metge", "dynamic"])
def test_streaming_block_equals_arrays(mode):
    from quadcosim.orchestrator import System, Table

    cal = calibration()
    rng = np.random.default_rng(2)
    steps, dt = 500, 1e-3
    c = np.clip(0.5 + 0.3 * np.sin(np.arange(steps)[:, None] * 0.02 + np.arange(4)), 0, 1)
    u = 11.7 + 0.1 * rng.normal(size=steps)
    mag = REFERENCE + rng.normal(scale=1e-6, size=(steps, 3))
    system = System(dt)
    system.add(Table("Rig", ["magneto_x", "magneto_y", "magneto_z", "c1", "c2", "c3", "c4", "u_batt"],
                     np.column_stack([mag, c, u])))
    system.add(MagCompensator(cal, mode, sample_rate=100.0))
    system.connect("Rig.magneto", "MagCompensator.magneto")
    for name in ("c1", "c2", "c3", "c4", "u_batt"):
        system.connect(f"Rig.{name}", f"MagCompensator.{name}")
    result = system.run((steps - 1) * dt)
    batch = compensate(cal, result.time, mag[:len(result)], c[:len(result)], u[:len(result)], mode, 100.0)
    difference = np.abs(result["MagCompensator.magneto"] - batch).max()
    print(f"{mode}: streaming - arrays = {difference:.1e} T over {len(result)} steps")
    assert difference <= 1e-12 * NORM
