"""Items 6, 7, 8, 9 and 17: logs whose sensors do not line up are named, at the reading layer, never
met with a traceback: time spans that do not overlap, two logs joined, a singular soft-iron
matrix in the parameters, missing message types, test flights without the training's sensors."""

import json

import pytest

from quadcosim.main import main as cli
from tests.flightlog_synthetic import write_log

MODELS = ["--models", "current", "throttle"]


def _log(tmp_path, name, change=None, duration=20.0):
    """The synthetic text log, each line passed through ``change`` (None drops it)."""
    path = tmp_path / name
    write_log(path, duration=duration)
    if change is not None:
        lines = [change(line) for line in path.read_text().splitlines()]
        path.write_text("\n".join(line for line in lines if line is not None) + "\n")
    return path


def _shift(kind: str, seconds: float):
    def change(line):
        parts = line.split(", ")
        if parts[0] == kind:
            parts[1] = str(int(parts[1]) + int(seconds * 1e6))
        return ", ".join(parts)
    return change


def test_a_compass_outside_the_other_sensors_span_is_named(tmp_path, capsys):
    log = _log(tmp_path, "shifted.log", _shift("MAG", 1000.0))
    assert cli(["calibrate", str(log), "--out", str(tmp_path / "cal"), *MODELS]) == 2
    err = capsys.readouterr().err
    assert "its sensors share no span of time (MAG[0] 1001.0 to 1019.9 s, attitude 1.0 to 19.9 s" in err
    assert not (tmp_path / "cal").exists()
    assert cli(["log", "replay", str(log)]) == 2
    assert "share no span of time" in capsys.readouterr().err


def test_two_logs_joined_are_refused_where_the_clock_goes_back(tmp_path, capsys):
    one = _log(tmp_path, "one.log")
    joined = tmp_path / "joined.log"
    joined.write_text(one.read_text() * 2)
    for command in (["log", "info", str(joined)], ["log", "info", str(joined), "--json"],
                    ["log", "replay", str(joined)], ["calibrate", str(joined), "--out", str(tmp_path / "c"), *MODELS]):
        assert cli(command) == 2, command
        captured = capsys.readouterr()
        assert "the clock of MAG[0] goes back (once; first from 19.900 s to 1.000 s): two logs joined" in captured.err
        assert captured.out == ""  # no duration of -19 s printed, no rate of 0 Hz


def test_a_few_damaged_time_stamps_are_dropped_and_counted(tmp_path, capsys):
    count = {"n": 0}

    def damage(line):
        if line.startswith("ATT,"):
            count["n"] += 1
            if count["n"] in (50, 120):  # two stamps read 0.000005 s: out of order
                parts = line.split(", ")
                parts[1] = "5"
                return ", ".join(parts)
        return line

    log = _log(tmp_path, "glitch.log", damage)
    assert cli(["log", "info", str(log), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["warnings"] == ["samples dropped (out of order): attitude 2"]
    assert info["common_span_s"] == pytest.approx([1.0, 19.9], abs=1e-3)  # the span of the attitude, 10 Hz


def test_a_singular_soft_iron_matrix_is_refused_naming_its_parameters(tmp_path, capsys):
    def zero_diagonal(line):
        if line.startswith("PARM, 1000, COMPASS_OFS_X"):
            return [line, "PARM, 1000, COMPASS_DIA_X, 0, 0", "PARM, 1000, COMPASS_DIA_Y, 0, 0",
                    "PARM, 1000, COMPASS_DIA_Z, 1, 0"]  # with the Default column of a 4.x log
        return line

    path = _log(tmp_path, "dia.log")
    lines = []
    for line in path.read_text().splitlines():
        changed = zero_diagonal(line)
        lines += changed if isinstance(changed, list) else [changed]
    path.write_text("\n".join(lines) + "\n")
    assert cli(["log", "info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "warning: compass MAG[0]: its soft-iron matrix is singular (COMPASS_DIA_X = 0, COMPASS_DIA_Y = 0" in out
    assert cli(["log", "plot", str(path), "--out", str(tmp_path / "overview.png")]) == 0
    capsys.readouterr()
    assert cli(["calibrate", str(path), "--out", str(tmp_path / "cal"), *MODELS]) == 2
    assert "compass 0 (MAG[0]): its soft-iron matrix is singular (COMPASS_DIA_X = 0" in capsys.readouterr().err


@pytest.mark.parametrize(("dropped", "named"), [("ATT", "the attitude (ATT)"), ("IMU", "an IMU (IMU)")])
def test_a_replay_names_the_message_types_the_log_lacks(tmp_path, capsys, dropped, named):
    log = _log(tmp_path, "partial.log", lambda line: None if line.startswith(dropped + ",") else line)
    assert cli(["log", "replay", str(log)]) == 2
    assert f"a replay needs what the log does not hold: {named}" in capsys.readouterr().err


def test_test_flights_without_the_training_current_sensor(tmp_path, capsys):
    train = _log(tmp_path, "train.log")

    def no_current(line):  # the current sensor reads 0: not wired
        parts = line.split(", ")
        if parts[0] == "BAT":
            parts[-1] = "0.000"
        return ", ".join(parts)

    test = _log(tmp_path, "test.log", no_current)
    out = tmp_path / "cal"
    assert cli(["calibrate", "--train", str(train), "--test", str(test), "--out", str(out), *MODELS]) == 0
    shown = capsys.readouterr().out
    assert "current   refused: fitted on the training flights, but the test flights have no current sensor" in shown
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "completed"
    # the export carries the current model the training flights identify; on test flights that
    # read no current it compensates nothing, and is scored so
    assert metrics["export"]["model"] == "current" and metrics["export"]["explained_test"] == 0.0


def test_a_short_shared_span_and_a_gap_are_reported(tmp_path, capsys):
    log = _log(tmp_path, "late.log", _shift("ATT", 10.0))
    assert cli(["log", "info", str(log), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["common_span_s"] == pytest.approx([11.0, 19.9], abs=1e-3)
    assert info["warnings"] == ["its sensors share 8.9 s of the 28.9 s logged (11.0 to 19.9 s; attitude starts at "
                                "11.0 s, motors ends at 19.9 s): a replay or a calibration uses that span alone"]

    def stall(line):  # nothing logged from 10 to 25 s
        parts = line.split(", ")
        return None if parts[0] in ("IMU", "ATT", "RCOU", "BAT", "MAG") and 10e6 < int(parts[1]) < 25e6 else line

    log = _log(tmp_path, "stalled.log", stall, duration=40.0)
    assert cli(["log", "info", str(log), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    # a stall cuts the log to its longest stretch (flightlogs/trim.py): 25 to 40 s, the 9 s before it dropped
    assert info["warnings"] == ["logging stalls (15.0 s from 10.0 s): the longest stretch between stalls is kept, "
                                "25.0 to 40.0 s (15.0 s of the 39.0 s logged)"]
    assert info["duration_s"] == pytest.approx(15.0, abs=0.1)

    def gap(line):  # a gap in the compass alone (10 to 25 s), the IMU logging on: reported, not cut
        parts = line.split(", ")
        return None if parts[0] == "MAG" and 10e6 < int(parts[1]) < 25e6 else line

    log = _log(tmp_path, "gap.log", gap, duration=40.0)
    assert cli(["log", "info", str(log), "--json"]) == 0
    warnings = json.loads(capsys.readouterr().out)["warnings"]
    assert warnings == ["samples stop for a while (two flights in one file, or logging that stalled): MAG[0] 15.1 s "
                        "from 9.9 s"]
