"""Gain analysis of the estimators with python-control.

Linear filter, per axis, as implemented (explicit Euler at the sample period ``dt``):
``e[n+1] = (1 - k dt) e[n] + dt n_g[n] + k dt n_a[n] + dt b``, where ``e`` is the estimation
error, ``n_g`` the gyro noise, ``n_a`` the noise of the measured angle (accelerometer noise
over g for roll and pitch) and ``b`` a gyro bias. Transfer functions to the error:
``dt / (z - 1 + k dt)`` from gyro noise and from bias (steady error ``b / k``),
``k dt / (z - 1 + k dt)`` from the measured-angle noise; continuous-time limits
``1/(s + k)`` and ``k/(s + k)``, bandwidth ``k`` rad/s. The error variance for white noises
of standard deviations ``sigma_g`` (rad/s) and ``sigma_a`` (rad) per sample is
``sigma_g^2 ||H_g||^2 + sigma_a^2 ||H_a||^2``, the H2 norms from the discrete Lyapunov
equation.

Passive filter with bias, linearised about the truth with ``R_y = R``: with ``x`` the
body-frame rotation from estimate to truth and ``b~ = b - b_est``,
``dx = -kP x - b~``, ``db~ = kI x``, per axis: poles of ``s^2 + kP s + kI``.

Explicit filter, linearised: ``omega_mes = M x`` with ``M = sum k_i (I - v_i v_i^T)`` (unit
body directions ``v_i``), so ``dx = -kP M x - b~``; without bias estimation the steady
estimation error (estimate minus truth, small angles, body axes) is ``(kP M)^-1 b``.
"""

from __future__ import annotations

import math

import control
import numpy as np
from quadcosim.fmus import vehicle
from scipy.optimize import minimize_scalar

HORIZON_TIME_CONSTANTS = 12.0  # simulated span of a bias transient, in time constants of its slowest pole
RESPONSE_SAMPLES = 20001  # samples of that transient (the convergence time is read to span / 20000)


# ------------------------------------------------------------------ linear filter
def linear_transfer_functions(k: float, dt: float) -> dict:
    """Discrete transfer functions from gyro noise, measured-angle noise and gyro bias to the
    estimation error of one axis, and their continuous-time limits, at gain ``k`` (1/s) and
    sample time ``dt`` (s)."""
    pole = 1.0 - k * dt
    return {
        "gyro_noise": control.tf([dt], [1.0, -pole], dt),
        "angle_noise": control.tf([k * dt], [1.0, -pole], dt),
        "gyro_bias": control.tf([dt], [1.0, -pole], dt),
        "gyro_noise_continuous": control.tf([1.0], [1.0, k]),
        "angle_noise_continuous": control.tf([k], [1.0, k]),
    }


def _h2_squared(system) -> float:
    """Sum of the squared impulse response of a stable discrete system (its H2 norm squared)."""
    ss = control.ss(system)
    gram = control.dlyap(ss.A, ss.B @ ss.B.T)
    return float((ss.C @ gram @ ss.C.T + ss.D @ ss.D.T).item())


def linear_bandwidth(k: float) -> float:
    """-3 dB bandwidth (rad/s) of the measured-angle path k/(s + k)."""
    return float(control.bandwidth(control.tf([k], [1.0, k])))


def linear_error_variance(k, dt: float, sigma_gyro: float, sigma_angle: float) -> np.ndarray:
    """Predicted steady error variance (rad^2) of one axis, for each gain in ``k`` (1/s), at sample
    time ``dt`` (s), with per-sample noise standard deviations ``sigma_gyro`` (rad/s) and
    ``sigma_angle`` (rad, the accelerometer-derived angle); see :func:`imu_noise_per_sample`."""
    out = []
    for gain in np.atleast_1d(k):
        tf = linear_transfer_functions(float(gain), dt)
        out.append(sigma_gyro**2 * _h2_squared(tf["gyro_noise"]) + sigma_angle**2 * _h2_squared(tf["angle_noise"]))
    return np.array(out)


def linear_optimal_gain(dt: float, sigma_gyro: float, sigma_angle: float, bounds=(1e-4, 50.0)) -> float:
    """Gain (1/s) that minimises the predicted error variance at sample time ``dt`` (s), with the
    per-sample noise ``sigma_gyro`` (rad/s) and ``sigma_angle`` (rad), searched within
    ``bounds`` (1/s)."""
    fit = minimize_scalar(lambda logk: math.log(linear_error_variance(math.exp(logk), dt, sigma_gyro,
                                                                      sigma_angle)[0]),
                          bounds=tuple(math.log(b) for b in bounds), method="bounded",
                          options={"xatol": 1e-6})
    return math.exp(fit.x)


