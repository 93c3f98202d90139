"""``rig``: the drone clamped to the ground, each motor swept in turn, then all four together.

The test rig of Metge et al. (GRETSI 2013): with the body fixed, the Earth field in the sensor
frame is constant, so whatever moves the measured field comes from the motor currents.
Phases: motors off (the reference field m0), then each motor alone with its command ramped
from 0 to 1 and back to 0, then a free set where all four commands vary fast and together.
The metrics are the uncompensated mean angular errors between the measured field and m0
(Metge et al., Table 1, row "no dynamic calibration").
"""

from __future__ import annotations

import numpy as np
from quadcosim.orchestrator import System, Table, portable
from quadcosim.scenarios import Option, Scenario
from quadcosim.scenarios.divergence import CLAMPED
from quadcosim.scenarios.figures import fault_text, faults_of, label_axes, shade_faults, title_lines
from quadcosim.scenarios.plant import PLANT_BLOCKS, add_plant, angle_between, imu_parameters, save_figure

OPTIONS = {
    "reference": Option(1.0, "motors-off time at the start (s)", minimum=0.1),
    "sweep": Option(4.0, "time of one motor's ramp up and down (s)", minimum=0.1),
    "rest": Option(0.5, "motors-off time between sweeps (s)", minimum=0.0),
    "free": Option(6.0, "time of the free set, all motors varied together (s)", minimum=0.0),
    "dt": Option(1e-3, "macro step (s)", minimum=1e-6),
    "noise": Option(True, "IMU white noise"),
    "seed": Option(1, "seed of the IMU noise and of the free-set commands"),
    "roll": Option(0.0, "roll of the rig (rad)"),
    "pitch": Option(0.0, "pitch of the rig (rad)"),
    "yaw": Option(0.0, "yaw of the rig (rad)"),
}


def phases(o: dict) -> list[tuple[str, float, float]]:
    """(name, start, stop) of each phase (s)."""
    out, t = [("reference", 0.0, o["reference"])], o["reference"]
    for n in range(1, 5):
        out.append((f"motor{n}", t, t + o["sweep"]))
        t += o["sweep"] + o["rest"]
    if o["free"] > 0:
        out.append(("free", t, t + o["free"]))
        t += o["free"]
    return out


def duration(o: dict) -> float:
    """Simulated length (s) of the rig's run: the end of its last phase (:func:`phases`).

    Parameters
    ----------
    o : dict
        Parsed options; ``reference``, ``sweep``, ``rest`` and ``free`` (s) are used.

    Returns
    -------
    float
        Duration (s).
    """
    return phases(o)[-1][2]


def commands(o: dict) -> np.ndarray:
    """ESC commands of every phase: none during the reference, a triangle 0 -> 1 -> 0 on one motor
    at a time, then (``free`` > 0) sums of random sinusoids up to 3 Hz on all four.

    Parameters
    ----------
    o : dict
        Parsed options; ``dt`` (s), the phase lengths (s) and ``seed`` are used.

    Returns
    -------
    numpy.ndarray
        (n, 4) commands (1, in [0, 1]) at 0, dt, ..., :func:`duration`; columns are motors 1..4.
    """
    dt = o["dt"]
    t = np.arange(int(round(duration(o) / dt)) + 1) * dt
    c = np.zeros((len(t), 4))
    for name, start, stop in phases(o):
        inside = (t >= start) & (t < stop)
        s = (t[inside] - start) / (stop - start)
        if name.startswith("motor"):
            c[inside, int(name[-1]) - 1] = 1.0 - np.abs(2.0 * s - 1.0)  # triangle 0 -> 1 -> 0
        elif name == "free":
            rng = np.random.default_rng(o["seed"])
            # sums of random sinusoids up to 3 Hz: fast, simultaneous changes of all four
            for motor in range(4):
                f = rng.uniform(0.3, 3.0, 4)
                phase = rng.uniform(0, 2 * np.pi, 4)
                wave = portable.sin(2 * np.pi * f[:, None] * t[inside][None, :] + phase[:, None]).sum(axis=0)
                c[inside, motor] = np.clip(0.5 + 0.15 * wave, 0.0, 1.0)
    return c


