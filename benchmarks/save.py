"""What saving costs in a long run: ``save_fraction``, the CPU of writing a 320 s ``tp``
run's record over the CPU of the whole run (``quadcosim bench`` reports it).

``python -m quadcosim.benchmarks.save [--duration 320] [--compressed] [--stream-peak] [--json]``

The run is ``quadcosim.scenarios.run("tp", duration=320)`` into a temporary folder, in this process,
after a short run that loads the compiled steps. Its CPU time (``time.process_time``: the
build, the loop, the save, the report and its figures) is measured around the call; the save's
CPU is the time :class:`quadcosim.scenarios.outputs.RunFiles` spends writing the record
(``metrics.json``'s ``save_cpu_s``). ``--compressed`` measures the compressed archive too.

``--stream-peak`` measures, instead of the save's share, how flat ``--stream`` keeps memory: the
peak resident set of ``quadcosim run tp --stream`` (bench supply on) for 60 s and 3600 s of
flight, each in a child process (:func:`quadcosim.benchmarks.memory.peak_rss`), and their ratio (with
``--compressed`` the save's share is measured as well).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

#: Simulated seconds of the run whose save is measured.
DURATION_S = 320.0


def save_fraction(duration: float = DURATION_S, compress: bool = False) -> dict:
    """CPU of a ``tp`` run's save over the CPU of the whole run.

    Parameters
    ----------
    duration : float
        Simulated seconds of the run.
    compress : bool
        Write the compressed archive (``--compress``).

    Returns
    -------
    dict
        ``fraction``, ``save_cpu_s`` and ``run_cpu_s`` (s of CPU), ``record_mb`` (the
        ``results.npz`` written, MB).
    """
    from quadcosim import scenarios

    with tempfile.TemporaryDirectory() as folder:
        scenarios.run("tp", {"duration": 1.0}, Path(folder) / "warm-up")  # compiled steps loaded
        out = Path(folder) / "run"
        started = time.process_time()
        _, metrics = scenarios.run("tp", {"duration": duration, "bench_supply": True}, out, compress=compress)
        run_cpu = time.process_time() - started
        size = (out / "results.npz").stat().st_size
    return {"fraction": metrics["save_cpu_s"] / run_cpu, "save_cpu_s": metrics["save_cpu_s"],
            "run_cpu_s": run_cpu, "record_mb": size / 1e6}


def figures(duration: float = DURATION_S) -> dict:
    """The keys ``quadcosim bench --json`` adds: ``save_fraction`` (default, uncompressed
    save), ``save_cpu_s`` and ``save_run_cpu_s`` of a ``duration`` s ``tp`` run."""
    measured = save_fraction(duration)
    return {"save_fraction": measured["fraction"], "save_cpu_s": measured["save_cpu_s"],
            "save_run_cpu_s": measured["run_cpu_s"]}


def stream_peak(durations=(60.0, 3600.0)) -> dict:
    """Peak memory of streamed ``tp`` runs of each duration and the ratio of the longest to the shortest.

    Parameters
    ----------
    durations : sequence of float
        Simulated seconds of each run.

    Returns
    -------
    dict
        ``peak_mb`` (duration to MB) and ``ratio`` (longest over shortest).
    """
    from quadcosim.benchmarks.memory import peak_rss

    peaks = {}
    for duration in durations:
        with tempfile.TemporaryDirectory() as folder:
            peaks[duration] = peak_rss([sys.executable, "-m", "quadcosim.main", "run", "tp", "--set",
                                        f"duration={duration:g}", "bench_supply=on", "--stream", "--out",
                                        str(Path(folder) / "run")]) / 1e6
    return {"peak_mb": peaks, "ratio": peaks[max(durations)] / peaks[min(durations)]}


def main(argv=None) -> int:
    """Print the save's share of a long run's CPU (uncompressed, and compressed if asked), or with
    ``--stream-peak`` the streamed runs' peak memory.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (the process's by default).
    """
    parser = argparse.ArgumentParser(prog="python -m quadcosim.benchmarks.save", description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=DURATION_S, help="simulated seconds (default 320)")
    parser.add_argument("--compressed", action="store_true", help="measure the compressed archive too")
    parser.add_argument("--stream-peak", action="store_true", help="peak memory of 60 s and 3600 s streamed runs")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    found = {} if args.stream_peak and not args.compressed else {"uncompressed": save_fraction(args.duration)}
    if args.compressed:
        found["compressed"] = save_fraction(args.duration, compress=True)
    peak = stream_peak() if args.stream_peak else None
    if args.json:
        print(json.dumps(found | ({"stream_peak": peak} if peak else {})))
    else:
        if peak:
            shortest, longest = min(peak["peak_mb"]), max(peak["peak_mb"])
            print(f"--stream peak memory: {peak['peak_mb'][longest]:.0f} MB for {longest:g} s of flight, "
                  f"{peak['peak_mb'][shortest]:.0f} MB for {shortest:g} s, ratio {peak['ratio']:.2f}")
        for kind, measured in found.items():
            print(f"{kind:13s} save_fraction {measured['fraction']:.3f}: save {measured['save_cpu_s']:.3f} s of "
                  f"{measured['run_cpu_s']:.2f} s CPU, results.npz {measured['record_mb']:.0f} MB")
    return 0


if __name__ == "__main__":  # the same as quadcosim bench save
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench save").run, main)
