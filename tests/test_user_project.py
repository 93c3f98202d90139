"""A user's own project beside the installed package: its packages named as the repository's folders
(``flight/``, ``calibration/``, ...) neither break quadcosim nor are broken by it, through the pytest
plugin, the Python API and the command line; ``--estimator module:Class`` leaves ``sys.path`` as it was."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from quadcosim.fmus import vehicle

#: The user's own packages, named as the repository's folders; each defines a name of its own.
PACKAGES = ("flight", "calibration", "scenarios", "estimators", "fmus", "orchestrator")
#: The user's own single-file modules, named as other folders of the repository.
MODULES = ("flightlogs", "studies", "benchmarks")
QUADCOSIM = Path(sys.executable).with_name("quadcosim")

PLUGIN_TEST = '''
import flight, calibration, scenarios, estimators, fmus, orchestrator, flightlogs, studies, benchmarks
from quadcosim.scenarios.testing import assert_attitude_error


def test_my_hover(run_scenario):
    result = run_scenario("tp", duration=1, flight="hover")
    assert result.metrics["samples"] == 1001
    assert_attitude_error(result, below_deg=0.05, after_s=0.5)


def test_my_own_packages_are_mine():
    modules = (flight, calibration, scenarios, estimators, fmus, orchestrator, flightlogs, studies, benchmarks)
    assert [m.OWNER for m in modules] == ["the user's " + m.__name__ for m in modules]
'''

API_SCRIPT = '''
import json
import flight, calibration, scenarios, estimators, fmus, orchestrator
from quadcosim import FMUBlock, System, Table, run

system = System(dt=1e-3)
system.add(Table("Setpoint", ["c1", "c2", "c3", "c4"], [[0.46] * 4]))
system.add(FMUBlock("MotorMagnetics")); system.connect("Setpoint.c", "MotorMagnetics.c")
motors = system.run(0.5)
result, metrics = run("tp", {"duration": 0.5, "flight": "hover"})
print(json.dumps({"owners": [m.OWNER for m in (flight, calibration, scenarios, estimators, fmus, orchestrator)],
                  "omega_r": motors["MotorMagnetics.omega_r"][-1].tolist(), "samples": metrics["samples"],
                  "status": metrics["status"], "rms_error_deg": metrics["rms_error_deg"]}))
'''


def user_project(folder: Path) -> Path:
    """A project of the user's: its own packages and modules named as the repository's folders."""
    for name in PACKAGES:
        (folder / name).mkdir(parents=True)
        (folder / name / "__init__.py").write_text(f'OWNER = "the user\'s {name}"\nFLIGHTS = None\n')
    for name in MODULES:
        (folder / f"{name}.py").write_text(f'OWNER = "the user\'s {name}"\n')
    return folder


def test_a_users_project_runs_the_plugin_the_api_and_the_command_line(tmp_path):
    project = user_project(tmp_path / "project")
    (project / "test_mine.py").write_text(PLUGIN_TEST)
    plugin = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
                             "test_mine.py"], cwd=project, capture_output=True, text=True, timeout=600)
    print(plugin.stdout[-3000:], plugin.stderr[-2000:])
    assert "2 passed" in plugin.stdout

    (project / "my_run.py").write_text(API_SCRIPT)
    api = subprocess.run([sys.executable, "my_run.py"], cwd=project, capture_output=True, text=True, timeout=600)
    assert api.returncode == 0, api.stderr[-3000:]
    found = json.loads(api.stdout.strip().splitlines()[-1])
    assert found["owners"] == [f"the user's {name}" for name in PACKAGES]
    assert found["samples"] == 501 and found["status"] == "completed"
    assert max(found["rms_error_deg"]) < 0.1  # a hover, the estimator on noiseless samples
    # the README's command 0.46 holds each rotor at the hover speed (495.1 rad/s after 0.5 s; hover 495.2)
    assert found["omega_r"] == pytest.approx([vehicle.hover_rotor_speed()] * 4, rel=1e-3)

    command = subprocess.run([str(QUADCOSIM), "run", "tp", "--set", "duration=0.5", "--out", "results/tp"],
                             cwd=project, capture_output=True, text=True, timeout=600)
    assert command.returncode == 0, command.stderr[-3000:]
    metrics = json.loads((project / "results" / "tp" / "metrics.json").read_text())
    assert metrics["status"] == "completed" and metrics["samples"] == 501 and metrics["options"]["duration"] == 0.5


MY_FILTER = '''
import numpy as np
from quadcosim.estimators.contract import AttitudeEstimator


class Gyro(AttitudeEstimator):
    """Integrates the gyro alone."""

    def update(self, acc, gyro, mag):
        w = 0.5 * self.dt * np.asarray(gyro)
        q0, q1, q2, q3 = self.q
        dq = np.array([-q1 * w[0] - q2 * w[1] - q3 * w[2], q0 * w[0] + q2 * w[2] - q3 * w[1],
                       q0 * w[1] - q1 * w[2] + q3 * w[0], q0 * w[2] + q1 * w[1] - q2 * w[0]])
        q = self.q + dq
        self.q = q / np.linalg.norm(q)
'''


def test_an_estimator_module_leaves_the_path_and_the_standard_library_alone(tmp_path, monkeypatch):
    """A ``fractions.py`` beside the user's estimator module: the module is found in the working
    folder, the folder is off ``sys.path`` again once it is imported, and the run's report (which
    imports the standard ``fractions``) completes."""
    from quadcosim.estimators import contract

    (tmp_path / "my_filter.py").write_text(MY_FILTER)
    (tmp_path / "fractions.py").write_text('raise ImportError("the user\'s fractions.py, not the standard one")\n')
    monkeypatch.chdir(tmp_path)
    path = list(sys.path)
    assert contract.load("my_filter:Gyro").__name__ == "Gyro"
    assert sys.path == path
    done = subprocess.run([str(QUADCOSIM), "run", "tp", "--estimator", "my_filter:Gyro", "--set", "duration=0.5",
                           "--out", "results/gyro"], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    metrics = json.loads((tmp_path / "results" / "gyro" / "metrics.json").read_text())
    assert metrics["status"] == "completed" and metrics["options"]["estimator"] == "my_filter:Gyro"
    assert max(metrics["rms_error_deg"]) < 1.0  # half a second of a noiseless gyro, integrated
