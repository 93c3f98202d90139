"""PX4 1.9 to 1.15 as read: the shared PX4 logs through every flight-log command, compasses matched
to their ``CAL_MAGn`` slot by device id with their priority, ``vehicle_magnetometer`` beside
``sensor_mag``, the motor outputs normalised by the PWM limits of each era or PX4's defaults, and a
log whose compass is logged too slowly refused with the rate it needs and the setting that gives it."""

import json

import numpy as np
import pytest
from quadcosim.calibration.flight.data import MIN_COMPASS_RATE_HZ
from quadcosim.flightlogs import read_log
from quadcosim.flightlogs.autopilots.px4 import firmware as px4
from quadcosim.flightlogs.info import summary

from quadcosim.main import main
from tests.flightlog_data import PX4, path
from tests.flightlog_synthetic import _commands
from tests.flightlog_ulog_synthetic import PWM_LAYOUTS, write_ulog

TROPIC = "px4_tropic_flight.ulg"


@pytest.mark.parametrize("name", [PX4, TROPIC])
def test_every_command_runs_on_the_shared_px4_logs_without_a_traceback(name, tmp_path, capsys):
    log = str(path(name))
    assert main(["log", "info", log]) == 0
    assert main(["log", "plot", log, "--out", str(tmp_path / "overview.png")]) == 0
    assert (tmp_path / "overview.png").stat().st_size > 20_000
    assert main(["log", "replay", log]) == 0
    replayed = capsys.readouterr().out
    if name == TROPIC:  # replayed, without a compensation fitted on a compass logged at 1 Hz, and said so
        assert "compensation: none: " in replayed and "SDLOG_PROFILE = 65" in replayed
    code = main(["calibrate", log, "--out", str(tmp_path / "cal")])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    if name == TROPIC:
        # sensor_mag at 1.0 Hz under the default logging profile: refused, naming the rate and the setting
        assert code == 2 and "sensor_mag[0] is logged at 1.0 Hz" in err
        assert f"needs the compass at {MIN_COMPASS_RATE_HZ:g} Hz or faster" in err
        assert "SDLOG_PROFILE = 65" in err and "sensor comparison bit (64" in err
        assert not (tmp_path / "cal").exists()
    else:  # the bench log, never armed: no throttle variation to identify a model with, refused by name
        assert code == 2 and "no interference model could be identified" in err


def test_the_tropic_flights_compasses_are_matched_by_device_id_with_their_priority():
    log = read_log(path(TROPIC))
    info = summary(log)
    assert info["firmware"] == "v1.15.0 (beta) on NXP_MR_TROPIC"
    names = [c["name"] for c in info["compasses"]]
    assert names == ["sensor_mag[0]", "sensor_mag[1]", "vehicle_magnetometer[0]"]
    rates = [c["rate_hz"] for c in info["compasses"]]
    assert rates == pytest.approx([1.0, 1.0, 2.0], abs=0.02)  # the default profile: 1000 ms and 500 ms intervals
    setups = [c["setup"] for c in info["compasses"]]
    # CAL_MAG0_ID 396809 (external, CAL_MAG0_PRIO 75), CAL_MAG1_ID 15012897 (internal, 50): the selected one,
    # vehicle_magnetometer, is the external sensor of the highest priority, found by its own device id
    assert [s["slot"] for s in setups] == ["CAL_MAG0", "CAL_MAG1", "CAL_MAG0"]
    assert [s["priority"] for s in setups] == ["75", "50", "75"]
    assert [s["device_id"] for s in setups] == ["396809", "15012897", "396809"]
    assert [c.external for c in log.compasses] == [True, False, True]
    # the selected sensor's calibrated field is its raw one through the same slot: one field, two rates
    raw, selected = log.compasses[0], log.compasses[2]
    at = np.column_stack([np.interp(raw.time, selected.time, selected.raw[:, k]) for k in range(3)])
    assert np.median(np.linalg.norm(at - raw.raw, axis=1)) < 0.1 * np.median(np.linalg.norm(raw.raw, axis=1))
    assert info["imus"][0]["name"] == "sensor_combined" and info["imus"][0]["rate_hz"] > 150


@pytest.mark.parametrize("layout", list(PWM_LAYOUTS))
def test_actuator_outputs_are_normalised_by_each_eras_pwm_limits_or_px4s_defaults(layout, tmp_path):
    truth = write_ulog(tmp_path / "flight.ulg", duration=6.0, pwm=layout)
    log = read_log(tmp_path / "flight.ulg")
    commands = _commands(log.motors.time)
    assert np.abs(log.motors.commands - commands).max() < 1e-4  # float32 outputs in us
    assert (log.motors.pwm_min, log.motors.pwm_max) == truth["pwm_limits"]
    expected = {"global": "PWM_MAIN_MIN/PWM_MAIN_MAX", "per_output": "PWM_MAIN_MINn/PWM_MAIN_MAXn",
                None: "PX4's defaults, 1000/2000 us"}[layout]
    assert log.motors.limits_from.startswith(expected)
    assert log.firmware.startswith("v1.11.3" if layout is None else "v1.15.0")


def test_pwm_limits_take_the_newest_layout_the_log_holds_for_every_output():
    per_output = {f"PWM_MAIN_MIN{n}": 1100 for n in range(1, 5)} | {f"PWM_MAIN_MAX{n}": 1900 for n in range(1, 5)}
    low, high, source = px4.pwm_limits(per_output | {"PWM_MIN": 1050, "PWM_MAX": 1950}, 4)
    assert (low.tolist(), high.tolist(), source) == ([1100.0] * 4, [1900.0] * 4, "PWM_MAIN_MINn/PWM_MAIN_MAXn")
    partial = {k: v for k, v in per_output.items() if not k.endswith("4")}  # output 4 not logged: the older pair
    assert px4.pwm_limits(partial | {"PWM_MIN": 1050, "PWM_MAX": 1950}, 4)[2] == "PWM_MIN/PWM_MAX"
    assert px4.pwm_limits({}, 4)[0].tolist() == [1000.0] * 4


def test_a_slot_s_priority_is_logged_or_the_firmware_s_default_and_zero_disables_it():
    assert px4.priority({"CAL_MAG1_PRIO": 0}, 1, True) == 0
    assert px4.priority({}, 0, True) == 75 and px4.priority({}, 0, False) == 50
    assert px4.priority({"CAL_MAG2_PRIO": 90}, 2, False) == 90


def test_log_info_json_carries_each_px4_compass_setup(capsys):
    assert main(["log", "info", str(path(TROPIC)), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["compasses"][1]["setup"]["orientation"] == "the board's, SENS_BOARD_ROT = 0"
    assert info["compasses"][0]["setup"]["use"] == "yes"
