"""ArduPilot's compass corrections as each firmware version applies them, and its parameters.

Every rule here is read from ArduPilot's source and cited by file and function:

- the order of the motor compensation (``AP_Compass_Backend::correct_field``,
  ``libraries/AP_Compass/AP_Compass_Backend.cpp``). Up to Copter 3.5 the motor offset is added
  before the soft-iron matrix, ``field = M (raw + OFS + MOT x)``; from Copter 3.6 after it,
  ``field = M (raw + OFS) + MOT x`` (the source's comment: "we apply the motor offsets after we
  apply the eliptical correction ... as they are calculated based on final field outputs");
- ``COMPASS_SCALE`` (Copter 4.0 and later, same function): ``field = M (s (raw + OFS)) + MOT x``,
  with ``s`` applied only inside ``Compass::have_scale_factor``'s range (:data:`SCALE_RANGE`);
- ``M`` from ``COMPASS_DIA*`` on its diagonal and ``COMPASS_ODI*`` off it; an all-zero diagonal is
  set to ones (``correct_field``: ``if (state.diagonals.get().is_zero()) diagonals.set(1, 1, 1)``),
  the off-diagonals kept;
- ``x``: the battery current in A (``COMPASS_MOTCT = 2``, ``AP_BattMonitor::current_amps``) or
  ``motors->get_throttle()`` (``COMPASS_MOTCT = 1``, passed by ``Copter::update_batt_compass``
  through ``Compass::set_throttle``; logged as ``CTUN.ThO``, 0 to 1). Up to 3.5 the compensation
  is skipped while ``x`` is exactly zero (``!is_zero(_thr_or_curr)``), which changes nothing;
- per-motor compensation ``COMPASS_PMOT*`` (Copter 4.0 and later; ``Compass_PerMotor::compensate``
  and ``::scaled_output``, ``libraries/AP_Compass/Compass_PerMotor.cpp``), for the first compass
  only, replacing ``COMPASS_MOT``: ``MOT x = sum_n PMOTn ((c_n V)^EXP)`` with ``c_n`` the motor's
  demand from 0 to 1 (``scale_esc_to_unity``), ``V`` the battery voltage (``Compass::set_voltage``,
  low-passed by ``0.9 V + 0.1 V_new`` at the compass's rate), ``EXP`` ``COMPASS_PMOT_EXP``;
- rotations (``AP_Compass_Backend::rotate_field``): the driver's rotation, then
  ``AHRS_ORIENTATION`` for an internal compass or ``COMPASS_ORIENT`` for an external one, all
  before the correction. ``MAG`` logs the corrected field in the autopilot's body frame, so the
  raw field recovered from it, the offsets and the motor vectors are all in that frame;
- ``AHRS_TRIM_X/Y`` (rad): the attitude ``ATT`` logs is the vehicle's, the board's rotated by the
  trim (``AP_AHRS::update_trig``: ``_rotation_autopilot_body_to_vehicle_body.from_euler(trim.x,
  trim.y, 0)``; ``AP_AHRS_NavEKF::update_EKF2`` multiplies the board's rotation by its transpose),
  so the board's attitude is ``R_vehicle R(trim)``.

Fields are in milligauss (:data:`MILLIGAUSS`). ``MAG`` logs the corrected field with ``Ofs*``, the
offsets, and ``MOfs*``, the motor offset applied, which recover the raw field by
:func:`recover_raw`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

MILLIGAUSS = 1e-7  # T
AXES = "XYZ"
MOTCT = {"throttle": 1, "current": 2}
SCALE_RANGE = (1.0 / 1.5, 1.5)  # Compass::have_scale_factor: COMPASS_MIN/MAX_SCALE_FACTOR (CompassCalibrator.h)
PMOT_MOTORS = 4  # Compass_PerMotor of the 4.x releases: the first four motors
PMOT_VOLTAGE_SMOOTHING = 0.1  # Compass_PerMotor::set_voltage: voltage = 0.9 voltage + 0.1 new
DEFAULT_VERSION = (4, 0)  # the rules assumed when the log names no Copter version (a warning says so)


@dataclass(frozen=True)
class Rules:
    """What an ArduPilot version does with its compass parameters.

    Attributes
    ----------
    version : tuple of int
        (major, minor) of the Copter release whose rules apply.
    motor_after_soft_iron : bool
        Copter 3.6 and later: ``M (raw + OFS) + MOT x``; earlier ``M (raw + OFS + MOT x)``.
    scale : bool
        ``COMPASS_SCALE*`` exists (4.0 and later).
    per_motor : bool
        ``COMPASS_PMOT*`` exists (4.0 and later).
    """

    version: tuple
    motor_after_soft_iron: bool
    scale: bool
    per_motor: bool

    @property
    def name(self) -> str:
        """``Copter 3.4`` and the rule set in words."""
        order = "M (raw + OFS) + MOT x" if self.motor_after_soft_iron else "M (raw + OFS + MOT x)"
        extra = ", COMPASS_SCALE, COMPASS_PMOT" if self.scale else ""
        return f"Copter {self.version[0]}.{self.version[1]} ({order}{extra})"


def parse_version(firmware: str) -> tuple[int, int] | None:
    """(major, minor) of a firmware banner (``APM:Copter V3.4-dev (461eff25)``,
    ``ArduCopter V4.5.0``); None when it holds no Copter version."""
    match = re.search(r"(?:APM:|Ardu)Copter V(\d+)\.(\d+)", firmware)
    return (int(match.group(1)), int(match.group(2))) if match else None


def rules(version: tuple[int, int]) -> Rules:
    """The :class:`Rules` of Copter ``version`` (major, minor)."""
    version = tuple(version)
    return Rules(version, version >= (3, 6), version >= (4, 0), version >= (4, 0))


def log_rules(firmware: str) -> Rules:
    """The :class:`Rules` of a log's firmware banner, :data:`DEFAULT_VERSION`'s when it names none."""
    return rules(parse_version(firmware) or DEFAULT_VERSION)


def suffix(compass: int) -> str:
    """The parameter suffix of compass ``compass`` (0-based): ``""``, ``"2"``, ``"3"``."""
    return "" if compass == 0 else str(compass + 1)


def soft_iron(params: dict, compass: int) -> np.ndarray:
    """``M`` (3, 3) of compass ``compass`` from ``COMPASS_DIA*``/``ODI*`` as ``correct_field`` builds
    it from ``params`` (name: value): an all-zero diagonal becomes ones, the off-diagonals kept."""
    s = suffix(compass)
    dia = [float(params.get(f"COMPASS_DIA{s}_{a}", 0.0)) for a in AXES]
    odi = [float(params.get(f"COMPASS_ODI{s}_{a}", 0.0)) for a in AXES]
    if not any(dia):
        dia = [1.0, 1.0, 1.0]
    return np.array([[dia[0], odi[0], odi[1]], [odi[0], dia[1], odi[2]], [odi[1], odi[2], dia[2]]])


def scale_factor(params: dict, compass: int, rule: Rules) -> float:
    """``COMPASS_SCALE*`` of compass ``compass`` in ``params`` as applied under ``rule``: 1 before 4.0 or
    outside :data:`SCALE_RANGE` (``have_scale_factor``)."""
    if not rule.scale:
        return 1.0
    value = float(params.get(f"COMPASS_SCALE{suffix(compass)}", 0.0))
    return value if SCALE_RANGE[0] <= value <= SCALE_RANGE[1] else 1.0


def offsets(params: dict, compass: int) -> np.ndarray:
    """``COMPASS_OFS*`` of compass ``compass`` in ``params`` (3,) (mG)."""
    return np.array([float(params.get(f"COMPASS_OFS{suffix(compass)}_{a}", 0.0)) for a in AXES])


def per_motor_outputs(commands, voltage) -> np.ndarray:
    """``Compass_PerMotor::scaled_output`` of each motor (T, N): ``(c V_lp)^1`` before the exponent,
    ``c`` the demand (``commands``, T x N, 0..1; 0 when not positive), ``V_lp`` the low-passed battery
    ``voltage`` (T,) (V)."""
    commands = np.asarray(commands, dtype=float)
    voltage = np.asarray(voltage, dtype=float)
    smoothed = np.empty_like(voltage)
    level = voltage[0] if len(voltage) else 0.0
    for k, v in enumerate(voltage):  # the firmware's first-order filter, sample by sample
        level = (1 - PMOT_VOLTAGE_SMOOTHING) * level + PMOT_VOLTAGE_SMOOTHING * v
        smoothed[k] = level
    return np.where(commands > 0, commands, 0.0) * smoothed[:, None]


def motor_offset(params: dict, compass: int, rule: Rules, current, throttle, commands=None,
                 voltage=None) -> np.ndarray:
    """The motor offset (T, 3) (mG) ``correct_field`` adds: per-motor for the first compass when
    ``COMPASS_PMOT_EN`` (4.0 and later), else ``COMPASS_MOT*`` times the current (A) or the throttle
    (0..1) as ``COMPASS_MOTCT`` says; zeros when compensation is off or its input absent. ``params``:
    the parameters; ``rule``: the version's :class:`Rules`; ``commands`` (T, N) and ``voltage`` (T,)
    (V): the per-motor inputs."""
    n = len(current if current is not None else throttle)
    if rule.per_motor and compass == 0 and params.get("COMPASS_PMOT_EN", 0):
        if commands is None or voltage is None:
            raise ValueError("COMPASS_PMOT_EN is set: the motor outputs and battery voltage are needed")
        exponent = float(params.get("COMPASS_PMOT_EXP", 0.65))
        outputs = per_motor_outputs(commands, voltage)[:, :PMOT_MOTORS] ** exponent
        vectors = np.array([[float(params.get(f"COMPASS_PMOT{m + 1}_{a}", 0.0)) for a in AXES]
                            for m in range(outputs.shape[1])])
        return outputs @ vectors
    kind = int(params.get("COMPASS_MOTCT", 0))
    x = current if kind == MOTCT["current"] else throttle if kind == MOTCT["throttle"] else None
    if x is None:
        return np.zeros((n, 3))
    vector = np.array([float(params.get(f"COMPASS_MOT{suffix(compass)}_{a}", 0.0)) for a in AXES])
    return np.outer(np.asarray(x, dtype=float), vector)


def apply(params: dict, compass: int, rule: Rules, raw, current=None, throttle=None, commands=None,
          voltage=None) -> np.ndarray:
    """The field (T, 3) (T) ArduPilot reports for compass ``compass`` from ``raw`` (T, 3) (T, body
    frame, after ``rotate_field``) with ``params`` under ``rule``, as ``correct_field`` computes it;
    ``current`` (A), ``throttle`` (``CTUN.ThO``), ``commands`` (0..1) and ``voltage`` (V) at the
    samples, as the compensation in force needs them."""
    raw_mG = np.asarray(raw, dtype=float) / MILLIGAUSS
    M = soft_iron(params, compass)
    s = scale_factor(params, compass, rule)
    mot = motor_offset(params, compass, rule, current, throttle, commands, voltage)
    corrected = raw_mG + offsets(params, compass)
    if rule.motor_after_soft_iron:
        field = (s * corrected) @ M.T + mot
    else:
        field = (corrected + mot) @ M.T
    return field * MILLIGAUSS


def recover_raw(params: dict, compass: int, rule: Rules, field, logged_offsets, logged_motor) -> np.ndarray:
    """The raw field (T, 3) (T) under the logged ``field`` (T, 3) (T), inverting ``correct_field``
    with the logged ``Ofs`` (``logged_offsets``, T) and ``MOfs`` (``logged_motor``, T) sample by
    sample, ``M`` and the scale of compass ``compass`` from ``params``, in ``rule``'s order."""
    M = soft_iron(params, compass)
    s = scale_factor(params, compass, rule)
    field, ofs, mofs = (np.asarray(a, dtype=float) for a in (field, logged_offsets, logged_motor))
    if rule.motor_after_soft_iron:
        return np.linalg.solve(M, (field - mofs).T).T / s - ofs
    return np.linalg.solve(M, field.T).T - mofs - ofs


