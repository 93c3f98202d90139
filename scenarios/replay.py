"""Replay: any estimator on a recorded IMU file, scored against its reference attitude.

    quadcosim replay RECORDING [--estimator explicit]     (or python -m quadcosim.scenarios.replay) [--set kP=0.5 ...]
        [--corrections on|off|NAMES] [--ry reel|triad] [--discretisation exp|euler]
        [--initial triad] [--q0 Q0,Q1,Q2,Q3] [--b0 BX,BY,BZ] [--frame ned|enu]
        [--field-from-data SECONDS] [--dip DEG] [--declination DEG] [--align-heading]
        [--rate HZ] [--json] [--out FILE] [--figure FILE]
    python -m quadcosim.scenarios.replay results/tp            # a tp run's results folder, as it is
    python -m quadcosim.scenarios.replay --from-tp RESULTS_DIR --write RECORDING
    python -m quadcosim.scenarios.replay FLIGHT.ulg|.bin|.log [--compass N] [--json OUT]

A flight log (PX4 ULog, ArduPilot DataFlash) is replayed by :mod:`quadcosim.scenarios.flightlog.replay`:
every estimator, without and with the magnetometer compensation, against the autopilot's own
attitude (a reference, not the truth).

The recording is read by :mod:`quadcosim.estimators.recording` (``.npz``, ``.mat``, ``.csv``: gyro, acc,
mag, rate, optional reference quaternion and scored samples). With a reference, the
quaternion-error RMSE (total, inclination, heading; degrees) over the scored samples is
printed, the metric of :func:`quadcosim.estimators.score`, with the gains and correction settings in force
(defaults filled in; :func:`summary`); ``--json`` prints every setting and the errors as JSON
instead, ``--out FILE`` writes that JSON (``gains_in_force`` among it). ``--figure FILE`` draws
the errors sample by sample against time (PNG, SVG or PDF).

A ``tp`` run's results folder (or its ``results.npz``) is read as a recording directly: the
IMU's samples, the true attitude as reference, the samples after the run's settling time as
scored, and the run's estimator settings; with no option it runs that estimator again and
reproduces the run's ``quaternion_rmse_deg`` (the block and the batch path share one compiled
update). ``--from-tp`` writes that recording to a file. A run whose estimator ran slower than the
macro step is refused; one whose estimator inputs carried a fault (``--fault``) does not
reproduce: the IMU's record is not what the estimator saw.

Exit status: 0, or 2 with a message naming the problem for a bad file or option.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import zipfile
from pathlib import Path

import numpy as np
from quadcosim.estimators import estimate, kinds, parse_corrections, recording

from quadcosim.infra.files import write_text
from quadcosim.infra.inputs import read_small_text

FLIGHT_LOGS = (".ulg", ".bin", ".log")  # replayed by quadcosim.scenarios.flightlog.replay


def field_from_data(acc, mag, samples: int) -> dict:
    """Field references from the first ``samples`` of ``acc`` (m/s^2) and ``mag`` (N, 3, body
    axes): dip (rad, below the horizontal, from the angle between specific force and field) and
    norm (the magnetometer's unit)."""
    a, m = np.asarray(acc[:samples]), np.asarray(mag[:samples])
    cos_up = np.einsum("ij,ij->i", a, m) / (np.linalg.norm(a, axis=1) * np.linalg.norm(m, axis=1))
    return {"dip": float(np.median(np.arcsin(np.clip(-cos_up, -1, 1)))),
            "norm": float(np.median(np.linalg.norm(m, axis=1)))}


def references(frame: str, dip: float | None, norm: float | None, declination: float = 0.0) -> dict:
    """Gravity and Earth field for ``frame`` ("ned": x north; "enu": y north), heading to magnetic
    north (or to geographic north with the field's ``declination``, rad, east of north), the
    field of ``dip`` (rad, below the horizontal) and ``norm`` (None: the lab's)."""
    from quadcosim.fmus import vehicle

    dip = vehicle.EARTH_FIELD_INCLINATION if dip is None else dip
    norm = vehicle.EARTH_FIELD_NORM if norm is None else norm
    horizontal, down = norm * math.cos(dip), norm * math.sin(dip)
    north, east = horizontal * math.cos(declination), horizontal * math.sin(declination)
    if frame == "ned":
        return {"gravity": (0.0, 0.0, vehicle.GRAVITY), "earth_field": (north, east, down)}
    if frame == "enu":
        return {"gravity": (0.0, 0.0, -vehicle.GRAVITY), "earth_field": (east, north, -down)}
    raise ValueError(f"frame {frame!r} must be 'ned' or 'enu'")


def _value(text: str):
    try:
        return float(text)
    except ValueError:
        return text


def replay(data: dict, estimator: str | None = None, gains: dict | None = None, corrections=None,
           initial: str | None = None, frame: str | None = None, field_from_data_s: float = 0.0,
           align_heading: bool = False, keep_estimate: bool = False, **options) -> dict:
    """Run an estimator on a loaded recording (see :func:`quadcosim.estimators.recording.load`).

    Settings not given come from the recording's ``meta`` (a ``tp`` run's), then from the
    package's defaults. Returns the errors (degrees) when the recording has a reference, the
    settings used and the gains in force (``gains_in_force``, every gain and correction
    setting with its value).

    ``data``: the recording; ``estimator``, ``gains``, ``corrections`` and ``initial``
    (``"triad"`` or None): as :func:`quadcosim.estimators.estimate` takes them; ``frame``: ``"ned"`` or
    ``"enu"``; ``field_from_data_s`` (s): take the field's dip and norm from that first stretch
    of the data (0: the lab's field); ``align_heading``: remove the constant heading offset
    before scoring; ``keep_estimate``: also return the estimate (``q``, (N, 4), body to inertial)
    and the gravity vector of the scoring (``gravity``, m/s^2), for :func:`draw_errors`;
    ``options``: any other option of :func:`quadcosim.estimators.estimate` (``ry``, ``discretisation``,
    ``q0``, ``b0``, ``dip``, ``declination``; angles in rad).
    """
    meta = data["meta"].get("estimator") or {}
    if not isinstance(meta, dict):
        raise ValueError(f"the recording's meta: estimator = {meta!r} must be a JSON object ({{\"kind\": ..., "
                         "\"gains\": {...}}); fix or remove it")
    for key, kinds_ in (("gains", dict), ("corrections", (dict, str, bool)), ("kind", str)):
        if meta.get(key) is not None and not isinstance(meta[key], kinds_):
            raise ValueError(f"the recording's meta: estimator.{key} = {meta[key]!r} is a "
                             f"{type(meta[key]).__name__}; it must be a "
                             f"{'JSON object' if key == 'gains' else 'text' if key == 'kind' else 'setting'}")
    kind = estimator or meta.get("kind", "explicit")
    settings = {
        "gains": gains if gains is not None else (meta.get("gains") if kind == meta.get("kind") else None),
        "corrections": corrections if corrections is not None else meta.get("corrections"),
        "ry": options.pop("ry", None) or meta.get("ry", "triad"),
        "discretisation": options.pop("discretisation", None) or meta.get("discretisation", "exp"),
        "initial": initial if initial is not None else meta.get("initial"),
        "q0": options.pop("q0", None) or meta.get("q0"),
        "b0": list(options.pop("b0", None) or meta.get("b0", (0.0, 0.0, 0.0))),
    }
    frame = frame or data["meta"].get("frame", "ned")
    dip, declination = options.pop("dip", None), options.pop("declination", 0.0)
    if options:
        raise ValueError(f"unknown replay option {next(iter(options))!r}")
    norm = None
    if field_from_data_s > 0:
        field = field_from_data(data["acc"], data["mag"], max(1, int(field_from_data_s * data["rate"])))
        dip, norm = (field["dip"] if dip is None else dip), field["norm"]
    refs = references(frame, dip, norm, declination)
    member = kinds.get(kind)
    corrected = member is not None and member.lab and member.corrections is not None  # runs the corrections
    corrections_used = settings["corrections"] if corrected else None
    out = estimate(kind, gyro=data["gyro"], acc=data["acc"], mag=data["mag"], dt=1.0 / data["rate"],
                   gains=settings["gains"], corrections=corrections_used if corrected else False,
                   ry=settings["ry"], discretisation=settings["discretisation"], initial=settings["initial"],
                   q0=settings["q0"], b0=settings["b0"], outputs=("q",) if keep_estimate else (),
                   reference=data["quat"], scored=data["scored"], align_heading=align_heading, **refs)
    errors = {k: float(v[0]) for k, v in out.get("errors", {}).items()}
    result = {"estimator": kind, **settings, "frame": frame, "dip_deg": None if dip is None else math.degrees(dip),
              "gains_in_force": gains_in_force(kind, settings["gains"], corrections_used), "errors": errors}
    if keep_estimate:
        result.update(q=out["q"][0], gravity=np.asarray(refs["gravity"], dtype=float))
    return result


def draw_errors(data: dict, result: dict, path, title: str = "") -> Path:
    """The estimate's errors against the recording's reference, sample by sample: inclination
    and heading (deg) against time, the samples scored unshaded, each curve's RMS over them in
    its legend (the figures ``errors`` holds).

    Parameters
    ----------
    data : dict
        The recording, as :func:`load_any` returns it (with a reference ``quat``).
    result : dict
        :func:`replay`'s result, with ``keep_estimate=True``.
    path : str or pathlib.Path
        PNG, SVG or PDF file.
    title : str
        The figure's title (the recording's name).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    ValueError
        A recording without a reference attitude: there is no error to draw.
    """
    import matplotlib.pyplot as plt
    from quadcosim.estimators.core import error_angles

    from quadcosim.infra.files import figure_file, headless_backend, save_figure

    reference = data.get("quat")
    if reference is None or not len(reference):
        raise ValueError("--figure draws the errors against the recording's reference attitude, and this "
                         "recording has none (a quat column or array); drop --figure")
    path = figure_file(path, "replay.png", None)
    offset = math.radians(result["errors"].get("heading_offset_deg", 0.0))
    angles = np.degrees([error_angles(q, r, result["gravity"], offset) if np.all(np.isfinite(r)) else (np.nan,) * 3
                         for q, r in zip(result["q"], reference, strict=True)])
    time = np.arange(len(angles)) / data["rate"]
    headless_backend()
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(9.0, 5.2), layout="constrained")
    scored = np.asarray(data["scored"], dtype=bool).reshape(-1) if data.get("scored") is not None else None
    shaded = scored is not None and not scored.all()
    for ax, column, name in ((axes[0], 1, "inclination"), (axes[1], 2, "heading")):
        rms = result["errors"].get(f"{name}_rmse_deg")
        ax.plot(time, angles[:, column], lw=0.8)
        if shaded:
            ax.fill_between(time, 0, 1, where=~scored, transform=ax.get_xaxis_transform(), color="0.9")
        over = " over the scored samples (unshaded)" if shaded else ""
        ax.set_title(f"{name} error of {result['estimator']}" + ("" if rms is None else f": RMS {rms:.3g} deg{over}"),
                     loc="left", fontsize=9)  # a title, not a legend, covers no curve
        ax.set_ylabel("deg")
        ax.grid(True, alpha=0.3)
    axes[1].set_xlabel("time (s)")
    fig.suptitle(title, fontsize=10)
    try:
        return save_figure(fig, path, dpi=120)
    finally:
        plt.close(fig)


