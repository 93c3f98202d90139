"""``quadcosim log example OUT``: small synthetic flight logs to try the flight-log commands on.

Three short flights of one quad (``example-a.log``, ``example-b.log``, ``example-c.log``), written
as ArduPilot DataFlash text logs (the text form of ``.bin``, which ``pymavlink``'s
``DFReader_text`` reads, as it reads a real Copter's). Each holds what the commands of the
flight-log guide use: an IMU at 50 Hz; two compasses at 10 Hz (``MAG`` instance 0, an external
one that the battery current barely moves, and instance 1, an internal one it moves by
:data:`INTERNAL_T_PER_A` with a :data:`DELAY_S` lag, as the internal compass of a real quad
does); the battery current and voltage; four motor outputs and the throttle; the autopilot's
attitude; a GPS fix; the parameters a calibration reads.

The flights are simulated here, not recorded: a vehicle rocking in roll and pitch while it turns
slowly in yaw over a site's Earth field (the World Magnetic Model's at :data:`SITE`), the current
following the throttle. They are no simulator (SITL) log, and no recording either: a text
message (:data:`STATEMENT`) says so in each, and ``quadcosim log info`` shows it. The numbers they give are the
synthetic model's, to learn the commands with; the guide's findings are real flights'.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from quadcosim.flightlogs.model import SYNTHETIC_MARK

#: Earth position of the flights: latitude, longitude (deg), altitude (m), and the date (year).
SITE = (45.19, 5.72, 210.0)
YEAR = 2024.5
GPS_WEEK, GPS_MS = 2321, 259200000  # 2024-07-03, the GPS week and milliseconds of the week
#: Field of the battery current at the internal compass (T per A, body frame) and its lag (s).
INTERNAL_T_PER_A = np.array([0.4e-6, -0.6e-6, 0.9e-6])
EXTERNAL_T_PER_A = np.array([0.02e-6, -0.01e-6, 0.03e-6])
DELAY_S = 0.1
#: Hard iron of each compass (T, body frame); the vehicle's earlier compass calibration set the
#: offsets (``COMPASS_OFS*``) against it to within :data:`OFFSET_ERROR_T`, as a flown vehicle's are.
HARD_IRON_T = (np.array([8e-6, -12e-6, 4e-6]), np.array([15e-6, 6e-6, -9e-6]))
OFFSET_ERROR_T = np.array([0.6e-6, -0.4e-6, 0.3e-6])
PWM_MIN, PWM_MAX = 1100.0, 1900.0
#: The text message that says, in the log itself, what wrote it (``quadcosim log info`` shows it).
STATEMENT = SYNTHETIC_MARK + "written by quadcosim log example (simulated; not recorded)"
FLIGHTS = ("a", "b", "c")
FORMATS = [
    ("PARM", "QNf", "TimeUS,Name,Value"), ("MSG", "QZ", "TimeUS,Message"),
    ("GPS", "QBIHBcLLeeEefB", "TimeUS,Status,GMS,GWk,NSats,HDop,Lat,Lng,RAlt,Alt,Spd,GCrs,VZ,U"),
    ("CTUN", "Qffffffeccf", "TimeUS,ThI,ABst,ThO,ThH,DAlt,Alt,BAlt,DCRt,CRt,N"),
    ("IMU", "QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
    ("MAG", "QBhhhhhhhhh", "TimeUS,I,MagX,MagY,MagZ,OfsX,OfsY,OfsZ,MOfsX,MOfsY,MOfsZ"),
    ("ATT", "Qffffff", "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw"),
    ("RCOU", "QHHHH", "TimeUS,C1,C2,C3,C4"), ("BAT", "QBff", "TimeUS,Inst,Volt,Curr"),
]


def earth_field() -> np.ndarray:
    """The World Magnetic Model's field (NED, T) at :data:`SITE` in :data:`YEAR`."""
    from pygeomag import GeoMag

    r = GeoMag(base_year=int(YEAR)).calculate(glat=SITE[0], glon=SITE[1], alt=SITE[2] / 1e3, time=YEAR)
    return np.array([r.x, r.y, r.z]) * 1e-9


