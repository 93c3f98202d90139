"""A small synthetic ArduPilot text log written for the tests: a simulated quad flight whose
magnetometer sees a known Earth field, hard iron and battery-current interference, with a known
delay. Nothing is copied from a real log; the file is made in the test's temporary folder.

Optionally (keywords of :func:`write_log`): a GPS fix, with the Earth field then the World
Magnetic Model's there; a firmware version; the compass parameters the firmware applied before
logging (offsets, soft iron, motor compensation, scale), applied by the firmware's own equations
written out here, not the project's; ``AHRS_TRIM`` (the logged attitude is the vehicle's); a
compass mounted at a yaw its ``COMPASS_ORIENT`` does not declare; a flight that only yaws.

The log's layout follows the firmware's era (the ``version``): up to Copter 3.6, ``MAG`` with
``MOfsX..Z`` and ``PARM`` without defaults; from 4.0, ``MAG`` with ``MOX..Z``, ``PARM`` with its
``Default`` column, ``BAT`` with ``Instance``, ``GPS`` with ``I``, the motors on the outputs
``SERVOn_FUNCTION`` names (1, 8, 5, 4, as a CubeOrange's) and, with ``internal``, a second
(internal) compass as ``MAG`` instance 1, matched to its parameter slot by ``COMPASS_PRIOn_ID`` and
``COMPASS_DEV_IDn``."""

import numpy as np
from scipy.spatial.transform import Rotation

