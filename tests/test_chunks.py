"""The chunk runner (compiled loop) gives, bit for bit, what the per-step master gives: every
scenario, multirate blocks, decimation, faults, Python-only blocks; and a failure inside a chunk
is reported at the same step, time and block, with the same record kept."""

import numpy as np
import pytest
from numba import carray, cfunc
from quadcosim.orchestrator import Block, FMUBlock, SimulationError, System, Table
from quadcosim.orchestrator.blocks import COMPILED_SIGNATURE, CompiledStep
from quadcosim.orchestrator.chunks import CHUNK_STEPS
from quadcosim.orchestrator.faults import Fault
from quadcosim.scenarios.testing.assertions import assert_runs_close

from quadcosim import (
    scenarios,
    studies,  # noqa: F401  (registers gain-study in the scenarios' catalogue)
)


def both(build, duration, **run):
    """Results of the system from ``build()`` run per step and by chunks."""
    return [build().run(duration, master=master, **run) for master in ("step", "chunk")]


def assert_identical(step, chunk):
    assert step.names == chunk.names and len(step) == len(chunk) > 1
    assert_runs_close(step, chunk, equal_nan=True)  # same times, every signal equal bit for bit
    assert step.error == chunk.error


@pytest.mark.parametrize("name", list(scenarios.registry()))
def test_every_scenario_is_identical_by_chunks(name):
    scenario = scenarios.get(name)
    options = scenario.parse({})  # the defaults, run for a short time
    duration = min(0.3, scenario.duration(options) if scenario.duration else options["duration"])
    assert_identical(*both(lambda: scenario.build(options), duration, record=scenario.extra.get("record")))


@pytest.mark.parametrize("settings, run", [
    ({"estimator": "explicit", "feedback": "estimate", "noise": True, "bias": True}, {}),
    ({"estimator": "passive", "ry": "triad", "corrections": "on", "imu_rate": 250.0}, {"decimation": 3}),
    ({"estimator": "passive", "feedback": "estimate", "flight": "tilt"}, {"decimation": 7}),
    ({"estimator": "madgwick", "feedback": "estimate", "noise": True}, {}),  # a Python-only block
    ({"estimator": "linear", "magnetic": True, "compensation": "static"}, {"record": ["Quadrotor.q", "IMU.acc"]}),
])
def test_closed_loop_variants_are_identical_by_chunks(settings, run):
    from quadcosim.scenarios import tp

    options = tp.SCENARIO.parse({"duration": 0.6} | settings)
    assert_identical(*both(lambda: tp.build(options), 0.6, **run))


def test_faults_are_exact_by_chunks():
    from quadcosim.scenarios import tp

    def build():
        system = tp.build(tp.SCENARIO.parse({"estimator": "explicit", "feedback": "estimate"}))
        system.inject(Fault("Quaternion_estim.gyro_x", "noise", 0.1, 0.3, 0.05, seed=3))
        system.inject(Fault("Quaternion_estim.acc_z", "stuck", 0.2, 0.25))
        system.inject(Fault("MotorMagnetics.c2", "offset", 0.15, 0.4, 0.02))
        system.inject(Fault("Controller.u_batt", "dropout", 0.3, 0.31))
        return system

    step, chunk = both(build, 0.5, decimation=2)
    assert_identical(step, chunk)
    clean = tp.build(tp.SCENARIO.parse({"estimator": "explicit", "feedback": "estimate"})).run(0.5, decimation=2)
    assert not np.array_equal(clean["Quaternion_estim.q_est1"], chunk["Quaternion_estim.q_est1"])  # they act


