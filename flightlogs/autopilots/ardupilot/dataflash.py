"""ArduPilot DataFlash logs, binary (``.bin``) and text (``.log``), read with pymavlink's
``DFReader_binary`` and ``DFReader_text``.

What ArduPilot logs, and how it is turned into the project's conventions:

- ``MAG``, ``MAG2``, ``MAG3`` (up to Copter 3.6), or one ``MAG`` with an instance column ``I``
  (4.0 and later): the field in the body frame, in milligauss, *after* the compass's corrections,
  with the offsets ``Ofs`` (``COMPASS_OFS*``) and the motor compensation ``MOfs`` (``MOX..MOZ`` from
  4.0) logged beside it. The raw field is recovered sample by sample in the order of the log's
  firmware version (:func:`quadcosim.flightlogs.autopilots.ardupilot.firmware.recover_raw`:
  ``M^-1 Mag - MOfs - Ofs`` up to Copter 3.5, ``M^-1 (Mag - MOfs) / COMPASS_SCALE - Ofs`` later). A
  4.x instance ``I`` is the compass's priority; its parameters are those of the slot whose ``COMPASS_DEV_IDn`` is
  ``COMPASS_PRIO{I+1}_ID`` (:func:`quadcosim.flightlogs.autopilots.ardupilot.firmware.slot_of`).
- ``PARM``: the parameters (pymavlink's), and from 4.x the firmware's default of each (``Default``).
- ``GPS`` (the first receiver, ``I = 0`` in 4.x logs): the position and date the Earth field model is
  evaluated at (3D fixes only).
- ``ATT``'s ``DesRoll``/``DesPitch`` against ``Roll``/``Pitch``: a crash at the end of a flight
  (:func:`quadcosim.flightlogs.trim.crash_time`), which is cut off with the logging stalls
  (:mod:`quadcosim.flightlogs.trim`).
- ``CTUN.ThO`` (``ThrOut`` in 0..1000 in older firmware): ``motors->get_throttle()``, the throttle
  ``COMPASS_MOTCT = 1`` multiplies.
- ``IMU``, ``IMU2``, ``IMU3`` (or ``IMU`` with ``I``): rad/s and m/s^2, body frame.
- ``BAT`` with ``Instance`` (4.x) or ``Inst``: the first battery monitor.
- ``ATT``: roll, pitch, yaw (degrees, Z-Y-X), the attitude the vehicle flew on.
- ``RCOU``: PWM (us) per output; motors are normalised with ``MOT_PWM_MIN``/``MOT_PWM_MAX``,
  or, when those are 0 or absent (Copter 3.4 and earlier), the throttle channel's
  ``RC3_MIN``/``RC3_MAX``.
- ``BAT`` (float V, A) or the older ``CURR`` (whose integer ``Volt`` and ``Curr`` are in
  hundredths of a volt and an ampere).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from quadcosim.flightlogs import trim
from quadcosim.flightlogs.autopilots.ardupilot import firmware as ardupilot
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
    synthetic_statement,
)

MILLIGAUSS = 1e-7  # T
CENTI = 0.01
WANTED = {"MAG", "MAG2", "MAG3", "IMU", "IMU2", "IMU3", "ATT", "RCOU", "CURR", "BAT", "MSG", "GPS", "CTUN", "PARM"}
SENSORS = {"MAG", "MAG2", "MAG3", "IMU", "IMU2", "IMU3", "ATT", "RCOU", "CURR", "BAT"}
GPS_3D_FIX = 3
GPS_EPOCH = "1980-01-06"  # GPS week 0
SECONDS_PER_WEEK = 604800.0
INTEGER_FORMATS = "bBhHiI"
# motors per frame: Copter's FRAME_CLASS, and the "Frame: NAME" message of older firmware
FRAME_CLASS_MOTORS = {1: 4, 2: 6, 3: 8, 4: 8, 5: 6, 7: 3, 12: 4, 14: 4}
FRAME_NAME_MOTORS = {"QUAD": 4, "HEXA": 6, "OCTA": 8, "OCTA_QUAD": 8, "Y6": 6, "TRI": 3}
VOLTAGE_ONLY_MONITOR = 3
MOTOR1_FUNCTION = 33  # SRV_Channel::k_motor1: SERVOn_FUNCTION of motor 1, 34 of motor 2, ...
MIN_CURRENT_A = 0.2  # a current sensor that never reads more than this is not wired
SINGULAR_CONDITION = 1e12  # a soft-iron matrix this ill-conditioned cannot be undone
ZERO_TAIL_BYTES = 528  # zeros past this at a binary log's end are named (pymavlink reads past fewer)


def _reader(path: Path, text: bool):
    from pymavlink import DFReader

    try:
        return DFReader.DFReader_text(str(path)) if text else DFReader.DFReader_binary(str(path))
    except Exception as error:  # pymavlink raises bare exceptions on a malformed header
        raise LogError(f"{path}: not a readable DataFlash log ({error}); check the file is a complete "
                       "ArduPilot .bin or .log") from None


def _collect(path: Path, text: bool):
    """Rows of the wanted messages (type -> list of dicts), the formats, the parameters, what
    pymavlink printed while it read (:class:`quadcosim.flightlogs.noise.Noise`) and the bytes the
    last message lacks."""
    from quadcosim.flightlogs.noise import captured

    from quadcosim.infra.interrupts import surfaced

    rows: dict[str, list] = {}
    with surfaced(), captured() as noise:
        reader = _reader(path, text)
        try:
            while (m := reader.recv_match(type=WANTED)) is not None:
                rows.setdefault(m.get_type(), []).append(m.to_dict())
        except Exception as error:
            raise LogError(f"{path}: the log is corrupt ({type(error).__name__}: {error}); "
                           "download it again from the vehicle") from None
        finally:
            reader.close()
    formats = {f.name: f for f in reader.formats.values()}
    trailing = _cut_line(path) if text else _unfinished(reader)
    return rows, formats, dict(reader.params), noise, trailing


def _cut_line(path: Path) -> int:
    """Bytes of a text log's last line when it does not end with a newline (a copy cut short), else 0."""
    with open(path, "rb") as file:
        file.seek(0, 2)
        size = file.tell()
        file.seek(max(0, size - 4096))
        tail = file.read()
    return 0 if not tail or tail.endswith(b"\n") else len(tail) - (tail.rfind(b"\n") + 1)


