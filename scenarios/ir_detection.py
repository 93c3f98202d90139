"""How small a sensor fault the infrared calibration's Kalman filter finds, how fast, and how often it cries wolf.

``python -m scenarios.ir_detection`` flies the ``ir-calibration`` flight (8000 samples, drift
on, seed 1) with one fault at a time, the slides' onsets and lengths (IR from 60 s, GPS from
280 s, 2000 samples each), over a range of sizes, and tabulates for each the delay of its
declaration, the sensor it was attributed to, and how long after its end it was ended; then
flies fault-free flights (seeds 1 to 100 by default) and counts the faults declared there.
The filter's detectors are those of :mod:`calibration.infrared.detection`.
:mod:`scenarios.ir_detectability` measures why the smallest faults escape and what the detectors'
settings were set on.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from calibration.infrared import EKFSettings, Estimator
from scenarios.ir_calibration import fault_report, fault_windows, simulate_flight

IR_SIZES = (50.0, 100.0, 200.0, 400.0, 800.0, 1200.0)  # count
GPS_SIZES = (0.05, 0.1, 0.2, 0.3, 0.5, 1.0, 1.5)  # rad/s
CLEAN_SEEDS = (1, 100)  # first and last seed of the fault-free flights
SAMPLES = 8000


def kalman(flight: dict) -> dict:
    """The gated Kalman filter (default settings) over ``flight`` (:func:`simulate_flight`)."""
    use = flight["gps_valid"] > 0.5
    return Estimator("kalman", EKFSettings()).run(flight["ir"], flight["gps_turn_rate"], use)


def one_fault(sensor: str, size: float, seed: int = 1) -> dict:
    """The declaration of one fault of ``size`` on ``sensor`` (``"ir"``, count, or ``"gps"``, rad/s).

    Parameters
    ----------
    sensor : {"ir", "gps"}
        The faulty sensor.
    size : float
        Its offset (count for the IR, rad/s for the GPS).
    seed : int
        Flight and noise seed.

    Returns
    -------
    dict
        ``sensor``, ``size``, ``declared_after_s`` (s after the onset, None if never),
        ``attributed`` (the sensor it was declared on, None if never), ``ended_after_s`` (s after
        the fault's end, None if never ended), ``false_alarms`` (other declarations) and
        ``turn_rate_error_std_deg_s`` (deg/s, after 30 s).
    """
    flight = simulate_flight(SAMPLES, seed=seed, faults=sensor, ir_fault=size, gps_fault=size)
    estimate = kalman(flight)
    windows = fault_windows(sensor, size, size)
    flags = {"ir": estimate["ir_fault"], "gps": estimate["gps_fault"]}
    faults, false_alarms = fault_report(windows, flags, flight["time"])
    other = "gps" if sensor == "ir" else "ir"
    wrong, _ = fault_report([(other, *windows[0][1:])], flags, flight["time"])
    (fault,) = faults
    declared, attributed = fault["declared_s"], sensor
    if declared is None and wrong[0]["declared_s"] is not None:
        declared, attributed, false_alarms = wrong[0]["declared_s"], other, false_alarms - 1
    settled = flight["time"] >= 30.0
    return {"sensor": sensor, "size": size,
            "declared_after_s": None if declared is None else declared - fault["onset_s"],
            "attributed": attributed if declared is not None else None,
            "ended_after_s": None if fault["cleared_s"] is None else fault["cleared_s"] - fault["end_s"],
            "false_alarms": false_alarms,
            "turn_rate_error_std_deg_s": float(np.degrees(estimate["turn_rate"] - flight["r"])[settled].std())}


def false_alarms(seeds=range(CLEAN_SEEDS[0], CLEAN_SEEDS[1] + 1)) -> dict:
    """Faults declared on fault-free flights (drift on), one per seed.

    Parameters
    ----------
    seeds : iterable of int
        Flight and noise seeds.

    Returns
    -------
    dict
        ``flights``, ``hours`` (of flight, h), ``false_alarms`` (declarations in all),
        ``flights_with_a_false_alarm`` (their seeds).
    """
    total, flagged, flights = 0, [], 0
    for seed in seeds:
        flight = simulate_flight(SAMPLES, seed=seed)
        estimate = kalman(flight)
        _, count = fault_report([], {"ir": estimate["ir_fault"], "gps": estimate["gps_fault"]}, flight["time"])
        total += count
        flights += 1
        if count:
            flagged.append(seed)
    return {"flights": flights, "hours": flights * float(flight["time"][-1] + flight["time"][1]) / 3600.0,
            "false_alarms": total, "flights_with_a_false_alarm": flagged}


def table(ir_sizes=IR_SIZES, gps_sizes=GPS_SIZES) -> list[dict]:
    """:func:`one_fault` for every size, printed as it comes.

    Parameters
    ----------
    ir_sizes : sequence of float
        IR offsets (count).
    gps_sizes : sequence of float
        GPS turn-rate offsets (rad/s).
    """
    rows = []
    for sensor, sizes, unit in (("ir", ir_sizes, "count"), ("gps", gps_sizes, "rad/s")):
        for size in sizes:
            row = one_fault(sensor, size)
            rows.append(row)
            print(_line(row, unit), flush=True)
    return rows


def _line(row: dict, unit: str) -> str:
    def seconds(value):
        return "never" if value is None else f"{value:.2f} s"

    return (f"{row['sensor']:3s} +{row['size']:g} {unit}: declared after {seconds(row['declared_after_s'])} "
            f"on {row['attributed'] or '-'}, ended {seconds(row['ended_after_s'])} after its end, "
            f"{row['false_alarms']} other declarations, "
            f"turn-rate error std {row['turn_rate_error_std_deg_s']:.2f} deg/s")


def main(argv=None) -> int:
    """``python -m scenarios.ir_detection [--seeds A:B] [--out FILE]``: the table and the false alarms.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (the process's if None).
    """
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default=f"{CLEAN_SEEDS[0]}:{CLEAN_SEEDS[1]}",
                        help="fault-free flights, first:last seed (default 1:100)")
    parser.add_argument("--out", help="write the table and the false alarms to this JSON file")
    args = parser.parse_args(argv)
    try:
        first, last = (int(x) for x in args.seeds.split(":"))
    except ValueError:
        parser.error(f"--seeds {args.seeds!r}: write FIRST:LAST, e.g. 1:100")
    rows = table()
    clean = false_alarms(range(first, last + 1))
    print(f"fault-free flights, seeds {first} to {last} ({clean['flights']} flights, {clean['hours']:.1f} h): "
          f"{clean['false_alarms']} faults "
          f"declared" + (f" (seeds {clean['flights_with_a_false_alarm']})" if clean["false_alarms"] else ""))
    if args.out:
        from orchestrator.files import write_json

        write_json(args.out, {"faults": rows, "fault_free": clean})
    return 0


if __name__ == "__main__":
    sys.exit(main())
