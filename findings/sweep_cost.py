"""Findings of what a sweep costs: ``quadcosim bench sweep`` (:func:`quadcosim.benchmarks.sweep.measure`:
40 closed-loop members on 1 then 2 local workers, and the 10 000-member study it extrapolates)
and a study of :data:`STUDY_MEMBERS` members on 2 workers (``python -m quadcosim.benchmarks.study``:
run as written in a fresh interpreter, :func:`study`), a few minutes in all on a loaded machine.

CPU times per member, on the member's thread, moved by under a tenth between runs at load
averages 5 and 8: their tolerance is half their value. Wall times and rates on the shared cores
moved up to fivefold (two workers: 11.4 then 4.3 members per second here; one worker: 4.0 and
0.8 at load averages 5 and 18 in earlier runs): their tolerance is four times their value, and
the speed-up with 2 workers (1.90 then 0.44) measures the machine's load more than the engine.
A member's CPU over its stepping loop's is a ratio on one thread (1.45 then 1.50). Disk per
member hardly moves. Timings are never re-checked in tests, and the disk figures come from the
same sweep: ``quick`` returns none.
"""

from __future__ import annotations

from findings import finding

BENCH = "quadcosim bench sweep"
STUDY_MEMBERS = 1000
STUDY_WORKERS = 2
STUDY = f"python -m quadcosim.benchmarks.study --members {STUDY_MEMBERS} --workers {STUDY_WORKERS}"
MS = 1e3
CPU_SWING = 0.5  # CPU time of a member on its worker's thread
WALL_SWING = 4.0  # wall time and rates on shared cores: a re-run may take five times as long
GROWTH_SWING = 1.0  # the client's memory growth per member: 16 then 25 kB
SPEED_UP_TOLERANCE = 1.5  # 1.90 then 0.44 at load averages 5 and 8
# a member's CPU over its stepping loop's: both on one thread, the load moves it little
OVER_STEPPING_TOLERANCE = 0.2
DISK_BYTES_TOLERANCE = 100.0  # a member's metrics.json: the digits of its times vary
STUDY_WORKER_COUNTS = (1, 2, 8, 32)
# the client's resident memory: library versions and Dask's bookkeeping move it, not the load
MEMORY_SHARE = 0.3


def _timing(name: str, value: float, unit: str, command: str, digits: int, swing: float = WALL_SWING) -> dict:
    """A finding of an absolute time or rate: tolerance ``swing`` times its value."""
    return finding(f"sweep_cost.{name}", value, unit, command, swing * abs(value), digits)


def _disk(key: str, value: float) -> dict:
    return finding(f"sweep_cost.bench.{key}", value, "B", BENCH, DISK_BYTES_TOLERANCE, 0)


def bench_findings(figures: dict) -> list[dict]:
    """The findings of one ``quadcosim bench sweep`` (:func:`quadcosim.benchmarks.sweep.measure`'s dict ``figures``)."""
    one, two = figures["workers_1"], figures["workers_2"]
    found = [_timing("bench.members_per_s_1", one["members_per_s"], "1/s", BENCH, 2),
             _timing("bench.members_per_s_2", two["members_per_s"], "1/s", BENCH, 2),
             finding("sweep_cost.bench.speed_up_2_workers", figures["speed_up_2_workers"], "1", BENCH,
                     SPEED_UP_TOLERANCE, 2),
             _timing("bench.member_cpu_s", one["median_member_cpu_s"], "s", BENCH, 3, CPU_SWING),
             _timing("bench.member_wall_s", one["median_member_s"], "s", BENCH, 3),
             _timing("bench.stepping_cpu_ms", one["median_stepping_cpu_s"] * MS, "ms", BENCH, 1, CPU_SWING),
             finding("sweep_cost.bench.member_over_stepping", figures["member_over_stepping"], "1", BENCH,
                     OVER_STEPPING_TOLERANCE, 2),
             _timing("bench.start_s_1", one["start_s"], "s", BENCH, 1),
             _timing("bench.start_s_2", two["start_s"], "s", BENCH, 1),
             _timing("bench.first_member_extra_s", one["first_member_extra_s"], "s", BENCH, 2),
             *[_disk(key, figures[key]) for key in ("disk_per_member_bytes", "disk_per_member_allocated_bytes",
                                              "table_bytes_per_member")]]
    study = figures["study_10000"]
    for n in STUDY_WORKER_COUNTS:
        minutes = study["workers"][n]
        found += [_timing(f"bench.study_10000.minutes_{n}", minutes["minutes"], "min", BENCH, 1),
                  _timing(f"bench.study_10000.cpu_bound_minutes_{n}", minutes["cpu_bound_minutes"], "min", BENCH, 1,
                          CPU_SWING)]
    disk_tolerance = study["disk_mb"] * DISK_BYTES_TOLERANCE / figures["disk_per_member_bytes"]
    return found + [finding("sweep_cost.bench.study_10000.disk_mb", study["disk_mb"], "MB", BENCH, disk_tolerance, 0)]


