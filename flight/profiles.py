"""Flight profiles: the setpoint tables the ``Setpoint`` block plays to the controller.

Each row is ``SETPOINT``: roll, pitch, yaw (rad), ``x_d, y_d, z_d`` (m, NED, so up is
negative), ``hold`` (1: hold the horizontal position and derive roll and pitch from it;
0: fly the roll and pitch setpoints). Every profile eases in over its first seconds.

- ``hover``: hold the origin.
- ``quasi`` (quasi-stationary, the lab's definition): small, slow attitude and position
  changes about a steady flight. The vehicle starts in trimmed cruise, 2 m/s north, pitched
  nose-down by the angle at which rotor drag balances the tilted thrust (2.75 degrees,
  :func:`quadcosim.flight.trim.wind_hover_tilt`), and flies slow variations about it: pitch
  1 degree at 0.02 Hz, roll 1 degree at 0.015 Hz, yaw 10 degrees at 0.01 Hz, altitude 0.5 m at
  0.05 Hz, without position hold. Its velocity stays near the steady one (the variations are
  slow against the drag's 4.2 s time constant), so the accelerometer, which reads gravity
  minus acceleration, sees the tilt. Without rotor drag the same setpoints accelerate the
  vehicle for ever and the accelerometer never sees the tilt.
- ``nonstationary``: large, fast attitude changes and accelerations: roll and pitch of 20
  degrees at 0.4 and 0.3 Hz, yaw of 30 degrees at 0.1 Hz, altitude of 1 m at 0.2 Hz, no
  position hold. The accelerometer then measures much more than gravity.
- ``tilt``: level hover, then from ``STEP_TIME`` a constant pitch setpoint ``tilt`` (rad)
  held with no position hold, so the vehicle accelerates until the drag balances the
  tilted thrust (a tilt step, for the accelerometer's first-order lag).
- ``step``: level hover without position hold, then at ``step_time`` an attitude step of
  ``step`` (rad) on the axes ``step_axis`` (``roll``, ``pitch``, ``yaw`` or ``all``), the
  altitude held: the response a control engineer tunes on (rise, settling, overshoot).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from quadcosim.flight import trim

EASE_IN = 2.0  # s, ramp of the periodic profiles
STEP_TIME = 1.0  # s, start of the tilt step
DEG = math.pi / 180.0  # rad per degree

# quasi-stationary
CRUISE_SPEED = 2.0  # m/s, north
QUASI_PITCH, QUASI_PITCH_FREQUENCY = 1.0 * DEG, 0.02  # rad, Hz, about the cruise pitch
QUASI_ROLL, QUASI_ROLL_FREQUENCY = 1.0 * DEG, 0.015  # rad, Hz
QUASI_YAW, QUASI_YAW_FREQUENCY = 10.0 * DEG, 0.01  # rad, Hz
QUASI_HEAVE, QUASI_HEAVE_FREQUENCY = 0.5, 0.05  # m, Hz
# non-stationary
FAST_ROLL, FAST_ROLL_FREQUENCY = 20.0 * DEG, 0.4  # rad, Hz
FAST_PITCH, FAST_PITCH_FREQUENCY, FAST_PITCH_PHASE = 20.0 * DEG, 0.3, 0.5  # rad, Hz, rad
FAST_YAW, FAST_YAW_FREQUENCY = 30.0 * DEG, 0.1  # rad, Hz
FAST_HEAVE, FAST_HEAVE_FREQUENCY = 1.0, 0.2  # m, Hz

FLIGHTS = ("quasi", "nonstationary", "hover", "tilt", "step")
STEP_AXES = {"roll": (0,), "pitch": (1,), "yaw": (2,), "all": (0, 1, 2)}  # attitude columns a step moves


@lru_cache
def cruise_pitch(speed: float = CRUISE_SPEED) -> float:
    """Pitch (rad, negative: nose down) of steady level flight north at ``speed`` (m/s) with the
    default vehicle's drag: the hover-in-wind trim mirrored (the airspeed is the same)."""
    return -trim.wind_hover_tilt(speed)[0]


