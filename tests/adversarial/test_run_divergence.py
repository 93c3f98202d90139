"""Item 15: a gain set that destabilises the loop is flagged. The run ends with the status
``diverged`` (its record, figures and metrics kept), a warning naming the settings, and exit 1;
a flight within the bounds is not flagged."""

import math

import pytest
from conftest import assert_whole

from quadcosim.main import main as cli


@pytest.mark.parametrize("gain", ["5000", "1e300"])
def test_an_unstable_gain_ends_the_run_as_diverged(tmp_path, capsys, gain):
    out = tmp_path / "run"
    assert cli(["run", "tp", "--set", "duration=4", f"Controller.kp={gain}", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert "tp diverged at t = " in err and f"Controller.kp={float(gain)}" in err
    assert "the run diverged (metrics.json: status diverged)" in err
    metrics = assert_whole(out)
    assert metrics["status"] == "diverged"
    crossing = metrics["diverged"]
    assert crossing["at_s"] < 4.0 and crossing["value"] > crossing["bound"]
    assert f"Controller.kp={float(gain)}" in crossing["settings"]
    assert metrics["files"] == ["diagram.png", "results.npz", "roll_pitch.png", "yaw.png"]


def test_the_default_gains_fly_within_the_bounds(tmp_path, capsys):
    out = tmp_path / "run"
    assert cli(["run", "tp", "--set", "duration=4", "flight=nonstationary", "--out", str(out)]) == 0
    assert "diverged" not in capsys.readouterr().err
    assert assert_whole(out)["status"] == "completed"


class _Record:
    """A record of the signals the bounds read, as functions of time."""

    def __init__(self, time, **signals):
        self.time, self.signals = time, signals
        self.names = list(signals)

    def __getitem__(self, name):
        return self.signals[name]


def test_a_crossing_must_be_held_and_is_dated_where_it_starts():
    import numpy as np
    from quadcosim.scenarios.divergence import Bounds, first_crossing
    from quadcosim.scenarios.tp import DIVERGENCE

    t = np.arange(0.0, 5.0, 0.01)
    zero = np.zeros_like(t)
    step = np.where((t > 1.0) & (t < 1.5), math.radians(70.0), 0.0)  # a 0.5 s excursion: not held
    record = _Record(t, **{"Quadrotor.theta1": step, "Controller.theta_d1": zero, "Quadrotor.theta2": zero,
                           "Controller.theta_d2": zero})
    assert first_crossing(record, DIVERGENCE) is None
    record.signals["Quadrotor.theta1"] = np.where(t > 2.0, math.radians(70.0), 0.0)
    crossing = first_crossing(record, Bounds(60.0, 10.0, 60.0, 1.0))
    assert crossing["at_s"] == pytest.approx(2.01) and crossing["what"] == "roll 70 deg from its setpoint"
