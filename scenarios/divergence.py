"""Whether a closed-loop run diverged: bounds on the attitude and altitude errors, per scenario.

A gain set that destabilises the loop (``--set Controller.kp=5000``) still gives finite numbers:
the vehicle tumbles and falls, and its errors are those of a crash, not of a controller. A
scenario that flies declares :class:`Bounds` (``Scenario.extra["divergence"]``); after the loop,
:func:`first_crossing` finds the first time a bound was crossed and held, and the run ends with
the status ``diverged`` (its record, figures and ``metrics.json`` kept), a warning naming the
settings it ran with, and exit code 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Signals the bounds are read from: the true attitude and position, and what the controller asked.
ROLL_PITCH = (("Quadrotor.theta1", "Controller.theta_d1"), ("Quadrotor.theta2", "Controller.theta_d2"))
ALTITUDE = ("Quadrotor.p_z", "Setpoint.z_d")
SPEED = ("Quadrotor.v_x", "Quadrotor.v_y", "Quadrotor.v_z")
TURN_RATE = "InfraredSensor.r"  # a fixed-wing's true turn rate (rad/s), from its bank and airspeed
CONTROLLER = ("Controller.tau_x", "Controller.tau_y", "Controller.tau_z", "Controller.thrust")


@dataclass(frozen=True)
class Bounds:
    """How far a closed-loop flight may stray before it counts as diverged.

    Attributes
    ----------
    tilt_error_deg : float or None
        Roll or pitch away from the controller's setpoint (deg); None: not bounded (no controller).
    altitude_error_m : float or None
        Altitude away from its setpoint, above or below (m); None: not bounded.
    speed_m_s : float or None
        Speed (m/s); None: not bounded (the scenario does not record the velocity).
    held_s : float
        How long a bound must stay crossed (s): a setpoint step is not a divergence.
    tilt_deg : float or None
        Roll or pitch away from level (deg), for a vehicle flown without a controller; None: not bounded.
    turn_rate_rad_s : float or None
        A fixed-wing's turn rate, either way (rad/s); None: not bounded.
    """

    tilt_error_deg: float | None
    altitude_error_m: float | None
    speed_m_s: float | None
    held_s: float
    tilt_deg: float | None = None
    turn_rate_rad_s: float | None = None


def _held(crossed: np.ndarray, time: np.ndarray, held_s: float) -> int | None:
    """Index of the first sample of the first run of ``crossed`` lasting ``held_s`` (s), or None."""
    if not crossed.any():
        return None
    edges = np.diff(np.concatenate([[0], crossed.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    lasting = time[stops] - time[starts] >= held_s
    return int(starts[lasting][0]) if lasting.any() else None


def first_crossing(result, bounds: Bounds) -> dict | None:
    """The first bound ``result`` crossed and held, or None (also when it did not record what a
    bound reads: see :func:`unchecked`).

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        A closed-loop run's record.
    bounds : Bounds

    Returns
    -------
    dict or None
        ``at_s`` (s), ``what`` (the text of the crossing), ``bound`` and ``value`` (in the
        bound's unit), and ``controller_peak`` (the largest torque, N.m, and thrust, N, the
        controller asked for) when recorded.
    """
    time = np.asarray(result.time)
    found = []
    names = set(result.names)
    if bounds.tilt_error_deg is not None and all(a in names and b in names for a, b in ROLL_PITCH):
        for k, (true, wanted) in enumerate(ROLL_PITCH):
            error = np.degrees(np.abs((result[wanted] - result[true] + math.pi) % (2 * math.pi) - math.pi))
            at = _held(error > bounds.tilt_error_deg, time, bounds.held_s)
            if at is not None:
                found.append((at, f"{'roll' if k == 0 else 'pitch'} {error[at]:.0f} deg from its setpoint",
                              bounds.tilt_error_deg, float(error[at]), "deg"))
    if bounds.altitude_error_m is not None and all(n in names for n in ALTITUDE):
        error = result[ALTITUDE[0]] - result[ALTITUDE[1]]  # NED: positive is below the setpoint
        at = _held(np.abs(error) > bounds.altitude_error_m, time, bounds.held_s)
        if at is not None:
            where = "below" if error[at] > 0 else "above"
            found.append((at, f"{abs(error[at]):.1f} m {where} its altitude setpoint", bounds.altitude_error_m,
                          float(abs(error[at])), "m"))
    if bounds.tilt_deg is not None and all(true in names for true, _ in ROLL_PITCH):
        for k, (true, _) in enumerate(ROLL_PITCH):
            tilt = np.degrees(np.abs((result[true] + math.pi) % (2 * math.pi) - math.pi))
            at = _held(tilt > bounds.tilt_deg, time, bounds.held_s)
            if at is not None:
                found.append((at, f"{'roll' if k == 0 else 'pitch'} {tilt[at]:.0f} deg from level", bounds.tilt_deg,
                              float(tilt[at]), "deg"))
    if bounds.turn_rate_rad_s is not None and TURN_RATE in names:
        rate = np.abs(result[TURN_RATE])
        at = _held(rate > bounds.turn_rate_rad_s, time, bounds.held_s)
        if at is not None:
            found.append((at, f"a turn rate of {rate[at]:.2f} rad/s", bounds.turn_rate_rad_s, float(rate[at]), "rad/s"))
    if bounds.speed_m_s is not None and all(n in names for n in SPEED):
        speed = np.sqrt(sum(result[n] ** 2 for n in SPEED))
        at = _held(speed > bounds.speed_m_s, time, bounds.held_s)
        if at is not None:
            found.append((at, f"a speed of {speed[at]:.1f} m/s", bounds.speed_m_s, float(speed[at]), "m/s"))
    if not found:
        return None
    at, what, bound, value, unit = min(found)
    crossing = {"at_s": float(time[at]), "what": what, "bound": bound, "value": value, "unit": unit}
    peaks = {n: float(np.max(np.abs(result[n]))) for n in CONTROLLER if n in names}
    if peaks:
        crossing["controller_peak"] = peaks
    return crossing


def unchecked(result, bounds: Bounds | None = None) -> list[str]:
    """The signals a bound (of ``bounds``, default all) reads that ``result`` did not record (its
    bound is then not checked)."""
    wanted = [n for pair in ROLL_PITCH for n in pair] if bounds is None or bounds.tilt_error_deg is not None else []
    wanted += list(ALTITUDE) if bounds is None or bounds.altitude_error_m is not None else []
    if bounds is not None and bounds.tilt_deg is not None:
        wanted += [true for true, _ in ROLL_PITCH if true not in wanted]
    wanted += [TURN_RATE] if bounds is not None and bounds.turn_rate_rad_s is not None else []
    wanted += list(SPEED) if bounds is None or bounds.speed_m_s is not None else []
    return [n for n in wanted if n not in set(result.names)]


def message(scenario: str, crossing: dict, settings: list[str]) -> str:
    """The warning of a run that diverged: when and how, the bound, the settings it ran with.

    Parameters
    ----------
    scenario : str
        The scenario's name.
    crossing : dict
        What :func:`first_crossing` found.
    settings : list of str
        The options off their defaults and the block parameters set, ``key=value``.
    """
    peaks = crossing.get("controller_peak", {})
    torque = max((v for n, v in peaks.items() if n.startswith("Controller.tau")), default=None)
    asked = f"; the controller asked for up to {torque:.3g} N.m" if torque is not None else ""
    given = ", ".join(settings) if settings else "the default settings"
    # no controller signal recorded: an open loop (or a rig) left its bounds; there is no loop to call unstable
    cause = (f"The loop is unstable with {given}" if peaks else
             f"The vehicle left the scenario's bounds with {given}, with no controller flying it")
    return (f"{scenario} diverged at t = {crossing['at_s']:.2f} s: {crossing['what']} (bound {crossing['bound']:g} "
            f"{crossing['unit']}){asked}. {cause}; its numbers describe a crash, not the controller or the "
            "estimator")


#: The bounds of a vehicle clamped to its rig (``rig``, ``metge``): it does not move. A rig whose
#: clamp is released (``--set Quadrotor.clamped=false``) falls and tumbles; its run once
#: completed with errors of 64 to 93 deg, the vehicle 284 m below the ground.
CLAMPED = Bounds(tilt_error_deg=None, altitude_error_m=None, speed_m_s=0.1, held_s=0.05)