def parameters(compass: int, rule: Rules, offset_T, correction, model: str | None, K_T) -> dict:
    """The parameters (name: value, ArduPilot's units) that make ``rule``'s firmware correct
    compass ``compass`` as ``correction (raw - b) - K x`` would, with ``offset_T`` the hard iron
    ``b`` (T), ``correction`` the soft-iron inverse ``A^-1`` (3, 3), ``model`` ``"current"``,
    ``"throttle"``, ``"motors"`` (per motor, 4.0 and later, first compass) or None and ``K_T`` the
    field per unit of its regressor (3,) or per motor output (N, 3) (T).

    The motor vector is ``-A^-1 K`` after the soft iron (3.6 and later) and ``-K`` before it (up to 3.5)."""
    s = suffix(compass)
    correction = np.asarray(correction, dtype=float)
    params = {f"COMPASS_OFS{s}_{a}": float(-offset_T[i] / MILLIGAUSS) for i, a in enumerate(AXES)}
    params |= {f"COMPASS_DIA{s}_{a}": float(correction[i, i]) for i, a in enumerate(AXES)}
    params |= {f"COMPASS_ODI{s}_{a}": float(correction[i, j])
               for a, (i, j) in zip(AXES, ((0, 1), (0, 2), (1, 2)), strict=True)}
    if model == "motors":
        if not (rule.per_motor and compass == 0):
            raise ValueError(f"{rule.name} has no per-motor compensation for compass {compass}")
        vectors = -np.asarray(K_T, dtype=float) @ correction.T / MILLIGAUSS
        params["COMPASS_PMOT_EN"] = 1
        params["COMPASS_PMOT_EXP"] = 1.0
        params |= {f"COMPASS_PMOT{m + 1}_{a}": float(vectors[m, i]) for m in range(len(vectors))
                   for i, a in enumerate(AXES)}
        params["COMPASS_MOTCT"] = 0
        return params
    params["COMPASS_MOTCT"] = MOTCT.get(model, 0)
    K = np.zeros(3) if model is None else np.asarray(K_T, dtype=float).reshape(3)
    motor = (-correction @ K if rule.motor_after_soft_iron else -K) / MILLIGAUSS
    params |= {f"COMPASS_MOT{s}_{a}": float(motor[i]) for i, a in enumerate(AXES)}
    return params


