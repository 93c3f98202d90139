"""Runs and files under hostile but honest use: interrupts, bad output folders, runs too large
for memory, out-of-range seeds, FMU warnings. Each case checks the message, the exit code and
what is left on disk."""

import gc
import io
import json
import os
import re
import shlex
import signal
import subprocess
import sys
import time
import tracemalloc
import warnings
import weakref
from pathlib import Path

import numpy as np
import pytest
from helpers import documentation
from quadcosim.orchestrator import Block, Fault, FMUBlock, Result, SimulationError, System, Table
from scipy.io import loadmat

import quadcosim.infra.files
from quadcosim import scenarios
from quadcosim.infra.files import atomic_path
from quadcosim.infra.interrupts import Terminated, first_only
from quadcosim.main import main as cli

ROOT = Path(__file__).resolve().parent.parent


# ---------------------------------------------------------------------- interrupts
@pytest.mark.parametrize("sent, raised", [(signal.SIGINT, KeyboardInterrupt), (signal.SIGTERM, Terminated)])
def test_a_signal_landing_in_a_weakref_callback_is_raised_once_the_callback_is_over(sent, raised):
    # Python prints and drops an exception raised in a weakref callback; a matplotlib figure
    # being freed runs many, and a Ctrl-C there had let a run finish with exit 0.
    class Node:
        pass

    after, hook, handler = [], sys.unraisablehook, signal.getsignal(signal.SIGINT)
    with pytest.raises(raised):
        with first_only():
            node = Node()
            reference = weakref.ref(node, lambda _: signal.raise_signal(sent))  # the handler runs inside
            with warnings.catch_warnings():
                warnings.simplefilter("error")  # nothing reported as ignored
                del node  # the callback runs, and its interrupt is dropped
                deadline = time.monotonic() + 1.0
                while time.monotonic() < deadline:  # ordinary code: the signal is raised here
                    after.append(time.monotonic())
    assert reference() is None and 0 < len(after) and after[-1] < deadline
    # the handlers in force before are back (Python's own, or SIG_IGN inherited from a nohup'd parent)
    assert sys.unraisablehook is hook and signal.getsignal(signal.SIGINT) is handler


@pytest.mark.parametrize("sent, raised", [(signal.SIGINT, KeyboardInterrupt), (signal.SIGTERM, Terminated)])
def test_a_signal_landing_in_a_file_closed_by_its_finaliser_is_raised_once_it_is_closed(sent, raised):
    # A file object's finaliser clears an exception of its close() without a word: fmpy's zip
    # members closed so while a model description was read let a SIGTERM end a run with exit 0.
    class Member(io.RawIOBase):
        def close(self):
            signal.raise_signal(sent)  # the handler runs inside
            super().close()

    after, handler = [], signal.getsignal(signal.SIGINT)
    with pytest.raises(raised):
        with first_only():
            member = Member()
            del member  # its finaliser closes it, and clears what close() raises
            deadline = time.monotonic() + 1.0
            while time.monotonic() < deadline:  # ordinary code: the signal is raised here
                after.append(time.monotonic())
    assert 0 < len(after) and after[-1] < deadline
    assert signal.getsignal(signal.SIGINT) is handler


