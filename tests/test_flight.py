"""Controller, mixer and flight profiles (flight)."""

import numpy as np
import pytest
from quadcosim.flight import GAINS, Controller, allocation_matrix, esc_command, initial_state, profile, profiles, trim
from quadcosim.flight import controller as law
from quadcosim.fmus import vehicle
from quadcosim.scenarios.testing.assertions import assert_bounds

from quadcosim import scenarios


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
    motors' steady-state map (the one in quadcosim.fmus.vehicle) at the battery voltage."""
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


def steady_speed(tilt: float) -> float:
    """Steady speed (m/s) of level flight at pitch ``tilt`` (rad) with rotor drag, from the force
    balance: along the flight ``T sin(tilt) = k_d S V cos(tilt)^2``, along gravity ``T cos(tilt) +
    k_d S V cos(tilt) sin(tilt) = m g``, so ``T = m g cos(tilt)`` and ``V = m g tan(tilt) / (k_d S)``,
    ``S = 2 sqrt(T / k_f)`` the four equal rotors' summed speed."""
    thrust = vehicle.MASS * vehicle.GRAVITY * np.cos(tilt)
    return vehicle.MASS * vehicle.GRAVITY * np.tan(tilt) / (
        vehicle.ROTOR_DRAG_COEFF * 2.0 * np.sqrt(thrust / vehicle.THRUST_COEFF))


def test_profiles_are_small_and_slow_or_large_and_fast():
    dt = 0.01
    quasi = profile("quasi", 60.0, dt)
    fast = profile("nonstationary", 60.0, dt)
    assert np.all(quasi[:, 6] == 0) and np.all(fast[:, 6] == 0)
    cruise = initial_state("quasi")
    assert cruise["theta2_0"] == quasi[0, 1]
    # level flight at the cruise speed: the pitch whose steady speed (the force balance) is that speed
    print(f"cruise pitch {np.degrees(cruise['theta2_0']):.4f} deg, its steady speed "
          f"{steady_speed(-cruise['theta2_0']):.12f} m/s")
    assert steady_speed(-cruise["theta2_0"]) == pytest.approx(profiles.CRUISE_SPEED, rel=1e-12)  # 0 measured
    variation = np.degrees(np.abs(quasi[:, :2] - quasi[0, :2])).max()  # about the trim: 1 deg, 2 at most
    rate = np.degrees(np.abs(np.diff(quasi[:, :3], axis=0)).max()) / dt
    assert variation <= 2.0 and rate < 0.7  # deg, deg/s
    assert np.degrees(np.abs(fast[:, :2]).max()) == pytest.approx(20.0, rel=1e-3)
    assert np.degrees(np.abs(np.diff(fast[:, :2], axis=0)).max()) / dt > 40.0  # deg/s
    tilt = profile("tilt", 3.0, dt, np.radians(5.0))
    assert tilt[0, 1] == 0.0 and np.degrees(tilt[-1, 1]) == pytest.approx(5.0)
    with pytest.raises(ValueError, match="flight 'quasy' must be one of quasi"):
        profile("quasy", 1.0, dt)


@pytest.mark.parametrize("drag", [True, False])
def test_steady_tilted_flight_accelerometer_sees_the_tilt_only_with_drag(drag):
    """A 5 deg pitch held until the speed settles (30 s, 7 drag time constants): with rotor drag
    the accelerometer's tilt is the true tilt (0.006 deg measured); without, it reads level.
    The figures are those tp's metrics.json records. The speed reached is the force balance's
    steady speed less what a first-order lag of the trim's time constant leaves after the 29 s
    since the step (6e-5 of it measured)."""
    result, metrics = scenarios.run("tp", {"flight": "tilt", "tilt_deg": 5.0, "duration": 30.0, "rotor_drag": drag})
    pitch = metrics["accelerometer_tilt_final_deg"]
    assert metrics["true_tilt_final_deg"] == pytest.approx(5.0, abs=1e-6)
    assert metrics["true_tilt_final_deg"] == np.degrees(result["Quadrotor.theta2"][-1])
    if drag:
        assert abs(pitch - metrics["true_tilt_final_deg"]) < 0.01
        steady = steady_speed(np.radians(5.0))
        lagged = steady * (1.0 - np.exp(-(30.0 - profiles.STEP_TIME) / metrics["tilt_lag_predicted_s"]))
        print(f"speed {metrics['speed_final_m_s']:.5f} m/s: steady {steady:.5f}, after the lag {lagged:.5f}")
        assert metrics["speed_final_m_s"] == pytest.approx(lagged, rel=1.2e-4)  # 6e-5 measured
        # Martin and Salaun (2010): the accelerometer's tilt follows the true tilt through
        # 1/(1 + tau s), tau = m / (k_d sum|omega_n|): fitted 4.257 s against 4.250 s predicted
        assert metrics["tilt_lag_fitted_s"] == pytest.approx(metrics["tilt_lag_predicted_s"], rel=0.003)
        assert metrics["tilt_lag_predicted_s"] == pytest.approx(
            trim.drag_time_constant(thrust=result["Quadrotor.thrust"][-1]), rel=1e-12)
    else:
        assert abs(pitch) < 1e-9 and abs(result["Quadrotor.v"][-1, 0]) > 20.0  # still accelerating
        assert "tilt_lag_fitted_s" not in metrics


