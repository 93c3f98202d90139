"""Real flight logs, of every installed autopilot (:mod:`quadcosim.flightlogs.autopilots`): PX4 ULog
(pyulog) and ArduPilot DataFlash, binary and text (pymavlink), and any other registered.

:func:`read_log` turns a log into a :class:`FlightLog` in the project's conventions: NED
inertial frame, FRD body frame, SI units (T, rad/s, m/s^2, A, V, s), every compass and IMU
instance with its own time stamps, motor outputs normalised to 0..1 from the log's own PWM
limits, the battery, the autopilot's attitude, the parameters, firmware, vehicle type and
whether it is a simulator log. Each compass carries the field as logged and the raw field
before the autopilot's offsets and motor compensation, which is what a calibration starts
from (each autopilot's reader says how it logs it, :mod:`quadcosim.flightlogs.autopilots`).
The format is told by the file's first bytes, by the detection of each registered autopilot's
formats. This is the one reading layer: the command line, the estimators' replay and the
calibration all read logs through it.
"""

from __future__ import annotations

from pathlib import Path

from quadcosim.flightlogs.model import (
    Attitude,
    Battery,
    Compass,
    FlightLog,
    Imu,
    LogError,
    Motors,
    Position,
    Throttle,
    rate,
)

#: The largest log read (bytes). The readers take about a second per megabyte of DataFlash (a
#: gigabyte is hours); the longest flights log a few hundred megabytes.
MAX_LOG_BYTES = 1_000_000_000
#: A log this large (bytes) or larger whose blocks on the disk hold less than half its length
#: is a sparse file, not a log written by a vehicle.
SPARSE_MIN_BYTES = 16_000_000


def check_file(path) -> int:
    """Refuse, before any reader opens it, a path that is not a log a reader can finish.

    A FIFO, a device, a socket or a folder (a reader would block on it, or read forever), a
    file larger than :data:`MAX_LOG_BYTES`, and a sparse file (mostly holes: a copy cut
    short, or a file made with ``truncate``) are refused.

    Parameters
    ----------
    path : str or pathlib.Path
        The log.

    Returns
    -------
    int
        The file's size (bytes).

    Raises
    ------
    LogError
        Naming the file, what it is and the fix.
    """
    from quadcosim.flightlogs.autopilots import known_formats

    from quadcosim.infra.inputs import regular_file

    path = Path(path)
    status = regular_file(path, "the log", f"give a log file ({known_formats()}); copy a log streamed elsewhere "
                          "to a file first", LogError)
    size = status.st_size
    if size > MAX_LOG_BYTES:
        raise LogError(f"{path}: {size / 1e9:.1f} GB, more than the {MAX_LOG_BYTES / 1e9:.0f} GB quadcosim reads "
                       "(a long flight logs a few hundred MB; reading this one would take hours); cut the log to "
                       "the flight you need")
    stored = getattr(status, "st_blocks", None)
    if stored is not None and size >= SPARSE_MIN_BYTES and stored * 512 < size // 2:
        raise LogError(f"{path}: a sparse file ({size / 1e6:.0f} MB long, {stored * 512 / 1e6:.1f} MB stored): its "
                       "holes read as zeros, not a log a vehicle wrote (a copy cut short?); copy the log again")
    return size


def detect_format(path) -> str:
    """The name of the log format of the file at ``path`` (``ulog``, ``dataflash-binary``,
    ``dataflash-text`` or another installed autopilot's) from its first bytes (not its name), checked
    first by :func:`check_file`; a :class:`LogError` naming the file and the formats known otherwise."""
    return _detected(path)[1].name


def _detected(path):
    """The autopilot and log format (:class:`quadcosim.flightlogs.autopilots.LogFormat`) whose detection
    claims the file at ``path``."""
    from quadcosim.flightlogs.autopilots import HEAD_BYTES, known_formats, recognised

    path = Path(path)
    check_file(path)
    try:
        with open(path, "rb") as file:
            head = file.read(HEAD_BYTES)
    except OSError as error:
        raise LogError(f"{path}: cannot read the log ({error.strerror})") from None
    if not head:
        raise LogError(f"{path}: the file is empty; copy the log again from the vehicle")
    found = recognised(head)
    if found is None:
        raise LogError(f"{path}: unknown log format (it starts with {head[:8]!r}): no installed autopilot recognises "
                       f"it; quadcosim reads {known_formats()}")
    return found


def read_log(path) -> FlightLog:
    """Read the flight log at ``path`` (format detected from its content).

    The file is checked before a reader opens it (:func:`check_file`); what the readers print
    while they read is summarised in one warning (:mod:`quadcosim.flightlogs.noise`); every
    sensor's time stamps are checked, and the span the sensors share reported
    (:func:`quadcosim.flightlogs.checks.validated`).

    Raises
    ------
    LogError
        Unknown format, unreadable, empty, corrupt beyond use or truncated before its data, not
        a regular file, too large, sparse, or a clock that restarts (two logs joined); the
        message names the file and the fix. Corruption read past is listed in
        ``FlightLog.warnings``.
    KeyboardInterrupt
        A signal stopped the reading (never reported as a corrupt log).
    """
    from quadcosim.flightlogs.checks import validated

    path = Path(path)
    _, found = _detected(path)
    return validated(found.read(path))


__all__ = ["Attitude", "Battery", "Compass", "FlightLog", "Imu", "LogError", "Motors", "Position", "Throttle",
           "check_file", "detect_format", "rate", "read_log"]
