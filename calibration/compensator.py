"""Compensation of the motor currents' field (Metge et al., eq. 9) and a motor-dynamics-aware variant.

The mathematics is written once, in :func:`step` (compiled by numba), and used by both the
streaming :class:`MagCompensator` block (one call per macro step) and :func:`compensate` on
recorded arrays (a compiled loop over the same calls), so the two agree to round-off.

Eq. 9 of "Compensation dynamique des perturbations magnétiques pour l'estimation d'attitude
d'un micro-drone"::

    m_hat(t) = A^-1 (m_bar(t) - b_s - sum_n f(c_n(t), u(t); theta_n) v_n)

Modes:

- ``STATIC`` (0): ``b_d = 0``, the classical calibration alone;
- ``METGE`` (1): eq. 9 with the bi-polynomial of the command and the voltage;
- ``DYNAMIC`` (2): the commands pass through the identified motor dynamics
  (:class:`quadcosim.calibration.identify.MotorDynamics`): per motor a back-EMF state ``e`` (V) with
  ``de/dt = rate w - drag e |e|`` (DC motor, quasi-static current), the winding voltage
  ``w = clip(c u - e, low, limit)`` with ``low = 0`` when the ESC free-wheels (else
  ``-limit``), and the amplitude
  ``gain c^exponent w``, with the command and voltage held over the last step (the current at
  ``t`` answers the voltage applied before ``t``) (``exponent = 1``: the supply cable carries the ESC input current
  ``c i``; ``0``: the motor current ``i``). Integrated by Heun's method on the macro step.

The magnetometer is sampled and held at ``sample_rate`` (instants ``k / sample_rate``); the
compensator evaluates ``b_d`` at those instants and holds it, so a held reading is corrected
by the perturbation of its own instant.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from quadcosim.orchestrator.blocks import Block

STATIC, METGE, DYNAMIC = 0, 1, 2
MODES = {"static": STATIC, "metge": METGE, "dynamic": DYNAMIC}
# dynamics vector: rate (1/s), drag (1/(V s)), limit (V), exponent (0 or 1), freewheel (0 or 1), gains (T/V)
RATE, DRAG, LIMIT, EXPONENT, FREEWHEEL, GAINS = 0, 1, 2, 3, 4, 5


@njit(cache=True, error_model="numpy")
def steady_emf(c, u, rate, drag):
    """Back-EMF (V) at which de/dt = 0 for command ``c`` (1) and supply voltage ``u`` (V).

    ``rate`` (1/s) and ``drag`` (1/(V s)) are the identified motor dynamics
    ``de/dt = rate (c u - e) - drag e |e|``.
    """
    drive = max(c, 0.0) * u
    if drag <= 0.0:
        return drive
    return (-rate + math.sqrt(rate * rate + 4.0 * drag * rate * drive)) / (2.0 * drag)


@njit(cache=True, error_model="numpy")
def winding_voltage(drive, e, low, limit):
    """``c u - e`` (V) clipped by the ESC: at ``low`` (0 when it free-wheels, else ``-limit``) and
    at ``limit`` (the current limit times R); ``drive`` is ``c u`` (V), ``e`` the back-EMF (V)."""
    return min(max(drive - e, low), limit)


@njit(cache=True, error_model="numpy")
def _emf_rate(e, drive, rate, drag, low, limit):
    return rate * winding_voltage(drive, e, low, limit) - drag * e * abs(e)


@njit(cache=True, error_model="numpy")
def _amplitude_polynomial(c, u, theta, I, J):
    total = 0.0
    k = 0
    ci = 1.0
    for _ in range(I):
        ci *= c
        uj = 1.0
        for _ in range(J + 1):
            total += theta[k] * uj * ci
            uj *= u
            k += 1
    return total


@njit(cache=True, error_model="numpy")
def step(t, dt, mag, c, u, A_inv, b_s, v, theta, I, J, dynamics, mode, sample_rate, state, out):
    """One compensator update at time ``t`` (s) after a step ``dt`` (s).

    ``mag`` (3, T) raw reading; ``c`` (N, 1) commands and ``u`` (V) voltage at ``t``;
    ``state``: back-EMF ``[0:N]``, previous commands ``[N:2N]``, previous voltage ``[2N]``,
    held ``b_d`` ``[2N+1:2N+4]``, started flag ``[2N+4]``. Writes the compensated field to ``out``.
    The calibration: ``A_inv`` (3, 3) and ``b_s`` (3, T) the static (hard and soft iron)
    correction, ``v`` (N, 3) the motors' field directions (sensor frame), ``theta`` (N, I (J + 1))
    the amplitude coefficients of orders ``I``, ``J``, ``dynamics`` the identified motor
    dynamics (indices ``RATE``, ``DRAG``, ``LIMIT``, ``FREEWHEEL``, ``EXPONENT``, ``GAINS``).
    ``mode`` is ``STATIC``, ``METGE`` or ``DYNAMIC``; with ``sample_rate`` (Hz) > 0 the motor field
    is refreshed only at that rate's instants (held between), as the magnetometer samples.
    """
    n_motors = v.shape[0]
    held = 2 * n_motors + 1
    started = 2 * n_motors + 4
    limit = dynamics[LIMIT]
    low = 0.0 if dynamics[FREEWHEEL] > 0.5 else -limit
    if mode == DYNAMIC:
        rate, drag = dynamics[RATE], dynamics[DRAG]
        if state[started] == 0.0:
            for n in range(n_motors):
                state[n] = steady_emf(min(max(c[n], 0.0), 1.0), u, rate, drag)
        else:
            u0 = state[2 * n_motors]
            for n in range(n_motors):  # Heun on [t - dt, t] with the command held over the step
                drive = state[n_motors + n] * u0
                e = state[n]
                k1 = _emf_rate(e, drive, rate, drag, low, limit)
                k2 = _emf_rate(e + dt * k1, state[n_motors + n] * u, rate, drag, low, limit)
                state[n] = e + 0.5 * dt * (k1 + k2)
    sample = sample_rate <= 0.0 or abs(t * sample_rate - round(t * sample_rate)) < 1e-6 or state[started] == 0.0
    if sample:
        for a in range(3):
            state[held + a] = 0.0
        if mode != STATIC:
            for n in range(n_motors):
                if mode == METGE:
                    f = _amplitude_polynomial(min(max(c[n], 0.0), 1.0), u, theta[n], I, J)
                else:  # the current at t was driven by the command held over the last step
                    c_held = state[n_motors + n] if state[started] > 0.0 else min(max(c[n], 0.0), 1.0)
                    u_held = state[2 * n_motors] if state[started] > 0.0 else u
                    w = winding_voltage(c_held * u_held, state[n], low, limit)
                    f = dynamics[GAINS + n] * w * (c_held if dynamics[EXPONENT] > 0.5 else 1.0)
                for a in range(3):
                    state[held + a] += f * v[n, a]
    for n in range(n_motors):
        state[n_motors + n] = min(max(c[n], 0.0), 1.0)
    state[2 * n_motors] = u
    state[started] = 1.0
    for a in range(3):
        out[a] = 0.0
        for b in range(3):
            out[a] += A_inv[a, b] * (mag[b] - b_s[b] - state[held + b])


@njit(cache=True, error_model="numpy")
def _compensate(time, mag, c, u, A_inv, b_s, v, theta, I, J, dynamics, mode, sample_rate, out):
    state = np.zeros(2 * v.shape[0] + 5)
    previous = time[0]
    for k in range(len(time)):
        step(time[k], time[k] - previous, mag[k], c[k], u[k], A_inv, b_s, v, theta, I, J, dynamics, mode,
             sample_rate, state, out[k])
        previous = time[k]


def _arrays(calibration, mode: str):
    if mode not in MODES:
        raise ValueError(f"compensation mode {mode!r} must be one of {', '.join(MODES)}")
    static = calibration.static
    A_inv = np.eye(3) if static is None else np.linalg.inv(static.A)
    b_s = np.zeros(3) if static is None else np.asarray(static.b_s, dtype=float)
    field = calibration.field
    if mode != "static" and field is None:
        raise ValueError(f"compensation {mode!r} needs a dynamic calibration (v_n, theta_n); the file has none")
    if field is None:
        v, theta, orders = np.zeros((calibration.motors, 3)), np.zeros((calibration.motors, 1)), (1, 0)
    else:
        v, theta, orders = field.v, field.theta, field.orders
    if mode == "dynamic" and calibration.dynamics is None:
        raise ValueError("compensation 'dynamic' needs identified motor dynamics; the calibration has none")
    dynamics = (np.zeros(GAINS + len(v)) if calibration.dynamics is None
                else calibration.dynamics.vector())
    return (np.ascontiguousarray(A_inv), np.ascontiguousarray(b_s), np.ascontiguousarray(v, dtype=float),
            np.ascontiguousarray(theta, dtype=float), int(orders[0]), int(orders[1]), dynamics, MODES[mode])


def compensate(calibration, time, magneto, commands, voltage, mode: str = "metge",
               sample_rate: float = 0.0) -> np.ndarray:
    """Compensated field on recorded arrays, by the same arithmetic as :class:`MagCompensator`.

    Parameters
    ----------
    calibration : quadcosim.calibration.Calibration
    time : (T,) array
        Times (s) of the rows, increasing.
    magneto : (T, 3) array
        Raw magnetometer readings, sensor frame (T).
    commands : (T, N) array
        ESC commands (1).
    voltage : (T,) array
        Battery voltage (V).
    mode : {"static", "metge", "dynamic"}
    sample_rate : float
        Magnetometer rate (Hz) whose instants ``k / sample_rate`` refresh ``b_d``; 0: every row.

    Returns
    -------
    (T, 3) array
        ``A^-1 (m_bar - b_s - b_d)`` (T, or the unit of the static calibration).
    """
    time = np.ascontiguousarray(time, dtype=float)
    mag = np.ascontiguousarray(magneto, dtype=float)
    c = np.ascontiguousarray(commands, dtype=float)
    u = np.ascontiguousarray(voltage, dtype=float)
    if mag.shape != (len(time), 3) or c.shape[0] != len(time) or u.shape != (len(time),):
        raise ValueError(f"time {time.shape}, magneto {mag.shape}, commands {c.shape} and voltage {u.shape} "
                         "must have the same number of rows (magneto with 3 columns)")
    if c.shape[1] != calibration.motors:
        raise ValueError(f"commands have {c.shape[1]} columns; the calibration has {calibration.motors} motors")
    out = np.empty_like(mag)
    _compensate(time, mag, c, u, *_arrays(calibration, mode), float(sample_rate), out)
    return out


class MagCompensator(Block):
    """Streaming block between the IMU and ``Quaternion_estim``: eq. 9 or its dynamic variant.

    Inputs ``magneto_x/y/z`` (T, raw), ``c1..cN`` (1), ``u_batt`` (V); outputs
    ``magneto_x/y/z`` (T, compensated). Only the magnetometer is direct feedthrough: the
    commands and the voltage may come from blocks ordered after it (a unit delay), which
    keeps a controller fed by the estimate free of an algebraic loop.

    Parameters
    ----------
    calibration : quadcosim.calibration.Calibration
    mode : {"static", "metge", "dynamic"}
    sample_rate : float
        Magnetometer rate (Hz); 0 refreshes ``b_d`` at every step.
    name : str
    period : int
        Macro steps per update.
    """

    outputs = ("magneto_x", "magneto_y", "magneto_z")
    units = dict.fromkeys(outputs, "T")

    def __init__(self, calibration, mode: str = "metge", sample_rate: float = 0.0, name: str = "MagCompensator",
                 period: int = 1):
        super().__init__(name, period)
        self.calibration = calibration
        self.mode = mode
        self.sample_rate = float(sample_rate)
        self.arrays = _arrays(calibration, mode)
        self.motors = calibration.motors
        self.inputs = ("magneto_x", "magneto_y", "magneto_z", *[f"c{n}" for n in range(1, self.motors + 1)],
                       "u_batt")

    @property
    def feedthrough_inputs(self) -> set[str]:
        """The magnetometer only: commands and voltage may arrive one macro step late."""
        return {"magneto_x", "magneto_y", "magneto_z"}

    def start(self, t0, dt):
        self._state = np.zeros(2 * self.motors + 5)
        self._previous = t0
        self._out = np.empty(3)

    def step(self, t, u, y):
        n = self.motors
        step(t, t - self._previous, u[:3], u[3:3 + n], u[3 + n], *self.arrays, self.sample_rate, self._state,
             self._out)
        self._previous = t
        y[:] = self._out
