"""What a flight shows of the drag model, measured on a ``tp`` run: the figures :mod:`trim` predicts.

- :func:`tilt_step`: after the pitch step of ``flight=tilt``, the accelerometer's tilt against
  the true tilt at the end, the speed reached, and the time constant of a first-order lag
  fitted to the accelerometer's tilt (against ``m / (k_d sum|omega_n|)``, :func:`trim.drag_time_constant`);
- :func:`step_response`: an attitude step's rise time, settling time, overshoot and steady
  error on each axis (python-control's ``step_info``);
- :func:`wind_hold`: holding a position in a steady wind, the tilt into the wind against
  :func:`trim.wind_hover_tilt`, the final position error and the largest drift on the way.
"""

from __future__ import annotations

import math

import numpy as np
from quadcosim.flight import profiles, trim

SETTLED_AFTER_STEP = 1.0  # s after the step: the attitude loop has settled (0.3 s), the lag alone remains
FIT_START_TAU = 4.0  # s, first guess of the fitted time constant (the default vehicle's is 4.25 s)
FIT_PARAMETERS = 3
MM_PER_M = 1e3  # final tilt, amplitude, time constant
PERCENT = 100.0
STEADY_TAIL = 0.9  # the steady error is the mean over the window's last 10 %


def accelerometer_tilt(result) -> tuple[np.ndarray, np.ndarray]:
    """Roll and pitch (rad) of the specific force the IMU measures: ``atan2`` of its components.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        A run recording ``IMU.acc`` (m/s^2, body frame).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        Roll ``atan2(-a_y, -a_z)`` and pitch ``atan2(a_x, hypot(a_y, a_z))`` (rad), one per sample.
    """
    a = result["IMU.acc"]
    return np.arctan2(-a[:, 1], -a[:, 2]), np.arctan2(a[:, 0], np.hypot(a[:, 1], a[:, 2]))


def tilt_step(result, tilt: float, rotor_drag: bool) -> dict:
    """The accelerometer's view of a held pitch step (``flight=tilt``).

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        A ``tp`` run with ``flight=tilt``.
    tilt : float
        The commanded pitch (rad).
    rotor_drag : bool
        Whether the plant has rotor drag (without it there is no lag to fit).

    Returns
    -------
    dict
        ``accelerometer_tilt_final_deg`` and ``true_tilt_final_deg`` (deg, pitch at the last
        sample), ``speed_final_m_s`` (m/s, ground speed at the last sample); with drag,
        ``tilt_lag_fitted_s`` (s, time constant of ``final - amplitude exp(-(t - t_step) / tau)``
        fitted from 1 s after the step) and ``tilt_lag_predicted_s`` (s, ``m / (k_d sum|omega_n|)``
        at the final thrust).
    """
    _, pitch = accelerometer_tilt(result)
    found = {"accelerometer_tilt_final_deg": math.degrees(float(pitch[-1])),
             "true_tilt_final_deg": math.degrees(float(result["Quadrotor.theta2"][-1])),
             "speed_final_m_s": float(np.linalg.norm(result["Quadrotor.v"][-1]))}
    window = result.time > profiles.STEP_TIME + SETTLED_AFTER_STEP
    if rotor_drag and np.count_nonzero(window) > FIT_PARAMETERS:
        from scipy.optimize import curve_fit  # here: every tp report imports this module

        def lag(t, final, amplitude, tau):
            return final - amplitude * np.exp(-(t - profiles.STEP_TIME) / tau)

        (_, _, tau), _ = curve_fit(lag, result.time[window], pitch[window], p0=(tilt, tilt, FIT_START_TAU))
        found["tilt_lag_fitted_s"] = float(tau)
        found["tilt_lag_predicted_s"] = trim.drag_time_constant(thrust=float(result["Quadrotor.thrust"][-1]))
    return found


AXES = ("roll", "pitch", "yaw")


def step_figures(time, response, size: float, band: float = 0.02) -> tuple:
    """Rise time, settling time and overshoot of a step response, by python-control's ``step_info``
    where it applies: the one implementation behind :func:`step_response` and the testing
    assertions' step (:func:`quadcosim.scenarios.testing.assertions.step_response`).

    Parameters
    ----------
    time : array_like
        Time from the step (s).
    response : array_like
        The response less its value at the step (the signal's unit).
    size : float
        The step commanded, the reference of rise, settling and overshoot (same unit).
    band : float
        Settling band, a fraction of the step's size.

    Returns
    -------
    tuple
        ``rise`` (s, 10 to 90 % of the step; None when the response never reaches 90 %, where
        ``step_info`` does not apply), ``settling`` (s; None when the last sample is outside the
        band: it did not settle in the window), ``overshoot`` (% of the step, 0 or more).
    """
    import control

    time, response = np.asarray(time, float), np.asarray(response, float)
    outside = np.nonzero(np.abs(response - size) > band * abs(size))[0]
    unsettled = len(outside) > 0 and outside[-1] == len(response) - 1
    try:
        info = control.step_info(response, timepts=time, final_output=size, SettlingTimeThreshold=band)
    except IndexError:  # the response never reached 90 % of the step
        return None, None, max(0.0, PERCENT * (float(np.max(response / size)) - 1.0))
    settling = None if unsettled or math.isnan(info["SettlingTime"]) else float(info["SettlingTime"])
    return float(info["RiseTime"]), settling, float(info["Overshoot"])