def test_a_signal_during_an_import_is_raised_once_the_module_is_made(tmp_path, monkeypatch):
    # An interrupt inside an extension module's making (matplotlib's ft2font under pybind11)
    # became an ImportError, and the process later crashed on the half-made module.
    # A SIGTERM, then a Ctrl-C pressed because it seemed slow: the first is the one raised.
    (tmp_path / "interrupted_module.py").write_text(
        "import signal\nsignal.raise_signal(signal.SIGTERM)\nfor k in range(100000):\n    pass\n"
        "signal.raise_signal(signal.SIGINT)\nMADE = True\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    after = []
    with pytest.raises(Terminated):
        with first_only():
            import interrupted_module
            deadline = time.monotonic() + 1.0
            while time.monotonic() < deadline:  # the signal is raised here, after the import
                after.append(time.monotonic())
    assert sys.modules.pop("interrupted_module").MADE and interrupted_module.MADE
    assert 0 < len(after) and after[-1] < deadline


@pytest.mark.slow
@pytest.mark.parametrize("sent, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_an_interrupted_run_saves_what_it_recorded_and_leaves_no_temporary_files(tmp_path, sent, code):
    temporary, out, errors = tmp_path / "tmp", tmp_path / "run", tmp_path / "stderr"
    temporary.mkdir()
    # Two hours of flight (on a bench supply, so that no battery ends it; one row a second
    # recorded) are interrupted as soon as the progress bar shows simulated time past 0: the
    # signal lands inside the loop however loaded, or fast, the machine is.
    duration = 7200
    command = [sys.executable, "-m", "quadcosim.main", "run", "tp", "--set", f"duration={duration}",
               "--set", "bench_supply=on", "--decimation", "1000", "--out", str(out),
               "--format", "npz,mat"]

    def running() -> bool:  # a progress line "n/total" with n > 0
        return any(float(n) > 0 for n in re.findall(rf"([0-9.]+)/{duration}", errors.read_text()))

    with errors.open("w") as stderr:
        process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=stderr, cwd=ROOT,
                                   env=os.environ | {"TMPDIR": str(temporary)})
        try:
            deadline = time.monotonic() + 300
            while not running() and process.poll() is None and time.monotonic() < deadline:
                time.sleep(0.05)
            assert process.poll() is None and running(), \
                f"no progress bar of a running loop: {errors.read_text()[-2000:]}"
            process.send_signal(sent)
            assert process.wait(timeout=60) == code, errors.read_text()[-2000:]
        finally:
            if process.poll() is None:
                process.kill()
    message = errors.read_text()
    assert f"interrupted by {sent.name} at t = " in message
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "interrupted" and metrics["interrupted_by"] == sent.name
    stopped = metrics["recorded_until_s"]
    assert 0 < stopped < duration
    saved = Result.from_npz(out / "results.npz")
    assert len(saved) == metrics["samples"] and saved.time[-1] == pytest.approx(stopped)
    assert np.isfinite(saved.data).all() and saved["Quadrotor.q0"].shape == (len(saved),)
    matlab = loadmat(out / "results.mat")
    assert matlab["time"].size == len(saved)
    assert sorted(os.listdir(temporary)) == []  # the extracted FMUs are gone
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no half-written file
    print(f"{sent.name}: exit {code}, stopped at t = {stopped} s, {len(saved)} samples kept")


def test_an_interrupt_while_saving_keeps_the_earlier_file(tmp_path, monkeypatch):
    path = tmp_path / "results.npz"
    earlier = Result(np.arange(3.0), ["A.x"], np.ones((3, 1)))
    earlier.to_npz(path)
    before = path.read_bytes()

    def interrupted_write(file, array, **options):
        file.write(b"half an array")
        raise KeyboardInterrupt

    monkeypatch.setattr(np.lib.format, "write_array", interrupted_write)
    with pytest.raises(KeyboardInterrupt):
        Result(np.arange(5.0), ["A.x"], np.zeros((5, 1))).to_npz(path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.npz"]


def test_atomic_files_take_the_usual_permissions(tmp_path):
    with atomic_path(tmp_path / "metrics.json") as temporary:
        temporary.write_text("{}")
    assert (tmp_path / "metrics.json").stat().st_mode & 0o777 == 0o666 & ~quadcosim.infra.files._UMASK


def test_a_signal_as_the_temporary_file_is_made_leaves_no_temporary(tmp_path, monkeypatch):
    made = quadcosim.infra.files.tempfile.mkstemp

    def interrupted_right_after_creation(*args, **kwargs):
        handle, name = made(*args, **kwargs)
        signal.raise_signal(signal.SIGINT)  # the file exists, its name not yet returned
        return handle, name

    monkeypatch.setattr(quadcosim.infra.files.tempfile, "mkstemp", interrupted_right_after_creation)
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(tmp_path / "yaw.png") as temporary:
            temporary.write_bytes(b"never reached")
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------- output folder
def test_out_is_checked_before_the_run(tmp_path, capsys):
    existing_file = tmp_path / "results"
    existing_file.write_text("not a folder")
    start = time.perf_counter()
    assert cli(["run", "open-loop", "--out", str(existing_file)]) == 2
    assert "--out " + str(existing_file) + ": a file of that name exists; give a folder name" in capsys.readouterr().err
    assert cli(["run", "open-loop", "--out", "/proc/quadcosim-results"]) == 2
    assert "cannot create the folder" in capsys.readouterr().err
    assert time.perf_counter() - start < 5  # refused before anything is simulated


def test_existing_results_are_refused_unless_overwrite_and_stale_files_go(tmp_path, capsys):
    out = tmp_path / "run"
    base = ["run", "open-loop", "--set", "duration=0.05", "--out", str(out)]
    assert cli([*base, "--format", "npz,csv"]) == 0
    assert {"results.npz", "results.csv", "metrics.json", "open_loop.png"} <= {p.name for p in out.iterdir()}
    first = (out / "results.npz").read_bytes()
    capsys.readouterr()
    assert cli(base) == 2
    assert "already holds results (results.npz, results.csv, metrics.json); give another folder or add " \
        "--overwrite to replace them" in capsys.readouterr().err
    assert (out / "results.npz").read_bytes() == first
    assert cli([*base, "--format", "mat", "--overwrite"]) == 0
    names = {p.name for p in out.iterdir()}
    assert "results.csv" not in names and "results.npz" not in names and "results.mat" in names
    assert json.loads((out / "metrics.json").read_text())["files"] == ["imu.png", "open_loop.png", "results.mat"]


# ---------------------------------------------------------------------- recording options
def test_decimation_record_and_format_on_the_command_line(tmp_path, capsys):
    out = tmp_path / "run"
    assert cli(["run", "open-loop", "--set", "duration=0.1", "--out", str(out), "--decimation", "10",
                "--record", "IMU.acc", "Quadrotor.q", "--format", "npz,mat,csv"]) == 0
    saved = Result.from_npz(out / "results.npz")
    assert saved.names == ["Quadrotor.q0", "Quadrotor.q1", "Quadrotor.q2", "Quadrotor.q3",
                           "IMU.acc_x", "IMU.acc_y", "IMU.acc_z"]
    assert np.allclose(saved.time, np.arange(11) * 0.01)
    header = (out / "results.csv").read_text().splitlines()[0]
    assert header == "time," + ",".join(saved.names)
    assert loadmat(out / "results.mat")["IMU"]["acc_x"][0, 0].size == 11
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["decimation"] == 10 and metrics["samples"] == 11
    assert "report skipped" in metrics["report"] and "Setpoint.c" in metrics["report"]
    import matplotlib.pyplot as plt  # imported by the run

    assert not plt.get_fignums()  # the figure the report had begun is closed


@pytest.mark.parametrize("arguments, words", [
    (["--decimation", "0"], "argument --decimation: '0' is not a positive integer"),
    (["--format", "npz,xls"], "--format npz,xls: choose among npz, mat, csv"),
    (["--record", "IMU.acc_w"], "IMU has no output 'acc_w'. Did you mean"),
])
def test_bad_recording_options_are_refused(arguments, words, tmp_path, capsys):
    assert run_cli(["run", "open-loop", "--set", "duration=0.05", "--out", str(tmp_path / "run"), *arguments]) == 2
    assert words in capsys.readouterr().err


def run_cli(arguments) -> int:
    """The command's exit code, argparse's refusals included."""
    try:
        return cli(arguments)
    except SystemExit as exit:
        return exit.code


# ---------------------------------------------------------------------- memory
def test_a_run_that_would_not_fit_in_memory_is_refused_with_the_figure_and_the_way_out(tmp_path, capsys):
    start = time.perf_counter()
    assert cli(["run", "open-loop", "--set", "duration=1e7", "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert "this run would record 10000000001 samples of" in err
    assert "GB of memory available (bound by " in err
    assert "Record less: every N-th step (--decimation N, now 1)" in err
    assert time.perf_counter() - start < 20


@pytest.mark.slow
def test_the_record_is_not_copied_at_the_end_of_a_run():
    """Python-side allocations during a run: the record, its time vector, and little else."""
    steps = 200_000
    system = System(dt=1e-3)
    system.add(Table("Source", ["a", "b", "c", "d"], np.ones((1, 4))))
    tracemalloc.start()
    result = system.run(steps * 1e-3)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    recorded = result.data.nbytes + result.time.nbytes
    print(f"peak Python allocation {peak / 1e6:.2f} MB for {recorded / 1e6:.2f} MB recorded")
    assert peak < 1.05 * recorded


# ---------------------------------------------------------------------- FMU parameters and warnings
def test_a_seed_beyond_32_bits_is_refused_not_wrapped(tmp_path, capsys):
    assert cli(["run", "open-loop", "--set", "seed=4294967297", "--out", str(tmp_path / "run")]) == 2
    assert "IMU.seed = 4294967297 is outside the range of an FMI Integer, -2147483648 to 2147483647" \
        in capsys.readouterr().err


def test_fmu_warnings_are_counted_and_the_first_shown(tmp_path, capsys):
    system = System()
    system.add(Table("Setpoint", ["c1", "c2", "c3", "c4"], [[1.5, 0.5, -0.2, 0.5]]))
    system.add(FMUBlock("MotorMagnetics"))
    system.connect("Setpoint.c", "MotorMagnetics.c")
    result = system.run(0.01)
    warnings = result.meta["fmu_warnings"]["MotorMagnetics"]
    assert warnings["count"] == 2
    assert warnings["first"][0].startswith("[Warning] c1 = 1.5 at t = 0 is outside [0, 1]: saturated")
    out = tmp_path / "run"
    assert cli(["run", "open-loop", "--set", "duration=0.3", "--out", str(out),
                "--fault", "MotorMagnetics.c2:offset:0.1:0.2:1.0"]) == 0
    err = capsys.readouterr().err
    assert "FMU warnings: MotorMagnetics 1" in err
    assert "MotorMagnetics: [Warning] c2 = " in err and "is outside [0, 1]: saturated" in err
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["fmu_warnings"]["MotorMagnetics"]["count"] == 1


# ---------------------------------------------------------------------- faults
class Echo(Block):
    inputs, outputs = ("u",), ("y",)

    def step(self, t, u, y):
        y[0] = u[0]


def echo_system(*faults):
    system = System()
    system.add(Table("Source", ["x"], [[1.0]]))
    system.add(Echo("Echo"))
    system.connect("Source.x", "Echo.u")
    for fault in faults:
        system.inject(fault)
    return system


def test_faults_on_one_input_compose_in_the_order_given():
    result = echo_system(Fault("Echo.u", "offset", 0.0, 0.5, 10.0), Fault("Echo.u", "offset", 0.0, 0.5, 100.0),
                         Fault("Echo.u", "scale", 0.25, 0.5, 2.0)).run(1.0)
    y = result["Echo.y"]
    assert y[0] == 111.0 and y[249] == 111.0  # 1 + 10 + 100
    assert y[250] == 222.0  # then scaled: 2 (1 + 110)
    assert y[500] == 1.0  # every window closed
    swapped = echo_system(Fault("Echo.u", "scale", 0.0, 0.5, 2.0), Fault("Echo.u", "offset", 0.0, 0.5, 10.0)).run(0.1)
    assert swapped["Echo.y"][0] == 12.0  # 2 x + 10, not 2 (x + 10)


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -float("inf")])
def test_a_non_finite_fault_value_is_refused(value):
    with pytest.raises(ValueError, match=f"offset fault on Echo.u: value {value} is not a finite number"):
        Fault("Echo.u", "offset", 0.0, 1.0, value)


def test_a_non_finite_fault_value_is_refused_on_the_command_line(tmp_path, capsys):
    assert cli(["run", "open-loop", "--out", str(tmp_path / "run"), "--fault", "IMU.omega_x:offset:0.5:1:nan"]) == 2
    assert "offset fault on IMU.omega_x: value nan is not a finite number" in capsys.readouterr().err
    assert not (tmp_path / "run" / "results.npz").exists()


@pytest.mark.parametrize("start, stop", [(2.0, 3.0), (-2.0, -1.0), (0.1004, 0.1008)])
def test_a_fault_window_no_step_falls_in_warns(start, stop):
    with pytest.warns(RuntimeWarning, match=rf"the offset fault on Echo.u acts for {start} s <= t < {stop} s, "
                                            r"when no step of the run \(0 s to 1 s, every 0.001 s\) falls: it has "
                                            "no effect"):
        result = echo_system(Fault("Echo.u", "offset", start, stop, 5.0)).run(1.0)
    assert (result["Echo.y"] == 1.0).all()


def test_a_fault_window_inside_the_run_does_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = echo_system(Fault("Echo.u", "offset", 1.0, 3.0, 5.0)).run(1.0)  # active at the last step only
    assert result["Echo.y"][-1] == 6.0


def test_a_fault_window_outside_the_run_warns_on_the_command_line(tmp_path, capsys):
    assert cli(["run", "open-loop", "--set", "duration=0.2", "--out", str(tmp_path / "run"),
                "--fault", "IMU.omega_x:offset:5:6:0.1"]) == 0
    assert "the offset fault on IMU.omega_x acts for 5.0 s <= t < 6.0 s, when no step of the run (0 s to 0.2 s" \
        in capsys.readouterr().err


def test_a_non_finite_value_made_by_a_fault_names_the_fault():
    class Estimator(Block):  # a Python block that turns an infinite input into NaN
        inputs, outputs = ("u",), ("y",)

        def step(self, t, u, y):
            y[0] = u[0] - u[0]

    system = System()
    system.add(Table("Source", ["x"], [[1.0]]))
    system.add(Estimator("Estimator"))
    system.connect("Source.x", "Estimator.u")
    system.inject(Fault("Estimator.u", "scale", 0.1, 0.2, 1e300))
    system.inject(Fault("Estimator.u", "scale", 0.1, 0.2, 1e300))
    with pytest.raises(SimulationError) as error:
        system.run(1.0)
    assert str(error.value).startswith("the scale fault on Estimator.u (value 1e+300, from 0.1 s to 0.2 s) made it "
                                       "inf at t = 0.1 s")
    assert len(error.value.result) == 101


# ---------------------------------------------------------------------- the README's commands
def readme_commands() -> list[str]:
    """Every ``quadcosim`` command in the README's shell blocks, comments removed."""
    text = documentation()  # the README and the documentation's pages
    blocks = re.findall(r"```sh\n(.*?)```", text, flags=re.S)
    lines = [line.split(" #")[0].strip() for block in blocks for line in block.splitlines()]
    return list(dict.fromkeys(line for line in lines if line.startswith("quadcosim ")))


def test_the_readme_has_command_examples():
    commands = readme_commands()
    assert len(commands) >= 8 and any("--fault" in c for c in commands)


@pytest.mark.parametrize("command", readme_commands())
def test_every_command_in_the_readme_runs(command, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)  # results/ and figures land here
    code = run_cli(shlex.split(command)[1:])
    assert code == 0, capsys.readouterr().err[-3000:]


def test_the_help_fault_example_runs(tmp_path, capsys):
    from quadcosim.cli.run import _parse_fault

    with pytest.raises(ValueError) as error:
        _parse_fault("IMU.omega_x")
    example = re.search(r"e\.g\. (\S+)", str(error.value)).group(1)
    assert cli(["run", "open-loop", "--fault", example, "--out", str(tmp_path / "run")]) == 0
    assert "warning" not in capsys.readouterr().err.lower()


def test_the_tp_report_adds_little_to_the_memory_of_its_record(tmp_path):
    """The report's own allocations grow by under 5 % of what a longer run records (the full
    benchmark, peak RSS of whole runs, is ``python -m quadcosim.benchmarks.memory``)."""
    scenario = scenarios.get("tp")
    peaks, recorded = [], []
    for duration in (5.0, 5.0, 40.0):
        options = scenario.parse({"duration": duration})
        result = scenario.build(options).run(duration)
        # The first report pays for imports and font caches once; its peak is not kept. The
        # collection before each keeps one report's cyclic garbage out of the next one's peak.
        gc.collect()
        tracemalloc.start()
        scenario.report(result, options, tmp_path)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
        recorded.append(result.data.nbytes + result.time.nbytes)
    peaks, recorded = peaks[1:], recorded[1:]
    growth = (peaks[1] - peaks[0]) / (recorded[1] - recorded[0])
    print(f"tp report: peak allocation {peaks[0] / 1e6:.2f} MB at 5 s, {peaks[1] / 1e6:.2f} MB at 40 s: "
          f"{growth:.3f} of the record's growth")
    assert growth < 0.05
