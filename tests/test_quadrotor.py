"""Rigid-body physics of the Quadrotor FMU."""

import numpy as np
import pytest

from fmus import vehicle
from fmus.airframe import MOTORS
from orchestrator.fmu import FMUInstance
from tests.helpers import rotation, run_fmu

W_HOVER = vehicle.hover_rotor_speed()
HOVER = {f"omega_r{n}": W_HOVER for n in range(1, 5)}


def test_hover_stays_put():
    out = run_fmu("Quadrotor", {}, HOVER, 1000, outputs=["p_x", "p_y", "p_z", "v_z", "f_z"])
    for axis in ("p_x", "p_y", "p_z"):
        assert np.abs(out[axis]).max() < 1e-9
    assert out["f_z"][-1] == pytest.approx(-vehicle.GRAVITY, rel=1e-12)


def test_more_thrust_climbs():
    out = run_fmu("Quadrotor", {}, {k: 1.05 * w for k, w in HOVER.items()}, 500, outputs=["p_z", "v_z"])
    assert out["v_z"][-1] < -0.4  # NED: climbing is negative z
    assert np.all(np.diff(out["p_z"][1:]) < 0)


def test_torque_free_rotation_conserves_momentum_and_energy():
    fmu = FMUInstance("Quadrotor", {"omega_x0": 0.8, "omega_y0": -0.5, "omega_z0": 1.1,
                                    "theta1_0": 0.3, "theta2_0": -0.2, "theta3_0": 1.0, "g": 9.81})
    J = np.diag(vehicle.INERTIA)

    def invariants():
        q = fmu.get(["q0", "q1", "q2", "q3"])
        w = fmu.get(["omega_x", "omega_y", "omega_z"])
        return rotation(q) @ J @ w, 0.5 * w @ J @ w, np.linalg.norm(q)

    h0, e0, _ = invariants()
    worst_norm = 0.0
    for k in range(10000):
        fmu.step(k * 1e-3, 1e-3)
        if k % 100 == 99:
            worst_norm = max(worst_norm, abs(invariants()[2] - 1.0))
    h1, e1, _ = invariants()
    assert np.linalg.norm(h1 - h0) / np.linalg.norm(h0) < 1e-8
    assert abs(e1 - e0) / e0 < 1e-8
    assert worst_norm < 1e-12
    fmu.close()


def test_clamped_keeps_pose_while_motors_run():
    params = {"clamped": True, "theta1_0": 0.2, "theta3_0": 0.5}
    out = run_fmu("Quadrotor", params, {k: 1.5 * w for k, w in HOVER.items()}, 300,
                  outputs=["p_z", "theta1", "theta3", "omega_x", "f_x", "f_y", "f_z", "thrust"])
    assert np.abs(out["p_z"]).max() == 0.0 and np.abs(out["omega_x"]).max() == 0.0
    assert np.allclose(out["theta1"], 0.2, atol=1e-15) and np.allclose(out["theta3"], 0.5, atol=1e-15)
    # at rest the specific force is R^T (0, 0, -g)
    g = vehicle.GRAVITY
    expected = np.array([0.0, -g * np.sin(0.2), -g * np.cos(0.2)])  # rolled right: f_y < 0
    assert np.allclose([out["f_x"][-1], out["f_y"][-1], out["f_z"][-1]], expected, atol=1e-12)
    assert out["thrust"][-1] > 2 * g  # the rotors push, the rig holds


@pytest.mark.parametrize("motor", MOTORS, ids=lambda m: f"motor{m.number}")
def test_torque_of_each_motor_follows_the_airframe(motor):
    """A rotor faster than the others tilts the body away from its arm and yaws with its spin."""
    inputs = dict(HOVER)
    inputs[f"omega_r{motor.number}"] = 1.1 * W_HOVER
    out = run_fmu("Quadrotor", {}, inputs, 1, outputs=["tau_x", "tau_y", "tau_z"])
    x, y = motor.direction
    assert np.sign(out["tau_x"][-1]) == -np.sign(y)  # more lift on the right rolls left
    assert np.sign(out["tau_y"][-1]) == np.sign(x)  # more lift in front pitches up
    assert np.sign(out["tau_z"][-1]) == motor.spin
