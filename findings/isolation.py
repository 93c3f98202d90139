"""Findings of what an FMU in a worker process of its own costs: ``quadcosim bench isolation``
(:func:`quadcosim.benchmarks.isolation.measure`: the closed loop ``tp`` with its ``MotorMagnetics`` FMU
in process and in a worker, alternately, in wall time), a few minutes on a loaded machine.

The crossing between the processes is wall time on shared cores: it moves with the machine's
load several fold, and so does the ratio of the two loops (4.7, 8.0 and 3.4 between runs at load
averages 9 to 13; what the isolated FMU adds to a step, 8 then 27 µs). Tolerances are four times
the values. Timings are never re-checked in tests:
``quick`` returns none.
"""

from __future__ import annotations

from findings import finding

BENCH = "quadcosim bench isolation --json"
WALL_SWING = 4.0  # wall time on shared cores: a re-run may take five times as long


def compute(quick: bool = False) -> list[dict]:
    """The isolated FMU's cost on the closed loop; none when ``quick``.

    Raises
    ------
    RuntimeError
        The isolated run's trajectory parted from the in-process one's (the guide says equal).
    """
    if quick:
        return []
    from quadcosim.benchmarks.isolation import measure

    figures = measure()
    if not figures["isolated_identical"]:
        raise RuntimeError(f"{BENCH}: isolated_identical false; the speed guide says equal to the last bit")
    return [finding(f"isolation.bench.{key}", figures[key], unit, BENCH, WALL_SWING * abs(figures[key]), digits)
            for key, unit, digits in (("isolated_over_in_process", "1", 1), ("isolated_us_per_step", "us", 1),
                                      ("in_process_us_per_step", "us", 1), ("isolated_step_cost_us", "us", 0))]
