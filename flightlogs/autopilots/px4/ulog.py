"""PX4 ULog files, read with pyulog.

How PX4's logged topics differ from ArduPilot's messages:

- ``sensor_mag`` (one topic instance per compass) is the field *before* calibration, in
  gauss, already rotated by the driver into the board frame; the calibrated field is
  ``vehicle_magnetometer`` (newer firmware) or ``sensor_combined.magnetometer_ga`` (older),
  ``(raw - CAL_MAGn_*OFF) * CAL_MAGn_*SCALE`` in the body frame. When only the calibrated field
  is logged, the raw one is recovered by undoing ``CAL_MAGn_*OFF`` and ``*SCALE``.
- No motor-compensation offsets are logged: PX4 adds ``CAL_MAGn_*COMP`` times the throttle or
  the current inside the calibration step, so the raw topic is the field before it.
- The calibration slot ``CAL_MAGn`` of a sensor is the one whose ``CAL_MAGn_ID`` is its
  ``device_id`` (:func:`quadcosim.flightlogs.autopilots.px4.firmware.slot`); the raw field stays in the
  sensor's frame and :attr:`Compass.rotation` carries ``CAL_MAGn_ROT`` or the board's rotation into the body frame.
- ``vehicle_gps_position``: the position and date of the Earth field model; the thrust setpoint's
  norm (``vehicle_thrust_setpoint``, or ``actuator_controls_0.control[3]`` in older logs) is the
  throttle ``CAL_MAG_COMP_TYP = 1`` multiplies.
- IMUs: ``sensor_accel`` and ``sensor_gyro`` per instance (newer), or ``sensor_combined``.
- Motors: ``actuator_motors`` (already 0..1, newer) or ``actuator_outputs`` in us, normalised
  output by output with ``PWM_MAIN_MINn``/``PWM_MAIN_MAXn`` (1.13 and later), ``PWM_MAIN_MIN``/``MAX``
  (1.11, 1.12) or ``PWM_MIN``/``PWM_MAX`` (1.9, 1.10), or PX4's defaults when none is logged
  (:func:`quadcosim.flightlogs.autopilots.px4.firmware.pwm_limits`).
- Battery: ``battery_status.voltage_v`` and ``current_a`` (negative when not measured).
- Attitude: ``vehicle_attitude.q``, scalar first, body FRD to NED: the project's convention.
- Time stamps are microseconds since boot.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from quadcosim.flightlogs.autopilots.px4 import firmware as px4
from quadcosim.flightlogs.model import Attitude, Battery, Compass, FlightLog, Imu, LogError, Motors, Position, Throttle

GAUSS = 1e-4  # T
MICRO = 1e-6
SINGULAR_CONDITION = 1e12  # a CAL_MAGn scale matrix this ill-conditioned cannot be undone
INVALID_RELATIVE = 2147483647  # sensor_combined: no new sample of this sensor
MAV_TYPE_MOTORS = {2: 4, 13: 6, 14: 8, 15: 3}
MAV_TYPE_NAMES = {1: "fixed wing", 2: "quadrotor", 13: "hexarotor", 14: "octorotor", 15: "tricopter",
                  19: "VTOL", 20: "VTOL", 21: "VTOL", 22: "VTOL"}


def _topics(ulog, name: str) -> list:
    return sorted((d for d in ulog.data_list if d.name == name), key=lambda d: d.multi_id)


def _vector(data: dict, names) -> np.ndarray:
    return np.column_stack([np.asarray(data[n], dtype=float) for n in names])


def _external(params: dict, n: int) -> bool:
    """PX4 marks an internal compass by ``CAL_MAGn_ROT = -1``."""
    return int(params.get(f"CAL_MAG{n}_ROT", -1)) >= 0


def _setup(params: dict, n: int, external: bool, device: int | None) -> dict:
    """What ``log info`` prints of slot ``n``: its priority and use, orientation, scale and device id."""
    level = px4.priority(params, n, external)
    logged = f"CAL_MAG{n}_PRIO" in params
    where = f"CAL_MAG{n}_ROT = {int(params.get(f'CAL_MAG{n}_ROT', 0))}" if external else \
        f"the board's, SENS_BOARD_ROT = {int(params.get('SENS_BOARD_ROT', 0))}"
    scale = px4.scale_matrix(params, n)
    shown = f"{level}" + ("" if logged else " (CAL_MAGn_PRIO not logged: the default of PX4 1.12 and later)")
    return {"priority": shown,
            "use": "no (priority 0 disables it)" if level == 0 else "yes", "orientation": where,
            "scale": "diagonal " + " ".join(f"{v:.4g}" for v in np.diag(scale)) + " (CAL_MAGn_xSCALE)",
            "slot": f"CAL_MAG{n}", "device_id": str(device) if device else "not logged"}


def _raw_compasses(ulog, params: dict) -> list[Compass]:
    """Every ``sensor_mag`` instance: the field before calibration, in the sensor's frame."""
    out = []
    for d in _topics(ulog, "sensor_mag"):
        raw = _vector(d.data, ["x", "y", "z"]) * GAUSS
        device = int(d.data["device_id"][0]) if "device_id" in d.data else None
        n = px4.slot(params, device, d.multi_id)
        external = _external(params, n)
        offsets = np.array([params.get(f"CAL_MAG{n}_{a}OFF", 0.0) for a in "XYZ"]) * GAUSS
        matched = f"CAL_MAG{n} matched by device id {device}" if device else f"CAL_MAG{n} by topic order (no device id)"
        source = f"sensor_mag (logged before calibration, sensor frame); {matched}"
        setup = _setup(params, n, external, device)
        unusable = _unusable(params, n, external)
        if unusable:
            out.append(Compass(f"sensor_mag[{d.multi_id}]", d.data["timestamp"] * MICRO, np.full_like(raw, np.nan),
                               raw, offsets, external, source, np.full((3, 3), np.nan), np.eye(3), n, unusable,
                               setup))
            continue
        field = px4.apply(params, n, external, raw)
        out.append(Compass(f"sensor_mag[{d.multi_id}]", d.data["timestamp"] * MICRO, field, raw, offsets, external,
                           source, np.linalg.inv(px4.scale_matrix(params, n)), px4.body_rotation(params, n, external),
                           n, "", setup))
    return out


