"""fmi2Reset gives back a fresh instance, bit for bit: what lets a sweep worker reuse its FMU
instances from member to member (quadcosim.orchestrator.pool) without changing any trajectory."""

import math

import numpy as np
import pytest
from quadcosim.fmus import MODELS
from quadcosim.fmus.models import sensor
from quadcosim.orchestrator import pool
from quadcosim.orchestrator.fmu import FMUError, FMUInstance
from quadcosim.scenarios.testing.assertions import assert_runs_close

from quadcosim import scenarios

DT = 1e-3


def reset_parameters(model: str) -> tuple[dict, dict]:
    """The model's ``RESET_PARAMETERS`` (its folder's ``__init__.py``): those of a fresh run and of an
    earlier one, off their defaults, so that a reset that kept the earlier run's values would show."""
    return sensor(model).check("RESET_PARAMETERS")


def inputs_at(fmu: FMUInstance, k: int, phase: float) -> np.ndarray:
    """Inputs near their start values, varying with the step k (attitudes held: the IMU takes a
    unit quaternion, the infrared sensor a bank angle short of 90 deg)."""
    starts = np.array([float(fmu.variables[name].start or 0.0) for name in fmu.inputs])
    wobble = np.array([0.0 if name.startswith("q") else 0.01 * math.sin(0.05 * k + i + phase)
                       for i, name in enumerate(fmu.inputs)])
    return starts + wobble


def trajectory(fmu: FMUInstance, steps: int, phase: float = 0.0) -> np.ndarray:
    rows = []
    for k in range(steps):
        fmu.set(fmu.inputs, inputs_at(fmu, k, phase))
        rows.append(fmu.get(fmu.outputs))
        fmu.step(k * DT, DT)
    rows.append(fmu.get(fmu.outputs))
    return np.array(rows)


@pytest.mark.parametrize("model", MODELS)
def test_a_reset_instance_steps_exactly_as_a_fresh_one(model):
    wanted, other = reset_parameters(model)
    fresh = FMUInstance(model, wanted)
    expected = trajectory(fresh, 300)
    fresh.close()

    reused = FMUInstance(model, other)
    trajectory(reused, 170, phase=1.0)  # an earlier run, with other parameters and inputs
    reused.reset(wanted)
    again = trajectory(reused, 300)
    reused.close()
    assert again.shape == expected.shape
    assert np.array_equal(again, expected), f"{model}: largest difference {np.abs(again - expected).max()}"


@pytest.mark.parametrize("model", MODELS)
def test_a_reset_after_an_error_state_gives_a_fresh_instance(model):
    wanted, _ = reset_parameters(model)
    fresh = FMUInstance(model, wanted)
    expected = trajectory(fresh, 50)
    fresh.close()
    broken = FMUInstance(model, wanted)
    trajectory(broken, 20, phase=2.0)
    with pytest.raises(FMUError):
        broken.set(broken.inputs[:1], [math.nan])  # the FMU goes to its error state
    with pytest.raises(FMUError):
        broken.step(20 * DT, DT)
    broken.reset(wanted)
    assert np.array_equal(trajectory(broken, 50), expected)
    broken.close()


def test_a_sweep_member_on_reused_instances_equals_one_on_fresh_instances():
    options = {"duration": 1.0, "noise": True, "bias": True, "feedback": "estimate", "estimator": "explicit"}
    fresh, fresh_metrics = scenarios.run("tp", options | {"seed": 4})
    previous = pool.reuse(True)
    try:
        scenarios.run("tp", options | {"seed": 9, "flight": "nonstationary"})  # leaves its instances idle
        assert pool.idle_count() >= 3
        reused, reused_metrics = scenarios.run("tp", options | {"seed": 4})
    finally:
        pool.reuse(previous)
    assert pool.idle_count() == 0
    assert fresh.names == reused.names
    assert_runs_close(fresh, reused)  # bit for bit
    assert {k: v for k, v in fresh_metrics.items() if k != "real_time_factor"} == \
        {k: v for k, v in reused_metrics.items() if k != "real_time_factor"}
