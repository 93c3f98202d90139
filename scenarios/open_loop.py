"""``open-loop``: scripted ESC commands into MotorMagnetics, then Quadrotor, then IMU.

The motors spin up to the hover command, the vehicle hovers, then a short differential
pulse on each pair of motors rolls, pitches and yaws it. No controller: the attitude is
left free after each pulse.
"""

from __future__ import annotations

from functools import partial

import numpy as np
from quadcosim.fmus import vehicle
from quadcosim.orchestrator import System, Table
from quadcosim.scenarios import Option, Scenario
from quadcosim.scenarios.divergence import Bounds
from quadcosim.scenarios.figures import fault_text, faults_of, label_axes, shade_faults, title_lines
from quadcosim.scenarios.plant import PLANT_BLOCKS, add_plant, imu_parameters, save_figure

OPTIONS = {
    "duration": Option(2.0, "simulated time (s)", minimum=1e-3),
    "dt": Option(1e-3, "macro step (s)", minimum=1e-6),
    "noise": Option(True, "IMU white noise"),
    "bias": Option(False, "IMU accelerometer and gyro biases"),
    "magnetic": Option(True, "field of the motor currents at the magnetometer"),
    "seed": Option(1, "IMU noise seed"),
    "pulse": Option(0.01, "height of the differential command pulses (1)", minimum=0.0),
}


# the differential pulses: axis, start (s), sign per motor (columns are motors 1..4: 1 front-right,
# 2 rear-left, 3 front-left, 4 rear-right)
PULSES = (("roll", 0.8, (-1, 1, 1, -1)), ("pitch", 1.2, (1, -1, 1, -1)), ("yaw", 1.6, (1, 1, -1, -1)))
PULSE_LENGTH = 0.05  # s


def commands(duration: float, dt: float, pulse: float) -> np.ndarray:
    """(n, 4) ESC commands at 0, dt, ..., duration (s), with pulses of height ``pulse`` (1): see
    :func:`commands_at`."""
    return commands_at(np.arange(int(round(duration / dt)) + 1) * dt, pulse)


def commands_at(t: np.ndarray, pulse: float) -> np.ndarray:
    """(len(t), 4) ESC commands at times ``t`` (s): spin-up, hover, then roll, pitch and yaw
    pulses of 50 ms and height ``pulse`` (1)."""
    c = np.full((len(t), 4), vehicle.hover_command())
    c *= np.clip(t / 0.3, 0.0, 1.0)[:, None]
    for _, start, pattern in PULSES:
        window = (t >= start) & (t < start + PULSE_LENGTH)
        c[window] += pulse * np.array(pattern)
    return c


def build(o: dict) -> System:
    """The plant driven by a table of ESC commands (:func:`commands_at`): no controller, no estimator.

    Parameters
    ----------
    o : dict
        Parsed options; ``dt`` (s), ``pulse`` (height of the differential command pulses, 1),
        ``noise``, ``bias``, ``seed`` and ``magnetic`` are used.

    Returns
    -------
    quadcosim.orchestrator.System
        Blocks ``Setpoint``, ``MotorMagnetics``, ``Quadrotor`` and ``IMU``.
    """
    system = System(dt=o["dt"])
    system.add(Table("Setpoint", ["c1", "c2", "c3", "c4"], partial(commands_at, pulse=o["pulse"]),
                     units=dict.fromkeys(("c1", "c2", "c3", "c4"), "1")))
    add_plant(system, imu=imu_parameters(o["noise"], o["bias"], o["seed"]), magnetic=o["magnetic"])
    system.connect("Setpoint.c", "MotorMagnetics.c")
    return system


