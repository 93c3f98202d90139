"""The FMUs under hostile but honest use: each bad call gets an FMI error status and a message
naming the problem; nothing crashes, hangs or returns OK with garbage. Then a fuzz of every FMU
and a leak check over many instantiate/step/free cycles."""

import ctypes
import json
import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from quadcosim.fmus import MODELS
from raw_fmu import RawFMU

OK, ERROR = 0, 3
HERE = Path(__file__).resolve().parent


def stepping(model, parameters=None):
    fmu = RawFMU(model)
    assert fmu.instantiate()
    assert fmu.initialize(parameters=parameters) == OK, fmu.messages()
    return fmu


@pytest.mark.parametrize("model", MODELS)
def test_value_references_beyond_the_table_are_refused_not_a_segfault(model):
    fmu = stepping(model)
    for reference in (2**31, 2**32 - 1, fmu.count["Real"]):
        assert fmu.set_real([reference], [1.0]) == ERROR
        assert f"fmi2SetReal: unknown value reference {reference}" in fmu.messages()
        assert fmu.get_real([reference])[0] == ERROR
        assert f"fmi2GetReal: unknown value reference {reference}: this model has {fmu.count['Real']} Real" \
            in fmu.messages()
    assert fmu.set_integer([2**31], [1]) == ERROR
    assert "fmi2SetInteger: unknown value reference 2147483648" in fmu.messages()
    fmu.free()


@pytest.mark.parametrize("model", MODELS)
def test_non_finite_times_are_refused(model):
    fmu = RawFMU(model)
    fmu.instantiate()
    assert fmu.setup(math.nan) == ERROR
    assert "fmi2SetupExperiment: startTime = nan is not a finite number" in fmu.messages()
    fmu = stepping(model)
    for t in (math.nan, math.inf, 1e308):
        assert fmu.do_step(t, 1e-3 if t != 1e308 else 1e308) == ERROR
        assert "is not a finite time" in fmu.messages() or "differs from the model time" in fmu.messages()
    assert "fmi2DoStep: communication point nan (step 0.001) is not a finite time" in fmu.messages()
    assert fmu.time() == 0.0  # a refused step does not advance the time
    assert fmu.do_step(0.0, 1e-3) == OK
    fmu.free()


@pytest.mark.parametrize("model, parameter, value, step, words", [
    ("MotorMagnetics", None, None, 1e12, "step of 1e+12 s at t = 0 would need 4e+15 sub-steps of sub_step = 0.00025 s"),
    ("IMU", None, None, 1e12, "would need 1e+15 samples at sample_rate = 1000 Hz"),
    ("IMU", "sample_rate", 1e12, 1e-3, "would need 1e+09 samples at sample_rate = 1e+12 Hz"),
    ("MotorMagnetics", "sub_step", 1e-11, 1e-3, "would need 1e+08 sub-steps of sub_step = 1e-11 s"),
    ("Quadrotor", "sub_step", 1e-11, 1e-3, "would need 1e+08 sub-steps of sub_step = 1e-11 s"),
    ("Quadrotor", "sub_step", 1e-300, 1e-3, "would need 1e+297 sub-steps of sub_step = 1e-300 s"),
    # more sub-steps than an int holds
    ("Quadrotor", "sub_step", 1e-4, 1e6, "would need 1e+10 sub-steps"),
])
def test_steps_needing_too_much_work_are_refused_at_once(model, parameter, value, step, words):
    fmu = stepping(model, {parameter: value} if parameter else None)
    start = time.thread_time()  # CPU time: a busy machine's preemptions do not count
    assert fmu.do_step(0.0, step) == ERROR
    elapsed = time.thread_time() - start
    assert words in fmu.messages()
    assert "more than the 200000 allowed per step" in fmu.messages()
    assert elapsed < 0.01
    fmu.free()


