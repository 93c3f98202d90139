"""Items 6, 7 and 15: values an FMU refuses at initialisation, a decimation beyond the run, and
malformed fault specifications are refused with exit 2 and a message naming the fix; a fault
without end is written as valid JSON."""

import json

import pytest
from conftest import SHORT_TP, metrics_of

from quadcosim.main import main as cli


@pytest.mark.parametrize("settings, words", [
    (["noise=on", "IMU.gyro_noise_density=-1"], ["IMU refused its parameters at initialisation",
                                                  "gyro_noise_density=-1.0", "must be non-negative",
                                                  "quadcosim list --parameters IMU"]),
    (["Quadrotor.m=-1"], ["Quadrotor refused its parameters", "m = -1 must be positive",
                          "quadcosim list --parameters Quadrotor"]),
])
def test_a_value_an_fmu_refuses_at_initialisation_exits_2_and_leaves_nothing(settings, words, tmp_path, capsys):
    out = tmp_path / "run"
    assert cli([*SHORT_TP, "--set", *settings, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    for word in words:
        assert word in err, err[-1500:]
    assert "Traceback" not in err
    assert not out.exists()  # the diagram drawn before the refusal is removed, and the folder the run made


def test_a_decimation_beyond_the_run_is_refused_and_one_up_to_it_completes(tmp_path, capsys):
    out = tmp_path / "run"
    assert cli([*SHORT_TP, "--decimation", "501", "--out", str(out)]) == 2
    assert ("--decimation 501 is more than the run's 500 steps (0.5 s every 0.001 s): it would record the first "
            "sample alone. Give at most --decimation 500") in capsys.readouterr().err
    assert not out.exists()
    assert cli([*SHORT_TP, "--decimation", "500", "--out", str(out)]) == 0
    metrics = metrics_of(out)
    assert metrics["status"] == "completed" and metrics["samples"] == 2


@pytest.mark.parametrize("fault, words", [
    ("IMU.omega_x:offset:a:b:c", "START 'a' is not a number (s)"),
    ("IMU.omega_x:offset:0:1:c", "VALUE 'c' is not a number (in the unit of the target"),
    ("IMU.omega_x:offset:0:x", "STOP 'x' is not a number (s; inf for no end)"),
    ("IMU.omega_x:offset:0:nan:1", "START must be a finite time (s) and STOP a time or inf"),
    ("IMU.omega_x:offset:inf:1:1", "START must be a finite time"),
    ("IMU.omega_x:offset:0", "write TARGET:KIND:START:STOP[:VALUE]"),
    ("IMU.omega_x:bogus:0:1:1", "unknown fault kind 'bogus'"),
])
def test_a_malformed_fault_names_the_field_and_the_form(fault, words, tmp_path, capsys):
    assert cli([*SHORT_TP, "--fault", fault, "--out", str(tmp_path / "run")]) == 2
    assert words in capsys.readouterr().err


def test_a_fault_without_end_is_written_as_valid_json(tmp_path):
    out = tmp_path / "run"
    assert cli(["run", "open-loop", "--set", "duration=0.2", "--fault", "IMU.omega_x:offset:0.1:inf:0.05",
                "--out", str(out)]) == 0
    text = (out / "metrics.json").read_text()
    metrics = json.loads(text, parse_constant=lambda c: pytest.fail(f"not JSON: {c}"))
    assert metrics["injected_faults"][0] | {"seed": 0} == {"target": "IMU.omega_x", "kind": "offset", "start": 0.1,
                                                           "stop": None, "value": 0.05, "seed": 0}
    assert "stop null: no end" in metrics["units"]["injected_faults"]
