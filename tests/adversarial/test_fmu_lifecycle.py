"""Calls FMI leaves undefined, answered with an error status rather than a crash: a second
fmi2FreeInstance, any call on a freed instance, any call on a handle the FMU never issued; and
InfraredSensor's GPS delay and window, which once overflowed an integer and slipped past the
limit of its heading history."""

import ctypes
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from quadcosim.fmus import MODELS  # noqa: E402
from raw_fmu import RawFMU  # noqa: E402

OK, ERROR = 0, 3


def calls_on(fmu: RawFMU) -> dict:
    """The status of one call of each kind on the FMU's present handle."""
    real = fmu.refs[next(iter(fmu.names["Real"].values()))]
    value = ctypes.c_double()
    kind = ctypes.c_int()
    return {
        "fmi2DoStep": fmu.do_step(0.0, 1e-3),
        "fmi2GetReal": fmu.get_real([real])[0],
        "fmi2SetReal": fmu.set_real([real], [0.5]),
        "fmi2GetInteger": fmu.get_integer([])[0],
        "fmi2SetBoolean": fmu.set_boolean([], []),
        "fmi2SetupExperiment": fmu.setup(0.0),
        "fmi2EnterInitializationMode": fmu.call("fmi2EnterInitializationMode"),
        "fmi2ExitInitializationMode": fmu.call("fmi2ExitInitializationMode"),
        "fmi2Terminate": fmu.call("fmi2Terminate"),
        "fmi2Reset": fmu.call("fmi2Reset"),
        "fmi2SetDebugLogging": fmu.call("fmi2SetDebugLogging", 1, 0, None),
        "fmi2GetStatus": fmu.call("fmi2GetStatus", 0, ctypes.byref(kind)),
        "fmi2GetRealStatus": fmu.call("fmi2GetRealStatus", 2, ctypes.byref(value)),
        "fmi2GetString": fmu.call("fmi2GetString", None, 0, None),
        "fmi2CancelStep": fmu.call("fmi2CancelStep"),
    }


def stepping(model: str) -> RawFMU:
    fmu = RawFMU(model)
    assert fmu.instantiate()
    assert fmu.initialize() == OK, fmu.messages()
    return fmu


@pytest.mark.parametrize("model", MODELS)
def test_every_call_on_a_freed_instance_returns_an_error_status(model):
    fmu = stepping(model)
    stale = fmu.component
    fmu.f["fmi2FreeInstance"](stale)
    fmu.component = stale  # the master kept the handle it freed
    statuses = calls_on(fmu)
    assert statuses == dict.fromkeys(statuses, ERROR)
    fmu.component = None


@pytest.mark.parametrize("model", MODELS)
def test_a_second_free_is_ignored_and_the_fmu_still_works(model):
    fmu = stepping(model)
    stale = fmu.component
    fmu.f["fmi2FreeInstance"](stale)
    fmu.f["fmi2FreeInstance"](stale)  # undefined in FMI 2.0; a crash before the live-instance check
    fresh = stepping(model)
    assert fresh.do_step(0.0, 1e-3) == OK
    fmu.component = stale
    assert fmu.do_step(0.0, 1e-3) == ERROR
    fmu.component = None
    fresh.free()


@pytest.mark.parametrize("model", MODELS)
def test_a_handle_never_issued_is_refused(model):
    fmu = RawFMU(model)
    garbage = ctypes.create_string_buffer(4096)  # readable memory that is no instance
    fmu.component = ctypes.addressof(garbage)
    statuses = calls_on(fmu)
    assert statuses == dict.fromkeys(statuses, ERROR)
    fmu.f["fmi2FreeInstance"](fmu.component)
    fmu.component = None


@pytest.mark.parametrize("model", MODELS)
def test_a_stale_handle_keeps_failing_while_new_instances_come_and_go(model):
    fmu = stepping(model)
    stale = fmu.component
    fmu.f["fmi2FreeInstance"](stale)
    others = [stepping(model) for _ in range(100)]  # slots are taken while the stale one waits
    fmu.component = stale
    assert fmu.do_step(0.0, 1e-3) == ERROR
    fmu.component = None
    assert all(other.do_step(0.0, 1e-3) == OK for other in others)
    for other in others:
        other.free()


@pytest.mark.parametrize("parameter", ["gps_delay", "gps_window"])
@pytest.mark.parametrize("seconds", [1e8, 1e12, 2.0**31 / 20])
def test_infrared_gps_delay_or_window_beyond_the_history_is_refused_not_wrapped(parameter, seconds):
    fmu = RawFMU("InfraredSensor")
    assert fmu.instantiate()
    status = fmu.initialize(parameters={parameter: seconds})
    assert status == ERROR, f"{parameter} = {seconds:g} s accepted; gps_valid = {fmu.get_real([fmu.refs['gps_valid']])}"
    assert "more than the 4095 kept" in fmu.messages()
    fmu.free()


def test_the_long_fuzz_reports_calls_on_freed_instances_and_double_frees():
    import json
    import subprocess

    done = subprocess.run([sys.executable, "-m", "quadcosim.benchmarks.fuzz", "--calls", "600",
                           "--models", "Quadrotor", "IMU",
                           "--json"], capture_output=True, text=True, timeout=300,
                          cwd=Path(__file__).resolve().parents[2])
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    report = json.loads(done.stdout)
    assert report["failed"] == []
    assert report["totals"]["calls"] >= 1200
    assert report["totals"]["calls_after_free"] > 0 and report["totals"]["double_frees"] > 0