def test_the_largest_step_allowed_runs():
    fmu = stepping("MotorMagnetics")
    start = time.perf_counter()
    assert fmu.do_step(0.0, 0.99 * 200000 * 2.5e-4) == OK, fmu.messages()
    print(f"MotorMagnetics: a step of 200000 sub-steps takes {time.perf_counter() - start:.3f} s")
    fmu.free()


def test_a_state_becoming_non_finite_fails_the_step_itself():
    fmu = stepping("Quadrotor")
    refs = [fmu.refs[f"omega_r{n}"] for n in range(1, 5)]
    assert fmu.set_real(refs, [1e200] * 4) == OK
    assert fmu.do_step(0.0, 1e-3) == ERROR
    assert "fmi2DoStep: " in fmu.messages() and "became" in fmu.messages()
    assert "in the step from t = 0 to 0.001" in fmu.messages()
    assert fmu.get_real([fmu.refs["p_z"]])[0] == ERROR  # the FMU is in its error state
    assert "the FMU is in the error state" in fmu.messages()
    fmu.free()


def test_an_empty_battery_fails_the_step_and_the_charge_never_goes_negative():
    fmu = stepping("MotorMagnetics", {"capacity": 20.0, "soc0": 0.5})  # 10 A.s of charge
    commands = [fmu.refs[f"c{n}"] for n in range(1, 5)]
    soc, volts = fmu.refs["soc"], fmu.refs["u_batt"]
    fmu.set_real(commands, [0.8] * 4)
    charges, status, k = [], OK, 0
    while status == OK and k < 10000:
        status = fmu.do_step(k * 1e-3, 1e-3)
        if status == OK:
            _, (charge, voltage) = fmu.get_real([soc, volts])
            charges.append(charge)
            assert voltage > 0
        k += 1
    assert status == ERROR and 0.0 <= min(charges) < 0.01
    message = fmu.messages()
    empty = float(re.search(r"fmi2DoStep: the battery is empty at t = (\S+) s", message).group(1))
    assert (k - 1) * 1e-3 < empty <= k * 1e-3 + 1e-12  # within the failed step, to the sub-step
    assert "raise capacity (20 A.s) or soc0 (0.5), or shorten the run" in message
    print(f"battery of 20 A.s at 50 % empty after {k} ms: {message.splitlines()[-1]}")
    fmu.free()


IMU_INPUTS = {"omega_x": 0.0, "omega_y": 0.0, "omega_z": 0.0, "f_x": 0.0, "f_y": 0.0, "f_z": -9.81,
              "b_d_x": 0.0, "b_d_y": 0.0, "b_d_z": 0.0}


@pytest.mark.parametrize("q, accepted", [
    ((1.0005, 0.0, 0.0, 0.0), True),  # rounding of a recorded attitude: normalised
    ((0.6 * 0.9995, 0.8 * 0.9995, 0.0, 0.0), True),
    ((10.0, 10.0, 0.0, 0.0), False),  # R(q) would not be a rotation (R_reel_11 = -399 before)
    ((0.0, 0.0, 0.0, 0.0), False),
])
def test_the_imu_normalises_a_nearly_unit_quaternion_and_refuses_others(q, accepted):
    fmu = stepping("IMU", {"noise_enabled": 0})
    names = ["q0", "q1", "q2", "q3", *IMU_INPUTS]
    assert fmu.set_real([fmu.refs[n] for n in names], [*q, *IMU_INPUTS.values()]) == OK
    status = fmu.do_step(0.0, 1e-3)
    if accepted:
        assert status == OK, fmu.messages()
        _, r = fmu.get_real([fmu.refs[f"R_reel_{i}{j}"] for i in (1, 2, 3) for j in (1, 2, 3)])
        r = np.reshape(r, (3, 3))
        assert np.abs(r @ r.T - np.eye(3)).max() < 1e-15
        unit = np.array(q) / np.linalg.norm(q)
        assert r[0, 0] == pytest.approx(1 - 2 * (unit[2] ** 2 + unit[3] ** 2), abs=1e-15)
    else:
        assert status == ERROR
        assert "the IMU takes a unit quaternion and normalises one only within 0.001 of norm 1" in fmu.messages()
    fmu.free()