def initial_state(flight: str) -> dict:
    """Initial condition of the profile ``flight``, as Quadrotor FMU parameters: the trimmed
    cruise of ``quasi`` (velocity m/s, pitch rad), rest otherwise."""
    if flight == "quasi":
        return {"v_x0": CRUISE_SPEED, "theta2_0": cruise_pitch()}
    return {}


def _sine(amplitude, frequency, t, phase=0.0):
    return amplitude * np.sin(2.0 * np.pi * frequency * t + phase)


def profile(flight: str, duration: float, dt: float, tilt: float = 5.0 * DEG) -> np.ndarray:
    """Setpoint table of the profile ``flight`` at 0, dt, ..., duration (s), the ``tilt`` profile
    pitched by ``tilt`` (rad): see :func:`profile_at`.

    Returns
    -------
    (n, 7) ndarray
        Rows of ``SETPOINT``.
    """
    return profile_at(flight, np.arange(int(round(duration / dt)) + 1) * dt, tilt)


def step_sizes(flight: str, axis: str = "pitch", size: float = 5.0 * DEG, tilt: float = 5.0 * DEG) -> list:
    """The attitude step of a profile on roll, pitch and yaw (rad; None on an axis it does not
    step): ``flight=step`` on ``axis`` by ``size``, ``flight=tilt`` on pitch by ``tilt``; None
    for a profile without a step."""
    if flight == "step":
        return [size if i in STEP_AXES[axis] else None for i in range(3)]
    if flight == "tilt":
        return [None, tilt, None]
    return None


def profile_at(flight: str, t: np.ndarray, tilt: float = 5.0 * DEG, step_axis: str = "pitch",
               step: float = 5.0 * DEG, step_time: float = STEP_TIME) -> np.ndarray:
    """Setpoints of a flight profile at times ``t`` (s). A ``Table`` evaluates it a chunk of
    rows at a time, so that a long run never holds its whole profile.

    Parameters
    ----------
    flight : str
        One of :data:`FLIGHTS` (see the module docstring).
    t : ndarray
        Times (s).
    tilt : float
        Pitch of the ``tilt`` profile (rad); ignored by the others.
    step_axis, step, step_time : str, float, float
        The ``step`` profile's axes (:data:`STEP_AXES`), size (rad) and time (s).

    Returns
    -------
    (len(t), 7) ndarray
        Rows of ``SETPOINT``: roll, pitch, yaw (rad), x_d, y_d, z_d (m, NED), hold (1 or 0).
    """
    ramp = np.clip(t / EASE_IN, 0.0, 1.0)
    zero, one = np.zeros_like(t), np.ones_like(t)
    if flight == "hover":
        return np.column_stack([zero, zero, zero, zero, zero, zero, one])
    if flight == "quasi":
        roll = _sine(QUASI_ROLL, QUASI_ROLL_FREQUENCY, t)
        pitch = cruise_pitch() + _sine(QUASI_PITCH, QUASI_PITCH_FREQUENCY, t)
        yaw = _sine(QUASI_YAW, QUASI_YAW_FREQUENCY, t)
        z = -_sine(QUASI_HEAVE, QUASI_HEAVE_FREQUENCY, t)
        return np.column_stack([roll, pitch, yaw, zero, zero, z, zero])
    if flight == "nonstationary":
        roll = _sine(FAST_ROLL, FAST_ROLL_FREQUENCY, t)
        pitch = _sine(FAST_PITCH, FAST_PITCH_FREQUENCY, t, FAST_PITCH_PHASE)
        yaw = _sine(FAST_YAW, FAST_YAW_FREQUENCY, t)
        z = -_sine(FAST_HEAVE, FAST_HEAVE_FREQUENCY, t)
        return np.column_stack([roll * ramp, pitch * ramp, yaw * ramp, zero, zero, z * ramp, zero])
    if flight == "tilt":
        pitch = np.where(t >= STEP_TIME, tilt, 0.0)
        return np.column_stack([zero, pitch, zero, zero, zero, zero, zero])
    if flight == "step":
        stepped = np.where(t >= step_time, step, 0.0)
        angles = [stepped if i in STEP_AXES[step_axis] else zero for i in range(3)]
        return np.column_stack([*angles, zero, zero, zero, zero])
    raise ValueError(f"flight {flight!r} must be one of {', '.join(FLIGHTS)}")
