"""The plant of the lab's diagram, wired once for every scenario.

``MotorMagnetics -> (omega_r, domega_r) -> Quadrotor -> (q, omega, f) -> IMU``, the field of
the supply currents ``b_d`` into the IMU (or zero when the perturbation is off), and the rotor
speeds into the IMU for its optional vibration. The wind into the Quadrotor is a constant NED
vector, or left for the caller to connect.
"""

from __future__ import annotations

import contextlib
import contextvars

import numpy as np
from quadcosim.orchestrator import FMUBlock, System

#: The blocks :func:`add_plant` adds, by name: each an FMU of that model.
PLANT_BLOCKS = {"MotorMagnetics": "MotorMagnetics", "Quadrotor": "Quadrotor", "IMU": "IMU"}


def add_plant(system: System, quadrotor=None, motors=None, imu=None, magnetic: bool = True,
              imu_period: int = 1, wind=(0.0, 0.0, 0.0), specific_force: str = "Quadrotor.f") -> System:
    """Add the three plant FMUs to ``system`` and wire them.

    Parameters
    ----------
    system : System
    quadrotor, motors, imu : dict, optional
        Parameter overrides of the Quadrotor, MotorMagnetics and IMU FMUs.
    magnetic : bool
        Feed the field of the supply currents ``b_d`` (T, sensor frame) to the IMU; zero if False.
    imu_period : int
        IMU period in macro steps.
    specific_force : str
        Source of the IMU's specific-force input (m/s^2, body), a block added beforehand; the
        Quadrotor's by default (an ablation swaps in gravity alone).
    wind : sequence of 3 floats or None
        Constant wind velocity (m/s, NED: north, east, down). ``None`` leaves ``Quadrotor.wind``
        unconnected, for the caller to connect a wind source.
    """
    system.add(FMUBlock("MotorMagnetics", parameters=motors))
    system.add(FMUBlock("Quadrotor", parameters=quadrotor))
    system.add(FMUBlock("IMU", parameters=imu, period=imu_period))
    system.connect("MotorMagnetics.omega_r", "Quadrotor.omega_r")
    system.connect("MotorMagnetics.domega_r", "Quadrotor.domega_r")
    if wind is not None:
        for axis, value in zip("xyz", wind, strict=True):
            system.set_input(f"Quadrotor.wind_{axis}", float(value))
    system.connect("Quadrotor.q", "IMU.q")
    system.connect("Quadrotor.omega", "IMU.omega")
    system.connect(specific_force, "IMU.f")
    system.connect("MotorMagnetics.omega_r", "IMU.omega_r")
    if magnetic:
        system.connect("MotorMagnetics.b_d", "IMU.b_d")
    else:
        system.set_input("IMU.b_d", 0.0)
    return system


def imu_parameters(noise: bool, bias: bool, seed: int, sample_rate: float = 1000.0, **extra) -> dict:
    """Parameter overrides of the IMU FMU.

    Parameters
    ----------
    noise : bool
        White measurement noise on all three sensors.
    bias : bool
        Accelerometer and gyrometer biases (the gyro's default is the lab's, rad/s, {B}).
    seed : int
        Seed of the IMU's noise generator.
    sample_rate : float
        Accelerometer and gyrometer sampling rate (Hz); the magnetometer keeps its own
        ``mag_sample_rate`` (100 Hz by default) unless given in ``extra``.
    **extra
        Any other IMU parameter, by its FMU name (e.g. ``mag_sample_rate`` in Hz).

    Returns
    -------
    dict
        FMU parameter name to value.
    """
    return {"noise_enabled": noise, "bias_enabled": bias, "seed": seed, "sample_rate": sample_rate, **extra}


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (rad) between rows of ``a`` and the vector(s) ``b``."""
    a = np.atleast_2d(a)
    b = np.broadcast_to(b, a.shape)
    cross = np.linalg.norm(np.cross(a, b), axis=1)
    return np.arctan2(cross, np.einsum("ij,ij->i", a, b))


#: The format of the reports' figures (``quadcosim run --figures``): png (120 dpi), svg or pdf.
FIGURE_FORMAT = contextvars.ContextVar("figure_format", default="png")


@contextlib.contextmanager
def figure_format(name: str):
    """Within it, the reports write their figures as ``name`` (png, svg or pdf) files.

    Parameters
    ----------
    name : {"png", "svg", "pdf"}
        The format; the suffix of each figure file.
    """
    if name not in ("png", "svg", "pdf"):
        raise ValueError(f"figure format {name!r}: give png, svg or pdf")
    token = FIGURE_FORMAT.set(name)
    try:
        yield
    finally:
        FIGURE_FORMAT.reset(token)


def save_figure(figure, out_dir, name: str):
    """Save ``figure`` as ``out_dir / name`` (PNG, 120 dpi; or the format of :func:`figure_format`,
    which replaces the suffix of ``name``) and close it.

    Parameters
    ----------
    figure : matplotlib.figure.Figure
    out_dir : pathlib.Path or None
        Output folder; ``None`` closes the figure without saving it.
    name : str
        File name.

    Returns
    -------
    str or None
        The file name written, or ``None``.
    """
    if out_dir is None:
        import matplotlib.pyplot as plt

        plt.close(figure)
        return None
    import matplotlib.pyplot as plt

    from quadcosim.infra.files import save_figure as save_atomically
    from quadcosim.infra.progress import status

    path = (out_dir / name).with_suffix("." + FIGURE_FORMAT.get())
    status(f"figure {path.name}")
    try:
        figure.tight_layout()
        save_atomically(figure, path, dpi=120)  # a temporary name, fsync, rename: never a truncated figure
    finally:
        plt.close(figure)
    return str(path.name)
