"""The project's estimators on a real flight log, without and with the magnetometer
compensation, scored against the autopilot's own attitude.

The autopilot's attitude is a reference, not the truth: it is another estimator's output (for
ArduPilot's EKF, one that fuses the primary compass), so the differences reported are
disagreements, not errors.

How a log is replayed:

- the first IMU, resampled to a uniform period (its median sample spacing), gives gyro and
  specific force; the compass (``--compass``) is interpolated to the same instants;
- the compensation is calibrated on the first half of the flight (:func:`quadcosim.calibration.flight.calibrate`)
  and applied by :func:`quadcosim.calibration.compensate` (eq. 9 of Metge et al.) with the offsets fitted
  with its model (the log's offsets already hold the motors' mean field); without it, only the
  log's offsets are removed;
- the Earth field in NED is the compass's field rotated by the log's attitude, averaged over the
  first half; every estimator starts from the TRIAD attitude of the first sample;
- the differences are scored over the second half, the part the compensation was not fitted on.
"""

from __future__ import annotations

import numpy as np
from quadcosim.estimators import kinds

MIN_SAMPLES = 100  # IMU samples a replay needs: half of them, the second, are scored
ESTIMATORS = kinds.compared(batch=True)  # estimator -> its settings (estimators/kinds.py)
REFERENCE_NOTE = ("differences from the autopilot's own attitude estimate, a reference and not the truth "
                  "(it fuses the primary compass itself)")


def _uniform(log, compass: int):
    from quadcosim.flightlogs import LogError
    from scipy.spatial.transform import Rotation, Slerp

    imu = log.imus[0]
    chosen = log.compass(compass)
    lo, hi = log.overlap((imu.name, imu), ("attitude", log.attitude), (chosen.name, chosen))
    dt = float(np.median(np.diff(imu.time)))
    time = np.arange(lo, hi, dt)
    if len(time) < MIN_SAMPLES:
        raise LogError(f"{log.path}: {imu.name}, the attitude and {chosen.name} share {hi - lo:.1f} s "
                       f"({len(time)} IMU samples, from {lo:.1f} to {hi:.1f} s); a replay needs {MIN_SAMPLES} or more: "
                       "give a longer flight")
    gyro = np.column_stack([np.interp(time, imu.time, imu.gyro[:, k]) for k in range(3)])
    acc = np.column_stack([np.interp(time, imu.time, imu.acc[:, k]) for k in range(3)])
    rotations = Rotation.from_quat(log.attitude.q, scalar_first=True)
    reference = Slerp(log.attitude.time, rotations)(time).as_quat(scalar_first=True)
    return time, dt, gyro, acc, reference


def _fields(log, compass: int, time, model_offsets: bool = True):
    """The compass at ``time`` without and with the compensation fitted on the first half, and the
    model's name; ``model_offsets``: the model with the offsets fitted with it (False: with the
    log's, which count the motors' mean field twice; an ablation)."""
    from dataclasses import replace

    from quadcosim.calibration import compensate
    from quadcosim.calibration.flight import calibrate, flight_data

    data = flight_data(log, compass)
    train, test = data.split(0.5)
    # the calibration pairs its model with the offsets fitted with it when the log's are kept
    # (quadcosim.calibration.flight.calibrate.paired_static); without the model, the log's offsets
    metrics, calibration, _ = calibrate([train], [test], ("current", "throttle", "motors", "metge"))
    raw = np.column_stack([np.interp(time, data.time, data.raw[:, k]) for k in range(3)])
    motors = log.motors
    commands = np.column_stack([np.interp(time, motors.time, motors.commands[:, n])
                                for n in range(motors.commands.shape[1])])
    voltage = (np.interp(time, log.battery.time, log.battery.voltage) if log.battery is not None
               else np.full(len(time), np.nan))
    model = metrics["calibration_model"]
    unpaired = calibration
    if model is not None and metrics["static"]["source"] == "log":
        log_offsets = np.asarray(log.compasses[compass].offsets, dtype=float)
        unpaired = replace(calibration, static=replace(calibration.static, b_s=log_offsets))
    without = compensate(unpaired, time, raw, commands, voltage, "static")
    if model is None:
        return without, without, model
    return without, compensate(calibration if model_offsets else unpaired, time, raw, commands, voltage,
                               "metge"), model