EARTH_T = np.array([19.6e-6, -5.0e-6, 47.5e-6])  # NED
HARD_IRON_T = np.array([10e-6, -20e-6, 5e-6])  # body
K_CURRENT_T_PER_A = np.array([0.3e-6, -0.5e-6, 0.8e-6])
DELAY_S = 0.1
PWM_MIN, PWM_MAX = 1000.0, 2000.0
GPS_POSITION = (48.85, 2.35, 35.0)  # Paris: lat, lon (deg), altitude (m)
GPS_WEEK, GPS_MS = 2108, 259200000  # 2020-06-03 (GPS week and milliseconds of the week)
GPS_YEAR = 2020.42
FORMATS = [
    ("PARM", "QNf", "TimeUS,Name,Value"), ("MSG", "QZ", "TimeUS,Message"),
    ("GPS", "QBIHBcLLeeEefB", "TimeUS,Status,GMS,GWk,NSats,HDop,Lat,Lng,RAlt,Alt,Spd,GCrs,VZ,U"),
    ("CTUN", "Qffffffeccf", "TimeUS,ThI,ABst,ThO,ThH,DAlt,Alt,BAlt,DCRt,CRt,N"),
    ("IMU", "QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
    ("MAG", "QBhhhhhhhhh", "TimeUS,I,MagX,MagY,MagZ,OfsX,OfsY,OfsZ,MOfsX,MOfsY,MOfsZ"),
    ("ATT", "Qffffff", "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw"),
    ("RCOU", "QHHHH", "TimeUS,C1,C2,C3,C4"), ("BAT", "QBff", "TimeUS,Inst,Volt,Curr"),
]
# Copter 4.x's layout of the messages that changed (as a 4.3 log's FMT states them)
FORMATS_4 = {"PARM": ("QNff", "TimeUS,Name,Value,Default"),
             "GPS": ("QBBIHBcLLeeEefB", "TimeUS,I,Status,GMS,GWk,NSats,HDop,Lat,Lng,RAlt,Alt,Spd,GCrs,VZ,U"),
             "MAG": ("QBhhhhhhhhh", "TimeUS,I,MagX,MagY,MagZ,OfsX,OfsY,OfsZ,MOX,MOY,MOZ"),
             "RCOU": ("QHHHHHHHH", "TimeUS,C1,C2,C3,C4,C5,C6,C7,C8"), "BAT": ("QBff", "TimeUS,Instance,Volt,Curr")}
MOTOR_OUTPUTS_4 = (1, 8, 5, 4)  # the outputs of motors 1 to 4 (SERVOn_FUNCTION 33 to 36) in the 4.x layout
DEVICES = (658953, 590114)  # COMPASS_DEV_ID of the external and the internal compass (a CubeOrange's)
HARD_IRON_INTERNAL_T = np.array([-15e-6, -3e-6, 44e-6])  # the internal compass: near the board's power
K_INTERNAL_T_PER_A = np.array([-0.9e-6, 0.5e-6, 0.8e-6])


def _euler(t, tumble: float):
    """Roll, pitch, yaw (rad) and their rates: two slow turns, rocking of ``tumble`` times a
    gentle amplitude (1: a multirotor's flight; 10: the sensor turned through most orientations)."""
    a_roll, a_pitch = 0.12 * tumble, min(0.1 * tumble, 1.2)
    roll, pitch, yaw = a_roll * np.sin(0.9 * t), a_pitch * np.sin(0.6 * t + 1.0), 0.2 * t
    rates = np.column_stack([0.9 * a_roll * np.cos(0.9 * t), 0.6 * a_pitch * np.cos(0.6 * t + 1.0),
                             np.full_like(t, 0.2)])
    return np.column_stack([roll, pitch, yaw]), rates


def _current(t):
    return 12.0 + 6.0 * np.sin(0.45 * t) + 3.0 * np.sin(1.7 * t)


def _commands(t):
    base = 0.35 + 0.012 * _current(t)
    return np.column_stack([base + 0.05 * np.sin(0.8 * t + n) for n in range(4)])


def model_earth() -> np.ndarray:
    """The World Magnetic Model's field (NED, T) at :data:`GPS_POSITION` in :data:`GPS_YEAR`."""
    from pygeomag import GeoMag

    r = GeoMag(base_year=int(GPS_YEAR)).calculate(glat=GPS_POSITION[0], glon=GPS_POSITION[1],
                                                  alt=GPS_POSITION[2] / 1e3, time=GPS_YEAR)
    return np.array([r.x, r.y, r.z]) * 1e-9


def _trim_matrix(trim) -> np.ndarray:
    return Rotation.from_euler("ZYX", [0.0, trim[1], trim[0]]).as_matrix()


def _firmware_field(raw_mG, params, version, x_current, x_throttle, slot=0):
    """ArduPilot's ``correct_field``, written out from its source (not the project's code): the
    logged field, offsets and motor offset (mG) of one sample of the compass of parameter ``slot``."""
    n = "" if slot == 0 else str(slot + 1)
    ofs = np.array([params.get(f"COMPASS_OFS{n}_{a}", 0.0) for a in "XYZ"])
    dia = np.array([params.get(f"COMPASS_DIA{n}_{a}", 0.0) for a in "XYZ"])
    odi = np.array([params.get(f"COMPASS_ODI{n}_{a}", 0.0) for a in "XYZ"])
    if not dia.any():
        dia = np.ones(3)
    M = np.array([[dia[0], odi[0], odi[1]], [odi[0], dia[1], odi[2]], [odi[1], odi[2], dia[2]]])
    kind = params.get("COMPASS_MOTCT", 0)
    x = x_current if kind == 2 else x_throttle if kind == 1 else 0.0
    mot = np.array([params.get(f"COMPASS_MOT{n}_{a}", 0.0) for a in "XYZ"]) * x
    scale = params.get(f"COMPASS_SCALE{n}", 1.0) if version >= (4, 0) else 1.0
    scale = scale if 1 / 1.5 <= scale <= 1.5 else 1.0  # Compass::have_scale_factor
    if version >= (3, 6):
        return M @ ((raw_mG + ofs) * scale) + mot, ofs, mot
    return M @ (raw_mG + ofs + mot), ofs, mot


def _slot_names(slot: int) -> list[str]:
    """The parameters of one compass slot (0-based) as the firmware names them."""
    n = "" if slot == 0 else str(slot + 1)
    names = [f"COMPASS_{kind}{n}_{a}" for kind in ("OFS", "DIA", "ODI", "MOT") for a in "XYZ"]
    return names + [f"COMPASS_SCALE{n}", f"COMPASS_DEV_ID{n}", f"COMPASS_ORIENT{n}",
                    "COMPASS_EXTERNAL" if slot == 0 else f"COMPASS_EXTERN{n}"]


def _slot_name(name: str, slot: int) -> str:
    """``name``, a parameter of either slot, in the other slot ``slot``'s name."""
    for own, other in zip(_slot_names(1 - slot), _slot_names(slot), strict=True):
        if name == own:
            return other
    raise KeyError(name)


def write_log(path, duration=60.0, simulator=True, seed=1, tumble=1.0, gps=False, version=(4, 5), compass=None,
              trim=(0.0, 0.0), mount_yaw_deg=0.0, orient=0, hard_iron=HARD_IRON_T, interference=True, internal=None,
              swapped=False):
    """Write the synthetic flight to ``path`` (text DataFlash) and return its truth as a dict;
    ``tumble`` scales the rocking (see :func:`_euler`; 0: a flight that only yaws), ``gps`` logs a
    fix and takes the Earth field from the World Magnetic Model there, ``version`` the Copter
    version in the banner (and the log's era: see the module's docstring), ``compass`` the compass
    parameters the firmware applied before logging, ``trim`` ``AHRS_TRIM_X/Y`` (rad),
    ``mount_yaw_deg`` a yaw of the compass its ``COMPASS_ORIENT`` (``orient``) does not declare,
    ``hard_iron`` (T) the offset in the raw field. 4.x only: ``internal``, the parameters of a
    second, internal compass (slot 2: ``COMPASS_OFS2_*``...; its own hard iron and current field),
    logged as ``MAG`` instance 1; ``swapped`` stores the two compasses' parameters in each other's
    slot (``COMPASS_DEV_ID`` the internal's), as the priorities ``COMPASS_PRIOn_ID`` say."""
    rng = np.random.default_rng(seed)
    earth = model_earth() if gps else EARTH_T
    compass = dict(compass or {})
    era4 = tuple(version) >= (4, 0)
    formats = [(name, *FORMATS_4[name]) if era4 and name in FORMATS_4 else (name, fmt, cols)
               for name, fmt, cols in FORMATS]
    lines = ["FMT, 128, 89, FMT, BBnNZ, Type,Length,Name,Format,Columns"]
    lines += [f"FMT, {129 + k}, 64, {name}, {fmt}, {cols}" for k, (name, fmt, cols) in enumerate(formats)]
    params = {"RC3_MIN": PWM_MIN, "RC3_MAX": PWM_MAX, "MOT_PWM_MIN": 0, "MOT_PWM_MAX": 0, "BATT_MONITOR": 4,
              "FRAME_CLASS": 1, "COMPASS_EXTERNAL": 1, "COMPASS_OFS_X": 0, "COMPASS_OFS_Y": 0, "COMPASS_OFS_Z": 0,
              "AHRS_TRIM_X": trim[0], "AHRS_TRIM_Y": trim[1], "COMPASS_ORIENT": orient, **compass}
    slots = (1, 0) if swapped else (0, 1)  # the parameter slot of MAG instance 0 (external) and 1 (internal)
    if era4:
        params |= {f"SERVO{n}_FUNCTION": 33 + k for k, n in enumerate(MOTOR_OUTPUTS_4)}
        params |= {"COMPASS_PRIO1_ID": DEVICES[0], "COMPASS_PRIO2_ID": DEVICES[1], "AHRS_ORIENTATION": 2}
        if internal is not None:
            own = {f"COMPASS_OFS2_{a}": 0 for a in "XYZ"} | {"COMPASS_EXTERN2": 0, **internal}
            params |= own
            params["COMPASS_DEV_ID"], params["COMPASS_DEV_ID2"] = DEVICES
            if swapped:  # the two slots' parameters change places; COMPASS_USEn follows the priorities, not slots
                params |= {_slot_name(name, 1 - slot): params.get(name, 0) for slot in (0, 1)
                           for name in _slot_names(slot)}
    if simulator:
        params["SIM_SPEEDUP"] = 1
    lines += [f"PARM, 1000, {name}, {value}" + (", 0" if era4 else "") for name, value in params.items()]
    banner = f"ArduCopter V{version[0]}.{version[1]}.0 (test)"
    lines += ["MSG, 1100, " + banner + (" SITL" if simulator else ""), "MSG, 1200, Frame: QUAD"]
    rows = []
    t_imu = np.arange(1.0, duration, 0.02)
    euler, rates = _euler(t_imu, tumble)
    R = Rotation.from_euler("ZYX", euler[:, ::-1]).as_matrix()  # the board's attitude
    roll, pitch = euler[:, 0], euler[:, 1]
    p = rates[:, 0] - rates[:, 2] * np.sin(pitch)
    q = rates[:, 1] * np.cos(roll) + rates[:, 2] * np.cos(pitch) * np.sin(roll)
    r = -rates[:, 1] * np.sin(roll) + rates[:, 2] * np.cos(pitch) * np.cos(roll)
    acc = np.einsum("tji,j->ti", R, [0.0, 0.0, -9.81])
    vehicle = Rotation.from_matrix(R @ _trim_matrix(trim).T).as_euler("ZYX")[:, ::-1]  # what ATT logs
    mount = Rotation.from_euler("z", mount_yaw_deg, degrees=True).as_matrix()
    for k, t in enumerate(t_imu):
        us = int(t * 1e6)
        rows.append((us, f"IMU, {us}, 0, {p[k]:.6f}, {q[k]:.6f}, {r[k]:.6f}, {acc[k, 0]:.4f}, {acc[k, 1]:.4f}, "
                         f"{acc[k, 2]:.4f}"))
        if k % 5 == 0:
            deg = np.degrees(vehicle[k])
            rows.append((us + 10, f"ATT, {us + 10}, {deg[0]:.3f}, {deg[0]:.3f}, {deg[1]:.3f}, {deg[1]:.3f}, "
                                  f"{deg[2] % 360:.3f}, {deg[2] % 360:.3f}"))  # the target followed: no crash
            commands = _commands(np.array([t]))[0]
            pwm = PWM_MIN + (PWM_MAX - PWM_MIN) * commands
            if era4:  # the motors on the outputs SERVOn_FUNCTION names, the others idle
                outputs = np.zeros(8)
                outputs[np.array(MOTOR_OUTPUTS_4) - 1] = pwm
                pwm = outputs
            rows.append((us + 20, f"RCOU, {us + 20}, " + ", ".join(str(int(v)) for v in np.round(pwm))))
            rows.append((us + 30, f"BAT, {us + 30}, 0, {12.0 - 0.02 * _current(t):.3f}, {_current(t):.3f}"))
            throttle = float(np.mean(commands))
            rows.append((us + 35, f"CTUN, {us + 35}, 0, 0, {throttle:.4f}, 0.4, 0, 0, 0, 0, 0, 0"))
            body = mount.T @ R[k].T @ earth + hard_iron
            if interference:
                body = body + K_CURRENT_T_PER_A * _current(t - DELAY_S)
            raw_mG = (body + rng.normal(0.0, 0.1e-6, 3)) / 1e-7
            field, ofs, mot = _firmware_field(raw_mG, params, version, _current(t), throttle, slots[0])
            values = [*np.round(field), *np.round(ofs), *np.round(mot)]
            rows.append((us + 40, f"MAG, {us + 40}, 0, " + ", ".join(str(int(v)) for v in values)))
            if era4 and internal is not None:
                inside = R[k].T @ earth + HARD_IRON_INTERNAL_T + K_INTERNAL_T_PER_A * _current(t - DELAY_S)
                raw_mG = (inside + rng.normal(0.0, 0.1e-6, 3)) / 1e-7
                field, ofs, mot = _firmware_field(raw_mG, params, version, _current(t), throttle, slots[1])
                values = [*np.round(field), *np.round(ofs), *np.round(mot)]
                rows.append((us + 45, f"MAG, {us + 45}, 1, " + ", ".join(str(int(v)) for v in values)))
            if gps:
                lat, lon, alt = GPS_POSITION
                instance = "0, " if era4 else ""
                rows.append((us + 50, f"GPS, {us + 50}, {instance}3, {GPS_MS + int(t * 1e3)}, {GPS_WEEK}, 10, 0.9, "
                                      f"{lat}, {lon}, 0, {alt}, 0, 0, 0, 1"))
    lines += [text for _, text in sorted(rows)]
    path.write_text("\n".join(lines) + "\n")
    return {"K": K_CURRENT_T_PER_A, "delay": DELAY_S, "earth": earth, "hard_iron": np.asarray(hard_iron),
            "K_internal": K_INTERNAL_T_PER_A, "hard_iron_internal": HARD_IRON_INTERNAL_T, "slots": slots}