def test_wrong_state_messages_name_the_states():
    fmu = RawFMU("IMU")
    fmu.instantiate()
    assert fmu.do_step(0.0, 1e-3) == ERROR
    assert "fmi2DoStep: not allowed: the FMU is instantiated (allowed only when it is in step mode)" \
        in fmu.messages()
    fmu.initialize()
    assert fmu.call("fmi2EnterInitializationMode") == ERROR
    assert "the FMU is in step mode (allowed only when it is instantiated)" in fmu.messages()
    assert "mode 2" not in fmu.messages()
    fmu.free()


FUZZ_CALLS = 10_000


@pytest.mark.slow
@pytest.mark.parametrize("model", MODELS)
def test_fuzz(model, tmp_path):
    """Random calls in random order, run in a child process so that a crash is a failure with
    the call that caused it, not the end of the test session."""
    log = tmp_path / "calls.log"
    done = subprocess.run([sys.executable, str(HERE / "fuzz_fmu.py"), model, str(FUZZ_CALLS), str(log)],
                          capture_output=True, text=True, timeout=300, env=os.environ | {"PYTHONHASHSEED": "0"})
    last = log.read_text().splitlines()[-1:] if log.exists() else []
    assert done.returncode == 0, (f"fuzzing {model} ended with code {done.returncode} at call {last}\n"
                                  f"{done.stderr[-3000:]}")
    summary = json.loads(done.stdout.splitlines()[-1])
    print(f"{model}: {summary['calls']} calls in {summary['sessions']} sessions, statuses {summary['statuses']}, "
          f"slowest {summary['slowest_call_cpu_s'] * 1e3:.1f} ms of CPU ({summary['slowest_call']}), "
          f"{summary['slowest_call_wall_s'] * 1e3:.1f} ms of wall time")
    assert summary["calls"] >= FUZZ_CALLS
    assert summary["statuses"].get("0", 0) > 0.2 * FUZZ_CALLS  # the fuzz gets past the first error
    assert summary["slowest_call_cpu_s"] < 1.0


class _MallocInfo(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in
                ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks",
                 "keepcost")]


_LIBC = ctypes.CDLL(None)
if hasattr(_LIBC, "mallinfo2"):
    _LIBC.mallinfo2.restype = _MallocInfo


def allocated_bytes() -> int:
    """Bytes the C allocator has handed out and not had back (glibc's ``mallinfo2``): unlike the
    resident size, it moves by the bytes of every block an FMU forgets to free."""
    if not hasattr(_LIBC, "mallinfo2"):
        pytest.skip("needs glibc's mallinfo2 (glibc 2.33 or later) to count allocated bytes")
    info = _LIBC.mallinfo2()
    return info.uordblks + info.hblkhd  # the heap's blocks in use and the mmapped ones


@pytest.mark.parametrize("model", MODELS)
def test_instantiate_step_free_cycles_do_not_leak(model):
    fmu = RawFMU(model)
    inputs = [v.valueReference for v in fmu.description.modelVariables if v.causality == "input"]

    def cycle():
        assert fmu.instantiate()
        assert fmu.initialize() == OK
        fmu.set_real(inputs, [0.5] * len(inputs))
        for k in range(10):
            assert fmu.do_step(k * 1e-3, 1e-3) == OK
        fmu.get_real(fmu.outputs)
        fmu.free()

    for _ in range(300):  # past the 256 freed slots the FMU keeps in quarantine, and the logger's buffers
        cycle()
    before = allocated_bytes()
    for _ in range(1000):
        cycle()
    growth = allocated_bytes() - before
    print(f"{model}: allocated memory grew by {growth / 1024:.1f} KiB over 1000 cycles")
    assert growth < 8 * 1024  # measured 0; any block leaked each cycle (32 bytes of heap at least) fails
