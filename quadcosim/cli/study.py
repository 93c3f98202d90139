"""``quadcosim study NAME [ARGS...]``: a study or measurement the documentation's figures come
from, each with its own options (``quadcosim study NAME --help``). Each is also
``python -m MODULE``: the same parser and the same work, through the same exit codes."""

from __future__ import annotations

import argparse
import importlib

from quadcosim.infra.errors import UsageError

#: The studies, by name, and the module of each in ``quadcosim`` (its ``main(argv)`` returns the exit code).
STUDIES = {
    "ablation": "scenarios.ablation",
    "agreement": "fmus.agreement",
    "hover": "studies.hover",
    "ir-detectability": "studies.ir_detectability",
    "ir-detection": "studies.ir_detection",
    "ir-slides": "studies.ir_slides",
    "lab-matrix": "studies.lab_matrix",
    "mag-rate": "studies.mag_rate",
    "metge": "studies.metge",
    "recording": "estimators.recording",
    "yaw-loop": "studies.yaw_loop",
}


def add(sub) -> None:
    """Add the ``study`` verb to the sub-parsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``quadcosim`` parser's sub-parsers.
    """
    study = sub.add_parser("study", add_help=False,
                           help=f"a study the documentation's figures come from: {', '.join(STUDIES)} "
                                "(quadcosim study NAME --help)")
    study.add_argument("rest", nargs=argparse.REMAINDER)  # quadcosim.cli.main hands them to main()


def main(argv) -> int:
    """``quadcosim study NAME ARGS...``: the study's own ``main(ARGS)``.

    Parameters
    ----------
    argv : list of str
        The arguments after ``study``: the study's name, then its own.
    """
    if argv[:1] in (["-h"], ["--help"]):
        print("usage: quadcosim study NAME [ARGS...]   (quadcosim study NAME --help: its options)\n\nstudies:")
        for name, module in STUDIES.items():
            print(f"  {name:18s} python -m quadcosim.{module}")
        return 0
    if not argv or argv[0] not in STUDIES:
        given = f"{argv[0]!r}: not a study" if argv and not argv[0].startswith("-") else "give a study"
        raise UsageError(f"{given}; choose one of {', '.join(STUDIES)} (quadcosim study NAME --help)")
    return importlib.import_module(f"quadcosim.{STUDIES[argv[0]]}").main(argv[1:])
