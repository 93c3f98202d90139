"""One meaning of ``--json`` (a flag: JSON on standard output) and ``--out`` (where files go, with a
default under results/) across sub-commands; the old ``--json FILE`` still works, saying it is
deprecated."""

import json

import pytest
from quadcosim.scenarios.flightlog.example import write_flight

from quadcosim.main import main


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    return write_flight(tmp_path_factory.mktemp("logs") / "example-a.log", duration=30.0)


def test_json_is_a_flag_that_prints_json_and_out_writes_the_file(flight, tmp_path, capsys):
    assert main(["log", "replay", str(flight), "--compass", "1", "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["compass"] == "MAG[1]" and set(printed["estimators"]) >= {"explicit", "vqf"}
    assert main(["log", "replay", str(flight), "--compass", "1", "--out", str(tmp_path / "r.json")]) == 0
    assert "heading RMS" in capsys.readouterr().out  # the table, the file beside it
    assert json.loads((tmp_path / "r.json").read_text()) == printed
    assert main(["log", "info", str(flight), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["compasses"]


def test_the_old_json_file_spelling_still_writes_the_file_and_says_it_is_deprecated(flight, tmp_path, capsys):
    assert main(["log", "replay", str(flight), "--compass", "1", "--json", str(tmp_path / "old.json")]) == 0
    told = capsys.readouterr()
    assert "--json FILE is deprecated" in told.err and f"--out {tmp_path / 'old.json'}" in told.err
    assert "heading RMS" in told.out and json.loads((tmp_path / "old.json").read_text())["compass"] == "MAG[1]"


def test_calibrate_writes_to_a_default_folder_and_never_replaces_it_unasked(flight, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["calibrate", str(flight), "--compass", "1"]) == 0
    assert (tmp_path / "results" / "calibrate-example-a" / "calibration.json").is_file()
    assert main(["calibrate", str(flight), "--compass", "1"]) == 0
    assert "writing to results/calibrate-example-a-2/" in capsys.readouterr().err
    assert (tmp_path / "results" / "calibrate-example-a-2" / "calibration.json").is_file()