def gains_in_force(kind: str, gains: dict | None, corrections=None) -> dict:
    """Every gain and correction setting the filter ``kind`` runs with, defaults filled in
    (``gains`` and ``corrections`` as :func:`quadcosim.estimators.estimate` takes them)."""
    from quadcosim.estimators import reference
    from quadcosim.estimators.filters import check_gains

    if kind in reference.PUBLISHED:
        merged = reference.check_gains(kind, gains)
    else:
        member = kinds.get(kind)
        merged = check_gains(kind, gains, False if member is not None and member.corrections is None else corrections)
    return {name: float(np.asarray(value).reshape(-1)[0]) for name, value in merged.items()}


def tp_recording(results_dir) -> dict:
    """The recording of the ``tp`` run in the results folder ``results_dir``, as
    :func:`quadcosim.estimators.recording.load` returns one (see the module docstring)."""
    from quadcosim.estimators.quaternions import euler_to_quaternion
    from quadcosim.orchestrator.result import Result
    from quadcosim.scenarios.tp import estimator_gains, initial_state

    results_dir = Path(results_dir)
    stream = results_dir / "results.stream"
    if not (results_dir / "metrics.json").exists() or not ((results_dir / "results.npz").exists() or stream.is_dir()):
        raise ValueError(f"{results_dir} is not a tp results folder (no metrics.json beside a results.npz or a "
                         "results.stream/)")
    try:
        metrics = json.loads(read_small_text(results_dir / "metrics.json", "the run's metrics.json", "run tp again"))
    except (OSError, ValueError) as error:
        raise ValueError(f"{results_dir}: metrics.json is not readable ({error}); run tp again") from None
    metrics = metrics if isinstance(metrics, dict) else {"scenario": None}
    o = metrics.get("options", {})
    if metrics.get("scenario", "tp") != "tp" or "estimator" not in o:
        raise ValueError(f"{results_dir} holds a {metrics.get('scenario')!r} run, not a tp run")
    try:
        result = Result.load(results_dir)  # its results.npz, or the record it streamed
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as error:
        raise ValueError(f"{results_dir}: the run's record is not readable ({error}); run tp again") from None
    if round(1.0 / (o["imu_rate"] * o["dt"])) != 1:
        raise ValueError("the estimator of this run ran slower than the macro step: its samples are not the "
                         "recorded ones; run tp with imu_rate = 1/dt")
    missing = [name for name in ("IMU.gyro", "IMU.acc", "IMU.magneto", "Quadrotor.q") if name not in result]
    if missing:
        raise ValueError(f"{results_dir}: the run did not record {', '.join(missing)}; run tp without --record")
    settle = min(o["settle"], 0.5 * o["duration"])
    meta = {"frame": "ned", "source": f"tp run {results_dir}",
            "estimator": {"kind": o["estimator"], "gains": estimator_gains(o) or None,
                          "corrections": parse_corrections(o.get("corrections", "off")), "ry": o["ry"],
                          "discretisation": o["discretisation"],
                          "q0": list(euler_to_quaternion(0.0, initial_state(o["flight"]).get("theta2_0", 0.0), 0.0))},
            "reported_quaternion_rmse_deg": metrics.get("quaternion_rmse_deg")}
    return {"gyro": result["IMU.gyro"], "acc": result["IMU.acc"], "mag": result["IMU.magneto"], "rate": 1.0 / o["dt"],
            "quat": result["Quadrotor.q"], "scored": result.time >= settle, "meta": meta}


