"""Controller, mixer and flight profiles (scenarios.flight)."""

import numpy as np
import pytest

from fmus import vehicle
from scenarios.flight import GAINS, Controller, allocation_matrix, esc_command, profile
from scenarios.flight import controller as law


def test_unknown_or_bad_gains_are_refused_with_the_nearest_name():
    with pytest.raises(ValueError, match="unknown controller gain 'kp_zz'.*kp_z"):
        Controller(gains={"kp_zz": 1.0})
    with pytest.raises(ValueError, match="kd = -1"):
        Controller(gains={"kd": -1.0})
    with pytest.raises(ValueError, match="ki_xy = 2.0 must be below kp_xy \\* kd_xy = 1.8"):
        Controller(gains={"ki_xy": 2.0})
    assert Controller(gains={"kp": 100.0}).parameters[law.P_KP] == 100.0


def test_the_law_reads_its_slots_by_name():
    assert law.INPUTS[law.U_Q:law.U_Q + 4] == ("q0", "q1", "q2", "q3")
    assert law.INPUTS[law.U_V + 2] == "v_z" and law.INPUTS[law.U_BATT] == "u_batt"
    assert law.OUTPUTS[law.Y_C + 3] == "c4" and law.OUTPUTS[law.Y_PITCH_D] == "theta_d2"
    p = law.parameters()
    for name, (default, _, _) in GAINS.items():
        assert p[law.PARAMETERS.index(name)] == default


def test_level_hover_commands_the_motors_steady_state_map():
    """At the hover point the law asks every motor for the hover speed; the command is the
    motors' steady-state map (the one in fmus.vehicle) at the battery voltage."""
    block = Controller()
    block.start(0.0, 1e-3)
    u = np.zeros(len(law.INPUTS))
    u[law.U_Q], u[law.U_HOLD], u[law.U_BATT] = 1.0, 1.0, 11.5
    y = np.zeros(len(law.OUTPUTS))
    block.step(0.0, u, y)
    expected = vehicle.steady_command(vehicle.hover_rotor_speed(), 11.5)
    assert y[law.Y_C:law.Y_C + 4] == pytest.approx([expected] * 4, rel=1e-12)
    assert y[law.Y_THRUST] == pytest.approx(vehicle.MASS * vehicle.GRAVITY)
    assert esc_command(400.0, 11.0, vehicle.MOTOR_RESISTANCE, vehicle.MOTOR_KE, vehicle.DRAG_TORQUE_COEFF) \
        == vehicle.steady_command(400.0, 11.0)


def test_allocation_gives_pure_torques():
    m = allocation_matrix()
    inverse = np.linalg.inv(m)
    roll = inverse @ [0.0, 0.1, 0.0, 0.0]
    assert roll.sum() == pytest.approx(0.0, abs=1e-15)
    assert m @ roll == pytest.approx([0.0, 0.1, 0.0, 0.0])


def test_profiles_are_small_and_slow_or_large_and_fast():
    dt = 0.01
    quasi = profile("quasi", 60.0, dt)
    fast = profile("nonstationary", 60.0, dt)
    assert np.all(quasi[:, 6] == 1) and np.all(fast[:, 6] == 0)
    speed = np.abs(np.diff(quasi[:, 3:5], axis=0)).max() / dt
    assert 0.9 < speed < 1.1  # m/s: 2 pi 0.04 Hz x 4 m
    assert np.degrees(np.abs(fast[:, :2]).max()) == pytest.approx(20.0, rel=1e-3)
    tilt = profile("tilt", 3.0, dt, np.radians(5.0))
    assert tilt[0, 1] == 0.0 and np.degrees(tilt[-1, 1]) == pytest.approx(5.0)
    with pytest.raises(ValueError, match="flight 'quasy' must be one of quasi"):
        profile("quasy", 1.0, dt)
