"""The end of a flight cut off where the log stops being a flight: a crash, a logging stall.

A log that ends in a crash holds seconds of a vehicle tumbling or lying on the ground, and a log
whose recording stalled holds two stretches with nothing between them; neither is what a
calibration or a replay should see. :func:`trimmed` keeps the longest stretch between stalls and
cuts it at a crash, saying both in the log's warnings; :func:`cut` keeps a span the user names
(``--span`` of ``quadcosim calibrate``).

- A stall: no IMU sample (the fastest series) for :data:`STALL_S` or more. The stretches on either
  side are separate flights (Copter stops logging while disarmed unless ``LOG_DISARMED`` is set);
  the longest is kept.
- A crash, as ArduCopter's own ``Copter::crash_check`` (``ArduCopter/crash_check.cpp``) declares it:
  the attitude more than ``CRASH_CHECK_ANGLE_DEVIATION_DEG`` (30 deg) from its target for
  ``CRASH_CHECK_TRIGGER_SEC`` (2 s) without a break, from ``ATT``'s ``Roll``/``Pitch`` against
  ``DesRoll``/``DesPitch`` (the firmware's check also asks for a lean of 15 deg and little
  acceleration, which a log at 10 Hz cannot check as it does; the deviation alone is used). The
  flight is cut where that run begins.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from quadcosim.flightlogs.model import FlightLog

STALL_S = 1.0  # s without an IMU sample: logging stalled (an IMU logs at 10 Hz or more)
MIN_STRETCH = 10  # samples on each side of a gap for it to be a stall
CRASH_ANGLE_DEG = 30.0  # Copter::crash_check: CRASH_CHECK_ANGLE_DEVIATION_DEG
CRASH_TRIGGER_S = 2.0  # Copter::crash_check: CRASH_CHECK_TRIGGER_SEC
#: The per-sample arrays of each kind of series, beside its ``time``.
PER_SAMPLE = {"Compass": ("field", "raw"), "Imu": ("gyro", "acc"), "Motors": ("commands", "pwm"),
              "Battery": ("voltage", "current"), "Attitude": ("q",), "Throttle": ("value",)}


def _tilt_error_deg(roll, pitch, desired_roll, desired_pitch) -> np.ndarray:
    """Angle (deg) between the body z axes of the attitude and its target (roll and pitch in deg)."""
    def down(r, p):
        r, p = np.radians(r), np.radians(p)
        return np.column_stack([-np.sin(p), np.sin(r) * np.cos(p), np.cos(r) * np.cos(p)])

    cosine = np.sum(down(roll, pitch) * down(desired_roll, desired_pitch), axis=1)
    return np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))


def crash_time(att_rows: list[dict]) -> float | None:
    """The time (s, the log's clock) a crash begins in ArduPilot's ``ATT`` rows (dicts with
    ``TimeUS`` or ``TimeMS``, ``Roll``, ``Pitch``, ``DesRoll``, ``DesPitch`` in deg): the start of the
    first run of :data:`CRASH_TRIGGER_S` or longer in which the attitude stays more than
    :data:`CRASH_ANGLE_DEG` from its target; None when there is none."""
    if not att_rows or "DesRoll" not in att_rows[0]:
        return None
    key, unit = ("TimeUS", 1e-6) if "TimeUS" in att_rows[0] else ("TimeMS", 1e-3)
    values = np.array([[r[key], r["Roll"], r["Pitch"], r["DesRoll"], r["DesPitch"]] for r in att_rows], dtype=float)
    time = values[:, 0] * unit
    off = _tilt_error_deg(*values[:, 1:].T) > CRASH_ANGLE_DEG
    start = None
    for k, flag in enumerate(off):
        if flag and start is None:
            start = k
        if start is not None and (not flag or k == len(off) - 1):
            end = k if flag else k - 1
            if time[end] - time[start] >= CRASH_TRIGGER_S:
                return float(time[start])
            start = None
    return None


def _series(log: FlightLog) -> list:
    return [*log.compasses, *log.imus, *(s for s in (log.motors, log.battery, log.attitude, log.throttle) if s)]


def _restricted(series, lo: float, hi: float):
    """``series`` (any of the log's, with ``time`` and per-sample arrays) restricted to ``lo <= t < hi``."""
    keep = (series.time >= lo) & (series.time < hi)
    if keep.all():
        return series
    names = ["time", *(n for n in PER_SAMPLE[type(series).__name__] if getattr(series, n) is not None)]
    return replace(series, **{name: np.asarray(getattr(series, name))[keep] for name in names})


def cut(log: FlightLog, lo: float, hi: float, why: str) -> FlightLog:
    """``log`` with every series restricted to ``lo <= t < hi`` (s, the log's clock), ``why`` added to
    its warnings."""
    single = {name: None if getattr(log, name) is None else _restricted(getattr(log, name), lo, hi)
              for name in ("motors", "battery", "attitude", "throttle")}
    return replace(log, compasses=[_restricted(c, lo, hi) for c in log.compasses],
                   imus=[_restricted(i, lo, hi) for i in log.imus], **single, warnings=[*log.warnings, why])


def stalls(log: FlightLog) -> list[tuple[float, float]]:
    """The logging stalls of ``log``: (last sample before, first after) (s) of each stretch of
    :data:`STALL_S` or more without a sample of its first IMU (of its first compass without IMU)."""
    series = log.imus[0] if log.imus else log.compasses[0] if log.compasses else None
    if series is None or len(series.time) < 2:
        return []
    time = np.asarray(series.time, dtype=float)
    time = np.sort(time[np.isfinite(time)])  # a damaged stamp (checked later) makes a gap at an end, not a split
    if len(time) < 2:
        return []
    gaps = [k for k in np.flatnonzero(np.diff(time) >= STALL_S)
            if k + 1 >= MIN_STRETCH and len(time) - k - 1 >= MIN_STRETCH]  # a lone damaged stamp is no stall
    return [(float(time[k]), float(time[k + 1])) for k in gaps]


def trimmed(log: FlightLog, crash: float | None = None) -> FlightLog:
    """``log`` cut to its longest stretch between logging stalls, and cut again at ``crash`` (s, the
    log's clock; :func:`crash_time`) when it falls in that stretch; each cut said in the warnings."""
    found = stalls(log)
    if not found and crash is None:
        return log
    series = [s for s in _series(log) if len(s.time)]
    if not series:
        return log
    start, end = min(s.time[0] for s in series), max(s.time[-1] for s in series)
    edges = [start, *(x for gap in found for x in gap), end]
    stretches = [(edges[2 * k], edges[2 * k + 1]) for k in range(len(found) + 1)]
    lo, hi = max(stretches, key=lambda s: s[1] - s[0])
    notes = []
    if found:
        named = "; ".join(f"{b - a:.1f} s from {a:.1f} s" for a, b in found)
        notes.append(f"logging stalls ({named}): the longest stretch between stalls is kept, {lo:.1f} to {hi:.1f} s "
                     f"({hi - lo:.1f} s of the {end - start:.1f} s logged)")
    upper = np.nextafter(hi, np.inf)
    if crash is not None and lo <= crash <= hi:
        notes.append(f"the flight ends in a crash: the attitude stays more than {CRASH_ANGLE_DEG:g} deg from its "
                     f"target for {CRASH_TRIGGER_S:g} s or more from {crash:.1f} s (ArduCopter's crash check): cut "
                     f"there, {hi - crash:.1f} s removed")
        upper = crash
    if not notes:
        return log
    return cut(log, lo, upper, "; ".join(notes))
