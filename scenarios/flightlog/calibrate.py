"""``quadcosim calibrate FILE [FILE...] --compass N --out DIR``: a magnetometer calibration from
real flights, validated out of sample, exported as ArduPilot and PX4 parameters.

Validation: ``--test-fraction F`` (default 0.5) keeps the last fraction of each flight for
testing; ``--train FILES --test FILES`` trains on some flights of one vehicle and tests on others.
Outputs in DIR: ``metrics.json``, ``calibration.json`` (the project's format, for ``tp``'s
``calibration=`` option), ``ardupilot.parm``, ``px4.params``, ``residual.png`` and ``heading.png``.
"""

from __future__ import annotations

import sys
from pathlib import Path

FIGURES = ("residual.png", "heading.png")
PARAMETER_FILES = ("ardupilot.parm", "px4.params")


def _parts(files, compass: int, attitude: str, verb: str):
    from calibration.flight import flight_data
    from scenarios.flightlog.command import load

    return [flight_data(load(f, verb), compass, attitude) for f in files]


def _split(args):
    """Training and test parts, from --train/--test or from --test-fraction."""
    if bool(args.train) != bool(args.test):
        raise ValueError("--train and --test go together: give both lists of flights, or neither")
    if args.train:
        return (_parts(args.train, args.compass, args.attitude, "calibrate"),
                _parts(args.test, args.compass, args.attitude, "calibrate"))
    if not args.files:
        raise ValueError("give FILE(s) to calibrate from, or --train FILES --test FILES")
    if not 0.0 < args.test_fraction < 1.0:
        raise ValueError(f"--test-fraction {args.test_fraction} must lie strictly between 0 and 1")
    flights = _parts(args.files, args.compass, args.attitude, "calibrate")
    pairs = [f.split(args.test_fraction) for f in flights]
    return [p[0] for p in pairs], [p[1] for p in pairs]


def exported_model(fitted: dict) -> str | None:
    """The model the autopilots' parameters carry, of the ``fitted`` models (name: Fitted): the
    current model when identified (both autopilots recommend it), else the throttle model, else none."""
    return next((name for name in ("current", "throttle") if name in fitted), None)


def _write(out: Path, train, test, metrics, calibration, fitted, compass: int) -> list[str]:
    from calibration.flight import autopilot
    from orchestrator.files import write_json
    from scenarios.flightlog.calibration_figures import heading_figure, residual_figure

    model = exported_model(fitted)
    K = None if model is None else fitted[model].extra["K"][0]
    ardupilot = autopilot.ardupilot_parameters(compass, calibration.static, model, K)
    px4 = autopilot.px4_parameters(compass, calibration.static, model, K)
    autopilot.write_ardupilot(ardupilot, out / PARAMETER_FILES[0])
    autopilot.write_px4(px4, out / PARAMETER_FILES[1])
    calibration.save(out / "calibration.json")
    files = ["metrics.json", "calibration.json", *PARAMETER_FILES]
    metrics["exported_model"] = model
    if model is not None:
        name = Path(train[0].source).name
        residual_figure(test, fitted[model], model, out / FIGURES[0],
                        f"{name}: field residual on the held-out part, before and after the {model} model")
        whole = train[0] if len(train) == len(test) and train[0].log is test[0].log else test[0]
        cut = test[0].time[0] if whole is train[0] else whole.time[0]
        if whole is train[0]:
            from calibration.flight import flight_data

            whole = flight_data(train[0].log, compass, metrics["attitude"])
        heading_figure(whole, fitted[model], model, cut, out / FIGURES[1],
                       f"{Path(whole.source).name}: heading from the compass against the log's, "
                       f"before and after the {model} model")
        files += list(FIGURES)
    metrics["files"] = files
    write_json(out / "metrics.json", metrics)
    return files


def _report(metrics: dict) -> list[str]:
    lines = [f"trained on {', '.join(metrics['train'])}; tested on {', '.join(metrics['test'])}",
             f"hard and soft iron: {metrics['static']['reason']}"]
    for name, m in metrics["models"].items():
        if "refused" in m:
            lines.append(f"  {name:9s} refused: {m['refused']}")
            continue
        lines.append(f"  {name:9s} explained {100 * m['explained_test']:5.1f} % of the test residual "
                     f"({100 * m['explained_train']:.1f} % in training), {m['perturbation_at_hover_T'] * 1e6:.2f} uT "
                     f"at hover, heading moved {m['heading_rms_change_deg']:.2f} deg RMS, delay {m['delay_s']:.2f} s")
    return lines


def run(args) -> int:
    """``quadcosim calibrate`` (``args`` from :func:`add_arguments`); 2 on bad input."""
    from calibration.flight import calibrate
    from calibration.static import CalibrationError
    from orchestrator.files import prepare_out_dir
    from orchestrator.logs import LogError

    try:
        _check_choices(args)
        out = prepare_out_dir(args.out, args.overwrite)
        train, test = _split(args)
        metrics, calibration, fitted = calibrate(train, test, tuple(args.models), args.attitude)
        files = _write(out, train, test, metrics, calibration, fitted, args.compass)
    except (LogError, CalibrationError, ValueError) as error:
        print(f"quadcosim calibrate: {error}", file=sys.stderr)
        return 2
    print("\n".join(_report(metrics)))
    print(f"exported model: {metrics['exported_model'] or 'none identified'}; {', '.join(files)} in {out}/")
    if not fitted:
        sources = ", ".join(sorted({str(Path(p.source).parent / Path(p.source).name) for p in train}))
        print(f"quadcosim calibrate: no interference model could be identified from {sources} (reasons above); "
              "the parameter files keep the log's offsets", file=sys.stderr)
        return 2
    return 0


def _check_choices(args):
    """--attitude and --models against the calibration's own names (checked here rather than by
    argparse, so that the command line's help does not import the calibration package)."""
    from calibration.flight import ATTITUDES, MODELS

    if args.attitude not in ATTITUDES:
        raise ValueError(f"--attitude {args.attitude!r} must be one of {', '.join(ATTITUDES)}")
    unknown = [m for m in args.models if m not in MODELS]
    if unknown:
        raise ValueError(f"--models: unknown {', '.join(unknown)}; the models are {', '.join(MODELS)}")


def add_arguments(parser):
    """The ``calibrate`` verb's options on ``parser`` (an argparse parser); returns it."""
    parser.add_argument("files", nargs="*", metavar="FILE", help="PX4 .ulg, ArduPilot .bin or .log flights")
    parser.add_argument("--compass", type=int, default=0, help="compass to calibrate, from 0 in the log's order")
    parser.add_argument("--out", required=True, help="folder for the results")
    parser.add_argument("--test-fraction", type=float, default=0.5,
                        help="last fraction of each flight kept for testing (default 0.5)")
    parser.add_argument("--train", nargs="+", metavar="FILE", help="flights to fit on (with --test)")
    parser.add_argument("--test", nargs="+", metavar="FILE", help="flights of the same vehicle to score on")
    parser.add_argument("--attitude", default="gyro",
                        help="attitude removing the Earth field: gyro (default: roll and pitch from the log, heading "
                             "integrated from the gyro, so not from the compass being calibrated) or log")
    parser.add_argument("--models", nargs="+", default=["current", "throttle", "motors", "metge", "dynamic"],
                        help="models to fit: current, throttle, motors, metge, dynamic (default all)")
    parser.add_argument("--overwrite", action="store_true", help="replace the results already in --out")
    parser.set_defaults(func=run)
    return parser