def from_tp(results_dir, path) -> Path:
    """Write the recording of the ``tp`` run in the results folder ``results_dir`` to ``path``
    (see the module docstring)."""
    data = tp_recording(results_dir)
    return recording.save(path, gyro=data["gyro"], acc=data["acc"], mag=data["mag"], rate=data["rate"],
                          quat=data["quat"], scored=data["scored"], meta=data["meta"])


def load_any(path, rate: float | None = None) -> dict:
    """The recording at ``path``: a recording file, or a ``tp`` run's results folder (or its
    ``results.npz``), loaded (``rate`` (Hz) overrides the file's)."""
    path = Path(path)
    folder = path if path.is_dir() else path.parent if path.name == "results.npz" else None
    if folder is not None and (folder / "metrics.json").exists():
        return tp_recording(folder)
    if path.is_dir():
        raise ValueError(f"{path} is a folder without a tp run's metrics.json; give a recording file")
    return recording.load(path, rate=rate)


def _vector(text: str, size: int, label: str) -> list:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise ValueError(f"{label} {text!r} must be {size} comma-separated numbers") from None
    if len(values) != size:
        raise ValueError(f"{label} {text!r} must be {size} comma-separated numbers")
    return values


def _parser(prog: str = "python -m quadcosim.scenarios.replay") -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=prog, description=__doc__.splitlines()[0])
    parser.add_argument("recording", nargs="?", help=".npz, .mat or .csv recording, or a tp run's results folder")
    parser.add_argument("--estimator", help=", ".join(name for name, kind in kinds.registry().items() if kind.batch))
    parser.add_argument("--set", action="append", default=[], metavar="GAIN=VALUE",
                        help="a gain or correction setting by name")
    parser.add_argument("--corrections", nargs="?", const="on", metavar="on|off|NAMES",
                        help="disturbance-aware corrections: on, off, or names (a,b=value)")
    parser.add_argument("--ry", choices=("reel", "triad"), help="passive filter's measured rotation")
    parser.add_argument("--discretisation", choices=("exp", "euler"), help="quaternion update")
    parser.add_argument("--initial", choices=("triad",), help="start from the TRIAD attitude of the first sample")
    parser.add_argument("--q0", metavar="Q0,Q1,Q2,Q3", help="initial attitude, body to inertial, scalar first")
    parser.add_argument("--b0", metavar="BX,BY,BZ", help="initial gyro-bias estimate (rad/s)")
    parser.add_argument("--frame", choices=("ned", "enu"), help="inertial frame of the recording (default ned)")
    parser.add_argument("--field-from-data", type=float, default=0.0, metavar="SECONDS",
                        help="take the field's dip and norm from the first SECONDS of the recording")
    parser.add_argument("--dip", type=float, metavar="DEG", help="the Earth field's dip below the horizontal")
    parser.add_argument("--declination", type=float, default=0.0, metavar="DEG", help="the field's declination")
    parser.add_argument("--align-heading", action="store_true", help="remove a constant heading offset")
    parser.add_argument("--rate", type=float, help="sampling rate (Hz), if the file has none")
    from quadcosim.scenarios.output_options import add_json_flag

    add_json_flag(parser, "the result as JSON on standard output, in place of the summary (of a recording) or the "
                          "table (of a flight log)")
    parser.add_argument("--out", metavar="FILE", help="also write the result to this JSON file")
    parser.add_argument("--figure", metavar="FILE",
                        help="also draw the inclination and heading errors against time (PNG, SVG or PDF; needs "
                             "a reference attitude)")
    parser.add_argument("--from-tp", metavar="RESULTS_DIR", help="write a recording from a tp run's results")
    parser.add_argument("--write", metavar="RECORDING", help="with --from-tp: the recording to write")
    parser.add_argument("--compass", type=int, default=0, help="flight logs: the compass, from 0 in the log's order")
    return parser