def build(o: dict) -> System:
    """The clamped vehicle (the test rig) at a fixed attitude, its motors driven by :func:`commands`.

    Parameters
    ----------
    o : dict
        Parsed options; ``dt`` (s), ``roll``, ``pitch``, ``yaw`` (rad, Z-Y-X, NED), ``noise`` and
        ``seed`` are used.

    Returns
    -------
    quadcosim.orchestrator.System
        Blocks ``Setpoint``, ``MotorMagnetics``, ``Quadrotor`` (clamped) and ``IMU``.
    """
    system = System(dt=o["dt"])
    system.add(Table("Setpoint", ["c1", "c2", "c3", "c4"], commands(o),
                     units=dict.fromkeys(("c1", "c2", "c3", "c4"), "1")))
    add_plant(system, quadrotor={"clamped": True, "theta1_0": o["roll"], "theta2_0": o["pitch"],
                                 "theta3_0": o["yaw"]},
              imu=imu_parameters(o["noise"], False, o["seed"]))
    system.connect("Setpoint.c", "MotorMagnetics.c")
    return system


def mean_errors(result, o) -> tuple[np.ndarray, dict[str, float]]:
    """Angular error (deg) of the field measured in ``result`` against the motors-off reference,
    and its mean over each phase of the options ``o``."""
    field = result["IMU.magneto"]
    t = result.time
    spans = phases(o)
    _, start, stop = spans[0]
    reference = field[(t >= start) & (t < stop)].mean(axis=0)
    error = np.degrees(angle_between(field, reference))
    means = {name: float(error[(t >= a) & (t < b)].mean()) for name, a, b in spans[1:]}
    return error, means


def report(result, o, out) -> dict:
    """Mean angular errors of each phase and the figure ``rig_field.png``: the measured field,
    the ESC commands and the angle between the field and the motors-off reference, phases and
    fault windows shaded.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        The recorded run.
    o : dict
        Parsed options.
    out : pathlib.Path or None
        Folder of the figure; None writes no file.

    Returns
    -------
    dict
        ``mean_angular_error_deg`` per phase and its mean over the four one-motor phases (deg),
        ``reference_field_uT`` (body frame, motors off), and the figures written.
    """
    import matplotlib.pyplot as plt

    error, means = mean_errors(result, o)
    t = result.time
    faults = faults_of(result)
    fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    result.plot("IMU.magneto", ax=axes[0], scale=1e6, unit="µT")
    axes[0].set_ylabel("measured field (µT)")
    result.plot("Setpoint.c", ax=axes[1])
    axes[1].set_ylabel("ESC command (1)")
    axes[2].plot(t, error, lw=0.8)
    axes[2].set_ylabel("angle to m0 (deg)")
    axes[2].set_xlabel("time (s)")
    top = max(float(error.max()), 1.0)
    for name, a, b in phases(o)[1:]:
        for ax in axes:
            ax.axvspan(a, b, color="#1f77b4", alpha=0.06, lw=0)
        axes[2].text(0.5 * (a + b), top * 1.02, f"{name}\nmean {means[name]:.1f}°", ha="center", va="bottom",
                     fontsize=7)
    axes[2].set_ylim(0.0, top * 1.25)
    shade_faults(axes, faults)
    for ax in axes:
        ax.label_outer()
        ax.grid(True, alpha=0.3)
    if faults:
        axes[0].legend(fontsize=7, loc="upper left")  # with the fault window
    attitude = ", ".join(f"{k} {np.degrees(o[k]):g}°" for k in ("roll", "pitch", "yaw"))
    fig.suptitle(title_lines("rig: drone clamped to the ground, each motor's command ramped 0 to 1 to 0 in turn, "
                             "then all four varied together (free set)",
                             f"rig attitude {attitude}; IMU noise {'on' if o['noise'] else 'off'}; "
                             f"reference (motors off) {o['reference']:g} s, sweeps {o['sweep']:g} s",
                             fault_text(faults)), fontsize=9)
    label_axes(axes)
    figure = save_figure(fig, out, "rig_field.png")
    single = [means[f"motor{n}"] for n in range(1, 5)]
    return {
        "mean_angular_error_deg": means,
        "mean_angular_error_single_motor_deg": float(np.mean(single)),
        "reference_field_uT": (result["IMU.magneto"][t < o["reference"]].mean(axis=0) * 1e6).tolist(),
        "figures": [figure] if figure else [],
    }


SCENARIO = Scenario("rig", __doc__.split(": ", 1)[1].splitlines()[0], OPTIONS, build, report, duration=duration,
                    extra={"derived": {"IMU.noise_enabled": "noise", "IMU.seed": "seed"}, "divergence": CLAMPED,
                           "blocks": {"Setpoint": Table, **PLANT_BLOCKS}})
