"""The ``ir-calibration`` flight in batch: the InfraredSensor FMU's arithmetic on whole arrays.

A study of fault detection over thousands of flights cannot step the FMU sample by sample (a
flight of 8000 samples takes about a second through it). :func:`fly` computes the same flight
from the same equations as ``fmus/InfraredSensor/model.c``, on arrays:

- the turn rate ``r = g tan(phi) / V`` of the bank profile
  (:func:`quadcosim.scenarios.ir_calibration.bank_profile`, the same function the FMU is fed from);
- the drift of ``a`` and ``b`` (time of day, temperature, cloud) at ``t_k = k / rate``;
- ``IR_k = a r + b + n_IR``, the noise drawn by the FMU's counter-based generator
  (``fmus/c/noise.h``: splitmix64 of the seed, the sample and the channel, then Box-Muller),
  compiled with numba;
- the heading advanced by ``r / rate`` a sample, its noisy samples differenced over the GPS
  window and delivered the GPS delay late.

``tests/test_infrared_fleet.py`` holds it to the FMU's output to rounding. Faults are added as
:func:`quadcosim.scenarios.ir_calibration.simulate_flight` adds them.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from quadcosim.fmus.build import table
from quadcosim.scenarios.ir_calibration import RATE, bank_profile, fault_windows

from quadcosim.infra import numba_cache

numba_cache.install()  # before any decorator: numba picks a function's cache folder then

_MASK = (1 << 64) - 1
GOLDEN, MIX1, MIX2, SECOND = 0x9E3779B97F4A7C15, 0xBF58476D1CE4E5B9, 0x94D049BB133111EB, 0xD1B54A32D192ED03
KEYS_PER_SAMPLE = 64  # sample k owns the keys 64 k to 64 k + 63, as in the FMU
CH_IR, CH_HEADING = 0, 1  # the FMU's noise channels


@njit(cache=True)
def _splitmix64(z):
    z = z + np.uint64(GOLDEN)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(MIX1)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(MIX2)
    return z ^ (z >> np.uint64(31))


@njit(cache=True)
def gaussian(seed, first, count, channel):
    """Standard normal draws ``channel`` of samples ``first`` to ``first + count - 1``: the
    FMU's ``gaussian(seed, k, channel)`` (``fmus/c/noise.h``), the same integers and the same
    Box-Muller."""
    out = np.empty(count)
    base = _splitmix64(np.uint64(seed & 0xFFFFFFFF))
    scale = 2.0 ** -53
    for j in range(count):
        k = np.uint64(first + j)
        key = base ^ (k * np.uint64(KEYS_PER_SAMPLE) + np.uint64(2 * channel))
        u1 = (float(_splitmix64(key) >> np.uint64(11)) + 1.0) * scale
        u2 = float(_splitmix64(key ^ np.uint64(SECOND)) >> np.uint64(11)) * scale
        out[j] = math.sqrt(-2.0 * math.log(u1)) * math.cos(6.283185307179586 * u2)
    return out


def parameters(overrides: dict | None = None) -> dict:
    """The InfraredSensor's parameters (its defaults, then ``overrides``)."""
    values = {v.name: v.start for v in table("InfraredSensor").of("parameter")}
    unknown = set(overrides or {}) - set(values)
    if unknown:
        raise ValueError(f"InfraredSensor has no parameter {', '.join(sorted(unknown))}; "
                         f"its parameters: {', '.join(sorted(values))}")
    return values | dict(overrides or {})


def _cloud(p: dict, t: np.ndarray) -> np.ndarray:
    """Cloud cover in [0, 1] at ``t`` (s): sin^2 in, a plateau, cos^2 out (the FMU's ``cloud_cover``)."""
    ramp = p["cloud_ramp"]
    into = t - p["cloud_start"]
    out = into - ramp - p["cloud_duration"]
    cover = np.zeros_like(t)
    rising = (into > 0.0) & (into < ramp)
    cover[rising] = np.sin(0.5 * np.pi * into[rising] / ramp) ** 2
    cover[(into >= ramp) & (out <= 0.0)] = 1.0
    falling = (out > 0.0) & (out < ramp)
    cover[falling] = np.cos(0.5 * np.pi * out[falling] / ramp) ** 2
    return cover


