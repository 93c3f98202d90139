"""The exported parameter files, applied with each firmware's equations written out here (not the
project's), give the figures metrics.json reports; offsets come back against the Earth field
model from a flight that only yaws; a compass never calibrated is never exported with zeros."""

import json

import numpy as np
import pytest
from quadcosim.calibration.flight import flight_data
from quadcosim.calibration.flight.autopilot import read_parameters
from quadcosim.flightlogs import read_log

from quadcosim.main import main
from tests.flightlog_synthetic import write_log
from tests.flightlog_ulog_synthetic import write_ulog

MG, GAUSS = 1e-7, 1e-4


def _ardupilot(params: dict, raw_T, current, throttle, version) -> np.ndarray:
    """ArduPilot's AP_Compass_Backend::correct_field for compass 0, written from its source."""
    get = lambda name, default=0.0: float(params.get(name, default))  # noqa: E731
    dia = np.array([get(f"COMPASS_DIA_{a}") for a in "XYZ"])
    odi = np.array([get(f"COMPASS_ODI_{a}") for a in "XYZ"])
    if not dia.any():
        dia = np.ones(3)
    M = np.array([[dia[0], odi[0], odi[1]], [odi[0], dia[1], odi[2]], [odi[1], odi[2], dia[2]]])
    kind = get("COMPASS_MOTCT")
    x = current if kind == 2 else throttle if kind == 1 else np.zeros(len(raw_T))
    mot = np.outer(x, [get(f"COMPASS_MOT_{a}") for a in "XYZ"])
    raw = raw_T / MG + [get(f"COMPASS_OFS_{a}") for a in "XYZ"]
    scale = get("COMPASS_SCALE", 1.0) if version >= (4, 0) and 1 / 1.5 <= get("COMPASS_SCALE", 1.0) <= 1.5 else 1.0
    field = (scale * raw) @ M.T + mot if version >= (3, 6) else (raw + mot) @ M.T
    return field * MG


def _px4(params: dict, raw_T, current, thrust) -> np.ndarray:
    """PX4's calibration::Magnetometer::Correct for slot 0, internal, board not rotated."""
    get = lambda name, default=0.0: float(params.get(name, default))  # noqa: E731
    d = [get(f"CAL_MAG0_{a}SCALE", 1.0) for a in "XYZ"]
    o = [get(f"CAL_MAG0_{a}ODIAG") for a in "XYZ"]
    S = np.array([[d[0], o[0], o[1]], [o[0], d[1], o[2]], [o[1], o[2], d[2]]])
    kind = get("CAL_MAG_COMP_TYP")
    p = current / 1000.0 if kind == 2 else thrust if kind == 1 else np.zeros(len(raw_T))
    raw = raw_T / GAUSS + np.outer(p, [get(f"CAL_MAG0_{a}COMP") for a in "XYZ"])
    return (raw - [get(f"CAL_MAG0_{a}OFF") for a in "XYZ"]) @ S.T * GAUSS


def _heading_error(field, euler) -> np.ndarray:
    """Tilt-compensated heading of ``field`` against the attitude's, wrapped, nothing removed (rad)."""
    roll, pitch, yaw = euler.T
    x, y, z = field.T
    north = x * np.cos(pitch) + (y * np.sin(roll) + z * np.cos(roll)) * np.sin(pitch)
    east = y * np.cos(roll) - z * np.sin(roll)
    return np.angle(np.exp(1j * (np.arctan2(-east, north) - yaw)))


def _heading_rms(corrected, data) -> float:
    """Heading error (deg RMS) on the score part (``data``'s held-out half's second half) of the field
    ``corrected(part)`` gives, less its circular mean on the fit and choice parts (the first half and
    the held-out half's first half), frozen."""
    fit, held = data.split(0.5)
    choice, score = held.split(0.5)
    unscored = np.concatenate([_heading_error(corrected(p), p.euler) for p in (fit, choice)])
    offset = np.angle(np.mean(np.exp(1j * unscored)))
    error = np.angle(np.exp(1j * (_heading_error(corrected(score), score.euler) - offset)))
    return float(np.degrees(np.sqrt(np.mean(error**2))))


# (Copter version, the compass parameters its firmware applied while logging)
VERSIONS = [
    ((3, 4), {"COMPASS_OFS_X": 40.0, "COMPASS_OFS_Y": -60.0, "COMPASS_OFS_Z": 25.0, "COMPASS_DIA_X": 1.04,
              "COMPASS_DIA_Y": 0.97, "COMPASS_DIA_Z": 1.01, "COMPASS_ODI_X": 0.02, "COMPASS_MOTCT": 2,
              "COMPASS_MOT_X": 1.5, "COMPASS_MOT_Y": -2.0, "COMPASS_MOT_Z": 3.0}),
    ((3, 6), {"COMPASS_OFS_X": 40.0, "COMPASS_OFS_Y": -60.0, "COMPASS_OFS_Z": 25.0, "COMPASS_DIA_X": 1.04,
              "COMPASS_DIA_Y": 0.97, "COMPASS_DIA_Z": 1.01, "COMPASS_ODI_X": 0.02, "COMPASS_MOTCT": 1,
              "COMPASS_MOT_X": 20.0, "COMPASS_MOT_Y": -30.0, "COMPASS_MOT_Z": 40.0}),
    ((4, 5), {"COMPASS_OFS_X": 40.0, "COMPASS_OFS_Y": -60.0, "COMPASS_OFS_Z": 25.0, "COMPASS_SCALE": 1.05,
              "COMPASS_MOTCT": 2, "COMPASS_MOT_X": 1.5, "COMPASS_MOT_Y": -2.0, "COMPASS_MOT_Z": 3.0}),
]


