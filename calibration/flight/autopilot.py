"""A flight calibration as ArduPilot and PX4 parameters, and the corrections those autopilots
apply with them (to check the export against the project's own correction).

ArduPilot (``AP_Compass``), field in milligauss, compass ``k`` named ``""``, ``2``, ``3``::

    corrected = M (raw + COMPASS_OFS) + COMPASS_MOT * x

``M`` from ``COMPASS_DIA*`` and ``COMPASS_ODI*`` (all-zero diagonal: identity); ``x`` the current
(A, ``COMPASS_MOTCT = 2``) or the throttle (0..1, ``COMPASS_MOTCT = 1``).

PX4 (``sensor_calibration::Magnetometer``), field in gauss, compass ``k`` as ``CAL_MAGk_*``::

    corrected = S ((raw + CAL_MAGk_COMP * p) - CAL_MAGk_OFF)

``S`` from ``*SCALE`` and ``*ODIAG``; ``p`` the throttle (``CAL_MAG_COMP_TYP = 1``) or the battery
current in kA (``CAL_MAG_COMP_TYP = 2``). Both apply the offsets and compensation in the frame the
field was calibrated in (the body frame here; a compass with its own rotation parameter keeps it).

The project's correction is ``A^-1 (raw - b_s - K x)``; the motor vector is exported as ``-A^-1 K``
for ArduPilot (which adds it after the soft iron) and ``-K`` for PX4 (before it).
"""

from __future__ import annotations

import numpy as np

MILLIGAUSS = 1e-7  # T
GAUSS = 1e-4  # T
KILO = 1e3
AXES = "XYZ"
ARDUPILOT_MOTCT = {"throttle": 1, "current": 2}
PX4_COMP_TYPE = {"throttle": 1, "current": 2}


def _symmetric(diagonal, off) -> np.ndarray:
    return np.array([[diagonal[0], off[0], off[1]], [off[0], diagonal[1], off[2]], [off[1], off[2], diagonal[2]]])


def ardupilot_parameters(compass: int, static, model: str | None, K) -> dict:
    """ArduPilot parameters (name: value, in ArduPilot's units) of compass ``compass`` (0-based):
    ``static`` a :class:`calibration.StaticCalibration` (T), ``model`` ``"current"``,
    ``"throttle"`` or None, ``K`` its field vector (T/A or T per unit throttle)."""
    suffix = "" if compass == 0 else str(compass + 1)
    correction = np.linalg.inv(static.A)
    params = {f"COMPASS_OFS{suffix}_{a}": float(-static.b_s[i] / MILLIGAUSS) for i, a in enumerate(AXES)}
    params |= {f"COMPASS_DIA{suffix}_{a}": float(correction[i, i]) for i, a in enumerate(AXES)}
    params |= {f"COMPASS_ODI{suffix}_{a}": float(correction[i, j]) for a, (i, j) in zip(AXES, ((0, 1), (0, 2), (1, 2)),
                                                                                         strict=True)}
    params["COMPASS_MOTCT"] = ARDUPILOT_MOTCT.get(model, 0)
    motor = np.zeros(3) if model is None else -correction @ np.asarray(K, dtype=float) / MILLIGAUSS
    params |= {f"COMPASS_MOT{suffix}_{a}": float(motor[i]) for i, a in enumerate(AXES)}
    return params


def apply_ardupilot(params: dict, compass: int, raw, x) -> np.ndarray:
    """The field (T) ArduPilot's compass ``compass`` reports for ``raw`` (T, 3) (T) with ``params``;
    ``x`` (T,) the current (A) or throttle (1) as ``COMPASS_MOTCT`` says."""
    suffix = "" if compass == 0 else str(compass + 1)
    diagonal = [params[f"COMPASS_DIA{suffix}_{a}"] for a in AXES]
    M = _symmetric(diagonal if any(diagonal) else [1.0, 1.0, 1.0], [params[f"COMPASS_ODI{suffix}_{a}"] for a in AXES])
    offsets = np.array([params[f"COMPASS_OFS{suffix}_{a}"] for a in AXES])
    motor = np.array([params[f"COMPASS_MOT{suffix}_{a}"] for a in AXES]) if params["COMPASS_MOTCT"] else np.zeros(3)
    field_mG = (np.asarray(raw) / MILLIGAUSS + offsets) @ M.T + np.outer(np.asarray(x), motor)
    return field_mG * MILLIGAUSS


