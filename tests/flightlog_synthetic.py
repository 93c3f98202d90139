"""A small synthetic ArduPilot text log written for the tests: a simulated quad flight whose
magnetometer sees a known Earth field, hard iron and battery-current interference, with a known
delay. Nothing is copied from a real log; the file is made in the test's temporary folder."""

import numpy as np
from scipy.spatial.transform import Rotation

EARTH_T = np.array([19.6e-6, -5.0e-6, 47.5e-6])  # NED
HARD_IRON_T = np.array([10e-6, -20e-6, 5e-6])  # body
K_CURRENT_T_PER_A = np.array([0.3e-6, -0.5e-6, 0.8e-6])
DELAY_S = 0.1
PWM_MIN, PWM_MAX = 1000.0, 2000.0
FORMATS = [
    ("PARM", "QNf", "TimeUS,Name,Value"), ("MSG", "QZ", "TimeUS,Message"),
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


def write_log(path, duration=60.0, simulator=True, seed=1, tumble=1.0):
    """Write the synthetic flight to ``path`` (text DataFlash) and return its truth as a dict;
    ``tumble`` scales the rocking (see :func:`_euler`)."""
    rng = np.random.default_rng(seed)
    lines = ["FMT, 128, 89, FMT, BBnNZ, Type,Length,Name,Format,Columns"]
    lines += [f"FMT, {129 + k}, 64, {name}, {fmt}, {cols}" for k, (name, fmt, cols) in enumerate(FORMATS)]
    params = {"RC3_MIN": PWM_MIN, "RC3_MAX": PWM_MAX, "MOT_PWM_MIN": 0, "MOT_PWM_MAX": 0, "BATT_MONITOR": 4,
              "FRAME_CLASS": 1, "COMPASS_EXTERNAL": 1, "COMPASS_OFS_X": 0, "COMPASS_OFS_Y": 0, "COMPASS_OFS_Z": 0}
    if simulator:
        params["SIM_SPEEDUP"] = 1
    lines += [f"PARM, 1000, {name}, {value}" for name, value in params.items()]
    lines += ["MSG, 1100, ArduCopter V4.5.0 (test)" + (" SITL" if simulator else ""), "MSG, 1200, Frame: QUAD"]
    rows = []
    t_imu = np.arange(1.0, duration, 0.02)
    euler, rates = _euler(t_imu, tumble)
    R = Rotation.from_euler("ZYX", euler[:, ::-1]).as_matrix()
    roll, pitch = euler[:, 0], euler[:, 1]
    p = rates[:, 0] - rates[:, 2] * np.sin(pitch)
    q = rates[:, 1] * np.cos(roll) + rates[:, 2] * np.cos(pitch) * np.sin(roll)
    r = -rates[:, 1] * np.sin(roll) + rates[:, 2] * np.cos(pitch) * np.cos(roll)
    acc = np.einsum("tji,j->ti", R, [0.0, 0.0, -9.81])
    for k, t in enumerate(t_imu):
        us = int(t * 1e6)
        rows.append((us, f"IMU, {us}, 0, {p[k]:.6f}, {q[k]:.6f}, {r[k]:.6f}, {acc[k, 0]:.4f}, {acc[k, 1]:.4f}, "
                         f"{acc[k, 2]:.4f}"))
        if k % 5 == 0:
            deg = np.degrees(euler[k])
            rows.append((us + 10, f"ATT, {us + 10}, 0, {deg[0]:.3f}, 0, {deg[1]:.3f}, 0, {deg[2] % 360:.3f}"))
            pwm = PWM_MIN + (PWM_MAX - PWM_MIN) * _commands(np.array([t]))[0]
            rows.append((us + 20, f"RCOU, {us + 20}, " + ", ".join(str(int(v)) for v in np.round(pwm))))
            rows.append((us + 30, f"BAT, {us + 30}, 0, {12.0 - 0.02 * _current(t):.3f}, {_current(t):.3f}"))
            body = R[k].T @ EARTH_T + HARD_IRON_T + K_CURRENT_T_PER_A * _current(t - DELAY_S)
            logged = np.round((body + rng.normal(0.0, 0.1e-6, 3)) / 1e-7)  # milligauss, no offsets applied
            field = ", ".join(str(int(v)) for v in logged)
            rows.append((us + 40, f"MAG, {us + 40}, 0, {field}, 0, 0, 0, 0, 0, 0"))
    lines += [text for _, text in sorted(rows)]
    path.write_text("\n".join(lines) + "\n")
    return {"K": K_CURRENT_T_PER_A, "delay": DELAY_S, "earth": EARTH_T, "hard_iron": HARD_IRON_T}