def step_response(result, steps: list, step_time: float) -> dict:
    """Step metrics of an attitude step on each axis, by python-control's ``step_info``.

    The response is the true attitude (``Quadrotor.theta1..3``) from ``step_time`` on, less its
    value just before the step; the reference of rise, settling and overshoot is the step
    commanded (so a steady error counts against settling).

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        A ``tp`` run with a step (``flight=step`` or ``flight=tilt``).
    steps : list
        The step on roll, pitch, yaw (rad), None on an axis not stepped
        (:func:`quadcosim.flight.profiles.step_sizes`).
    step_time : float
        When the step is commanded (s).

    Returns
    -------
    dict
        Lists over roll, pitch, yaw (None on an axis not stepped): ``step_rise_time_s`` (10 to 90 %
        of the step), ``step_settling_time_s`` (s after the step until the response stays within
        2 % of the step; the whole window when it never does), ``step_overshoot_pct`` (% of the
        step), ``step_steady_error_deg`` (the step less the mean response over the last 10 % of
        the window, deg), ``step_iae_deg_times_s`` (the integral of the absolute error to the step
        over the window, deg s); ``step_settling_worst_s``, the largest settling time of the axes
        stepped (s), and ``step_iae_total_deg_times_s``, the sum of their integrals (deg s): one
        number each to tune on (the integral varies smoothly with the gains, a settling time by
        jumps).
    """
    after = result.time >= step_time
    before = max(int(np.argmax(after)) - 1, 0)
    time = result.time[after] - step_time
    found = {"step_rise_time_s": [], "step_settling_time_s": [], "step_overshoot_pct": [],
             "step_steady_error_deg": [], "step_iae_deg_times_s": []}
    for i, step in enumerate(steps):
        if step is None or len(time) < 3:
            for values in found.values():
                values.append(None)
            continue
        angle = result[f"Quadrotor.theta{i + 1}"]
        response = angle[after] - angle[before]
        rise, settling, overshoot = step_figures(time, response, step)
        found["step_rise_time_s"].append(rise)
        # not settled by the end: the whole window
        found["step_settling_time_s"].append(float(time[-1]) if settling is None else settling)
        found["step_overshoot_pct"].append(overshoot)
        late = response[time >= STEADY_TAIL * time[-1]]
        found["step_steady_error_deg"].append(math.degrees(step - float(late.mean())))
        found["step_iae_deg_times_s"].append(math.degrees(float(np.trapezoid(np.abs(step - response), time))))
    settled = [t for t in found["step_settling_time_s"] if t is not None]
    found["step_settling_worst_s"] = max(settled) if settled else None
    found["step_iae_total_deg_times_s"] = sum(v for v in found["step_iae_deg_times_s"] if v is not None)
    return found


def wind_hold(result, wind_speed: float) -> dict:
    """The position hold in a steady horizontal wind (``flight=hover``, ``wind_n``, ``wind_e``).

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        A ``tp`` run holding its position in the wind.
    wind_speed : float
        Horizontal wind speed (m/s).

    Returns
    -------
    dict
        ``wind_tilt_final_deg`` (deg, the tilt of the body's z axis from the vertical at the
        last sample), ``wind_tilt_predicted_deg`` (deg, :func:`trim.wind_hover_tilt`),
        ``position_error_final_mm`` (mm, horizontal distance from the held point at the last
        sample), ``drift_max_m`` (m, the largest horizontal distance on the way).
    """
    predicted, _ = trim.wind_hover_tilt(wind_speed)
    roll, pitch = result["Quadrotor.theta1"][-1], result["Quadrotor.theta2"][-1]
    horizontal = np.hypot(result["Quadrotor.p"][:, 0], result["Quadrotor.p"][:, 1])
    return {"wind_tilt_final_deg": math.degrees(math.acos(math.cos(roll) * math.cos(pitch))),
            "wind_tilt_predicted_deg": math.degrees(predicted),
            "position_error_final_mm": MM_PER_M * float(horizontal[-1]), "drift_max_m": float(horizontal.max())}