def _zero_tail(path: Path) -> int:
    """Bytes of zeros that end the file at ``path`` (a log padded, or cut when power was lost)."""
    block = 1 << 16
    with open(path, "rb") as file:
        file.seek(0, 2)
        end = file.tell()
        zeros = 0
        while end > 0:
            start = max(0, end - block)
            file.seek(start)
            data = file.read(end - start)
            kept = data.rstrip(b"\0")
            zeros += len(data) - len(kept)
            if kept:
                break
            end = start
    return zeros


def _unfinished(reader) -> int:
    """Bytes the last message of a binary log lacks (0 when it is complete), from the reader's index."""
    last = max(((offsets[-1], mtype) for mtype, offsets in enumerate(reader.offsets) if offsets), default=None)
    if last is None or last[1] not in reader.formats:
        return 0
    return max(0, last[0] + reader.formats[last[1]].len - reader.data_len)


def _columns(rows: list[dict], names) -> np.ndarray:
    return np.array([[row[n] for n in names] for row in rows], dtype=float)


def _time(rows: list[dict]) -> np.ndarray:
    key = "TimeUS" if "TimeUS" in rows[0] else "TimeMS"
    return _columns(rows, [key])[:, 0] * (1e-6 if key == "TimeUS" else 1e-3)


def _instances(rows: dict, base: str, key: str = "I") -> list[tuple[str, list]]:
    """(name, rows) per instance: ``BASE``, ``BASE2``, ``BASE3``, or ``BASE`` split by ``key``."""
    found = []
    for name in (base, f"{base}2", f"{base}3"):
        group = rows.get(name, [])
        if group and key in group[0]:
            for instance in sorted({r[key] for r in group}):
                found.append((f"{name}[{instance}]", [r for r in group if r[key] == instance]))
        elif group:
            found.append((name, group))
    return found


