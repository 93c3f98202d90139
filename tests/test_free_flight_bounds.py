"""Silent wrong results: a vehicle flown without a controller (``open-loop``), or the ground-truth hover
whose stream ``gain-study`` filters, once completed while it tumbled; ``ir-calibration``'s aircraft
turned at any rate its settings gave. Each declares the bounds of its flight
(:mod:`quadcosim.scenarios.divergence`): the tilt from level and, where recorded, the speed; the aircraft's turn
rate. A setting that breaks that flight ends ``diverged``, exit 1; its default flight completes."""

import json

from quadcosim.scenarios import get, names

from quadcosim.main import main as cli

# gain-study shortened to seconds: the batch-means check wants 20 blocks longer than 1/k_min
GAIN_STUDY = ["run", "gain-study", "--set", "duration=4", "burn_in=1", "closed_loop=false", "count=3", "k_min=10",
              "k_max=20"]


def _metrics(folder):
    return json.loads((folder / "metrics.json").read_text())


def test_open_loop_rolled_over_by_its_pulses_ends_diverged(tmp_path, capsys):
    # pulse=0.1 (ten times the default) rolls the free vehicle over: 175 deg of roll within 2 s
    assert cli(["run", "open-loop", "--set", "pulse=0.1", "--out", str(tmp_path / "o")]) == 1
    crossing = _metrics(tmp_path / "o")["diverged"]
    assert crossing["what"].startswith("roll ") and crossing["what"].endswith("deg from level")
    assert crossing["bound"] == 60.0 and 1.0 < crossing["at_s"] < 2.0
    said = capsys.readouterr().err
    assert "open-loop diverged at t = " in said
    # no controller flies it: the message says the vehicle left its bounds, not that a loop is unstable
    assert "with no controller flying it" in said and "loop is unstable" not in said


def test_open_loop_flown_past_its_pulses_ends_diverged(tmp_path):
    # left free for 4 s the default flight falls and tumbles: 16 m/s, 73 deg of roll
    assert cli(["run", "open-loop", "--set", "duration=4", "--out", str(tmp_path / "o")]) == 1
    assert _metrics(tmp_path / "o")["status"] == "diverged"


def test_open_loop_default_flight_completes_within_its_bounds(tmp_path):
    # measured: 22 deg of roll and 3.2 m/s at most over the default 2 s
    assert cli(["run", "open-loop", "--out", str(tmp_path / "o")]) == 0
    metrics = _metrics(tmp_path / "o")
    assert metrics["status"] == "completed" and "divergence_unchecked" not in metrics
    assert max(metrics["max_abs_attitude_deg"][:2]) < 30.0


def test_gain_study_hover_with_an_unstable_gain_ends_diverged(tmp_path, capsys):
    assert cli([*GAIN_STUDY, "Controller.kp=5000", "--out", str(tmp_path / "g")]) == 1
    crossing = _metrics(tmp_path / "g")["diverged"]
    assert crossing["what"].endswith("deg from level") and crossing["bound"] == 30.0
    assert "Controller.kp=5000.0" in crossing["settings"]
    assert "gain-study diverged at t = " in capsys.readouterr().err


def test_gain_study_hover_completes_within_its_bounds(tmp_path):
    assert cli([*GAIN_STUDY, "--out", str(tmp_path / "g")]) == 0
    metrics = _metrics(tmp_path / "g")
    assert metrics["status"] == "completed" and "divergence_unchecked" not in metrics


def test_ir_calibration_flown_too_slow_for_its_banks_ends_diverged(tmp_path, capsys):
    # the bank profile at 1 m/s instead of the sensor's 12: turn rates up to 5.9 rad/s
    assert cli(["run", "ir-calibration", "--set", "duration=60", "InfraredSensor.airspeed=1",
                "--out", str(tmp_path / "i")]) == 1
    crossing = _metrics(tmp_path / "i")["diverged"]
    assert crossing["what"].startswith("a turn rate of") and crossing["bound"] == 2.5
    assert "ir-calibration diverged at t = " in capsys.readouterr().err


def test_ir_calibration_flight_completes_within_its_bounds(tmp_path):
    assert cli(["run", "ir-calibration", "--set", "duration=60", "--out", str(tmp_path / "i")]) == 0
    metrics = _metrics(tmp_path / "i")
    assert metrics["status"] == "completed" and "divergence_unchecked" not in metrics


def test_the_scenario_without_bounds_is_the_one_without_a_vehicle():
    # static-cal turns the IMU by a scripted attitude, motors off: no vehicle whose flight could diverge
    unbounded = {name for name in names() if get(name).extra.get("divergence") is None}
    assert unbounded == {"static-cal"}


def test_the_command_line_guide_states_the_declared_bounds():
    from pathlib import Path

    guide = (Path(__file__).resolve().parent.parent / "docs" / "guides" / "command-line.md").read_text()
    free, hover, turn = (get(name).extra["divergence"] for name in ("open-loop", "gain-study", "ir-calibration"))
    assert (f"`open-loop` (no controller): `{free.tilt_deg:g}` deg from level or `{free.speed_m_s:g}` m/s held "
            f"`{free.held_s:g}` s; `gain-study`'s hover: `{hover.tilt_deg:g}` deg held `{hover.held_s:g}` s; "
            f"`ir-calibration`: a turn rate of `{turn.turn_rate_rad_s:g}` rad/s held `{turn.held_s:g}` s.") in guide