def calibration(p: dict, t: np.ndarray, drift: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """True ``a`` (count per rad/s) and ``b`` (count) at ``t`` (s), the FMU's ``calibration``, for
    the FMU's parameters ``p``; constant at their initial values when ``drift`` is False."""
    if not drift:
        return np.full_like(t, p["ir_gain"]), np.full_like(t, p["ir_offset"])
    wave = np.sin(2.0 * np.pi * t / p["temperature_period"])
    cloud = _cloud(p, t)
    a = p["ir_gain"] * (1.0 + p["gain_day_rate"] * t + p["gain_temperature"] * wave + p["gain_cloud"] * cloud)
    b = p["ir_offset"] + p["offset_day_rate"] * t + p["offset_temperature"] * wave + p["offset_cloud"] * cloud
    return a, b


def sensor(phi: np.ndarray, seed: int, drift: bool = True, noise: bool = True,
           overrides: dict | None = None) -> dict[str, np.ndarray]:
    """The InfraredSensor's outputs for the bank angles ``phi`` (rad, one per sample from
    ``t = 0``), as :func:`quadcosim.scenarios.ir_calibration.simulate_flight` reads them from the FMU.

    Parameters
    ----------
    phi : (n,) array
        Bank angle per sample (rad), ``|phi| < pi/2``.
    seed : int
        Noise seed (the FMU's ``seed``).
    drift, noise : bool
        The FMU's ``drift_enabled`` and ``noise_enabled``.
    overrides : dict, optional
        Other parameters of the FMU.

    Returns
    -------
    dict of (n,) arrays
        ``time`` (s), ``r`` (rad/s), ``a``, ``b``, ``ir`` (count), ``gps_turn_rate`` (rad/s),
        ``gps_valid`` (1 once the heading history covers the window).
    """
    p = parameters(overrides)
    phi = np.asarray(phi, dtype=float)
    if np.any(np.abs(phi) >= 0.5 * np.pi):
        raise ValueError("a bank angle is at or beyond +-pi/2: a coordinated turn needs |phi| < pi/2")
    rate, n = p["sample_rate"], phi.shape[0]
    delay, window = int(round(p["gps_delay"] * rate)), int(round(p["gps_window"] * rate))
    t = np.arange(n) / rate
    r = p["gravity"] * np.tan(phi) / p["airspeed"]
    a, b = calibration(p, t, drift)
    ir = a * r + b
    # heading at each sample: the FMU adds r h a step, from psi0
    psi = p["psi0"] + np.concatenate([[0.0], np.cumsum(r[:-1] * (1.0 / rate))])
    heading = psi.copy()
    if noise:
        ir += p["ir_noise"] * gaussian(int(seed), 0, n, CH_IR)
        heading += p["gps_heading_noise"] * gaussian(int(seed), 0, n, CH_HEADING)
    gps = np.zeros(n)
    valid = np.zeros(n)
    span = delay + window
    if n > span:
        gps[span:] = (heading[span - delay:n - delay] - heading[:n - span]) / p["gps_window"]
        valid[span:] = 1.0
    return {"time": t, "r": r, "a": a, "b": b, "ir": ir, "gps_turn_rate": gps, "gps_valid": valid}


def fly(seed: int, samples: int = 8000, faults: str = "none", ir_fault: float = 1200.0, gps_fault: float = 1.5,
        drift: bool = True, noise: bool = True, overrides: dict | None = None) -> dict[str, np.ndarray]:
    """One ``ir-calibration`` flight in batch: :func:`quadcosim.scenarios.ir_calibration.simulate_flight`'s
    flight (the same bank profile, sensor and faults) without the FMU.

    Parameters
    ----------
    seed : int
        Seed of the bank profile and of the noise.
    samples : int
        Samples at 20 Hz.
    faults : {"none", "ir", "gps", "both"}
        The faults at the slides' onsets, 2000 samples each.
    ir_fault, gps_fault : float
        Their offsets (count, rad/s).
    drift, noise : bool
        The sensor's drift and noise.
    overrides : dict, optional
        Other parameters of the FMU.
    """
    if samples / RATE != samples / parameters(overrides)["sample_rate"]:
        raise ValueError("the bank profile is drawn at 20 Hz: keep the FMU's sample_rate")
    flight = sensor(bank_profile(samples, seed), seed, drift, noise, overrides)
    for name, start, stop, offset in fault_windows(faults, ir_fault, gps_fault):
        inside = (flight["time"] >= start - 1e-9) & (flight["time"] < stop - 1e-9)
        flight["ir" if name == "ir" else "gps_turn_rate"][inside] += offset
    return flight