def trim_rotation(params: dict) -> np.ndarray:
    """``R(trim)`` (3, 3): the board's attitude is ``R_vehicle R(trim)`` (``AHRS_TRIM_X/Y`` in rad,
    Z-Y-X Euler with no yaw, as ``Matrix3f::from_euler``), from ``params``."""
    from scipy.spatial.transform import Rotation

    roll, pitch = float(params.get("AHRS_TRIM_X", 0.0)), float(params.get("AHRS_TRIM_Y", 0.0))
    return Rotation.from_euler("ZYX", [0.0, pitch, roll]).as_matrix()


def fused_compass(params: dict) -> int:
    """The compass the attitude estimator fuses, 0-based in the log's order: ``COMPASS_PRIMARY`` up to
    Copter 3.6; from 4.0, which has no such parameter, the first in priority order whose
    ``COMPASS_USEn`` is set (``Compass::get_first_usable``), ``MAG`` instance ``I`` being that order."""
    if "COMPASS_PRIMARY" in params or not any(f"COMPASS_PRIO{n}_ID" in params for n in (1, 2, 3)):
        return int(params.get("COMPASS_PRIMARY", 0))
    return next((p for p in range(MAX_SLOTS) if in_use(params, p)), 0)


MAX_SLOTS = 3  # COMPASS_MAX_INSTANCES: the compasses with a calibration (COMPASS_OFS, OFS2, OFS3)
#: ``enum Rotation`` (``libraries/AP_Math/rotations.h``) by value, those a compass or board is usually set to.
ROTATIONS = {0: "NONE", 1: "YAW_45", 2: "YAW_90", 3: "YAW_135", 4: "YAW_180", 5: "YAW_225", 6: "YAW_270",
             7: "YAW_315", 8: "ROLL_180", 9: "ROLL_180_YAW_45", 10: "ROLL_180_YAW_90", 11: "ROLL_180_YAW_135",
             12: "PITCH_180", 13: "ROLL_180_YAW_225", 14: "ROLL_180_YAW_270", 15: "ROLL_180_YAW_315",
             24: "PITCH_90", 25: "PITCH_270", 100: "CUSTOM"}


