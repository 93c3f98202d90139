"""Every FMI type, FMI 2.0 and 3.0 alike: the tests' own FMUs (``tests/typed_fmus``, built from C
here) have an input and an output of each numeric type, arrays, String and Binary parameters and a
counter that steps when an integrator crosses a threshold. Run by the master, in process and in a
worker process of their own (:mod:`quadcosim.orchestrator.isolated`), their outputs equal fmpy's
(``simulate_fmu``, same inputs, same step) to 1e-9, integers and Booleans exactly, and the record
keeps each signal's type into its files."""

import csv
import json
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from quadcosim.orchestrator import FMUBlock, Result, System, Table

from quadcosim.main import main

sys.path.insert(0, str(Path(__file__).parent / "typed_fmus"))
from build import build  # noqa: E402

DT, STEPS = 1e-3, 300


@pytest.fixture(scope="session")
def typed_fmus(tmp_path_factory):
    """The FMI 2.0 and FMI 3.0 test models, compiled once per session."""
    folder = tmp_path_factory.mktemp("typed_fmus")
    return {2: build("types2", folder), 3: build("types3", folder)}


@pytest.fixture(params=[False, True], ids=["in_process", "isolated"])
def isolated(request) -> bool:
    """Run the test's FMU in process, then in a worker process of its own."""
    return request.param


@pytest.fixture
def workers(monkeypatch) -> list:
    """The FMU files of the worker processes started during the test."""
    from quadcosim.orchestrator.isolated import IsolatedInstance

    started, init = [], IsolatedInstance.__init__

    def counted(self, model, *args, **kwargs):
        started.append(Path(model).name)
        init(self, model, *args, **kwargs)

    monkeypatch.setattr(IsolatedInstance, "__init__", counted)
    return started


