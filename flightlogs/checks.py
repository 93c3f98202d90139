"""The checks every log read goes through, whatever its format: time stamps and values.

A log is read as it was written, and a copy may be damaged: a bit flipped in a time stamp, a
value logged as NaN, two logs joined in one file, a sensor whose clock was shifted. Every
sensor series (compass, IMU, motors, battery, attitude) is checked here, the same way for
PX4 and ArduPilot:

- samples with a non-finite time or value are dropped, counted in a warning;
- time stamps must not go back: a few samples out of order (a damaged stamp) are dropped,
  counted in a warning; a clock that goes back for good (two logs joined, an autopilot that
  restarted while logging) is refused, naming the series and where its clock went back;
- a time stamp repeated (a sample logged twice) keeps its first sample;
- a series left with no sample is read as absent, said in a warning;
- a gap in a series (no sample for :data:`GAP_PERIODS` of its periods, and at least
  :data:`GAP_MIN_S`) is said in a warning: two flights joined, or a logging stall;
- the span of time all the series share is what a replay or a calibration can use
  (:meth:`quadcosim.flightlogs.FlightLog.overlap`); a series that shares no time with the
  others, and a shared span shorter than :data:`SHARED_SHARE` of the log, are said in a warning.
"""

from __future__ import annotations

import bisect
from dataclasses import replace

import numpy as np
from quadcosim.flightlogs.model import FlightLog, LogError

#: Share of a series' samples that may be out of order and dropped as damaged stamps; more is
#: a clock that goes back for good (two logs joined), refused.
MAX_OUT_OF_ORDER = 0.05
#: A gap in a series this many of its median periods long, and at least GAP_MIN_S, is warned about.
GAP_PERIODS = 100
GAP_MIN_S = 2.0  # s
#: A span shared by every series shorter than this share of the log's duration is warned about.
SHARED_SHARE = 0.9


#: The per-sample arrays of each kind of series (beside its ``time``).
PER_SAMPLE = {"Compass": ("field", "raw"), "Imu": ("gyro", "acc"), "Motors": ("commands", "pwm"),
              "Battery": ("voltage", "current"), "Attitude": ("q",)}


def _arrays(series) -> list[str]:
    """The per-sample arrays a series holds (None for a battery without current is left out)."""
    return [name for name in PER_SAMPLE[type(series).__name__] if getattr(series, name) is not None]


def _checked_names(series) -> list[str]:
    """The arrays whose values must be finite."""
    names = _arrays(series)
    if getattr(series, "unusable", ""):
        names = [n for n in names if n != "raw"]  # NaN by construction
    return [n for n in names if n != "pwm"]  # PX4 logs NaN for the outputs it does not drive


def _longest_in_order(time: np.ndarray) -> np.ndarray:
    """Indices of the longest run of samples whose times never go back (not necessarily
    consecutive), in O(n log n)."""
    tails: list[float] = []
    tail_index: list[int] = []
    previous = np.full(len(time), -1)
    for i, t in enumerate(time):
        k = bisect.bisect_right(tails, t)
        if k == len(tails):
            tails.append(t)
            tail_index.append(i)
        else:
            tails[k], tail_index[k] = t, i
        previous[i] = tail_index[k - 1] if k else -1
    kept, i = [], tail_index[-1] if tail_index else -1
    while i >= 0:
        kept.append(i)
        i = previous[i]
    return np.array(kept[::-1], dtype=int)


def _kept(name: str, series, path: str, notes: dict) -> np.ndarray:
    """Indices of the samples of ``series`` kept; what was dropped is counted in ``notes``."""
    time = np.asarray(series.time, dtype=float)
    finite = np.isfinite(time)
    for array in _checked_names(series):
        values = np.asarray(getattr(series, array), dtype=float)
        finite &= np.isfinite(values.reshape(len(values), -1)).all(axis=1)
    if hasattr(series, "q"):
        norm = np.linalg.norm(np.asarray(series.q, dtype=float), axis=1)
        finite &= np.abs(norm - 1.0) < 0.1  # a damaged quaternion, not a rotation
    index = np.flatnonzero(finite)
    if len(index) < len(time):
        notes.setdefault("non-finite", []).append(f"{name} {len(time) - len(index)}")
    t = time[index]
    if len(t) > 1 and np.any(np.diff(t) < 0):
        order = _longest_in_order(t)
        dropped = len(t) - len(order)
        if dropped > MAX_OUT_OF_ORDER * len(t):
            back = int(np.flatnonzero(np.diff(t) < 0)[0])
            raise LogError(f"{path}: the clock of {name} goes back ({_times(int(np.sum(np.diff(t) < 0)))}; first from "
                           f"{t[back]:.3f} s to {t[back + 1]:.3f} s): two logs joined in one file, or an autopilot "
                           "that restarted while logging. Split the file where the clock restarts and give each "
                           "flight apart")
        notes.setdefault("out of order", []).append(f"{name} {dropped}")
        index, t = index[order], t[order]
    if len(t) > 1:
        repeated = np.concatenate([[False], np.diff(t) == 0])
        if repeated.any():
            notes.setdefault("repeated time stamp", []).append(f"{name} {int(repeated.sum())}")
            index = index[~repeated]
    return index


