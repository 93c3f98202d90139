"""quadcosim: run the quadrotor co-simulation scenarios, build the FMUs, benchmark the master.

  quadcosim build [--force]                build the plant FMUs (those not up to date) and the master's call runner
  quadcosim list [--parameters MODEL]      scenarios and their options (or an FMU's parameters)
  quadcosim run SCENARIO [--set k=v k2=v2 ...] [--estimator module:Class] [--out DIR] [--fault ...]
                                           (--set IMU.gyro_noise_density=0.001: an FMU parameter)
  quadcosim diagram SCENARIO [--out FILE]  picture of the wiring
  quadcosim plot RUN SIGNAL...             signals of a finished run (its folder) against time
  quadcosim compare RUN RUN... SIGNAL      one signal of several finished runs on one figure
  quadcosim bench [--json]                 speed of the master
  quadcosim bench infrared [--json]        IR calibration: operations per iteration, us per update
  quadcosim bench sweep [--json]           sweep engine: 40 closed-loop runs on 1 and 2 Dask workers
  quadcosim bench pytest [--json]          cost of a short test written with the pytest plugin
  quadcosim bench isolation [--json]       cost of an FMU run in a worker process of its own
  quadcosim sweep SCENARIO [--grid k=a:b:logN]... [--set k=v]... [--seeds N] [--workers N | --scheduler ADDR]
                  [--out DIR] [--resume]  the scenario over a grid, on Dask (see `quadcosim sweep -h`)
  quadcosim sweep-plot DIR METRIC --x OPTION [--by OPTION]   a metric of a sweep against an option
  quadcosim tune SCENARIO --minimize METRIC --over NAME=LOW:HIGH[:log]... [--seeds N] [--budget N]
                  [--workers N | --scheduler ADDR] [--out DIR] [--resume]   the options that minimise it
  quadcosim replay RECORDING [--estimator KIND] [--figure FILE]   an estimator on a recorded file, scored
  quadcosim log info|plot FILE             a PX4 or ArduPilot flight log: what it holds, an overview figure
  quadcosim calibrate FILE... --compass N --out DIR   the magnetometer and its motor interference from flights
  quadcosim study NAME [...]              a study the documentation's figures come from (quadcosim study NAME -h)
  quadcosim bench NAME [...]              a measurement of the documentation (real-recordings, tuning, ...)
"""

from __future__ import annotations

import argparse
import importlib
import sys

#: The verbs' modules (:mod:`quadcosim.cli.run`, ...), in the order ``quadcosim --help`` lists them.
#: Each has ``add(sub)``, which adds its verbs to the sub-parsers ``sub`` with their ``func``.
VERBS = ("build", "listing", "run", "diagram", "bench", "replay", "plot", "sweep", "tune", "log", "calibrate",
         "study")

#: The verbs whose work may compile the numba steps: said before, not in silence.
COMPILING = ("run", "sweep", "tune", "bench", "build")


def _version() -> str:
    """The installed package's version (pyproject.toml's), or ``unknown`` outside an installation."""
    from importlib import metadata

    try:
        return metadata.version("quadcosim")
    except metadata.PackageNotFoundError:
        return "unknown (not installed: pip install -e .)"


def parser() -> argparse.ArgumentParser:
    """The ``quadcosim`` argument parser, one sub-command per verb (:data:`VERBS`)."""
    from quadcosim.scenarios.shown import PlainHelp

    p = argparse.ArgumentParser(prog="quadcosim", description=__doc__, formatter_class=PlainHelp)
    p.add_argument("--version", action="version", version=f"quadcosim {_version()}")
    sub = p.add_subparsers(dest="command", required=True)
    for verb in VERBS:
        importlib.import_module(f"quadcosim.cli.{verb}").add(sub)
    return p


def _prog(args) -> str:
    """The command as its messages name it: ``quadcosim VERB`` and its suite or scenario when it has one."""
    words = ["quadcosim", args.command]
    if getattr(args, "log_command", None):
        words.append(args.log_command)
    for positional in ("suite", "scenario"):
        if isinstance(getattr(args, positional, None), str):
            words.append(getattr(args, positional))
    return " ".join(words)


def main(argv=None) -> int:
    """Run ``quadcosim`` with ``argv`` (the process arguments if None); returns the exit code.

    Every verb raises: :class:`quadcosim.infra.command.Command` turns what it raised into its
    message and exit code, the one place that does.

    Parameters
    ----------
    argv : list of str, optional
        The arguments after ``quadcosim``.

    Returns
    -------
    int
        The exit code.
    """
    from quadcosim.infra.command import Command

    command = Command("quadcosim")
    return command.run(_verb, command, argv)


def _verb(command, argv) -> int | None:
    """Read ``argv`` (the process's arguments if None), name ``command`` after the verb, and do it."""
    final = argv is None  # the process's own command line, not a call from Python
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["replay"]:  # the replay's own parser (its options depend on the estimator)
        from quadcosim.cli import replay

        command.prog = "quadcosim replay"
        return replay.main(argv[1:])
    if argv[:1] == ["study"]:  # each study's own parser
        from quadcosim.cli import study

        command.prog = " ".join(["quadcosim", *argv[:2]])
        return study.main(argv[1:])
    from quadcosim.cli import bench

    if argv[:1] == ["bench"] and argv[1:2] and argv[1] in bench.MEASUREMENTS:  # each measurement's own parser
        command.prog = f"quadcosim bench {argv[1]}"
        return bench.measurement(argv[1], argv[2:])
    args = parser().parse_args(argv)
    args.final = final
    command.prog = _prog(args)
    if args.command in COMPILING:
        from quadcosim.scenarios.compiled import announce_compiles

        announce_compiles()
    return args.func(args)


def entry(argv=None) -> None:
    """The ``quadcosim`` program: :func:`main`, then exit with its code
    (:func:`quadcosim.infra.command.program`).

    Parameters
    ----------
    argv : list of str, optional
        The arguments after ``quadcosim`` (the process's own if None).
    """
    from quadcosim.infra.command import program

    program(main, argv)
