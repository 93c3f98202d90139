"""Ablation of the linear filter's error: which signal makes it, measured by swapping in the ideal one.

    python -m scenarios.ablation --set flight=nonstationary --set duration=20

Runs one ``tp`` case (GT feedback, the options given with ``--set``), then re-runs the
linear filter on the recorded stream through the batch path (the same compiled update as
the streaming block) four times:

- ``recorded``: the IMU's accelerometer and gyro, as in the closed loop;
- ``ideal accelerometer``: the accelerometer replaced by gravity alone, ``R^T (0, 0, -g)``
  from the true attitude (no acceleration, no drag seen);
- ``true Euler rates``: the gyro replaced by the true Euler-angle rates, so that the filter's
  integration ``dtheta = omega_m`` is exact;
- ``both``: the two swaps together.

The roll, pitch and yaw RMS errors after ``settle`` say which input the error comes from.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from estimators import estimate
from estimators.core import euler_to_quaternion
from fmus import vehicle

VARIANTS = ("recorded", "ideal accelerometer", "true Euler rates", "both")


def euler_rates(theta: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """Z-Y-X Euler-angle rates (rad/s, roll, pitch, yaw) from the angles (rad) and the body rates
    ``omega`` (rad/s, FRD), row by row."""
    roll, pitch = theta[:, 0], theta[:, 1]
    p, q, r = omega.T
    lateral = q * np.sin(roll) + r * np.cos(roll)
    return np.column_stack([p + lateral * np.tan(pitch), q * np.cos(roll) - r * np.sin(roll),
                            lateral / np.cos(pitch)])


def gravity_only(rotation: np.ndarray, g: float = vehicle.GRAVITY) -> np.ndarray:
    """Specific force (m/s^2, body) of a vehicle at rest: ``R^T (0, 0, -g)``; ``rotation`` is
    (N, 9), row-major, body to NED."""
    return -g * rotation[:, 6:9]


def linear_ablation(settings: dict | None = None) -> dict:
    """Linear filter RMS errors (deg, roll/pitch/yaw) for each of :data:`VARIANTS`.

    Parameters
    ----------
    settings : dict
        ``tp`` options (``estimator`` is forced to ``linear`` and ``feedback`` to ``gt``).

    Returns
    -------
    dict
        ``{variant: [roll, pitch, yaw]}`` in degrees, plus ``"streaming"``: the closed loop's own
        RMS error (the ``recorded`` variant reproduces it).
    """
    import scenarios

    options = dict(settings or {}) | {"estimator": "linear", "feedback": "gt"}
    result, metrics = scenarios.run("tp", options)
    o = scenarios.get("tp").parse(options)
    dt = o["dt"] * round(1.0 / (o["imu_rate"] * o["dt"]))
    step = round(dt / o["dt"])
    picked = slice(0, None, step)  # the estimator's own samples
    truth = np.column_stack([result[f"Quadrotor.theta{i}"] for i in (1, 2, 3)])[picked]
    acc, gyro, mag = result["IMU.acc"][picked], result["IMU.gyro"][picked], result["IMU.magneto"][picked]
    ideal_acc = gravity_only(result["IMU.R_reel"][picked])
    rates = euler_rates(truth, result["Quadrotor.omega"][picked])
    gains = {f"k{i}": o["k"] for i in (1, 2, 3)}
    after = result.time[picked] >= min(o["settle"], 0.5 * o["duration"])
    rms = {"streaming": metrics["rms_error_deg"]}
    for name, (a, w) in zip(VARIANTS, [(acc, gyro), (ideal_acc, gyro), (acc, rates), (ideal_acc, rates)],
                            strict=True):
        theta = estimate("linear", gyro=w, acc=a, mag=mag, dt=dt, gains=gains,
                         q0=euler_to_quaternion(*truth[0]))["theta"][0]
        error = (theta - truth + np.pi) % (2 * np.pi) - np.pi
        rms[name] = np.degrees(np.sqrt((error[after] ** 2).mean(axis=0))).tolist()
    return rms


def markdown(rms: dict) -> str:
    lines = ["| linear filter fed with | RMS error (deg, roll / pitch / yaw) |", "|---|---|"]
    for name, values in rms.items():
        lines.append(f"| {name} | {' / '.join(f'{v:.3f}' for v in values)} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m scenarios.ablation", description=__doc__.splitlines()[0])
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a tp option")
    args = parser.parse_args(argv)
    print(markdown(linear_ablation(dict(s.split("=", 1) for s in args.set))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
