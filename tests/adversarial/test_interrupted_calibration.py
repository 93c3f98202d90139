"""Item 5: an interrupted or refused calibration leaves its files with their ``metrics.json``, or
nothing: a signal while the files are written lets them finish (metrics.json last), a signal
while the flights are read leaves no folder, and neither does a refusal."""

import dataclasses
import json
import signal

import pytest
import quadcosim.scenarios.flightlog.reading
from conftest import send_self
from quadcosim.calibration.flight import autopilot

from quadcosim.main import main as cli
from tests.flightlog_synthetic import write_log

MODELS = ["--models", "current"]


@pytest.fixture
def flight(tmp_path):
    path = tmp_path / "flight.log"
    write_log(path, duration=20.0)
    return path


@pytest.mark.parametrize("number", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_while_the_files_are_written_keeps_them_all_with_metrics_json(flight, tmp_path, monkeypatch,
                                                                               number, capsys):
    from quadcosim.flightlogs.autopilots import ardupilot, of

    member = of("ArduPilot")

    def signalled(params, path):
        send_self(number)  # as the first parameter file is written
        member.write(params, path)

    monkeypatch.setattr(ardupilot, "AUTOPILOT", dataclasses.replace(member, write=signalled))
    out = tmp_path / "cal"
    assert cli(["calibrate", str(flight), "--out", str(out), *MODELS]) == 128 + number
    capsys.readouterr()
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "completed"
    assert sorted(p.name for p in out.iterdir()) == sorted(metrics["files"])  # every file listed, whole
    assert autopilot.read_parameters(out / "ardupilot.parm")["COMPASS_MOTCT"] == 2


def test_a_signal_while_the_flights_are_read_leaves_no_folder(flight, tmp_path, monkeypatch, capsys):
    load = quadcosim.scenarios.flightlog.reading.load

    def signalled(path, verb):
        log = load(path, verb)
        send_self(signal.SIGINT)
        return log

    monkeypatch.setattr(quadcosim.scenarios.flightlog.reading, "load", signalled)
    # Python's own Ctrl-C handler, whatever an earlier test of the session left installed: once in a
    # loaded full run this signal was lost (exit 0); a handler leaking between tests is suspected, unproven
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    out = tmp_path / "cal"
    try:
        code = cli(["calibrate", str(flight), "--out", str(out), *MODELS])
    finally:
        signal.signal(signal.SIGINT, previous)
    assert code == 130
    capsys.readouterr()
    assert not out.exists()


def test_a_refused_calibration_leaves_no_folder(tmp_path, capsys):
    log = tmp_path / "notes.log"
    log.write_text("take-off at noon\n")
    out = tmp_path / "cal"
    assert cli(["calibrate", str(log), "--out", str(out)]) == 2
    assert "unknown log format" in capsys.readouterr().err
    assert not out.exists()
