"""A user's own FMU in the loop: an FMU made by another exporter (pythonfmu) runs in a system by
its path, and replaces a plant block from the command line, its interface checked by variable
name and unit."""

import json
import zipfile

import numpy as np
import pytest
from quadcosim.orchestrator import Constant, FMUBlock, System

from quadcosim.main import main

MOTOR = "FirstOrderMotor"
TAU, OMEGA_MAX = 0.03, 1000.0  # s, rad/s: the motor model's defaults (tests/user_fmus/first_order_motor.py)


@pytest.fixture(scope="module")
def motor_fmu(tmp_path_factory):
    """The user's motor, exported by pythonfmu (not by this project's FMU builder)."""
    from pathlib import Path

    from pythonfmu.builder import FmuBuilder

    folder = tmp_path_factory.mktemp("user")
    FmuBuilder.build_FMU(Path(__file__).parent / "user_fmus" / "first_order_motor.py", dest=folder)
    path = folder / f"{MOTOR}.fmu"
    with zipfile.ZipFile(path) as archive:
        assert 'generationTool="PythonFMU' in archive.read("modelDescription.xml").decode()
    return path


def test_an_fmu_of_another_exporter_runs_in_a_system_by_its_path(motor_fmu, tmp_path, monkeypatch):
    """Commands 0.5 into the motor: each rotor's speed is the explicit-Euler first-order response,
    omega_k = c omega_max (1 - (1 - dt/tau)^k), to the last bits (the model steps exactly so)."""
    monkeypatch.chdir(motor_fmu.parent)
    system = System(dt=1e-3)
    system.add(Constant("Command", {f"c{n}": 0.25 * n for n in (1, 2, 3, 4)}))
    block = system.add(FMUBlock("Motor", model=motor_fmu.name, parameters={"tau": TAU}))  # relative to here
    for n in (1, 2, 3, 4):
        system.connect(f"Command.c{n}", f"Motor.c{n}")
    result = system.run(0.2)
    k = np.arange(len(result))
    for n in (1, 2, 3, 4):
        expected = min(0.25 * n, 1.0) * OMEGA_MAX * (1.0 - (1.0 - 1e-3 / TAU) ** k)
        assert np.allclose(result[f"Motor.omega_r{n}"], expected, rtol=1e-12, atol=1e-9)
    assert block.path == motor_fmu and block.inputs == ("c1", "c2", "c3", "c4")
    with pytest.raises(FileNotFoundError, match=r"FMU file missing\.fmu not found"):
        FMUBlock("Motor", model="missing.fmu")
    (tmp_path / "text.fmu").write_text("not a zip")
    with pytest.raises(ValueError, match="not a readable FMU"):
        FMUBlock("Motor", model=tmp_path / "text.fmu")


def test_fmu_on_the_command_line_replaces_a_plant_block(motor_fmu, tmp_path, capsys):
    """open-loop with the user's motor in the place of MotorMagnetics: the vehicle's rotors
    follow the user's model (spin-up 63 % at tau), the run records the replacement."""
    out = tmp_path / "ol"
    assert main(["run", "open-loop", "--set", "duration=0.3", "--fmu", f"MotorMagnetics={motor_fmu}",
                 "--out", str(out)]) == 0, capsys.readouterr().err
    err = capsys.readouterr().err
    assert "MotorMagnetics.omega_r1: the FMU declares no unit; taken as rad/s" in err  # pythonfmu writes none
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["replaced_blocks"]["MotorMagnetics"]["fmu"] == str(motor_fmu)
    from quadcosim.orchestrator import Result

    result = Result.load(out)
    command, speed = result["Setpoint.c1"], result["MotorMagnetics.omega_r1"]
    expected = np.zeros_like(speed)  # the user's law, stepped on the commands the master fed it
    for k in range(len(speed) - 1):
        expected[k + 1] = expected[k] + 1e-3 / TAU * (command[k] * OMEGA_MAX - expected[k])
    assert np.allclose(speed, expected, rtol=1e-12, atol=1e-9)
    assert speed[-1] > 300.0  # spun up: the Quadrotor flew on the user's rotors
    assert "MotorMagnetics.soc" not in result.names  # the plant's battery is gone with its block


def _with_units(source, target, units: dict, rename: tuple):
    """A copy of the FMU with units written into its variable table and one variable renamed."""
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                for name, unit in units.items():
                    real = text.index("<Real", text.index(f'name="{name}"'))
                    text = text[:real] + f'<Real unit="{unit}"' + text[real + len("<Real"):]
                declared = "".join(f'<Unit name="{unit}"/>' for unit in units.values())
                text = text.replace("<LogCategories>", f"<UnitDefinitions>{declared}</UnitDefinitions><LogCategories>")
                data = text.replace(f'name="{rename[0]}"', f'name="{rename[1]}"').encode()
            zout.writestr(item, data)


def test_an_fmu_whose_interface_differs_is_refused_with_every_mismatch(motor_fmu, tmp_path, capsys):
    other = tmp_path / "rpm_motor.fmu"
    _with_units(motor_fmu, other, {"omega_r1": "rpm", "c2": "%"}, rename=("domega_r4", "spin_acceleration4"))
    assert main(["run", "open-loop", "--set", "duration=0.1", "--fmu", f"MotorMagnetics={other}",
                 "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert "the FMU's interface differs from MotorMagnetics's (3 mismatches)" in err
    assert "input c2 in %, where MotorMagnetics has 1" in err
    assert "output omega_r1 in rpm, where MotorMagnetics has rad/s" in err
    assert "no output domega_r4 (rad/s2), which the system reads" in err
    assert not (tmp_path / "x").exists()
    assert main(["run", "open-loop", "--fmu", "Setpoint=" + str(motor_fmu), "--out", str(tmp_path / "y")]) == 2
    assert "Setpoint is a Python block" in capsys.readouterr().err
    assert main(["run", "open-loop", "--fmu", "MotorMagnetics=nowhere.fmu", "--out", str(tmp_path / "z")]) == 2
    assert "--fmu MotorMagnetics=nowhere.fmu: no file nowhere.fmu" in capsys.readouterr().err


def test_a_vector_whose_components_are_apart_in_the_record_is_saved_as_recorded(tmp_path):
    """Another exporter may interleave a vector's components with other outputs (omega_r1, domega_r1,
    i1, omega_r2, ...): the .npz gathers them into one array, in C order, and reads them back
    unchanged (it wrote Fortran-ordered copies under a C-order header, scrambling every sample)."""
    from quadcosim.orchestrator import Result

    t = np.arange(50) * 1e-3
    names = [f"M.{kind}{n}" for n in (1, 2, 3) for kind in ("omega_r", "i")]
    data = np.asfortranarray(np.random.default_rng(3).normal(size=(len(t), len(names))))
    Result(t, names, data, {"units": {}}).to_npz(tmp_path / "r.npz")
    back = Result.from_npz(tmp_path / "r.npz")
    for k, name in enumerate(names):
        assert np.array_equal(back[name], data[:, k]), name
