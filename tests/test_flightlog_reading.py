"""Reading real PX4 and ArduPilot logs: what they hold, and their units against known values."""

import numpy as np
import pytest
from quadcosim.flightlogs import LogError, read_log
from quadcosim.flightlogs.info import summary

from tests.flightlog_data import COPTER36, COPTER43, ERLE, PX4, QUAD, log, path

# WMM 2015 at the quad's GPS position (42.356 N, 71.299 W), October 2015: 51.9 uT total
BOSTON_FIELD_T = 51.9e-6
GRAVITY = 9.81

# (file, format, compasses, IMUs, current sensor, duration (s)) as the data folder's README states them
EXPECTED = [
    (QUAD[0], "dataflash-text", ["MAG", "MAG2"], ["IMU", "IMU2"], True, 106.5),
    (QUAD[1], "dataflash-text", ["MAG", "MAG2"], ["IMU", "IMU2"], True, 67.8),
    (QUAD[2], "dataflash-text", ["MAG", "MAG2"], ["IMU", "IMU2"], True, 112.9),
    # 226.2 s logged: two flights apart by a 26.0 s stall from 37.6 s; the longer (63.6 to 240.2 s) is kept
    (ERLE, "dataflash-binary", ["MAG"], ["IMU"], False, 176.6),
    (COPTER43, "dataflash-binary", ["MAG[0]", "MAG[1]"], ["IMU[0]", "IMU[1]", "IMU[2]"], True, 98.0),
    # 80.5 s logged: the 9.2 s before the 21.2 s stall from 74.8 s and the crash from 143.2 s cut
    (COPTER36, "dataflash-binary", ["MAG", "MAG2", "MAG3"], ["IMU", "IMU2", "IMU3"], True, 47.2),
    (PX4, "ulog", ["sensor_combined.magnetometer_ga"], ["sensor_combined"], False, 68.9),
]


@pytest.mark.parametrize(("name", "kind", "compasses", "imus", "current", "duration"), EXPECTED)
def test_log_info_is_right_for_every_shared_log(name, kind, compasses, imus, current, duration):
    info = summary(log(name))
    assert info["format"] == kind
    assert [c["name"] for c in info["compasses"]] == compasses
    assert [i["name"] for i in info["imus"]] == imus
    assert info["current_sensor"] is current
    assert info["simulator"] is False
    assert info["duration_s"] == pytest.approx(duration, abs=0.1)
    assert info["motors"]["count"] == 4
    assert info["vehicle"].startswith("quadrotor")
    assert info["attitude"] is not None


@pytest.mark.parametrize("name", [QUAD[1], ERLE])
def test_dataflash_rates_and_compass_location_as_logged(name):
    info = summary(log(name))
    if name == ERLE:
        assert info["firmware"] == "APM:Copter V3.4-rc2 (f46a31d0)"
        assert [c["external"] for c in info["compasses"]] == [False]
        assert info["battery"]["current_sensor"].startswith("none")
    else:  # MAG and MAG2 at about 10 Hz, IMU at about 48 Hz (the data README)
        assert info["firmware"] == "APM:Copter V3.4-dev (461eff25)"
        assert [c["external"] for c in info["compasses"]] == [True, False]
        assert [c["rate_hz"] for c in info["compasses"]] == pytest.approx([9.6, 9.6], abs=0.1)
        assert [i["rate_hz"] for i in info["imus"]] == pytest.approx([48.1, 48.1], abs=0.1)
        assert info["battery"]["current_range_A"] == pytest.approx([1.25, 25.38], abs=0.01)


@pytest.mark.parametrize("name", [*QUAD, ERLE, PX4])
def test_units_field_norm_is_the_local_earth_field_and_gravity_at_rest(name):
    flight = log(name)
    compass = flight.compasses[0]
    norm = np.median(np.linalg.norm(compass.field, axis=1))
    if name in QUAD:  # the external compass, calibrated, at the log's GPS position
        assert norm == pytest.approx(BOSTON_FIELD_T, abs=2.5e-6)
    else:  # position not logged: within the Earth's range, in tesla not gauss
        assert 25e-6 < norm < 65e-6
    imu = flight.imus[0]
    rest = np.interp(imu.time, flight.motors.time, flight.motors.throttle) < 0.15  # motors idle: on the ground
    assert rest.sum() > 20
    # m/s^2; the Erle-Brain's accelerometer reads 10.20 at rest (uncalibrated, 4 % high)
    assert np.linalg.norm(imu.acc[rest], axis=1).mean() == pytest.approx(GRAVITY, abs=0.45 if name == ERLE else 0.15)
    assert np.abs(np.median(imu.gyro[rest], axis=0)).max() < 0.01  # rad/s, not deg/s
    assert imu.acc[rest, 2].mean() < -9.5  # FRD: level at rest reads -g on z


