"""The calibration scenarios on short horizons: static-cal recovers the IMU's soft and hard
iron; metge reproduces the shape of Metge et al.'s Table 1 and the motor-dynamics gain."""

import numpy as np
import pytest

import scenarios


def test_static_cal_recovers_the_iron_of_the_imu(tmp_path):
    _, m = scenarios.run("static-cal", {"duration": 40.0}, out_dir=tmp_path)
    print({k: m[k] for k in ("A_error_max", "b_s_error_max_uT", "quality", "heading_error_max_deg")})
    assert m["A_error_max"] < 1e-3
    assert m["b_s_error_max_uT"] < 0.03
    assert m["heading_error_max_deg"] < 0.15 < 40 < m["heading_error_uncorrected_max_deg"]
    assert m["quality"]["coverage"] > 0.9
    assert (tmp_path / "static.json").exists()


@pytest.mark.slow
def test_metge_table1_and_the_motor_dynamics(tmp_path):
    _, m = scenarios.run("metge", {"levels": 6, "free": 6.0}, out_dir=tmp_path)
    table = m["table1_deg"]
    print(table, m["free_set_dynamic_deg"], m["direction_error_deg"], m["free_eq9_slow_fast_deg"])
    for row in ("calibration1", "calibration2"):
        for column in ("set1", "set2"):
            assert table["none"][column] / table[row][column] > 15
        assert table[row]["free"] < 0.8 * table["none"]["free"]
    assert np.max(m["direction_error_deg"]["calibration1"]) < 1.0
    assert m["free_eq9_slow_fast_deg"]["fast"] > 2 * m["free_eq9_slow_fast_deg"]["slow"]
    assert m["free_set_dynamic_deg"] < table["calibration1"]["free"] / 2
    assert {"calibration1.json", "calibration2.json", "figure3_free_set.png", "table1.md"} <= {
        p.name for p in tmp_path.iterdir()}


@pytest.mark.slow
def test_tp_compensation_restores_the_yaw(tmp_path):
    """The closed loop with the motor field at the magnetometer: the explicit filter's yaw
    error without and with the dynamics-aware compensation, from a rig calibration."""
    scenarios.run("metge", {"levels": 6, "free": 3.0}, out_dir=tmp_path / "metge")
    yaw, calibration = {}, str(tmp_path / "metge" / "calibration1.json")
    for mode in ("none", "dynamic"):
        _, m = scenarios.run("tp", {"estimator": "explicit", "magnetic": True, "noise": True, "duration": 6.0,
                                    "compensation": mode, "calibration": calibration if mode != "none" else ""})
        yaw[mode] = m["rms_error_deg"][2]
    print(f"explicit filter, yaw RMS: {yaw['none']:.3f} deg uncompensated, {yaw['dynamic']:.3f} deg compensated")
    assert yaw["dynamic"] < yaw["none"] / 20


KAPPA1 = 8e-6  # T/A, against the default vehicle's 2.78e-6: motor 1's cable field x2.88
SHORT_RIG = {"levels": 4, "hold": 0.3, "settle": 0.2, "free": 1.0}


@pytest.mark.slow
def test_a_block_parameter_reaches_every_rig_run_and_both_calibrations():
    """`--set MotorMagnetics.kappa1=...` changes the field of motor 1 in both calibration sets
    (each set's runs identify its calibration's gains): motor 1's identified gain scales with
    kappa1 in calibration 1 and calibration 2, the other motors' do not move."""
    from fmus import vehicle

    gains = {}
    for kappa in (None, KAPPA1):
        settings = SHORT_RIG | ({"MotorMagnetics.kappa1": KAPPA1} if kappa else {})
        _, m = scenarios.run("metge", settings)
        gains[kappa] = {name: np.array(d["gain"]) for name, d in m["motor_dynamics"].items()}
    expected = KAPPA1 / vehicle.MOTOR_FIELD_GAIN[0]
    for name in ("calibration1", "calibration2"):
        ratio = gains[KAPPA1][name] / gains[None][name]
        print(name, ratio)
        assert ratio[0] == pytest.approx(expected, rel=0.01)
        assert ratio[1:] == pytest.approx(np.ones(3), rel=0.01)


@pytest.mark.slow
def test_tp_calibrates_on_the_rig_of_its_own_vehicle():
    """tp's automatic rig calibration takes tp's vehicle settings (not the gyro bias of its flight)."""
    from fmus import vehicle
    from scenarios.metge import rig_calibration

    tp = scenarios.get("tp")
    options = tp.parse({"magnetic": True, "compensation": "dynamic", "MotorMagnetics.kappa1": KAPPA1,
                        "bias": True, "IMU.gyro_bias": "0.01,0,0"})
    compensator = tp.system(options).blocks["MagCompensator"]
    settings = (("MotorMagnetics.kappa1", str(KAPPA1)),)
    assert rig_calibration.cache_info().currsize >= 1
    calibrated, default = rig_calibration(settings=settings), rig_calibration()
    assert compensator.calibration is calibrated
    ratio = np.array(calibrated.dynamics.gain) / np.array(default.dynamics.gain)
    assert ratio[0] == pytest.approx(KAPPA1 / vehicle.MOTOR_FIELD_GAIN[0], rel=0.01)
    assert ratio[1:] == pytest.approx(np.ones(3), rel=0.01)


def test_a_calibration_file_with_compensation_none_is_refused():
    with pytest.raises(ValueError, match="compensation=none, which uses no calibration"):
        scenarios.get("tp").system(scenarios.get("tp").parse({"calibration": "results/missing.json"}))