@pytest.mark.parametrize(("version", "compass"), VERSIONS, ids=["3.4", "3.6", "4.5-scale"])
def test_ardupilot_parm_applied_by_each_versions_equations_gives_the_reported_figures(tmp_path, version, compass):
    truth = write_log(tmp_path / "flight.log", gps=True, version=version, compass=compass, tumble=3.0,
                      trim=(0.01, 0.03), seed=5)
    assert main(["calibrate", str(tmp_path / "flight.log"), "--out", str(tmp_path / "out"), "--models", "current",
                 "throttle"]) == 0
    metrics = json.loads((tmp_path / "out" / "metrics.json").read_text())
    log = read_log(tmp_path / "flight.log")
    data = flight_data(log, 0)
    # the raw field the reader recovered gives back the logged field through the log's own parameters
    logged = log.compasses[0].field
    replayed = _ardupilot(log.params, log.compasses[0].raw, np.interp(log.compasses[0].time, log.battery.time,
                                                                       log.battery.current),
                          np.interp(log.compasses[0].time, log.throttle.time, log.throttle.value), version)
    assert np.abs(replayed - logged).max() < 1.5 * MG  # whole milligauss logged; measured 1.0 mG
    params = read_parameters(tmp_path / "out" / "ardupilot.parm")
    for label, chosen, reported in (("export", {**log.params, **params}, metrics["export"]["heading_rms_deg"]),
                                    ("as flown", log.params, metrics["export"]["as_flown"]["heading_rms_deg"])):
        def corrected(part, chosen=chosen):
            return _ardupilot(chosen, part.raw, part.current(), part.autopilot_throttle(), version)

        assert _heading_rms(corrected, data) == pytest.approx(reported, abs=1e-6), label
    # the export beats what the log flew with; offsets within 0.5 uT of the truth
    assert metrics["export"]["heading_rms_deg"] < metrics["export"]["as_flown"]["heading_rms_deg"]
    if metrics["export"]["kept"]["offsets"] == "fitted" and metrics["export"]["kept"]["soft_iron"] == "log":
        exported = np.array([params[f"COMPASS_OFS_{a}"] for a in "XYZ"]) * MG
        assert np.abs(exported + truth["hard_iron"]).max() < 0.5e-6


def test_px4_params_applied_by_px4s_equations_gives_the_reported_figures(tmp_path):
    write_ulog(tmp_path / "flight.ulg")
    assert main(["calibrate", str(tmp_path / "flight.ulg"), "--out", str(tmp_path / "out"), "--models",
                 "current"]) == 0
    metrics = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert metrics["export"]["file"] == "px4.params" and metrics["export"]["model"] == "current"
    params = read_parameters(tmp_path / "out" / "px4.params")
    assert params["CAL_MAG_COMP_TYP"] == 2
    log = read_log(tmp_path / "flight.ulg")
    def corrected(part):
        return _px4({**log.params, **params}, part.raw, part.current(), part.autopilot_throttle())

    assert _heading_rms(corrected, flight_data(log, 0)) == pytest.approx(metrics["export"]["heading_rms_deg"],
                                                                          abs=1e-6)
    # measured 0.53 deg exported against 8.34 as flown: the current's field removed
    assert metrics["export"]["heading_rms_deg"] < 0.12 * metrics["export"]["as_flown"]["heading_rms_deg"]


def test_a_yaw_only_flight_gives_all_three_offsets_against_the_field_model_and_is_refused_without_gps(tmp_path, capsys):
    settings = {"tumble": 0.0, "trim": (0.02, -0.03), "orient": 6, "hard_iron": np.array([12e-6, -25e-6, 9e-6])}
    truth = write_log(tmp_path / "gps.log", gps=True, **settings)
    write_log(tmp_path / "nogps.log", gps=False, **settings)
    assert main(["calibrate", str(tmp_path / "gps.log"), "--out", str(tmp_path / "gps"), "--models", "current"]) == 0
    metrics = json.loads((tmp_path / "gps" / "metrics.json").read_text())
    assert metrics["export"]["kept"]["offsets"] == "fitted"
    params = read_parameters(tmp_path / "gps" / "ardupilot.parm")
    exported = np.array([params[f"COMPASS_OFS_{a}"] for a in "XYZ"]) * MG
    assert np.abs(exported + truth["hard_iron"]).max() < 0.5e-6  # the acceptance bound; measured 0.07 uT, z included
    assert abs(metrics["mounting"]["offset_deg"]) < 0.5  # COMPASS_ORIENT declared the mounting; measured 0.21 deg
    capsys.readouterr()
    assert main(["calibrate", str(tmp_path / "nogps.log"), "--out", str(tmp_path / "nogps"), "--models",
                 "current"]) == 2
    err = capsys.readouterr().err
    assert "offsets are all zero (never calibrated)" in err and "cannot tell the z offset" in err
    assert not (tmp_path / "nogps" / "ardupilot.parm").exists()


