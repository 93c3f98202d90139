"""The plant's own FMUs in FMI 3.0 (``quadcosim.fmus.fmu_path(name, fmi_version=3)``) run in the master as
their FMI 2.0 builds do: given by path to ``quadcosim run open-loop --fmu``, each gives the FMI 2.0
run's record bit for bit (the IMU's FMI 3.0 arrays as ``acc_1`` ... where FMI 2.0 has ``acc_x``
...), in process, since they are this project's builds; and in a worker process of its own
(:mod:`quadcosim.orchestrator.isolated`) an FMI 3.0 motor gives its FMI 2.0 build's outputs bit for bit."""

import numpy as np
import pytest
from quadcosim.orchestrator import FMUBlock, Result, System

from quadcosim import fmus
from quadcosim.main import main

DURATION = "0.3"


@pytest.fixture(scope="module")
def fmi2_run(tmp_path_factory) -> Result:
    """``quadcosim run open-loop`` with the FMI 2.0 plant."""
    out = tmp_path_factory.mktemp("fmi2") / "run"
    assert main(["run", "open-loop", "--set", f"duration={DURATION}", "--out", str(out)]) == 0
    return Result.load(out / "results.npz")


@pytest.mark.parametrize("model", ["MotorMagnetics", "Quadrotor", "IMU"])
def test_an_fmi3_plant_fmu_by_path_gives_the_fmi2_record(model, fmi2_run, tmp_path):
    from quadcosim.orchestrator.isolated import runs_isolated

    path = fmus.fmu_path(model, fmi_version=3)
    assert not runs_isolated(path)  # the project's own build: in process
    out = tmp_path / "run"
    assert main(["run", "open-loop", "--set", f"duration={DURATION}", "--fmu", f"{model}={path}",
                 "--out", str(out)]) == 0
    result = Result.load(out / "results.npz")
    assert len(result) == len(fmi2_run) == round(float(DURATION) / 1e-3) + 1
    renamed = {f"IMU.{v}_{c}": f"IMU.{v}_{k}" for v in ("acc", "gyro", "magneto")
               for k, c in zip("123", "xyz", strict=True)}
    for name in fmi2_run.names:
        ours = renamed.get(name, name) if model == "IMU" else name
        assert np.array_equal(result[ours], fmi2_run[name]), name
    moving = fmi2_run["MotorMagnetics.omega_r1"]
    assert np.ptp(moving) > 1.0  # the record moves: the equality is of a run, not of zeros


def test_an_fmi3_motor_isolated_equals_its_fmi2_build():
    """The FMI 3.0 MotorMagnetics forced into a worker process, against the FMI 2.0 one in
    process, with the same commands: every output equal, bit for bit."""
    def run(path, isolated):
        system = System(dt=1e-3)
        block = system.add(FMUBlock("M", model=path, isolated=isolated))
        for k, name in enumerate(block.inputs):
            system.set_input(f"M.{name}", 0.2 + 0.1 * k)
        return system.run(0.2)

    isolated = run(fmus.fmu_path("MotorMagnetics", fmi_version=3), True)
    in_process = run(fmus.fmu_path("MotorMagnetics"), False)
    assert isolated.names == in_process.names
    assert np.array_equal(isolated.data, in_process.data)
    assert np.ptp(isolated["M.omega_r4"]) > 1.0
