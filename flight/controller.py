"""Attitude, altitude and position-hold controller of the closed loop, with the mixer.

``Controller`` is a block like the others. It takes the setpoint (roll, pitch, yaw in rad;
position ``x_d, y_d, z_d`` in m, NED so up is negative; ``hold`` = 1 to hold the horizontal
position, 0 to fly the roll and pitch setpoints), an attitude ``q0..q3`` and body rates
``omega_x/y/z`` (from the ground truth in "gt" mode, from ``Quaternion_estim`` in "estimate"
mode), the position and velocity from the ground truth, and the battery voltage ``u_batt``;
it outputs the ESC commands ``c1..c4``, the thrust and torques it asked for, and the roll
and pitch setpoints it flew.

Law, per sample of period ``dt``:

- position hold (when ``hold``): PID on the horizontal position error ``e = x_d - x`` (NED),
  ``a = kp_xy e + ki_xy int(e) - kd_xy v``, turned into roll and pitch setpoints in the yaw
  frame, ``theta1_d = atan(a_right / g)``, ``theta2_d = -atan(a_forward / g)``, limited to
  ``max_tilt``. The integral is what holds position in a steady wind: the force to cancel is
  rotor drag on the *airspeed*, and the controller knows the ground speed only, so a drag
  feedforward would need a wind estimate; the integral needs none. It is clamped to what the
  tilt limit can deliver (anti-windup) and frozen while the profile flies attitude setpoints.
- attitude: ``q_e = q_d* (x) q``, ``e = 2 sign(q_e0) q_e,v``,
  ``tau = J (-K_p e - K_d omega) + omega x J omega``, ``K_p = diag(kp, kp, kp_yaw)``, ``K_d`` alike.
  Yaw is slower (8 against 12 rad/s): the rotors' reaction to their own acceleration,
  ``J_r dω/dt``, acts in the sense of the drag torque and makes the yaw actuator's first
  30 ms about 7 times stronger than ``k_m ω^2`` says (``J_r / (2 k_m ω τ_motor)``). With the
  whole loop at 100 Hz, a yaw loop above 11 rad/s is unstable: at 12 rad/s an 18 Hz
  oscillation grows until the motor currents reach zero, where free-wheeling ESCs hold them
  (the ESC commands stay inside [0, 1]: 0.35 to 0.58 in non-stationary flight); 8 rad/s is
  quiet, and so is 12 rad/s at 1 kHz (:mod:`quadcosim.studies.yaw_loop` measures it);
- altitude: ``a_z = kp_z (z_d - p_z) - kd_z v_z``, ``T = m (g - a_z) / R33``;
- mixer: ``[T_1..T_4] = M^-1 [T, tau]`` (:func:`quadcosim.flight.mixer.allocation_matrix`),
  each rotor thrust saturated to ``[0, T_max]``, ``omega_n = sqrt(T_n / k_f)``, and the ESC
  command from the motors' steady-state map at the present battery voltage, saturated to
  ``[0, 1]``.

The compiled law reads its inputs, outputs and parameters through the named slots below,
each derived from the declared names.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from quadcosim.estimators.quaternions import euler_to_quaternion
from quadcosim.flight.mixer import allocation_matrix, esc_command
from quadcosim.fmus import vehicle
from quadcosim.orchestrator import portable
from quadcosim.orchestrator.blocks import Block
from quadcosim.orchestrator.fmu import nearest

SETPOINT = ("theta_d1", "theta_d2", "theta_d3", "x_d", "y_d", "z_d", "hold")
INPUTS = SETPOINT + ("q0", "q1", "q2", "q3", "omega_x", "omega_y", "omega_z", "p_x", "p_y", "p_z",
                     "v_x", "v_y", "v_z", "u_batt")
OUTPUTS = ("c1", "c2", "c3", "c4", "thrust", "tau_x", "tau_y", "tau_z", "theta_d1", "theta_d2")
#: Units of the outputs and of the setpoint, as the variable tables write them.
UNITS = {"c1": "1", "c2": "1", "c3": "1", "c4": "1", "thrust": "N", "tau_x": "N.m", "tau_y": "N.m", "tau_z": "N.m",
         "theta_d1": "rad", "theta_d2": "rad"}
SETPOINT_UNITS = {"theta_d1": "rad", "theta_d2": "rad", "theta_d3": "rad", "x_d": "m", "y_d": "m", "z_d": "m",
                  "hold": "1"}

#: Gains: name -> (default, unit, meaning). Only these names are accepted.
GAINS = {
    "kp": (144.0, "1/s^2", "attitude, proportional (natural frequency 12 rad/s)"),
    "kd": (19.2, "1/s", "attitude, derivative (damping 0.8)"),
    "kp_yaw": (64.0, "1/s^2", "yaw, proportional (natural frequency 8 rad/s)"),
    "kd_yaw": (12.8, "1/s", "yaw, derivative (damping 0.8)"),
    "kp_z": (9.0, "1/s^2", "altitude, proportional"),
    "kd_z": (5.4, "1/s", "altitude, derivative"),
    "kp_xy": (1.0, "1/s^2", "position hold, proportional"),
    "kd_xy": (1.8, "1/s", "position hold, derivative"),
    "ki_xy": (0.3, "1/s^3", "position hold, integral (steady wind)"),
}
MAX_TILT = math.radians(20.0)  # rad, largest roll or pitch the position hold asks for
MAX_ROTOR_SPEED = 1000.0  # rad/s, full throttle on a charged 3S battery
MIN_THRUST_COSINE = 0.5  # 1, floor of R33 in T = m (g - a_z) / R33 (no thrust boost past 60 deg)
MIN_BATTERY_VOLTAGE = 1.0  # V, floor of the voltage the ESC map divides by

#: Parameters of the compiled law, by name; gains follow the vehicle constants.
PARAMETERS = ("mass", "jx", "jy", "jz", "gravity", "thrust_coeff", "max_rotor_thrust", "resistance", "ke",
              "drag_torque_coeff", "max_tilt") + tuple(GAINS)


def _slot(names: tuple, *members: str) -> int:
    """Index of ``members[0]`` in ``names``, checking that the members follow it in order."""
    first = names.index(members[0])
    if names[first:first + len(members)] != members:
        raise AssertionError(f"{members} are not contiguous in {names}")
    return first


# inputs
U_ROLL_D, U_PITCH_D, U_YAW_D = (_slot(INPUTS, n) for n in ("theta_d1", "theta_d2", "theta_d3"))
U_X_D, U_Y_D, U_Z_D, U_HOLD = (_slot(INPUTS, n) for n in ("x_d", "y_d", "z_d", "hold"))
U_Q = _slot(INPUTS, "q0", "q1", "q2", "q3")
U_OMEGA = _slot(INPUTS, "omega_x", "omega_y", "omega_z")
U_P = _slot(INPUTS, "p_x", "p_y", "p_z")
U_V = _slot(INPUTS, "v_x", "v_y", "v_z")
U_BATT = _slot(INPUTS, "u_batt")
# outputs
Y_C = _slot(OUTPUTS, "c1", "c2", "c3", "c4")
Y_THRUST, Y_TAU = _slot(OUTPUTS, "thrust"), _slot(OUTPUTS, "tau_x", "tau_y", "tau_z")
Y_ROLL_D, Y_PITCH_D = _slot(OUTPUTS, "theta_d1"), _slot(OUTPUTS, "theta_d2")
# parameters
P_MASS, P_JX, P_JY, P_JZ = (_slot(PARAMETERS, n) for n in ("mass", "jx", "jy", "jz"))
P_G, P_KF, P_TMAX = (_slot(PARAMETERS, n) for n in ("gravity", "thrust_coeff", "max_rotor_thrust"))
P_RES, P_KE, P_KM = (_slot(PARAMETERS, n) for n in ("resistance", "ke", "drag_torque_coeff"))
P_TILT = _slot(PARAMETERS, "max_tilt")
P_KP, P_KD, P_KPZ, P_KDZ = (_slot(PARAMETERS, n) for n in ("kp", "kd", "kp_z", "kd_z"))
P_KPYAW, P_KDYAW = _slot(PARAMETERS, "kp_yaw"), _slot(PARAMETERS, "kd_yaw")
P_KPXY, P_KDXY, P_KIXY = (_slot(PARAMETERS, n) for n in ("kp_xy", "kd_xy", "ki_xy"))
# state
S_INT_X, S_INT_Y = 0, 1  # integral of the north and east position errors (m s)
STATE_SIZE = 2
# the block's memory, shared by its Python step and its compiled step: parameters, inverse
# allocation matrix (row-major), state, period (s)
MOTORS = 4
D_PARAMETERS, D_MIXER = 0, len(PARAMETERS)
D_STATE = D_MIXER + MOTORS * 4
D_DT = D_STATE + STATE_SIZE
DATA_SIZE = D_DT + 1


def parameters(gains: dict | None = None) -> np.ndarray:
    """Parameter vector of the law, in :data:`PARAMETERS` order, from the default vehicle
    (:mod:`quadcosim.fmus.vehicle`) and ``gains`` (names of :data:`GAINS`, their units).

    Raises
    ------
    ValueError
        On an unknown gain name (with the nearest valid one), a negative or non-finite gain, or
        a position loop that the integral gain destabilises (``ki_xy >= kp_xy kd_xy``).
    """
    gains = dict(gains or {})
    for key, value in gains.items():
        if key not in GAINS:
            raise ValueError(f"unknown controller gain {key!r}.{nearest(key, GAINS)} Gains: {', '.join(GAINS)}.")
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"controller gain {key} = {value} must be finite and non-negative")
    g = {name: spec[0] for name, spec in GAINS.items()} | gains
    if g["ki_xy"] > 0 and g["ki_xy"] >= g["kp_xy"] * g["kd_xy"]:
        raise ValueError(f"controller gain ki_xy = {g['ki_xy']} must be below kp_xy * kd_xy = "
                         f"{g['kp_xy'] * g['kd_xy']:g} for a stable position hold (Routh)")
    values = {"mass": vehicle.MASS, "jx": vehicle.INERTIA[0], "jy": vehicle.INERTIA[1], "jz": vehicle.INERTIA[2],
              "gravity": vehicle.GRAVITY, "thrust_coeff": vehicle.THRUST_COEFF,
              "max_rotor_thrust": vehicle.THRUST_COEFF * MAX_ROTOR_SPEED**2, "resistance": vehicle.MOTOR_RESISTANCE,
              "ke": vehicle.MOTOR_KE, "drag_torque_coeff": vehicle.DRAG_TORQUE_COEFF, "max_tilt": MAX_TILT} | g
    return np.array([values[name] for name in PARAMETERS])


@njit(cache=True, error_model="numpy")
def control_law(u, p, mixer_inverse, state, dt, y):
    """One sample of the law: inputs ``u`` (:data:`INPUTS`), parameters ``p`` (:data:`PARAMETERS`),
    the inverse allocation matrix ``mixer_inverse`` (each motor's thrust from the total thrust
    and the three torques), the integral ``state`` (updated), the period ``dt`` (s);
    writes the outputs ``y`` (:data:`OUTPUTS`)."""
    roll_d, pitch_d, yaw = u[U_ROLL_D], u[U_PITCH_D], u[U_YAW_D]
    g = p[P_G]
    if u[U_HOLD] > 0.5:  # hold the horizontal position
        ex, ey = u[U_X_D] - u[U_P], u[U_Y_D] - u[U_P + 1]
        if p[P_KIXY] > 0.0:
            limit = g * math.tan(p[P_TILT]) / p[P_KIXY]  # anti-windup: what the tilt limit can deliver
            state[S_INT_X] = min(max(state[S_INT_X] + ex * dt, -limit), limit)
            state[S_INT_Y] = min(max(state[S_INT_Y] + ey * dt, -limit), limit)
        ax = p[P_KPXY] * ex + p[P_KIXY] * state[S_INT_X] - p[P_KDXY] * u[U_V]
        ay = p[P_KPXY] * ey + p[P_KIXY] * state[S_INT_Y] - p[P_KDXY] * u[U_V + 1]
        forward = math.cos(yaw) * ax + math.sin(yaw) * ay
        right = -math.sin(yaw) * ax + math.cos(yaw) * ay
        roll_d = min(max(math.atan(right / g), -p[P_TILT]), p[P_TILT])
        pitch_d = min(max(-math.atan(forward / g), -p[P_TILT]), p[P_TILT])
    d0, d1, d2, d3 = euler_to_quaternion(roll_d, pitch_d, yaw)
    q0, q1, q2, q3 = u[U_Q], u[U_Q + 1], u[U_Q + 2], u[U_Q + 3]
    # q_e = conj(q_d) (x) q
    e0 = d0 * q0 + d1 * q1 + d2 * q2 + d3 * q3
    e1 = d0 * q1 - d1 * q0 - d2 * q3 + d3 * q2
    e2 = d0 * q2 + d1 * q3 - d2 * q0 - d3 * q1
    e3 = d0 * q3 - d1 * q2 + d2 * q1 - d3 * q0
    sign = 2.0 if e0 >= 0.0 else -2.0
    wx, wy, wz = u[U_OMEGA], u[U_OMEGA + 1], u[U_OMEGA + 2]
    jx, jy, jz = p[P_JX], p[P_JY], p[P_JZ]
    tx = jx * (-p[P_KP] * sign * e1 - p[P_KD] * wx) + (jz - jy) * wy * wz
    ty = jy * (-p[P_KP] * sign * e2 - p[P_KD] * wy) + (jx - jz) * wz * wx
    tz = jz * (-p[P_KPYAW] * sign * e3 - p[P_KDYAW] * wz) + (jy - jx) * wx * wy
    r33 = max(1.0 - 2.0 * (q1 * q1 + q2 * q2), MIN_THRUST_COSINE)
    a_z = p[P_KPZ] * (u[U_Z_D] - u[U_P + 2]) - p[P_KDZ] * u[U_V + 2]
    thrust = p[P_MASS] * (g - a_z) / r33
    u_batt = max(u[U_BATT], MIN_BATTERY_VOLTAGE)
    for n in range(mixer_inverse.shape[0]):  # one row per motor
        t_n = mixer_inverse[n, 0] * thrust + mixer_inverse[n, 1] * tx + mixer_inverse[n, 2] * ty \
            + mixer_inverse[n, 3] * tz
        t_n = min(max(t_n, 0.0), p[P_TMAX])
        c = esc_command(math.sqrt(t_n / p[P_KF]), u_batt, p[P_RES], p[P_KE], p[P_KM])
        y[Y_C + n] = min(max(c, 0.0), 1.0)
    y[Y_THRUST], y[Y_TAU], y[Y_TAU + 1], y[Y_TAU + 2] = thrust, tx, ty, tz
    y[Y_ROLL_D], y[Y_PITCH_D] = roll_d, pitch_d


class Controller(Block):
    """Attitude, altitude and position-hold controller with mixer and ESC map.

    Parameters
    ----------
    name : str
        Block name.
    period : int
        Runs every ``period`` macro steps.
    gains : dict, optional
        Overrides of :data:`GAINS` by name (units there); unknown names are refused.

    Notes
    -----
    Inputs :data:`INPUTS`, outputs :data:`OUTPUTS`; see the module docstring for the law.
    """

    inputs = INPUTS
    outputs = OUTPUTS
    units = UNITS
    #: The unit of each gain (``--set Controller.kp=...``), as :data:`GAINS` declares it.
    parameter_units = {name: unit for name, (_, unit, _) in GAINS.items()}

    def __init__(self, name: str = "Controller", period: int = 1, gains: dict | None = None):
        super().__init__(name, period)
        self.parameters = parameters(gains)
        self.mixer_inverse = portable.inverse(allocation_matrix())  # LAPACK's bits differ by CPU

    def parameter_values(self) -> dict:
        """The gains (:data:`GAINS`) by name, their present values; ``--set Controller.kp_yaw=50``
        sets one (:meth:`set_parameter`).

        Returns
        -------
        dict
            Gain name to value (units in :data:`GAINS`).
        """
        return {name: float(self.parameters[PARAMETERS.index(name)]) for name in GAINS}

    @classmethod
    def check_parameter(cls, name: str, value: float) -> float:
        """Gain ``name`` at ``value`` (its unit in :data:`GAINS`), checked with the other gains at
        their defaults, as :func:`parameters` checks it; refused with a ValueError."""
        parameters({name: float(value)})
        return float(value)

    def set_parameter(self, name: str, value: float):
        """Set gain ``name`` to ``value`` before the run, checked as :func:`parameters` checks.

        Parameters
        ----------
        name : str
            A name of :data:`GAINS`.
        value : float
            The gain, in its unit (:data:`GAINS`).
        """
        self.parameters = parameters(self.parameter_values() | {name: float(value)})

    def start(self, t0, dt):
        """Reset the integral; compile the law before the run. ``t0``: the start time (s);
        ``dt``: the block's period (s)."""
        self.data = np.zeros(DATA_SIZE)
        self.data[D_PARAMETERS:D_MIXER] = self.parameters
        self.data[D_MIXER:D_STATE] = self.mixer_inverse.ravel()
        self.data[D_DT] = dt
        law, p, mix = control_law, self.data[D_PARAMETERS:D_MIXER], self.data[D_MIXER:D_STATE].reshape(MOTORS, 4)
        state = self.data[D_STATE:D_DT]
        law(np.zeros(len(INPUTS)), p, mix, state, dt, np.empty(len(OUTPUTS)))
        state[:] = 0.0
        self.state = state

        def step(t, u, y):
            law(u, p, mix, state, dt, y)

        self.step = step

    def compiled(self):
        """The law as a C-callable step on the block's memory (see :meth:`Block.compiled`)."""
        from quadcosim.orchestrator.blocks import CompiledStep

        function = _compiled_step()
        return CompiledStep(function.address, np.zeros(len(INPUTS)), self.data, function)


def _compiled_step():
    """The numba ``cfunc`` of the law, compiled (or loaded from numba's cache) on first use."""
    global _COMPILED
    if _COMPILED is None:
        from numba import carray, cfunc
        from quadcosim.estimators import quaternions
        from quadcosim.flight import mixer
        from quadcosim.orchestrator.blocks import COMPILED_SIGNATURE, source_fingerprint

        sources = source_fingerprint(quaternions, mixer, vehicle)  # the files the law calls into: in the cache key

        @cfunc(COMPILED_SIGNATURE, cache=True, error_model="numpy")
        def step(t, u, y, data):
            memory = carray(data, DATA_SIZE)
            control_law(carray(u, len(INPUTS)), memory[D_PARAMETERS:D_MIXER],
                        memory[D_MIXER:D_STATE].reshape((MOTORS, 4)), memory[D_STATE:D_DT], memory[D_DT],
                        carray(y, len(OUTPUTS)))
            return sources & 0  # 0: done

        _COMPILED = step
    return _COMPILED


_COMPILED = None