def test_position_hold_in_steady_wind_at_the_tilt_that_balances_drag():
    """3 m/s north wind, position hold: the integral brings the position back (0.5 m at most on
    the way) and the vehicle leans into the wind at the predicted tilt (4.118 deg, agreement 1e-8)."""
    result, metrics = scenarios.run("tp", {"flight": "hover", "wind_n": 3.0, "duration": 40.0})
    predicted, _ = trim.wind_hover_tilt(3.0)
    assert np.degrees(result["Quadrotor.theta2"][-1]) == pytest.approx(np.degrees(predicted), rel=1e-4)
    assert metrics["wind_tilt_final_deg"] == pytest.approx(metrics["wind_tilt_predicted_deg"], rel=1e-4)
    assert metrics["position_error_final_mm"] < 0.1 and metrics["drift_max_m"] < 0.6  # measured 0.030 mm, 0.51 m
    assert abs(result["Quadrotor.theta1"][-1]) < 1e-9
    assert np.abs(result["Quadrotor.p"][-1, :2]).max() < 1e-4  # m, position held (measured 3.0e-5)
    assert_bounds(result, "Quadrotor.p_x", lower=-0.6, upper=0.6)  # m, blown off at most


def test_without_integral_action_the_wind_pushes_the_vehicle_off():
    """Ablation of the integral: with ki_xy = 0 the PD hold settles downwind, by the drag force
    over kp_xy (0.72 m predicted from the trim)."""
    system = scenarios.get("tp").build(scenarios.get("tp").parse({"flight": "hover", "wind_n": 3.0, "duration": 40.0}))
    system.blocks["Controller"].parameters[law.P_KIXY] = 0.0
    result = system.run(40.0)
    tilt, _ = trim.wind_hover_tilt(3.0)
    offset = np.tan(tilt) * vehicle.GRAVITY / GAINS["kp_xy"][0]  # m: kp_xy e = g tan(tilt)
    assert result["Quadrotor.p"][-1, 0] == pytest.approx(offset, rel=0.02)


def test_a_12_rad_s_yaw_loop_at_100_hz_rings_until_the_free_wheeling_currents_reach_zero():
    """At a 100 Hz loop rate a 12 rad/s yaw loop is unstable: an 18 Hz oscillation grows from
    rounding error in hover until the motor currents reach zero, where a free-wheeling ESC
    holds them (it cannot brake); the ESC commands never reach their bounds. 8 rad/s at 100 Hz
    and 12 rad/s at 1 kHz stay quiet (rounding error, 1e-17 N m measured; quiet is below 1e-3),
    and so does 24 rad/s at 100 Hz without the rotors' reaction torque (Quadrotor.J_r = 0): the
    cause. Measured: ringing 2.2e-2 N m at 18.5 Hz; commands 0.403-0.508 in hover, 0.347-0.582
    in non-stationary flight; the hover current 3.78 A when quiet."""
    from quadcosim.studies.yaw_loop import QUIET_NM, yaw_loop

    ringing, flying = yaw_loop(100.0, 12.0), yaw_loop(100.0, 12.0, "nonstationary")
    quiet, fast = yaw_loop(100.0, 8.0), yaw_loop(1000.0, 12.0)
    no_reaction = yaw_loop(100.0, 24.0, "hover", {"Quadrotor.J_r": 0.0})
    for name, case in (("100 Hz, 12 rad/s", ringing), ("100 Hz, 12 rad/s, flying", flying),
                       ("100 Hz, 8 rad/s", quiet), ("1 kHz, 12 rad/s", fast),
                       ("100 Hz, 24 rad/s, no reaction torque", no_reaction)):
        print(name, {k: round(v, 4) if isinstance(v, float) else v for k, v in case.items()})
    assert 1.1e-2 < ringing["ringing_nm"] < 4.4e-2 and 17.5 < ringing["ring_hz"] < 19.5
    assert ringing["current_min_a"] == pytest.approx(0.0, abs=1e-9)  # the free-wheeling bound
    assert 0.35 < ringing["command_min"] and ringing["command_max"] < 0.55
    assert 0.3 < flying["command_min"] < 0.4 and 0.55 < flying["command_max"] < 0.65  # inside [0, 1]
    hover_current = vehicle.steady_current(vehicle.hover_rotor_speed())
    for case in (quiet, fast, no_reaction):
        assert case["ringing_nm"] < QUIET_NM
        assert case["current_min_a"] == pytest.approx(hover_current, rel=1e-3)