def slot_of(params: dict, priority: int) -> int:
    """The parameter slot (0-based: ``COMPASS_OFS``, ``OFS2``, ``OFS3``...) of the compass that Copter 4.x
    logs as ``MAG`` instance ``priority``.

    ``MAG.I`` is the compass's priority (``Compass::Write_Compass_instance`` logs ``get_field(i)``,
    read through ``_get_state(Priority(i))``); the parameters belong to a state slot, the one whose
    ``COMPASS_DEV_IDn`` is the device ``COMPASS_PRIO{priority + 1}_ID`` names
    (``Compass::_get_state_id``). ``Compass::_reorder_compass_params`` swaps the slots at boot so
    that they match the priorities, so the two agree on a log unless a device was replaced. Logs
    without priorities (up to Copter 3.6) number their compasses by slot."""
    device = int(params.get(f"COMPASS_PRIO{priority + 1}_ID", 0))
    if device:
        for slot in range(MAX_SLOTS):
            if int(params.get(f"COMPASS_DEV_ID{suffix(slot)}", 0)) == device:
                return slot
    return priority


def priority_of(params: dict, slot: int) -> int | None:
    """The priority (0-based) of the compass of parameter ``slot``: the ``n`` whose
    ``COMPASS_PRIO{n+1}_ID`` is its ``COMPASS_DEV_IDn`` (the inverse of :func:`slot_of`); None in a log
    without priorities (up to Copter 3.6)."""
    device = int(params.get(f"COMPASS_DEV_ID{suffix(slot)}", 0))
    if not any(f"COMPASS_PRIO{n + 1}_ID" in params for n in range(MAX_SLOTS)):
        return None
    found = [n for n in range(MAX_SLOTS) if device and int(params.get(f"COMPASS_PRIO{n + 1}_ID", 0)) == device]
    return found[0] if found else slot