def _compasses(rows: dict, params: dict, rule: ardupilot.Rules) -> list[Compass]:
    out = []
    for k, (name, group) in enumerate(_instances(rows, "MAG")):
        instanced = "I" in group[0]
        priority = int(group[0]["I"]) if instanced else None
        slot = ardupilot.slot_of(params, priority) if instanced else k
        motor = ["MOX", "MOY", "MOZ"] if "MOX" in group[0] else ["MOfsX", "MOfsY", "MOfsZ"]
        mag = _columns(group, ["MagX", "MagY", "MagZ"]) * MILLIGAUSS
        ofs = _columns(group, ["OfsX", "OfsY", "OfsZ"]) * MILLIGAUSS
        mofs = _columns(group, motor) * MILLIGAUSS
        matrix = ardupilot.soft_iron(params, slot)
        unusable = _singular(matrix, params, ardupilot.suffix(slot))
        if unusable:
            raw, inverse = np.full_like(mag, np.nan), np.full((3, 3), np.nan)
        else:
            raw, inverse = ardupilot.recover_raw(params, slot, rule, mag, ofs, mofs), np.linalg.inv(matrix)
        out.append(Compass(name, _time(group), mag, raw, -np.median(ofs, axis=0), ardupilot.external(params, slot),
                           f"logged field with the logged offsets, soft iron and motor offsets undone as {rule.name} "
                           "applies them", inverse, np.eye(3), slot, unusable,
                           ardupilot.setup(params, slot, priority, rule)))
    return out


def _defaults(rows: dict) -> dict:
    """The firmware's default of each parameter (``PARM.Default``, Copter 4.x), name: value."""
    return {r["Name"]: r["Default"] for r in rows.get("PARM", []) if "Default" in r}


def _singular(matrix: np.ndarray, params: dict, suffix: str) -> str:
    """Why the soft-iron ``matrix`` of compass ``suffix`` cannot be undone (empty when it can),
    naming the parameters it comes from."""
    if np.all(np.isfinite(matrix)) and np.linalg.cond(matrix) < SINGULAR_CONDITION:
        return ""
    named = ", ".join(f"{kind}{suffix}_{a} = {params.get(f'{kind}{suffix}_{a}', 0.0):g}"
                      for kind in ("COMPASS_DIA", "COMPASS_ODI") for a in "XYZ")
    return (f"its soft-iron matrix is singular ({named}): the field before the autopilot's corrections cannot "
            "be recovered from this log (a diagonal of 1 and off-diagonals of 0 are no correction)")


def _position(rows: dict) -> Position | None:
    """The median 3D fix of ``GPS`` and its date (GPS week and milliseconds of the week)."""
    import datetime

    group = [r for r in rows.get("GPS", []) if r.get("Status", 0) >= GPS_3D_FIX and r.get("GWk", 0) > 0
             and r.get("I", 0) == 0]  # the first receiver (4.x logs every one as GPS with an instance I)
    if not group:
        return None
    lat, lon, alt = np.median(_columns(group, ["Lat", "Lng", "Alt"]), axis=0)
    week, ms = group[0]["GWk"], group[0]["GMS"]
    try:
        when = datetime.datetime.fromisoformat(GPS_EPOCH) + datetime.timedelta(
            seconds=week * SECONDS_PER_WEEK + ms / 1e3)
    except (OverflowError, ValueError):  # a GPS week no receiver reports (a damaged message): no date, no position
        return None
    if not (np.isfinite([lat, lon, alt]).all() and abs(lat) <= 90 and abs(lon) <= 180 and when.year < 9999):
        return None
    start = datetime.datetime(when.year, 1, 1)
    year = when.year + (when - start).total_seconds() / (datetime.datetime(when.year + 1, 1, 1) - start).total_seconds()
    return Position(float(lat), float(lon), float(alt), float(year), "GPS (median of the 3D fixes)")