def imu_noise_per_sample(sample_rate: float, gyro_density: float | None = None, acc_density: float | None = None):
    """Per-sample standard deviations of the gyro (rad/s) and of the accelerometer-derived
    roll/pitch angle (rad, accelerometer noise over g) at ``sample_rate`` (Hz), from the noise
    densities ``gyro_density`` (rad/s/sqrt(Hz)) and ``acc_density`` (m/s^2/sqrt(Hz)), by default
    the IMU model's."""
    from quadcosim.fmus.IMU.variables import ACC_NOISE_DENSITY, GYRO_NOISE_DENSITY

    root = math.sqrt(sample_rate)
    gyro = (GYRO_NOISE_DENSITY if gyro_density is None else gyro_density) * root
    acc = (ACC_NOISE_DENSITY if acc_density is None else acc_density) * root
    return gyro, acc / vehicle.GRAVITY


# ------------------------------------------------------------------ passive filter
def passive_error_system(kP: float, kI: float):
    """Linearised error dynamics of one axis: state (x, b~), output b~, at the gains ``kP``
    (1/s) and ``kI`` (1/s^2)."""
    return control.ss([[-kP, -1.0], [kI, 0.0]], [[0.0], [0.0]], [[0.0, 1.0]], [[0.0]])


def passive_poles(kP: float, kI: float) -> dict:
    """Poles, natural frequency and damping of the linearised passive filter at the gains ``kP``
    (1/s) and ``kI`` (1/s^2)."""
    system = passive_error_system(kP, kI)
    wn, zeta, poles = control.damp(system, doprint=False)
    return {"poles": poles, "natural_frequency": float(wn[0]), "damping": float(zeta[0])}


def passive_bias_convergence_time(kP: float, kI: float, initial_bias_error: float, tolerance: float,
                                  horizon: float | None = None) -> float:
    """Time (s) after which the linearised bias error stays within ``tolerance`` (rad/s), at the
    gains ``kP`` (1/s) and ``kI`` (1/s^2), from ``initial_bias_error`` (rad/s); the response is
    simulated over ``horizon`` (s; default: long enough for the slowest pole)."""
    slowest = min(abs(p.real) for p in control.poles(passive_error_system(kP, kI)))
    horizon = horizon or HORIZON_TIME_CONSTANTS * math.log(abs(initial_bias_error) / tolerance + 1.0) / slowest + 1.0
    t = np.linspace(0.0, horizon, RESPONSE_SAMPLES)
    response = control.initial_response(passive_error_system(kP, kI), t, X0=[0.0, initial_bias_error])
    outside = np.flatnonzero(np.abs(np.squeeze(response.outputs)) > tolerance)
    return 0.0 if len(outside) == 0 else float(t[min(outside[-1] + 1, len(t) - 1)])


# ------------------------------------------------------------------ explicit filter
def explicit_bias_steady_error(k1: float, k2: float, kP: float, bias, attitude=(0.0, 0.0, 0.0),
                               earth_field=vehicle.EARTH_FIELD) -> np.ndarray:
    """Predicted steady estimation error (rad, body axes) of the explicit filter without bias
    estimation, for a constant gyro ``bias`` (rad/s, body axes), at a fixed ``attitude`` (rad;
    roll, pitch, yaw), with the weights ``k1`` (gravity), ``k2`` (field), the gain ``kP`` (1/s)
    and the reference field ``earth_field`` (T, NED; only its direction counts)."""
    from quadcosim.estimators.quaternions import quaternion_from_euler, rotation

    q, r = np.empty(4), np.empty((3, 3))
    quaternion_from_euler(np.asarray(attitude, dtype=float), q)
    rotation(q, r)
    v1 = r.T @ np.array([0.0, 0.0, -1.0])
    v2 = r.T @ np.asarray(earth_field) / np.linalg.norm(earth_field)
    M = k1 * (np.eye(3) - np.outer(v1, v1)) + k2 * (np.eye(3) - np.outer(v2, v2))
    # error dynamics d(err) = -kP M err + b: DC gain (kP M)^-1
    system = control.ss(-kP * M, np.eye(3), np.eye(3), np.zeros((3, 3)))
    return control.dcgain(system) @ np.asarray(bias, dtype=float)
