"""The ``dynamic`` model's flight wrapper on a fast synthetic record made by the project's own
compensator (the shared logs are too slow for it: 10 Hz)."""

from types import SimpleNamespace

import numpy as np
import pytest
from quadcosim.calibration import Calibration, MotorDynamics, MotorFieldModel, compensate
from quadcosim.calibration.flight.data import FlightData
from quadcosim.calibration.flight.dynamic import DynamicModel
from quadcosim.calibration.flight.models import Fitted
from scipy.spatial.transform import Rotation


@pytest.mark.slow
def test_motor_dynamics_identified_from_a_fast_flight_record():
    rng = np.random.default_rng(4)
    truth = MotorDynamics(rate=40.0, drag=0.5, limit=np.inf, exponent=1, freewheel=True,
                          gain=np.array([2e-6, 1.8e-6, 2.2e-6, 1.9e-6]))
    v = np.array([[0.6, 0.0, 0.8], [0.0, 0.6, 0.8], [-0.6, 0.0, 0.8], [0.0, -0.6, 0.8]])
    field = MotorFieldModel(v, np.ones((4, 1)), (1, 0))
    grid = np.arange(0.0, 5.0, 1 / 200.0)
    commands = 0.45 + 0.15 * np.sign(np.sin(2 * np.pi * 0.7 * grid[:, None] + np.arange(4)))  # steps: dynamics show
    voltage = np.full(len(grid), 12.0)
    b_d = -compensate(Calibration(4, field=field, dynamics=truth), grid, np.zeros((len(grid), 3)), commands, voltage,
                      "dynamic")
    mag_time = grid[::2]  # 100 Hz
    yaw = 0.3 * mag_time
    R = Rotation.from_euler("ZYX", np.column_stack([yaw, 0 * yaw, 0 * yaw])).as_matrix()
    m_E, b = np.array([2e-5, 0, 4.5e-5]), np.array([1e-6, -2e-6, 3e-6])
    raw = np.einsum("tji,j->ti", R, m_E) + b + b_d[::2] + rng.normal(0, 5e-8, (len(mag_time), 3))
    motors = SimpleNamespace(time=grid, commands=commands)
    battery = SimpleNamespace(time=grid, voltage=voltage, current=None)
    data = FlightData("synthetic", mag_time, raw, R, np.zeros((len(mag_time), 3)), motors, battery, None, 0)
    metge = Fitted("metge", 0.0, {}, None, extra={"nuisance": np.r_[m_E, b][None], "field": field})
    model = DynamicModel(metge)
    assert model.refusal([data]) is None
    fitted = model.fit([data])
    assert fitted.coefficients["rate_1_s"] == pytest.approx(truth.rate, rel=0.02)  # measured 0.4 %
    error = fitted.predict(data) - b_d[::2]
    # measured 6.5 %: the 100 Hz magnetometer is interpolated onto the 200 Hz grid the dynamics run on
    assert np.sqrt((error**2).mean()) < 0.08 * np.sqrt((b_d[::2] ** 2).mean())
    slow = FlightData("slow", mag_time[::10], raw[::10], R[::10], np.zeros((len(mag_time[::10]), 3)), motors,
                      battery, None, 0)
    assert "magnetometer at 10.0 Hz" in model.refusal([slow])