def report(result, o, out) -> dict:
    """Final position, largest attitude, hover current; figures ``open_loop.png`` (commands,
    rotor speeds, attitude) and ``imu.png`` (the three sensors), pulses and faults shaded.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        The recorded run.
    o : dict
        Parsed options.
    out : pathlib.Path or None
        Folder of ``open_loop.png`` and ``imu.png``; None writes no file.

    Returns
    -------
    dict
        ``final_position_m`` (NED), ``max_abs_attitude_deg`` (roll, pitch, yaw),
        ``hover_current_A`` (motor 1 at 0.7 s), ``us_per_step`` and ``real_time_factor`` of the
        loop, and the figures written.
    """
    figures = _figures(result, o, out)  # first: the figures need the most signals
    loop = result.meta.get("loop_seconds")
    return {
        "final_position_m": result["Quadrotor.p"][-1].tolist(),
        "max_abs_attitude_deg": np.degrees(np.abs(np.column_stack(
            [result[f"Quadrotor.theta{i}"] for i in (1, 2, 3)])).max(axis=0)).tolist(),
        "hover_current_A": float(result["MotorMagnetics.i1"][np.searchsorted(result.time, min(0.7, o["duration"]))]
                                 if result.time[-1] >= 0.7 else np.nan),
        "us_per_step": None if loop is None else loop / (len(result) - 1) * 1e6,
        "real_time_factor": None if loop is None else o["duration"] / loop,
        "figures": figures,
        "units": {"us_per_step": "us", "real_time_factor": "1"},
    }


def _figures(result, o, out) -> list[str]:
    """``open_loop.png`` and ``imu.png`` in ``out``; none, and nothing drawn, without a folder."""
    if out is None:
        return []
    import matplotlib.pyplot as plt

    faults = faults_of(result)
    title = title_lines("open-loop: scripted ESC commands, no controller: spin-up, hover, then "
                        f"differential pulses of \u00b1{o['pulse']:g} on the commands, {PULSE_LENGTH * 1e3:g} ms each "
                        "(roll, pitch, yaw)",
                        f"IMU noise {'on' if o['noise'] else 'off'}, biases {'on' if o['bias'] else 'off'}, "
                        f"motor-current field {'on' if o['magnetic'] else 'off'}", fault_text(faults))

    def finish(fig, axes, name):
        for ax in axes:
            for _, start, _ in PULSES:
                if start < result.time[-1]:
                    ax.axvspan(start, start + PULSE_LENGTH, color="#7f7f7f", alpha=0.15, lw=0)
            ax.label_outer()
        shade_faults(axes, faults)
        if faults:
            axes[0].legend(fontsize=7, loc="best")  # with the fault window
        axes[0].set_title("grey: command pulses", fontsize=7, loc="right")
        fig.suptitle(title, fontsize=9)
        label_axes(axes)
        return save_figure(fig, out, name)

    figures = []
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    result.plot("Setpoint.c", ax=axes[0])
    axes[0].set_ylabel("ESC command (1)")
    result.plot("MotorMagnetics.omega_r", ax=axes[1])
    axes[1].set_ylabel("rotor speed (rad/s)")
    result.plot("Quadrotor.theta1", "Quadrotor.theta2", "Quadrotor.theta3", ax=axes[2], scale=180 / np.pi, unit="deg")
    axes[2].set_ylabel("roll, pitch, yaw (deg)")
    figures.append(finish(fig, axes, "open_loop.png"))
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    result.plot("IMU.acc", ax=axes[0])
    axes[0].set_ylabel("accelerometer (m/s²)")
    result.plot("IMU.gyro", ax=axes[1])
    axes[1].set_ylabel("gyrometer (rad/s)")
    result.plot("IMU.magneto", ax=axes[2], scale=1e6, unit="µT")
    axes[2].set_ylabel("magnetometer (µT)")
    figures.append(finish(fig, axes, "imu.png"))
    return [f for f in figures if f]


# without a controller the vehicle is free: a tilt of 60 deg (its thrust holds half its weight) or 10 m/s
# (a second of free fall), held 0.1 s (longer than a 50 ms pulse), is a tumble. The default 2 s run reaches
# 22 deg of roll and 3.2 m/s; pulse=0.1 rolls it over (175 deg) and duration=4 reaches 73 deg and 16 m/s
DIVERGENCE = Bounds(tilt_error_deg=None, altitude_error_m=None, speed_m_s=10.0, held_s=0.1, tilt_deg=60.0)
SCENARIO = Scenario("open-loop", __doc__.split(": ", 1)[1].splitlines()[0], OPTIONS, build, report,
                    extra={"derived": {"IMU.noise_enabled": "noise", "IMU.bias_enabled": "bias", "IMU.seed": "seed"},
                           "divergence": DIVERGENCE, "blocks": {"Setpoint": Table, **PLANT_BLOCKS}})
