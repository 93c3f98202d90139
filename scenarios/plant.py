"""The plant of the lab's diagram, wired once for every scenario.

``MotorMagnetics -> omega_r -> Quadrotor -> (q, omega, f) -> IMU``, and the field of the
motor currents ``b_d`` into the IMU (or zero when the perturbation is off).
"""

from __future__ import annotations

import numpy as np

from orchestrator import FMUBlock, System


def add_plant(system: System, quadrotor=None, motors=None, imu=None, magnetic: bool = True,
              imu_period: int = 1) -> System:
    system.add(FMUBlock("MotorMagnetics", parameters=motors))
    system.add(FMUBlock("Quadrotor", parameters=quadrotor))
    system.add(FMUBlock("IMU", parameters=imu, period=imu_period))
    system.connect("MotorMagnetics.omega_r", "Quadrotor.omega_r")
    system.connect("Quadrotor.q", "IMU.q")
    system.connect("Quadrotor.omega", "IMU.omega")
    system.connect("Quadrotor.f", "IMU.f")
    if magnetic:
        system.connect("MotorMagnetics.b_d", "IMU.b_d")
    else:
        system.set_input("IMU.b_d", 0.0)
    return system


def imu_parameters(noise: bool, bias: bool, seed: int, sample_rate: float = 1000.0, **extra) -> dict:
    return {"noise_enabled": noise, "bias_enabled": bias, "seed": seed, "sample_rate": sample_rate, **extra}


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (rad) between rows of ``a`` and the vector(s) ``b``."""
    a = np.atleast_2d(a)
    b = np.broadcast_to(b, a.shape)
    cross = np.linalg.norm(np.cross(a, b), axis=1)
    return np.arctan2(cross, np.einsum("ij,ij->i", a, b))


def save_figure(figure, out_dir, name: str):
    if out_dir is None:
        import matplotlib.pyplot as plt

        plt.close(figure)
        return None
    path = out_dir / name
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    import matplotlib.pyplot as plt

    plt.close(figure)
    return str(path.name)