def _options(args) -> dict:
    options = {"ry": args.ry, "discretisation": args.discretisation, "declination": math.radians(args.declination)}
    if args.q0:
        options["q0"] = _vector(args.q0, 4, "--q0")
    if args.b0:
        options["b0"] = _vector(args.b0, 3, "--b0")
    if args.dip is not None:
        options["dip"] = math.radians(args.dip)
    return options


def main(argv=None) -> int:
    """``python -m quadcosim.scenarios.replay``, the same as ``quadcosim replay``: :func:`command`'s
    exit code, its errors printed (2 on bad input).

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default ``sys.argv[1:]``).
    """
    from quadcosim.infra.command import Command

    return Command("quadcosim replay").run(command, argv)


def command(argv=None, prog: str = "quadcosim replay") -> int:
    """``quadcosim replay`` (see the module docstring); returns 0, raises a
    :class:`~quadcosim.infra.errors.UsageError` on bad input (exit 2).

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default ``sys.argv[1:]``).
    prog : str
        The command as its help names it.
    """
    from quadcosim.infra.errors import refusals

    parser = _parser(prog)
    args = parser.parse_args(argv)
    if args.recording and Path(args.recording).suffix.lower() in FLIGHT_LOGS:
        from quadcosim.scenarios.flightlog import replay as flight

        return flight.run(argparse.Namespace(file=args.recording, compass=args.compass, json=args.json, out=args.out))
    with refusals(usage=(ValueError, OSError), failures=()):  # a file missing or unreadable, a value refused
        if args.from_tp:
            if not args.write:
                parser.error("--from-tp needs --write RECORDING")
            print(from_tp(args.from_tp, args.write))
            return 0
        if not args.recording:
            parser.error("give a RECORDING (or --from-tp with --write)")
        pairs = [item.split("=", 1) for item in args.set]
        if any(len(pair) != 2 for pair in pairs):
            raise ValueError(f"--set takes GAIN=VALUE, not {args.set}")
        gains = {k.strip(): _value(v) for k, v in pairs} if pairs else None
        corrections = None if args.corrections is None else parse_corrections(args.corrections)
        _check_numbers(args)
        if args.figure:
            from quadcosim.infra.files import figure_file

            figure_file(args.figure, "replay.png", None)  # a path refused before the replay runs
        if args.out:
            from quadcosim.infra.files import output_file

            output_file(args.out)  # a folder missing or read-only refused before the replay runs
        data = load_any(args.recording, rate=args.rate)
        _check_stretch(args, data)
        result = replay(data, args.estimator, gains, corrections, args.initial, args.frame, args.field_from_data,
                        args.align_heading, keep_estimate=bool(args.figure), **_options(args))
        estimate = {k: result.pop(k) for k in ("q", "gravity") if k in result}
        text = json.dumps(result, indent=2, default=float)
        print(text if args.json else summary(result, args.recording))
        if args.out:  # the JSON first: on a nearly full disk it fits where a figure may not
            write_text(args.out, text + "\n")
        if args.figure:
            print(f"figure: {draw_errors(data, result | estimate, args.figure, Path(args.recording).name)}",
                  file=sys.stderr)
    return 0


