"""Benchmark of the sweep engine (``quadcosim bench sweep``).

Runs the same 40 short closed-loop members (the lab's loop, linear filter fed back to the
controller, IMU noise on, 5 s simulated each, seeds 1 to 40) on a local Dask cluster of 1 and
then 2 worker processes, and prints:

- members per second with 1 and 2 workers (cluster start and shut-down excluded) and the
  speed-up;
- the per-worker start-up cost: cluster start with the workers' preparation, and the extra
  time of each worker's first member (compiled code loaded from numba's cache, which one
  discarded warm-up member has filled beforehand);
- the disk per member (its ``metrics.json``) and per table row;
- the cost of a 10 000-member study, measured rate extrapolated to N workers;
- how idle the machine was: load average before and after, CPUs, this process's niceness.
"""

from __future__ import annotations

import json
import os
import statistics
import tempfile
from pathlib import Path

MEMBERS = 40
SETTINGS = ["duration=5", "noise=on", "feedback=estimate", "flight=quasi"]


def _disk(paths) -> tuple[int, int]:
    """(apparent bytes, allocated bytes) of the files."""
    apparent = allocated = 0
    for path in paths:
        stat = path.stat()
        apparent += stat.st_size
        allocated += stat.st_blocks * 512
    return apparent, allocated


def measure(members: int = MEMBERS, duration: float = 5.0) -> dict:
    """Run the benchmark sweep on 1 then 2 local workers.

    Parameters
    ----------
    members : int
        Closed-loop runs (seeds 1 to ``members``).
    duration : float
        Simulated time of each run (s).

    Returns
    -------
    dict
        Rates (members/s), start-up (s), CPU and wall time per member (s) and of its stepping
        loop, ``member_over_stepping`` (the median over the 1-worker members of their CPU over
        their stepping loop's CPU), disk per member (bytes), the 10 000-member extrapolation (min,
        MB), load averages.
    """
    from quadcosim.studies.sweep import engine, grid, table

    settings = [s for s in SETTINGS if not s.startswith("duration=")] + [f"duration={duration:g}"]
    plan = grid.plan("tp", settings=settings, seeds=str(members))
    figures = {"members": members, "simulated_s_per_member": duration, "cpus": os.cpu_count(),
               "niceness": os.nice(0), "load_average_before": list(os.getloadavg())}
    with tempfile.TemporaryDirectory() as folder:
        # Fills numba's on-disk cache, so neither measured cluster pays a first compilation.
        engine.run(grid.plan("tp", settings=settings, seeds="1"), Path(folder) / "warm-up", workers=1, progress=False)
        for workers in (1, 2):
            out = Path(folder) / f"workers-{workers}"
            summary = engine.run(plan, out, workers=workers, progress=False)
            if summary.failed:
                raise RuntimeError(f"{summary.failed} benchmark members failed: {summary.failures[:1]}")
            columns = table.read(out)
            walls = columns["wall_s"]
            firsts = {}
            for worker, wall in zip(columns["worker"], walls, strict=True):
                firsts.setdefault(worker, wall)  # members run in order on a worker, first one first
            typical = statistics.median(walls)
            running = summary.seconds - summary.startup_s - summary.shutdown_s
            figures[f"workers_{workers}"] = {
                "members_per_s": members / running,
                "start_s": summary.startup_s,
                "shutdown_s": summary.shutdown_s,
                "first_member_extra_s": statistics.mean(firsts.values()) - typical,
                "median_member_s": typical,
                "median_member_cpu_s": statistics.median(columns["cpu_s"]),
                "median_stepping_cpu_s": statistics.median(columns["stepping_cpu_s"]),
            }
            if workers == 1:
                # a member's CPU against its stepping loop's alone: what the rest of the member costs
                figures["member_over_stepping"] = statistics.median(
                    cpu / stepping for cpu, stepping in zip(columns["cpu_s"], columns["stepping_cpu_s"], strict=True))
            if workers == 1:
                files = list((out / "members").glob("*/metrics.json"))
                apparent, allocated = _disk(files)
                figures["disk_per_member_bytes"] = apparent / len(files)
                figures["disk_per_member_allocated_bytes"] = allocated / len(files)
                figures["table_bytes_per_member"] = _disk([out / "sweep.csv", out / "sweep.parquet"])[0] / members
    figures["load_average_after"] = list(os.getloadavg())
    one, two = figures["workers_1"], figures["workers_2"]
    figures["speed_up_2_workers"] = two["members_per_s"] / one["members_per_s"]
    study = {}
    for n in (1, 2, 8, 32):  # beyond 2, each worker keeps the rate it had among 2
        rate = one["members_per_s"] if n == 1 else two["members_per_s"] * n / 2
        # On idle cores a member costs its CPU time: the bound a quiet machine approaches.
        study[n] = {"minutes": 10_000 / rate / 60, "cpu_bound_minutes": 10_000 * one["median_member_cpu_s"] / n / 60}
    figures["study_10000"] = {
        "workers": study,
        "disk_mb": 10_000 * (figures["disk_per_member_allocated_bytes"] + figures["table_bytes_per_member"]) / 1e6,
    }
    return figures