def in_use(params: dict, priority: int) -> bool:
    """``COMPASS_USEn`` of the compass at ``priority`` (0-based; absent: used, the firmware's default).
    From 4.0 the ``USE`` parameters follow the priorities, not the slots (``Compass::_use_for_yaw``
    is indexed by ``Priority``)."""
    return bool(params.get(f"COMPASS_USE{suffix(priority)}", 1))


def external(params: dict, slot: int) -> bool | None:
    """``COMPASS_EXTERNAL`` (slot 0) or ``COMPASS_EXTERNn`` of ``slot``; None when not logged."""
    value = params.get("COMPASS_EXTERNAL" if slot == 0 else f"COMPASS_EXTERN{slot + 1}")
    return None if value is None else bool(value)


def rotation_name(value) -> str:
    """``enum Rotation``'s name of ``value`` (``6 (YAW_270)``)."""
    return f"{int(value)} ({ROTATIONS.get(int(value), 'see rotations.h')})"


def setup(params: dict, slot: int, priority: int | None, rule: Rules) -> dict:
    """How the firmware is set up to use the compass of parameter ``slot`` (and ``priority``, 0-based,
    None before 4.0), as ``log info`` prints it: ``priority`` (1-based; 3.x: whether it is
    ``COMPASS_PRIMARY``), ``use`` (``COMPASS_USEn``), ``orientation`` (the parameter that rotates it:
    ``COMPASS_ORIENTn`` for an external compass, ``AHRS_ORIENTATION`` for an internal one,
    ``AP_Compass_Backend::rotate_field``), ``scale`` (``COMPASS_SCALEn`` as ``correct_field`` applies
    it) and ``device_id`` (``COMPASS_DEV_IDn``)."""
    use_index = slot if priority is None else priority
    outside = external(params, slot)
    name = orientation_parameter(slot, outside)
    value = params.get(name, 0)
    where = {True: "external", False: "internal", None: "location not logged"}[outside]
    if priority is None:
        order = "primary" if int(params.get("COMPASS_PRIMARY", 0)) == slot else "secondary"
    else:
        order = f"{priority + 1} (COMPASS_PRIO{priority + 1}_ID)"
    logged = params.get(f"COMPASS_SCALE{suffix(slot)}")
    if not rule.scale:
        scale = "none (before Copter 4.0)"
    elif logged is None:
        scale = "1 (not logged)"
    else:
        scale = f"{scale_factor(params, slot, rule):.4g} (COMPASS_SCALE{suffix(slot)} = {logged:.4g})"
    device = params.get(f"COMPASS_DEV_ID{suffix(slot)}")
    use_name = f"COMPASS_USE{suffix(use_index)}"
    return {"priority": order, "use": f"{'yes' if in_use(params, use_index) else 'no'} "
                                      f"({use_name} = {int(params.get(use_name, 1))})",
            "orientation": f"{where}, {name} = {rotation_name(value)}", "scale": scale,
            "parameters": f"slot {slot + 1} (COMPASS_OFS{suffix(slot)}_*)",
            **({} if device is None else {"device_id": str(int(device))})}


def enabling(params: dict, slot: int, priority: int | None) -> dict:
    """What a compass the log's firmware does not use (``COMPASS_USEn = 0``) needs to be used, as
    parameters: ``COMPASS_USEn = 1`` (``Compass::use_for_yaw``) and its ``COMPASS_DEV_IDn`` as
    detected (``Compass::configured`` refuses a compass whose stored device id differs from the
    detected one, or whose offsets are all zero); empty for a compass in use."""
    use_index = slot if priority is None else priority
    if in_use(params, use_index):
        return {}
    found = {f"COMPASS_USE{suffix(use_index)}": 1}
    device = params.get(f"COMPASS_DEV_ID{suffix(slot)}")
    if device:
        found[f"COMPASS_DEV_ID{suffix(slot)}"] = int(device)
    return found


def orientation_parameter(compass: int, external: bool | None) -> str:
    """The parameter that rotates compass ``compass`` into the body frame (``rotate_field``):
    ``COMPASS_ORIENT*`` for an external compass, ``AHRS_ORIENTATION`` for an internal one."""
    return f"COMPASS_ORIENT{suffix(compass)}" if external else "AHRS_ORIENTATION"