def _inputs(types: dict) -> np.ndarray:
    """Input signals at every step, one field per input, in the FMU's own types (fmpy's form)."""
    k = np.arange(STEPS + 1)
    t = k * DT
    signals = np.zeros(STEPS + 1, dtype=[("time", float), *types.items()])
    signals["time"] = t
    patterns = {"u": np.sin(7 * t) + 1.5, "f32_in": np.float32(0.1) * (k % 7), "i8_in": k % 9 - 4, "u8_in": k % 200,
                "i16_in": -(k % 300), "u16_in": k * 100, "i32_in": k * 1000 - 5, "u32_in": k * 7, "i64_in": -3 * k,
                "u64_in": 11 * k, "enable": (k // 50) % 2 == 0, "mode": 1 + k // 120, "mode_in": 1 + k // 120,
                "k_in": k % 5 - 2, "b_in": k % 3 == 0}
    for name in types:
        signals[name] = patterns[name]
    return signals


def _system(path, signals, parameters: dict, master_vector=None, isolated=None) -> System:
    names = list(signals.dtype.names[1:])
    system = System(dt=DT)
    system.add(Table("In", names, np.column_stack([signals[n].astype(float) for n in names])))
    system.add(FMUBlock("T", model=path, parameters=parameters, isolated=isolated))
    for name in names:
        system.connect(f"In.{name}", f"T.{name}")
    if master_vector is not None:
        system.set_input("T.v", master_vector)
    return system


def _equal_to_fmpy(result: Result, reference: np.ndarray, outputs):
    for name in outputs:
        ours, theirs = result[f"T.{name}"], reference[name]
        assert ours.dtype == theirs.dtype, name  # integers and Booleans keep their type
        theirs = theirs.reshape(ours.shape)
        if ours.dtype.kind in "biu":
            assert np.array_equal(ours, theirs), name
        else:
            assert np.allclose(ours, theirs, rtol=0, atol=1e-9), (name, np.max(np.abs(ours - theirs)))


TYPES2 = {"u": float, "k_in": np.int32, "b_in": np.bool_, "mode_in": np.int32}
OUTPUTS2 = ["x", "counter", "k_sum", "flips", "above", "mode_out"]


def test_an_fmi2_fmu_of_every_type_equals_fmpy(typed_fmus, isolated, workers):
    """Real, Integer, Boolean and Enumeration inputs and outputs, a String parameter, a state that
    changes at events: the counter starts at 3, steps 13 times, and the Boolean it drives toggles."""
    import fmpy

    signals = _inputs(TYPES2)
    parameters = {"start_count": 3, "invert": True, "label": "abc", "note": "set"}
    reference = fmpy.simulate_fmu(str(typed_fmus[2]), stop_time=STEPS * DT, output_interval=DT, input=signals,
                                  start_values=parameters, output=OUTPUTS2)
    with pytest.warns(RuntimeWarning, match=r"T: tag, note are String or Binary, not signals: .* meta\['texts'\]"):
        block_system = _system(typed_fmus[2], signals, parameters, isolated=isolated)
    result = block_system.run(STEPS * DT)
    assert workers == (["Types2.fmu"] if isolated else [])
    _equal_to_fmpy(result, reference, OUTPUTS2)
    counter = result["T.counter"]
    crossings = int(np.sum(signals["u"][:-1]) * DT // 0.05)  # u > 0: one per 0.05 of its integral
    assert crossings == 13 and counter[0] == 3 and counter[-1] == 3 + crossings
    assert len(np.unique(counter)) == crossings + 1
    assert result["T.above"].dtype == bool and np.any(result["T.above"]) and not np.all(result["T.above"])
    assert result["T.k_sum"][-1] == np.sum(signals["k_in"][:-1])  # the inputs of every step but the last
    assert set(result["T.mode_out"]) == {1, 2, 3}
    assert result.meta["texts"] == {"T.label": "abc", "T.tag": "abc", "T.note": "set"}  # recorded once
    assert block_system.blocks["T"].dtypes == {"k_in": "int32", "mode_in": "int32", "b_in": "bool",
                                               "k_sum": "int32", "counter": "int32", "flips": "int32",
                                               "mode_out": "int32", "above": "bool"}


TYPES3 = {"u": float, "f32_in": np.float32, "i8_in": np.int8, "u8_in": np.uint8, "i16_in": np.int16,
          "u16_in": np.uint16, "i32_in": np.int32, "u32_in": np.uint32, "i64_in": np.int64, "u64_in": np.uint64,
          "enable": np.bool_, "mode": np.int64}
OUTPUTS3 = ["x", "counter", "f32_acc", "i8_out", "u8_out", "i16_out", "u16_out", "i32_out", "u32_out", "i64_out",
            "u64_out", "above", "mode_out", "w", "m", "steps"]


def test_an_fmi3_fmu_of_every_type_and_arrays_equals_fmpy(typed_fmus, tmp_path, isolated, workers):
    """Float32/64, Int8 to UInt64, Boolean, Enumeration, a vector input set by ``set_input``, a
    vector and a 2 x 2 output, String and Binary parameters: equal to fmpy, and the master's chunk
    runner equal to its per-step loop, bit for bit."""
    import fmpy

    signals = _inputs(TYPES3)
    parameters = {"label": "abc", "gain": 2.0}
    v = [1.0, -2.0, 0.5]
    reference = fmpy.simulate_fmu(str(typed_fmus[3]), stop_time=STEPS * DT, output_interval=DT, input=signals,
                                  start_values=parameters | {"v": v}, output=OUTPUTS3)
    system = _system(typed_fmus[3], signals, parameters | {"key": "cdef"}, master_vector=v, isolated=isolated)
    block = system.blocks["T"]
    assert block.inputs[-3:] == ("v_1", "v_2", "v_3") and block.outputs[-5:] == ("m_11", "m_12", "m_21", "m_22",
                                                                                  "steps")
    result = system.run(STEPS * DT)
    assert workers == (["Types3.fmu"] if isolated else [])
    _equal_to_fmpy(result, reference, OUTPUTS3)
    assert result["T.counter"][-1] >= 10 and result["T.steps"][-1] == STEPS
    assert np.allclose(result["T.w"][-1], np.array(v) * STEPS * DT, rtol=1e-12)
    assert result.meta["texts"] == {"T.label": "abc", "T.key": "cdef"}  # a Binary parameter as hexadecimal
    step = _system(typed_fmus[3], signals, parameters | {"key": "cdef"}, master_vector=v,
                   isolated=isolated).run(STEPS * DT, master="step")
    assert np.array_equal(step.data, result.data)
    other = _system(typed_fmus[3], signals, parameters | {"key": "cdef"}, master_vector=v,
                    isolated=not isolated).run(STEPS * DT)
    assert np.array_equal(other.data, result.data)  # isolated and in process, bit for bit


def test_typed_signals_are_saved_with_their_types(typed_fmus, tmp_path):
    """The .npz keeps int32, bool, float32, uint64; the .mat int32 and logical; the .csv writes
    integers as integers; a streamed record and the reread .npz give the same types back."""
    from quadcosim.orchestrator.stream import StreamWriter
    from scipy.io import loadmat

    signals = _inputs(TYPES3)
    result = _system(typed_fmus[3], signals, {}, master_vector=[1, 2, 3]).run(0.1)
    result.save(tmp_path, formats=("npz", "mat", "csv"))
    with np.load(tmp_path / "results.npz") as archive:
        assert archive["T.counter"].dtype == np.int32 and archive["T.above"].dtype == bool
        assert archive["T.f32_acc"].dtype == np.float32 and archive["T.steps"].dtype == np.uint64
        assert archive["T.w"].dtype == np.float64 and archive["T.w"].shape == (len(result), 3)
        assert np.array_equal(archive["T.steps"], np.arange(len(result)))
        assert json.loads(str(archive["_meta"]))["dtypes"]["T.mode_out"] == "int64"
    back = Result.load(tmp_path / "results.npz")
    assert back["T.counter"].dtype == np.int32 and np.array_equal(back["T.counter"], result["T.counter"])
    mat = loadmat(tmp_path / "results.mat", squeeze_me=True)
    assert mat["T"]["counter"].item().dtype == np.int32 and mat["T"]["i8_out"].item().dtype == np.int8
    assert mat["T"]["above"].item().dtype in (bool, np.uint8)  # MATLAB's logical
    with open(tmp_path / "results.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert rows[-1]["T.steps"] == str(len(result) - 1) and rows[-1]["T.above"] in ("0", "1")
    assert "." in rows[-1]["T.x"]
    streamed = _system(typed_fmus[3], signals, {}, master_vector=[1, 2, 3]).run(
        0.1, stream=StreamWriter(tmp_path / "stream"))
    assert streamed["T.counter"].dtype == np.int32 and np.array_equal(streamed["T.counter"], result["T.counter"])


def test_integer_and_boolean_inputs_take_the_nearest_value_in_range(typed_fmus):
    """A value on the bus set into an Int8 input is rounded and held in -128..127, into a UInt8
    one held at 0, into a Boolean one true unless zero; outputs are the inputs plus the counter (0)."""
    system = System(dt=DT)
    system.add(FMUBlock("T", model=typed_fmus[3]))
    values = {"u": 0.0, "f32_in": 0.0, "i8_in": 2.6, "u8_in": -5, "i16_in": 1e6, "u16_in": 7.4, "i32_in": -2.5,
              "u32_in": 3, "i64_in": -7, "u64_in": 1, "enable": 0.25, "mode": 2, "v": [0, 0, 0]}
    for name, value in values.items():
        system.set_input(f"T.{name}", value)
    result = system.run(2 * DT)
    last = {name: result[f"T.{name}"][-1] for name in ("i8_out", "u8_out", "i16_out", "u16_out", "i32_out")}
    assert last == {"i8_out": 3, "u8_out": 0, "i16_out": 32767, "u16_out": 7, "i32_out": -3}  # round half away
    assert result["T.mode_out"][-1] == 2 and result["T.counter"][-1] == 0
    with pytest.raises(ValueError, match=r"T\.v has 3 components \(v_1, v_2, v_3\): give one value or 3, not 2"):
        other = System(dt=DT)
        other.add(FMUBlock("T", model=typed_fmus[3]))
        other.set_input("T.v", [1, 2])


def test_a_vector_input_takes_a_vector():
    """``set_input`` ties each component of a vector input to its own value (it took one number)."""
    system = System(dt=DT)
    system.add(FMUBlock("Quadrotor"))
    system.set_input("Quadrotor.wind", [1.0, -2.0, 0.5])
    tied = {d: s for d, s in system.connections.items() if d.startswith("Quadrotor.wind")}
    constant = system.blocks[next(iter(tied.values())).split(".")[0]]
    assert list(tied) == ["Quadrotor.wind_x", "Quadrotor.wind_y", "Quadrotor.wind_z"]
    assert list(constant.values) == [1.0, -2.0, 0.5]
    with pytest.raises(ValueError, match="finite"):
        other = System(dt=DT)
        other.add(FMUBlock("Quadrotor"))
        other.set_input("Quadrotor.wind", [0.0, np.nan, 0.0])


def test_typed_signals_plot_as_steps(typed_fmus):
    import matplotlib

    matplotlib.use("Agg")
    result = _system(typed_fmus[3], _inputs(TYPES3), {}, master_vector=0.0).run(0.05)
    ax = result.plot("T.counter", "T.x")
    assert [line.get_drawstyle() for line in ax.lines] == ["steps-post", "default"]


def _clocked(source: Path, target: Path):
    """A copy of the FMI 3.0 model whose description declares a clock."""
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = data.replace(b"</ModelVariables>", b'<Clock name="tick" valueReference="40" causality="input" '
                                    b'variability="discrete" intervalVariability="constant" intervalDecimal="0.01"/>'
                                    b"</ModelVariables>")
            zout.writestr(item, data)


def test_an_fmu_with_clocks_is_refused_by_name(typed_fmus, tmp_path, capsys):
    clocked = tmp_path / "clocked.fmu"
    _clocked(typed_fmus[3], clocked)
    with pytest.raises(ValueError, match=r"has clocks \(tick\): the master runs FMI 3\.0 Co-Simulation without event"):
        FMUBlock("T", model=clocked)
    assert main(["run", "open-loop", "--set", "duration=0.1", "--fmu", f"MotorMagnetics={clocked}",
                 "--out", str(tmp_path / "x")]) == 2
    assert "has clocks (tick)" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_an_fmi3_instance_by_name_and_after_a_reset(typed_fmus, isolated):
    """Set and get by name (an array element alone: the others kept), step, and a reset that
    gives what a fresh instance gives, bit for bit (the pool of the pytest plugin resets)."""
    from quadcosim.orchestrator.fmu import FMU3Instance
    from quadcosim.orchestrator.isolated import IsolatedInstance, open_instance

    def FMUInstance(path, parameters=None, name=None):  # noqa: N802 (the class it stands for)
        return open_instance(path, parameters, name=name, isolated=isolated)

    def run(instance):
        instance.set(["v_2", "u", "i8_in", "enable"], [4.0, 30.0, -3.0, 1.0])
        for k in range(20):
            instance.step(k * DT, DT)
        return instance.get(["w_1", "w_2", "w_3", "x", "counter", "i8_out", "above"])

    fresh = FMUInstance(typed_fmus[3], {"gain": 2.0})
    assert isinstance(fresh, IsolatedInstance if isolated else FMU3Instance)
    first = run(fresh)
    assert np.allclose(first[:3], [0.0, 4.0 * 20 * DT, 0.0], rtol=1e-12, atol=0)
    assert first[4] == 20 and first[5] == -3 + 20  # x gains 0.06 a step: one crossing of 0.05 each step
    fresh.reset({"gain": 2.0})
    assert np.array_equal(run(fresh), first)
    fresh.close()
    with pytest.raises(KeyError, match=r"T3\.v is an array; name its elements \(v_1, v_2, v_3, \.\.\.\)"):
        other = FMUInstance(typed_fmus[3], name="T3")
        try:
            other.get(["v"])
        finally:
            other.close()


def test_an_fmu_that_asks_to_end_the_simulation_ends_the_run_with_its_record(typed_fmus, isolated):
    """terminateSimulation from fmi3DoStep (the counter reaching stop_count) ends the run: the
    error says so, and the record holds every step before, as fmpy's does."""
    import fmpy
    from quadcosim.orchestrator import SimulationError

    system = System(dt=DT)
    system.add(FMUBlock("T", model=typed_fmus[3], parameters={"stop_count": 4}, isolated=isolated))
    for name in TYPES3:
        system.set_input(f"T.{name}", {"u": 7.3, "enable": 1.0, "mode": 1.0}.get(name, 0.0))
    system.set_input("T.v", 0.0)
    asked = r"T \(Types3\.fmu\): fmi3DoStep asked to end the simulation \(terminateSimulation"
    with pytest.raises(SimulationError, match=asked):
        system.run(STEPS * DT)
    try:
        system.run(STEPS * DT)
    except SimulationError as error:
        result = error.result
    reference = fmpy.simulate_fmu(str(typed_fmus[3]), stop_time=STEPS * DT, output_interval=DT,
                                  start_values={"stop_count": 4, "u": 7.3}, output=["counter", "x"])
    assert result["T.counter"][-1] == 3 and reference["counter"][-1] == 4  # fmpy records the last step too
    assert np.array_equal(result["T.counter"], reference["counter"][:-1])
    assert np.allclose(result["T.x"], reference["x"][:-1], rtol=0, atol=1e-9)


def test_a_refused_typed_set_names_its_function(typed_fmus, isolated):
    """The model refuses a UInt16 input of 65535 (the bus's 70000, held in range): the run fails
    at once, naming the block and fmi3SetUInt16 among the typed calls of the step."""
    from quadcosim.orchestrator import SimulationError

    system = System(dt=DT)
    system.add(FMUBlock("T", model=typed_fmus[3], isolated=isolated))
    for name in TYPES3:
        system.set_input(f"T.{name}", 70000.0 if name == "u16_in" else 0.0)
    system.set_input("T.v", 0.0)
    with pytest.raises(SimulationError, match=r"^T \(Types3\.fmu\): fmi3SetUInt16 returned Error at t = 0 s"):
        system.run(10 * DT)


@pytest.fixture(scope="session")
def lying_fmus(tmp_path_factory):
    """The test models whose step returns -1 (no FMI status) from t = 0.1 s."""
    return {v: build(f"types{v}", tmp_path_factory.mktemp(f"lying{v}"), defines=("LYING_STEP",)) for v in (2, 3)}


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("master", ["chunk", "step"])
def test_a_step_that_returns_minus_one_fails_the_run(lying_fmus, version, master, isolated):
    """-1 is no FMI status: the run fails at the step that returned it, in both FMI versions,
    both masters, in process and isolated, and the record keeps every step before it."""
    from quadcosim.orchestrator import SimulationError

    system = System(dt=DT)
    block = system.add(FMUBlock("T", model=lying_fmus[version], isolated=isolated))
    for name in block.inputs:
        system.set_input(f"T.{name}", 1.0)
    with pytest.raises(SimulationError) as caught:
        system.run(0.3, master=master)
    message = str(caught.value)
    assert f"fmi{version}DoStep returned -1 (no FMI status: taken as a failure) at t = 0.1 s" in message, message
    result = caught.value.result
    assert len(result) == 101 and result.time[-1] == pytest.approx(0.1, abs=1e-12)
    assert result["T.x"][-1] > 0  # the steps before it ran: the integrator moved


def _moved_binary(source: Path, target: Path, rename: dict | None = None, machine: int | None = None):
    """A copy of an FMU with its binaries renamed (``{old: new}``), or its ELF machine changed."""
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if machine is not None and item.filename.endswith(".so"):
                data = data[:18] + machine.to_bytes(2, "little") + data[20:]
            zout.writestr((rename or {}).get(item.filename, item.filename), data)


@pytest.mark.parametrize("change, said", [
    ({"rename": {"binaries/x86_64-linux/Types3.so": "binaries/x86_64-windows/Types3.dll"}},
     "this FMU has no x86_64-linux binary (it has x86_64-windows): export it for Linux"),
    ({"rename": {"binaries/x86_64-linux/Types3.so": "binaries/aarch64-linux/Types3.so"}},
     "this FMU has no x86_64-linux binary (it has aarch64-linux): export it for Linux"),
    ({"machine": 183}, "its x86_64-linux binary is built for aarch64; this machine runs x86_64"),
], ids=["windows_only", "aarch64_folder", "aarch64_elf"])
def test_an_fmi3_fmu_without_a_binary_for_this_machine_is_refused(typed_fmus, tmp_path, capsys, change, said):
    """FMI 3.0 names its platform folders ``x86_64-linux``, ``x86_64-windows``, ``aarch64-linux``:
    the refusal (exit 2, metrics.json alone, ``refused``) names the folder it looked for and the
    ones it found."""
    import platform

    if platform.machine().lower() not in ("x86_64", "amd64"):
        pytest.skip("the refusals name an x86_64 machine")
    moved = tmp_path / "moved.fmu"
    _moved_binary(typed_fmus[3], moved, **change)
    assert main(["run", "open-loop", "--set", "duration=0.1", "--fmu", f"MotorMagnetics={moved}",
                 "--out", str(tmp_path / "x")]) == 2
    assert said in capsys.readouterr().err
    assert sorted(p.name for p in (tmp_path / "x").iterdir()) == ["metrics.json"]
    metrics = json.loads((tmp_path / "x" / "metrics.json").read_text())
    assert metrics["status"] == "refused" and said in metrics["error"] and metrics["samples"] == 0


def test_an_fmi3_fmu_that_crashes_in_its_worker_ends_the_run_with_its_record(tmp_path):
    """A segmentation fault in ``fmi3DoStep`` of an isolated FMI 3.0 FMU: the run fails naming the
    block, the FMU, fmi3DoStep and SIGSEGV, and keeps the 101 samples before it."""
    from quadcosim.orchestrator import SimulationError

    crashing = build("types3", tmp_path, defines=("CRASHING_STEP",))
    system = System(dt=DT)
    block = system.add(FMUBlock("T", model=crashing))  # a foreign FMU: isolated by default
    for name in block.inputs:
        system.set_input(f"T.{name}", 1.0)
    with pytest.raises(SimulationError) as caught:
        system.run(0.3)
    message = str(caught.value)
    assert message.startswith(f"T ({crashing}, run in its own process) at t = 0.1 s: Types3.fmu crashed in "
                              "fmi3DoStep: its process was killed by SIGSEGV"), message
    result = caught.value.result
    assert len(result) == 101 and result["T.steps"][-1] == 100