def report(f: dict) -> str:
    """The figures of :func:`measure` as lines of text."""
    one, two = f["workers_1"], f["workers_2"]
    lines = [
        f"sweep engine: {f['members']} closed-loop members of {f['simulated_s_per_member']:g} s simulated "
        "(tp, linear filter fed back, noise on), local Dask cluster",
        f"  machine: {f['cpus']} CPUs, load average before {f['load_average_before'][0]:.2f} "
        f"(1 min), after {f['load_average_after'][0]:.2f}; niceness {f['niceness']}",
        f"  1 worker : {one['members_per_s']:6.2f} members/s   (median member {one['median_member_s']:.3f} s, "
        f"{one['median_member_cpu_s']:.3f} s of CPU)",
        f"  2 workers: {two['members_per_s']:6.2f} members/s   (median member {two['median_member_s']:.3f} s, "
        f"{two['median_member_cpu_s']:.3f} s of CPU)",
        f"  speed-up with 2 workers: {f['speed_up_2_workers']:.2f}",
        f"  a member's CPU over its stepping loop's (median, 1 worker): {f['member_over_stepping']:.2f} "
        f"(stepping {one['median_stepping_cpu_s'] * 1e3:.1f} ms of {one['median_member_cpu_s'] * 1e3:.1f} ms)",
        f"  start-up per worker: cluster and preparation {one['start_s']:.2f} s (1 worker), {two['start_s']:.2f} s "
        f"(2 workers at once); first member {one['first_member_extra_s']:.2f} s longer than the others; "
        f"shut-down {one['shutdown_s']:.2f} s (1 worker), {two['shutdown_s']:.2f} s (2 workers)",
        f"  disk per member: {f['disk_per_member_bytes']:.0f} B of metrics.json "
        f"({f['disk_per_member_allocated_bytes']:.0f} B allocated), {f['table_bytes_per_member']:.0f} B of table",
        "  a 10 000-member study of such runs: "
        + ", ".join(f"{n} worker{'s' * (int(n) > 1)} {s['minutes']:.1f} min"
                    for n, s in f["study_10000"]["workers"].items())
        + f" (beyond 2: each worker at its 2-worker rate); {f['study_10000']['disk_mb']:.0f} MB on disk",
        "    on idle cores (CPU time per member): "
        + ", ".join(f"{n}: {s['cpu_bound_minutes']:.1f} min" for n, s in f["study_10000"]["workers"].items()),
    ]
    return "\n".join(lines)


def main(argv=None) -> int:
    """``quadcosim bench sweep [--json]``: measure and print; returns 0.
    ``argv``: the arguments (default ``sys.argv[1:]``)."""
    import argparse

    parser = argparse.ArgumentParser(prog="quadcosim bench sweep", description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--members", type=int, default=MEMBERS)
    parser.add_argument("--duration", type=float, default=5.0, help="simulated seconds per member")
    args = parser.parse_args(argv)
    figures = measure(args.members, args.duration)
    print(json.dumps(figures) if args.json else report(figures))
    return 0


if __name__ == "__main__":  # the same as quadcosim bench sweep
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench sweep").run, main)
