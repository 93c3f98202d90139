"""Benchmark figures of the estimators and of the closed loop, for ``quadcosim bench``.

- ``rtf_closed_loop``: real-time factor of the ``tp`` scenario at 1 kHz (three FMUs, the
  estimator, the controller), stepping loop only;
- ``batch_updates_per_s``: filter updates per second of the batch path (explicit filter,
  256 gain sets evaluated in one call);
- ``ahrs_samples_per_s``: samples per second of the ``ahrs`` package's Mahony filter
  (``updateIMU``) on the same data, measured in the same run, for the ratio.
"""

from __future__ import annotations

import time

import numpy as np


def rtf_closed_loop(seconds: float, repeats: int) -> float:
    """Real-time factor of ``tp`` (explicit filter, noise and bias) over ``seconds`` simulated, best of ``repeats``."""
    import scenarios

    scenario = scenarios.get("tp")
    options = scenario.parse({"duration": seconds, "estimator": "explicit", "noise": True, "bias": True})
    best = np.inf
    for _ in range(repeats):
        result = scenario.build(options).run(seconds)
        best = min(best, result.meta["loop_seconds"])
    return seconds / best


def _data(samples: int):
    rng = np.random.default_rng(0)
    acc = np.array([0.0, 0.0, -9.81]) + 0.1 * rng.standard_normal((samples, 3))
    gyro = 0.01 * rng.standard_normal((samples, 3))
    mag = np.array([2e-5, 0.0, 4.3e-5]) + 1e-7 * rng.standard_normal((samples, 3))
    return acc, gyro, mag


def batch_updates_per_s(gain_sets: int = 256, samples: int = 4000, repeats: int = 3) -> float:
    """Filter updates per second of the explicit filter's batch path over ``gain_sets`` gain
    sets and ``samples`` samples, best of ``repeats``."""
    from estimators import estimate

    acc, gyro, mag = _data(samples)
    gains = {"k1": np.geomspace(0.01, 10, gain_sets), "kI": 0.1}
    estimate("explicit", acc=acc[:10], gyro=gyro[:10], mag=mag[:10], dt=1e-3, gains=gains)  # compile
    best = np.inf
    for _ in range(repeats):
        started = time.perf_counter()
        estimate("explicit", acc=acc, gyro=gyro, mag=mag, dt=1e-3, gains=gains)
        best = min(best, time.perf_counter() - started)
    return gain_sets * samples / best


def ahrs_samples_per_s(samples: int = 4000) -> float:
    """Samples per second of the ``ahrs`` package's Mahony ``updateIMU`` on ``samples`` samples."""
    from ahrs.filters import Mahony

    acc, gyro, _ = _data(samples)
    mahony = Mahony(k_P=1.0, k_I=0.1, frequency=1000.0)
    q = np.array([1.0, 0.0, 0.0, 0.0])
    started = time.perf_counter()
    for n in range(samples):
        q = mahony.updateIMU(q, gyr=gyro[n], acc=-acc[n], dt=1e-3)
    return samples / (time.perf_counter() - started)


def measure(seconds: float = 5.0, repeats: int = 3) -> dict:
    """The estimator figures as a dict, runs of ``seconds`` simulated, best of ``repeats``."""
    figures = {"rtf_closed_loop": rtf_closed_loop(seconds, repeats), "batch_updates_per_s": batch_updates_per_s()}
    try:
        figures["ahrs_samples_per_s"] = ahrs_samples_per_s()
        figures["batch_over_ahrs"] = figures["batch_updates_per_s"] / figures["ahrs_samples_per_s"]
    except ImportError:
        figures["ahrs_samples_per_s"] = None
    return figures
