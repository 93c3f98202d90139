"""PX4's magnetometer calibration as the firmware applies it, and its parameters.

From PX4's source, cited by file and function:

- ``calibration::Magnetometer::Correct`` (``src/lib/sensor_calibration/Magnetometer.hpp``)::

      corrected = R (S ((raw + COMP p) - OFF))

  ``raw`` is ``sensor_mag`` in gauss (the driver's own chip rotation applied), ``OFF``
  ``CAL_MAGn_{X,Y,Z}OFF``, ``S`` from ``CAL_MAGn_{X,Y,Z}SCALE`` on the diagonal and
  ``CAL_MAGn_{X,Y,Z}ODIAG`` off it (``Magnetometer::ParametersUpdate``), ``COMP``
  ``CAL_MAGn_{X,Y,Z}COMP`` and ``R`` the rotation into the body frame: ``CAL_MAGn_ROT`` for an
  external compass, the board's rotation (``SENS_BOARD_ROT`` with ``SENS_BOARD_{X,Y,Z}_OFF``,
  ``GetBoardRotation``) for an internal one. Offsets and compensation therefore live in the
  sensor's frame, before ``R``;
- the slot ``n`` is the one whose ``CAL_MAGn_ID`` equals the sensor's device id
  (``FindCalibrationIndex``), not the order of the topics;
- ``p`` (``VehicleMagnetometer::Run``, ``src/modules/sensors/vehicle_magnetometer``): with
  ``CAL_MAG_COMP_TYP = 1`` the thrust setpoint's norm (0..1), with ``2`` (``3``) battery
  instance 0 (1)'s ``current_a`` times 0.001, in kA; 0 while disarmed.

- the priority of a sensor is ``CAL_MAGn_PRIO``, by default ``DEFAULT_EXTERNAL_PRIORITY`` (75) for
  an external sensor and ``DEFAULT_PRIORITY`` (50) for an internal one (``calibration::Magnetometer``,
  ``set_external``); ``0`` disables it: ``VehicleMagnetometer`` gives it no vote, and the sensor of
  the highest priority is the one ``vehicle_magnetometer`` carries;
- the motor outputs ``actuator_outputs`` are in us between ``PWM_MAIN_MINn``/``PWM_MAIN_MAXn`` (one
  pair per output, PX4 1.13 and later: ``pwm_out``'s ``module.yaml``, ``standard_params`` min and max),
  ``PWM_MAIN_MIN``/``PWM_MAIN_MAX`` (1.11, 1.12: ``pwm_out``'s parameters) or ``PWM_MIN``/``PWM_MAX``
  (1.9, 1.10: ``src/modules/sensors/pwm_params.c``); every one of them defaults to 1000 and 2000 us
  (:data:`PWM_DEFAULTS`), and a parameter left at its default is not always in a log's parameters.

Fields are in gauss (:data:`GAUSS`).
"""

from __future__ import annotations

import numpy as np

GAUSS = 1e-4  # T
KILO = 1e3
AXES = "XYZ"
COMP_TYPE = {"throttle": 1, "current": 2}
# rotations of PX4's (and ArduPilot's) Rotation enum handled here: (roll, pitch, yaw) in degrees
ROTATIONS = {0: (0, 0, 0), 1: (0, 0, 45), 2: (0, 0, 90), 3: (0, 0, 135), 4: (0, 0, 180), 5: (0, 0, 225),
             6: (0, 0, 270), 7: (0, 0, 315), 8: (180, 0, 0), 9: (180, 0, 45), 10: (180, 0, 90), 11: (180, 0, 135),
             12: (0, 180, 0), 13: (180, 0, 225), 14: (180, 0, 270), 15: (180, 0, 315)}


