"""``quadcosim log info|plot|replay|example``: a PX4 ULog or ArduPilot DataFlash flight log
(:mod:`quadcosim.scenarios.flightlog.command`)."""

from __future__ import annotations


def add(sub) -> None:
    """Add the ``log`` verb to the sub-parsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``quadcosim`` parser's sub-parsers.
    """
    from quadcosim.scenarios.flightlog import command as flightlog

    flightlog.add_arguments(sub.add_parser("log", help="read a PX4 ULog or ArduPilot DataFlash flight log"))
