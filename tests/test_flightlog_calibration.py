"""Magnetometer calibration from flights: a synthetic log with known interference, the real
quad's flights, refusals, and the exported autopilot parameters against the project's correction."""

import json

import numpy as np
import pytest
from helpers import documentation
from quadcosim.calibration import Calibration, StaticCalibration, compensate
from quadcosim.calibration.flight import autopilot, calibrate, flight_data
from quadcosim.calibration.flight.calibrate import _field_model
from quadcosim.flightlogs.autopilots.ardupilot import firmware as ardupilot
from quadcosim.flightlogs.autopilots.px4 import firmware as px4

from quadcosim.main import main
from tests.flightlog_data import ERLE, PX4, QUAD, log, path
from tests.flightlog_synthetic import write_log


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    folder = tmp_path_factory.mktemp("synthetic")
    truth = write_log(folder / "sitl.log")
    return folder, truth


def test_a_synthetic_flight_gives_back_its_current_interference_and_delay(synthetic, capsys):
    folder, truth = synthetic
    assert main(["calibrate", str(folder / "sitl.log"), "--compass", "0", "--out", str(folder / "out"),
                 "--models", "current", "throttle"]) == 0
    err = capsys.readouterr().err
    assert "simulator (SITL) log" in err
    metrics = json.loads((folder / "out" / "metrics.json").read_text())
    current = metrics["models"]["current"]
    K = np.array(current["coefficients"]["K_T_per_A"])
    assert np.abs(K - truth["K"]).max() < 0.01 * np.linalg.norm(truth["K"])  # measured 0.5 %
    assert current["delay_s"] == pytest.approx(truth["delay"], abs=1e-9)
    assert current["explained_test"] > 0.995  # measured 0.998: the rest is 0.1 uT noise and mG rounding
    assert current["heading_error_rms_deg"]["without"] > 5.0 > 0.4 > current["heading_error_rms_deg"]["with"]
    export = metrics["export"]
    assert export["model"] == "current" and export["file"] == "ardupilot.parm"
    assert metrics["static"]["source"] == "log" and metrics["static"]["coverage"] < 0.5
    params = autopilot.read_parameters(folder / "out" / "ardupilot.parm")
    assert params["COMPASS_MOTCT"] == 2
    # fitted without delay, as the firmware applies it: the 0.1 s delay costs a little of the vector
    exported = np.array([params[f"COMPASS_MOT_{a}"] for a in "XYZ"]) * 1e-7
    assert np.abs(exported + truth["K"]).max() < 0.05 * np.linalg.norm(truth["K"])
    assert export["heading_rms_deg"] < 0.2 * export["as_flown"]["heading_rms_deg"]
    assert not (folder / "out" / "px4.params").exists()  # an ArduPilot log exports ArduPilot's file
    assert Calibration.load(folder / "out" / "calibration.json", motors=4).field is not None
    for figure in ("residual.png", "heading.png"):
        assert (folder / "out" / figure).stat().st_size > 20_000


