"""Findings of what the quad's three flight logs hold: battery current range and logging rates.

``quadcosim log info logs/FLIGHT`` prints them (:mod:`quadcosim.flightlogs.info`): the battery
current's range (A) and the rates (Hz) of the internal compass (``MAG2``, the one the
documentation calibrates) and of the motor outputs. The logs are read from
``$QUADCOSIM_FLIGHT_LOGS`` (see :mod:`findings.flightlogs`); without it the group is
skipped. Reading three logs takes seconds: the quick subset is the whole group.
"""

from __future__ import annotations

from findings import finding
from findings.flightlogs import FLIGHTS, _path, _shown

COMPASS = 1  # the internal compass, MAG2
CURRENT_TOLERANCE_A = 0.06  # A: read from the log; the command prints 1 decimal (a half-way value rounds either way)
RATE_TOLERANCE_HZ = 0.06  # Hz: from the time stamps; printed to 1 decimal, as the current


def flight(key: str) -> list[dict]:
    """The findings of flight ``key`` (``a``, ``b`` or ``c``).

    Parameters
    ----------
    key : str
        A flight of :data:`findings.flightlogs.FLIGHTS`.
    """
    from quadcosim.flightlogs import read_log
    from quadcosim.flightlogs.info import summary

    info = summary(read_log(_path(key)))
    command = f"quadcosim log info {_shown(key)}"
    low, high = info["battery"]["current_range_A"]
    prefix = f"log_info.{key}"
    return [finding(f"{prefix}.current_min_a", low, "A", command, CURRENT_TOLERANCE_A, 1),
            finding(f"{prefix}.current_max_a", high, "A", command, CURRENT_TOLERANCE_A, 1),
            finding(f"{prefix}.compass_rate_hz", info["compasses"][COMPASS]["rate_hz"], "Hz", command,
                    RATE_TOLERANCE_HZ, 1),
            finding(f"{prefix}.motors_rate_hz", info["motors"]["rate_hz"], "Hz", command, RATE_TOLERANCE_HZ, 1)]


def compute(quick: bool = False) -> list[dict]:
    """The three flights' findings (the same with ``quick``: seconds)."""
    return [f for key in FLIGHTS for f in flight(key)]