def _calibrated_sources(ulog) -> list[tuple]:
    """(name, time (s), field (G), device id or None, topic instance) of every calibrated field logged:
    ``vehicle_magnetometer`` (the selected sensor, 1.10 and later), else ``sensor_combined.magnetometer_ga``."""
    calibrated = _topics(ulog, "vehicle_magnetometer")
    if calibrated:
        return [(f"vehicle_magnetometer[{d.multi_id}]", d.data["timestamp"] * MICRO,
                 _vector(d.data, [f"magnetometer_ga[{a}]" for a in range(3)]),
                 int(d.data["device_id"][0]) if "device_id" in d.data else None, d.multi_id) for d in calibrated]
    combined = _topics(ulog, "sensor_combined")
    if not combined or "magnetometer_ga[0]" not in combined[0].data:
        return []
    data = combined[0].data
    valid = data["magnetometer_timestamp_relative"] != INVALID_RELATIVE
    time = (data["timestamp"][valid] + data["magnetometer_timestamp_relative"][valid]) * MICRO
    field = _vector(data, [f"magnetometer_ga[{a}]" for a in range(3)])[valid]
    time, first = np.unique(time, return_index=True)  # each new sample once
    return [("sensor_combined.magnetometer_ga", time, field[first], None, 0)]


def _compasses(ulog, params: dict) -> list[Compass]:
    """The raw ``sensor_mag`` instances, then each calibrated ``vehicle_magnetometer`` instance (often
    logged faster: 2 Hz against 1 Hz under the default profile), its calibration undone for the raw
    field (its slot matched by device id, ``FindCalibrationIndex``); ``sensor_combined``'s field only
    when neither is logged."""
    out = _raw_compasses(ulog, params)
    sources = _calibrated_sources(ulog)
    if out and sources and sources[0][0].startswith("sensor_combined"):
        return out
    for name, time, field, device, instance in sources:
        k = px4.slot(params, device, instance)
        offsets = np.array([params.get(f"CAL_MAG{k}_{a}OFF", 0.0) for a in "XYZ"]) * GAUSS
        field = field * GAUSS
        external = _external(params, k)
        undone = f"{name} with CAL_MAG{k}_*OFF, *SCALE, *ODIAG and the rotation undone (no raw topic logged)" \
            if not out else f"{name} (the selected sensor) with CAL_MAG{k}_*OFF, *SCALE, *ODIAG and the rotation undone"
        setup = _setup(params, k, external, device)
        where = external if device else None  # the slot, and so the mounting, known from the device id alone
        unusable = _unusable(params, k, external)
        if unusable:
            out.append(Compass(name, time, field, np.full_like(field, np.nan), offsets, where, undone,
                               np.full((3, 3), np.nan), np.eye(3), k, unusable, setup))
            continue
        out.append(Compass(name, time, field, px4.recover_raw(params, k, external, field), offsets, where, undone,
                           np.linalg.inv(px4.scale_matrix(params, k)), px4.body_rotation(params, k, external), k, "",
                           setup))
    return out


