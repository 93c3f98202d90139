"""Findings of the default vehicle at hover: its trim, its motors' time constant and what follows.

All come from ``python -m quadcosim.studies.hover`` (:func:`quadcosim.studies.hover.figures`), a second of the
MotorMagnetics FMU at the hover command and a small step from there, and the drag model's
predictions; deterministic, a few seconds in all.
"""

from __future__ import annotations

from findings import finding

COMMAND = "python -m quadcosim.studies.hover"
# name, key of quadcosim.studies.hover.figures, unit, tolerance, digits (tolerances: the printed rounding,
# the figures being deterministic; the time constant is read on a 0.1 ms grid)
FIGURES = (
    ("command", "command", "1", 5e-4, 2),
    ("omega_rad_s", "omega_rad_s", "rad/s", 0.05, 0),
    ("current_a", "current_a", "A", 5e-3, 1),
    ("motor_time_constant_ms", "motor_time_constant_ms", "ms", 0.1, 0),
    ("yaw_spin_up_ratio", "yaw_spin_up_ratio", "1", 0.02, 1),
    ("drag_time_constant_s", "drag_time_constant_s", "s", 5e-3, 1),
    ("cruise_pitch_deg", "cruise_pitch_deg", "deg", 5e-3, 2),
)


def compute(quick: bool = False) -> list[dict]:
    """The hover findings (the same, and fast, with ``quick``)."""
    from quadcosim.studies.hover import figures

    measured = figures()
    return [finding(f"plant.hover.{name}", measured[key], unit, COMMAND, tolerance, digits)
            for name, key, unit, tolerance, digits in FIGURES]
