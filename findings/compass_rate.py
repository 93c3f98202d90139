"""Findings of the compass rate a flight calibration needs: the example flights (``quadcosim log
example``, their internal compass moved by :data:`quadcosim.scenarios.flightlog.example.INTERNAL_T_PER_A`
lagging :data:`quadcosim.scenarios.flightlog.example.DELAY_S`) calibrated with the default Earth field
model as ``quadcosim calibrate`` fits them, their compass decimated from its logged 10 Hz to
each of :data:`RATES_HZ`: the ``current`` model's coefficient error (% of the true vector's norm)
and its delay error (ms), flight by flight.

The slowest rate at which every flight still gives its delay exactly is the floor
:data:`quadcosim.calibration.flight.data.MIN_COMPASS_RATE_HZ` the command enforces; PX4's default logging
profile logs ``sensor_mag`` at 1 Hz, under it.
"""

from __future__ import annotations

import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from findings import finding

COMMAND = "python -m findings compass_rate"  # the group prints them; the logs are written on the way
FLIGHTS = ("a", "b", "c")
COMPASS = 1  # the internal compass, the one the battery current moves
RATES_HZ = {10: 1, 2.5: 4, 2: 5, 1: 10}  # rate (Hz): the decimation of the logged 10 Hz
QUICK_RATES_HZ = (10,)


def decimated(log, compass: int, step: int):
    """``log`` (a FlightLog) with compass ``compass`` keeping one sample in ``step``."""
    kept = list(log.compasses)
    c = kept[compass]
    kept[compass] = replace(c, time=c.time[::step], field=c.field[::step], raw=c.raw[::step])
    return replace(log, compasses=kept)


def recovered(log, step: int) -> tuple[float, float]:
    """The ``current`` model fitted on the first half of ``log`` (one sample in ``step`` of its compass
    :data:`COMPASS`), as ``quadcosim calibrate`` splits and aligns it: its coefficient error (% of the
    true vector's norm) and delay error (ms)."""
    from quadcosim.calibration.flight import calibrate
    from quadcosim.scenarios.flightlog.calibrate import split_parts
    from quadcosim.scenarios.flightlog.example import DELAY_S, INTERNAL_T_PER_A

    split = split_parts([decimated(log, COMPASS, step)], [], COMPASS)
    metrics, _, _ = calibrate(split.train, split.test, ("current",))
    current = metrics["models"]["current"]
    error = np.linalg.norm(np.array(current["coefficients"]["K_T_per_A"]) - INTERNAL_T_PER_A)
    return float(100 * error / np.linalg.norm(INTERNAL_T_PER_A)), float(1e3 * (current["delay_s"] - DELAY_S))


def compute(quick: bool = False) -> list[dict]:
    """The group's findings (``quick``: the logged rate alone, seconds; all of them: about a minute)."""
    from quadcosim.flightlogs import read_log
    from quadcosim.scenarios.flightlog.example import write_examples

    found = []
    with tempfile.TemporaryDirectory() as folder:
        logs = dict(zip(FLIGHTS, (read_log(p) for p in write_examples(Path(folder))), strict=True))
        for rate, step in RATES_HZ.items():
            if quick and rate not in QUICK_RATES_HZ:
                continue
            for key, log in logs.items():
                error_pct, delay_ms = recovered(log, step)
                label = f"{rate:g}".replace(".", "_")
                found.append(finding(f"compass_rate.hz{label}.{key}.coefficient_error_pct", error_pct, "%", COMMAND,
                                     0.05, 1))
                found.append(finding(f"compass_rate.hz{label}.{key}.delay_error_ms", delay_ms, "ms", COMMAND, 0.5, 0))
    return found
