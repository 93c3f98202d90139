"""The pytest plugin's edges: Ctrl-C ends a session as pytest's own KeyboardInterrupt does, the
assertion helpers refuse a bound that cannot fail (NaN, negative, a string, an unknown axis) and
fail on NaN data, a filter that estimates no bias is refused, and ``run_scenario`` checks its
arguments."""

import subprocess
import sys

import numpy as np
import pytest
from quadcosim.scenarios.testing.assertions import (
    assert_attitude_error,
    assert_bias_converges,
    assert_bounds,
    assert_runs_close,
    assert_step,
    assert_tracking,
)
from test_pytest_plugin import attitude, record, second_order

LONG_TESTS = '''
import os
import signal

from quadcosim.estimators.contract import AttitudeEstimator


class CtrlC(AttitudeEstimator):
    """Holds the attitude; the 200th sample is met by a Ctrl-C, as a user's key would be."""

    def update(self, acc, gyro, mag):
        self.count = getattr(self, "count", 0) + 1
        if self.count == 200:
            os.kill(os.getpid(), signal.SIGINT)


def test_first(run_scenario):
    run_scenario("tp", duration=5, estimator=CtrlC)


def test_second(run_scenario):
    run_scenario("tp", duration=0.2)


def test_third():
    pass
'''


def test_ctrl_c_ends_the_session_with_exit_2(tmp_path):
    """Ctrl-C 0.2 s into the first of three tests' runs: the session stops there (pytest's exit 2,
    "KeyboardInterrupt"), the other tests are not run. Before: "1 failed, 2 passed", exit 1."""
    (tmp_path / "test_long.py").write_text(LONG_TESTS)
    try:
        done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
                               "test_long.py"], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    except subprocess.TimeoutExpired:
        pytest.fail("the session did not end")
    output = done.stdout + done.stderr
    assert done.returncode == 2, output[-3000:]
    assert "KeyboardInterrupt" in output and "test_long.py::test_first: " in output, output[-3000:]
    assert "passed" not in output and "failed" not in output, output[-3000:]


@pytest.mark.parametrize("check", [
    lambda: assert_attitude_error(attitude(0.3, 1.5), below_deg=float("nan")),
    lambda: assert_runs_close(record({"y": np.sin}), record({"y": lambda t: np.sin(t) + 0.141}), atol=float("nan")),
    lambda: assert_bounds(record({"y": np.sin}), "y", lower=float("nan"), upper=float("nan")),
    lambda: assert_tracking(record({"y": lambda t: 5.05 + 0 * t}), "y", 0.0, within=float("nan")),
    lambda: assert_step(record({"y": second_order(0.25, 10.0)}, duration=3.0), "y", step_s=0.5, final=2.0,
                        overshoot_below_percent=float("nan")),
    lambda: assert_bias_converges(_bias_run(), tolerance=float("nan")),
], ids=["attitude", "runs_close", "bounds", "tracking", "step", "bias"])
def test_a_nan_bound_is_refused(check):
    with pytest.raises(ValueError, match="=nan is not a bound: no comparison with NaN fails"):
        check()


def test_a_nan_signal_fails_rather_than_passes():
    nan = record({"y": lambda t: np.full_like(t, np.nan)})
    with pytest.raises(AssertionError, match=r"y is NaN at t = 0\.0000 s \(2001 of 2001 samples checked\)"):
        assert_bounds(nan, "y", lower=-1.0, upper=1.0)
    with pytest.raises(AssertionError, match="is NaN at t"):
        assert_tracking(nan, "y", 0.0, within=1.0)


def test_negative_tolerances_strings_and_bad_axes_are_refused_clearly():
    run = attitude(0.3, 1.5)
    with pytest.raises(ValueError, match="below_deg=-1 is negative: it bounds a magnitude"):
        assert_attitude_error(run, below_deg=-1)
    with pytest.raises(ValueError, match="atol=-1 is negative"):
        assert_runs_close(run, run, atol=-1)
    with pytest.raises(TypeError, match=r"below_deg='0\.5 deg' must be a number \(a str was given\)"):
        assert_attitude_error(run, below_deg="0.5 deg")
    with pytest.raises(ValueError, match=r"axes=\('Roll',\): 'Roll'; give axes among 'roll', 'pitch', 'yaw'"):
        assert_attitude_error(run, below_deg=1.0, axes=("Roll",))
    assert assert_attitude_error(run, below_deg=0.31, axes="pitch") == pytest.approx(0.3)
    with pytest.raises(ValueError, match="lower=1 is above upper=0"):
        assert_bounds(run, "Quadrotor.theta2", lower=1, upper=0)


def _bias_run(estimated: bool = True):
    truth = (0.02, -0.01, 0.015)
    return record({**{f"IMU.gyro_bias_{a}": (lambda t, b=b: b + 0.0 * t) for a, b in zip("xyz", truth, strict=True)},
                   **{f"Quaternion_estim.b_est_{a}": (lambda t, b=b: estimated * b * (1 - np.exp(-t)))
                      for a, b in zip("xyz", truth, strict=True)}}, duration=4.0)


def test_bias_convergence_refuses_a_filter_without_a_bias_estimate(run_scenario):
    """tp's explicit filter with kI = 0 holds b_est at 0: before, with no true bias, the check
    passed vacuously."""
    result = run_scenario("tp", duration=0.5, estimator="explicit", kI=0.0)
    with pytest.raises(ValueError, match=r"Quaternion_estim\.b_est holds \[0\.0, 0\.0, 0\.0\] at every sample: "
                                         "this filter estimates no gyro bias"):
        assert_bias_converges(result)
    assert assert_bias_converges(_bias_run()) == pytest.approx(np.log(0.02 / 1e-3), abs=1e-3)


@pytest.mark.parametrize(("arguments", "said"), [
    ({"duration": True}, "duration=True must be a positive number of seconds"),
    ({"duration": float("nan")}, "duration=nan must be a positive number of seconds"),
    ({"k": None}, "option k=None is not a valid float: give one value, such as 0.05"),
    ({"k": [1, 2]}, r"option k=\[1, 2\] is not a valid float: give one value"),
    ({"name": "tpp"}, r"run_scenario: no scenario 'tpp'\. Did you mean tp\? Scenarios: .*gain-study"),
])
def test_run_scenario_checks_its_arguments(run_scenario, arguments, said):
    arguments = {"name": "tp"} | arguments
    with pytest.raises(ValueError, match=said):
        run_scenario(**arguments)


def test_run_scenario_takes_one_signal_by_name_and_knows_gain_study(run_scenario):
    result = run_scenario("tp", duration=0.2, record="Quadrotor.q")
    assert result.names == ["Quadrotor.q0", "Quadrotor.q1", "Quadrotor.q2", "Quadrotor.q3"]
    assert np.allclose(np.linalg.norm(result["Quadrotor.q"], axis=1), 1.0, atol=1e-9)
    from quadcosim import scenarios

    assert "gain-study" in scenarios.names()  # registered by the plugin's studies entry point
