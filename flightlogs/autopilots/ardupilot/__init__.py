"""ArduPilot: its DataFlash logs, binary and text (:mod:`.dataflash`), its compass arithmetic as each
Copter version applies it (:mod:`.firmware`, every rule cited from ArduPilot's source) and its
parameter file (``NAME,VALUE`` lines, as Mission Planner loads them), as one :data:`AUTOPILOT`.
"""

from __future__ import annotations

import numpy as np
from quadcosim.flightlogs.autopilots import Autopilot, LogFormat
from quadcosim.flightlogs.autopilots.ardupilot import firmware

DATAFLASH_HEAD = b"\xa3\x95"  # HEAD_BYTE1, HEAD_BYTE2 of every binary DataFlash message (AP_Logger)


def write(params: dict, path) -> None:
    """``params`` as an ArduPilot parameter file (``NAME,VALUE`` lines, as Mission Planner loads) at
    ``path``, written atomically (:func:`quadcosim.infra.files.atomic_path`)."""
    from quadcosim.infra.files import write_text

    write_text(path, "".join(f"{name},{value:.9g}\n" for name, value in params.items()))


def _binary(path):
    from quadcosim.flightlogs.autopilots.ardupilot.dataflash import read_dataflash

    return read_dataflash(path, text=False)


def _text(path):
    from quadcosim.flightlogs.autopilots.ardupilot.dataflash import read_dataflash

    return read_dataflash(path, text=True)


def rules_of(part, override=None) -> firmware.Rules:
    """The rules of the firmware named by the banner of ``part``'s log, or ``override`` (``--firmware``'s)."""
    return override or firmware.log_rules(part.log.firmware)


def versions(text: str) -> firmware.Rules:
    """The rules of the Copter version ``text`` (``3.4``, ``4.5``); ValueError when it names none."""
    version = firmware.parse_version(f"ArduCopter V{text}")
    if version is None:
        raise ValueError(f"--firmware {text!r} is not a Copter version such as 3.4 or 4.5")
    return firmware.rules(version)


def _compass(part):
    return part.log.compasses[part.compass]


def _apply(part, params, inputs, rule):
    return firmware.apply(params, _compass(part).slot, rules_of(part, rule), part.raw, inputs["current"],
                          inputs["throttle"], inputs["commands"], inputs["voltage"])


def _parameters(part, candidate, rule):
    return firmware.parameters(_compass(part).slot, rules_of(part, rule), candidate.offset, candidate.correction,
                               candidate.model, candidate.K) | _enabling(part)


def _enabling(part):
    slot = _compass(part).slot
    return firmware.enabling(part.log.params, slot, firmware.priority_of(part.log.params, slot))


def _motor_models(part, rule):
    if rules_of(part, rule).per_motor and _compass(part).slot == 0:  # COMPASS_PMOT: 4.0 and later, first compass
        return ("current", "motors", "throttle")
    return ("current", "throttle")


def _motor_inputs(model: str, inputs: dict):
    if model == "current":
        return None if inputs["current"] is None else inputs["current"][:, None]
    if model == "throttle":
        return inputs["throttle"][:, None]
    if np.isnan(inputs["voltage"]).any():  # no voltage logged
        return None
    return firmware.per_motor_outputs(inputs["commands"], inputs["voltage"])[:, :firmware.PMOT_MOTORS]


def _scale(part, rule):
    return {f"COMPASS_SCALE{firmware.suffix(_compass(part).slot)}": 1.0} if rules_of(part, rule).scale else {}


def _firmware(part, rule):
    return rules_of(part, rule).name


def _motor_key(name: str) -> bool:
    return name.startswith("COMPASS_") and "MOT" in name  # not every COMPASS_*: offsets and soft iron


#: ArduPilot, registered by its line in ``quadcosim.autopilots``.
AUTOPILOT = Autopilot(
    name="ArduPilot",
    formats=(LogFormat("dataflash-binary", "ArduPilot DataFlash binary (.bin)",
                       lambda head: head.startswith(DATAFLASH_HEAD), _binary),
             LogFormat("dataflash-text", "ArduPilot DataFlash text (.log)",
                       lambda head: head.lstrip().startswith(b"FMT,"), _text)),
    messages={"compass": "MAG", "imu": "IMU", "attitude": "ATT", "motors": "RCOU", "battery": "BAT or CURR"},
    logging="LOG_BITMASK",
    faster_compass="log the compass at its full rate (LOG_BITMASK with IMU and compass; ArduPilot logs MAG at 10 Hz "
                   "or faster) and fly again",
    file="ardupilot.parm", write=write, apply=_apply, parameters=_parameters, motor_models=_motor_models,
    motor_inputs=_motor_inputs, scale_reset=_scale, firmware=_firmware,
    motor_off={"COMPASS_MOTCT": 0, "COMPASS_PMOT_EN": 0}, is_motor_key=_motor_key,
    fused_compass=firmware.fused_compass, board_trim=firmware.trim_rotation, enabling=_enabling, versions=versions)
