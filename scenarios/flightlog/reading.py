"""A flight log read for a command, its warnings announced: shared by the ``log`` verbs, the
replay and the calibration."""

from __future__ import annotations

import sys


def load(path, verb: str):
    """The :class:`quadcosim.flightlogs.FlightLog` at ``path``, with a simulator log and corruption read
    past announced on standard error, prefixed by ``verb``; raises ``LogError``."""
    from quadcosim.flightlogs import read_log

    log = read_log(path)
    if log.simulator:
        print(f"quadcosim {verb}: warning: {path} is a simulator (SITL) log; its sensors are simulated, not "
              "a real vehicle's", file=sys.stderr)
    for warning in log.warnings:
        print(f"quadcosim {verb}: warning: {path}: {warning}", file=sys.stderr)
    return log