def _throttle(rows: dict) -> Throttle | None:
    group = rows.get("CTUN")
    column = next((c for c in ("ThO", "ThrOut") if group and c in group[0]), None)
    if column is None:
        return None
    value = _columns(group, [column])[:, 0]
    scaled = value.max() > 1.5  # older firmware logged it from 0 to 1000 and passed it divided by 1000
    return Throttle(_time(group), value / 1000.0 if scaled else value,
                    f"CTUN.{column}{' / 1000' if scaled else ''} (motors->get_throttle())")


def _imus(rows: dict) -> list[Imu]:
    return [Imu(name, _time(group), _columns(group, ["GyrX", "GyrY", "GyrZ"]),
                _columns(group, ["AccX", "AccY", "AccZ"])) for name, group in _instances(rows, "IMU")]


def _attitude(rows: dict) -> Attitude | None:
    group = rows.get("ATT")
    if not group:
        return None
    from scipy.spatial.transform import Rotation

    angles = np.radians(_columns(group, ["Yaw", "Pitch", "Roll"]))
    q = Rotation.from_euler("ZYX", angles).as_quat(scalar_first=True)
    return Attitude(_time(group), q * np.sign(q[:, :1] + 1e-300), "ATT")


def _motor_count(params: dict, messages: list[str]) -> int:
    if params.get("FRAME_CLASS") in FRAME_CLASS_MOTORS:
        return FRAME_CLASS_MOTORS[int(params["FRAME_CLASS"])]
    for text in messages:
        match = re.match(r"Frame: (\w+)", text)
        if match and match.group(1).upper() in FRAME_NAME_MOTORS:
            return FRAME_NAME_MOTORS[match.group(1).upper()]
    return 4


def _motor_channels(params: dict, n: int) -> list[int]:
    """The output channels (1-based) of motors 1 to ``n``: the channel whose ``SERVOn_FUNCTION`` is
    ``33 + k`` for motor ``k + 1`` (``SRV_Channel::k_motor1`` on, Copter 3.5 and later; the map
    ``Compass_PerMotor::scaled_output`` reads the motors through), else channels 1 to ``n``."""
    functions = {int(v): int(name[5:-9]) for name, v in params.items()
                 if re.fullmatch(r"SERVO\d+_FUNCTION", name)}
    mapped = [functions.get(MOTOR1_FUNCTION + k) for k in range(n)]
    return mapped if all(mapped) else list(range(1, n + 1))


def _motors(rows: dict, params: dict, messages: list[str], path: Path) -> Motors | None:
    group = rows.get("RCOU")
    if not group:
        return None
    n = _motor_count(params, messages)
    channels = _motor_channels(params, n)
    names = [f"C{k}" if f"C{k}" in group[0] else f"Ch{k}" for k in channels]
    missing = [name for name in names if name not in group[0]]
    if missing:
        raise LogError(f"{path}: the motors' outputs ({', '.join(missing)}, by SERVOn_FUNCTION) are not in RCOU; the "
                       "log holds " + ", ".join(c for c in group[0] if c.startswith("C")) + ": log every output "
                       "(RCOU) or fix SERVOn_FUNCTION")
    pwm = _columns(group, names)
    low, high = params.get("MOT_PWM_MIN", 0.0), params.get("MOT_PWM_MAX", 0.0)
    source = "MOT_PWM_MIN/MAX"
    if not (low > 0 and high > low):
        low, high, source = params.get("RC3_MIN", 0.0), params.get("RC3_MAX", 0.0), "RC3_MIN/MAX"
    if not (low > 0 and high > low):
        raise LogError(f"{path}: no PWM limits to normalise the motor outputs (MOT_PWM_MIN/MAX and RC3_MIN/MAX "
                       "are absent or 0); the log's parameters are incomplete: log them (LOG_BITMASK) or fix them")
    return Motors(_time(group), np.clip((pwm - low) / (high - low), 0.0, 1.0), pwm, float(low), float(high), source)


