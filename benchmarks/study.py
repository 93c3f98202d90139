"""A large study on the local cluster (``python -m quadcosim.benchmarks.study``): what a member costs at scale.

Runs ``members`` closed-loop members (the sweep benchmark's: the lab's loop, linear filter fed
back, IMU noise on, 5 s simulated, one seed each) on a local Dask cluster of ``workers``
processes, and reports:

- CPU per member (the member's thread on its worker) and of its stepping loop alone;
- the wall time per member and per worker slot, against the members' own wall time: what the
  scheduler, the transfers and the client's bookkeeping add per member;
- the CPU the client process (which hosts the local scheduler) spent per member;
- the client process's resident memory over the run (sampled every half second): flat, since
  members are made when submitted and submitted in a bounded window.
"""

from __future__ import annotations

import json
import statistics
import tempfile
import threading
import time
from pathlib import Path

SETTINGS = ["duration=5", "noise=on", "feedback=estimate", "flight=quasi"]


def _sample_memory(samples: list, stop: threading.Event, period: float = 0.5):
    import psutil

    process, started = psutil.Process(), time.perf_counter()
    while not stop.wait(period):
        samples.append((time.perf_counter() - started, process.memory_info().rss))


def measure(members: int = 10_000, workers: int = 2, duration: float = 5.0) -> dict:
    """Run the study and return its figures.

    Parameters
    ----------
    members : int
        Members (seeds 1 to ``members``).
    workers : int
        Local worker processes.
    duration : float
        Simulated time per member (s).

    Returns
    -------
    dict
        ``member_cpu_s`` and ``stepping_cpu_s`` (medians, s), ``member_wall_s`` (median, s),
        ``wall_per_member_s`` (the run's wall time over the members, s), ``slot_overhead_s``
        (worker time per member not spent in a member, s), ``client_cpu_per_member_s`` (s),
        ``client_rss_mb`` (first, middle and last samples, and the peak, MB),
        ``client_rss_growth_per_member_kb`` (last sample less the first, over the members, kB),
        counts and times.
    """
    from quadcosim.studies.sweep import engine, grid, table

    settings = [s for s in SETTINGS if not s.startswith("duration=")] + [f"duration={duration:g}"]
    plan = grid.plan("tp", settings=settings, seeds=str(members))
    samples, stop = [], threading.Event()
    with tempfile.TemporaryDirectory() as folder:
        engine.run(grid.plan("tp", settings=settings, seeds="1"), Path(folder) / "warm-up", workers=1, progress=False)
        sampler = threading.Thread(target=_sample_memory, args=(samples, stop), daemon=True)
        sampler.start()
        cpu = time.process_time()
        summary = engine.run(plan, Path(folder) / "study", workers=workers, progress=False)
        client_cpu = time.process_time() - cpu
        stop.set()
        sampler.join()
        columns = table.read(Path(folder) / "study")
    running = summary.seconds - summary.startup_s - summary.shutdown_s
    rss = [r / 1e6 for _, r in samples] or [float("nan")]
    return {
        "members": members, "workers": workers, "simulated_s_per_member": duration, "failed": summary.failed,
        "seconds": summary.seconds, "startup_s": summary.startup_s, "shutdown_s": summary.shutdown_s,
        "member_cpu_s": statistics.median(columns["cpu_s"]),
        "stepping_cpu_s": statistics.median(columns["stepping_cpu_s"]),
        "member_wall_s": statistics.median(columns["wall_s"]),
        "wall_per_member_s": running / members,
        "slot_overhead_s": (running * workers - sum(columns["wall_s"])) / members,
        "client_cpu_per_member_s": client_cpu / members,
        "client_rss_mb": {"first": rss[0], "middle": rss[len(rss) // 2], "last": rss[-1], "peak": max(rss)},
        "client_rss_growth_per_member_kb": (rss[-1] - rss[0]) * 1e3 / members,
    }


def main(argv=None) -> int:
    """``python -m quadcosim.benchmarks.study [--members N] [--workers W] [--json]``; returns 0, or 1 when a
    member failed. ``argv``: the arguments (default ``sys.argv[1:]``)."""
    import argparse

    parser = argparse.ArgumentParser(prog="python -m quadcosim.benchmarks.study", description=__doc__.splitlines()[0])
    parser.add_argument("--members", type=int, default=10_000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--duration", type=float, default=5.0, help="simulated seconds per member")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    f = measure(args.members, args.workers, args.duration)
    if args.json:
        print(json.dumps(f))
    else:
        rss = f["client_rss_mb"]
        print(f"{f['members']:,} members of {f['simulated_s_per_member']:g} s on {f['workers']} local workers: "
              f"{f['seconds']:.0f} s ({f['startup_s']:.1f} s to start, {f['shutdown_s']:.1f} s to stop), "
              f"{f['failed']} failed\n"
              f"  per member: {f['member_cpu_s'] * 1e3:.1f} ms of CPU, of which stepping "
              f"{f['stepping_cpu_s'] * 1e3:.1f} ms; "
              f"{f['member_wall_s'] * 1e3:.1f} ms of wall time on its worker\n"
              f"  the run: {f['wall_per_member_s'] * 1e3:.1f} ms of wall time per member; per worker slot "
              f"{f['slot_overhead_s'] * 1e3:.1f} ms per member outside members (scheduler, transfers, client)\n"
              f"  client and scheduler process: {f['client_cpu_per_member_s'] * 1e3:.2f} ms of CPU per member; "
              f"resident memory {rss['first']:.0f} MB at the start, {rss['middle']:.0f} MB midway, "
              f"{rss['last']:.0f} MB at the end (peak {rss['peak']:.0f} MB), "
              f"{f['client_rss_growth_per_member_kb']:.1f} kB more per member")
    return 1 if f["failed"] else 0


if __name__ == "__main__":  # the same as quadcosim bench study
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench study").run, main)
