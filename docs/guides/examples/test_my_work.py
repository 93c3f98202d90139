"""A user's estimator and controller, tested on the lab's closed loop (``tp``) with the quadcosim
pytest plugin: the fixtures ``run_scenario`` and ``make_system`` need no import, the checks come
from ``quadcosim``. Run it with ``pytest test_my_work.py`` (``-n 2`` on two cores)."""

import numpy as np
import pytest

from quadcosim import (
    AttitudeEstimator,
    Controller,
    assert_attitude_error,
    assert_bias_converges,
    assert_bounds,
    assert_runs_close,
    assert_step,
    assert_tracking,
)

EARTH_FIELD = np.array([np.cos(np.radians(65.0)), 0.0, np.sin(np.radians(65.0))])  # direction in NED (Paris)


def rotation(q):
    """Body-to-NED rotation matrix of a unit quaternion (scalar first)."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


class MyFilter(AttitudeEstimator):
    """Mahony's explicit complementary filter without bias estimate: gravity and the Earth's
    field pull the gyro's integration towards the measured directions with gain ``kp`` (1/s)."""

    def __init__(self, name="Quaternion_estim", period=1, q0=None, kp=1.0):
        super().__init__(name, period, q0)
        self.kp = kp  # a public number: a parameter, set by parameters={"Quaternion_estim.kp": ...}

    def update(self, acc, gyro, mag):
        estimate = rotation(self.q).T  # NED to body
        correction = (np.cross(acc / np.linalg.norm(acc), estimate @ [0.0, 0.0, -1.0])
                      + np.cross(mag / np.linalg.norm(mag), estimate @ EARTH_FIELD))
        rate = gyro + self.kp * correction
        half = 0.5 * self.dt * rate
        w, x, y, z = self.q
        self.q = self.q + np.array([-x * half[0] - y * half[1] - z * half[2], w * half[0] + y * half[2] - z * half[1],
                                    w * half[1] + z * half[0] - x * half[2], w * half[2] + x * half[1] - y * half[0]])
        self.q /= np.linalg.norm(self.q)


def test_my_filter_tracks_the_quasi_stationary_flight(run_scenario):
    result = run_scenario("tp", duration=2, estimator=MyFilter)
    assert_attitude_error(result, below_deg=0.15, after_s=1)  # 0.079 deg measured (roll)


@pytest.mark.parametrize("kp, below_deg", [(0.5, 0.12), (2.0, 0.25)])  # 0.068 and 0.14 deg at most on seeds 11-13
def test_my_filter_with_noise_at_several_gains(run_scenario, kp, below_deg):
    """The seed of the IMU's noise is the test's own (from its name): the same on every run.
    A larger gain lets more of the accelerometer's noise through."""
    result = run_scenario("tp", duration=2, estimator=MyFilter, noise=True, parameters={"Quaternion_estim.kp": kp})
    assert_attitude_error(result, below_deg=below_deg, after_s=1)


@pytest.mark.parametrize("seed", [1, 2])
def test_the_lab_passive_filter_finds_the_gyro_bias(run_scenario, seed):
    """kP = kI = 3: 2.19 s predicted by the linearised filter, 2.20 to 2.27 s measured on seeds 1-4."""
    result = run_scenario("tp", duration=4, estimator="passive", flight="hover", bias=True, noise=True,
                          kP=3.0, kI=3.0, seed=seed)
    assert_bias_converges(result, within_s=2.6, tolerance=1e-3)  # s, rad/s


# attitude gains kp (1/s^2), kd (1/s); bounds on settling (s), overshoot (%), tracking error (deg). Measured:
# 0.27 s, 0.22 %, 6e-5 deg at 12 rad/s (the default gains); 0.44 s, 0.68 %, 0.010 deg at 8 rad/s.
STEPS = [(144.0, 19.2, 0.5, 0.4, 1.2e-4), (64.0, 12.8, 0.8, 1.2, 0.02)]


@pytest.mark.parametrize("kp, kd, settles_s, overshoot_percent, tracking_deg", STEPS)
def test_my_controller_takes_a_5_degree_pitch_step(run_scenario, kp, kd, settles_s, overshoot_percent, tracking_deg):
    """Natural frequency sqrt(kp) rad/s, damping kd / (2 sqrt(kp)) = 0.8."""
    mine = Controller(gains={"kp": kp, "kd": kd})
    result = run_scenario("tp", duration=2, flight="tilt", tilt_deg=5.0, blocks={"Controller": mine})
    assert_step(result, "Quadrotor.theta2", step_s=1.0, final=np.radians(5.0), settles_within_s=settles_s,
                overshoot_below_percent=overshoot_percent)
    assert_tracking(result, "Quadrotor.theta2", "Controller.theta_d2", within=np.radians(tracking_deg), after_s=1.8,
                    angle=True)
    assert_bounds(result, "Controller.c", lower=0.4, upper=0.52)  # ESC commands near hover: 0.44 to 0.48 measured


def test_the_estimate_fed_loop_flies_as_the_truth_fed_one(run_scenario):
    truth_fed = run_scenario("tp", duration=2, estimator="passive")
    estimate_fed = run_scenario("tp", duration=2, estimator="passive", feedback="estimate")
    assert_runs_close(estimate_fed, truth_fed, ["Quadrotor.theta"], atol=np.radians(0.0015))  # 0.0007 deg measured


def test_my_own_system(make_system):
    system = make_system(dt=1e-3)
    assert system.dt == 1e-3 and not system.blocks


@pytest.mark.slow
def test_my_filter_over_the_whole_flight(run_scenario):
    """The whole quasi-stationary flight, 20 s: deselected by ``pytest -m "not slow"``."""
    result = run_scenario("tp", duration=20, estimator=MyFilter, noise=True)
    assert_attitude_error(result, below_deg=1.0, after_s=2)  # 0.50 and 0.55 deg (yaw) on seeds 5 and 6
