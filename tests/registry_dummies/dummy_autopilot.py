"""A dummy autopilot, added as a maintainer adds one: this file and one registry line
(``Dummy = "dummy_autopilot:AUTOPILOT"`` in the group ``quadcosim.autopilots``).

Its logs are a text format of its own, one record a line, ``KIND,values...``, after the line
:data:`MAGIC`: ``firmware``, ``param`` (name, value), ``gps`` (latitude, longitude (deg), altitude (m),
decimal year), ``mag`` (time (s), the raw field before any correction, body frame, uT), ``imu`` (time,
gyro (rad/s), specific force (m/s^2)), ``att`` (time, quaternion body to NED, scalar first), ``mot``
(time, motor commands 0..1) and ``bat`` (time, voltage (V), current (A)). Its firmware corrects the
compass as ``field = raw - OFS - ON MOT i`` (``DUMMY_OFS_*`` and ``DUMMY_MOT_*`` in uT and uT/A,
``DUMMY_MOT_ON`` 0 or 1, ``i`` the battery current): no soft iron, one motor compensation. Its
parameter file ``dummy.cfg`` holds ``NAME = VALUE`` lines, which ``quadcosim calibrate --score`` reads
by its ``parameter_line``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from quadcosim.flightlogs.autopilots import Autopilot, LogFormat
from quadcosim.flightlogs.model import Attitude, Battery, Compass, FlightLog, Imu, LogError, Motors, Position

MAGIC = "# dummy-autopilot log 1"
MICRO = 1e-6  # T per uT
AXES = "XYZ"
COLUMNS = {"mag": 4, "imu": 7, "att": 5, "bat": 3}


def _field(params: dict, raw, current) -> np.ndarray:
    """The field (T, 3) (T) the dummy firmware reports from ``raw`` (T, 3) (T) and ``current`` (T,) (A or None)."""
    offsets = np.array([float(params.get(f"DUMMY_OFS_{a}", 0.0)) for a in AXES]) * MICRO
    field = np.asarray(raw) - offsets
    if int(params.get("DUMMY_MOT_ON", 0)) and current is not None:
        field = field - np.outer(current, [float(params.get(f"DUMMY_MOT_{a}", 0.0)) * MICRO for a in AXES])
    return field


def read(path) -> FlightLog:
    """The dummy log at ``path`` as a :class:`quadcosim.flightlogs.FlightLog`."""
    rows: dict[str, list] = {}
    params, firmware, position = {}, "Dummy (version not logged)", None
    for number, line in enumerate(Path(path).read_text().splitlines()[1:], 2):
        kind, _, rest = line.partition(",")
        if kind == "firmware":
            firmware = rest
        elif kind == "param":
            name, value = rest.split(",")
            params[name] = float(value)
        elif kind == "gps":
            lat, lon, alt, year = (float(v) for v in rest.split(","))
            position = Position(lat, lon, alt, year, "gps")
        elif kind in ("mag", "imu", "att", "mot", "bat"):
            rows.setdefault(kind, []).append([float(v) for v in rest.split(",")])
        elif line.strip():
            raise LogError(f"{path}, line {number}: {kind!r} is no record of a dummy log; fix or remove the line")
    if "mag" not in rows and "imu" not in rows:
        raise LogError(f"{path}: no sensor records (mag, imu); the dummy log is empty")
    table = {kind: np.array(values) for kind, values in rows.items()}
    compasses = []
    if "mag" in table:
        raw = table["mag"][:, 1:4] * MICRO
        current = np.interp(table["mag"][:, 0], table["bat"][:, 0], table["bat"][:, 2]) if "bat" in table else None
        offsets = np.array([params.get(f"DUMMY_OFS_{a}", 0.0) for a in AXES]) * MICRO
        compasses.append(Compass("mag", table["mag"][:, 0], _field(params, raw, current), raw, offsets,
                                 raw_source="logged raw (mag)", slot=0))
    imus = [Imu("imu", table["imu"][:, 0], table["imu"][:, 1:4], table["imu"][:, 4:7])] if "imu" in table else []
    motors = battery = attitude = None
    if "mot" in table:
        commands = table["mot"][:, 1:]
        motors = Motors(table["mot"][:, 0], commands, 1000.0 + 1000.0 * commands, 1000.0, 2000.0, "fixed")
    if "bat" in table:
        battery = Battery(table["bat"][:, 0], table["bat"][:, 1], table["bat"][:, 2], "bat records")
    if "att" in table:
        attitude = Attitude(table["att"][:, 0], table["att"][:, 1:5], "att")
    return FlightLog(str(path), "dummy-text", "Dummy", firmware, "quadrotor", False, compasses, imus, motors, battery,
                     attitude, params, [], position)


def write_log(log: FlightLog, path, parts=("mag", "imu", "att", "mot", "bat")) -> None:
    """``log`` (any autopilot's :class:`quadcosim.flightlogs.FlightLog`: its first compass, IMU, attitude,
    motors, battery and GPS fix) as the dummy would have logged the same flight, at ``path``; the
    dummy's offsets are the log's, its motor compensation off. ``parts``: the records written."""
    compass = log.compasses[0]
    lines = [MAGIC, "firmware,Dummy 1.0"]
    lines += [f"param,DUMMY_OFS_{a},{compass.offsets[i] / MICRO:.9g}" for i, a in enumerate(AXES)]
    lines.append("param,DUMMY_MOT_ON,0")
    if log.position is not None:
        p = log.position
        lines.append(f"gps,{p.latitude_deg:.9g},{p.longitude_deg:.9g},{p.altitude_m:.9g},{p.year:.9g}")
    series = {"mag": (compass.time, compass.raw / MICRO), "imu": (log.imus[0].time, log.imus[0].gyro, log.imus[0].acc),
              "att": (log.attitude.time, log.attitude.q), "mot": (log.motors.time, log.motors.commands),
              "bat": (log.battery.time, log.battery.voltage, log.battery.current)}
    for kind in parts:
        time, *values = series[kind]
        block = np.column_stack([time, *values])
        lines += [kind + "," + ",".join(f"{v:.9g}" for v in row) for row in block]
    Path(path).write_text("\n".join(lines) + "\n")


def write(params: dict, path) -> None:
    """``params`` as the dummy's parameter file: ``NAME = VALUE`` lines."""
    Path(path).write_text("".join(f"{name} = {value:.9g}\n" for name, value in params.items()))


