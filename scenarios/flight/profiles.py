"""Flight profiles: the setpoint tables the ``Setpoint`` block plays to the controller.

Each row is ``SETPOINT``: roll, pitch, yaw (rad), ``x_d, y_d, z_d`` (m, NED, so up is
negative), ``hold`` (1: hold the horizontal position and derive roll and pitch from it;
0: fly the roll and pitch setpoints). Every profile eases in over its first seconds.

- ``hover``: hold the origin.
- ``quasi`` (quasi-stationary, the lab's definition): small, slow attitude and position
  changes. The position setpoint draws a slow Lissajous figure from rest at the origin,
  ``x_d = A (1 - cos(2 pi f t))`` (A = 4 m; f = 0.04 Hz north, 0.03 Hz east), the yaw swings
  by 20 degrees at 0.02 Hz, the altitude by 0.5 m at 0.05 Hz. The position hold tilts the
  vehicle by a few degrees, slowly, so the vehicle stays near its steady velocity and, with
  rotor drag, its accelerometer sees the tilt.
- ``nonstationary``: large, fast attitude changes and accelerations: roll and pitch of 20
  degrees at 0.4 and 0.3 Hz, yaw of 30 degrees at 0.1 Hz, altitude of 1 m at 0.2 Hz, no
  position hold. The accelerometer then measures much more than gravity.
- ``tilt``: level hover, then from ``STEP_TIME`` a constant pitch setpoint ``tilt`` (rad)
  held with no position hold, so the vehicle accelerates until the drag balances the
  tilted thrust (a tilt step, for the accelerometer's first-order lag).
"""

from __future__ import annotations

import math

import numpy as np

EASE_IN = 2.0  # s, ramp of the periodic profiles
STEP_TIME = 1.0  # s, start of the tilt step
DEG = math.pi / 180.0  # rad per degree

# quasi-stationary
QUASI_RADIUS = 4.0  # m, amplitude of the north and east position setpoints
QUASI_FREQUENCY = (0.04, 0.03)  # Hz, north, east
QUASI_YAW, QUASI_YAW_FREQUENCY = 20.0 * DEG, 0.02  # rad, Hz
QUASI_HEAVE, QUASI_HEAVE_FREQUENCY = 0.5, 0.05  # m, Hz
# non-stationary
FAST_ROLL, FAST_ROLL_FREQUENCY = 20.0 * DEG, 0.4  # rad, Hz
FAST_PITCH, FAST_PITCH_FREQUENCY, FAST_PITCH_PHASE = 20.0 * DEG, 0.3, 0.5  # rad, Hz, rad
FAST_YAW, FAST_YAW_FREQUENCY = 30.0 * DEG, 0.1  # rad, Hz
FAST_HEAVE, FAST_HEAVE_FREQUENCY = 1.0, 0.2  # m, Hz

FLIGHTS = ("quasi", "nonstationary", "hover", "tilt")


def _sine(amplitude, frequency, t, phase=0.0):
    return amplitude * np.sin(2.0 * np.pi * frequency * t + phase)


def profile(flight: str, duration: float, dt: float, tilt: float = 5.0 * DEG) -> np.ndarray:
    """Setpoint table of a flight profile at 0, dt, ..., duration (s): see :func:`profile_at`.

    Returns
    -------
    (n, 7) ndarray
        Rows of ``SETPOINT``.
    """
    return profile_at(flight, np.arange(int(round(duration / dt)) + 1) * dt, tilt)


def profile_at(flight: str, t: np.ndarray, tilt: float = 5.0 * DEG) -> np.ndarray:
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
        north = QUASI_RADIUS - _sine(QUASI_RADIUS, QUASI_FREQUENCY[0], t, np.pi / 2)  # from rest
        east = QUASI_RADIUS - _sine(QUASI_RADIUS, QUASI_FREQUENCY[1], t, np.pi / 2)
        yaw = _sine(QUASI_YAW, QUASI_YAW_FREQUENCY, t)
        z = -_sine(QUASI_HEAVE, QUASI_HEAVE_FREQUENCY, t)
        return np.column_stack([zero, zero, yaw * ramp, north, east, z * ramp, one])
    if flight == "nonstationary":
        roll = _sine(FAST_ROLL, FAST_ROLL_FREQUENCY, t)
        pitch = _sine(FAST_PITCH, FAST_PITCH_FREQUENCY, t, FAST_PITCH_PHASE)
        yaw = _sine(FAST_YAW, FAST_YAW_FREQUENCY, t)
        z = -_sine(FAST_HEAVE, FAST_HEAVE_FREQUENCY, t)
        return np.column_stack([roll * ramp, pitch * ramp, yaw * ramp, zero, zero, z * ramp, zero])
    if flight == "tilt":
        pitch = np.where(t >= STEP_TIME, tilt, 0.0)
        return np.column_stack([zero, pitch, zero, zero, zero, zero, zero])
    raise ValueError(f"flight {flight!r} must be one of {', '.join(FLIGHTS)}")
