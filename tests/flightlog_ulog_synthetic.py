"""A small synthetic PX4 ULog written for the tests, with the topics of current PX4 firmware
(``sensor_mag`` before calibration in two instances, ``sensor_accel``, ``sensor_gyro``,
``vehicle_attitude``, ``actuator_outputs``, ``battery_status``). The messages are laid out as the
ULog format defines them (header, flag bits, formats, info, parameters, subscriptions, data);
the flight is the one of :mod:`tests.flightlog_synthetic`."""

import struct

import numpy as np
from scipy.spatial.transform import Rotation

from tests.flightlog_synthetic import (
    DELAY_S,
    EARTH_T,
    HARD_IRON_T,
    K_CURRENT_T_PER_A,
    PWM_MAX,
    PWM_MIN,
    _commands,
    _current,
    _euler,
)

GAUSS = 1e-4
TOPICS = {
    "sensor_mag": [("float", "x"), ("float", "y"), ("float", "z")],
    "sensor_accel": [("float", "x"), ("float", "y"), ("float", "z")],
    "sensor_gyro": [("float", "x"), ("float", "y"), ("float", "z")],
    "vehicle_attitude": [("float[4]", "q")],
    "actuator_outputs": [("uint32_t", "noutputs"), ("float[16]", "output")],
    "battery_status": [("float", "voltage_v"), ("float", "current_a")],
}
PACK = {"float": "f", "uint32_t": "I"}


def _message(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def _key_value(key: str, value: bytes) -> bytes:
    return struct.pack("<B", len(key)) + key.encode() + value


def _definitions(params: dict, hardware: str, release: str = "v1.15.0") -> bytes:
    out = b"ULog\x01\x12\x35" + struct.pack("<BQ", 1, 0)
    out += _message(b"B", bytes(16) + struct.pack("<QQQ", 0, 0, 0))
    for name, fields in TOPICS.items():
        text = f"{name}:uint64_t timestamp;" + "".join(f"{t} {n};" for t, n in fields)
        out += _message(b"F", text.encode())
    for key, value in (("sys_name", "PX4"), ("ver_hw", hardware), ("ver_sw_release", release)):
        out += _message(b"I", _key_value(f"char[{len(value)}] {key}", value.encode()))
    for name, value in params.items():
        packed = struct.pack("<i", value) if isinstance(value, int) else struct.pack("<f", value)
        out += _message(b"P", _key_value(f"{'int32_t' if isinstance(value, int) else 'float'} {name}", packed))
    return out


def _data(msg_id: int, topic: str, t_us: int, values) -> bytes:
    payload = struct.pack("<HQ", msg_id, t_us)
    for (kind, _), value in zip(TOPICS[topic], values, strict=True):
        base, _, count = kind.partition("[")
        n = int(count.rstrip("]")) if count else 1
        payload += struct.pack("<" + PACK[base] * n, *(np.atleast_1d(value) if count else [value]))
    return _message(b"D", payload)


#: The PWM limits (us) of each ``pwm`` layout of :func:`write_ulog`: PX4 1.11 and 1.12's global pair, 1.13
#: and later's one pair an output, and none logged (an older PX4 at its defaults, 1000 and 2000 us).
PWM_LAYOUTS = {"global": (PWM_MIN, PWM_MAX), "per_output": (1100.0, 1900.0), None: (1000.0, 2000.0)}


def write_ulog(path, duration=40.0, hardware="PX4_SITL", seed=2, pwm="global"):
    """Write the synthetic flight to ``path`` (ULog) and return its truth (see :func:`write_log`).

    ``pwm`` (a key of :data:`PWM_LAYOUTS`) is how its PWM limits are logged: ``"global"``
    (``PWM_MAIN_MIN/MAX``), ``"per_output"`` (``PWM_MAIN_MINn/MAXn``) or None (no limit logged, the
    outputs within PX4's defaults, an older release: ``v1.11.3``); the truth holds the commands'
    ``pwm_limits`` (us)."""
    rng = np.random.default_rng(seed)
    low, high = PWM_LAYOUTS[pwm]
    limits = {"global": {"PWM_MAIN_MIN": low, "PWM_MAIN_MAX": high},
              "per_output": {f"PWM_MAIN_{kind}{n}": value for n in range(1, 5)
                             for kind, value in (("MIN", low), ("MAX", high))}, None: {}}[pwm]
    params = {**limits, "MAV_TYPE": 2,
              **{f"CAL_MAG0_{a}OFF": float(HARD_IRON_T[i] / GAUSS) for i, a in enumerate("XYZ")}}
    subscriptions = [("sensor_mag", 0), ("sensor_mag", 1), ("sensor_accel", 0), ("sensor_gyro", 0),
                     ("vehicle_attitude", 0), ("actuator_outputs", 0), ("battery_status", 0)]
    out = bytearray(_definitions(params, hardware, "v1.15.0" if pwm else "v1.11.3"))
    for msg_id, (topic, multi) in enumerate(subscriptions):
        out += _message(b"A", struct.pack("<BH", multi, msg_id) + topic.encode())
    t = np.arange(1.0, duration, 0.01)
    euler, rates = _euler(t, 1.0)
    R = Rotation.from_euler("ZYX", euler[:, ::-1]).as_matrix()
    roll, pitch = euler[:, 0], euler[:, 1]
    gyro = np.column_stack([rates[:, 0] - rates[:, 2] * np.sin(pitch),
                            rates[:, 1] * np.cos(roll) + rates[:, 2] * np.cos(pitch) * np.sin(roll),
                            -rates[:, 1] * np.sin(roll) + rates[:, 2] * np.cos(pitch) * np.cos(roll)])
    acc = np.einsum("tji,j->ti", R, [0.0, 0.0, -9.81])
    q = Rotation.from_matrix(R).as_quat(scalar_first=True)
    for k, time in enumerate(t):
        us = int(time * 1e6)
        out += _data(3, "sensor_gyro", us, gyro[k]) + _data(2, "sensor_accel", us + 1, acc[k])
        out += _data(4, "vehicle_attitude", us + 2, [q[k]])
        if k % 2 == 0:  # 50 Hz
            body = R[k].T @ EARTH_T + HARD_IRON_T + K_CURRENT_T_PER_A * _current(time - DELAY_S)
            for instance in (0, 1):
                noisy = (body + rng.normal(0.0, 0.1e-6, 3)) / GAUSS
                out += _data(instance, "sensor_mag", us + 3 + instance, noisy)
            outputs = np.zeros(16)
            outputs[:4] = low + (high - low) * _commands(np.array([time]))[0]
            out += _data(5, "actuator_outputs", us + 5, [4, outputs])
            out += _data(6, "battery_status", us + 6, [16.0 - 0.02 * _current(time), _current(time)])
    path.write_bytes(bytes(out))
    return {"K": K_CURRENT_T_PER_A, "delay": DELAY_S, "hard_iron": HARD_IRON_T, "pwm_limits": (low, high)}