def study_findings(figures: dict) -> list[dict]:
    """The findings of one ``python -m quadcosim.benchmarks.study`` (:func:`study`'s dict ``figures``)."""
    if figures["failed"]:
        raise RuntimeError(f"{STUDY}: {figures['failed']} members failed")
    rss = figures["client_rss_mb"]
    return [_timing("study.seconds", figures["seconds"], "s", STUDY, 0),
            _timing("study.startup_s", figures["startup_s"], "s", STUDY, 1),
            _timing("study.member_cpu_ms", figures["member_cpu_s"] * MS, "ms", STUDY, 1, CPU_SWING),
            _timing("study.stepping_cpu_ms", figures["stepping_cpu_s"] * MS, "ms", STUDY, 1, CPU_SWING),
            _timing("study.member_wall_ms", figures["member_wall_s"] * MS, "ms", STUDY, 1),
            _timing("study.wall_per_member_ms", figures["wall_per_member_s"] * MS, "ms", STUDY, 1),
            _timing("study.slot_overhead_ms", figures["slot_overhead_s"] * MS, "ms", STUDY, 1),
            _timing("study.client_cpu_per_member_ms", figures["client_cpu_per_member_s"] * MS, "ms", STUDY, 2,
                    CPU_SWING),
            finding("sweep_cost.study.client_rss_first_mb", rss["first"], "MB", STUDY, MEMORY_SHARE * rss["first"], 0),
            finding("sweep_cost.study.client_rss_last_mb", rss["last"], "MB", STUDY, MEMORY_SHARE * rss["last"], 0),
            _timing("study.client_rss_growth_per_member_kb", figures["client_rss_growth_per_member_kb"], "kB",
                    STUDY, 1, GROWTH_SWING)]


def study(members: int = STUDY_MEMBERS, workers: int = STUDY_WORKERS) -> dict:
    """The figures of ``python -m quadcosim.benchmarks.study --members MEMBERS --workers WORKERS --json``,
    run as written in a fresh interpreter: the client's memory is that of the command, not of
    a process that ran other benchmarks first.

    Parameters
    ----------
    members : int
        Members of the study.
    workers : int
        Local worker processes.

    Returns
    -------
    dict
        :func:`quadcosim.benchmarks.study.measure`'s figures.

    Raises
    ------
    RuntimeError
        The command failed other than by failed members (which :func:`study_findings` refuses).
    """
    import json
    import subprocess
    import sys

    from findings import ROOT

    command = [sys.executable, "-m", "quadcosim.benchmarks.study", "--members", str(members),
               "--workers", str(workers), "--json"]
    done = subprocess.run(command, capture_output=True, text=True, cwd=ROOT)
    if done.returncode not in (0, 1):  # 1: a member failed, reported in the figures
        raise RuntimeError(f"{' '.join(command[1:])} exited with {done.returncode}: {done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def compute(quick: bool = False) -> list[dict]:
    """Every figure of the sweeps page's cost section, from one run of each benchmark. ``quick``:
    none (timings are not re-checked; the disk figures come from the timed sweep)."""
    if quick:
        return []
    from quadcosim.benchmarks import sweep

    return bench_findings(sweep.measure()) + study_findings(study())