def _unusable(params: dict, n: int, external: bool) -> str:
    """Why slot ``n``'s calibration in ``params`` cannot be undone (empty when it can): a singular
    ``CAL_MAGn_*SCALE``/``*ODIAG`` matrix or a rotation this reader does not handle, named."""
    S = px4.scale_matrix(params, n)
    if not (np.all(np.isfinite(S)) and np.linalg.cond(S) < SINGULAR_CONDITION):
        named = ", ".join(f"CAL_MAG{n}_{a}{kind} = {params.get(f'CAL_MAG{n}_{a}{kind}', default):g}"
                          for kind, default in (("SCALE", 1.0), ("ODIAG", 0.0)) for a in "XYZ")
        return (f"its scale factors make a singular correction ({named}): the field before PX4's calibration "
                "cannot be recovered from this log (a scale of 1 and off-diagonals of 0 are no correction)")
    try:
        px4.body_rotation(params, n, external)
    except ValueError as error:
        which = f"CAL_MAG{n}_ROT" if external else "SENS_BOARD_ROT"
        return f"its rotation cannot be applied ({which}: {error})"
    return ""


def _position(ulog) -> Position | None:
    """The median 3D fix of ``vehicle_gps_position`` (or ``sensor_gps``) and its UTC date."""
    import datetime

    topics = _topics(ulog, "vehicle_gps_position") or _topics(ulog, "sensor_gps")
    if not topics:
        return None
    d = topics[0].data
    fixed = (np.asarray(d.get("fix_type", np.zeros(1))) >= 3) & (np.asarray(d.get("time_utc_usec", np.zeros(1))) > 0)
    if not fixed.any():
        return None
    if "latitude_deg" in d:
        lat, lon, alt = d["latitude_deg"][fixed], d["longitude_deg"][fixed], d["altitude_msl_m"][fixed]
    else:
        lat, lon, alt = d["lat"][fixed] * 1e-7, d["lon"][fixed] * 1e-7, d["alt"][fixed] * 1e-3
    try:
        when = datetime.datetime.fromtimestamp(float(d["time_utc_usec"][fixed][0]) * MICRO, datetime.UTC)
    except (OverflowError, ValueError, OSError):  # a date no receiver reports (a damaged message)
        return None
    if when.year >= 9999 or not np.isfinite([np.median(lat), np.median(lon), np.median(alt)]).all():
        return None
    start = datetime.datetime(when.year, 1, 1, tzinfo=datetime.UTC)
    end = datetime.datetime(when.year + 1, 1, 1, tzinfo=datetime.UTC)
    year = when.year + (when - start).total_seconds() / (end - start).total_seconds()
    return Position(float(np.median(lat)), float(np.median(lon)), float(np.median(alt)), float(year),
                    f"{topics[0].name} (median of the 3D fixes)")


def _thrust(ulog) -> Throttle | None:
    topics = _topics(ulog, "vehicle_thrust_setpoint")
    if topics:
        d = topics[0].data
        value = np.linalg.norm(_vector(d, [f"xyz[{k}]" for k in range(3)]), axis=1)
        return Throttle(d["timestamp"] * MICRO, value, "vehicle_thrust_setpoint (norm)")
    topics = _topics(ulog, "actuator_controls_0")
    if topics and "control[3]" in topics[0].data:
        d = topics[0].data
        return Throttle(d["timestamp"] * MICRO, np.asarray(d["control[3]"], dtype=float),
                        "actuator_controls_0.control[3]")
    return None


