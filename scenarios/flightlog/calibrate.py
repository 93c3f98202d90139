"""``quadcosim calibrate FILE [FILE...] --compass N --out DIR``: a magnetometer calibration from
real flights, validated out of sample, exported as the log's autopilot's parameters and scored
as its firmware will apply them.

Validation: one flight: its last ``--test-fraction`` (default 0.5) is held out; several flights
(of one vehicle): the last one is held out and the others train (cross-flight, the default);
``--train FILES --test FILES`` chooses. The export is fitted on the training part, each of its
groups chosen on a choice part (one flight: the first half of the held-out part; several: the
training flights' second halves, the fit taking their first halves) and scored on a score part
neither has seen (the held-out part's second half, or the held-out flights); see :class:`Split`.
``--score PARAMS`` scores a parameter file (any tool's) on that score part instead, with the
same code that scores the export.
Outputs in DIR: ``metrics.json``, ``calibration.json`` (the project's format, for ``tp``'s
``calibration=`` option), the parameter file of the log's autopilot (``ardupilot.parm``, ``px4.params``: its ``file``),
``residual.png`` and ``heading.png``.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

FIGURES = ("residual.png", "heading.png")


def _logs(files, verb: str, span=None) -> list:
    """The logs at ``files``, each cut to ``span`` (start, end; s on its clock) when given."""
    from quadcosim.scenarios.flightlog.reading import load

    logs = [load(f, verb) for f in files]
    return logs if span is None else [_spanned(log, span) for log in logs]


def _spanned(log, span):
    """``log`` cut to ``span`` (``--span START END``, s on the log's clock); a span outside it is refused."""
    from quadcosim.flightlogs import LogError, trim

    start, end = (float(x) for x in span)
    first, last = log.start, log.start + log.duration
    if not (end > start and start < last and end > first):
        raise LogError(f"{log.path}: --span {start:g} {end:g} holds none of the log ({first:.1f} to {last:.1f} s on "
                       "its clock, as 'quadcosim log info' prints it); give a span inside it")
    return trim.cut(log, start, end, f"cut to --span {start:g} {end:g} s")


@dataclass
class Split:
    """The parts of the flights of one compass, the Earth field model attached.

    ``train``/``test``: the models' analysis (fit, and score with the Earth field and offset fitted
    again); ``fit``/``choice``/``score``: the export, fitted on ``fit``, each group chosen on
    ``choice`` and every export figure measured on ``score``, which neither has seen. One flight:
    ``train``=``fit`` its first part, ``test`` the held-out rest, ``choice`` and ``score`` that
    rest's two halves in time. Several: ``train`` the training flights, ``fit``/``choice`` their
    halves, ``test``=``score`` the held-out flights. ``notes``: the validation's description, the
    Earth field's lines and the yaw-mounting check.
    """

    train: list
    test: list
    fit: list
    choice: list
    score: list
    notes: dict


def split_parts(train_logs, test_logs, compass: int, attitude: str = "auto", trim: bool = True,
                earth: str = "model", test_fraction: float | None = None) -> Split:
    """:class:`Split` of compass ``compass`` of ``train_logs`` (FlightLogs; one alone is split in time
    with its last ``test_fraction``, default 0.5, held out) and ``test_logs`` (held-out flights, or
    empty), with the ``attitude``, ``trim`` and ``earth`` field (``model`` or ``free``) the command uses."""
    from quadcosim.calibration.flight import flight_data
    from quadcosim.calibration.flight.earth import align, model_field

    fields, notes = {}, {}
    for log in [*train_logs, *test_logs]:
        fields[log.path], notes[log.path] = (None, "the free Earth field (--earth free)") if earth == "free" \
            else model_field(log.position)

    def parts(logs):
        return [flight_data(log, compass, attitude, trim=trim) for log in logs]

    if test_logs:
        train, test = parts(train_logs), parts(test_logs)
        halves = [p.split(0.5) for p in train]
        fit, choice, score = [h[0] for h in halves], [h[1] for h in halves], test
        validation = ("cross-flight; export fitted on the first half of each training flight, chosen on their "
                      "second halves, scored on the held-out flights")
    else:
        fraction = test_fraction or 0.5
        pairs = [f.split(fraction) for f in parts(train_logs)]
        train, test = [p[0] for p in pairs], [p[1] for p in pairs]
        quarters = [p.split(0.5) for p in test]
        fit, choice, score = train, [q[0] for q in quarters], [q[1] for q in quarters]
        validation = (f"last {fraction:g} of each flight held out; export fitted on the first {1 - fraction:g}, "
                      f"chosen on the next {fraction / 2:g}, scored on the last {fraction / 2:g}")
    rest = [*test, *fit, *choice, *score]
    train, rest, check = align(train, rest, fields)
    cuts = np.cumsum([len(test), len(fit), len(choice)])
    test, fit, choice, score = (rest[:cuts[0]], rest[cuts[0]:cuts[1]], rest[cuts[1]:cuts[2]], rest[cuts[2]:])
    return Split(train, test, fit, choice, score, {"validation": validation,
                                                   "earth_field": sorted(set(notes.values())), "mounting": check})


def _split(args) -> Split:
    """The command's :class:`Split`, from its arguments."""
    if bool(args.train) != bool(args.test):
        raise ValueError("--train and --test go together: give both lists of flights, or neither")
    if not args.train and not args.files:
        raise ValueError("give FILE(s) to calibrate from, or --train FILES --test FILES")
    if args.test_fraction is not None and not 0.0 < args.test_fraction < 1.0:
        raise ValueError(f"--test-fraction {args.test_fraction} must lie strictly between 0 and 1")
    if args.train:
        train_logs, test_logs = _logs(args.train, "calibrate", args.span), _logs(args.test, "calibrate", args.span)
    else:
        logs = _logs(args.files, "calibrate", args.span)
        train_logs, test_logs = (logs, []) if len(logs) == 1 or args.test_fraction is not None else \
            (logs[:-1], logs[-1:])
    from quadcosim.calibration.flight.data import rate_refusal
    from quadcosim.calibration.static import CalibrationError

    for log in [*train_logs, *test_logs]:  # the command's floor; split_parts itself fits any rate (a measurement)
        refusal = rate_refusal(log, args.compass)
        if refusal:
            raise CalibrationError(refusal)
    return split_parts(train_logs, test_logs, args.compass, args.attitude, not args.no_trim, args.earth,
                       args.test_fraction)


def _rule(args, part):
    """The firmware rules the export follows: None (the log's own firmware), or ``--firmware``'s, read by
    the autopilot of ``part``'s log (its ``versions``; an autopilot with one set of rules ignores it).
    ``part`` None: checked against every installed autopilot that has versions, before a log is read."""
    if args.firmware is None:
        return None
    from quadcosim.flightlogs.autopilots import of, registry

    if part is not None:
        versions = of(part.log.autopilot).versions
        return None if versions is None else versions(args.firmware)
    refusals = []
    for autopilot in registry().values():
        if autopilot.versions is not None:
            try:
                return autopilot.versions(args.firmware)
            except ValueError as error:
                refusals.append(str(error))
    raise ValueError("; ".join(refusals) or f"--firmware {args.firmware!r}: no installed autopilot has firmware "
                     "versions to choose from")


def _write(out: Path, split: Split, metrics: dict, calibration, fitted: dict, export: tuple,
           attitude: str) -> list[str]:
    """Every output file, ``metrics.json`` last (in the room kept for it: a disk that fills on the
    way still takes it, listing what was not written); the files written. ``export``: the
    autopilot, the parameter file's name and its parameters."""
    from quadcosim.calibration.flight.autopilot import write_parameters

    from quadcosim.infra.files import DiskFull, Reserve, write_json

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

    autopilot, name, params = export
    keep("calibration.json", calibration.save)
    keep(name, lambda path: write_parameters(autopilot, params, path))
    analysis = next((m for m in ("current", "throttle") if m in fitted), None)
    if analysis is not None:
        for figure, draw in zip(FIGURES, _figures(split.train, split.test, fitted, analysis, attitude), strict=True):
            keep(figure, draw)
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


def _figures(train, test, fitted, model, attitude) -> tuple:
    """The drawers (path -> None) of :data:`FIGURES`: the residual on the held-out part and the
    heading over a whole flight, before and after ``model``."""
    from quadcosim.scenarios.flightlog.calibration_figures import heading_figure, residual_figure

    name = Path(train[0].source).name

    def residual(path):
        residual_figure(test, fitted[model], model, path,
                        f"{name}: field residual on the held-out part, before and after the {model} model fitted here")

    def heading(path):
        whole = train[0] if len(train) == len(test) and train[0].log is test[0].log else test[0]
        cut = test[0].time[0] if whole is train[0] else whole.time[0]
        if whole is train[0]:
            from dataclasses import replace

            from quadcosim.calibration.flight import flight_data

            whole = replace(flight_data(train[0].log, train[0].compass, attitude), earth=train[0].earth)
        heading_figure(whole, fitted[model], model, cut, path,
                       f"{Path(whole.source).name}: heading from the compass against the log's, before and after "
                       f"the {model} model fitted here")

    return residual, heading


def _export(args, split: Split, metrics: dict) -> tuple:
    """The parameters of the log's autopilot chosen and scored (:mod:`quadcosim.calibration.flight.export`),
    described in ``metrics["export"]``; (autopilot, file name, parameters)."""
    from quadcosim.calibration.flight.autopilot import autopilot_of
    from quadcosim.calibration.flight.export import choose, judge, log_parameters, score_parameters

    train, score = split.train, split.score
    rule = _rule(args, split.test[0])
    params, chosen = choose(split.fit, split.choice, rule)
    autopilot = autopilot_of(train[0])
    name = autopilot.file
    flown_params = log_parameters(score[0], params)
    unscored = [*split.fit, *split.choice]  # where each candidate's heading offset is estimated
    flown = score_parameters(score, flown_params, rule, offset_from=unscored)
    exported = score_parameters(score, params, rule, offset_from=unscored)
    params, exported, kept_why = judge(score[0], params, exported, flown_params, flown)
    if kept_why is not None:
        chosen["notes"]["judge"] = kept_why
        if exported is flown:  # the log's values written back
            chosen = {**chosen, "kept": {group: "log" for group in chosen["kept"]}, "model": None}
            chosen["notes"].pop("use", None)  # nothing that enables the compass is written
    firmware = autopilot.firmware(train[0], rule)
    metrics["export"] = {"file": name, "firmware": firmware, "model": chosen["model"],
                         "heading_rms_deg": exported["heading_rms_deg"], "explained_test": exported["explained"],
                         "heading_offset_deg": exported["heading_offset_deg"],
                         "as_flown": flown, "kept": chosen["kept"], "notes": chosen["notes"],
                         "split": {"fit": sorted({p.source for p in split.fit}),
                                   "choice": sorted({p.source for p in split.choice}),
                                   "score": sorted({p.source for p in score}),
                                   "score_from_s": [float(p.time[0]) for p in score],
                                   "choice_from_s": [float(p.time[0]) for p in split.choice],
                                   "rule": split.notes["validation"]}}
    return autopilot.name, name, params

def _report(metrics: dict) -> list[str]:
    lines = [f"trained on {', '.join(metrics['train'])}; tested on {', '.join(metrics['test'])} "
             f"({metrics['validation']})"]
    lines += [f"Earth field: {note}" for note in metrics["earth_field"]]
    if metrics["mounting"]:
        lines.append(f"yaw mounting: {metrics['mounting']['note']}")
    static = metrics["static"]
    lines.append(f"hard and soft iron (calibration.json): {static['reason']}"
                 + (f"; beside the model, the offsets are {static['offsets']}" if "offsets" in static else ""))
    lines.append("models fitted here, each scored with the Earth field and offset fitted again on the test part "
                 "(an analysis; the export is scored below):")
    for name, m in metrics["models"].items():
        if "refused" in m:
            lines.append(f"  {name:9s} refused: {m['refused']}")
            continue
        lines.append(f"  {name:9s} explained {100 * m['explained_test']:5.1f} % of the test residual "
                     f"({100 * m['explained_train']:.1f} % in training), {m['perturbation_at_hover_T'] * 1e6:.2f} uT "
                     f"at hover, heading moved {m['heading_rms_change_deg']:.2f} deg RMS, delay {m['delay_s']:.2f} s")
    lines += [f"calibration.json passes over {name}: it {why}"
              for name, why in metrics.get("calibration_model_passed_over", {}).items()]
    return lines + _export_lines(metrics["export"])


def _percent(share: float) -> str:
    """``share`` (1) as a percentage with one decimal, never ``-0.0``."""
    shown = f"{100 * share:.1f}"
    return "0.0" if float(shown) == 0 else shown


def _export_lines(export: dict) -> list[str]:
    kept = export["kept"]
    fitted = [g for g in ("offsets", "soft_iron") if kept[g] == "fitted"] + ([kept["motor"]] if kept["motor"] != "log"
                                                                             else [])
    logged = [g.replace("_", " ") for g in ("offsets", "motor", "soft_iron") if kept[g] == "log"]
    flown = export["as_flown"]
    return [f"export: {export['file']} for {export['firmware']}, carrying "
            f"{', '.join(g.replace('_', ' ') for g in fitted) or 'nothing fitted'}; the log's values kept for "
            f"{', '.join(logged) or 'nothing'}",
            f"  heading on the score part (seen by neither the fit nor the choice), {export['file']} applied as the "
            "firmware does: "
            f"{export['heading_rms_deg']:.2f} deg RMS (the log as flown: {flown['heading_rms_deg']:.2f} deg), each "
            "less its heading offset as the fit and choice parts show it",
            f"  share of the score part's residual its motor compensation explains: "
            f"{_percent(export['explained_test'])} % "
            f"(as flown: {_percent(flown['explained'])} %)",
            *(f"  {group}: {note}" for group, note in export["notes"].items() if isinstance(note, str))]


def _score(args, split: Split) -> int:
    from quadcosim.calibration.flight.export import (
        Candidate,
        log_parameters,
        parameters_of,
        score_file,
        score_parameters,
    )

    from quadcosim.infra.files import write_json

    score = split.score
    rule = _rule(args, score[0])

    def scores():
        unscored = [*split.fit, *split.choice]  # where each file's heading offset is estimated
        given = score_file(args.score, score, rule, offset_from=unscored)
        names = list(parameters_of(score[0], Candidate(np.zeros(3), np.eye(3)), rule))
        return given, score_parameters(score, log_parameters(score[0], names), rule, offset_from=unscored)

    given, flown = _numeric(scores, [p.source for p in score])
    out = Path(args.out)
    metrics = {"test": sorted({p.source for p in score}), "validation": split.notes["validation"],
               "scored_on": "the export's score part", "score": given, "as_flown": flown, "files": ["metrics.json"]}
    _saved(out, args.overwrite, lambda: write_json(out / "metrics.json", metrics))
    print(f"tested on {', '.join(metrics['test'])} ({split.notes['validation']}; scored on the export's score part)")
    print(f"heading on the score part, {args.score} applied as the firmware does: {given['heading_rms_deg']:.2f} deg "
          f"RMS (the log as flown: {flown['heading_rms_deg']:.2f} deg)")
    print(f"share of the score part's residual its motor compensation explains: {_percent(given['explained'])} % "
          f"(as flown: {_percent(flown['explained'])} %)")
    return 0


def run(args) -> int:
    """``quadcosim calibrate`` (``args`` from :func:`add_arguments`): 0, 2 on bad input (nothing
    written), 1 when the disk filled while the files were written (``metrics.json`` says which
    were not). The folder is held (:func:`quadcosim.infra.files.folder_lock`) from before its
    earlier results are replaced until ``metrics.json`` is written; signals wait while the files
    are written, so that an interrupt leaves them all with their ``metrics.json``, or nothing."""
    from quadcosim.calibration.flight import calibrate
    from quadcosim.scenarios.output_options import default_folder

    from quadcosim.infra.errors import RunError, UsageError, refusals

    if not args.out:
        first = (args.files or args.train or [None])[0]
        if first is not None:
            args.out = str(default_folder("calibrate", f"calibrate-{Path(first).stem}", args.overwrite))
    out = Path(args.out or "results/calibrate")
    with refusals(usage=(ValueError,)):  # CalibrationError, LogError, FolderBusy and OutputRefused among them
        _check_choices(args)
        _check_out(out, args.overwrite)  # before the flights are read; again, held, before writing
        split = _numeric(lambda: _split(args), args.files or [*(args.train or []), *(args.test or [])], also=())
        if args.score:
            return _score(args, split)
        sources = [p.source for p in [*split.train, *split.test]]
        metrics, calibration, fitted = _numeric(
            lambda: calibrate(split.train, split.test, tuple(args.models), args.attitude), sources)
        metrics |= split.notes
        export = _numeric(lambda: _export(args, split, metrics), sources)
        files = _saved(out, args.overwrite,
                       lambda: _write(out, split, metrics, calibration, fitted, export, args.attitude))
    print("\n".join(_report(metrics)))
    if metrics["status"] == "failed":
        for name, why in metrics["files_not_written"].items():
            print(f"quadcosim calibrate: {name} not written: {why}", file=sys.stderr)
        raise RunError(f"metrics.json in {out}/ lists what was written")
    print(f"{', '.join(files)} in {out}/")
    if not fitted:
        sources = ", ".join(sorted({p.source.rsplit(":", 1)[0] for p in split.train}))
        raise UsageError(f"no interference model could be identified from {sources} (reasons above)")
    return 0


def _saved(out: Path, overwrite: bool, write):
    """``write()``'s result, the folder ``out`` prepared and held, and signals waiting, meanwhile;
    a folder this command created is removed again when nothing could be written into it."""
    import contextlib

    from quadcosim.scenarios.outputs import remove_if_empty

    from quadcosim.infra.files import prepare_out_dir
    from quadcosim.infra.interrupts import held

    made = not out.exists()
    with contextlib.ExitStack() as lock, held():
        try:
            prepare_out_dir(out, overwrite, lock)
            return write()
        except BaseException:
            if made:
                remove_if_empty(out)
            raise

def _check_out(out: Path, overwrite: bool):
    """Refuse at once an output folder that will be refused after the flights are read and fitted."""
    from quadcosim.infra.files import FolderBusy, busy_message, held_by, holds_results

    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out}: a file of that name exists; give a folder name")
    earlier = holds_results(out)
    if earlier and not overwrite:
        raise ValueError(f"--out {out} already holds results ({', '.join(earlier)}); give another folder "
                         "or add --overwrite to replace them")
    holder = held_by(out) if out.is_dir() else None
    if holder is not None:
        raise FolderBusy(f"--out {busy_message(out, holder)}")