def test_the_trim_root_is_scipys_brentq_to_the_bit():
    """The cruise trim solves its root without importing scipy.optimize (start-up), by the same
    steps: every winds' tilt, and a few other roots, equal brentq's bits."""
    import math

    from scipy.optimize import brentq

    roots = [(lambda x: x * x - 2.0, 0.0, 3.0), (lambda x: math.cos(x) - x, 0.0, 1.0),
             (lambda x: x ** 3 - 2.0 * x - 5.0, 2.0, 3.0), (lambda x: math.exp(x) - 10.0, -5.0, 10.0),
             (lambda x: math.atan(x - 0.3), -10.0, 1e3)]
    for f, a, b in roots:
        for xtol in (2e-12, 1e-14, 1e-3):
            assert trim.brent_root(f, a, b, xtol) == brentq(f, a, b, xtol=xtol)
    for wind in np.linspace(0.05, 20.0, 40):
        tilt, thrust = trim.wind_hover_tilt(wind)
        original = trim.brent_root
        try:
            trim.brent_root = lambda f, a, b, xtol: brentq(f, a, b, xtol=xtol)
            assert (tilt, thrust) == trim.wind_hover_tilt(wind)
        finally:
            trim.brent_root = original
    with pytest.raises(ValueError, match="different signs"):
        trim.brent_root(lambda x: x * x + 1.0, -1.0, 1.0)


def test_an_attitude_step_is_measured_on_every_axis_stepped():
    """flight=step on all three axes: the lab's gains (kp = 144 1/s^2, kd = 19.2 1/s, damping 0.8;
    yaw 64 and 12.8, slower) settle every axis to the step, with the overshoot of a damping of
    0.8 or less; yaw rises and settles later than roll and pitch."""
    import control

    _, metrics = scenarios.run("tp", {"flight": "step", "step_axis": "all", "step_deg": 5.0, "step_time": 0.5,
                                      "duration": 2.0})
    rise, settling = np.array(metrics["step_rise_time_s"]), np.array(metrics["step_settling_time_s"])
    overshoot, steady = np.array(metrics["step_overshoot_pct"]), np.array(metrics["step_steady_error_deg"])
    # measured: rise 0.16 / 0.16 / 0.40 s, settling 0.31 / 0.28 / 0.60 s, overshoot 0.1 / 1.3 / 1.6 %
    assert np.all(rise > 0.05) and np.all(settling < 1.0) and np.all(settling > rise)
    assert rise[2] > 1.5 * max(rise[:2]) and settling[2] > max(settling[:2])
    bound = control.step_info(control.tf([144.0], [1.0, 19.2, 144.0]))["Overshoot"]  # 1.5 %
    assert np.all(overshoot < 2 * bound) and np.all(np.abs(steady) < 0.05)  # 1 % of the step; measured 0.023
    assert metrics["step_settling_worst_s"] == settling.max()
    _, pitched = scenarios.run("tp", {"flight": "step", "duration": 1.5})  # the default: pitch only
    assert pitched["step_rise_time_s"][0] is None and pitched["step_rise_time_s"][1] > 0.05
