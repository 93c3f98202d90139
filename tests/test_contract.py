"""A user's estimator in the loop (the README's Madgwick filter, from the command line and from
Python) and block parameters set by name from the command line, checked against the FMU."""

import json
import re
import shlex
from pathlib import Path

import numpy as np
import pytest
from helpers import documentation
from quadcosim.estimators.contract import REQUIRED, AttitudeEstimator
from quadcosim.orchestrator import Block, Result, System

from quadcosim import scenarios
from quadcosim.main import main as cli

README = Path(__file__).resolve().parent.parent / "README.md"


def readme_estimator() -> tuple[str, str]:
    """The README's Madgwick file and the command that flies it."""
    text = documentation()
    section = text[text.index("### Your own estimator in the loop"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    command = re.search(r"```bash\n(quadcosim run tp --estimator .*?)\n```", section, re.S).group(1)
    return code, command


def run_cli(arguments) -> int:
    try:
        return cli(arguments)
    except SystemExit as exit:
        return exit.code


def test_the_readme_madgwick_flies_estimate_fed_from_the_command_line(tmp_path, monkeypatch, capsys):
    """Acceptance: the README's own Madgwick block, run by the README's command as written,
    flies the closed loop on its estimate; its errors are those of the ``ahrs`` package's
    Madgwick filter at the same gain (an independent implementation of the same equations)."""
    code, command = readme_estimator()
    assert 25 <= len(code.strip().splitlines()) <= 45
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my_madgwick.py").write_text(code)
    assert run_cli(shlex.split(command)[1:]) == 0, capsys.readouterr().err[-3000:]
    out = tmp_path / re.search(r"--out (\S+)", command).group(1)
    mine = json.loads((out / "metrics.json").read_text())
    assert mine["status"] == "completed"
    assert mine["options"]["estimator"] == "my_madgwick.py:Madgwick"
    assert mine["options"]["feedback"] == "estimate"
    assert max(mine["rms_error_deg"][:2]) < 1.0 and mine["rms_error_deg"][2] < 2.0
    settings = re.search(r"--set (.*?) --out", command).group(1).split()
    assert run_cli(["run", "tp", "--set", *settings, "estimator=madgwick", "--out", str(tmp_path / "ahrs")]) == 0
    published = json.loads((tmp_path / "ahrs" / "metrics.json").read_text())
    print("README Madgwick RMS (deg):", mine["rms_error_deg"], " ahrs Madgwick:", published["rms_error_deg"])
    np.testing.assert_allclose(mine["rms_error_deg"], published["rms_error_deg"], rtol=5e-4)


def test_a_users_block_from_python_is_named_in_metrics_and_tuned_by_set(tmp_path):
    code, _ = readme_estimator()
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)
    madgwick = namespace["Madgwick"]
    result, metrics = scenarios.run("tp", {"duration": 1.0, "feedback": "estimate", "Quaternion_estim.beta": 0.2},
                                    tmp_path / "run", estimator=madgwick)
    block_label = metrics["options"]["estimator"]
    assert block_label.endswith(":Madgwick") and metrics["options"]["Quaternion_estim.beta"] == 0.2
    assert "Quaternion_estim.q_est0" in result.names and np.isfinite(result["Quaternion_estim.q_est"]).all()
    with pytest.raises(ValueError, match="no estimator to replace; the scenarios with one: tp"):
        scenarios.run("rig", {}, estimator=madgwick)


def test_system_replace_keeps_the_wiring_and_refuses_a_block_missing_an_output():
    tp = scenarios.get("tp")
    system = tp.build(tp.parse({"feedback": "estimate", "duration": 0.5}))

    class Frozen(AttitudeEstimator):
        def update(self, acc, gyro, mag):
            pass

    system.replace("Quaternion_estim", Frozen(name="anything"))
    result = system.run(0.5)
    assert np.all(result["Quaternion_estim.q_est0"] == 1.0)  # identity, held: the block ran
    assert np.array_equal(result["Quaternion_estim.omega_est_x"], result["IMU.gyro_x"])

    class Partial(Block):
        inputs = ("gyro_x",)
        outputs = ("q_est0",)

    with pytest.raises(KeyError, match="lacks the outputs omega_est_x, omega_est_y, omega_est_z, q_est1"):
        system.replace("Quaternion_estim", Partial("x"))


def test_a_block_breaking_the_contract_is_refused_before_the_run(tmp_path, monkeypatch, capsys):
    (tmp_path / "broken.py").write_text("from quadcosim.orchestrator import Block\n\nclass NoOutputs(Block):\n"
                                        "    inputs = ('gyro_x',)\n    outputs = ('q_est0',)\n")
    monkeypatch.chdir(tmp_path)
    assert run_cli(["run", "tp", "--estimator", "broken:NoOutputs", "--out", "x"]) == 2
    message = capsys.readouterr().err
    assert "lacks the outputs q_est1, q_est2" in message and "estimators/contract.py" in message
    assert run_cli(["run", "tp", "--estimator", "broken:Missing", "--out", "y"]) == 2
    assert "broken has no 'Missing'; its blocks: NoOutputs" in capsys.readouterr().err
    assert run_cli(["run", "rig", "--estimator", "broken:NoOutputs"]) == 2
    assert "scenario rig has no estimator" in capsys.readouterr().err
    assert len(REQUIRED) == 13


def test_a_gyro_noise_density_set_from_the_command_line_is_the_noise_in_the_result(tmp_path):
    """Acceptance: over 1e5 gyro samples (3 axes x 33 334 at 100 Hz, scripted rotation, no
    bias) the measured noise is the density set on the command line times sqrt(rate)."""
    density = 2e-3  # rad/s/sqrt(Hz), about eleven times the default
    out = tmp_path / "run"
    assert cli(["run", "static-cal", "--set", "duration=333.33", f"IMU.gyro_noise_density={density}",
                "--record", "IMU.gyro", "Hand.omega", "IMU.magneto", "--format", "npz", "--out", str(out)]) == 0
    data = Result.from_npz(out / "results.npz")  # the archive holds IMU.gyro as one N x 3 array
    noise = np.concatenate([data[f"IMU.gyro_{a}"] - data[f"Hand.omega_{a}"] for a in "xyz"])
    expected = density * np.sqrt(100.0)  # the IMU samples at the macro rate of static-cal, 100 Hz
    print(f"{noise.size} samples: noise {noise.std():.6g} rad/s, expected {expected:.6g} "
          f"({noise.std() / expected - 1:+.2%})")
    assert noise.size >= 100_000
    assert noise.std() == pytest.approx(expected, rel=0.03)
    assert json.loads((out / "metrics.json").read_text())["options"]["IMU.gyro_noise_density"] == density


def test_several_settings_after_one_set_flag_and_vector_parameters(tmp_path):
    out = tmp_path / "run"
    assert cli(["run", "tp", "--set", "estimator=explicit", "k1=0.3", "duration=0.5", "bias=true",
                "IMU.gyro_bias=0.01,0,-0.02", "--out", str(out), "--format", "npz"]) == 0
    options = json.loads((out / "metrics.json").read_text())["options"]
    assert options["estimator"] == "explicit" and options["k1"] == 0.3
    assert options["IMU.gyro_bias"] == [0.01, 0.0, -0.02]
    data = Result.from_npz(out / "results.npz")
    assert data["IMU.gyro_bias_x"][-1] == 0.01 and data["IMU.gyro_bias_z"][-1] == -0.02


@pytest.mark.parametrize("setting, message", [
    ("IMU.gyro_noise_densty=1e-3", "IMU has no parameter 'gyro_noise_densty'. Did you mean gyro_noise_density"),
    ("IMU.gyro_noise_density=1e-3 deg/s/Hz0.5", "the unit is rad/s/Hz0.5, not 'deg/s/Hz0.5'"),
    ("IMU.gyro_noise_density=fast", "is not a number (in rad/s/Hz0.5)"),
    ("IMU.gyro_bias=0.01,0", "has 3 components: give 3 values, comma-separated, not 2"),
    ("IMU.seed=3", "IMU.seed is set by scenario tp's option seed: use --set seed=..."),
    ("IMU.acc_noise_density=0.01", "has no effect while IMU.noise_enabled is false: turn it on (--set noise=true)"),
    ("Imu.seed=1", "unknown block 'Imu'"),
    ("Quaternion_estim.beta=1", "Quaternion_estim has no parameter 'beta'"),
])
def test_bad_parameters_are_refused_with_the_fix(setting, message, tmp_path, capsys):
    assert run_cli(["run", "tp", "--set", setting, "--out", str(tmp_path / "run")]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "run" / "metrics.json").exists()


def test_set_parameter_in_python_with_units_and_the_list_shows_them(capsys):
    system = System()
    from quadcosim.orchestrator import FMUBlock

    imu = system.add(FMUBlock("IMU"))
    assert system.set_parameter("IMU.gyro_noise_density", "0.003 rad/s/Hz0.5") == 0.003
    assert system.set_parameter("IMU.bias_enabled", "on") is True
    assert system.set_parameter("IMU.acc_bias", (0.1, 0.2, 0.3)) == [0.1, 0.2, 0.3]
    assert imu.parameters["b_a_y"] == 0.2 and imu.parameters["bias_enabled"] is True
    assert cli(["list", "--parameters", "IMU"]) == 0
    listing = capsys.readouterr().out
    assert re.search(r"gyro_noise_density\s+= 0.000174\d*\s+\[rad/s/Hz0.5\]", listing)
    assert "gyro_bias stands for the vector b_g" in listing


def test_a_nan_caused_by_a_fault_names_the_fault_not_the_block(tmp_path, capsys):
    """A gyro offset of 1e300 rad/s into the estimator makes its quaternion NaN: the message
    names that fault as the cause (active, on the failing block's input) before the others."""
    code = cli(["run", "tp", "--set", "duration=1", "feedback=estimate", "estimator=explicit",
                "--fault", "Controller.p_x:offset:0:1:1", "--fault", "Quaternion_estim.gyro_x:offset:0.5:1:1e300",
                "--out", str(tmp_path / "run"), "--format", "npz"])
    message = capsys.readouterr().err
    assert code == 1
    assert ("Quaternion_estim.q_est0 became nan at t = 0.5 s (the first non-finite signal in the block order). "
            "Likely cause: the offset fault on Quaternion_estim.gyro_x (value 1e+300, from 0.5 s to 1 s), active "
            "at that time, on an input of Quaternion_estim.") in message
    assert "Other faults that had started and feed Quaternion_estim: the offset fault on Controller.p_x" in message
    assert "Check the block" not in message


@pytest.mark.parametrize("scenario, setting, option", [
    ("open-loop", "IMU.seed=2", "seed"), ("rig", "IMU.noise_enabled=false", "noise"),
    ("static-cal", "IMU.sample_rate=50", "mag_rate")])
def test_a_parameter_a_scenario_sets_from_an_option_names_the_option(scenario, setting, option, capsys, tmp_path):
    assert run_cli(["run", scenario, "--set", setting, "--out", str(tmp_path / "run")]) == 2
    assert f"is set by scenario {scenario}'s option {option}: use --set {option}=..." in capsys.readouterr().err
