"""The autopilots a flight calibration exports for, one line each in :data:`AUTOPILOTS`: what
each firmware does with the parameters (applies them to the raw field, names them, which motor
compensations it has) and its parameter file, ArduPilot's (``NAME,VALUE`` lines, as Mission
Planner loads them) or PX4's (QGroundControl's tab-separated format). The firmware arithmetic
itself is in :mod:`quadcosim.flightlogs.ardupilot` and :mod:`quadcosim.flightlogs.px4`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from quadcosim.flightlogs import ardupilot, px4


def write_ardupilot(params: dict, path) -> None:
    """``params`` as an ArduPilot parameter file (``NAME,VALUE`` lines, as Mission Planner loads) at
    ``path``, written atomically (:func:`quadcosim.infra.files.atomic_path`)."""
    from quadcosim.infra.files import write_text

    write_text(path, "".join(f"{name},{value:.9g}\n" for name, value in params.items()))


def write_px4(params: dict, path) -> None:
    """``params`` as a QGroundControl parameter file for PX4 (tab-separated, vehicle 1) at ``path``,
    written atomically (:func:`quadcosim.infra.files.atomic_path`)."""
    from quadcosim.infra.files import write_text

    lines = ["# Vehicle-Id Component-Id Name Value Type\n"]
    for name, value in params.items():
        kind = 6 if isinstance(value, int) else 9  # MAV_PARAM_TYPE_INT32, REAL32
        lines.append(f"1\t1\t{name}\t{value:.9g}\t{kind}\n")
    write_text(path, "".join(lines))


def rules_of(part, override=None) -> ardupilot.Rules:
    """The ArduPilot rules of the firmware named by the banner of ``part``'s log (``part``: a
    :class:`quadcosim.calibration.flight.data.FlightData`), or ``override`` (a
    :class:`quadcosim.flightlogs.ardupilot.Rules`)."""
    return override or ardupilot.log_rules(part.log.firmware)


def _compass(part):
    return part.log.compasses[part.compass]


def _ardupilot_apply(part, params, inputs, rule):
    return ardupilot.apply(params, _compass(part).slot, rules_of(part, rule), part.raw, inputs["current"],
                           inputs["throttle"], inputs["commands"], inputs["voltage"])


def _px4_apply(part, params, inputs, rule):
    compass = _compass(part)
    return px4.apply(params, compass.slot, bool(compass.external), part.raw, inputs["current"], inputs["throttle"])


def _ardupilot_parameters(part, candidate, rule):
    return ardupilot.parameters(_compass(part).slot, rules_of(part, rule), candidate.offset, candidate.correction,
                                candidate.model, candidate.K) | _ardupilot_enabling(part)


def _px4_parameters(part, candidate, rule):
    return px4.parameters(_compass(part).slot, candidate.offset, candidate.correction,
                          None if candidate.model == "motors" else candidate.model, candidate.K)


def _ardupilot_enabling(part):
    slot = _compass(part).slot
    return ardupilot.enabling(part.log.params, slot, ardupilot.priority_of(part.log.params, slot))


def _ardupilot_models(part, rule):
    from quadcosim.calibration.flight import catalogue

    if rules_of(part, rule).per_motor and _compass(part).slot == 0:  # COMPASS_PMOT: 4.0 and later, first compass
        return catalogue.preferred("autopilot")
    return ("current", "throttle")


def _px4_models(part, rule):
    return ("current", "throttle")


def _ardupilot_scale(part, rule):
    return {f"COMPASS_SCALE{ardupilot.suffix(_compass(part).slot)}": 1.0} if rules_of(part, rule).scale else {}


def _no_scale(part, rule):
    return {}


def _ardupilot_firmware(part, rule):
    return rules_of(part, rule).name


def _px4_firmware(part, rule):
    return part.log.firmware


def _first_compass(params):
    return 0  # PX4's heading fuses its first magnetometer


def _ardupilot_motor_key(name: str) -> bool:
    return name.startswith("COMPASS_") and "MOT" in name  # not every COMPASS_*: offsets and soft iron


def _px4_motor_key(name: str) -> bool:
    return name.startswith("CAL_MAG") and "COMP" in name


@dataclass(frozen=True)
class Autopilot:
    """An autopilot the export writes parameters for, and how its firmware uses them.

    The callables ``apply`` to ``firmware`` take ``part`` (a
    :class:`quadcosim.calibration.flight.data.FlightData` of one compass of one of this autopilot's logs)
    and, last, ``rule``: a :class:`quadcosim.flightlogs.ardupilot.Rules` overriding the firmware version
    the log names (None: the log's); it is ArduPilot's, and the PX4 functions ignore it.

    Attributes
    ----------
    name : str
        As a flight log names it (:attr:`quadcosim.flightlogs.FlightLog.autopilot`).
    file : str
        The parameter file the export writes in the results folder.
    write : callable
        ``(params, path)``: the parameters in the autopilot's file format.
    apply : callable
        ``(part, params, inputs, rule)``: the body-frame field (T, 3) (T) the firmware reports
        from the part's raw field with ``params`` (all of them, the log's included) and
        ``inputs`` (``current`` (A), ``throttle`` (0..1), ``commands`` (0..1), ``voltage`` (V)).
    parameters : callable
        ``(part, candidate, rule)``: a :class:`quadcosim.calibration.flight.export.Candidate` (hard iron
        ``offset`` (T), soft-iron inverse ``correction`` (1), motor ``model`` and its field ``K``
        (T per unit of the model's input: A, throttle or motor command)) as the firmware's
        parameters of the part's compass, name: value in the firmware's units.
    motor_models : callable
        ``(part, rule)``: the motor compensations the firmware has for the part's compass, names
        of :data:`quadcosim.calibration.flight.catalogue.MODELS`.
    scale_reset : callable
        ``(part, rule)``: parameters to reset when a fitted soft iron is exported (it carries the
        scale).
    firmware : callable
        ``(part, rule)``: the firmware as the export's metrics name it (str): ArduPilot's rules
        (the version, or ``--firmware``'s), PX4's log banner.
    motor_off : dict
        The parameters that switch the firmware's motor compensation off.
    is_motor_key : callable
        ``(name)``: whether a parameter name is one of the motor compensation's.
    fused_compass : callable
        ``(params)``: the compass (0-based) the firmware's heading fuses.
    board_trim : callable or None
        ``(params)``: the rotation (3, 3) from the vehicle to the board that the logged attitude
        leaves out (ArduPilot's ``AHRS_TRIM``); None: the logged attitude is the sensors' frame's.
    enabling : callable or None
        ``(part)``: the parameters a compass the log's firmware does not use needs to be used
        (ArduPilot's ``COMPASS_USEn`` and ``COMPASS_DEV_IDn``, :func:`quadcosim.flightlogs.ardupilot.enabling`);
        empty for a compass in use; None: the firmware has no such switch. The export carries them
        and its notes say so.
    """

    name: str
    file: str
    write: Callable[[dict, object], None]
    apply: Callable
    parameters: Callable
    motor_models: Callable
    scale_reset: Callable
    firmware: Callable
    motor_off: dict
    is_motor_key: Callable[[str], bool]
    fused_compass: Callable[[dict], int]
    board_trim: Callable | None = None
    enabling: Callable | None = None


#: The autopilots, one line each: a flight log of one of them is exported in its own file.
AUTOPILOTS = {autopilot.name: autopilot for autopilot in (
    Autopilot("ArduPilot", "ardupilot.parm", write_ardupilot, _ardupilot_apply, _ardupilot_parameters,
              _ardupilot_models, _ardupilot_scale, _ardupilot_firmware, {"COMPASS_MOTCT": 0, "COMPASS_PMOT_EN": 0},
              _ardupilot_motor_key, ardupilot.fused_compass, ardupilot.trim_rotation, _ardupilot_enabling),
    Autopilot("PX4", "px4.params", write_px4, _px4_apply, _px4_parameters, _px4_models, _no_scale, _px4_firmware,
              {"CAL_MAG_COMP_TYP": 0}, _px4_motor_key, _first_compass),
)}


def autopilot_of(part) -> Autopilot:
    """The :class:`Autopilot` of ``part``'s log."""
    return AUTOPILOTS[part.log.autopilot]


def write_parameters(autopilot: str, params: dict, path) -> None:
    """``params`` in the file format of ``autopilot`` (a name of :data:`AUTOPILOTS`) at ``path``."""
    AUTOPILOTS[autopilot].write(params, path)


FLOAT32_MAX = 3.4028234663852886e38  # the largest value of the autopilots' 32-bit float parameters
MAX_PARAMETER_BYTES = 16 * 1024 * 1024  # an autopilot's whole parameter list takes a few hundred kB


def read_parameters(path) -> dict:
    """Parameters from an ArduPilot ``.parm`` (``NAME,VALUE`` or ``NAME VALUE`` lines) or a
    QGroundControl ``.params`` file (tab-separated) at ``path``, as :func:`write_ardupilot` and
    :func:`write_px4` write them.

    Raises
    ------
    ValueError
        The file is missing, not a regular file (a FIFO would block), too large, not text, or a
        line holds no ``NAME VALUE``; the message names the file, the line and the fix.
    """
    from quadcosim.infra.inputs import regular_file

    path = Path(path)
    status = regular_file(path, "the parameter file", "give a parameter file (.parm or .params)")
    if status.st_size > MAX_PARAMETER_BYTES:
        raise ValueError(f"{path}: {status.st_size / 1e6:.0f} MB, not a parameter file (.parm or .params)")
    try:
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark is not part of the first name
    except UnicodeDecodeError as error:
        raise ValueError(f"{path}: not a text parameter file (byte {error.start} is not UTF-8); give the .parm or "
                         ".params the ground station saved") from None
    except OSError as error:
        raise ValueError(f"{path}: cannot read the parameter file ({error.strerror})") from None
    params = {}
    for number, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        parts = line.split("\t") if "\t" in line else line.split(",") if "," in line else line.split()
        try:
            name, value = (parts[2], parts[3]) if len(parts) > 3 else parts[:2]
            given = int(value) if value.strip().lstrip("-").isdigit() else float(value)
        except (ValueError, IndexError):
            raise ValueError(f"{path}, line {number}: {line[:60]!r} is not NAME,VALUE (ArduPilot) nor "
                             "1<TAB>1<TAB>NAME<TAB>VALUE<TAB>TYPE (QGroundControl); fix or remove the line") from None
        if name.strip() in params:
            raise ValueError(f"{path}, line {number}: {name.strip()} is given a second time; an autopilot keeps one "
                             "value per name: remove one of the lines")
        params[name.strip()] = given
        if not abs(params[name.strip()]) <= FLOAT32_MAX:  # NaN and infinities too
            raise ValueError(f"{path}, line {number}: {name.strip()} = {value.strip()} is not a value an autopilot "
                             "stores (its parameters are finite 32-bit floats); fix or remove the line")
    if not params:
        raise ValueError(f"{path}: no parameters in the file; give the .parm or .params the ground station saved")
    return params