def px4_parameters(compass: int, static, model: str | None, K) -> dict:
    """PX4 parameters (name: value, in PX4's units) of compass ``compass`` (0-based): ``static`` a
    :class:`calibration.StaticCalibration` (T), ``model`` ``"current"``, ``"throttle"`` or None,
    ``K`` its field vector (T/A or T per unit throttle)."""
    prefix = f"CAL_MAG{compass}_"
    correction = np.linalg.inv(static.A)
    params = {f"{prefix}{a}OFF": float(static.b_s[i] / GAUSS) for i, a in enumerate(AXES)}
    params |= {f"{prefix}{a}SCALE": float(correction[i, i]) for i, a in enumerate(AXES)}
    params |= {f"{prefix}{a}ODIAG": float(correction[i, j]) for a, (i, j) in zip(AXES, ((0, 1), (0, 2), (1, 2)),
                                                                                strict=True)}
    per_unit = KILO if model == "current" else 1.0  # PX4 takes the current in kA
    comp = np.zeros(3) if model is None else -np.asarray(K, dtype=float) * per_unit / GAUSS
    params |= {f"{prefix}{a}COMP": float(comp[i]) for i, a in enumerate(AXES)}
    params["CAL_MAG_COMP_TYP"] = PX4_COMP_TYPE.get(model, 0)
    return params


def apply_px4(params: dict, compass: int, raw, x) -> np.ndarray:
    """The field (T) PX4 reports for compass ``compass``'s ``raw`` (T, 3) (T) with ``params``;
    ``x`` (T,) the current (A) or throttle (1) as ``CAL_MAG_COMP_TYP`` says."""
    prefix = f"CAL_MAG{compass}_"
    S = _symmetric([params[f"{prefix}{a}SCALE"] for a in AXES], [params[f"{prefix}{a}ODIAG"] for a in AXES])
    offsets = np.array([params[f"{prefix}{a}OFF"] for a in AXES])
    comp = np.array([params[f"{prefix}{a}COMP"] for a in AXES]) if params["CAL_MAG_COMP_TYP"] else np.zeros(3)
    power = np.asarray(x) / KILO if params["CAL_MAG_COMP_TYP"] == PX4_COMP_TYPE["current"] else np.asarray(x)
    field_G = (np.asarray(raw) / GAUSS + np.outer(power, comp) - offsets) @ S.T
    return field_G * GAUSS


def write_ardupilot(params: dict, path) -> None:
    """``params`` as an ArduPilot parameter file (``NAME,VALUE`` lines, as Mission Planner loads) at
    ``path``, written atomically (:func:`orchestrator.files.atomic_path`)."""
    from orchestrator.files import write_text

    write_text(path, "".join(f"{name},{value:.9g}\n" for name, value in params.items()))


def write_px4(params: dict, path) -> None:
    """``params`` as a QGroundControl parameter file for PX4 (tab-separated, vehicle 1) at ``path``,
    written atomically (:func:`orchestrator.files.atomic_path`)."""
    from orchestrator.files import write_text

    lines = ["# Vehicle-Id Component-Id Name Value Type\n"]
    for name, value in params.items():
        kind = 6 if isinstance(value, int) else 9  # MAV_PARAM_TYPE_INT32, REAL32
        lines.append(f"1\t1\t{name}\t{value:.9g}\t{kind}\n")
    write_text(path, "".join(lines))


def read_parameters(path) -> dict:
    """Parameters from a file written by :func:`write_ardupilot` or :func:`write_px4` at ``path``."""
    params = {}
    for line in open(path).read().splitlines():
        if not line or line.startswith("#"):
            continue
        parts = line.split("\t") if "\t" in line else line.split(",")
        name, value = (parts[2], parts[3]) if len(parts) > 2 else parts
        params[name] = int(value) if value.lstrip("-").isdigit() else float(value)
    return params
