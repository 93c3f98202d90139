"""``quadcosim calibrate FILE... --compass N --out DIR``: a magnetometer and its motor interference
from real flights, with ArduPilot and PX4 parameters (:mod:`quadcosim.scenarios.flightlog.calibrate`)."""

from __future__ import annotations


def add(sub) -> None:
    """Add the ``calibrate`` verb to the sub-parsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``quadcosim`` parser's sub-parsers.
    """
    from quadcosim.scenarios.flightlog import calibrate

    calibrate.add_arguments(sub.add_parser("calibrate", help="calibrate a magnetometer and its motor interference "
                                           "from real flights; ArduPilot and PX4 parameters"))
