"""``static-cal``: static magnetometer calibration (soft and hard iron) from a hand-held rotation sweep, motors off.

The IMU is driven by a scripted attitude, as a hand-held calibration turns the vehicle: three
rotations at incommensurate rates, ``R = Rz(w3 t) Ry(w2 t) Rx(w1 t)``, which carry the sensor
through every orientation. The magnetometer has a known soft iron ``A`` and hard iron ``b_s``
(the option values); :func:`quadcosim.calibration.fit_static` recovers them from the readings alone,
and the metrics compare them with the truth, give the quality figures, and the heading error
of the corrected field over a level yaw turn.
"""

from __future__ import annotations

import numpy as np
from quadcosim.calibration import Calibration, fit_static
from quadcosim.fmus import vehicle
from quadcosim.orchestrator import FMUBlock, System, Table
from quadcosim.scenarios import Option, Scenario
from quadcosim.scenarios.figures import title_lines
from quadcosim.scenarios.plant import angle_between, imu_parameters, save_figure

from quadcosim.infra.files import write_json

SOFT_IRON = ((1.06, 0.04, -0.03), (0.04, 0.95, 0.05), (-0.03, 0.05, 1.02))  # 1, symmetric
HARD_IRON = (12e-6, -8e-6, 20e-6)  # T

OPTIONS = {
    "duration": Option(60.0, "length of the sweep (s)", minimum=1.0),
    "rates": Option("0.23,0.17,0.41", "turn rates about x, y, z (rev/s)"),
    "mag_rate": Option(100.0, "magnetometer sample rate (Hz)", minimum=1.0),
    "dt": Option(1e-2, "macro step (s)", minimum=1e-5),
    "noise": Option(True, "IMU white noise"),
    "seed": Option(1, "IMU noise seed"),
    "iron": Option(True, "soft and hard iron on (the module's SOFT_IRON, HARD_IRON); off: A = I, b_s = 0"),
}


