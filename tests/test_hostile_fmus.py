"""FMUs that crash, exit, hang, lie or do not load, built from C at test time
(:mod:`tests.hostile_fmu`): each ends the run with a message naming the block, the FMU and
what happened, exit 1 in the loop (the record up to the last good step kept) or 2 before it
(metrics.json alone, ``refused`` with the message and no sample), and leaves no lock, temporary
folder or worker process behind."""

import json
import os
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import hostile_fmu
import numpy as np
import pytest
from hostile_fmu import FAULT_STEP
from quadcosim.orchestrator import Result

from quadcosim.main import main

ROOT = Path(__file__).resolve().parents[1]
RUN = ["run", "open-loop", "--set", "duration=0.3", "--format", "npz"]


@pytest.fixture(scope="session")
def hostile(tmp_path_factory):
    """``hostile(behaviour)``: the motor FMU with that behaviour, compiled once per session."""
    folder = tmp_path_factory.mktemp("hostile")
    built = {}

    def get(behaviour: str) -> Path:
        if behaviour not in built:
            built[behaviour] = hostile_fmu.build(behaviour, folder)
        return built[behaviour]
    return get


@pytest.fixture(scope="session")
def good_record(hostile, tmp_path_factory):
    """The open-loop run on the well-behaved motor: what every failing run must have recorded."""
    out = tmp_path_factory.mktemp("good") / "run"
    assert main([*RUN, "--fmu", f"MotorMagnetics={hostile('good')}", "--out", str(out)]) == 0
    return Result.load(out)


def _left_behind(out: Path) -> list[str]:
    return sorted(p.name for p in out.iterdir() if p.name.startswith(".") or p.name.endswith(".part"))