def replay_log(path, compass: int = 0, settle_s: float = 5.0, kinds=tuple(ESTIMATORS)) -> dict:
    """Run every estimator of :data:`ESTIMATORS` on the log at ``path`` (or an already read
    :class:`quadcosim.flightlogs.FlightLog`) with compass ``compass``, without and with the
    compensation; heading and inclination RMS differences (deg) from the log's attitude over the
    second half of the flight (at least ``settle_s`` (s) after the start); ``kinds``: the
    estimators run (names of :data:`ESTIMATORS`)."""
    from quadcosim.estimators import estimate
    from quadcosim.flightlogs import FlightLog, read_log

    log = path if isinstance(path, FlightLog) else read_log(path)
    log.require("a replay", "imu", "attitude", "compass", "motors")
    time, dt, gyro, acc, reference = _uniform(log, compass)
    without, with_model, model = _fields(log, compass, time)
    from quadcosim.calibration.flight.data import rate_refusal

    refused = rate_refusal(log, compass)
    if refused:  # a compass logged too slowly for a calibration: replayed without a compensation fitted on it
        with_model, model = without, None
    half = time[0] + 0.5 * (time[-1] - time[0])
    scored = time >= max(half, time[0] + settle_s)
    first = time < half
    results = {}
    for label, mag in (("without", without), ("with", with_model)):
        from scipy.spatial.transform import Rotation

        R = Rotation.from_quat(reference[first], scalar_first=True).as_matrix()
        earth = np.einsum("tij,tj->i", R, mag[first]) / first.sum()
        for kind in kinds:
            settings = ESTIMATORS[kind]
            out = estimate(kind, gyro=gyro, acc=acc, mag=mag, dt=dt, earth_field=earth, initial="triad",
                           outputs=(), reference=reference, scored=scored, **settings)
            errors = out["errors"]
            results.setdefault(kind, {})[label] = {"heading_rms_deg": float(errors["heading_rmse_deg"][0]),
                                                   "inclination_rms_deg": float(errors["inclination_rmse_deg"][0])}
    return {"file": log.path, "compass": log.compasses[compass].name, "compensation_model": model,
            "compensation_refused": refused or "", "note": REFERENCE_NOTE, "scored_s": float(scored.sum() * dt),
            "estimators": results}


def text(result: dict) -> str:
    """The replay ``result`` as a table."""
    model = result["compensation_model"] or (f"none: {result['compensation_refused']}"
                                             if result.get("compensation_refused") else "none identified")
    lines = [f"{result['file']} ({result['compass']}), compensation: {model}",
             f"  {result['note']}; over the last {result['scored_s']:.0f} s",
             "  estimator   heading RMS (deg) without / with   inclination RMS (deg) without / with"]
    for kind, r in result["estimators"].items():
        lines.append(f"  {kind:10s}  {r['without']['heading_rms_deg']:8.2f} / {r['with']['heading_rms_deg']:<8.2f}"
                     f"            {r['without']['inclination_rms_deg']:8.2f} / {r['with']['inclination_rms_deg']:.2f}")
    return "\n".join(lines)


def _replayed(log, compass: int) -> dict:
    """:func:`replay_log` of the read ``log``, a numerical library's failure named with the file,
    its likely cause and the fix."""
    from quadcosim.calibration.static import CalibrationError
    from quadcosim.flightlogs import LogError

    from quadcosim.infra.files import OutputRefused

    try:
        return replay_log(log, compass)
    except (LogError, CalibrationError, OutputRefused):
        raise
    except (np.linalg.LinAlgError, ValueError, FloatingPointError, ZeroDivisionError) as error:
        raise LogError(f"{log.path}: the replay failed ({type(error).__name__}: {error}): the log holds too little "
                       "usable data for the estimators (a damaged stretch, a sensor that barely varies); replay a "
                       "longer, undamaged flight") from None


def run(args) -> int:
    """``quadcosim log replay FILE [--compass N] [--json] [--out FILE]`` (``args`` from argparse):
    the table, or with ``--json`` the result as JSON, on standard output, and with ``--out`` the
    result written as JSON there. Bad input (a log, an option or an output path refused) raises a
    :class:`~quadcosim.infra.errors.UsageError` (exit 2), a JSON that could not be written (a full
    disk: nothing is left under its name) a :class:`~quadcosim.infra.errors.RunError` (exit 1)."""
    from quadcosim.scenarios.flightlog.reading import load

    from quadcosim.infra.errors import refusals
    from quadcosim.infra.files import output_file, write_json

    out = getattr(args, "out", None)
    with refusals(usage=(ValueError,), failures=()):  # LogError, CalibrationError and OutputRefused among them
        if out:
            output_file(out)  # refused before the replay, not after it
        result = _replayed(load(args.file, "log replay"), args.compass)
    if getattr(args, "json", False) is True:
        import json

        print(json.dumps(result, indent=2, default=float))
    else:
        print(text(result))
    if out:
        with refusals(usage=()):
            write_json(out, result)
    return 0