def _part(series, index: np.ndarray):
    if len(index) == len(series.time):
        return series
    changes = {name: np.asarray(getattr(series, name))[index] for name in ["time", *_arrays(series)]}
    return replace(series, **changes)


def validated(log: FlightLog) -> FlightLog:
    """``log`` with every series checked (see the module docstring); its warnings say what
    was dropped and which series share no time with the others.

    Parameters
    ----------
    log : FlightLog
        As a reader made it.

    Returns
    -------
    FlightLog
        The same log (its series replaced where samples were dropped).

    Raises
    ------
    LogError
        A clock that goes back for good, naming the series and where.
    """
    notes: dict[str, list[str]] = {}
    empty = []
    compasses, imus = [], []
    for kind, found, kept in (("compass", log.compasses, compasses), ("IMU", log.imus, imus)):
        for series in found:
            part = _part(series, _kept(series.name, series, log.path, notes))
            (kept.append(part) if len(part.time) else empty.append(f"{kind} {series.name}"))
    single = {}
    for attribute, name in (("motors", "motors"), ("battery", "battery"), ("attitude", "attitude")):
        series = getattr(log, attribute)
        if series is None:
            single[attribute] = None
            continue
        part = _part(series, _kept(name, series, log.path, notes))
        single[attribute] = part if len(part.time) else None
        if not len(part.time):
            empty.append(name)
    checked = replace(log, compasses=compasses, imus=imus, **single, warnings=list(log.warnings))
    for what, counts in notes.items():
        checked.warnings.append(f"samples dropped ({what}): {', '.join(counts)}")
    if empty:
        checked.warnings.append(f"no valid sample, read as absent: {', '.join(empty)}")
    for compass in compasses:
        if compass.unusable:
            checked.warnings.append(f"compass {compass.name}: {compass.unusable}")
    outside = _apart(checked)
    if outside:
        checked.warnings.append(outside)
    else:
        checked.warnings += _short_span(checked)
    checked.warnings += _gaps(checked)
    return checked


def _gaps(log: FlightLog) -> list[str]:
    """One warning naming the series with a gap in their samples (see the module docstring), and
    each one's longest gap."""
    found = []
    for name, series in _series(log):
        time = np.asarray(series.time)
        if len(time) < 3:
            continue
        steps = np.diff(time)
        gaps = np.flatnonzero(steps > max(GAP_MIN_S, GAP_PERIODS * float(np.median(steps))))
        if len(gaps):
            k = gaps[np.argmax(steps[gaps])]
            count = f", {len(gaps)} gaps" if len(gaps) > 1 else ""
            found.append(f"{name} {steps[k]:.1f} s from {time[k]:.1f} s{count}")
    if not found:
        return []
    return [f"samples stop for a while (two flights in one file, or logging that stalled): {'; '.join(found)}"]


def _short_span(log: FlightLog) -> list[str]:
    """A warning when the span every series covers is a small part of the log."""
    span, named = common_span(log), _series(log)
    if span is None or not named or log.duration <= 0:
        return []
    shared = span[1] - span[0]
    if shared >= SHARED_SHARE * log.duration:
        return []
    late = max(named, key=lambda item: item[1].time[0])
    early = min(named, key=lambda item: item[1].time[-1])
    return [f"its sensors share {shared:.1f} s of the {log.duration:.1f} s logged ({span[0]:.1f} to {span[1]:.1f} s; "
            f"{late[0]} starts at {late[1].time[0]:.1f} s, {early[0]} ends at {early[1].time[-1]:.1f} s): a replay or "
            "a calibration uses that span alone"]


def _series(log: FlightLog) -> list[tuple[str, object]]:
    named = [(c.name, c) for c in log.compasses] + [(i.name, i) for i in log.imus]
    named += [(name, getattr(log, name)) for name in ("motors", "battery", "attitude") if getattr(log, name)]
    return [(name, s) for name, s in named if len(s.time)]


def common_span(log: FlightLog) -> tuple[float, float] | None:
    """The span of time (s) every series of ``log`` covers, or None when they share none."""
    named = _series(log)
    if not named:
        return None
    lo, hi = max(s.time[0] for _, s in named), min(s.time[-1] for _, s in named)
    return (float(lo), float(hi)) if hi > lo else None


def _apart(log: FlightLog) -> str | None:
    """A warning naming the series that share no time with the others, or None."""
    named = _series(log)
    if len(named) < 2 or common_span(log) is not None:
        return None
    spans = ", ".join(f"{name} {s.time[0]:.1f} to {s.time[-1]:.1f} s" for name, s in named)
    return (f"its sensors share no span of time ({spans}): their time stamps do not match; a replay or a "
            "calibration needs them recorded together")


def _times(count: int) -> str:
    return "once" if count == 1 else f"{count} times"
