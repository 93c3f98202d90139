"""The overview figure of a flight log: field, current, throttle and attitude over time."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np

from quadcosim.infra.files import printable, save_figure

TESLA_TO_UT = 1e6
#: Legends stand right of their axes, where they cover no trace.
LEGEND = {"loc": "upper left", "bbox_to_anchor": (1.005, 1.0), "fontsize": 7, "frameon": False, "borderaxespad": 0.0}


def _euler_deg(q: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw (deg, Z-Y-X; yaw wrapped to -180..180) of quaternions ``q`` (T, 4), scalar first."""
    from scipy.spatial.transform import Rotation

    return np.degrees(Rotation.from_quat(q, scalar_first=True).as_euler("ZYX")[:, ::-1])


def _broken_at_wraps(time: np.ndarray, angle_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``time`` and ``angle_deg`` with a NaN inserted where the angle wraps (a step over 180 deg), so
    a turn through +-180 deg draws no line across the axes."""
    jumps = np.flatnonzero(np.abs(np.diff(angle_deg)) > 180.0) + 1
    return np.insert(np.asarray(time, dtype=float), jumps, np.nan), np.insert(angle_deg, jumps, np.nan)


def plot_overview(log, out) -> Path:
    """Draw the overview of ``log`` (:class:`quadcosim.flightlogs.FlightLog`) into the figure file ``out``
    (its format from its suffix, written atomically: :func:`quadcosim.infra.files.save_figure`): each
    compass's raw field (uT), battery current (A) and voltage (V), motor commands and throttle
    (1), and the autopilot's roll, pitch and yaw (deg), on the log's clock (s)."""
    from quadcosim.infra.files import headless_backend

    headless_backend()
    import matplotlib.pyplot as plt

    t0 = log.start
    panels = max(1, len(log.compasses)) + 4
    fig, axes = plt.subplots(panels, 1, figsize=(11, 2.2 * panels), sharex=True, constrained_layout=True)
    for ax, compass in zip(axes, log.compasses, strict=False):
        for k, axis in enumerate("xyz"):
            ax.plot(compass.time - t0, compass.raw[:, k] * TESLA_TO_UT, lw=0.8, label=f"raw {axis}")
        ax.plot(compass.time - t0, np.linalg.norm(compass.field, axis=1) * TESLA_TO_UT, "k", lw=0.8,
                label="|field| as logged")
        where = {True: "external", False: "internal", None: ""}[compass.external]
        name = textwrap.fill(f"{compass.name} {where}".strip().replace(".", ". "), 24).replace(". ", ".")
        ax.set_ylabel(f"{name}\n(uT, body FRD)", fontsize=9)  # a topic name longer than the axes, wrapped
        ax.legend(**LEGEND)
    if not log.compasses:
        axes[0].text(0.5, 0.5, "no magnetometer in this log", ha="center", transform=axes[0].transAxes)
    ax = axes[-4]
    if log.battery is not None and log.battery.current is not None:
        ax.plot(log.battery.time - t0, log.battery.current, "C3", lw=0.8)
        ax.set_ylabel("current (A)")
    else:
        ax.text(0.02, 0.8, "no current sensor", transform=ax.transAxes)
    if log.battery is not None:
        twin = ax.twinx()
        twin.plot(log.battery.time - t0, log.battery.voltage, "C7", lw=0.8)
        twin.set_ylabel("voltage (V)", color="C7")
    ax = axes[-3]
    if log.motors is not None:
        for n in range(log.motors.commands.shape[1]):
            ax.plot(log.motors.time - t0, log.motors.commands[:, n], lw=0.6, label=f"motor {n + 1}")
        ax.plot(log.motors.time - t0, log.motors.throttle, "k", lw=1.0, label="throttle (mean)")
        ax.legend(**LEGEND)
    ax.set_ylabel("command (1)")
    ax, yaw_ax = axes[-2], axes[-1]
    source = log.attitude.source if log.attitude else "none logged"
    if log.attitude is not None:
        euler = _euler_deg(log.attitude.q)
        for k, name in enumerate(("roll", "pitch")):
            ax.plot(log.attitude.time - t0, euler[:, k], lw=0.8, label=name)
        ax.legend(**LEGEND)
        yaw_ax.plot(*_broken_at_wraps(log.attitude.time - t0, euler[:, 2]), "C2", lw=0.8, label="yaw")
        yaw_ax.legend(**LEGEND)
    ax.set_ylabel(f"roll, pitch (deg)\n{source}")
    # the heading on its own axis, wrapped: unwrapped, its turns (hundreds of degrees) flatten roll and pitch
    yaw_ax.set_ylabel(f"yaw (deg)\n{source}")
    yaw_ax.set_ylim(-185.0, 185.0)
    yaw_ax.set_yticks([-180, -90, 0, 90, 180])
    yaw_ax.set_xlabel("time from the first sample (s)")
    sim = ", SIMULATOR" if log.simulator else ""
    fig.suptitle(printable(f"{Path(log.path).name}: {log.autopilot} {log.firmware}, {log.vehicle}{sim}"), fontsize=10)
    out = Path(out)
    try:
        return save_figure(fig, out, dpi=110)
    finally:
        plt.close(fig)
