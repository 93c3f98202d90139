"""What a wrong firmware rule costs the exported calibration: the export made under each wrong
rule, applied as the log's firmware really applies it, on the same score part as the export
made under the right rules (:func:`quadcosim.scenarios.flightlog.calibrate.split_parts`: fitted on the
first half, chosen on the third quarter, scored on the last).

The wrong rules: the motor offset's order of the other era (after the soft iron, Copter 3.6 and
later, on a 3.4 log; before it on a later one);
``AHRS_TRIM`` ignored (the vehicle's attitude taken for the board's); the Earth field fitted free
per flight instead of the World Magnetic Model; the mean RC3-normalised motor output instead of
the autopilot's own throttle ``CTUN.ThO`` (that one with the ``throttle`` compensation alone, the
only one it touches).
"""

from __future__ import annotations

from dataclasses import replace

WRONG_RULES = ("other_order", "no_trim", "free_earth", "pwm_throttle")


def _heading(split, params) -> float:
    from quadcosim.calibration.flight.export import score_parameters

    return score_parameters(split.score, params, offset_from=[*split.fit, *split.choice])["heading_rms_deg"]


def costs(log, compass: int) -> dict:
    """Heading error (deg RMS) on the score part of the export of ``log``'s (a FlightLog) compass
    ``compass`` made under the right rules (``right``; ``right_throttle`` with the throttle
    compensation alone) and under each of :data:`WRONG_RULES`, every one applied with the log's
    own firmware rules."""
    from quadcosim.calibration.flight.export import choose
    from quadcosim.flightlogs.autopilots.ardupilot import firmware as ardupilot
    from quadcosim.scenarios.flightlog.calibrate import split_parts

    right = split_parts([log], [], compass)
    found = {"right": _heading(right, choose(right.fit, right.choice)[0]),
             "right_throttle": _heading(right, choose(right.fit, right.choice, models=("throttle",))[0])}
    # the other era's order: the export written for the rules it does not have, loaded by its own firmware
    other = ardupilot.rules((3, 5) if ardupilot.log_rules(log.firmware).motor_after_soft_iron else (3, 6))
    found["other_order"] = _heading(right, choose(right.fit, right.choice, other)[0])
    for name, split in (("no_trim", split_parts([log], [], compass, trim=False)),
                        ("free_earth", split_parts([log], [], compass, earth="free"))):
        found[name] = _heading(right, choose(split.fit, split.choice)[0])
    pwm = split_parts([replace(log, throttle=None)], [], compass)
    found["pwm_throttle"] = _heading(right, choose(pwm.fit, pwm.choice, models=("throttle",))[0])
    return found