#: The fastest sampling a recording may give (Hz): no IMU samples faster; beyond it, rates such as
#: 1e308 overflow the sample count of a stretch.
MAX_RATE_HZ = 1e5


def _check_numbers(args) -> None:
    """Refuse a number of the command line that would mislead the replay or overflow it."""
    if args.rate is not None and not 0 < args.rate <= MAX_RATE_HZ:
        raise ValueError(f"--rate {args.rate:g}: a sampling rate is a number of Hz above 0 and at most "
                         f"{MAX_RATE_HZ:g}")
    if not 0 <= args.field_from_data < math.inf:
        raise ValueError(f"--field-from-data {args.field_from_data:g}: give the seconds (0 or more) at the start of "
                         "the recording to take the field from")
    if args.dip is not None and not -90 <= args.dip <= 90:
        raise ValueError(f"--dip {args.dip:g}: the field's dip is an angle from -90 to 90 deg below the horizontal")
    if not -360 <= args.declination <= 360:
        raise ValueError(f"--declination {args.declination:g}: give an angle in deg, from -360 to 360")


def _check_stretch(args, data: dict) -> None:
    """Refuse a recording's rate beyond :data:`MAX_RATE_HZ`, and a --field-from-data longer than it."""
    if not data["rate"] <= MAX_RATE_HZ:
        raise ValueError(f"{args.recording}: rate = {data['rate']:g} Hz is beyond any IMU's (at most "
                         f"{MAX_RATE_HZ:g} Hz); fix the recording's rate, or pass --rate")
    length = len(data["gyro"]) / data["rate"]
    if args.field_from_data > length:
        raise ValueError(f"--field-from-data {args.field_from_data:g} s is longer than the recording "
                         f"({length:.4g} s); give at most that")


