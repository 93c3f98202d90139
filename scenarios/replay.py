"""Replay: any estimator on a recorded IMU file, scored against its reference attitude.

    python -m scenarios.replay RECORDING [--estimator explicit] [--set kP=0.5 ...]
        [--corrections] [--initial triad] [--frame ned|enu] [--field-from-data]
        [--align-heading] [--rate HZ] [--json OUT]
    python -m scenarios.replay --from-tp RESULTS_DIR --write RECORDING

The recording is read by :mod:`estimators.recording` (``.npz``, ``.mat``, ``.csv``: gyro, acc,
mag, rate, optional reference quaternion and scored samples). With a reference, the
quaternion-error RMSE (total, inclination, heading; degrees) over the scored samples is
printed, the metric of :func:`estimators.score`.

``--from-tp`` turns the results folder of a ``quadcosim run tp`` into a recording: the IMU's
samples, the true attitude as reference, the samples after the run's settling time as
scored, and the run's estimator settings in ``meta``; replaying it with no option runs that
estimator again and reproduces the run's ``quaternion_rmse_deg`` (the block and the batch path
share one compiled update). A run whose estimator ran slower than the macro step is refused;
one whose estimator inputs carried a fault (``--fault``) does not reproduce: the IMU's record
is not what the estimator saw.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from estimators import estimate, parse_corrections, recording
from orchestrator.files import write_text


def field_from_data(acc, mag, samples: int) -> dict:
    """Field references from the first ``samples`` of ``acc`` (m/s^2) and ``mag`` (N, 3, body
    axes): dip (rad, below the horizontal, from the angle between specific force and field) and
    norm (the magnetometer's unit)."""
    a, m = np.asarray(acc[:samples]), np.asarray(mag[:samples])
    cos_up = np.einsum("ij,ij->i", a, m) / (np.linalg.norm(a, axis=1) * np.linalg.norm(m, axis=1))
    return {"dip": float(np.median(np.arcsin(np.clip(-cos_up, -1, 1)))),
            "norm": float(np.median(np.linalg.norm(m, axis=1)))}


def references(frame: str, dip: float | None, norm: float | None) -> dict:
    """Gravity and Earth field for ``frame`` ("ned": x north; "enu": y north), heading to magnetic
    north, the field of ``dip`` (rad, below the horizontal) and ``norm`` (None: the lab's)."""
    from fmus import vehicle

    dip = vehicle.EARTH_FIELD_INCLINATION if dip is None else dip
    norm = vehicle.EARTH_FIELD_NORM if norm is None else norm
    horizontal, down = norm * math.cos(dip), norm * math.sin(dip)
    if frame == "ned":
        return {"gravity": (0.0, 0.0, vehicle.GRAVITY), "earth_field": (horizontal, 0.0, down)}
    if frame == "enu":
        return {"gravity": (0.0, 0.0, -vehicle.GRAVITY), "earth_field": (0.0, horizontal, -down)}
    raise ValueError(f"frame {frame!r} must be 'ned' or 'enu'")


def _value(text: str):
    try:
        return float(text)
    except ValueError:
        return text


def replay(data: dict, estimator: str | None = None, gains: dict | None = None, corrections=None,
           initial: str | None = None, frame: str | None = None, field_from_data_s: float = 0.0,
           align_heading: bool = False) -> dict:
    """Run an estimator on a loaded recording (see :func:`estimators.recording.load`).

    Settings not given come from the recording's ``meta`` (written by ``--from-tp``), then
    from the package's defaults. Returns the errors (degrees) when the recording has a
    reference, and the settings used.

    ``data``: the recording; ``estimator``, ``gains``, ``corrections`` and ``initial``
    (``"triad"`` or None): as :func:`estimators.estimate` takes them; ``frame``: ``"ned"`` or
    ``"enu"``; ``field_from_data_s`` (s): take the field's dip and norm from that first stretch
    of the data (0: the lab's field); ``align_heading``: remove the constant heading offset
    before scoring.
    """
    meta = data["meta"].get("estimator", {})
    kind = estimator or meta.get("kind", "explicit")
    settings = {
        "gains": gains if gains is not None else (meta.get("gains") if kind == meta.get("kind") else None),
        "corrections": corrections if corrections is not None else meta.get("corrections"),
        "ry": meta.get("ry", "triad"),
        "discretisation": meta.get("discretisation", "exp"),
        "initial": initial if initial is not None else meta.get("initial"),
        "q0": meta.get("q0"),
    }
    frame = frame or data["meta"].get("frame", "ned")
    dip = norm = None
    if field_from_data_s > 0:
        field = field_from_data(data["acc"], data["mag"], max(1, int(field_from_data_s * data["rate"])))
        dip, norm = field["dip"], field["norm"]
    refs = references(frame, dip, norm)
    quat = data["quat"]
    out = estimate(kind, gyro=data["gyro"], acc=data["acc"], mag=data["mag"], dt=1.0 / data["rate"],
                   gains=settings["gains"], corrections=settings["corrections"] if kind in ("explicit", "passive")
                   else None, ry=settings["ry"], discretisation=settings["discretisation"],
                   initial=settings["initial"], q0=settings["q0"], outputs=(), reference=quat, scored=data["scored"],
                   align_heading=align_heading, **refs)
    errors = {k: float(v[0]) for k, v in out.get("errors", {}).items()}
    return {"estimator": kind, **settings, "frame": frame, "dip_deg": None if dip is None else math.degrees(dip),
            "errors": errors}


def from_tp(results_dir, path) -> Path:
    """Write the recording of the ``tp`` run in the results folder ``results_dir`` to ``path``
    (see the module docstring)."""
    from estimators.core import euler_to_quaternion
    from orchestrator.result import Result
    from scenarios.tp import estimator_gains, initial_state

    results_dir = Path(results_dir)
    result = Result.from_npz(results_dir / "results.npz")
    metrics = json.loads((results_dir / "metrics.json").read_text())
    o = metrics["options"]
    if round(1.0 / (o["imu_rate"] * o["dt"])) != 1:
        raise ValueError("the estimator of this run ran slower than the macro step: its samples are not the "
                         "recorded ones; run tp with imu_rate = 1/dt")
    settle = min(o["settle"], 0.5 * o["duration"])
    meta = {"frame": "ned", "source": f"tp run {results_dir}",
            "estimator": {"kind": o["estimator"], "gains": estimator_gains(o) or None,
                          "corrections": parse_corrections(o.get("corrections", "off")), "ry": o["ry"],
                          "discretisation": o["discretisation"],
                          "q0": list(euler_to_quaternion(0.0, initial_state(o["flight"]).get("theta2_0", 0.0), 0.0))},
            "reported_quaternion_rmse_deg": metrics.get("quaternion_rmse_deg")}
    return recording.save(path, gyro=result["IMU.gyro"], acc=result["IMU.acc"], mag=result["IMU.magneto"],
                          rate=1.0 / o["dt"], quat=result["Quadrotor.q"], scored=result.time >= settle, meta=meta)


def main(argv=None) -> int:
    """Command line (see the module docstring); returns the exit status (2 on bad input).
    ``argv``: the arguments (default ``sys.argv[1:]``)."""
    parser = argparse.ArgumentParser(prog="python -m scenarios.replay", description=__doc__.splitlines()[0])
    parser.add_argument("recording", nargs="?", help=".npz, .mat or .csv recording")
    parser.add_argument("--estimator", help="linear, explicit, passive, vqf or madgwick")
    parser.add_argument("--set", action="append", default=[], metavar="GAIN=VALUE", help="a gain by name")
    parser.add_argument("--corrections", action="store_true", default=None, help="disturbance-aware corrections on")
    parser.add_argument("--initial", choices=("triad",), help="start from the TRIAD attitude of the first sample")
    parser.add_argument("--frame", choices=("ned", "enu"), help="inertial frame of the recording (default ned)")
    parser.add_argument("--field-from-data", type=float, default=0.0, metavar="SECONDS",
                        help="take the field's dip and norm from the first SECONDS of the recording")
    parser.add_argument("--align-heading", action="store_true", help="remove a constant heading offset")
    parser.add_argument("--rate", type=float, help="sampling rate (Hz), if the file has none")
    parser.add_argument("--json", help="write the result here")
    parser.add_argument("--from-tp", metavar="RESULTS_DIR", help="write a recording from a tp run's results")
    parser.add_argument("--write", metavar="RECORDING", help="with --from-tp: the recording to write")
    args = parser.parse_args(argv)
    try:
        if args.from_tp:
            if not args.write:
                parser.error("--from-tp needs --write RECORDING")
            print(from_tp(args.from_tp, args.write))
            return 0
        if not args.recording:
            parser.error("give a RECORDING (or --from-tp with --write)")
        gains = dict(item.split("=", 1) for item in args.set) if args.set else None
        gains = None if gains is None else {k.strip(): _value(v) for k, v in gains.items()}
        data = recording.load(args.recording, rate=args.rate)
        result = replay(data, args.estimator, gains, args.corrections, args.initial, args.frame,
                        args.field_from_data, args.align_heading)
    except (ValueError, FileNotFoundError) as error:
        print(f"replay: {error}", file=sys.stderr)
        return 2
    text = json.dumps(result, indent=2, default=float)
    print(text)
    if args.json:
        write_text(args.json, text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
