"""The estimator contract is checked while the run goes: a user's filter whose quaternion leaves
unit norm or whose output turns NaN stops the run ("failed", exit 1) at the first such step,
and a user's exception is reported with its file, line and traceback (in ``metrics.json``)."""

import json

import numpy as np
import pytest
from quadcosim.estimators.contract import NORM_TOLERANCE, AttitudeEstimator
from quadcosim.orchestrator import SimulationError

from quadcosim import scenarios


class Growing(AttitudeEstimator):
    """q multiplied by 1.01 each step: |q| = 2.1e4 after 1 s at 1 kHz, once a run that completed."""

    def update(self, acc, gyro, mag):
        self.q = self.q * 1.01


class Drifting(AttitudeEstimator):
    """q off unit norm by half the tolerance: within the contract."""

    def update(self, acc, gyro, mag):
        self.q = self.q / np.linalg.norm(self.q) * (1 + NORM_TOLERANCE / 2)


class Poisoned(AttitudeEstimator):
    """A bias estimate that turns NaN at the 10th sample."""

    def update(self, acc, gyro, mag):
        self.count = getattr(self, "count", 0) + 1
        if self.count == 10:
            self.bias = np.full(3, np.nan)


class Raising(AttitudeEstimator):
    def update(self, acc, gyro, mag):
        raise ZeroDivisionError("the user's own bug")


def _failed(tmp_path, estimator) -> tuple[str, dict]:
    with pytest.raises(SimulationError) as caught:
        scenarios.run("tp", {"duration": 1.0}, out_dir=tmp_path / "run", estimator=estimator)
    return str(caught.value), json.loads((tmp_path / "run" / "metrics.json").read_text())


def test_a_quaternion_growing_off_unit_norm_fails_the_run_at_once(tmp_path):
    message, metrics = _failed(tmp_path, Growing)
    assert "|q_est| = 1.01 at t = 0.0000 s; the contract asks for a unit quaternion (within 0.001)" in message
    assert metrics["status"] == "failed" and metrics["samples"] <= 1


def test_a_nan_output_fails_the_run_naming_it(tmp_path):
    message, metrics = _failed(tmp_path, Poisoned)
    assert "b_est_x = nan at t = 0.0090 s; every output must be a finite number" in message
    assert metrics["status"] == "failed"


def test_a_quaternion_within_the_tolerance_completes(tmp_path):
    result, metrics = scenarios.run("tp", {"duration": 0.2}, estimator=Drifting)
    assert metrics["status"] == "completed" and len(result) == 201


def test_a_users_exception_names_its_file_line_and_keeps_the_traceback(tmp_path):
    message, metrics = _failed(tmp_path, Raising)
    line = Raising.update.__code__.co_firstlineno + 1
    assert f"ZeroDivisionError: the user's own bug (raised at {__file__}, line {line}, in update)" in message
    assert metrics["traceback"].startswith("Traceback (most recent call last):")
    assert f'File "{__file__}", line {line}, in update' in metrics["traceback"]