def summary(result: dict, recording: str) -> str:
    """What a replay found, in a few lines: the estimator and its settings, the gains in force and
    the errors against the reference (deg) when the recording has one.

    Parameters
    ----------
    result : dict
        :func:`replay`'s result.
    recording : str
        The recording replayed, as the user named it.
    """
    from quadcosim.estimators import CORRECTIONS

    def shown(values: dict) -> str:
        return ", ".join(f"{k}={v:g}" if isinstance(v, (int, float)) else f"{k}={v}" for k, v in values.items())

    kind = kinds.get(result["estimator"])
    named = ("frame",) if kind is None or not kind.lab else ("discretisation", "frame")
    named = ("ry", *named) if kind is not None and kind.reads_reel else named
    settings = [f"{k} {result[k]}" for k in named if result.get(k) is not None]
    in_force = result["gains_in_force"]
    gains = {k: v for k, v in in_force.items() if k not in CORRECTIONS}
    lines = [f"{result['estimator']} on {recording} ({', '.join(settings)})",
             f"  gains in force: {shown(gains) if gains else 'the published filter defaults'}"]
    corrections = {k: v for k, v in in_force.items() if k in CORRECTIONS and v}
    if any(k in CORRECTIONS for k in in_force):
        lines.append(f"  corrections: {shown(corrections) if corrections else 'off'}")
    errors = result["errors"]
    if errors:
        lines.append(f"  quaternion error RMS (deg): total {errors['total_rmse_deg']:.2f}, inclination "
                     f"{errors['inclination_rmse_deg']:.2f}, heading {errors['heading_rmse_deg']:.2f}"
                     + (f" (constant heading offset {errors['heading_offset_deg']:.2f} removed)"
                        if errors.get("heading_offset_deg") else ""))
    else:
        lines.append("  no reference attitude in the recording: nothing scored")
    lines.append("  (--json prints every setting as JSON; --out FILE writes it)")
    return "\n".join(lines)


if __name__ == "__main__":  # the same as quadcosim replay
    from quadcosim.infra.command import program

    program(main)