def test_an_fmu_failure_inside_a_chunk_names_the_step_block_and_keeps_the_record():
    def build():
        system = System()
        system.add(Table("Command", ["c1", "c2", "c3", "c4"], [[0.8] * 4]))
        system.add(FMUBlock("MotorMagnetics", parameters={"capacity": 300.0, "soc0": 0.5}))
        system.connect("Command.c", "MotorMagnetics.c")
        return system

    errors = []
    for master in ("step", "chunk"):
        with pytest.raises(SimulationError) as error:
            build().run(60.0, master=master)
        errors.append(error.value)
    step, chunk = errors
    assert str(step) == str(chunk)
    assert "MotorMagnetics: fmi2DoStep returned Error at t = " in str(chunk) and "battery is empty" in str(chunk)
    assert_identical(step.result, chunk.result)
    failed_at = float(str(chunk).split("Error at t = ")[1].split(" s")[0])
    assert len(chunk.result) == round(failed_at / 1e-3) + 1 > CHUNK_STEPS  # in a later chunk, the record kept


@cfunc(COMPILED_SIGNATURE, error_model="numpy")
def _ratio(t, u, y, data):
    inputs, outputs = carray(u, 2), carray(y, 1)
    outputs[0] = inputs[0] / inputs[1]  # 0 / 0 is NaN (numpy's error model)
    return 0


class Ratio(Block):
    """``y = a / b``, with a compiled step."""

    inputs, outputs = ("a", "b"), ("y",)

    def step(self, t, u, y):
        with np.errstate(invalid="ignore", divide="ignore"):
            y[0] = np.divide(u[0], u[1])

    def compiled(self):
        return CompiledStep(_ratio.address, np.zeros(2), np.zeros(1), _ratio)


def test_a_nan_made_by_a_compiled_block_inside_a_chunk_names_it_and_keeps_the_record():
    def build():
        system = System()
        system.add(Table("Source", ["a", "b"], [[1.0, 2.0]] * 250 + [[0.0, 0.0]]))
        system.add(Ratio("Ratio"))
        system.connect("Source.a", "Ratio.a")
        system.connect("Source.b", "Ratio.b")
        return system

    errors = []
    for master in ("step", "chunk"):
        with pytest.raises(SimulationError, match=r"Ratio.y became nan at t = 0.25 s") as error:
            build().run(1.0, master=master)
        errors.append(error.value)
    assert str(errors[0]) == str(errors[1])
    assert_identical(errors[0].result, errors[1].result)
    assert len(errors[1].result) == 251 and errors[1].result["Ratio.y"][249] == 0.5


def test_callable_tables_are_refilled_between_chunks_at_their_own_rate():
    def build():
        system = System()
        system.add(Table("Slow", ["a"], lambda t: np.sin(7.0 * t)[:, None], period=3, chunk=50))
        system.add(Table("Fast", ["b", "c"], lambda t: np.column_stack([t, np.cos(t)]), chunk=1000))
        system.add(Ratio("Ratio"))
        system.connect("Slow.a", "Ratio.a")
        system.connect("Fast.c", "Ratio.b")
        return system

    step, chunk = both(build, 9.0, decimation=4)  # over two chunks of steps, many rows of tables
    assert_identical(step, chunk)
    assert chunk["Fast.b"][-1] == 9.0 and len(np.unique(chunk["Slow.a"])) > 700


def test_an_unknown_master_is_refused():
    system = System()
    system.add(Table("Source", ["a"], [[1.0]]))
    with pytest.raises(ValueError, match="master = 'fast' must be 'chunk' or 'step'"):
        system.run(0.1, master="fast")


def test_the_cached_compiled_steps_follow_the_files_they_call_into():
    """numba reuses a cached function while its own file is unchanged; the compiled steps hold a
    fingerprint of the files they call into (estimators/core.py and those it compiles from, ...) in their cache key."""
    from quadcosim.estimators import core, filters, quaternions
    from quadcosim.flight import controller, mixer
    from quadcosim.fmus import vehicle
    from quadcosim.orchestrator.blocks import source_fingerprint

    for function, modules in ((filters._compiled_step(), (core, *core.SOURCES)),
                              (controller._compiled_step(), (quaternions, mixer, vehicle))):
        closure = [cell.cell_contents for cell in function._pyfunc.__closure__]
        assert source_fingerprint(*modules) in closure
    assert source_fingerprint(core) != source_fingerprint(core, mixer)
