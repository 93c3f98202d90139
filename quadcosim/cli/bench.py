"""``quadcosim bench [SUITE]``: the benchmarks (:mod:`quadcosim.benchmarks`), each suite's own
options shared with its ``python -m quadcosim.benchmarks.SUITE``."""

from __future__ import annotations

import importlib

from quadcosim.infra.errors import UsageError

#: The suites, by name, and the module of each (its ``main(argv)`` returns the exit code).
SUITES = {"master": "master", "infrared": "infrared", "sweep": "sweep", "pytest": "pytest_cost",
          "isolation": "isolation"}

#: The measurements the documentation's figures come from, by name, and the module of each: their
#: options are their own (``quadcosim bench NAME --help``), also ``python -m quadcosim.benchmarks.MODULE``.
MEASUREMENTS = {name.replace("_", "-"): name for name in (
    "estimators", "fuzz", "gaps", "magnetic", "memory", "real_recordings", "run_cost", "save", "startup", "study",
    "sweep_memory", "tuning")}


def add(sub) -> None:
    """Add the ``bench`` verb to the sub-parsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``quadcosim`` parser's sub-parsers.
    """
    bench = sub.add_parser("bench", help="benchmarks: co-simulation master, IR calibration cost, sweep engine, "
                                         "pytest plugin, an FMU in a worker process")
    bench.add_argument("suite", nargs="?", default="master", choices=tuple(SUITES),
                       help="what to time: master (the co-simulation loop, the default), infrared (the IR "
                            "calibration's cost per update), sweep (40 closed-loop runs on Dask), pytest (the "
                            "pytest plugin's fixtures) or isolation (an FMU in a worker process against in process); "
                            f"also, each with its own options, {', '.join(MEASUREMENTS)}")
    bench.add_argument("--json", action="store_true",
                       help="print the measurements as one JSON object on standard output instead of a table")
    bench.add_argument("--seconds", type=float, default=5.0, metavar="S",
                       help="simulated time of each timed run of the master suite (s, default 5)")
    bench.add_argument("--out", metavar="FILE",
                       help="the master suite: also draw its figures (PNG, SVG or PDF file, or a folder: bench.png)")
    bench.set_defaults(func=command)


def command(args) -> int:
    """Time the suite ``args.suite``; returns its exit code.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed ``bench`` arguments.
    """
    if args.out and args.suite != "master":
        raise UsageError("--out draws the master suite's figures only; drop --out, or run "
                         "quadcosim bench --out FILE")
    suite = importlib.import_module(f"quadcosim.benchmarks.{SUITES[args.suite]}")
    argv = ["--json"] if args.json else []
    if args.suite == "master":
        argv += ["--seconds", str(args.seconds)] + (["--out", args.out] if args.out else [])
    return suite.main(argv)


def measurement(name: str, argv: list) -> int:
    """``quadcosim bench NAME ARGS...`` for a measurement of :data:`MEASUREMENTS`: its own
    ``main(ARGS)``.

    Parameters
    ----------
    name : str
        The measurement.
    argv : list of str
        Its arguments.
    """
    return importlib.import_module(f"quadcosim.benchmarks.{MEASUREMENTS[name]}").main(argv)
