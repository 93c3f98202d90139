"""A small synthetic ArduPilot text log written for the tests: a simulated quad flight whose
magnetometer sees a known Earth field, hard iron and battery-current interference, with a known
delay. Nothing is copied from a real log; the file is made in the test's temporary folder.

Optionally (keywords of :func:`write_log`): a GPS fix, with the Earth field then the World
Magnetic Model's there; a firmware version; the compass parameters the firmware applied before
logging (offsets, soft iron, motor compensation, scale), applied by the firmware's own equations
written out here, not the project's; ``AHRS_TRIM`` (the logged attitude is the vehicle's); a
compass mounted at a yaw its ``COMPASS_ORIENT`` does not declare; a flight that only yaws."""

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


def _firmware_field(raw_mG, params, version, x_current, x_throttle):
    """ArduPilot's ``correct_field``, written out from its source (not the project's code): the
    logged field, offsets and motor offset (mG) of one sample."""
    ofs = np.array([params.get(f"COMPASS_OFS_{a}", 0.0) for a in "XYZ"])
    dia = np.array([params.get(f"COMPASS_DIA_{a}", 0.0) for a in "XYZ"])
    odi = np.array([params.get(f"COMPASS_ODI_{a}", 0.0) for a in "XYZ"])
    if not dia.any():
        dia = np.ones(3)
    M = np.array([[dia[0], odi[0], odi[1]], [odi[0], dia[1], odi[2]], [odi[1], odi[2], dia[2]]])
    kind = params.get("COMPASS_MOTCT", 0)
    x = x_current if kind == 2 else x_throttle if kind == 1 else 0.0
    mot = np.array([params.get(f"COMPASS_MOT_{a}", 0.0) for a in "XYZ"]) * x
    scale = params.get("COMPASS_SCALE", 1.0) if version >= (4, 0) else 1.0
    if version >= (3, 6):
        return M @ ((raw_mG + ofs) * scale) + mot, ofs, mot
    return M @ (raw_mG + ofs + mot), ofs, mot


def write_log(path, duration=60.0, simulator=True, seed=1, tumble=1.0, gps=False, version=(4, 5), compass=None,
              trim=(0.0, 0.0), mount_yaw_deg=0.0, orient=0, hard_iron=HARD_IRON_T, interference=True):
    """Write the synthetic flight to ``path`` (text DataFlash) and return its truth as a dict;
    ``tumble`` scales the rocking (see :func:`_euler`; 0: a flight that only yaws), ``gps`` logs a
    fix and takes the Earth field from the World Magnetic Model there, ``version`` the Copter
    version in the banner, ``compass`` the compass parameters the firmware applied before logging,
    ``trim`` ``AHRS_TRIM_X/Y`` (rad), ``mount_yaw_deg`` a yaw of the compass its ``COMPASS_ORIENT``
    (``orient``) does not declare, ``hard_iron`` (T) the offset in the raw field."""
    rng = np.random.default_rng(seed)
    earth = model_earth() if gps else EARTH_T
    compass = dict(compass or {})
    lines = ["FMT, 128, 89, FMT, BBnNZ, Type,Length,Name,Format,Columns"]
    lines += [f"FMT, {129 + k}, 64, {name}, {fmt}, {cols}" for k, (name, fmt, cols) in enumerate(FORMATS)]
    params = {"RC3_MIN": PWM_MIN, "RC3_MAX": PWM_MAX, "MOT_PWM_MIN": 0, "MOT_PWM_MAX": 0, "BATT_MONITOR": 4,
              "FRAME_CLASS": 1, "COMPASS_EXTERNAL": 1, "COMPASS_OFS_X": 0, "COMPASS_OFS_Y": 0, "COMPASS_OFS_Z": 0,
              "AHRS_TRIM_X": trim[0], "AHRS_TRIM_Y": trim[1], "COMPASS_ORIENT": orient, **compass}
    if simulator:
        params["SIM_SPEEDUP"] = 1
    lines += [f"PARM, 1000, {name}, {value}" for name, value in params.items()]
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
            rows.append((us + 20, f"RCOU, {us + 20}, " + ", ".join(str(int(v)) for v in np.round(pwm))))
            rows.append((us + 30, f"BAT, {us + 30}, 0, {12.0 - 0.02 * _current(t):.3f}, {_current(t):.3f}"))
            throttle = float(np.mean(commands))
            rows.append((us + 35, f"CTUN, {us + 35}, 0, 0, {throttle:.4f}, 0.4, 0, 0, 0, 0, 0, 0"))
            body = mount.T @ R[k].T @ earth + hard_iron
            if interference:
                body = body + K_CURRENT_T_PER_A * _current(t - DELAY_S)
            raw_mG = (body + rng.normal(0.0, 0.1e-6, 3)) / 1e-7
            field, ofs, mot = _firmware_field(raw_mG, params, version, _current(t), throttle)
            values = [*np.round(field), *np.round(ofs), *np.round(mot)]
            rows.append((us + 40, f"MAG, {us + 40}, 0, " + ", ".join(str(int(v)) for v in values)))
            if gps:
                lat, lon, alt = GPS_POSITION
                rows.append((us + 50, f"GPS, {us + 50}, 3, {GPS_MS + int(t * 1e3)}, {GPS_WEEK}, 10, 0.9, {lat}, "
                                      f"{lon}, 0, {alt}, 0, 0, 0, 1"))
    lines += [text for _, text in sorted(rows)]
    path.write_text("\n".join(lines) + "\n")
    return {"K": K_CURRENT_T_PER_A, "delay": DELAY_S, "earth": earth, "hard_iron": np.asarray(hard_iron)}