PRIORITY_DEFAULTS = {False: 50, True: 75}  # calibration::Magnetometer: DEFAULT_PRIORITY, DEFAULT_EXTERNAL_PRIORITY
PWM_DEFAULTS = (1000.0, 2000.0)  # us: PWM_MAIN_MIN(n), PWM_MAIN_MAX(n), PWM_MIN, PWM_MAX alike
#: PWM limit parameters, newest first: per output (``{n}`` the output, from 1), global, PX4 1.9's
PWM_LIMITS = (("PWM_MAIN_MIN{n}", "PWM_MAIN_MAX{n}"), ("PWM_MAIN_MIN", "PWM_MAIN_MAX"), ("PWM_MIN", "PWM_MAX"))


def priority(params: dict, n: int, external: bool) -> int:
    """The priority (0..100) of the sensor of slot ``n``: ``CAL_MAGn_PRIO`` in ``params``, else the
    firmware's default for an ``external`` or internal sensor (:data:`PRIORITY_DEFAULTS`); 0 disables it."""
    value = params.get(f"CAL_MAG{n}_PRIO")
    return PRIORITY_DEFAULTS[bool(external)] if value is None or not 0 <= int(value) <= 100 else int(value)


def pwm_limits(params: dict, outputs: int) -> tuple[np.ndarray, np.ndarray, str]:
    """The PWM limits (us) of the first ``outputs`` outputs: ``low`` (N,), ``high`` (N,) and the
    parameters they come from, the first of :data:`PWM_LIMITS` the log holds for every output, else
    the firmware's defaults (:data:`PWM_DEFAULTS`), said so."""
    for low_name, high_name in PWM_LIMITS:
        names = [(low_name.format(n=k + 1), high_name.format(n=k + 1)) for k in range(outputs)]
        if all(lo in params and hi in params for lo, hi in names):
            low = np.array([float(params[lo]) for lo, _ in names])
            high = np.array([float(params[hi]) for _, hi in names])
            if (low > 0).all() and (high > low).all():
                shown = f"{low_name}/{high_name}".replace("{n}", "n")
                return low, high, shown
    low, high = PWM_DEFAULTS
    return (np.full(outputs, low), np.full(outputs, high),
            f"PX4's defaults, {low:.0f}/{high:.0f} us (no PWM_MAIN_MINn/MAXn, PWM_MAIN_MIN/MAX or PWM_MIN/MAX logged)")


def rotation_matrix(value: int) -> np.ndarray:
    """The body-from-sensor matrix of rotation enum ``value`` (``get_rot_matrix``: Euler
    roll, pitch, yaw applied Z-Y-X); a ``ValueError`` naming the enums handled otherwise."""
    from scipy.spatial.transform import Rotation

    if int(value) not in ROTATIONS:
        raise ValueError(f"rotation {value} is not handled; rotations {min(ROTATIONS)} to {max(ROTATIONS)} are")
    roll, pitch, yaw = ROTATIONS[int(value)]
    return Rotation.from_euler("ZYX", [yaw, pitch, roll], degrees=True).as_matrix()


def slot(params: dict, device_id: int | None, order: int) -> int:
    """The calibration slot ``n`` of ``CAL_MAGn_*`` for the sensor ``device_id``
    (``FindCalibrationIndex`` over ``params``' ``CAL_MAGn_ID``); ``order`` (its topic instance) when the
    log has no device id."""
    if device_id:
        for n in range(4):
            if int(params.get(f"CAL_MAG{n}_ID", 0)) == int(device_id):
                return n
    return order


def body_rotation(params: dict, n: int, external: bool) -> np.ndarray:
    """``R`` (3, 3) of slot ``n`` in ``params``: ``CAL_MAGn_ROT`` when ``external``, the board's rotation otherwise."""
    from scipy.spatial.transform import Rotation

    if external:
        return rotation_matrix(int(params.get(f"CAL_MAG{n}_ROT", 0)))
    level = Rotation.from_euler("ZYX", [float(params.get(f"SENS_BOARD_{a}_OFF", 0.0)) for a in "ZYX"],
                                degrees=True).as_matrix()
    return level @ rotation_matrix(int(params.get("SENS_BOARD_ROT", 0)))


