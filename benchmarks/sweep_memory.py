"""How a sweep's client grows with its members: bytes of client memory per finished member.

``python -m quadcosim.benchmarks.sweep_memory [--members 20000] [--workers 2] [--json]``

A ``tp`` sweep over seeds 1..N runs on a real :class:`distributed.LocalCluster` (whose
scheduler lives in the client's process, as in every local sweep), through
:func:`quadcosim.studies.sweep.engine.run`. Each member returns, at once, the record of one real ``tp``
member (run once beforehand), so that the table rows have their real width and the cost is
the sweep engine's and Dask's alone, not the simulation's. The client's memory is sampled
each time another ``N / 40`` members have finished: its resident set, and with ``--traced``
the bytes Python's allocations hold (``tracemalloc``: what is live, not what the allocator
keeps for reuse; slower). The growth per
member is the slope of a least-squares line through the samples from ``N / 4`` members on (the
cluster started, the allocator's pools filled), in bytes per member.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
from pathlib import Path

MEMBERS = 20_000
FIT_FROM = 0.25  # share of the members after which the samples enter the fit
SAMPLES = 40


def resident_bytes() -> int:
    """This process's resident set (bytes), from ``/proc/self/statm``."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def canned_record() -> dict:
    """A real ``tp`` member's record (a 0.05 s run, seed 1), as a worker returns it."""
    from quadcosim.studies.sweep import engine

    return engine.run_member("tp", {"duration": 0.05})


def _canned(record):
    """A member function that returns ``record`` for any member (pickled by value to the workers)."""

    def member(scenario, options, keep_results=False, extra_metrics=None):
        return dict(record, metrics=dict(record["metrics"]), worker="bench")

    return member


def measure(members: int = MEMBERS, workers: int = 2, traced: bool = False) -> dict:
    """Run the sweep and fit the client's growth.

    Parameters
    ----------
    members : int
        Members of the sweep (seeds 1 to ``members``).
    workers : int
        Worker processes of the local cluster.
    traced : bool
        Also sample the bytes held by Python's allocations (``tracemalloc``).

    Returns
    -------
    dict
        ``bytes_per_member`` (the resident set's fitted slope, bytes), with ``traced``
        ``traced_bytes_per_member`` (the allocations' slope, bytes); ``samples`` (members
        finished, resident bytes, traced bytes or None), ``members``, ``workers``, ``seconds``
        (wall time of the sweep, s).
    """
    import time
    import tracemalloc

    import numpy as np
    from quadcosim.studies.sweep import engine, grid

    record = canned_record()
    samples = []
    step = max(1, members // SAMPLES)
    save = engine._save_member

    def sampled(out, member, saved, attempts, scenario):
        kept = save(out, member, saved, attempts, scenario)
        done = len(samples) * step
        if sampled.count >= done:
            samples.append((sampled.count, resident_bytes(), tracemalloc.get_traced_memory()[0] if traced else None))
        sampled.count += 1
        return kept

    sampled.count = 0
    engine._save_member, original = sampled, engine.run_member
    engine.run_member = _canned(record)
    plan = grid.plan("tp", settings=["duration=0.05", "noise=on"], seeds=str(members))
    if traced:
        tracemalloc.start()
    try:
        with tempfile.TemporaryDirectory() as folder:
            started = time.perf_counter()
            summary = engine.run(plan, Path(folder) / "sweep", workers=workers, progress=False)
            seconds = time.perf_counter() - started
    finally:
        engine._save_member, engine.run_member = save, original
        tracemalloc.stop()
    if summary.failed:
        raise RuntimeError(f"{summary.failed} members failed: {summary.failures[:1]}")
    fitted = [sample for sample in samples if sample[0] >= FIT_FROM * members]
    figures = {"bytes_per_member": float(np.polyfit([f[0] for f in fitted], [f[1] for f in fitted], 1)[0]),
               "samples": samples, "members": members, "workers": workers, "seconds": seconds}
    if traced:
        figures["traced_bytes_per_member"] = float(np.polyfit([f[0] for f in fitted], [f[2] for f in fitted], 1)[0])
    return figures


def main(argv=None) -> int:
    """Print the client's growth per member; returns 0. ``argv``: the arguments (default
    ``sys.argv[1:]``)."""
    parser = argparse.ArgumentParser(prog="python -m quadcosim.benchmarks.sweep_memory",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--members", type=int, default=MEMBERS, help=f"members of the sweep (default {MEMBERS})")
    parser.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--traced", action="store_true", help="also the bytes Python's allocations hold (slower)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    figures = measure(args.members, args.workers, args.traced)
    if args.json:
        print(json.dumps(figures))
        return 0
    first, last = figures["samples"][0], figures["samples"][-1]
    print(f"{args.members} members on {args.workers} workers in {figures['seconds']:.0f} s: the client grew "
          f"{figures['bytes_per_member'] / 1e3:.2f} kB per member (fit from {FIT_FROM:.0%} of the members on); "
          f"resident {first[1] / 1e6:.0f} MB after {first[0]} members, {last[1] / 1e6:.0f} MB after {last[0]}")
    if args.traced:
        print(f"Python's allocations grew {figures['traced_bytes_per_member'] / 1e3:.2f} kB per member")
    return 0


if __name__ == "__main__":  # the same as quadcosim bench sweep-memory
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench sweep-memory").run, main)
