"""``quadcosim replay RECORDING``: an estimator on a recorded IMU file, a tp run's folder or a flight
log, scored against its reference attitude (:mod:`quadcosim.scenarios.replay`, whose parser it
is: its options depend on the estimator)."""

from __future__ import annotations

import argparse


def add(sub) -> None:
    """Add the ``replay`` verb to the sub-parsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``quadcosim`` parser's sub-parsers.
    """
    replay = sub.add_parser("replay", add_help=False,
                            help="any estimator on a recorded IMU file or a tp run's folder, scored against its "
                                 "reference attitude (quadcosim replay --help)")
    replay.add_argument("rest", nargs=argparse.REMAINDER)  # quadcosim.cli.main hands them to main()


def main(argv) -> int:
    """``quadcosim replay`` with the arguments ``argv`` after it; returns 0 or raises.

    Parameters
    ----------
    argv : list of str
        The arguments after ``replay``.
    """
    from quadcosim.scenarios.replay import command

    return command(argv, prog="quadcosim replay")
