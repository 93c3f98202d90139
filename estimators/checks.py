"""Checks of recorded measurements and of gains, before a filter runs on them.

- :func:`check_measurements`: shapes (an (N, 3) array per sensor; a transposed 3 x N one is
  refused, never reshaped), finite values, a missing or all-zero magnetometer (a 6-axis
  estimate, with a warning), and the accelerometer's unit judged on the specific force at rest;
- :func:`check_stability`: gains whose discrete loop diverges at the sample period, refused by
  name before the run;
- :func:`check_finite`: a run whose estimates are not finite names the gain set that produced them.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from quadcosim.estimators import layout

UNIT_WINDOW_S = 2.0  # s, windows over which the specific force is averaged for the unit check (several steps)
QUIET_FRACTION = 0.2  # the windows with the least gyro activity that judge the unit
UNIT_RATIO = 3.0  # |acc| at rest within [g / 3, 3 g]: a unit error (g, mg, a swapped gyro) is a factor of 10 or more
MILLI_G = 1e3  # an accelerometer in mg reads this many times its value in g
STABLE_LIMIT = 2.0  # a first-order discrete loop x <- (1 - a) x is stable for 0 < a < 2


class NoMagnetometerWarning(UserWarning):
    """The magnetometer is missing or reads zero: the estimate is 6-axis (heading from the gyro alone)."""


def _array(label: str, value) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.ndim == 2 and array.shape[0] == 3 and array.shape[1] != 3:
        raise ValueError(f"{label} has shape {array.shape}: it looks transposed (3 x N); give it as an (N, 3) array "
                         f"(samples in rows), e.g. {label}.T")
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"{label} must be an (N, 3) array (samples in rows), not shape {array.shape}")
    return array


def rest_specific_force(acc, gyro, dt: float) -> float:
    """The norm of the specific force (acc's unit) where the sensor moves least.

    The accelerometer is averaged over windows of :data:`UNIT_WINDOW_S`; over a window whose
    velocity comes back (at rest, walking, running, vibrating), the mean specific force is gravity
    whatever the accelerations inside it. The median norm over the windows of least gyro activity
    is returned. ``acc`` (N, 3, m/s^2), ``gyro`` (N, 3, rad/s), ``dt`` (s).
    """
    samples = max(1, min(len(acc), int(round(UNIT_WINDOW_S / dt))))
    windows = len(acc) // samples
    mean_acc = acc[:windows * samples].reshape(windows, samples, 3).mean(axis=1)
    activity = np.linalg.norm(gyro[:windows * samples], axis=1).reshape(windows, samples).mean(axis=1)
    quiet = np.argsort(activity)[:max(1, int(math.ceil(QUIET_FRACTION * windows)))]
    return float(np.median(np.linalg.norm(mean_acc[quiet], axis=1)))


def _check_unit(acc, gyro, dt, gravity_norm):
    at_rest = rest_specific_force(acc, gyro, dt)
    if gravity_norm / UNIT_RATIO <= at_rest <= UNIT_RATIO * gravity_norm:
        return
    hint = ""
    if gravity_norm / UNIT_RATIO <= rest_specific_force(gyro, acc, dt) <= UNIT_RATIO * gravity_norm:
        hint = " The gyro's norm is near g: were acc and gyro swapped?"
    elif 1.0 / UNIT_RATIO <= at_rest <= UNIT_RATIO:
        hint = " Is acc in g? Give it in m/s^2 (multiply by 9.81)."
    elif MILLI_G / UNIT_RATIO <= at_rest <= MILLI_G * UNIT_RATIO:
        hint = " Is acc in mg? Give it in m/s^2."
    raise ValueError(f"acc at rest (its mean over the quietest {UNIT_WINDOW_S:g} s windows) has a norm of "
                     f"{at_rest:.3g}, not near |g| = {gravity_norm:.3g} m/s^2.{hint} (check_units=False skips this "
                     "check.)")


def check_measurements(gyro, acc, mag, gravity_norm: float, check_units: bool = True, dt: float = 0.01) -> np.ndarray:
    """(N, 9) samples ``acc, gyro, mag``, refused with a clear message when malformed.

    Parameters
    ----------
    gyro, acc : (N, 3) arrays
        rad/s and m/s^2, body axes; a (3, N) array is refused as transposed.
    mag : (N, 3) array or None
        Magnetometer (any unit); None or all zeros gives zeros and a :class:`NoMagnetometerWarning`:
        the filters then correct the tilt only.
    gravity_norm : float
        |g| (m/s^2).
    check_units : bool
        Refuse an ``acc`` whose specific force at rest (:func:`rest_specific_force`) is not
        within a factor :data:`UNIT_RATIO` of ``gravity_norm``: an accelerometer in g or mg, or a
        swapped gyro. A running or vibrating recording passes.
    dt : float
        Sample period (s), for the windows of the unit check.
    """
    parts = {"acc": _array("acc", acc), "gyro": _array("gyro", gyro)}
    if mag is None or not np.any(np.asarray(mag, dtype=float)):
        warnings.warn("no magnetometer (missing or all zeros): a 6-axis estimate, the heading from the gyro alone",
                      NoMagnetometerWarning, stacklevel=3)
        parts["mag"] = np.zeros_like(parts["acc"]) if mag is None else _array("mag", mag)
    else:
        parts["mag"] = _array("mag", mag)
    lengths = [len(p) for p in parts.values()]
    if len(set(lengths)) != 1 or lengths[0] == 0:
        raise ValueError(f"acc, gyro and mag must hold the same number (> 0) of samples, not {lengths}")
    inputs = np.ascontiguousarray(np.column_stack([parts["acc"], parts["gyro"], parts["mag"]]))
    if not np.isfinite(inputs).all():
        row, column = np.argwhere(~np.isfinite(inputs))[0]
        raise ValueError(f"the recorded measurements hold NaN or Inf ({('acc', 'gyro', 'mag')[column // 3]} at "
                         f"sample {row}); remove or interpolate those samples")
    if check_units:
        _check_unit(parts["acc"], parts["gyro"], dt, gravity_norm)
    return inputs


def loop_coefficients(kind: str, table: np.ndarray, dt: float) -> dict:
    """Per-sample coefficients of the correction loops of the filter ``kind``, per gain set of
    ``table`` (G, GAIN_SIZE) at the period ``dt`` (s): (G,) arrays named after the gain that sets
    them (the fraction of the error removed per sample; for ``kI`` the bias loop's)."""
    if kind == "linear":
        return {name: table[:, layout.GAIN_SLOTS[name]] * dt for name in ("k1", "k2", "k3")}
    strongest = np.maximum(table[:, layout.K1], table[:, layout.K2])
    return {"kP": table[:, layout.KP] * strongest * dt, "kI": table[:, layout.KI] * strongest * dt * dt,
            "rest_gain": table[:, layout.REST_GAIN] * dt}


def check_stability(kind: str, table: np.ndarray, dt: float, names=None):
    """Refuse gain sets of the filter ``kind`` whose discrete correction loop diverges at the period ``dt`` (s).

    ``table`` (G, GAIN_SIZE) as :func:`quadcosim.estimators.filters.gain_table` builds it. Linear filter:
    ``k_i dt < 2`` (explicit Euler). Explicit and passive: the loop ``e <- e - a e - b sum e``
    with ``a = kP max(k1, k2) dt`` and ``b = kI max(k1, k2) dt^2`` is stable for ``a < 2`` and
    ``b < 4 - 2 a``; the rest gain ``rest_gain dt < 2``. ``names`` labels the gain sets.
    """
    c = loop_coefficients(kind, table, dt)
    if kind == "linear":
        bad = {name: c[name] >= STABLE_LIMIT for name in c}
        limits = {name: f"{name} < {STABLE_LIMIT / dt:.4g} 1/s" for name in c}
    else:
        bad = {"kP": c["kP"] >= STABLE_LIMIT, "kI": c["kI"] >= 2.0 * STABLE_LIMIT - 2.0 * c["kP"],
               "rest_gain": c["rest_gain"] >= STABLE_LIMIT}
        limits = {"kP": f"kP max(k1, k2) < {STABLE_LIMIT / dt:.4g} 1/s",
                  "kI": "kI max(k1, k2) dt^2 < 4 - 2 kP max(k1, k2) dt",
                  "rest_gain": f"rest_gain < {STABLE_LIMIT / dt:.4g} 1/s"}
    for name, mask in bad.items():
        if np.any(mask):
            g = int(np.argmax(mask))
            label = f" (gain set {g})" if len(table) > 1 else ""
            value = table[g, layout.GAIN_SLOTS[name]]
            raise ValueError(f"gain {name} = {value:g}{label} makes the {kind} filter diverge at dt = {dt:g} s: "
                             f"keep {limits[name]}, or sample faster")


def check_finite(kind: str, table: np.ndarray, stored: np.ndarray, sums: np.ndarray):
    """Refuse the result of a run of the filter ``kind`` whose estimates or error sums are not finite,
    naming the first gain set of ``table`` (G, GAIN_SIZE) that produced them (``stored`` (G, N, k)
    outputs, ``sums`` (G, ERROR_SIZE))."""
    per_set = np.isfinite(sums).all(axis=1)
    if stored.size:
        per_set &= np.isfinite(stored).all(axis=(1, 2))
    if per_set.all():
        return
    g = int(np.argmin(per_set))
    gains = ", ".join(f"{name} = {table[g, slot]:g}" for name, slot in layout.GAIN_SLOTS.items() if table[g, slot])
    raise ValueError(f"the {kind} filter diverged (non-finite estimate) with gain set {g}: {gains}; lower kP or kI")
