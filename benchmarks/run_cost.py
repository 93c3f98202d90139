"""What a short run costs against a long one: the CPU of ``quadcosim run tp`` for 2 s and 320 s of flight.

``python -m quadcosim.benchmarks.run_cost [--short 2] [--long 320] [--repeats 3] [--in-process] [--parts] [--json]``

Each run is the command a user types, ``quadcosim run tp --set duration=D --out DIR
--overwrite``, in a fresh interpreter: its CPU (user and system, ``resource.getrusage`` of the
finished child) is the whole run, the interpreter's start, the imports, the system built, the
wiring diagram, the loop, the record written, the report and its figures. One warm-up run first
fills numba's cache and the diagram cache, as any earlier run on the machine has. The short
and the long run alternate, so that a load on the machine weighs on both alike; the ratio of
each pair is printed, then the median of the ratios.

With ``--in-process`` the runs are :func:`quadcosim.scenarios.run` calls in this one process, after a
first run that paid the imports: what a run costs in a notebook, a test session or a sweep's
worker, where the interpreter, numba and matplotlib are loaded once. Each run still builds its
system, draws (or copies) its wiring, writes its record and draws its report.

A short run costs what it simulates when the ratio approaches ``short / long``; what stays
above that is the start-up every run pays (the imports, numba's target, matplotlib's figures).
``--parts`` measures what a fresh interpreter pays to load each of them (:data:`PARTS`), and
the ratio of each pair with numba's or matplotlib's loading, or both, taken off both runs.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from quadcosim.benchmarks.startup import child_times

SHORT_S, LONG_S = 2.0, 320.0  # simulated seconds of the two runs compared


def run_cpu(duration: float, out: Path) -> float:
    """CPU seconds (user + system) of ``quadcosim run tp`` for ``duration`` s of flight, in a
    fresh interpreter, writing into ``out``.

    Parameters
    ----------
    duration : float
        Simulated time (s).
    out : pathlib.Path
        The run's output folder (replaced).

    Returns
    -------
    float
        CPU of the whole process (s).
    """
    return child_times([sys.executable, "-m", "quadcosim.main", "run", "tp", "--set", f"duration={duration:g}",
                        "--out", str(out), "--overwrite"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)[1]


def run_cpu_in_process(duration: float, out: Path) -> float:
    """CPU seconds of :func:`quadcosim.scenarios.run` of ``tp`` for ``duration`` s of flight in this process,
    writing into ``out`` (replaced), as ``quadcosim run`` writes.

    Parameters
    ----------
    duration : float
        Simulated time (s).
    out : pathlib.Path
        The run's output folder (replaced).

    Returns
    -------
    float
        CPU of this process during the run (s, every thread).
    """
    from quadcosim import scenarios

    started = time.process_time()
    scenarios.run("tp", {"duration": duration}, out_dir=out, overwrite=True)
    return time.process_time() - started


def measure(short: float = SHORT_S, long: float = LONG_S, repeats: int = 3, in_process: bool = False) -> dict:
    """CPU of ``repeats`` pairs of runs, short then long, and the ratio of each pair.

    Parameters
    ----------
    short, long : float
        Simulated time of the two runs (s).
    repeats : int
        Pairs measured.
    in_process : bool
        Runs in this process (:func:`run_cpu_in_process`), not each in a fresh interpreter.

    Returns
    -------
    dict
        ``short_cpu_s`` and ``long_cpu_s`` (s, one per pair), ``ratios`` (1, one per pair),
        ``median_ratio`` (1) and ``simulated_ratio`` (``short / long``, the floor).
    """
    cpu = run_cpu_in_process if in_process else run_cpu
    with tempfile.TemporaryDirectory() as folder:
        cpu(short, Path(folder) / "warm-up")  # numba's and the diagram's caches (and, in process, the imports)
        shorts, longs = [], []
        for _ in range(repeats):
            shorts.append(cpu(short, Path(folder) / "short"))
            longs.append(cpu(long, Path(folder) / "long"))
    ratios = [s / lo for s, lo in zip(shorts, longs, strict=True)]
    return {"short_s": short, "long_s": long, "short_cpu_s": shorts, "long_cpu_s": longs, "ratios": ratios,
            "median_ratio": statistics.median(ratios), "simulated_ratio": short / long}


#: What a fresh ``quadcosim run tp`` loads before it simulates, by name: what it is, and the
#: statement a fresh interpreter runs on top of those before it (with the command's one BLAS thread).
PARTS = {
    "interpreter": ("the interpreter", "pass"),
    "numpy": ("numpy and fmpy", "import numpy, fmpy"),
    "numba": ("the estimators and the controller, with numba and their two compiled steps from its cache",
              "import quadcosim.estimators.filters as e, quadcosim.flight.controller as c; "
               "e._compiled_step(); c._compiled_step()"),
    "matplotlib": ("matplotlib's pyplot", "import matplotlib; matplotlib.use('agg'); import matplotlib.pyplot"),
}
#: The loads :func:`without_loading` takes off both runs, alone and together: what only the
#: compiled steps and the figures need.
ABLATIONS = {"numba": ("numba",), "matplotlib": ("matplotlib",), "both": ("numba", "matplotlib")}


def statement_cpu(statement: str, repeats: int = 5) -> float:
    """Median CPU seconds (user + system) of a fresh interpreter running ``statement``.

    Parameters
    ----------
    statement : str
        Python code, as for ``python -c``.
    repeats : int
        Interpreters started.

    Returns
    -------
    float
        CPU of the whole process (s).
    """
    import os

    environment = {**os.environ, "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS", "1")}
    return statistics.median(child_times([sys.executable, "-c", statement], env=environment)[1]
                             for _ in range(repeats))


def parts(repeats: int = 5) -> dict[str, float]:
    """The CPU each of :data:`PARTS` adds to a fresh interpreter (s).

    Parameters
    ----------
    repeats : int
        Interpreters started for each part (the median is kept).

    Returns
    -------
    dict
        By the names of :data:`PARTS`, in order: the CPU of the statements up to that part's less
        that of those before it (s).
    """
    added, statement, before = {}, "", 0.0
    for name, (_, code) in PARTS.items():
        statement = f"{statement}; {code}" if statement else code
        cumulated = statement_cpu(statement, repeats)
        added[name] = cumulated - before
        before = cumulated
    return added


def without_loading(figures: dict) -> dict:
    """The median, over the pairs, of the short run's CPU over the long run's, each less what
    loading some of :data:`PARTS` costs a fresh interpreter: each of :data:`ABLATIONS`.

    Parameters
    ----------
    figures : dict
        :func:`measure`'s figures of fresh commands, with ``parts_cpu_s`` (:func:`parts`).

    Returns
    -------
    dict
        ``ratio_without`` (1): by the names of :data:`ABLATIONS`, the median ratio with those
        loads taken off both runs of each pair.
    """
    ratios = {}
    for ablation, names in ABLATIONS.items():
        loaded = sum(figures["parts_cpu_s"][name] for name in names)
        if loaded >= min(figures["short_cpu_s"]):
            raise RuntimeError(f"loading {' and '.join(names)} took {loaded:.2f} s, more than a whole short run "
                               f"({min(figures['short_cpu_s']):.2f} s): the machine's load moved between the "
                               "measurements; run again")
        ratios[ablation] = statistics.median((short - loaded) / (long - loaded) for short, long in
                                             zip(figures["short_cpu_s"], figures["long_cpu_s"], strict=True))
    return {"ratio_without": ratios}


def main(argv=None) -> int:
    """Print the CPU of each run and the ratios; returns 0. ``argv``: the arguments (default
    ``sys.argv[1:]``)."""
    parser = argparse.ArgumentParser(prog="python -m quadcosim.benchmarks.run_cost",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--short", type=float, default=SHORT_S, help="simulated time of the short run (s, default 2)")
    parser.add_argument("--long", type=float, default=LONG_S, help="simulated time of the long run (s, default 320)")
    parser.add_argument("--repeats", type=int, default=3, help="pairs of runs measured (default 3)")
    parser.add_argument("--in-process", action="store_true",
                        help="runs as quadcosim.scenarios.run calls in this process, after one that paid the imports")
    parser.add_argument("--parts", action="store_true",
                        help="also the CPU of what a fresh run loads before it simulates (the interpreter, numpy "
                             "and fmpy, the estimators and the controller with numba and their compiled steps, "
                             "matplotlib), and the ratio with the last two taken off both runs, each and together")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    if args.parts and args.in_process:
        parser.error("--parts measures fresh interpreters, which runs in one process do not start: give one of them")
    figures = measure(args.short, args.long, args.repeats, args.in_process)
    if args.parts:
        figures["parts_cpu_s"] = parts()
        figures |= without_loading(figures)
    if args.json:
        print(json.dumps(figures))
        return 0
    for k, (s, lo, r) in enumerate(zip(figures["short_cpu_s"], figures["long_cpu_s"], figures["ratios"],
                                       strict=True)):
        print(f"pair {k + 1}: {args.short:g} s run {s:.2f} s CPU, {args.long:g} s run {lo:.2f} s CPU, ratio {r:.3f}")
    print(f"median ratio {figures['median_ratio']:.3f} (the simulated time's ratio: {figures['simulated_ratio']:.3f})")
    if args.parts:
        for name, cpu in figures["parts_cpu_s"].items():
            print(f"  loading {PARTS[name][0]}: {cpu:.2f} s CPU")
        for ablation, ratio in figures["ratio_without"].items():
            print(f"median ratio, each run less the load of {' and '.join(ABLATIONS[ablation])}: {ratio:.3f}")
    return 0


if __name__ == "__main__":  # the same as quadcosim bench run-cost
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench run-cost").run, main)