def test_a_compass_never_calibrated_is_never_exported_with_zero_offsets(tmp_path, capsys):
    truth = write_log(tmp_path / "tumbling.log", gps=False, tumble=20.0, seed=3)  # zero offsets, no GPS
    assert main(["calibrate", str(tmp_path / "tumbling.log"), "--out", str(tmp_path / "out"), "--models",
                 "current"]) == 0
    params = read_parameters(tmp_path / "out" / "ardupilot.parm")
    exported = np.array([params[f"COMPASS_OFS_{a}"] for a in "XYZ"]) * MG
    assert np.abs(exported + truth["hard_iron"]).max() < 0.2e-6  # the rotations identify them (measured 0.09 uT)
    assert np.abs(exported).min() > 40 * MG


def test_a_compass_mounted_at_an_undeclared_yaw_is_reported(tmp_path, capsys):
    write_log(tmp_path / "turned.log", gps=True, tumble=1.0, mount_yaw_deg=12.0)
    assert main(["calibrate", str(tmp_path / "turned.log"), "--out", str(tmp_path / "out"), "--models",
                 "current"]) == 0
    out = capsys.readouterr().out
    metrics = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert metrics["mounting"]["offset_deg"] == pytest.approx(-12.0, abs=0.5)  # measured -12.24 deg
    assert not metrics["mounting"]["within_tolerance"] and "check its yaw mounting" in out


def test_score_judges_any_parameter_file_with_the_exports_own_scorer(tmp_path, capsys):
    write_log(tmp_path / "flight.log", gps=True)
    assert main(["calibrate", str(tmp_path / "flight.log"), "--out", str(tmp_path / "out"), "--models",
                 "current"]) == 0
    metrics = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert main(["calibrate", str(tmp_path / "flight.log"), "--score", str(tmp_path / "out" / "ardupilot.parm"),
                 "--out", str(tmp_path / "scored")]) == 0
    scored = json.loads((tmp_path / "scored" / "metrics.json").read_text())
    # the file holds 9 significant digits: the same figure to 1e-6 deg (measured 3e-9)
    assert scored["score"]["heading_rms_deg"] == pytest.approx(metrics["export"]["heading_rms_deg"], abs=1e-6)
    assert scored["as_flown"]["heading_rms_deg"] == pytest.approx(metrics["export"]["as_flown"]["heading_rms_deg"],
                                                                  abs=1e-9)
    # a partial file in MAVProxy's "NAME VALUE" form applies on top of the log's parameters
    (tmp_path / "partial.parm").write_text(f"COMPASS_MOTCT 2\nCOMPASS_MOT_X {-0.3e-6 / MG}\n")
    assert main(["calibrate", str(tmp_path / "flight.log"), "--score", str(tmp_path / "partial.parm"),
                 "--out", str(tmp_path / "partial")]) == 0
    partial = json.loads((tmp_path / "partial" / "metrics.json").read_text())["score"]
    assert partial["parameters"] == 2 and 0 < partial["explained"] < 1


def test_the_log_motor_compensation_carried_into_a_trial_leaves_its_offsets_and_soft_iron_alone():
    from quadcosim.flightlogs.autopilots import of

    def _motor_keys(params, autopilot):  # what the export carries of the log's motor compensation
        return {k for k in params if of(autopilot).is_motor_key(k)}

    ardupilot = {"COMPASS_OFS2_X": -27.0, "COMPASS_DIA2_X": 1.0, "COMPASS_ODI2_X": 0.0, "COMPASS_SCALE": 1.0,
                 "COMPASS_MOTCT": 2, "COMPASS_MOT2_X": 0.5, "COMPASS_PMOT1_X": 0.1, "COMPASS_PMOT_EN": 1}
    px4 = {"CAL_MAG0_XOFF": 0.1, "CAL_MAG0_XSCALE": 1.0, "CAL_MAG0_XCOMP": 0.2, "CAL_MAG_COMP_TYP": 2}
    assert _motor_keys(ardupilot, "ArduPilot") == {"COMPASS_MOTCT", "COMPASS_MOT2_X", "COMPASS_PMOT1_X",
                                                   "COMPASS_PMOT_EN"}
    assert _motor_keys(px4, "PX4") == {"CAL_MAG0_XCOMP", "CAL_MAG_COMP_TYP"}