def scale_matrix(params: dict, n: int) -> np.ndarray:
    """``S`` (3, 3) of slot ``n`` in ``params`` (``*SCALE`` on the diagonal, default 1; ``*ODIAG`` off it)."""
    d = [float(params.get(f"CAL_MAG{n}_{a}SCALE", 1.0)) for a in AXES]
    o = [float(params.get(f"CAL_MAG{n}_{a}ODIAG", 0.0)) for a in AXES]
    return np.array([[d[0], o[0], o[1]], [o[0], d[1], o[2]], [o[1], o[2], d[2]]])


def power(params: dict, current=None, thrust=None):
    """``p`` (T,) as ``CAL_MAG_COMP_TYP`` in ``params`` says: the ``thrust`` (0..1) or the ``current``
    (A) in kA; None when off."""
    kind = int(params.get("CAL_MAG_COMP_TYP", 0))
    if kind == COMP_TYPE["throttle"]:
        return None if thrust is None else np.asarray(thrust, dtype=float)
    if kind in (2, 3):
        return None if current is None else np.asarray(current, dtype=float) / KILO
    return None


def apply(params: dict, n: int, external: bool, raw_sensor, current=None, thrust=None) -> np.ndarray:
    """The body-frame field (T, 3) (T) PX4 reports from ``raw_sensor`` (T, 3) (T, sensor frame) with
    slot ``n`` of ``params`` (``Magnetometer::Correct``); ``external``: the sensor is external;
    ``current`` (A) and ``thrust`` (0..1): the compensation's inputs (T,)."""
    raw_G = np.asarray(raw_sensor, dtype=float) / GAUSS
    offset = np.array([float(params.get(f"CAL_MAG{n}_{a}OFF", 0.0)) for a in AXES])
    comp = np.array([float(params.get(f"CAL_MAG{n}_{a}COMP", 0.0)) for a in AXES])
    p = power(params, current, thrust)
    if p is not None:
        raw_G = raw_G + np.outer(p, comp)
    field_G = ((raw_G - offset) @ scale_matrix(params, n).T) @ body_rotation(params, n, external).T
    return field_G * GAUSS


def recover_raw(params: dict, n: int, external: bool, field_body) -> np.ndarray:
    """The sensor-frame raw field (T, 3) (T) under a logged calibrated ``field_body`` (T, 3) (T) of
    slot ``n`` of ``params`` (``external``: an external sensor), with no compensation term (older
    logs record none)."""
    R = body_rotation(params, n, external)
    S = scale_matrix(params, n)
    offset = np.array([float(params.get(f"CAL_MAG{n}_{a}OFF", 0.0)) for a in AXES]) * GAUSS
    return np.linalg.solve(S, (np.asarray(field_body) @ R).T).T + offset


def parameters(n: int, offset_T, correction, model: str | None, K_T) -> dict:
    """The parameters (name: value, PX4's units) that make PX4 correct slot ``n`` as
    ``correction (raw - b) - ...``: ``offset_T`` the hard iron ``b`` (T, sensor frame),
    ``correction`` ``A^-1`` (3, 3), ``model`` ``"current"`` or ``"throttle"`` or None and ``K_T``
    the field per ampere or per unit thrust (3,) (T), exported as ``-K`` in gauss per kA or per unit."""
    prefix = f"CAL_MAG{n}_"
    correction = np.asarray(correction, dtype=float)
    params = {f"{prefix}{a}OFF": float(offset_T[i] / GAUSS) for i, a in enumerate(AXES)}
    params |= {f"{prefix}{a}SCALE": float(correction[i, i]) for i, a in enumerate(AXES)}
    params |= {f"{prefix}{a}ODIAG": float(correction[i, j])
               for a, (i, j) in zip(AXES, ((0, 1), (0, 2), (1, 2)), strict=True)}
    per_unit = KILO if model == "current" else 1.0
    comp = np.zeros(3) if model is None else -np.asarray(K_T, dtype=float).reshape(3) * per_unit / GAUSS
    params |= {f"{prefix}{a}COMP": float(comp[i]) for i, a in enumerate(AXES)}
    params["CAL_MAG_COMP_TYP"] = COMP_TYPE.get(model, 0)
    return params
