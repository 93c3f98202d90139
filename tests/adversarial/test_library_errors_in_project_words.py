"""Item 24: a numerical library's error on the flight-log paths reaches the user with the file, the
cause and the fix. Where the cause is in the log (attitude stamps repeated, attitude samples
that are NaN), the reading layer removes it and says so; a library failure left is named with
the flights it failed on."""

import numpy as np
import pytest
import quadcosim.scenarios.flightlog.replay
import scipy.optimize

from quadcosim.main import main as cli
from tests.flightlog_synthetic import write_log


def _log(tmp_path, change):
    path = tmp_path / "flight.log"
    write_log(path, duration=20.0)
    lines = []
    for line in path.read_text().splitlines():
        changed = change(line)
        lines += changed if isinstance(changed, list) else [changed]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_repeated_attitude_stamps_are_dropped_not_met_by_slerp(tmp_path, capsys):
    log = _log(tmp_path, lambda line: [line, line] if line.startswith("ATT,") else line)  # every sample twice
    assert cli(["log", "replay", str(log)]) == 0  # "Times must be in strictly increasing order" before
    assert "samples dropped (repeated time stamp): attitude 190" in capsys.readouterr().err


def test_attitude_samples_that_are_nan_are_dropped_not_met_by_scipy(tmp_path, capsys):
    count = {"n": 0}

    def nan(line):
        if line.startswith("ATT,"):
            count["n"] += 1
            if count["n"] % 10 == 0:
                parts = line.split(", ")
                parts[3] = "nan"
                return ", ".join(parts)
        return line

    log = _log(tmp_path, nan)
    assert cli(["calibrate", str(log), "--out", str(tmp_path / "cal"), "--models", "current"]) == 0
    assert "samples dropped (non-finite): attitude 19" in capsys.readouterr().err  # "Found zero norm quaternions"


@pytest.mark.parametrize("error", [np.linalg.LinAlgError("SVD did not converge"),
                                   np.linalg.LinAlgError("Singular matrix"),
                                   ValueError("Method 'lm' doesn't work when the number of residuals is less than "
                                              "the number of variables."),
                                   ValueError("Initial guess is outside of provided bounds"),
                                   ValueError("cannot reshape array of size 0 into shape (0,3)")])
def test_a_fit_that_fails_in_the_library_names_the_flight_and_the_fix(tmp_path, monkeypatch, capsys, error):
    log = _log(tmp_path, lambda line: line)

    def failing(*args, **kwargs):
        raise error

    monkeypatch.setattr(scipy.optimize, "least_squares", failing)
    out = tmp_path / "cal"
    assert cli(["calibrate", str(log), "--out", str(out), "--models", "current"]) == 2
    said = capsys.readouterr().err.strip().splitlines()[-1]
    assert said.startswith(f"quadcosim calibrate: {log}:MAG[0]: the fit failed ({type(error).__name__}: {error}):")
    assert said.endswith("give longer flights with climbs, descents and turns, or --models with fewer models")
    assert not out.exists()


@pytest.mark.parametrize("error", [ValueError("arange: cannot compute length"),
                                   ValueError("Times must be in strictly increasing order."),
                                   np.linalg.LinAlgError("Singular matrix")])
def test_a_replay_that_fails_in_the_library_names_the_log_and_the_fix(tmp_path, monkeypatch, capsys, error):
    log = _log(tmp_path, lambda line: line)

    def failing(*args, **kwargs):
        raise error

    monkeypatch.setattr(quadcosim.scenarios.flightlog.replay, "_fields", failing)
    assert cli(["log", "replay", str(log)]) == 2
    said = capsys.readouterr().err.strip().splitlines()[-1]
    assert said.startswith(f"quadcosim log replay: {log}: the replay failed ({type(error).__name__}: {error}):")
    assert said.endswith("replay a longer, undamaged flight")
