"""Ablation of the linear filter's error: which signal makes it, measured by swapping in the ideal one.

    python -m quadcosim.scenarios.ablation --set flight=nonstationary --set duration=20

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

``--triad`` does the same for the passive filter on TRIAD with the lab's gyro bias: its final
bias-estimate error with the recorded accelerometer and with gravity alone in its place.
"""

from __future__ import annotations

import argparse

import numpy as np
from quadcosim.estimators import estimate, parse_corrections
from quadcosim.estimators.quaternions import euler_to_quaternion
from quadcosim.fmus import vehicle
from quadcosim.orchestrator.blocks import Block

VARIANTS = ("recorded", "ideal accelerometer", "true Euler rates", "both")


class GravityOnly(Block):
    """Specific force of a vehicle at rest in its present attitude, ``f = R^T (0, 0, -g)`` (m/s^2,
    body FRD), from the true quaternion ``q0..q3``: wired into ``IMU.f`` in place of
    ``Quadrotor.f``, it gives an accelerometer that sees gravity alone (with the IMU's own noise
    and bias), in the closed loop. ``name``: the block's name; ``g`` (m/s^2): gravity."""

    inputs = ("q0", "q1", "q2", "q3")
    outputs = ("f_x", "f_y", "f_z")
    units = dict.fromkeys(outputs, "m/s2")

    def __init__(self, name: str = "GravityOnly", g: float = vehicle.GRAVITY):
        super().__init__(name)
        self.g = g

    def step(self, t, u, y):
        q0, q1, q2, q3 = u
        y[0] = -self.g * 2.0 * (q1 * q3 - q0 * q2)  # -g (R^T e3), the third row of R
        y[1] = -self.g * 2.0 * (q2 * q3 + q0 * q1)
        y[2] = -self.g * (1.0 - 2.0 * (q1 * q1 + q2 * q2))


def euler_rates(theta: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """Z-Y-X Euler-angle rates (rad/s, roll, pitch, yaw) from the angles ``theta`` (N, 3) (rad)
    and the body rates ``omega`` (N, 3) (rad/s, FRD), row by row."""
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
    from quadcosim import scenarios

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
        theta = estimate("linear", gyro=w, acc=a, mag=mag, dt=dt, gains=gains, discretisation=o["discretisation"],
                         q0=euler_to_quaternion(*truth[0]))["theta"][0]
        error = (theta - truth + np.pi) % (2 * np.pi) - np.pi
        rms[name] = np.degrees(np.sqrt((error[after] ** 2).mean(axis=0))).tolist()
    return rms


def triad_ablation(settings: dict | None = None) -> dict:
    """Passive filter on TRIAD (R_y from accelerometer and magnetometer) with the lab's gyro bias:
    final bias-estimate error (rad/s, x/y/z) with the recorded accelerometer and with gravity
    alone in its place, and the true bias. ``settings``: ``tp`` options (``estimator``,
    ``ry``, ``bias`` and ``feedback`` forced)."""
    from quadcosim import scenarios

    options = dict(settings or {}) | {"estimator": "passive", "ry": "triad", "bias": True, "feedback": "gt"}
    result, _ = scenarios.run("tp", options)
    o = scenarios.get("tp").parse(options)
    step = round(1.0 / (o["imu_rate"] * o["dt"]))
    picked = slice(0, None, step)
    gyro, acc, mag = result["IMU.gyro"][picked], result["IMU.acc"][picked], result["IMU.magneto"][picked]
    truth = np.column_stack([result[f"Quadrotor.theta{i}"] for i in (1, 2, 3)])[picked]
    gains = scenarios.tp.estimator_gains(o)
    true_bias = result["IMU.gyro_bias"][-1]
    out = {"true bias": true_bias.tolist(),
           "streaming": (result["Quaternion_estim.b_est"][-1] - true_bias).tolist()}
    for name, a in (("recorded", acc), ("ideal accelerometer", gravity_only(result["IMU.R_reel"][picked]))):
        b = estimate("passive", gyro=gyro, acc=a, mag=mag, dt=o["dt"] * step, gains=gains, ry="triad",
                     corrections=parse_corrections(o["corrections"]), discretisation=o["discretisation"],
                     q0=euler_to_quaternion(*truth[0]), outputs=("b",))["b"][0]
        out[name] = (b[-1] - true_bias).tolist()
    return out


def markdown(rms: dict) -> str:
    """Markdown table of the linear filter's RMS errors, one row per ablation variant.

    Parameters
    ----------
    rms : dict
        Variant name -> RMS error (deg; roll, pitch, yaw), as :func:`linear_ablation` returns.

    Returns
    -------
    str
        The table, two header lines and one line per variant.
    """
    lines = ["| linear filter fed with | RMS error (deg, roll / pitch / yaw) |", "|---|---|"]
    for name, values in rms.items():
        lines.append(f"| {name} | {' / '.join(f'{v:.3f}' for v in values)} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    """Command line ``python -m quadcosim.scenarios.ablation``: print the ablation table.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default ``sys.argv[1:]``): ``--set KEY=VALUE`` (tp options, repeated) and
        ``--triad`` (the passive filter on TRIAD: final gyro bias errors, rad/s, and the recorded
        accelerometer's error in times the true bias, instead).

    Returns
    -------
    int
        Exit status, 0.
    """
    parser = argparse.ArgumentParser(prog="python -m quadcosim.scenarios.ablation", description=__doc__.splitlines()[0])
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a tp option")
    parser.add_argument("--triad", action="store_true", help="the passive filter on TRIAD: bias error instead")
    args = parser.parse_args(argv)
    settings = dict(s.split("=", 1) for s in args.set)
    if args.triad:
        rows = triad_ablation(settings)
        print("| passive on TRIAD, gyro bias | final bias error (rad/s, x / y / z) |\n|---|---|")
        for name, values in rows.items():
            print(f"| {name} | {' / '.join(f'{v:+.4f}' for v in values)} |")
        times = [abs(error / bias) for error, bias in zip(rows["recorded"], rows["true bias"], strict=True)]
        print(f"| recorded, times the true bias | {' / '.join(f'{t:.2f}' for t in times)} |")
    else:
        print(markdown(linear_ablation(settings)))
    return 0


if __name__ == "__main__":  # the same as quadcosim study ablation
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim study ablation").run, main)