def _offsets_mG() -> list[np.ndarray]:
    """Each compass's ``COMPASS_OFS*`` (mG): minus its hard iron, off by :data:`OFFSET_ERROR_T`."""
    return [np.round((-iron + OFFSET_ERROR_T) / 1e-7) for iron in HARD_IRON_T]


def _flight(t: np.ndarray, k: int):
    """Euler angles (rad, roll, pitch, yaw), body rates (rad/s), throttle (1) and current (A) of
    flight ``k`` at ``t`` (s): each flight rocks and turns at its own rates."""
    w = 1.0 + 0.15 * k
    roll, pitch = 0.15 * np.sin(0.9 * w * t), 0.12 * np.sin(0.6 * w * t + 1.0)
    yaw = 0.25 * t + 0.7 * k
    droll, dpitch, dyaw = 0.135 * w * np.cos(0.9 * w * t), 0.072 * w * np.cos(0.6 * w * t + 1.0), 0.25
    p = droll - dyaw * np.sin(pitch)
    q = dpitch * np.cos(roll) + dyaw * np.cos(pitch) * np.sin(roll)
    r = -dpitch * np.sin(roll) + dyaw * np.cos(pitch) * np.cos(roll)
    throttle = 0.45 + 0.12 * np.sin(0.45 * w * t) + 0.05 * np.sin(1.7 * t + k)
    current = 2.0 + 28.0 * (throttle - 0.25)  # A: the current follows the throttle
    return np.column_stack([roll, pitch, yaw]), np.column_stack([p, q, r]), throttle, current


