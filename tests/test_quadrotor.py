"""Rigid-body physics of the Quadrotor FMU."""

import numpy as np
import pytest
from quadcosim.fmus import vehicle
from quadcosim.fmus.airframe import MOTORS
from quadcosim.orchestrator.fmu import FMUInstance
from raw_fmu import RawFMU

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
    extra = (1.1**2 - 1.0) * W_HOVER**2  # the other three cancel in pairs
    lift, drag = vehicle.THRUST_COEFF * extra, vehicle.DRAG_TORQUE_COEFF * extra
    # thrust along -z_B at r = arm (x, y): tau = r x F = (-y T, x T); more lift on the right
    # rolls left, in front pitches up; the yaw reaction follows the spin (measured: 4e-15 relative)
    expected = [-y * vehicle.ARM * lift, x * vehicle.ARM * lift, motor.spin * drag]
    assert [out["tau_x"][-1], out["tau_y"][-1], out["tau_z"][-1]] == pytest.approx(expected, rel=1e-12)


def test_rotor_drag_pulls_a_level_hover_to_the_wind_speed():
    """Level hover in a steady wind: the H-force -k_d sum(omega) v_a is linear in the airspeed, so
    the velocity relaxes to the wind's with the time constant m / (k_d sum omega), and the
    accelerometer (the specific force) sees that drag while thrust only balances gravity."""
    wind = (3.0, -1.0, 0.0)
    inputs = {**HOVER, "wind_x": wind[0], "wind_y": wind[1], "wind_z": wind[2]}
    out = run_fmu("Quadrotor", {}, inputs, 3000, outputs=["v_x", "v_y", "v_z", "f_x", "f_y", "drag_x"])
    tau = vehicle.MASS / (vehicle.ROTOR_DRAG_COEFF * 4 * W_HOVER)
    t = np.arange(3001) * 1e-3
    for axis, w in zip("xy", wind[:2], strict=True):
        expected = w * (1 - np.exp(-t / tau))
        assert np.abs(out[f"v_{axis}"] - expected).max() < 1e-9 * abs(w)
        assert np.allclose(out[f"f_{axis}"], (w - out[f"v_{axis}"]) / tau, rtol=1e-9, atol=1e-12)
    assert np.abs(out["v_z"]).max() < 1e-12
    assert out["drag_x"][0] == pytest.approx(vehicle.MASS * wind[0] / tau, rel=1e-12)
    print(f"\nrotor drag: lumped {vehicle.MASS / tau:.3f} kg/s at hover, time constant {tau:.2f} s")


def test_parasitic_drag_is_quadratic_in_the_airspeed():
    inputs = {**HOVER, "wind_x": -4.0, "wind_y": 0.0, "wind_z": 0.0}
    out = run_fmu("Quadrotor", {"k_d": 0.0, "c_Dx": 0.01}, inputs, 1, outputs=["drag_x", "drag_y", "f_x"])
    assert out["drag_x"][0] == pytest.approx(-0.01 * 4.0 * 4.0, rel=1e-12)  # airspeed +4 m/s north
    assert out["f_x"][0] == pytest.approx(out["drag_x"][0] / vehicle.MASS, rel=1e-12)
    assert out["drag_y"][0] == 0.0


def test_gyroscopic_moment_of_the_rotors_precesses_the_body_rates():
    """With Jxx = Jyy, no yaw rate and no rotor torques, only the rotors' gyroscopic moment acts.
    Rotors spinning counter-clockwise seen from above (s = +1) carry angular momentum along -z_B:
    h_r = -J_r sum(s_n omega_n) e3, and the body feels -omega x h_r. A roll rate p then pitches
    the nose down at -J_r sum(s_n omega_n) p / Jyy: (p, q) turns at Omega = J_r sum(s_n omega_n) / Jxx."""
    speeds = {m.number: (600.0 if m.spin > 0 else 400.0) for m in MOTORS}
    inputs = {f"omega_r{n}": w for n, w in speeds.items()}
    spin_sum = sum(m.spin * speeds[m.number] for m in MOTORS)
    params = {"k_m": 0.0, "omega_x0": 1.0}
    out = run_fmu("Quadrotor", params, inputs, 1000, outputs=["omega_x", "omega_y", "omega_z", "tau_x", "tau_y"])
    assert np.abs([out["tau_x"], out["tau_y"]]).max() < 1e-15  # diagonal pairs: no thrust torque
    rate = vehicle.ROTOR_INERTIA * spin_sum / vehicle.INERTIA[0]
    t = np.arange(1001) * 1e-3
    assert np.abs(out["omega_x"] - np.cos(rate * t)).max() < 1e-9
    assert np.abs(out["omega_y"] + np.sin(rate * t)).max() < 1e-9  # nose-down for a right roll
    assert out["omega_y"][1] < 0
    without = run_fmu("Quadrotor", {**params, "J_r": 0.0}, inputs, 10, outputs=["omega_y"])
    assert np.abs(without["omega_y"]).max() < 1e-12  # rounding of the arm directions only


