"""Start-up time of the command line: wall time of ``quadcosim list``, ``quadcosim --help`` and others.

Each command runs in a fresh interpreter (``python -m quadcosim.main ...``) ``repeats`` times;
the median and the spread (min, max) of the wall times are printed, and the modules among
:data:`HEAVY` that the command imported::

    python -m quadcosim.benchmarks.startup                      # list and --help, 5 runs each
    python -m quadcosim.benchmarks.startup --repeats 3 -- run tp --out /tmp/tp --overwrite
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

# packages a command should import only when it uses them
HEAVY = ("control", "dask", "distributed", "matplotlib", "pyarrow", "scipy", "scipy.optimize", "scipy.io",
         "numba", "fmpy", "vqf", "ahrs", "calibration", "quadcosim.estimators.analysis")

_REPORT = ("import atexit, os, sys, json\n"
           "def _report():\n"
           "    with open(os.environ['QUADCOSIM_IMPORTED'], 'w') as f:\n"
           "        json.dump(sorted(m for m in sys.modules), f)\n"
           "atexit.register(_report)\n"
           "from quadcosim.main import main\n"
           "sys.argv[0] = 'quadcosim'\n"
           "sys.exit(main())\n")


def imported_modules(args: list[str], env: dict | None = None) -> set[str]:
    """Names in ``sys.modules`` at the exit of ``quadcosim ARGS`` run in a fresh interpreter.

    Parameters
    ----------
    args : list of str
        Arguments after ``quadcosim``, e.g. ``["list"]``.
    env : dict, optional
        Environment of the subprocess (default: this process's).

    Returns
    -------
    set of str
        Module names imported by the command (including the interpreter's own).
    """
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "modules.json")
        subprocess.run([sys.executable, "-c", _REPORT, *args], check=True, capture_output=True,
                       env=(env or os.environ) | {"QUADCOSIM_IMPORTED": path})
        with open(path) as f:
            return set(json.load(f))


def child_times(argv: list[str], **options) -> tuple[float, float]:
    """Wall and CPU times (s) of one child process ``argv``, run to its end (a non-zero exit raises).

    Parameters
    ----------
    argv : list of str
        The program and its arguments.
    **options
        For :func:`subprocess.run` (``env``, ``stdout``, ``stderr``).

    Returns
    -------
    wall, cpu : float
        Its wall time, and its CPU (user + system of the finished child), s.
    """
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run(argv, check=True, **options)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime


def wall_times(args: list[str], repeats: int) -> tuple[list[float], list[float]]:
    """Wall and CPU times (s) of ``repeats`` runs of ``quadcosim ARGS``, each in a fresh interpreter.

    Parameters
    ----------
    args : list of str
        Arguments after ``quadcosim``.
    repeats : int
        Number of runs.

    Returns
    -------
    walls, cpus : list of float
        One wall time and one CPU time (user + system of the child) per run, s.
    """
    times = [child_times([sys.executable, "-m", "quadcosim.main", *args], stdout=subprocess.DEVNULL)
             for _ in range(repeats)]
    return [wall for wall, _ in times], [cpu for _, cpu in times]


#: The commands timed by default: ``quadcosim list`` and ``quadcosim --help``.
DEFAULT_COMMANDS = (["list"], ["--help"])


def measure(commands=DEFAULT_COMMANDS, repeats: int = 5) -> dict:
    """Wall and CPU times of each command over ``repeats`` fresh interpreters, and its heavy imports.

    Parameters
    ----------
    commands : sequence of list of str
        Arguments after ``quadcosim``, one list per command.
    repeats : int
        Runs per command.

    Returns
    -------
    dict
        ``"list"`` (the command's words joined by spaces) -> ``median_s``, ``min_s``, ``max_s``
        (wall, s), ``median_cpu_s`` (user + system of the child, s) and ``heavy_imports`` (the
        modules of :data:`HEAVY` it imported).
    """
    figures = {}
    for command in commands:
        times, cpus = wall_times(command, repeats)
        heavy = sorted(m for m in HEAVY if m in imported_modules(command))
        figures[" ".join(command)] = {"median_s": statistics.median(times), "min_s": min(times),
                                      "max_s": max(times), "median_cpu_s": statistics.median(cpus),
                                      "heavy_imports": heavy}
    return figures


def main(argv=None) -> int:
    """Print the median wall time and the heavy imports of each command; returns 0.
    ``argv``: the arguments (default ``sys.argv[1:]``)."""
    parser = argparse.ArgumentParser(prog="python -m quadcosim.benchmarks.startup", description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="runs per command")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("command", nargs="*", help="one quadcosim command (default: list, then --help)")
    args = parser.parse_args(argv)
    figures = measure([args.command] if args.command else DEFAULT_COMMANDS, args.repeats)
    if args.json:
        print(json.dumps(figures))
    else:
        for command, f in figures.items():
            print(f"quadcosim {command}: median {f['median_s']:.2f} s (min {f['min_s']:.2f}, max {f['max_s']:.2f}, "
                  f"{args.repeats} runs; CPU {f['median_cpu_s']:.2f} s); heavy imports: "
                  f"{', '.join(f['heavy_imports']) or 'none'}")
    return 0


if __name__ == "__main__":  # the same as quadcosim bench startup
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench startup").run, main)
