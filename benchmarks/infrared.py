"""Cost per iteration of the IR calibration estimators (``quadcosim bench infrared``).

Counts the operations of each estimator's step (flops, comparisons, functions; what counts is
stated in :mod:`quadcosim.calibration.infrared.cost`), by running its Python source on counting numbers,
over a fault-free flight of the ``ir-calibration`` scenario (``--faults both``: with the
slides' faults, during which part of the samples skip fusion and cost less); times one update
in the compiled batch loop and one streaming call from Python, best of ``repeats``. Sets them
against the slides' 300 operations per iteration at 20 Hz on the aircraft's 20 MHz processor.
Timings on a shared machine are noisy: compare ratios from one run.
"""

from __future__ import annotations

import json


def measure(samples: int = 8000, start_s: float = 0.0, repeats: int = 3, faults: str = "none") -> dict:
    """:func:`quadcosim.calibration.infrared.cost` on ``samples`` samples (20 Hz) of the ``ir-calibration``
    flight with ``faults`` (``"none"`` or ``"both"``), from ``start_s`` (s); timings best of
    ``repeats``."""
    from quadcosim.calibration.infrared import cost
    from quadcosim.scenarios.ir_calibration import RATE, simulate_flight

    first = int(start_s * RATE)
    flight = simulate_flight(first + samples, seed=1, faults=faults)
    window = slice(first, first + samples)
    use = flight["gps_valid"][window] > 0.5
    return cost(flight["ir"][window], flight["gps_turn_rate"][window], use, repeats=repeats)


def main(argv=None) -> int:
    """Print the cost table (or one JSON object with ``--json``); returns the exit status.
    ``argv``: the arguments (default ``sys.argv[1:]``)."""
    import argparse

    parser = argparse.ArgumentParser(prog="quadcosim bench infrared", description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--samples", type=int, default=8000, help="samples counted and timed")
    parser.add_argument("--repeats", type=int, default=3, help="timings, best kept")
    parser.add_argument("--faults", default="none", choices=("none", "both"),
                        help="the flight: fault-free (default) or with the slides' two faults")
    args = parser.parse_args(argv)
    figures = measure(args.samples, repeats=args.repeats, faults=args.faults)
    if args.json:
        print(json.dumps(figures))
        return 0
    slides = figures.pop("slides")
    flight = "fault-free" if args.faults == "none" else "with the slides' faults"
    print(f"operations per iteration (flops + comparisons + functions) over {args.samples} samples, {flight}; "
          f"the slides counted {slides['operations_per_iteration']} at {slides['rate_hz']:g} Hz "
          f"({slides['operations_per_s']:g}/s) for a {slides['processor_hz'] / 1e6:g} MHz processor")
    print(f"{'estimator':16s} {'mean':>7s} {'max':>5s} {'flops':>7s} {'compare':>8s} {'funcs':>6s} {'ops/s':>7s} "
          f"{'us batch':>9s} {'us stream':>10s}")
    for name, row in figures.items():
        print(f"{name:16s} {row['operations_mean']:7.1f} {row['operations_max']:5d} {row['flops_mean']:7.1f} "
              f"{row['comparisons_mean']:8.1f} {row['functions_mean']:6.1f} {row['operations_per_s']:7.0f} "
              f"{row['us_per_update_batch']:9.3f} {row['us_per_update_streaming']:10.2f}")
    return 0


if __name__ == "__main__":  # the same as quadcosim bench infrared
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench infrared").run, main)