def _battery(rows: dict, formats: dict, params: dict) -> Battery | None:
    name = "BAT" if rows.get("BAT") else "CURR" if rows.get("CURR") else None
    if name is None:
        return None
    group = rows[name]
    if "Instance" in group[0] or "Inst" in group[0]:
        key = "Instance" if "Instance" in group[0] else "Inst"
        group = [r for r in group if r[key] == min(x[key] for x in group)]
    fmt = formats.get(name)
    scale = {}
    for column in ("Volt", "Curr"):
        char = fmt.format[fmt.columns.index(column)] if fmt is not None and column in fmt.columns else "f"
        scale[column] = CENTI if char in INTEGER_FORMATS else 1.0
    voltage = _columns(group, ["Volt"])[:, 0] * scale["Volt"]
    current = _columns(group, ["Curr"])[:, 0] * scale["Curr"]
    monitor = params.get("BATT_MONITOR")
    if monitor == VOLTAGE_ONLY_MONITOR:
        return Battery(_time(group), voltage, None, "none: BATT_MONITOR = 3 (voltage only)")
    if np.abs(current).max() < MIN_CURRENT_A:
        return Battery(_time(group), voltage, None,
                       f"none: the current never exceeds {MIN_CURRENT_A} A (BATT_MONITOR = {monitor}): not wired")
    return Battery(_time(group), voltage, current, f"{name}.Curr (BATT_MONITOR = {monitor})")


def read_dataflash(path: Path, text: bool) -> FlightLog:
    """Read an ArduPilot DataFlash log at ``path``: text form when ``text`` is true, else binary."""
    rows, formats, params, noise, trailing = _collect(path, text)
    if not rows or not any(rows.get(k) for k in SENSORS):
        raise LogError(f"{path}: no sensor messages could be read (MAG, IMU, ATT, RCOU, BAT); the file is empty, "
                       "truncated before its data or not a DataFlash log")
    messages = [r["Message"] for r in rows.get("MSG", [])]
    warnings = []
    said = noise.summary("pymavlink")
    if said:
        warnings.append(f"corrupt stretches skipped: {said}")
    zeros = 0 if text else _zero_tail(path)
    if zeros > ZERO_TAIL_BYTES:
        warnings.append(f"the last {zeros / 1e6:.3g} MB are zeros (a log padded, or cut when the vehicle lost power); "
                        "the data before them are read")
    if trailing > 0:
        warnings.append(f"truncated: the last line is cut ({trailing} bytes without their end of line)" if text
                        else f"truncated: the last message lacks {trailing} bytes")
    firmware = next((m for m in messages if re.match(r"(APM:|Ardu)\w+ V", m)), "ArduPilot (version not logged)")
    simulator = any(k.startswith("SIM_") for k in params) or any("SITL" in m for m in messages)
    kind = re.search(r"(?:APM:|Ardu)(\w+)", firmware)
    vehicle = kind.group(1) if kind else "unknown"
    frame = next((m for m in messages if m.startswith("Frame:")), None)
    if vehicle == "Copter":
        vehicle = {3: "tricopter", 4: "quadrotor", 6: "hexarotor", 8: "octorotor"}[_motor_count(params, messages)]
        vehicle += f" (Copter{', ' + frame if frame else ''})"
    version = ardupilot.parse_version(firmware)
    if version is None:
        warnings.append(f"firmware {firmware!r} names no Copter version: the compass corrections are read with "
                        f"the rules of Copter {ardupilot.DEFAULT_VERSION[0]}.{ardupilot.DEFAULT_VERSION[1]}")
    rule = ardupilot.rules(version or ardupilot.DEFAULT_VERSION)
    log = FlightLog(str(path), "dataflash-text" if text else "dataflash-binary", "ArduPilot", firmware, vehicle,
                    simulator, _compasses(rows, params, rule), _imus(rows), _motors(rows, params, messages, path),
                    _battery(rows, formats, params), _attitude(rows), params, warnings, _position(rows),
                    _throttle(rows), _defaults(rows))
    log.synthetic = synthetic_statement(messages)
    return trim.trimmed(log, trim.crash_time(rows.get("ATT", [])))
