"""Flight profiles, the attitude and altitude controller, and the mixer.

The controller is a block like the others: ``Controller`` takes the setpoint (roll, pitch,
yaw in rad; position ``x_d, y_d, z_d`` in m, NED so up is negative; ``hold`` = 1 to hold the
horizontal position, 0 to fly the roll and pitch setpoints), an attitude ``q0..q3`` and body
rates ``omega_x/y/z`` (from the ground truth in "gt" mode, from ``Quaternion_estim`` in
"estimate" mode), the position and velocity from the ground truth and the battery voltage
``u_batt``, and outputs the ESC commands ``c1..c4``.

Why hold the position: with thrust along -z_B and no drag, a multirotor's accelerometer
reads ``(0, 0, -T/m)`` whatever its tilt; it measures the direction of gravity only while
the vehicle does not accelerate. Quasi-stationary flight is therefore a position hold
(changes of yaw and altitude); non-stationary flight flies large roll and pitch setpoints.

Law (per sample):
- position hold: ``a = kp_xy (x_d - x) - kd_xy v`` (horizontal, NED), turned into roll and
  pitch setpoints in the yaw frame, ``theta1_d = a_right / g``, ``theta2_d = -a_forward / g``,
  limited to 20 degrees;
- attitude: ``q_e = q_d* (x) q``, ``e = 2 sign(q_e0) q_e,v``,
  ``tau = J (-Kp e - Kd omega) + omega x J omega``;
- altitude: ``a_z = kp_z (z_d - p_z) - kd_z v_z``, ``T = m (g - a_z) / R33``;
- mixer: ``[T, tau] = M [T_1..T_4]`` from the airframe (fmus/airframe.py), inverted, each
  rotor thrust saturated to ``[0, T_max]``, ``omega_n = sqrt(T_n / k_f)``;
- ESC command: the motors' steady-state map at the present battery voltage,
  ``c_n = (R k_m omega_n^2 / k_e + k_e omega_n) / u_batt``, saturated to ``[0, 1]``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from estimators.core import euler_to_quaternion
from fmus import vehicle
from fmus.airframe import MOTORS
from orchestrator.blocks import Block

SETPOINT = ("theta_d1", "theta_d2", "theta_d3", "x_d", "y_d", "z_d", "hold")
# gains, with units
ATTITUDE_KP = 144.0  # 1/s^2, natural frequency 12 rad/s
ATTITUDE_KD = 19.2  # 1/s, damping 0.8
ALTITUDE_KP = 9.0  # 1/s^2
ALTITUDE_KD = 5.4  # 1/s
POSITION_KP = 1.0  # 1/s^2
POSITION_KD = 1.8  # 1/s
MAX_TILT = math.radians(20.0)  # rad, of the position loop
MAX_ROTOR_SPEED = 1000.0  # rad/s, full throttle on a charged 3S battery

# parameter vector of the law
(P_MASS, P_JX, P_JY, P_JZ, P_KP, P_KD, P_KPZ, P_KDZ, P_G, P_KF, P_TMAX, P_RM, P_KE, P_KM, P_KPXY, P_KDXY,
 P_TILT) = range(17)
P_MIX = 17  # 16 entries: the inverse mixer, row-major
PARAMETER_SIZE = 33


def mixer_matrix(arm=vehicle.ARM, k_f=vehicle.THRUST_COEFF, k_m=vehicle.DRAG_TORQUE_COEFF) -> np.ndarray:
    """M with [T, tau_x, tau_y, tau_z] = M [T_1, ..., T_4] (rotor thrusts, N)."""
    rows = [[1.0] * 4,
            [-arm * m.direction[1] for m in MOTORS],
            [arm * m.direction[0] for m in MOTORS],
            [k_m / k_f * m.spin for m in MOTORS]]
    return np.array(rows)


def parameters(gains: dict | None = None) -> np.ndarray:
    g = {"kp": ATTITUDE_KP, "kd": ATTITUDE_KD, "kp_z": ALTITUDE_KP, "kd_z": ALTITUDE_KD, "kp_xy": POSITION_KP,
         "kd_xy": POSITION_KD} | (gains or {})
    p = np.zeros(PARAMETER_SIZE)
    p[P_MASS], (p[P_JX], p[P_JY], p[P_JZ]) = vehicle.MASS, vehicle.INERTIA
    p[P_KP], p[P_KD], p[P_KPZ], p[P_KDZ] = g["kp"], g["kd"], g["kp_z"], g["kd_z"]
    p[P_G], p[P_KF] = vehicle.GRAVITY, vehicle.THRUST_COEFF
    p[P_TMAX] = vehicle.THRUST_COEFF * MAX_ROTOR_SPEED**2
    p[P_RM], p[P_KE], p[P_KM] = vehicle.MOTOR_RESISTANCE, vehicle.MOTOR_KE, vehicle.DRAG_TORQUE_COEFF
    p[P_KPXY], p[P_KDXY], p[P_TILT] = g["kp_xy"], g["kd_xy"], MAX_TILT
    p[P_MIX:P_MIX + 16] = np.linalg.inv(mixer_matrix()).ravel()
    return p


@njit(cache=True, error_model="numpy")
def control_law(u, p, y):
    """u: setpoint[7], q[4], omega[3], p[3], v[3], u_batt; y: c[4], T, tau[3], theta_d[2]."""
    roll_d, pitch_d, yaw = u[0], u[1], u[2]
    if u[6] > 0.5:  # hold the horizontal position
        ax = p[P_KPXY] * (u[3] - u[14]) - p[P_KDXY] * u[17]
        ay = p[P_KPXY] * (u[4] - u[15]) - p[P_KDXY] * u[18]
        forward = math.cos(yaw) * ax + math.sin(yaw) * ay
        right = -math.sin(yaw) * ax + math.cos(yaw) * ay
        roll_d = min(max(right / p[P_G], -p[P_TILT]), p[P_TILT])
        pitch_d = min(max(-forward / p[P_G], -p[P_TILT]), p[P_TILT])
    d0, d1, d2, d3 = euler_to_quaternion(roll_d, pitch_d, yaw)
    q0, q1, q2, q3 = u[7], u[8], u[9], u[10]
    # q_e = conj(q_d) (x) q
    e0 = d0 * q0 + d1 * q1 + d2 * q2 + d3 * q3
    e1 = d0 * q1 - d1 * q0 - d2 * q3 + d3 * q2
    e2 = d0 * q2 + d1 * q3 - d2 * q0 - d3 * q1
    e3 = d0 * q3 - d1 * q2 + d2 * q1 - d3 * q0
    sign = 2.0 if e0 >= 0.0 else -2.0
    wx, wy, wz = u[11], u[12], u[13]
    jx, jy, jz = p[P_JX], p[P_JY], p[P_JZ]
    tx = jx * (-p[P_KP] * sign * e1 - p[P_KD] * wx) + (jz - jy) * wy * wz
    ty = jy * (-p[P_KP] * sign * e2 - p[P_KD] * wy) + (jx - jz) * wz * wx
    tz = jz * (-p[P_KP] * sign * e3 - p[P_KD] * wz) + (jy - jx) * wx * wy
    r33 = max(1.0 - 2.0 * (q1 * q1 + q2 * q2), 0.5)
    a_z = p[P_KPZ] * (u[5] - u[16]) - p[P_KDZ] * u[19]
    thrust = p[P_MASS] * (p[P_G] - a_z) / r33
    u_batt = max(u[20], 1.0)
    for n in range(4):
        m = P_MIX + 4 * n
        t_n = p[m] * thrust + p[m + 1] * tx + p[m + 2] * ty + p[m + 3] * tz
        t_n = min(max(t_n, 0.0), p[P_TMAX])
        w = math.sqrt(t_n / p[P_KF])
        c = (p[P_RM] * p[P_KM] * w * w / p[P_KE] + p[P_KE] * w) / u_batt
        y[n] = min(max(c, 0.0), 1.0)
    y[4], y[5], y[6], y[7] = thrust, tx, ty, tz
    y[8], y[9] = roll_d, pitch_d


class Controller(Block):
    """Attitude and altitude controller with mixer and ESC map (see the module docstring)."""

    inputs = SETPOINT + ("q0", "q1", "q2", "q3", "omega_x", "omega_y", "omega_z", "p_x", "p_y", "p_z", "v_x", "v_y",
                         "v_z", "u_batt")
    outputs = ("c1", "c2", "c3", "c4", "thrust", "tau_x", "tau_y", "tau_z", "theta_d1", "theta_d2")

    def __init__(self, name: str = "Controller", period: int = 1, gains: dict | None = None):
        super().__init__(name, period)
        for key, value in (gains or {}).items():
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"controller gain {key} = {value} must be finite and non-negative")
        self.parameters = parameters(gains)

    def start(self, t0, dt):
        law, p = control_law, self.parameters
        law(np.zeros(len(self.inputs)), p, np.empty(len(self.outputs)))  # compile before the run

        def step(t, u, y):
            law(u, p, y)

        self.step = step


def profile(flight: str, duration: float, dt: float) -> np.ndarray:
    """Setpoint table (n, 7): roll, pitch, yaw (rad), x_d, y_d, z_d (m, NED), hold (1 or 0)."""
    t = np.arange(int(round(duration / dt)) + 1) * dt
    ramp = np.clip(t / 2.0, 0.0, 1.0)  # ease in over the first 2 s
    zero = np.zeros_like(t)
    d = np.radians
    if flight == "hover":
        # hold the position, the yaw and the altitude
        return np.column_stack([zero, zero, zero, zero, zero, zero, np.ones_like(t)])
    if flight == "quasi":
        # hover on the spot: slow changes of yaw and altitude, roll and pitch from the position hold
        yaw = d(20.0) * np.sin(2 * np.pi * 0.02 * t)
        z = -0.5 * np.sin(2 * np.pi * 0.05 * t)
        return np.column_stack([zero, zero, yaw * ramp, zero, zero, z * ramp, np.ones_like(t)])
    if flight == "nonstationary":
        # large, fast attitude changes and accelerations
        roll = d(20.0) * np.sin(2 * np.pi * 0.4 * t)
        pitch = d(20.0) * np.sin(2 * np.pi * 0.3 * t + 0.5)
        yaw = d(30.0) * np.sin(2 * np.pi * 0.1 * t)
        z = -1.0 * np.sin(2 * np.pi * 0.2 * t)
        return np.column_stack([roll * ramp, pitch * ramp, yaw * ramp, zero, zero, z * ramp, zero])
    raise ValueError(f"flight {flight!r} must be 'hover', 'quasi' or 'nonstationary'")
