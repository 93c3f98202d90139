"""Real flight logs: PX4 ULog (pyulog) and ArduPilot DataFlash, binary and text (pymavlink).

:func:`read_log` turns a log into a :class:`FlightLog` in the project's conventions: NED
inertial frame, FRD body frame, SI units (T, rad/s, m/s^2, A, V, s), every compass and IMU
instance with its own time stamps, motor outputs normalised to 0..1 from the log's own PWM
limits, the battery, the autopilot's attitude, the parameters, firmware, vehicle type and
whether it is a simulator log. Each compass carries the field as logged and the raw field
before the autopilot's offsets and motor compensation, which is what a calibration starts
from (:mod:`orchestrator.logs.dataflash` and :mod:`orchestrator.logs.ulog` say how each
autopilot logs it). This is the one reading layer: the command line, the estimators' replay and
the calibration all read logs through it.
"""

from __future__ import annotations

from pathlib import Path

from orchestrator.logs.model import (
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

ULOG_MAGIC = b"ULog\x01\x12\x35"
DATAFLASH_HEAD = b"\xa3\x95"
FORMATS = "PX4 ULog (.ulg), ArduPilot DataFlash binary (.bin) or text (.log)"


def detect_format(path) -> str:
    """``ulog``, ``dataflash-binary`` or ``dataflash-text`` from the first bytes of the file at
    ``path`` (not its name); a :class:`LogError` naming the file otherwise."""
    path = Path(path)
    try:
        with open(path, "rb") as file:
            head = file.read(64)
    except OSError as error:
        raise LogError(f"{path}: cannot read the log ({error.strerror})") from None
    if not head:
        raise LogError(f"{path}: the file is empty; copy the log again from the vehicle")
    if head.startswith(ULOG_MAGIC):
        return "ulog"
    if head.startswith(DATAFLASH_HEAD):
        return "dataflash-binary"
    if head.lstrip().startswith(b"FMT,"):
        return "dataflash-text"
    raise LogError(f"{path}: unknown log format (it starts with {head[:8]!r}); quadcosim reads {FORMATS}")


def read_log(path) -> FlightLog:
    """Read the flight log at ``path`` (format detected from its content).

    Raises
    ------
    LogError
        Unknown format, unreadable, empty, corrupt beyond use or truncated before its data; the
        message names the file and the fix. Corruption read past is listed in
        ``FlightLog.warnings``.
    """
    path = Path(path)
    kind = detect_format(path)
    if kind == "ulog":
        from orchestrator.logs.ulog import read_ulog

        return read_ulog(path)
    from orchestrator.logs.dataflash import read_dataflash

    return read_dataflash(path, text=kind == "dataflash-text")


__all__ = ["Attitude", "Battery", "Compass", "FlightLog", "Imu", "LogError", "Motors", "Position", "Throttle",
           "detect_format", "rate", "read_log"]
