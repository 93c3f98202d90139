"""The command line's tools for a student: controller gains by name, setpoint profiles from a
file, figures of finished runs, numbers at their precision, folders that never meet earlier
results, yaw curves without wrap lines."""

import json
import math

import numpy as np
import pytest
from matplotlib.image import imread
from quadcosim.flight import SETPOINT
from quadcosim.flight.profile_file import FileProfile
from quadcosim.scenarios import run as run_scenario
from quadcosim.scenarios.figures import angle_curve
from quadcosim.scenarios.shown import PARAMETER_DIGITS, shown
from quadcosim.studies.sweep.command import default_out

from quadcosim.main import main


def test_set_reaches_a_named_controller_gain_and_records_it(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", "tp", "--set", "Controller.kp_yaw=50", "--set", "duration=2", "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["options"]["Controller.kp_yaw"] == 50.0 and metrics["status"] == "completed"
    assert main(["run", "tp", "--set", "Controller.kp_yw=50", "--set", "duration=2", "--out", str(tmp_path / "x")]) == 2
    assert "Controller has no parameter 'kp_yw'. Did you mean kp_yaw" in capsys.readouterr().err
    assert main(["run", "tp", "--set", "Controller.ki_xy=5", "--set", "duration=2", "--out", str(tmp_path / "y")]) == 2
    assert "ki_xy = 5.0 must be below kp_xy * kd_xy" in capsys.readouterr().err


def test_a_yaw_gain_changes_how_fast_yaw_follows_its_setpoint(tmp_path):
    """The gain reaches the compiled law: a yaw step from a profile file settles slower with a
    tenth of the default yaw stiffness (kp_yaw = 6.4 1/s^2, kd_yaw kept)."""
    profile = tmp_path / "step.csv"
    profile.write_text("t,theta_d3_deg,hold\n0,0,1\n0.5,0,1\n0.501,20,1\n")
    settled = {}
    for label, gains in (("default", {}), ("soft", {"Controller.kp_yaw": 6.4})):
        result, _ = run_scenario("tp", {"flight": str(profile), "duration": 1.5, **gains})
        yaw = np.degrees(result["Quadrotor.theta3"])
        settled[label] = yaw[result.time.searchsorted(1.0)]
    assert settled["default"] == pytest.approx(17.6, abs=1.5)  # 0.5 s after a 20 deg step at 8 rad/s
    assert settled["soft"] < 0.5 * settled["default"]


def test_a_profile_file_is_interpolated_and_its_hold_switches_at_its_row(tmp_path):
    path = tmp_path / "p.csv"
    path.write_text("t,theta_d1_deg,z_d,hold\n0,0,0,0\n2,10,-1,1\n4,0,-1,0\n")
    rows = FileProfile(path, SETPOINT)(np.array([-1.0, 1.0, 2.0, 3.0, 10.0]))
    roll, z, hold = rows[:, SETPOINT.index("theta_d1")], rows[:, SETPOINT.index("z_d")], rows[:, SETPOINT.index("hold")]
    assert np.allclose(np.degrees(roll), [0, 5, 10, 5, 0])
    assert np.allclose(z, [0, -0.5, -1, -1, -1]) and list(hold) == [0, 0, 1, 1, 0]


@pytest.mark.parametrize("text, message", [
    ("t,rol\n0,1\n", "unknown column 'rol'. Did you mean"),
    ("theta_d1\n0\n", "needs a header with the time column 't'"),
    ("t,theta_d1\n0,1\n0,2\n", "must increase strictly"),
    ("t,theta_d1\n0,x\n", "row 2, column theta_d1: 'x' is not a finite number"),
    ("t,theta_d1\n0\n", "row 2: 1 values for 2 columns"),
])
def test_a_bad_profile_file_is_refused_naming_the_fault(tmp_path, capsys, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    assert main(["run", "tp", "--set", f"flight={path}", "duration=1", "--out", str(tmp_path / "run")]) == 2
    assert message in capsys.readouterr().err


def test_plot_and_compare_draw_signals_of_finished_runs(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for name, estimator in (("a", "linear"), ("b", "explicit")):
        assert main(["run", "tp", "--set", "duration=1", f"estimator={estimator}", "--out", name]) == 0
    capsys.readouterr()
    assert main(["plot", "a", "Quaternion_estim.theta_est", "IMU.gyro_x"]) == 0
    figure = tmp_path / "a" / "plot-Quaternion_estim.theta_est.png"
    assert (tmp_path / capsys.readouterr().out.strip()).resolve() == figure.resolve()
    assert imread(figure).shape[0] > imread(figure).shape[1] * 0.5  # two axes, one above the other
    assert main(["compare", "a", "b", "Quaternion_estim.theta_est", "--out", "both.png"]) == 0
    assert (tmp_path / "both.png").stat().st_size > 10_000
    assert main(["plot", "a", "IMU.gyr"]) == 2
    assert "no recorded signal 'IMU.gyr'. Did you mean IMU.gyro" in capsys.readouterr().err
    assert main(["compare", "a", "Quadrotor.q"]) == 2
    assert main(["plot", "nowhere", "IMU.acc"]) == 2
    assert "no results.npz or streamed record there" in capsys.readouterr().err


def test_numbers_are_printed_at_their_precision(capsys):
    assert shown(7920.000000000001, PARAMETER_DIGITS) == "7920"
    assert shown([0.04806407807056596, None, True, 3]) == "[0.048064, None, True, 3]"
    assert shown(1.19e-4, PARAMETER_DIGITS) == "0.000119"
    assert main(["list", "--parameters", "MotorMagnetics"]) == 0
    listed = capsys.readouterr().out
    assert "capacity               = 7920 " in listed and "000000000" not in listed


def test_a_default_sweep_folder_never_meets_an_earlier_sweep(tmp_path, capsys):
    base = tmp_path / "lab-matrix"
    assert default_out(base, False, "x") == base
    base.mkdir()
    (base / "sweep.json").write_text("{}")
    assert default_out(base, False, "x") == tmp_path / "lab-matrix-2"
    assert "holds an earlier sweep; writing to" in capsys.readouterr().err
    assert default_out(base, True, "x") == base  # --resume continues it


def test_a_wrapping_yaw_is_drawn_with_a_gap_not_a_vertical_line():
    t = np.linspace(0.0, 20.0, 20001)
    yaw = (np.linspace(0.0, 300.0, t.size) + 180.0) % 360.0 - 180.0  # wraps once, at 180 deg
    times, values = angle_curve(t, yaw)
    finite = ~np.isnan(values)
    assert np.isnan(values).sum() == 1 and len(times) == len(values) <= 4001
    jumps = np.abs(np.diff(values))
    assert np.nanmax(jumps) < 1.0  # no segment crosses the axis
    assert values[finite].max() == pytest.approx(180.0, abs=0.2)
    assert values[finite].min() == pytest.approx(-180, abs=0.2)
    assert math.isclose(values[-1], -60.0, abs_tol=1e-6)


def test_a_tilt_run_draws_the_accelerometer_s_tilt_and_the_speed(tmp_path):
    from quadcosim.scenarios.tilt_figure import accelerometer_tilt_deg

    _, metrics = run_scenario("tp", {"flight": "tilt", "duration": 3.0}, tmp_path)
    assert "tilt.png" in metrics["figures"] and imread(tmp_path / "tilt.png").shape[1] > 900
    level, pitched = [0.0, 0.0, -9.81], [9.81 * math.sin(0.1), 0.0, -9.81 * math.cos(0.1)]
    roll, pitch = accelerometer_tilt_deg(np.array([level, pitched]))
    assert np.allclose(roll, 0.0) and np.allclose(pitch, [0.0, math.degrees(0.1)])
