"""Findings of the flight side: what rotor drag lets the accelerometer see, the wind hold, and
how fast the yaw loop may be at a 100 Hz loop rate.

Each is a ``tp`` run whose ``metrics.json`` records the number (:mod:`quadcosim.flight.measured`),
except the PD hold without integral, an ablation of the controller's gain that no option
reaches: it is computed here, as ``tests/test_flight.py`` does, and printed by this group; and
the yaw loop's cases (:mod:`quadcosim.studies.yaw_loop`), printed by their module.
"""

from __future__ import annotations

import math

from findings import command, finding

TILT = {"flight": "tilt", "tilt_deg": 5.0, "duration": 30.0}
WIND = {"flight": "hover", "wind_n": 3.0, "duration": 40.0}


def _command(options: dict) -> str:
    return command("quadcosim run tp", options)


def _run(options: dict) -> dict:
    from quadcosim import scenarios

    return scenarios.run("tp", options)[1]


def tilt(prefix: str, options: dict) -> list[dict]:
    """The tilt step: the accelerometer's and the true tilt and the speed at the end; with drag
    the fitted and predicted lag.

    Parameters
    ----------
    prefix : str
        Names of the findings, ``prefix.accelerometer_tilt_deg``, ...
    options : dict
        The ``tp`` options of the run (``flight=tilt``).
    """
    m, command = _run(options), _command(options)
    found = [finding(f"{prefix}.accelerometer_tilt_deg", m["accelerometer_tilt_final_deg"], "deg", command, 1e-3, 3),
             finding(f"{prefix}.true_tilt_deg", m["true_tilt_final_deg"], "deg", command, 1e-3, 3)]
    if options.get("rotor_drag", True):
        found += [finding(f"{prefix}.speed_m_s", m["speed_final_m_s"], "m/s", command, 0.005, 2),
                  finding(f"{prefix}.lag_fitted_s", m["tilt_lag_fitted_s"], "s", command, 0.002, 3),
                  finding(f"{prefix}.lag_predicted_s", m["tilt_lag_predicted_s"], "s", command, 0.001, 3)]
    else:
        found.append(finding(f"{prefix}.speed_m_s", m["speed_final_m_s"], "m/s", command, 0.05, 1))
    return found


def wind() -> list[dict]:
    """The position hold in a 3 m/s wind, and the PD hold without its integral."""
    m, command = _run(WIND), _command(WIND)
    return [finding("flight.wind.tilt_deg", m["wind_tilt_final_deg"], "deg", command, 5e-5, 4),
            finding("flight.wind.tilt_predicted_deg", m["wind_tilt_predicted_deg"], "deg", command, 5e-5, 4),
            finding("flight.wind.position_error_final_mm", m["position_error_final_mm"], "mm", command, 0.05, 2),
            finding("flight.wind.drift_max_m", m["drift_max_m"], "m", command, 0.005, 2),
            finding("flight.wind.offset_without_integral_m", offset_without_integral(), "m", ABLATION, 0.005, 2),
            finding("flight.wind.offset_predicted_m", predicted_offset(), "m", ABLATION, 0.005, 2)]


ABLATION = "python -m findings flight --check"  # prints the group, writes nothing


def predicted_offset() -> float:
    """Downwind offset (m) of a PD position hold: the drag to cancel over ``kp_xy``, ``g tan(tilt) / kp_xy``."""
    from quadcosim.flight import GAINS, trim
    from quadcosim.fmus import vehicle

    tilt, _ = trim.wind_hover_tilt(math.hypot(WIND["wind_n"], WIND.get("wind_e", 0.0)))
    return math.tan(tilt) * vehicle.GRAVITY / GAINS["kp_xy"][0]


def offset_without_integral() -> float:
    """Final downwind offset (m) of the position hold in :data:`WIND` with ``ki_xy = 0``."""
    from quadcosim.flight import controller as law

    from quadcosim import scenarios

    tp = scenarios.get("tp")
    system = tp.build(tp.parse(WIND))
    system.blocks["Controller"].parameters[law.P_KIXY] = 0.0
    result = system.run(WIND["duration"])
    return math.hypot(result["Quadrotor.p"][-1, 0], result["Quadrotor.p"][-1, 1])


YAW = "python -m quadcosim.studies.yaw_loop"
#: Tolerances of the yaw loop's figures: a ringing loop's limit cycle grows from rounding error,
#: so another CPU may sample it at other phases.
YAW_TOLERANCE = {"ringing_nm": 0.002, "ring_hz": 0.3, "command_min": 0.005, "command_max": 0.005,
                 "current_min_a": 0.05, "current_max_a": 0.05}
YAW_DIGITS = {"ringing_nm": 3, "ring_hz": 1, "command_min": 3, "command_max": 3, "current_min_a": 2,
              "current_max_a": 2}
YAW_UNITS = {"ringing_nm": "N m", "ring_hz": "Hz", "command_min": "1", "command_max": "1", "current_min_a": "A",
             "current_max_a": "A"}


def yaw(quick: bool = False) -> list[dict]:
    """The yaw loop's cases (a ringing one's ringing and its frequency; every one's command and
    current ranges), the largest quiet loop at 100 Hz and the first whose commands reach a
    bound; ``quick``: the 100 Hz cases alone (a second each)."""
    from quadcosim.studies import yaw_loop

    found = []
    for name, rate, w, flight, settings in yaw_loop.CASES:
        if quick and rate != 100.0:
            continue
        case = yaw_loop.yaw_loop(rate, w, flight, settings)
        keys = [k for k in YAW_DIGITS if case["oscillating"] or k not in ("ringing_nm", "ring_hz")]
        found += [finding(f"flight.yaw.{name}.{k}", case[k], YAW_UNITS[k], YAW, YAW_TOLERANCE[k], YAW_DIGITS[k])
                  for k in keys]
    if not quick:
        found += [finding("flight.yaw.largest_quiet_100hz_rad_s", yaw_loop.largest_quiet(), "rad/s", YAW, 0.0, 1),
                  finding("flight.yaw.first_at_bound_100hz_rad_s", yaw_loop.first_at_bound(), "rad/s", YAW, 0.0, 1)]
    return found


def compute(quick: bool = False) -> list[dict]:
    """The flight findings; ``quick``: the 30 s tilt step and the yaw loop's 100 Hz cases (about 10 s)."""
    found = tilt("flight.tilt", TILT)
    if quick:
        return found + yaw(quick=True)
    return found + tilt("flight.tilt_without_drag", TILT | {"rotor_drag": False}) + wind() + yaw()