@pytest.mark.parametrize("behaviour, words, watchdog", [
    ("segfault", "crashed in fmi2DoStep: its process was killed by SIGSEGV (a segmentation fault", None),
    ("abort", "crashed in fmi2DoStep: its process was killed by SIGABRT (the FMU called abort)", None),
    ("exit0", "ended its process in fmi2DoStep with exit code 0 (the FMU called exit)", None),
    ("status_m1", "fmi2DoStep returned -1 (no FMI status: taken as a failure)", None),
    ("hang_step", "did not return from fmi2DoStep within the watchdog's 0.5 s", "0.5"),
])
def test_an_fmu_failing_in_the_loop_ends_the_run_with_its_record(hostile, good_record, behaviour, words, watchdog,
                                                                 tmp_path, capsys, monkeypatch):
    """Exit 1, metrics.json ``failed`` with the message, and the samples up to the fault step
    equal to the well-behaved motor's, bit for bit."""
    if watchdog:
        monkeypatch.setenv("QUADCOSIM_FMU_WATCHDOG", watchdog)
    out = tmp_path / "run"
    fmu = hostile(behaviour)
    assert main([*RUN, "--fmu", f"MotorMagnetics={fmu}", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert words in err and "MotorMagnetics" in err and fmu.name in err
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "failed" and words in metrics["error"]
    assert metrics["recorded_until_s"] == pytest.approx(FAULT_STEP * 1e-3)
    result = Result.load(out)
    assert len(result) == FAULT_STEP + 1
    assert np.array_equal(result["MotorMagnetics.omega_r1"], good_record["MotorMagnetics.omega_r1"][:FAULT_STEP + 1])
    assert result["MotorMagnetics.omega_r1"][-1] > 10.0  # the rotors had spun up: a real record
    assert _left_behind(out) == []


def _repacked(fmu: Path, target: Path, description=None, binary=None) -> Path:
    """``fmu`` with its description (text) or binary (bytes) edited by the functions given."""
    with zipfile.ZipFile(fmu) as archive:
        text = archive.read("modelDescription.xml").decode()
        so = archive.read("binaries/linux64/Hostile.so")
    add = {"modelDescription.xml": (description or (lambda t: t))(text).encode(),
           "binaries/linux64/Hostile.so": (binary or (lambda b: b))(so)}
    return hostile_fmu.repacked(fmu, target, drop=tuple(add), add=add)


def _machine(so: bytes, number: int) -> bytes:
    return so[:18] + number.to_bytes(2, "little") + so[20:]


def _alias(text: str, output: str, ref: int) -> str:
    start = text.index(f'name="{output}" valueReference="')
    end = text.index('"', start + len(f'name="{output}" valueReference="'))
    return text[:start] + f'name="{output}" valueReference="{ref}' + text[end:]


REFUSALS = {
    "null_instance": (None, "refused to make an instance (fmi2Instantiate returned NULL; [Error] this FMU never makes"),
    "bad_vr": (None, "refuses to read b_d_z (value reference 99"),
    "no_do_step": (None, "binary has no function fmi2DoStep, which FMI 2.0 Co-Simulation requires"),
    "win64 only": (lambda fmu, target: hostile_fmu.repacked(
        fmu, target, rename={"binaries/linux64/Hostile.so": "binaries/win64/Hostile.dll"}),
        "this FMU has no linux64 binary (it has win64): export it for Linux"),
    "aarch64": (lambda fmu, target: _repacked(fmu, target, binary=lambda so: _machine(so, 183)),
                "its linux64 binary is built for aarch64; this machine runs x86_64: export it for x86_64 Linux"),
    "zip slip": (lambda fmu, target: hostile_fmu.repacked(fmu, target, add={"resources/../../evil.txt": b"x"}),
                 "would be written outside the folder the FMU is extracted to (a zip-slip path)"),
    "path identifier": (lambda fmu, target: _repacked(
        fmu, target, description=lambda t: t.replace('modelIdentifier="Hostile"', 'modelIdentifier="../Hostile"')),
        "its modelIdentifier '../Hostile' is not a plain name"),
    "aliased output": (lambda fmu, target: _repacked(fmu, target, description=lambda t: _alias(t, "omega_r1", 2)),
                       "the output omega_r1 has the value reference 2 of c1 (Real), so it would read back"),
    "shared input": (lambda fmu, target: _repacked(fmu, target, description=lambda t: _alias(t, "c2", 2)),
                     "c1, c2 share the value reference 2 (Real)"),
    "zip bomb": (lambda fmu, target: hostile_fmu.zip_bomb(fmu, target),
                 "would expand to 3904 MiB, over the extraction limit of 1024 MiB: it is refused before extracting"),
}


@pytest.mark.parametrize("case", list(REFUSALS))
def test_an_fmu_that_cannot_run_is_refused_before_the_loop(hostile, case, tmp_path, capsys, monkeypatch):
    """Exit 2 with the problem and the fix, nothing extracted, and metrics.json alone in the
    folder: ``refused``, the message naming the block and the FMU, the options, no sample."""
    make, words = REFUSALS[case]
    fmu = hostile(case) if make is None else make(hostile("good"), tmp_path / f"{case.replace(' ', '_')}.fmu")
    extracted = []
    if make is not None:  # refused from the archive alone: nothing of it is extracted
        import quadcosim.orchestrator.fmu as module

        monkeypatch.setattr(module, "extract", lambda *args: extracted.append(args))
    out = tmp_path / "run"
    assert main([*RUN, "--fmu", f"MotorMagnetics={fmu}", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert words in err, err
    assert "Traceback" not in err and not extracted
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json"]  # no lock, record, .part or reserve
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "refused" and words in metrics["error"]
    assert metrics["error"].startswith("MotorMagnetics: ") and fmu.name in metrics["error"]
    assert metrics["samples"] == 0 and metrics["files"] == [] and metrics["recorded_until_s"] is None
    assert metrics["options"]["duration"] == pytest.approx(0.3)


def test_a_refused_fmu_leaves_the_files_already_in_the_folder(hostile, tmp_path, capsys):
    """A folder that held files before keeps them; its refused metrics.json holds no result,
    so the next run into the folder needs no --overwrite and replaces it."""
    out = tmp_path / "run"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert main([*RUN, "--fmu", f"MotorMagnetics={hostile('null_instance')}", "--out", str(out)]) == 2
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "notes.txt"]
    assert json.loads((out / "metrics.json").read_text())["status"] == "refused"
    assert (out / "notes.txt").read_text() == "mine"
    assert main([*RUN, "--fmu", f"MotorMagnetics={hostile('good')}", "--out", str(out)]) == 0
    assert json.loads((out / "metrics.json").read_text())["status"] == "completed"
    assert {"metrics.json", "notes.txt", "results.npz"} <= {p.name for p in out.iterdir()}
    assert (out / "notes.txt").read_text() == "mine"


def _cli(args, env_extra, tmp):
    env = dict(os.environ, TMPDIR=str(tmp), **env_extra)
    return subprocess.Popen([sys.executable, "-m", "quadcosim.main", *args], cwd=ROOT, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)


def _workers(parent: int) -> list[str]:
    found = subprocess.run(["pgrep", "-P", str(parent)], capture_output=True, text=True).stdout.split()
    return found


@pytest.mark.parametrize("behaviour, number, samples", [
    ("hang_step", signal.SIGINT, FAULT_STEP + 1),
    ("hang_init", signal.SIGTERM, 0),
])
def test_a_hanging_fmu_yields_to_sigint_and_sigterm(hostile, behaviour, number, samples, tmp_path):
    """``quadcosim run open-loop --fmu MotorMagnetics=HANG.fmu``: the signal ends it within 5 s with
    130 or 143, metrics.json ``interrupted`` with the record so far, no lock, no temporary folder."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    out = tmp_path / "run"
    process = _cli([*RUN, "--fmu", f"MotorMagnetics={hostile(behaviour)}", "--out", str(out)], {}, tmp)
    deadline = time.monotonic() + 120
    while not (out / "metrics.json").exists() and time.monotonic() < deadline:  # it hangs once a worker runs
        if any(_workers(process.pid)):
            time.sleep(1.0 if behaviour == "hang_init" else 3.0)
            break
        time.sleep(0.2)
    sent = time.monotonic()
    process.send_signal(number)
    code = process.wait(timeout=30)
    took = time.monotonic() - sent
    err = process.stderr.read()
    assert code == 128 + number, err
    assert took < 5.0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "interrupted"
    assert metrics["samples"] == samples
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "results.npz"]
    assert list(tmp.iterdir()) == []


def test_a_crash_leaves_no_temporary_folder_and_the_watchdog_option_works(hostile, tmp_path):
    """In its own process (its exit handlers run): the extracted FMU is removed after a crash, and
    ``--watchdog`` ends a hanging step."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    for behaviour, extra in (("segfault", []), ("hang_step", ["--watchdog", "0.5"])):
        out = tmp_path / behaviour
        process = _cli([*RUN, *extra, "--fmu", f"MotorMagnetics={hostile(behaviour)}", "--out", str(out)], {}, tmp)
        assert process.wait(timeout=300) == 1
        err = process.stderr.read()
        assert f"MotorMagnetics ({hostile(behaviour)}, run in its own process) at t = 0.1 s" in err
        assert json.loads((out / "metrics.json").read_text())["samples"] == FAULT_STEP + 1
        assert list(tmp.iterdir()) == []


def _motor_system(fmu: Path):
    from quadcosim.orchestrator import Constant, FMUBlock, System

    system = System(dt=1e-3)
    system.add(Constant("Command", {f"c{n}": 0.2 * n for n in (1, 2, 3, 4)}))
    system.add(FMUBlock("Motor", model=fmu))
    for n in (1, 2, 3, 4):
        system.connect(f"Command.c{n}", f"Motor.c{n}")
    return system


def test_an_isolated_fmu_gives_the_numbers_it_gives_in_process(hostile, monkeypatch):
    """The worker steps the same instance code: both masters, isolated or in process, agree bit
    for bit, and follow the motor's explicit-Euler law."""
    system = _motor_system(hostile("good"))
    isolated = [system.run(0.2, master=master) for master in ("chunk", "step")]
    monkeypatch.setenv("QUADCOSIM_FMU_IN_PROCESS", "1")
    in_process = system.run(0.2)
    for result in isolated:
        assert np.array_equal(result.data, in_process.data)
    k = np.arange(len(in_process))
    omega = in_process["Motor.omega_r3"]
    assert np.allclose(omega, 0.6 * hostile_fmu.OMEGA_MAX * (1 - (1 - 1e-3 / hostile_fmu.TAU) ** k), rtol=1e-12)


@pytest.mark.parametrize("behaviour, pooled", [("good", True), ("noop_reset", False), ("reset_error", False)])
def test_the_pool_keeps_an_fmu_only_when_its_reset_resets(hostile, behaviour, pooled):
    """Three runs in a row with reuse on (as the pytest plugin's): each starts from rest and records
    the same numbers. An FMU whose reset resets nothing, or fails, is instantiated afresh for each
    run, and a warning says so once."""
    import warnings

    from quadcosim.orchestrator import pool

    system = _motor_system(hostile(behaviour))
    previous = pool.reuse(True)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            runs = [system.run(0.05) for _ in range(3)]
            idle = pool.idle_count()
    finally:
        pool.reuse(previous)
    said = [w for w in caught if "fmi2Reset does not reproduce a fresh instance" in str(w.message)]
    assert len(said) == (0 if pooled else 1)
    assert idle == (1 if pooled else 0)
    for result in runs:
        assert result["Motor.omega_r1"][0] == 0.0
        assert np.array_equal(result.data, runs[0].data)