def test_exported_parameters_applied_as_each_firmware_does_reproduce_the_projects_correction():
    data = flight_data(log(QUAD[1]), 1)
    train, test = data.split(0.5)
    metrics, _, fitted = calibrate([train], [test], ("current", "throttle"))
    # a soft iron that is not the identity, so that the order of corrections matters
    A = np.array([[1.05, 0.03, -0.02], [0.03, 0.97, 0.01], [-0.02, 0.01, 1.02]])
    b = np.array([2e-6, -4.7e-5, 7e-6])
    correction = np.linalg.inv(A)
    current, throttle = test.current(), test.autopilot_throttle()
    for model, x in (("current", current), ("throttle", throttle)):
        K = fitted[model].extra["K"][0]
        ours = np.linalg.solve(A, (test.raw - b - np.outer(x, K)).T).T
        scale = np.abs(ours).max()
        for version in ((3, 4), (3, 6), (4, 5)):
            rule = ardupilot.rules(version)
            params = ardupilot.parameters(1, rule, b, correction, model, K)
            applied = ardupilot.apply(params, 1, rule, test.raw, current, throttle)
            # the same algebra as ours, in the firmware's order: equal to rounding (measured 2.8e-16)
            assert np.abs(applied - ours).max() < 1e-12 * scale
        params = px4.parameters(1, b, correction, model, K)
        applied = px4.apply(params | {"CAL_MAG1_ROT": 0}, 1, True, test.raw, current, throttle)
        assert np.abs(applied - ours).max() < 1e-12 * scale
    # the order matters once the soft iron is not the identity: 3.6's file loaded by 3.4 is off
    K = fitted["current"].extra["K"][0]
    newer = ardupilot.parameters(1, ardupilot.rules((3, 6)), b, correction, "current", K)
    older = ardupilot.apply(newer, 1, ardupilot.rules((3, 4)), test.raw, current, throttle)
    assert np.abs(older - np.linalg.solve(A, (test.raw - b - np.outer(current, K)).T).T).max() > 1e-8  # T
    # the throttle model in the file's form, through the project's compensator (eq. 9)
    static = StaticCalibration(A=A, b_s=b, field_norm=5e-5)
    _, field = _field_model({"throttle": fitted["throttle"]}, 4)
    commands = test.commands(fitted["throttle"].delay)
    compensated = compensate(Calibration(4, static, field), test.time, test.raw, commands, test.voltage(), "metge")
    K = fitted["throttle"].extra["K"][0]
    params = ardupilot.parameters(1, ardupilot.rules((4, 5)), b, correction, "throttle", K)
    applied = ardupilot.apply(params, 1, ardupilot.rules((4, 5)), test.raw, throttle=commands.mean(axis=1))
    assert np.abs(applied - compensated).max() < 1e-12 * np.abs(compensated).max()  # measured 2.7e-16


def test_the_quads_internal_compass_moves_with_the_current_and_the_external_barely():
    flight = log(QUAD[0])
    figures = {}
    for compass in (0, 1):
        train, test = flight_data(flight, compass).split(0.5)
        metrics, _, _ = calibrate([train], [test], ("current",))
        figures[compass] = metrics["models"]["current"]
    internal, external = figures[1], figures[0]
    K_internal = np.linalg.norm(internal["coefficients"]["K_T_per_A"])
    K_external = np.linalg.norm(external["coefficients"]["K_T_per_A"])
    assert K_internal > 1.5e-7 > K_external  # T/A: 1.5 mG/A
    assert internal["explained_test"] > 0.1


def test_logs_without_a_current_sensor_or_throttle_variation_refuse_with_the_reason(capsys, tmp_path):
    train, test = flight_data(log(ERLE), 0).split(0.5)
    metrics, _, fitted = calibrate([train], [test], ("current", "throttle"))
    assert metrics["models"]["current"]["refused"].startswith("no current sensor in the log")
    assert metrics["models"]["throttle"]["explained_test"] > 0.5  # the Erle-Brain's compass sits by its ESCs
    assert main(["calibrate", str(path(PX4)), "--out", str(tmp_path / "px4"), "--models", "throttle"]) == 2
    captured = capsys.readouterr()
    assert "too little throttle variation" in captured.out
    assert "px4_sample.ulg" in captured.err
    assert main(["calibrate", str(path(QUAD[1])), "--compass", "2", "--out", str(tmp_path / "none")]) == 2
    assert "no compass 2; the log holds 0: MAG, 1: MAG2" in capsys.readouterr().err