def _imus(ulog) -> list[Imu]:
    """``sensor_combined`` (calibrated, body frame, at the IMU's rate) when logged; else each
    ``sensor_accel``/``sensor_gyro`` instance (1.13 and later log them at 1 Hz in the sensor's frame
    under the default profile, as ``sensor_mag``)."""
    combined = _topics(ulog, "sensor_combined")
    if combined and "gyro_rad[0]" in combined[0].data:
        data = combined[0].data
        return [Imu("sensor_combined", data["timestamp"] * MICRO, _vector(data, [f"gyro_rad[{a}]" for a in range(3)]),
                    _vector(data, [f"accelerometer_m_s2[{a}]" for a in range(3)]))]
    accels, gyros = _topics(ulog, "sensor_accel"), _topics(ulog, "sensor_gyro")
    out = []
    for acc, gyro in zip(accels, gyros, strict=False):
        t_gyro = gyro.data["timestamp"] * MICRO
        t_acc = acc.data["timestamp"] * MICRO
        a = _vector(acc.data, ["x", "y", "z"])
        out.append(Imu(f"sensor_gyro/accel[{gyro.multi_id}]", t_gyro, _vector(gyro.data, ["x", "y", "z"]),
                       np.column_stack([np.interp(t_gyro, t_acc, a[:, i]) for i in range(3)])))
    return out


def _motors(ulog, params: dict, path: Path) -> Motors | None:
    n = MAV_TYPE_MOTORS.get(int(params.get("MAV_TYPE", 2)), 4)
    motors = _topics(ulog, "actuator_motors")
    if motors:
        d = motors[0].data
        commands = _vector(d, [f"control[{k}]" for k in range(n)])
        return Motors(d["timestamp"] * MICRO, np.clip(np.nan_to_num(commands), 0.0, 1.0), commands, 0.0, 1.0,
                      "actuator_motors (normalised by PX4)")
    outputs = _topics(ulog, "actuator_outputs")
    if not outputs:
        return None
    d = outputs[0].data
    pwm = _vector(d, [f"output[{k}]" for k in range(n)])
    low, high, source = px4.pwm_limits(params, n)
    return Motors(d["timestamp"] * MICRO, np.clip((pwm - low) / (high - low), 0.0, 1.0), pwm, float(low.min()),
                  float(high.max()), source)


def _battery(ulog) -> Battery | None:
    topics = _topics(ulog, "battery_status")
    if not topics:
        return None
    d = topics[0].data
    current = np.asarray(d["current_a"], dtype=float)
    measured = (current >= 0).all() and current.max() > 0
    return Battery(d["timestamp"] * MICRO, np.asarray(d["voltage_v"], dtype=float), current if measured else None,
                   "battery_status.current_a" if measured else "none: battery_status.current_a is never measured")


def _attitude(ulog) -> Attitude | None:
    topics = _topics(ulog, "vehicle_attitude")
    if not topics:
        return None
    d = topics[0].data
    return Attitude(d["timestamp"] * MICRO, _vector(d, [f"q[{k}]" for k in range(4)]), "vehicle_attitude")


def read_ulog(path: Path) -> FlightLog:
    """Read the PX4 ULog at ``path``."""
    from pyulog import ULog
    from quadcosim.flightlogs.noise import captured

    from quadcosim.infra.interrupts import surfaced

    with surfaced(), captured() as noise:  # pyulog prints its warnings on standard output
        try:
            ulog = ULog(str(path))
        except Exception as error:  # pyulog raises bare exceptions on a bad header or definitions
            raise LogError(f"{path}: not a readable ULog ({type(error).__name__}: {error}); check the file is a "
                           "complete PX4 .ulg") from None
    if not ulog.data_list:
        raise LogError(f"{path}: the ULog holds no logged topic; it is truncated before its data")
    params = dict(ulog.initial_parameters)
    info = ulog.msg_info_dict
    hardware = str(info.get("ver_hw", ""))
    release = info.get("ver_sw_release")
    if isinstance(release, int | np.integer):  # major, minor, patch and type packed (``px4_firmware_version``)
        release = ulog.get_version_info_str() or release
    firmware = f"{release or info.get('ver_sw', 'version not logged')} on {hardware}"
    simulator = "SITL" in hardware.upper() or hardware.upper().startswith("PX4_SITL") or "SIH" in hardware.upper()
    vehicle = MAV_TYPE_NAMES.get(int(params.get("MAV_TYPE", 0)), f"MAV_TYPE {params.get('MAV_TYPE', '?')}")
    said = noise.summary("pyulog")
    warnings = [f"corrupt stretches skipped: {said or 'pyulog reports file corruption'}"] \
        if ulog.file_corruption or said else []
    return FlightLog(str(path), "ulog", "PX4", firmware, vehicle, simulator, _compasses(ulog, params), _imus(ulog),
                     _motors(ulog, params, path), _battery(ulog), _attitude(ulog), params, warnings,
                     _position(ulog), _thrust(ulog))
