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
    """Every output file, ``metrics.json`` last (in the room kept for it: a disk that fills on the
    way still takes it, listing what was not written); the files written."""
    from calibration.flight import autopilot
    from orchestrator.files import DiskFull, Reserve, write_json
    from scenarios.flightlog.calibration_figures import heading_figure, residual_figure

    reserve = Reserve(out)  # DiskFull when not even metrics.json fits: nothing is written
    files, not_written = ["metrics.json"], {}

    def keep(name, write):
        try:
            write(out / name)
            files.append(name)
        except DiskFull as error:
            not_written[name] = str(error)
        except Exception as error:  # a figure that could not be drawn: said in metrics.json, the rest kept
            not_written[name] = f"{type(error).__name__}: {error}"

    model = exported_model(fitted)
    K = None if model is None else fitted[model].extra["K"][0]
    ardupilot = autopilot.ardupilot_parameters(compass, calibration.static, model, K)
    px4 = autopilot.px4_parameters(compass, calibration.static, model, K)
    keep("calibration.json", calibration.save)
    keep(PARAMETER_FILES[0], lambda path: autopilot.write_ardupilot(ardupilot, path))
    keep(PARAMETER_FILES[1], lambda path: autopilot.write_px4(px4, path))
    metrics["exported_model"] = model
    if model is not None:
        name = Path(train[0].source).name
        keep(FIGURES[0], lambda path: residual_figure(
            test, fitted[model], model, path,
            f"{name}: field residual on the held-out part, before and after the {model} model"))
        whole = train[0] if len(train) == len(test) and train[0].log is test[0].log else test[0]
        cut = test[0].time[0] if whole is train[0] else whole.time[0]
        if whole is train[0]:
            from calibration.flight import flight_data

            whole = flight_data(train[0].log, compass, metrics["attitude"])
        keep(FIGURES[1], lambda path: heading_figure(
            whole, fitted[model], model, cut, path,
            f"{Path(whole.source).name}: heading from the compass against the log's, before and after the {model} "
            "model"))
    metrics["status"] = "failed" if not_written else "completed"
    metrics["files"] = files
    if not_written:
        metrics["files_not_written"] = not_written
    try:
        write_json(out / "metrics.json", metrics)
    except DiskFull:
        reserve.release()  # the room kept for it
        write_json(out / "metrics.json", metrics)
    finally:
        reserve.release()
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
    """``quadcosim calibrate`` (``args`` from :func:`add_arguments`): 0, 2 on bad input (nothing
    written), 1 when the disk filled while the files were written (``metrics.json`` says which
    were not). The folder is held (:func:`orchestrator.files.folder_lock`) from before its
    earlier results are replaced until ``metrics.json`` is written; signals wait while the files
    are written, so that an interrupt leaves them all with their ``metrics.json``, or nothing."""
    import contextlib

    from calibration.flight import calibrate
    from calibration.static import CalibrationError
    from orchestrator.files import prepare_out_dir
    from orchestrator.interrupts import held
    from scenarios.outputs import remove_if_empty

    out, made = Path(args.out), not Path(args.out).exists()
    try:
        _check_choices(args)
        _check_out(out, args.overwrite)  # before the flights are read; again, held, before writing
        train, test = _split(args)
        metrics, calibration, fitted = _fit(calibrate, train, test, args)
        with contextlib.ExitStack() as lock, held():
            try:
                prepare_out_dir(out, args.overwrite, lock)
                files = _write(out, train, test, metrics, calibration, fitted, args.compass)
            except BaseException:
                if made:
                    remove_if_empty(out)
                raise
    except (CalibrationError, ValueError) as error:  # LogError, FolderBusy and OutputRefused among them
        print(f"quadcosim calibrate: {error}", file=sys.stderr)
        return 2
    except OSError as error:  # not even metrics.json fitted: nothing written
        print(f"quadcosim calibrate: failed: {error}", file=sys.stderr)
        return 1
    print("\n".join(_report(metrics)))
    if metrics["status"] == "failed":
        for name, why in metrics["files_not_written"].items():
            print(f"quadcosim calibrate: {name} not written: {why}", file=sys.stderr)
        print(f"quadcosim calibrate: failed; metrics.json in {out}/ lists what was written", file=sys.stderr)
        return 1
    print(f"exported model: {metrics['exported_model'] or 'none identified'}; {', '.join(files)} in {out}/")
    if not fitted:
        sources = ", ".join(sorted({str(Path(p.source).parent / Path(p.source).name) for p in train}))
        print(f"quadcosim calibrate: no interference model could be identified from {sources} (reasons above); "
              "the parameter files keep the log's offsets", file=sys.stderr)
        return 2
    return 0


def _check_out(out: Path, overwrite: bool):
    """Refuse at once an output folder that will be refused after the flights are read and fitted."""
    from orchestrator.files import FolderBusy, busy_message, held_by, holds_results

    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out}: a file of that name exists; give a folder name")
    earlier = holds_results(out)
    if earlier and not overwrite:
        raise ValueError(f"--out {out} already holds results ({', '.join(earlier)}); give another folder "
                         "or add --overwrite to replace them")
    holder = held_by(out) if out.is_dir() else None
    if holder is not None:
        raise FolderBusy(f"--out {busy_message(out, holder)}")


def _fit(calibrate, train, test, args):
    """:func:`calibration.flight.calibrate` of the parts, a numerical library's failure named with
    the flights, its cause and the fix."""
    import numpy as np

    from calibration.static import CalibrationError

    try:
        return calibrate(train, test, tuple(args.models), args.attitude)
    except (np.linalg.LinAlgError, ValueError, FloatingPointError) as error:
        sources = ", ".join(sorted({p.source for p in [*train, *test]}))
        raise CalibrationError(f"{sources}: the fit failed ({type(error).__name__}: {error}): the flights hold too "
                               "little usable data to identify a model (values that barely vary, or a damaged log); "
                               "give longer flights with climbs, descents and turns, or --models with fewer "
                               "models") from None


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