def test_the_readmes_calibration_example_prints_what_the_readme_shows(tmp_path, capsys):

    readme = documentation()
    command = "quadcosim calibrate logs/quad_2015-10-11_19-59-09.log --compass 1 --out " \
              "results/flight-b-internal"
    assert command in readme
    shown = readme.split("$ " + command + "\n", 1)[1].split("\n```", 1)[0]
    log = str(path(QUAD[1]))
    assert main(["calibrate", log, "--compass", "1", "--out", str(tmp_path / "b")]) == 0
    printed = capsys.readouterr().out.replace(log, "logs/quad_2015-10-11_19-59-09.log")
    printed = printed.replace(str(tmp_path / "b"), "results/flight-b-internal")
    assert printed.strip() == shown.strip()
    parameters = readme.split("ends with the motor compensation (milligauss per ampere, `COMPASS_MOTCT = 2`):"
                              "\n\n```text\n", 1)[1]
    written = (tmp_path / "b" / "ardupilot.parm").read_text().strip().splitlines()[-4:]
    assert parameters.split("\n```", 1)[0].splitlines() == written


def test_the_command_lines_defaults_are_the_calibrations_names():
    from quadcosim.calibration.flight.catalogue import models
    from quadcosim.scenarios.flightlog.calibrate import _check_choices

    from quadcosim.main import parser

    args = parser().parse_args(["calibrate", "flight.log", "--out", "out"])
    assert args.models is None and args.attitude == "auto"
    _check_choices(args)  # the default read from the catalogue when the command runs
    assert tuple(args.models) == tuple(models()) == ("current", "throttle", "motors", "metge", "dynamic")


def test_rotations_covering_the_sphere_give_hard_and_soft_iron_and_flights_cross_validate(synthetic, capsys):
    folder, truth = synthetic
    write_log(folder / "tumbling.log", seed=3, tumble=20.0)  # rolled and pitched through most orientations
    out = folder / "cross"
    assert main(["calibrate", "--train", str(folder / "tumbling.log"), "--test", str(folder / "sitl.log"),
                 "--out", str(out), "--models", "current"]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["static"]["source"] == "flight" and metrics["static"]["coverage"] >= 0.5
    assert metrics["test"] == [f"{folder / 'sitl.log'}:MAG[0]"]
    assert metrics["models"]["current"]["explained_test"] > 0.995  # another flight, measured 0.998
    static = Calibration.load(out / "calibration.json").static
    assert np.abs(static.b_s - truth["hard_iron"]).max() < 0.1e-6  # measured 0.04 uT
    assert np.abs(static.A - np.eye(3)).max() < 2e-3  # no soft iron in the data; measured 5e-4
    params = autopilot.read_parameters(out / "ardupilot.parm")
    # the log's offsets are zero: the export carries the flights' own (measured within 0.02 uT)
    exported = np.array([params[f"COMPASS_OFS_{a}"] for a in "XYZ"]) * 1e-7
    assert np.abs(exported + truth["hard_iron"]).max() < 0.1e-6


def test_a_log_without_a_magnetometer_is_refused_naming_it(synthetic, tmp_path, capsys):
    folder, _ = synthetic
    lines = (folder / "sitl.log").read_text().splitlines()
    (tmp_path / "nomag.log").write_text("\n".join(line for line in lines if not line.startswith("MAG,")) + "\n")
    assert main(["calibrate", str(tmp_path / "nomag.log"), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path / 'nomag.log'}: the log holds no magnetometer" in err


def test_a_model_that_does_not_help_out_of_sample_is_not_carried_in_the_file(tmp_path, capsys):
    # the quad's internal compass, trained on flights a and b, tested on c: metge, the richest the flights
    # identify, explains -2.1 % of c's residual (it carried it at -3.7 % before); motors explain 2.6 %
    out = tmp_path / "cross"
    assert main(["calibrate", "--train", str(path(QUAD[0])), str(path(QUAD[1])), "--test", str(path(QUAD[2])),
                 "--compass", "1", "--out", str(out), "--models", "motors", "metge"]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["models"]["metge"]["explained_test"] <= 0.0 < metrics["models"]["motors"]["explained_test"]
    assert metrics["calibration_model"] == "motors" and list(metrics["calibration_model_passed_over"]) == ["metge"]
    assert Calibration.load(out / "calibration.json").notes["model"] == "motors"
    assert "calibration.json passes over metge: it explains -2.1 %" in capsys.readouterr().out
