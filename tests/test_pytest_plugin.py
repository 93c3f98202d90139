"""The pytest plugin (quadcosim.scenarios.testing): its helpers' checks and failure messages, the guide's
example run as written, and a test file outside the checkout run by the installed package."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from quadcosim.orchestrator import Result
from quadcosim.scenarios.testing import SEED_LIMIT, seed_of
from quadcosim.scenarios.testing.assertions import (
    assert_attitude_error,
    assert_bias_converges,
    assert_bounds,
    assert_runs_close,
    assert_step,
    assert_tracking,
    step_response,
)

EXAMPLE = Path(__file__).resolve().parents[1] / "docs" / "guides" / "examples" / "test_my_work.py"
DT = 1e-3  # s


def record(columns: dict, seed: int = 7, duration: float = 2.0) -> Result:
    """A result of ``columns`` (name -> function of time) sampled every ms, as run by test seed ``seed``."""
    time = np.arange(0.0, duration + DT / 2, DT)
    names = list(columns)
    data = np.column_stack([np.broadcast_to(columns[n](time), time.shape) for n in names])
    return Result(time, names, data, meta={"test": {"seed": seed, "node": "test_x.py::test_y"}})


def attitude(error_deg: float, at: float) -> Result:
    """Estimate equal to the truth but for a pitch error of ``error_deg`` at time ``at``."""
    def theta_est2(t):
        return 0.1 + np.radians(error_deg) * (np.abs(t - at) < DT / 2)
    return record({"Quadrotor.theta1": lambda t: 0.0 * t, "Quadrotor.theta2": lambda t: 0.1 + 0.0 * t,
                   "Quadrotor.theta3": lambda t: 3.1 + 0.0 * t, "Quaternion_estim.theta_est1": lambda t: 0.0 * t,
                   "Quaternion_estim.theta_est2": theta_est2,
                   "Quaternion_estim.theta_est3": lambda t: 3.1 - 2 * np.pi + 0.0 * t})  # yaw wraps: no error


def test_attitude_error_names_the_worst_sample_and_the_seed():
    assert assert_attitude_error(attitude(0.3, 1.5), below_deg=0.31, after_s=1.0) == pytest.approx(0.3)
    assert assert_attitude_error(attitude(0.3, 0.5), below_deg=0.01, after_s=1.0) < 1e-9  # before after_s
    with pytest.raises(AssertionError, match=r"pitch estimate off the truth by 0\.3 deg at t = 1\.5000 s, above the "
                                             r"bound 0\.29 deg .*; seed 7 \(test test_x\.py::test_y\)"):
        assert_attitude_error(attitude(0.3, 1.5), below_deg=0.29, after_s=1.0)


def test_tracking_and_bounds_name_the_worst_sample():
    run = record({"Quadrotor.theta2": lambda t: 0.05 * np.exp(-t), "Controller.theta_d2": lambda t: 0.0 * t,
                  "Controller.c": lambda t: np.column_stack([0.45 + 0.01 * np.sin(t), 0.45 + 0.0 * t])[:, 0]})
    worst = 0.05 * np.exp(-1.0)
    assert assert_tracking(run, "Quadrotor.theta2", "Controller.theta_d2", within=1.001 * worst, after_s=1.0) \
        == pytest.approx(worst, rel=1e-12)
    with pytest.raises(AssertionError, match=r"Quadrotor\.theta2 = 0\.01839\d* at t = 1\.0000 s against the setpoint "
                                             r"0 = 0: off by 0\.01839, beyond the bound 0\.01 .*seed 7"):
        assert_tracking(run, "Quadrotor.theta2", 0.0, within=0.01, after_s=1.0)
    assert assert_bounds(run, "Controller.c", 0.44, 0.46) == pytest.approx((0.45, 0.45 + 0.01 * np.sin(1.571)),
                                                                          abs=1e-6)
    with pytest.raises(AssertionError, match=r"Controller\.c = 0\.46 at t = 1\.5710 s, above the upper bound 0\.459 "
                                             r".*seed 7"):
        assert_bounds(run, "Controller.c", upper=0.459)
    with pytest.raises(AssertionError, match=r"speed = 1\.2 at t = 0\.0000 s, below the lower bound 1\.25"):
        assert_bounds(run, ("speed", 1.2 + run.time), lower=1.25)


def second_order(zeta: float, omega: float, step_s: float = 0.5):
    """Unit step at ``step_s`` of ``omega^2 / (s^2 + 2 zeta omega s + omega^2)``, from 1 to 2."""
    def response(t):
        tau = np.clip(t - step_s, 0.0, None)
        wd = omega * np.sqrt(1 - zeta**2)
        y = 1 - np.exp(-zeta * omega * tau) * (np.cos(wd * tau) + zeta / np.sqrt(1 - zeta**2) * np.sin(wd * tau))
        return 1.0 + y
    return response


def test_step_measures_the_overshoot_and_settling_of_a_second_order_response():
    """zeta = 0.5, omega = 10 rad/s: overshoot exp(-pi zeta / sqrt(1 - zeta^2)) = 16.3 %; the 2 %
    band entered for good near 4 / (zeta omega) = 0.8 s (the envelope's bound; 0.81 s sampled)."""
    run = record({"y": second_order(0.5, 10.0)}, duration=3.0)
    step = step_response(run, "y", step_s=0.5, final=2.0)
    assert step.overshoot_percent == pytest.approx(100 * np.exp(-np.pi * 0.5 / np.sqrt(0.75)), rel=1e-3)
    assert 0.7 < step.settling_time_s < 0.85 and step.peak_time_s == pytest.approx(0.5 + np.pi / (10 * np.sqrt(0.75)),
                                                                                    abs=DT)
    assert_step(run, "y", step_s=0.5, final=2.0, settles_within_s=0.85, overshoot_below_percent=17.0)
    with pytest.raises(AssertionError, match=r"overshoot 16\.3\d* %, above the bound 10 %; peak 2\.16\d* at t = "
                                             r"0\.8630 s; seed 7"):
        assert_step(run, "y", step_s=0.5, final=2.0, overshoot_below_percent=10.0)
    with pytest.raises(AssertionError, match=r"settles in 0\.\d+ s, beyond the bound 0\.5 s; the last sample outside "
                                             r"the 2 % band \[1\.98, 2\.02\] is 1\.97\d* at t = 1\.\d+ s"):
        assert_step(run, "y", step_s=0.5, final=2.0, settles_within_s=0.5)


def test_bias_convergence_names_the_last_sample_outside():
    truth = (0.02, -0.01, 0.015)
    run = record({**{f"IMU.gyro_bias_{a}": (lambda t, b=b: b + 0.0 * t) for a, b in zip("xyz", truth, strict=True)},
                  **{f"Quaternion_estim.b_est_{a}": (lambda t, b=b: b * (1 - np.exp(-t)))
                     for a, b in zip("xyz", truth, strict=True)}}, duration=4.0)
    converged = np.log(0.02 / 1e-3)  # x, the largest bias, the last inside: 3.0 s
    assert assert_bias_converges(run) == pytest.approx(converged, abs=DT)
    with pytest.raises(AssertionError, match=r"converges at 2\.99\d+ s, bound 1\.5 s; the last sample outside "
                                             r"\+-0\.001 rad/s of IMU\.gyro_bias is at t = 2\.99\d+ s, axis x off by "
                                             r"-0\.001\d* rad/s; seed 7"):
        assert_bias_converges(run, within_s=1.5)
    with pytest.raises(AssertionError, match="never converges"):
        assert_bias_converges(run, tolerance=1e-4)


def test_two_runs_compared_within_a_tolerance():
    a = record({"Quadrotor.theta2": lambda t: np.sin(t)}, seed=1)
    b = record({"Quadrotor.theta2": lambda t: np.sin(t) + 1e-6 * (t > 1.25)}, seed=2)
    assert assert_runs_close(a, a) == 0.0
    assert assert_runs_close(a, b, atol=1.01e-6) == pytest.approx(1e-6, rel=1e-6)
    with pytest.raises(AssertionError, match=r"Quadrotor\.theta2 = 0\.9492\d+ against 0\.9493\d+ at t = 1\.2510 s, "
                                             r"\|difference\| 1e-06 beyond the bound 5e-07; other run's seed 2 .*; "
                                             r"seed 1"):
        assert_runs_close(a, b, ["Quadrotor.theta2"], atol=5e-7)


def test_seeds_come_from_the_node_id():
    seeds = {seed_of(f"tests/test_mine.py::test_hover[{k}]") for k in range(1000)}
    assert len(seeds) == 1000 and min(seeds) >= 1 and max(seeds) <= SEED_LIMIT
    assert seed_of("tests/test_mine.py::test_hover[0]") == seed_of("tests/test_mine.py::test_hover[0]")


@pytest.fixture
def numba_loaded():
    """numba's lazily loaded registries (its polynomial types), loaded before pytester's snapshot of
    the modules: the guide's run is in this process, pytester drops the modules it imported when it
    ends, and the next test that compiles would register them a second time ("duplicate
    registration")."""
    from numba.core.registry import cpu_target

    cpu_target.target_context.refresh()


def test_the_guide_example_runs_as_written(numba_loaded, pytester):
    """docs/guides/examples/test_my_work.py, the slow test deselected as the guide shows."""
    pytester.makepyfile(test_my_work=EXAMPLE.read_text())
    result = pytester.runpytest("-p", "no:cacheprovider", "-m", "not slow")
    result.assert_outcomes(passed=9, deselected=1)


OUTSIDE = '''
def test_hover_holds_the_attitude(run_scenario):
    result = run_scenario("tp", duration=2, flight="hover", noise=True)
    assert_attitude_error(result, below_deg=0.2, after_s=1)   # 0.06 to 0.10 deg measured on seeds 1-3


def test_deliberately_failing(run_scenario, quadcosim_seed):
    result = run_scenario("tp", duration=2, flight="hover", noise=True)
    assert result.metrics["samples"] == 2001 and result.meta["test"]["seed"] == quadcosim_seed
    assert_attitude_error(result, below_deg=0.001, after_s=1)
'''


def test_a_test_file_outside_the_checkout_runs_with_the_installed_package(tmp_path):
    """Only the plugin's fixtures and helpers, in a folder of its own, run by pytest in a fresh
    process: one passes, the other fails and prints the worst sample's time, value, bound and seed."""
    (tmp_path / "test_outside.py").write_text("from quadcosim.scenarios.testing import assert_attitude_error\n" +
    OUTSIDE)
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
                           "test_outside.py"], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    print(done.stdout[-3000:], done.stderr[-2000:])
    assert "1 failed, 1 passed" in done.stdout
    assert "test_outside.py::test_deliberately_failing" in done.stdout
    seed = seed_of("test_outside.py::test_deliberately_failing")
    message = (r"AssertionError: attitude error: (roll|pitch|yaw) estimate off the truth by \d\.\d+ deg at t = "
               rf"\d\.\d{{4}} s, above the bound 0\.001 deg \(checked from 1 s\); seed {seed} \(test "
               r"test_outside\.py::test_deliberately_failing\)")
    import re

    assert re.search(message, done.stdout), message
    assert f"test seed {seed}, from the node id test_outside.py::test_deliberately_failing" in done.stdout
    assert f"run: tp flight=hover noise=True duration=2 seed={seed}" in done.stdout
