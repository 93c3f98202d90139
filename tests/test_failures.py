"""Each failure the master can meet is a clear error naming the problem and the fix, and what
was recorded before it is returned (and, with --out, saved)."""

import json

import numpy as np
import pytest
from quadcosim.fmus import FMUNotFoundError
from quadcosim.orchestrator import Block, FMUBlock, SimulationError, System, Table

from quadcosim import scenarios
from quadcosim.main import main as cli


class Source(Block):
    outputs = ("y",)
    feedthrough = False

    def __init__(self, name, bad_at, value):
        super().__init__(name)
        self.bad_at, self.value = bad_at, value

    def step(self, t, u, y):
        y[0] = self.value if t >= self.bad_at - 1e-12 else 400.0


def test_unknown_block_and_signal_name_the_nearest():
    system = System()
    system.add(FMUBlock("IMU"))
    with pytest.raises(KeyError, match="unknown block 'IMV'.*Did you mean IMU"):
        system.connect("IMV.acc_x", "IMU.q0")
    with pytest.raises(KeyError, match="IMU has no output 'acc_w'. Did you mean .*acc_x"):
        system.connect("IMU.acc_w", "IMU.q0")


def test_unconnected_input_says_how_to_connect():
    system = System()
    system.add(FMUBlock("MotorMagnetics"))
    with pytest.raises(ValueError, match=r"unconnected inputs: MotorMagnetics.c1.*system.connect"):
        system.run(0.1)


def test_missing_fmu_says_how_to_build(tmp_path, monkeypatch):
    monkeypatch.setenv("QUADCOSIM_FMU_DIR", str(tmp_path))
    with pytest.raises(FMUNotFoundError, match="quadcosim build"):
        FMUBlock("Quadrotor")


def test_fmu_error_status_names_block_time_and_log_and_keeps_the_record():
    system = System()
    system.add(Source("Speeds", 0.25, float("inf")))
    system.add(FMUBlock("Quadrotor"))
    for n in range(1, 5):
        system.connect("Speeds.y", f"Quadrotor.omega_r{n}")
    system.set_input("Quadrotor.domega_r", 0.0)
    system.set_input("Quadrotor.wind", 0.0)
    with pytest.raises(SimulationError) as error:
        system.run(1.0)
    message = str(error.value)
    assert "Quadrotor: fmi2SetReal returned Error at t = 0.25 s" in message
    assert "omega_r1 = inf at t = 0.25 is not a finite number" in message  # the FMU's log
    assert "Speeds.y became inf at t = 0.25 s" in message  # the first non-finite signal
    result = error.value.result
    assert len(result) == 250 and result.time[-1] == pytest.approx(0.249)
    assert np.isfinite(result.data).all()


def test_nan_in_a_python_signal_names_the_first_signal_and_time():
    system = System()
    system.add(Source("Sensor", 0.1, float("nan")))
    with pytest.raises(SimulationError, match=r"Sensor.y became nan at t = 0.1 s") as error:
        system.run(0.5)
    assert len(error.value.result) == 101  # the row of the NaN itself is kept for inspection


@pytest.mark.parametrize("make, words", [
    (lambda: System(dt=0.0), "dt = 0.0 s must be a positive"),
    (lambda: System(dt=-1e-3), "must be a positive"),
    (lambda: System().run(-1.0), "duration = -1.0 s must be a positive"),
    (lambda: FMUBlock("Quadrotor", parameters={"mass": 1.0}), "no parameter 'mass'"),
    (lambda: FMUBlock("IMU", period=0), "period must be a positive integer"),
    (lambda: Table("T", ["a"], [[np.nan]]), "NaN or Inf"),
    (lambda: scenarios.run("rig", {"sweep": -1.0}), "sweep=-1.0 must be at least"),
    (lambda: scenarios.run("rig", {"sweeep": 1.0}), "unknown option 'sweeep'.*Did you mean sweep"),
    (lambda: scenarios.run("riig"), "unknown scenario 'riig'.*Did you mean rig"),
])
def test_invalid_parameters_are_refused_with_the_fix(make, words):
    with pytest.raises((ValueError, KeyError), match=words):
        make()


def test_cli_failure_saves_what_was_recorded(tmp_path, capsys):
    out = tmp_path / "run"
    code = cli(["run", "open-loop", "--set", "duration=1", "--out", str(out),
                "--fault", "MotorMagnetics.c1:offset:0.5:0.6:1e308", "--fault", "MotorMagnetics.c1:scale:0.5:0.6:10"])
    assert code == 1
    err = capsys.readouterr().err
    assert "MotorMagnetics: fmi2SetReal returned Error at t = 0.5 s" in err
    assert "the scale fault on MotorMagnetics.c1 (value 10.0, from 0.5 s to 0.6 s) made it inf at t = 0.5 s" in err
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["recorded_until_s"] == pytest.approx(0.499)
    with np.load(out / "results.npz") as saved:
        assert len(saved["time"]) == 500


def test_cli_unknown_option_is_refused(capsys):
    assert cli(["run", "open-loop", "--set", "durtion=3"]) == 2
    assert "Did you mean duration" in capsys.readouterr().err