def _rot(axis: int, angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros((len(angle), 3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R[:, axis, axis] = 1
    R[:, i, i], R[:, i, j], R[:, j, i], R[:, j, j] = c, -s, s, c
    return R


def attitude(o: dict) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and rotations body -> NED of the sweep."""
    try:
        rates = [float(x) for x in o["rates"].split(",")]
        assert len(rates) == 3
    except (ValueError, AssertionError):
        raise ValueError(f"option rates = {o['rates']!r} must be three comma-separated turn rates (rev/s)") from None
    # sampled at min(1/dt, mag_rate): a rate beyond half of it aliases (1e6 rev/s sampled at 100 Hz is no motion)
    nyquist = 0.5 * min(1.0 / o["dt"], o["mag_rate"])
    if not all(np.isfinite(rates)) or max(abs(r) for r in rates) >= nyquist or not any(rates):
        raise ValueError(f"option rates = {o['rates']!r}: each turn rate must be a finite number of rev/s below "
                         f"{nyquist:g} (half the {2 * nyquist:g} Hz the sweep is sampled at, else it aliases), "
                         "and not all zero (the sweep must turn); the default is 0.23,0.17,0.41")
    t = np.arange(int(round(o["duration"] / o["dt"])) + 1) * o["dt"]
    R = _rot(2, 2 * np.pi * rates[2] * t) @ _rot(1, 2 * np.pi * rates[1] * t) @ _rot(0, 2 * np.pi * rates[0] * t)
    return t, R


def quaternions(R: np.ndarray) -> np.ndarray:
    """Unit quaternions (scalar first, q0 >= 0) of rotations ``R`` (n, 3, 3)."""
    from scipy.spatial.transform import Rotation

    xyzw = Rotation.from_matrix(R).as_quat()
    q = np.column_stack([xyzw[:, 3], xyzw[:, :3]])
    q[q[:, 0] < 0] *= -1
    return q


def iron(o: dict) -> tuple[np.ndarray, np.ndarray]:
    """The IMU's true soft iron ``A`` (1) and hard iron ``b_s`` (T) for option ``iron``."""
    if o["iron"]:
        return np.array(SOFT_IRON), np.array(HARD_IRON)
    return np.eye(3), np.zeros(3)


def build(o: dict) -> System:
    """A scripted attitude table driving the IMU, motors off."""
    t, R = attitude(o)
    q = quaternions(R)
    force = np.einsum("nji,j->ni", R, [0.0, 0.0, -vehicle.GRAVITY])  # at rest: R^T (0, 0, -g)
    omega = np.zeros((len(t), 3))
    omega[:-1] = np.array([[(r1.T @ r2)[2, 1], (r1.T @ r2)[0, 2], (r1.T @ r2)[1, 0]] for r1, r2 in zip(R[:-1], R[1:],
                                                                                                      strict=True)])
    omega[:-1] /= o["dt"]
    A, b = iron(o)
    period = round(1.0 / (o["mag_rate"] * o["dt"]))
    if period < 1 or abs(period * o["dt"] * o["mag_rate"] - 1.0) > 1e-9:
        raise ValueError(f"mag_rate = {o['mag_rate']} Hz must divide the macro step rate {1 / o['dt']:g} Hz")
    system = System(dt=o["dt"])
    names = ["q0", "q1", "q2", "q3", "omega_x", "omega_y", "omega_z", "f_x", "f_y", "f_z"]
    system.add(Table("Hand", names, np.column_stack([q, omega, force]),
                     units={name: "1" if name[0] == "q" else "rad/s" if name[0] == "o" else "m/s2" for name in names}))
    parameters = imu_parameters(o["noise"], False, o["seed"], sample_rate=o["mag_rate"],
                                mag_sample_rate=o["mag_rate"])
    parameters |= {f"A_{i + 1}{j + 1}": A[i, j] for i in range(3) for j in range(3)}
    parameters |= {f"b_s_{a}": b[k] for k, a in enumerate("xyz")}
    system.add(FMUBlock("IMU", parameters=parameters))
    for name in names:
        system.connect(f"Hand.{name}", f"IMU.{name}")
    system.set_input("IMU.b_d", 0.0)  # motors off
    system.set_input("IMU.omega_r", 0.0)
    return system


def duration(o: dict) -> float:
    """Length of the sweep (s)."""
    return o["duration"]


def _readings_panel(ax, points, colour: str, what: str, reach: float):
    """Magnetometer readings ``points`` (uT) as a 3-D cloud on ``ax``, the axes from ``-reach`` to
    ``reach`` (uT), titled with ``what`` and the range of their norm."""
    from matplotlib.ticker import MaxNLocator

    norm = np.linalg.norm(points, axis=1)
    ax.scatter(*points.T, s=1, color=colour)
    ax.set(xlim=(-reach, reach), ylim=(-reach, reach), zlim=(-reach, reach))
    ax.set_box_aspect((1.0, 1.0, 1.0))
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):  # four ticks a side: the default eight collide in 3-D
        axis.set_major_locator(MaxNLocator(4, symmetric=True))
    ax.tick_params(labelsize=7, pad=0)
    ax.set_xlabel("x (µT)", labelpad=2)
    ax.set_ylabel("y (µT)", labelpad=2)
    ax.set_zlabel("z (µT)", labelpad=2)
    ax.set_title(f"{what} readings, |m| from {norm.min():.1f} to {norm.max():.1f} µT", fontsize=9)


def report(result, o, out) -> dict:
    """Fit ``A``, ``b_s`` to the magnetometer samples of ``result``; compare with the truth; write
    ``static.json`` and the figure into ``out`` (none when None); return the figures of merit.
    ``o``: the parsed options."""
    import matplotlib.pyplot as plt

    A, b = iron(o)
    samples = result["IMU.magneto"][:: max(1, round(1.0 / (o["mag_rate"] * o["dt"])))]
    fit = fit_static(samples, field_norm=vehicle.EARTH_FIELD_NORM)
    earth = np.array(vehicle.EARTH_FIELD)
    yaw = np.linspace(-np.pi, np.pi, 721)
    level = np.column_stack([np.cos(yaw) * earth[0], -np.sin(yaw) * earth[0], np.full_like(yaw, earth[2])])
    corrected = fit.correct(level @ A.T + b)
    heading = np.degrees(np.angle(np.exp(1j * (np.arctan2(-corrected[:, 1], corrected[:, 0]) - yaw))))
    raw = level @ A.T + b
    heading_raw = np.degrees(np.angle(np.exp(1j * (np.arctan2(-raw[:, 1], raw[:, 0]) - yaw))))
    if out is not None:
        write_json(out / "static.json", Calibration(4, fit, notes={"made_by": "quadcosim run static-cal"}).to_dict())
    fig = plt.figure(figsize=(14, 4.8))
    raw_uT, corrected_uT = samples * 1e6, fit.correct(samples) * 1e6
    reach = np.abs(np.vstack([raw_uT, corrected_uT])).max()
    # raw and corrected on axes of their own, to the same scale: drawn on one axes, either hides the other
    for panel, (points, colour, what) in enumerate(((raw_uT, "C0", "raw"), (corrected_uT, "C1", "corrected")),
                                                   start=1):
        _readings_panel(fig.add_subplot(1, 3, panel, projection="3d"), points, colour, what, reach)
    ax2 = fig.add_subplot(1, 3, 3)
    ax2.plot(np.degrees(yaw), heading_raw, label="uncorrected")
    ax2.plot(np.degrees(yaw), heading, label="corrected")
    ax2.set_xlabel("true heading (deg)")
    ax2.set_ylabel("heading error (deg)")
    ax2.grid(True, alpha=0.3)
    ax2.legend(fontsize=8)
    ax2.set_title("level yaw turn, noise-free readings", fontsize=10)
    fig.suptitle(title_lines(f"static-cal: hand-held rotation sweep, {o['duration']:g} s at ({o['rates']}) rev/s "
                             "about x, y, z, motors off",
                             f"magnetometer {o['mag_rate']:g} Hz, IMU noise {'on' if o['noise'] else 'off'}, "
                             + ("soft and hard iron on" if o["iron"] else "no soft or hard iron")
                             + f"; fitted to |m| = {vehicle.EARTH_FIELD_NORM * 1e6:.1f} µT"), fontsize=9)
    figure = save_figure(fig, out, "static_calibration.png")
    truth = result["IMU.magneto"]  # the angle of every corrected reading to the true body field
    t, R = attitude(o)
    body = np.einsum("nji,j->ni", R[: len(truth)], earth)
    angle = np.degrees(angle_between(fit.correct(truth), body))
    return {
        "A": fit.A.tolist(), "b_s_uT": (fit.b_s * 1e6).tolist(),
        "A_true": A.tolist(), "b_s_true_uT": (b * 1e6).tolist(),
        "A_error_max": float(np.abs(fit.A - A).max()),
        "b_s_error_max_uT": float(np.abs(fit.b_s - b).max() * 1e6),
        "quality": fit.quality(),
        "heading_error_max_deg": float(np.abs(heading).max()),
        "heading_error_uncorrected_max_deg": float(np.abs(heading_raw).max()),
        "field_angle_error_mean_deg": float(angle.mean()),
        "figures": [figure] if figure else [],
        "units": {"A": "1", "A_true": "1", "A_error_max": "1"},
    }


SCENARIO = Scenario("static-cal", __doc__.split(": ", 1)[1].splitlines()[0], OPTIONS, build, report,
                    duration=duration, extra={"record": ["IMU.magneto"], "derived": {
                        "IMU.noise_enabled": "noise", "IMU.seed": "seed", "IMU.sample_rate": "mag_rate",
                        "IMU.mag_sample_rate": "mag_rate"}, "blocks": {"Hand": Table, "IMU": "IMU"}})