def test_raw_field_is_the_logged_one_with_arduPilot_offsets_undone():
    flight = log(QUAD[1])
    internal = flight.compasses[1]
    offsets_T = np.array([flight.params[f"COMPASS_OFS2_{a}"] for a in "XYZ"]) * 1e-7  # milligauss
    assert np.abs(internal.field - internal.raw - offsets_T).max() < 1.01e-7  # logged as whole milligauss
    assert internal.offsets == pytest.approx(-offsets_T, abs=1e-7)


def test_attitude_is_ned_from_frd_and_motors_are_normalised():
    flight = log(QUAD[1])
    q = flight.attitude.q
    assert np.linalg.norm(q, axis=1) == pytest.approx(1.0, abs=1e-9)
    motors = flight.motors
    assert (motors.pwm_min, motors.pwm_max) == (990.0, 2017.0)
    assert motors.commands.min() >= 0.0 and motors.commands.max() <= 1.0
    assert motors.commands[0] == pytest.approx((motors.pwm[0] - 990.0) / 1027.0)


def test_unknown_empty_truncated_and_corrupt_logs_are_named(tmp_path):
    source = path(ERLE).read_bytes()
    cases = {"notes.txt": b"take-off at 12:00\n", "empty.bin": b"", "head.bin": source[:1500]}
    messages = {"notes.txt": "unknown log format", "empty.bin": "empty", "head.bin": "no sensor messages"}
    for name, content in cases.items():
        (tmp_path / name).write_bytes(content)
        with pytest.raises(LogError, match=messages[name]) as error:
            read_log(tmp_path / name)
        assert str(tmp_path / name) in str(error.value)
    cut = tmp_path / "cut.bin"
    cut.write_bytes(source[:300_001])
    assert any(w.startswith("truncated") for w in read_log(cut).warnings)
    damaged = bytearray(source[:300_000])
    damaged[150_000:150_400] = bytes(400)
    (tmp_path / "damaged.bin").write_bytes(bytes(damaged))
    warnings = read_log(tmp_path / "damaged.bin").warnings
    assert any(w.startswith("corrupt stretches skipped") for w in warnings), warnings


def test_log_info_and_plot_commands(tmp_path, capsys):
    from quadcosim.main import main

    assert main(["log", "info", str(path(QUAD[1]))]) == 0
    shown = capsys.readouterr().out
    assert "compass 1 MAG2: 652 samples at 9.6 Hz, internal" in shown
    assert "current sensor: yes, 1.2 to 25.4 A" in shown
    assert "real hardware; 67.8 s" in shown
    figure = tmp_path / "overview.png"
    assert main(["log", "plot", str(path(PX4)), "--out", str(figure)]) == 0
    assert figure.stat().st_size > 20_000
    (tmp_path / "flight.csv").write_text("time,roll\n0,0\n")
    assert main(["log", "info", str(tmp_path / "flight.csv")]) == 2
    assert "unknown log format" in capsys.readouterr().err


def test_a_ulog_with_current_px4_topics(tmp_path):
    from quadcosim.calibration.flight import calibrate, flight_data

    from tests.flightlog_ulog_synthetic import write_ulog

    truth = write_ulog(tmp_path / "sitl.ulg")
    flight = read_log(tmp_path / "sitl.ulg")
    info = summary(flight)
    assert info["simulator"] is True and info["firmware"] == "v1.15.0 on PX4_SITL"
    assert [c["name"] for c in info["compasses"]] == ["sensor_mag[0]", "sensor_mag[1]"]
    assert [c["rate_hz"] for c in info["compasses"]] == pytest.approx([50.0, 50.0])
    assert info["imus"][0]["acc_norm_m_s2"] == pytest.approx(GRAVITY, abs=1e-4)
    compass = flight.compasses[0]
    assert compass.offsets == pytest.approx(truth["hard_iron"], abs=1e-12)  # CAL_MAG0_*OFF, gauss to tesla
    assert np.abs(compass.field - (compass.raw - truth["hard_iron"])).max() < 1e-12
    assert flight.motors.limits_from == "PWM_MAIN_MIN/PWM_MAIN_MAX" and 0.3 < flight.motors.throttle.mean() < 0.6
    assert flight.battery.current is not None
    train, test = flight_data(flight, 0).split(0.5)
    metrics, _, _ = calibrate([train], [test], ("current",))
    current = metrics["models"]["current"]
    assert np.abs(np.array(current["coefficients"]["K_T_per_A"]) - truth["K"]).max() < 0.01 * np.linalg.norm(truth["K"])
    assert current["delay_s"] == pytest.approx(truth["delay"], abs=1e-9)
