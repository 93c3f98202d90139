"""Scenarios from the command line: results, metrics and figures are left behind."""

import json
import re
from pathlib import Path

import numpy as np
import pytest
from quadcosim.scenarios.plant import angle_between
from quadcosim.scenarios.rig import phases
from scipy.stats import spearmanr

from quadcosim import scenarios
from quadcosim.main import main as cli

README = Path(__file__).resolve().parent.parent / "README.md"


def test_rig_reproduces_metge_figure_1(tmp_path):
    """Clamped drone: the measured field moves as one motor's command rises, and comes back to
    the motors-off reference when it falls."""
    options = {"sweep": 4.0, "rest": 0.3, "free": 1.0, "reference": 0.5, "noise": False}
    result, metrics = scenarios.run("rig", options, tmp_path)
    assert (tmp_path / "rig_field.png").stat().st_size > 10_000
    o = scenarios.get("rig").parse(options)
    t, field = result.time, result["IMU.magneto"]
    reference = field[t < 0.5].mean(axis=0)
    deviation = np.degrees(angle_between(field, reference))
    for n in range(1, 5):
        _, start, stop = next(p for p in phases(o) if p[0] == f"motor{n}")
        rising = (t >= start) & (t < 0.5 * (start + stop))
        command = result[f"Setpoint.c{n}"][rising]
        # the deviation grows with the command of the swept motor
        assert spearmanr(command, deviation[rising]).statistic > 0.99
        assert deviation[rising].max() > 10.0
    rests = (t >= o["reference"] + o["sweep"] + 0.2) & (t < o["reference"] + o["sweep"] + o["rest"])
    assert deviation[rests].max() < 0.01  # motors off again: back to the reference (measured 0.0025 deg)
    # the order of Metge et al.'s Table 1, about 10 deg (measured 9.9 deg)
    assert 8.0 < metrics["mean_angular_error_single_motor_deg"] < 12.0


def test_cli_run_writes_results_metrics_and_figures(tmp_path):
    assert cli(["run", "open-loop", "--set", "duration=0.5", "--out", str(tmp_path)]) == 0
    for name in ("results.npz", "metrics.json", "open_loop.png", "imu.png"):
        assert (tmp_path / name).is_file(), name
    assert not (tmp_path / "results.mat").exists()  # written when asked: --format npz,mat
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["options"]["duration"] == 0.5
    assert metrics["final_position_m"][2] > 0  # during the spin-up the drone sinks (NED: +z down)


def test_cli_diagram(tmp_path):
    path = tmp_path / "wiring.svg"
    assert cli(["diagram", "open-loop", "--out", str(path)]) == 0
    text = path.read_text()
    assert "MotorMagnetics" in text and "Quadrotor" in text and "omega_r[1-4]" in text


def test_readme_script_runs():
    """The five-line script of the README builds a small system and runs it."""
    code = re.search(r"```python\n(.*?)```", README.read_text(), re.S).group(1)
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)
    assert len(namespace["result"]) > 1


@pytest.mark.parametrize("name", ["open-loop", "rig"])
def test_listed(name, capsys):
    assert cli(["list"]) == 0
    assert name in capsys.readouterr().out


def test_a_set_block_parameter_is_resolved_once_and_the_parsed_options_stay_as_parsed(monkeypatch, tmp_path):
    """``--set Controller.kp_yaw=50`` from the command line to ``metrics.json``: parsed into
    read-only options, resolved once against the built system, set on the block by its type,
    and stated as set; the options parsed are never changed in place."""
    import json
    import pickle

    from quadcosim.orchestrator import parameters

    resolved = []
    original = parameters.resolve
    monkeypatch.setattr(parameters, "resolve",
                        lambda system, target, value: resolved.append(target) or original(system, target, value))
    tp = scenarios.get("tp")
    options = tp.parse(["duration=0.05", "Controller.kp_yaw=50"])
    with pytest.raises(TypeError, match="read-only"):
        options["k"] = 1.0
    assert pickle.loads(pickle.dumps(options)) == options and type(options | {"k": 1.0}) is dict
    prepared = tp.prepare(options)
    assert resolved == ["Controller.kp_yaw"]
    assert options["Controller.kp_yaw"] == 50.0  # read once, checked against the declared gains
    assert prepared.options["Controller.kp_yaw"] == prepared.used["Controller.kp_yaw"] == 50.0
    assert prepared.system.blocks["Controller"].parameter_values()["kp_yaw"] == 50.0
    assert prepared.used["kI"] == "lab" and prepared.options["k"] == 0.05
    resolved.clear()
    assert cli(["run", "tp", "--set", "duration=0.05", "Controller.kp_yaw=50", "--out", str(tmp_path / "run")]) == 0
    assert resolved == ["Controller.kp_yaw"]
    assert json.loads((tmp_path / "run" / "metrics.json").read_text())["options"]["Controller.kp_yaw"] == 50.0
