"""What running an FMU in a worker process of its own costs (``quadcosim bench``).

The closed loop ``tp`` is run with its ``MotorMagnetics`` FMU in process and in a worker process
(:mod:`quadcosim.orchestrator.isolated`), alternately, in wall time (the worker's time and the crossings
between the processes are not the master's CPU time). Both give the same trajectory, bit for bit.
"""

from __future__ import annotations

import statistics

import numpy as np

BLOCK = "MotorMagnetics"
CLOSED_LOOP = {"estimator": "explicit"}


def _run(definition, options, seconds: float, isolated: bool):
    system = definition.build(options)
    system.blocks[BLOCK].isolated = isolated
    result = system.run(seconds)
    return result, result.meta["loop_seconds"]


def measure(seconds: float = 5.0, repeats: int = 3) -> dict:
    """The isolated FMU's cost on the closed loop.

    Parameters
    ----------
    seconds : float
        Simulated time per run (s).
    repeats : int
        Pairs of runs (in process, isolated), back to back.

    Returns
    -------
    dict
        ``isolated_over_in_process`` (median ratio of the loops' wall times), its spread
        (lowest, highest), ``isolated_us_per_step`` and ``in_process_us_per_step`` (wall µs per
        macro step, the lowest over the repeats), ``isolated_step_cost_us`` (their difference:
        what one isolated FMU adds to a step) and ``isolated_identical`` (every signal equal).
    """
    from quadcosim import scenarios

    definition = scenarios.get("tp")
    options = definition.parse({"duration": seconds} | CLOSED_LOOP)
    steps = int(round(seconds / 1e-3))
    ratios, inside, outside, identical = [], [], [], True
    for _ in range(repeats):
        reference, in_process = _run(definition, options, seconds, False)
        result, isolated = _run(definition, options, seconds, True)
        identical &= bool(np.array_equal(reference.data, result.data))
        inside.append(in_process / steps)
        outside.append(isolated / steps)
        ratios.append(isolated / in_process)
    return {"isolated_over_in_process": statistics.median(ratios),
            "isolated_over_in_process_spread": [min(ratios), max(ratios)],
            "isolated_us_per_step": min(outside) * 1e6, "in_process_us_per_step": min(inside) * 1e6,
            "isolated_step_cost_us": (min(outside) - min(inside)) * 1e6, "isolated_identical": identical}


def main(argv=None) -> int:
    """``quadcosim bench isolation`` with the arguments ``argv``; prints the figures, returns 0."""
    import argparse
    import json

    parser = argparse.ArgumentParser(prog="quadcosim bench isolation", description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--seconds", type=float, default=5.0, help="simulated seconds per run")
    parser.add_argument("--repeats", type=int, default=3, help="pairs of runs")
    args = parser.parse_args(argv)
    figures = measure(args.seconds, args.repeats)
    if args.json:
        print(json.dumps(figures))
    else:
        for key, value in figures.items():
            print(f"{key:32s} {value:12.4g}" if isinstance(value, float) else f"{key:32s} {value}")
    return 0


if __name__ == "__main__":  # the same as quadcosim bench isolation
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench isolation").run, main)
