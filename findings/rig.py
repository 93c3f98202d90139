"""Findings of the clamped rig without calibration: the field the motor currents make (``quadcosim run rig``)."""

from __future__ import annotations

from findings import finding

RUN = "quadcosim run rig"


def compute(quick: bool = False) -> list[dict]:
    """The mean angular error of the measured field, one motor at a time and on the free set
    (a few seconds: the quick subset too)."""
    from quadcosim import scenarios

    m = scenarios.run("rig", {})[1]
    return [finding("rig.single_motor_deg", m["mean_angular_error_single_motor_deg"], "deg", RUN, 0.005, 1),
            finding("rig.free_deg", m["mean_angular_error_deg"]["free"], "deg", RUN, 0.005, 1)]
