"""PX4: its ULog files (:mod:`.ulog`, read with pyulog), its magnetometer calibration as the firmware
applies it (:mod:`.firmware`, every rule cited from PX4's source) and its parameter file
(QGroundControl's tab-separated format), as one :data:`AUTOPILOT`.
"""

from __future__ import annotations

from quadcosim.flightlogs.autopilots import Autopilot, LogFormat
from quadcosim.flightlogs.autopilots.px4 import firmware

ULOG_MAGIC = b"ULog\x01\x12\x35"  # the ULog file header's magic (PX4's ULog file format)

#: How PX4's logger (``LoggedTopics::add_default_topics``) logs a compass: ``sensor_mag`` every 1000 ms and
#: ``vehicle_magnetometer`` every 500 ms; the sensor comparison profile (``SDLogProfileMask::SENSOR_COMPARISON``,
#: bit 6, value 64: ``add_sensor_comparison_topics``) logs ``sensor_mag`` every 100 ms.
FASTER_COMPASS = ("set SDLOG_PROFILE's sensor comparison bit (64: SDLOG_PROFILE = 65 beside the default profile's 1), "
                  "which logs sensor_mag at 10 Hz, and fly again")


def write(params: dict, path) -> None:
    """``params`` as a QGroundControl parameter file for PX4 (tab-separated, vehicle 1) at ``path``,
    written atomically (:func:`quadcosim.infra.files.atomic_path`)."""
    from quadcosim.infra.files import write_text

    lines = ["# Vehicle-Id Component-Id Name Value Type\n"]
    for name, value in params.items():
        kind = 6 if isinstance(value, int) else 9  # MAV_PARAM_TYPE_INT32, REAL32
        lines.append(f"1\t1\t{name}\t{value:.9g}\t{kind}\n")
    write_text(path, "".join(lines))


def _read(path):
    from quadcosim.flightlogs.autopilots.px4.ulog import read_ulog

    return read_ulog(path)


def _compass(part):
    return part.log.compasses[part.compass]


def _apply(part, params, inputs, rule):
    compass = _compass(part)
    return firmware.apply(params, compass.slot, bool(compass.external), part.raw, inputs["current"],
                          inputs["throttle"])


def _parameters(part, candidate, rule):
    return firmware.parameters(_compass(part).slot, candidate.offset, candidate.correction,
                               None if candidate.model == "motors" else candidate.model, candidate.K)


def _motor_models(part, rule):
    return ("current", "throttle")  # CAL_MAG_COMP_TYP: thrust or current


def _motor_inputs(model: str, inputs: dict):
    if model == "current":
        return None if inputs["current"] is None else inputs["current"][:, None]
    return inputs["throttle"][:, None] if model == "throttle" else None


def _no_scale(part, rule):
    return {}


def _firmware(part, rule):
    return part.log.firmware


def _first_compass(params):
    return 0  # PX4's heading fuses its first magnetometer


def _motor_key(name: str) -> bool:
    return name.startswith("CAL_MAG") and "COMP" in name


#: PX4, registered by its line in ``quadcosim.autopilots``.
AUTOPILOT = Autopilot(
    name="PX4",
    formats=(LogFormat("ulog", "PX4 ULog (.ulg)", lambda head: head.startswith(ULOG_MAGIC), _read),),
    messages={"compass": "sensor_mag or vehicle_magnetometer", "imu": "sensor_accel and sensor_gyro, or "
              "sensor_combined", "attitude": "vehicle_attitude", "motors": "actuator_motors or actuator_outputs",
              "battery": "battery_status"},
    logging="SDLOG_PROFILE", faster_compass=FASTER_COMPASS,
    file="px4.params", write=write, apply=_apply, parameters=_parameters, motor_models=_motor_models,
    motor_inputs=_motor_inputs, scale_reset=_no_scale, firmware=_firmware, motor_off={"CAL_MAG_COMP_TYP": 0},
    is_motor_key=_motor_key, fused_compass=_first_compass)