def _rotation(euler: np.ndarray) -> np.ndarray:
    """Body-to-NED rotation matrices of ZYX Euler angles (N, 3: roll, pitch, yaw)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_euler("ZYX", euler[:, ::-1]).as_matrix()


def write_flight(path, k: int = 0, duration: float = 40.0, seed: int = 1) -> Path:
    """Write flight ``k`` (0, 1, 2 for a, b, c), ``duration`` seconds long, to ``path``.

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.log`` file written (replaced if there).
    k : int
        Which flight: its rates, heading and noise differ.
    duration : float
        Length of the flight (s).
    seed : int
        Seed of the sensors' noise (added to ``k``).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    rng = np.random.default_rng(seed + k)
    earth = earth_field()
    lines = ["FMT, 128, 89, FMT, BBnNZ, Type,Length,Name,Format,Columns"]
    lines += [f"FMT, {129 + j}, 64, {name}, {fmt}, {cols}" for j, (name, fmt, cols) in enumerate(FORMATS)]
    params = {"MOT_PWM_MIN": PWM_MIN, "MOT_PWM_MAX": PWM_MAX, "BATT_MONITOR": 4, "FRAME_CLASS": 1,
              "COMPASS_EXTERNAL": 1, "COMPASS_EXTERN2": 0, "COMPASS_ORIENT": 0, "COMPASS_MOTCT": 0,
              "AHRS_TRIM_X": 0, "AHRS_TRIM_Y": 0,
              **{f"COMPASS_OFS{n}_{a}": float(v) for n, ofs in zip(("", "2"), _offsets_mG(), strict=True)
                 for a, v in zip("XYZ", ofs, strict=True)}}
    lines += [f"PARM, 1000, {name}, {value}" for name, value in params.items()]
    lines += ["MSG, 1100, ArduCopter V4.5.0 (example)", "MSG, 1200, Frame: QUAD/X", f"MSG, 1300, {STATEMENT}"]
    t = np.arange(1.0, 1.0 + duration, 0.02)
    euler, rates, throttle, current = _flight(t, k)
    _, _, _, lagged = _flight(t - DELAY_S, k)
    R = _rotation(euler)
    acc = np.einsum("tji,j->ti", R, [0.0, 0.0, -9.81]) + rng.normal(0.0, 0.05, (len(t), 3))
    gyro = rates + rng.normal(0.0, 0.003, (len(t), 3))
    rows = []
    lat, lon, alt = SITE
    for i, time in enumerate(t):
        us = int(round(time * 1e6))
        rows.append(f"IMU, {us}, 0, {gyro[i, 0]:.6f}, {gyro[i, 1]:.6f}, {gyro[i, 2]:.6f}, "
                    f"{acc[i, 0]:.4f}, {acc[i, 1]:.4f}, {acc[i, 2]:.4f}")
        if i % 5:
            continue
        deg = np.degrees(euler[i])
        rows.append(f"ATT, {us + 10}, {deg[0]:.3f}, {deg[0]:.3f}, {deg[1]:.3f}, {deg[1]:.3f}, {deg[2] % 360:.3f}, "
                    f"{deg[2] % 360:.3f}")
        pwm = PWM_MIN + (PWM_MAX - PWM_MIN) * (throttle[i] + 0.03 * np.sin(0.8 * time + np.arange(4)))
        rows.append(f"RCOU, {us + 20}, " + ", ".join(str(int(v)) for v in np.round(pwm)))
        rows.append(f"BAT, {us + 30}, 0, {12.4 - 0.015 * current[i]:.3f}, {current[i]:.3f}")
        rows.append(f"CTUN, {us + 35}, 0, 0, {throttle[i]:.4f}, 0.45, 0, 0, 0, 0, 0, 0")
        for n, per_amp in enumerate((EXTERNAL_T_PER_A, INTERNAL_T_PER_A)):
            body = R[i].T @ earth + HARD_IRON_T[n] + per_amp * lagged[i] + rng.normal(0.0, 0.15e-6, 3)
            ofs = _offsets_mG()[n]
            mG = np.round(body / 1e-7 + ofs)  # logged: raw + offsets, in milligauss (no motor compensation set)
            rows.append(f"MAG, {us + 40 + n}, {n}, " + ", ".join(str(int(v)) for v in (*mG, *ofs)) + ", 0, 0, 0")
        rows.append(f"GPS, {us + 50}, 3, {GPS_MS + int(time * 1e3)}, {GPS_WEEK}, 12, 0.8, {lat}, {lon}, 0, {alt}, "
                    "0, 0, 0, 1")
    path = Path(path)
    path.write_text("\n".join(lines + rows) + "\n")
    return path


def write_examples(folder, duration: float = 40.0) -> list[Path]:
    """The three example flights, ``example-a.log`` to ``example-c.log``.

    Parameters
    ----------
    folder : str or pathlib.Path
        Where they are written (created).
    duration : float
        Length of each flight (s).

    Returns
    -------
    list of pathlib.Path
        The three files.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return [write_flight(folder / f"example-{name}.log", k, duration) for k, name in enumerate(FLIGHTS)]


def command(args) -> int:
    """``quadcosim log example OUT``: write the example logs into the folder ``OUT``.

    Parameters
    ----------
    args : argparse.Namespace
        ``out`` (the folder) and ``seconds`` (each flight's length, s).

    Returns
    -------
    int
        0, or 2 when the folder cannot be written (a file in its place, no permission).
    """
    import sys

    try:
        paths = write_examples(args.out, args.seconds)
    except OSError as error:
        print(f"quadcosim log example: cannot write into {args.out}: {error}", file=sys.stderr)
        return 2
    print("\n".join(str(p) for p in paths))
    print(f"three synthetic flights of {args.seconds:g} s (ArduPilot text logs, two compasses: 0 external, 1 internal "
          f"moved by the battery current); try: quadcosim log info {paths[0]}", file=sys.stderr)
    return 0