def _apply(part, params, inputs, rule):
    return _field(params, part.raw, inputs["current"])


def _parameters(part, candidate, rule):
    params = {f"DUMMY_OFS_{a}": float(candidate.offset[i] / MICRO) for i, a in enumerate(AXES)}
    K = np.zeros(3) if candidate.model != "current" else np.asarray(candidate.K, dtype=float).reshape(3)
    params |= {f"DUMMY_MOT_{a}": float(K[i] / MICRO) for i, a in enumerate(AXES)}
    params["DUMMY_MOT_ON"] = int(candidate.model == "current")
    return params


def _motor_inputs(model, inputs):
    return None if model != "current" or inputs["current"] is None else inputs["current"][:, None]


AUTOPILOT = Autopilot(
    name="Dummy",
    formats=(LogFormat("dummy-text", "dummy autopilot text (.dummy)",
                       lambda head: head.startswith(MAGIC.encode()), read),),
    messages={"compass": "mag records", "imu": "imu records", "attitude": "att records", "motors": "mot records",
              "battery": "bat records"},
    logging="DUMMY_LOG_RECORDS",
    faster_compass="log mag records faster (DUMMY_LOG_RECORDS) and fly again",
    file="dummy.cfg", write=write, apply=_apply, parameters=_parameters, motor_models=lambda part, rule: ("current",),
    motor_inputs=_motor_inputs, scale_reset=lambda part, rule: {}, firmware=lambda part, rule: part.log.firmware,
    motor_off={"DUMMY_MOT_ON": 0}, is_motor_key=lambda name: name.startswith("DUMMY_MOT"),
    fused_compass=lambda params: 0, parameter_line=lambda line: tuple(part.strip() for part in line.split("=")))