def _numeric(call, sources, also=(ValueError,)):
    """``call()``, a numerical library's failure (``LinAlgError``, ``FloatingPointError``,
    ``IndexError`` and the classes ``also``) named with the flights ``sources``, its cause and the
    fix; the project's own refusals (:class:`~quadcosim.calibration.static.CalibrationError`,
    :class:`~quadcosim.flightlogs.LogError`, ...) pass unchanged."""
    from quadcosim.calibration.static import CalibrationError
    from quadcosim.flightlogs import LogError

    from quadcosim.infra.files import OutputRefused

    try:
        return call()
    except (CalibrationError, LogError, OutputRefused):
        raise
    except (np.linalg.LinAlgError, FloatingPointError, IndexError, ZeroDivisionError, *also) as error:
        if type(error) is ValueError and _ours(error):  # a refusal of the project's own, in its words already
            raise
        named = ", ".join(sorted({str(s) for s in sources}))
        raise CalibrationError(f"{named}: the fit failed ({type(error).__name__}: {error}): the flights hold too "
                               "little usable data to identify a model (values that barely vary, or a damaged log); "
                               "give longer flights with climbs, descents and turns, or --models with fewer "
                               "models") from None

def _ours(error: BaseException) -> bool:
    """Whether ``error`` was raised by the project's own code (its last frame is not a library's)."""
    import traceback

    frames = traceback.extract_tb(error.__traceback__)
    if not frames:
        return True
    root = Path(__file__).resolve().parents[2]
    where = Path(frames[-1].filename).resolve()
    return "site-packages" not in where.parts and any(
        where.is_relative_to(root / package) for package in ("calibration", "orchestrator", "scenarios", "estimators"))