def rotor_pair_step(k_m, pair_step=0.1, h=1e-4, seconds=0.15):
    """Hover, then the counter-clockwise pair (motors 1 and 2, on a diagonal) gets a command step;
    motors and body co-simulated at step h. Returns the recorded signals."""
    from quadcosim.orchestrator import FMUBlock, System, Table

    w0 = vehicle.hover_rotor_speed()
    c0 = vehicle.hover_command()
    step_at = 0.02
    t = np.arange(int(round(seconds / h)) + 1) * h
    commands = np.full((len(t), 4), c0)
    for m in MOTORS:
        if m.spin > 0:
            commands[t >= step_at, m.number - 1] += pair_step
    system = System(dt=h)
    system.add(Table("Setpoint", ["c1", "c2", "c3", "c4"], commands))
    system.add(FMUBlock("MotorMagnetics", parameters={"omega0": w0, "k_m": k_m}))
    system.add(FMUBlock("Quadrotor", parameters={"clamped": False, "k_m": k_m}))
    system.connect("Setpoint.c", "MotorMagnetics.c")
    system.connect("MotorMagnetics.omega_r", "Quadrotor.omega_r")
    system.connect("MotorMagnetics.domega_r", "Quadrotor.domega_r")
    system.set_input("Quadrotor.wind", 0.0)
    return system.run(seconds, record=["Quadrotor.omega_z", "MotorMagnetics.omega_r", "MotorMagnetics.domega_r"])


def test_rotor_pair_step_yaws_the_body_by_the_reaction_of_the_rotor_acceleration(capsys):
    """Acceptance: a step in one rotor pair's speeds gives the yaw acceleration J_r dω/dt predicts.

    Without aerodynamic drag torque (k_m = 0 in both models) the yaw is driven by the reaction
    alone, so the yaw acceleration is J_r sum(s_n domega_n) / Jzz, and the angular momentum
    about z, Jzz omega_z - J_r sum(s_n omega_n), is conserved."""
    result = rotor_pair_step(k_m=0.0)
    t, h = result.time, result.time[1] - result.time[0]
    spin = np.array([m.spin for m in MOTORS], dtype=float)
    predicted = vehicle.ROTOR_INERTIA * (result["MotorMagnetics.domega_r"] @ spin) / vehicle.INERTIA[2]
    measured = np.gradient(result["Quadrotor.omega_z"], h)
    window = (t > 0.021) & (t < 0.1)  # the spin-up, after the first sub-millisecond current rise
    peak = np.abs(predicted[window]).max()
    worst = np.abs(measured[window] - predicted[window]).max() / peak
    momentum = vehicle.INERTIA[2] * result["Quadrotor.omega_z"] - vehicle.ROTOR_INERTIA * (
        result["MotorMagnetics.omega_r"] @ spin)
    with capsys.disabled():
        print(f"\nrotor pair step: peak yaw acceleration {measured[window].max():.3f} rad/s^2, "
              f"J_r dω/dt predicts {peak:.3f}; largest difference {worst:.2%} of the peak; "
              f"yaw rate after 0.15 s {result['Quadrotor.omega_z'][-1]:.4f} rad/s; momentum drift "
              f"{np.ptp(momentum) / np.abs(vehicle.INERTIA[2] * result['Quadrotor.omega_z']).max():.1e} of the body's")
    assert worst < 0.015  # measured 0.79 %
    assert measured[window].max() > 1.0  # a real acceleration, not zero against zero
    # the body sees each rotor acceleration held over a macro step: a transient lag of h/2
    assert np.ptp(momentum) < 3e-3 * np.abs(vehicle.INERTIA[2] * result["Quadrotor.omega_z"]).max()


def test_rotor_pair_step_with_drag_torque_adds_the_reaction():
    """With the default drag torque, the early yaw acceleration is mostly the reaction torque:
    the rotors have not sped up yet, so k_m sum(s_n omega_n^2) is still small."""
    result = rotor_pair_step(k_m=vehicle.DRAG_TORQUE_COEFF, seconds=0.04)
    t, h = result.time, result.time[1] - result.time[0]
    spin = np.array([m.spin for m in MOTORS], dtype=float)
    w = result["MotorMagnetics.omega_r"]
    predicted = (vehicle.ROTOR_INERTIA * (result["MotorMagnetics.domega_r"] @ spin)
                 + vehicle.DRAG_TORQUE_COEFF * (w ** 2 @ spin)) / vehicle.INERTIA[2]
    measured = np.gradient(result["Quadrotor.omega_z"], h)
    window = (t > 0.021) & (t < 0.035)
    assert np.abs(measured[window] - predicted[window]).max() < 0.015 * np.abs(predicted[window]).max()  # 0.79 %
    reaction = vehicle.ROTOR_INERTIA * (result["MotorMagnetics.domega_r"] @ spin)[window]
    assert reaction.max() > 0.5 * (predicted[window] * vehicle.INERTIA[2]).max()


def test_a_failed_step_leaves_the_model_time_at_the_last_good_point():
    fmu = RawFMU("Quadrotor")
    assert fmu.instantiate()
    assert fmu.initialize() == 0, fmu.messages()
    assert fmu.do_step(0.0, 1e-3) == 0
    refs = [fmu.refs[f"omega_r{n}"] for n in range(1, 5)]
    assert fmu.set_real(refs, [1e200] * 4) == 0
    assert fmu.do_step(1e-3, 1e-3) == 3  # the state overflows: Error
    assert fmu.time() == 1e-3  # fmi2LastSuccessfulTime: the step that failed did not count
    fmu.free()
