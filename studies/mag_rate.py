"""Ablation: the magnetometer at 1 kHz against its own 100 Hz (held), in the lab's closed loop.

Runs the ``tp`` scenario for each estimator and flight profile twice, with the IMU's
magnetometer at ``mag_sample_rate`` = 1000 Hz (every macro step, as before it had its own rate)
and at 100 Hz, held between samples, everything else equal, and prints the RMS estimation
errors (deg, roll/pitch/yaw, after the settling time) and their difference. It tells whether
the estimators need anything beyond the zero-order-held sample (a flag for a fresh sample,
a rate-aware gain)::

    python -m quadcosim.studies.mag_rate                       # noise off and on, 20 s per run
    python -m quadcosim.studies.mag_rate --duration 40 --noise on
"""

from __future__ import annotations

import argparse

import numpy as np
from quadcosim.scenarios import tp

from quadcosim import scenarios

DURATION_S = 20.0  # s, simulated time per run by default


def rms_errors(settings: dict, mag_rate: float) -> np.ndarray:
    """RMS estimation error (deg) of a ``tp`` run with the options ``settings`` (name -> text)
    and the magnetometer at ``mag_rate`` (Hz)."""
    scenario = scenarios.get("tp")
    o = scenario.parse(settings)
    system = scenario.build(o)
    system.blocks["IMU"].parameters["mag_sample_rate"] = mag_rate
    result = system.run(o["duration"], record=["Quadrotor.theta1", "Quadrotor.theta2", "Quadrotor.theta3",
                                              "Quaternion_estim.theta_est", "Controller.theta_d1",
                                              "Controller.theta_d2", "Setpoint.theta_d3"])
    estimation, _ = tp.errors(result)
    after = result.time >= min(o["settle"], 0.5 * o["duration"])
    return np.degrees(np.sqrt((estimation[after] ** 2).mean(axis=0)))


def differences(duration: float, noise: bool):
    """Each estimator and flight of the lab: (estimator, flight, RMS errors at 1 kHz, at 100 Hz
    held), the errors (deg) as roll, pitch, yaw arrays, of ``duration`` s runs with or without
    ``noise``."""
    for estimator in ("linear", "explicit"):
        for flight in ("quasi", "nonstationary"):
            settings = {"estimator": estimator, "flight": flight, "noise": noise, "duration": duration}
            yield estimator, flight, rms_errors(settings, 1000.0), rms_errors(settings, 100.0)


def main(argv=None) -> int:
    """Print the ablation table (deg) for the estimators and flights of the lab, then the largest
    difference with and without noise.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (``--duration`` in s, ``--noise off|on|both``).

    Returns
    -------
    int
        Exit status, 0.
    """
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=DURATION_S, help="simulated time per run (s)")
    parser.add_argument("--noise", choices=("off", "on", "both"), default="both", help="IMU white noise")
    args = parser.parse_args(argv)
    noises = {"off": [False], "on": [True], "both": [False, True]}[args.noise]
    print(f"{'estimator':10} {'flight':14} {'noise':5} | RMS error at 1 kHz (deg) | at 100 Hz held (deg) "
          "| difference (deg)")
    largest = {}
    for noise in noises:
        for estimator, flight, fast, held in differences(args.duration, noise):
            fmt = lambda v: " ".join(f"{x:7.4f}" for x in v)  # noqa: E731
            print(f"{estimator:10} {flight:14} {str(noise):5} | {fmt(fast)} | {fmt(held)} | {fmt(held - fast)}")
            largest[noise] = max(largest.get(noise, 0.0), float(np.abs(held - fast).max()))
    for noise, difference in largest.items():
        print(f"largest difference {'with' if noise else 'without'} noise: {difference:.5f} deg RMS")
    return 0


if __name__ == "__main__":  # the same as quadcosim study mag-rate
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim study mag-rate").run, main)