def _check_choices(args):
    """--attitude and --models against the calibration's own names (checked here rather than by
    argparse, so that the command line's help does not import the calibration package)."""
    from quadcosim.calibration.flight import ATTITUDES
    from quadcosim.calibration.flight.catalogue import models

    if args.attitude not in ATTITUDES:
        raise ValueError(f"--attitude {args.attitude!r} must be one of {', '.join(ATTITUDES)}")
    known = models()
    args.models = list(known) if args.models is None else args.models
    unknown = [m for m in args.models if m not in known]
    if unknown:
        raise ValueError(f"--models: unknown {', '.join(unknown)}; the models are {', '.join(known)}")
    if args.earth not in ("model", "free"):
        raise ValueError(f"--earth {args.earth!r} must be model or free")
    _rule(args, None)  # --firmware refused before the flights are read


def add_arguments(parser):
    """The ``calibrate`` verb's options on ``parser`` (an argparse parser); returns it."""
    parser.add_argument("files", nargs="*", metavar="FILE", help="flight logs, in a format an installed autopilot "
                        "writes (PX4 .ulg, ArduPilot .bin or .log)")
    parser.add_argument("--compass", type=int, default=0, help="compass to calibrate, from 0 in the log's order")
    parser.add_argument("--out", help="folder for the results (default results/calibrate-FLIGHT, FLIGHT the first "
                                      "flight's name, or results/calibrate-FLIGHT-N when that holds results)")
    parser.add_argument("--test-fraction", type=float, default=None,
                        help="last fraction of each flight kept for testing (default 0.5 for one flight; several "
                             "flights hold out the last one)")
    parser.add_argument("--train", nargs="+", metavar="FILE", help="flights to fit on (with --test)")
    parser.add_argument("--test", nargs="+", metavar="FILE", help="flights of the same vehicle to score on")
    parser.add_argument("--attitude", default="auto",
                        help="attitude removing the Earth field: auto (default: gyro for the compass the log's heading "
                             "fuses, log for the others), gyro (roll and pitch from the log, heading integrated from "
                             "the gyro) or log")
    parser.add_argument("--models", nargs="+", default=None,
                        help="models to fit (default: every installed interference model; an unknown "
                             "name lists them)")
    parser.add_argument("--earth", default="model",
                        help="Earth field: model (default: the World Magnetic Model at the log's GPS position and "
                             "date; free without a GPS fix) or free (fitted per flight)")
    parser.add_argument("--firmware", help="firmware version whose rules the export follows, for an autopilot "
                                           "with versions (ArduPilot: a Copter version such as 3.4; default: the "
                                           "log's)")
    parser.add_argument("--no-trim", action="store_true", help="ignore AHRS_TRIM (an ablation)")
    parser.add_argument("--span", nargs=2, type=float, metavar=("START", "END"),
                        help="use only this span of each log (s on its clock, as 'quadcosim log info' prints it); "
                             "a crash or logging stall at a flight's end is cut without it")
    parser.add_argument("--score", metavar="PARAMS", help="score this parameter file (.parm, .params) on the "
                                                          "held-out part instead of calibrating")
    parser.add_argument("--overwrite", action="store_true", help="replace the results already in --out")
    parser.set_defaults(func=run)
    return parser


def main(argv) -> int:
    """``quadcosim calibrate ARGV...`` called from Python (the findings run it so): its exit code.

    Parameters
    ----------
    argv : list of str
        The verb's arguments, without ``calibrate`` itself.
    """
    import argparse

    return run(add_arguments(argparse.ArgumentParser(prog="quadcosim calibrate")).parse_args(argv))
