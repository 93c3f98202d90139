"""Findings of the flight side: what rotor drag lets the accelerometer see, and the wind hold.

Each is a ``tp`` run whose ``metrics.json`` records the number (:mod:`scenarios.flight.measured`),
except the PD hold without integral, an ablation of the controller's gain that no option
reaches: it is computed here, as ``tests/test_flight.py`` does, and printed by this group.
"""

from __future__ import annotations

import math

from scenarios.findings import command, finding

TILT = {"flight": "tilt", "tilt_deg": 5.0, "duration": 30.0}
WIND = {"flight": "hover", "wind_n": 3.0, "duration": 40.0}


def _command(options: dict) -> str:
    return command("quadcosim run tp", options)


def _run(options: dict) -> dict:
    import scenarios

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


ABLATION = "python -m scenarios.findings flight --check"  # prints the group, writes nothing


def predicted_offset() -> float:
    """Downwind offset (m) of a PD position hold: the drag to cancel over ``kp_xy``, ``g tan(tilt) / kp_xy``."""
    from fmus import vehicle
    from scenarios.flight import GAINS, trim

    tilt, _ = trim.wind_hover_tilt(math.hypot(WIND["wind_n"], WIND.get("wind_e", 0.0)))
    return math.tan(tilt) * vehicle.GRAVITY / GAINS["kp_xy"][0]


def offset_without_integral() -> float:
    """Final downwind offset (m) of the position hold in :data:`WIND` with ``ki_xy = 0``."""
    import scenarios
    from scenarios.flight import controller as law

    tp = scenarios.get("tp")
    system = tp.build(tp.parse(WIND))
    system.blocks["Controller"].parameters[law.P_KIXY] = 0.0
    result = system.run(WIND["duration"])
    return math.hypot(result["Quadrotor.p"][-1, 0], result["Quadrotor.p"][-1, 1])


def compute(quick: bool = False) -> list[dict]:
    """The flight findings; ``quick``: the 30 s tilt step alone (about 5 s)."""
    found = tilt("flight.tilt", TILT)
    if quick:
        return found
    return found + tilt("flight.tilt_without_drag", TILT | {"rotor_drag": False}) + wind()
