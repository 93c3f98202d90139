"""``quadcosim run SCENARIO``: a scenario run, its record, metrics and figures written to its folder."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from quadcosim.infra.errors import RunError, refusals


def add(sub) -> None:
    """Add the ``run`` verb to the sub-parsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``quadcosim`` parser's sub-parsers.
    """
    run = sub.add_parser("run", help="run a scenario")
    run.add_argument("scenario", help="a scenario name: tp, open-loop, rig, static-cal, metge, ... "
                                      "(quadcosim list shows them and their options)")
    run.add_argument("--set", action="extend", nargs="+", default=[], metavar="KEY=VALUE",
                     help="scenario options, several after one flag (estimator=explicit k1=0.2), or block "
                          "parameters: IMU.gyro_noise_density=0.001, IMU.gyro_bias=0.01,0,0 (units: quadcosim list "
                          "--parameters IMU)")
    run.add_argument("--estimator", metavar="MODULE:CLASS",
                     help="your own attitude estimator block in the place of Quaternion_estim (a module, or "
                          "a file.py, and a class; see estimators/contract.py)")
    run.add_argument("--out", help="output folder (default results/SCENARIO, or results/SCENARIO-N when that "
                                   "holds earlier results); a given folder holding results is refused without "
                                   "--overwrite")
    run.add_argument("--fault", action="append", metavar="TARGET:KIND:START:STOP[:VALUE]",
                     help="fault on the connection into TARGET; KIND is offset, scale, stuck, noise or dropout")
    run.add_argument("--fmu", action="append", metavar="BLOCK=PATH",
                     help="put an FMU of your own (FMI 2.0 or 3.0 Co-Simulation, any exporter) in the place of a plant "
                          "block: MotorMagnetics=my_motor.fmu; its inputs and outputs are checked against the "
                          "block's by name and unit, mismatches listed")
    run.add_argument("--watchdog", type=float, default=None, metavar="SECONDS",
                     help="end the run when a step of an FMU of your own (--fmu) takes longer than this, in wall "
                          "seconds (default: no limit; Ctrl-C always stops it)")
    run.add_argument("--fmu-in-process", action="store_true",
                     help="run FMUs of your own in this process, not each in a worker process of its own: faster, "
                          "for an FMU you trust (a crash in it then ends quadcosim)")
    run.add_argument("--overwrite", action="store_true", help="replace the results already in the --out folder")
    run.add_argument("--decimation", type=_positive_int, default=1, metavar="N",
                     help="record every N-th macro step (default 1)")
    run.add_argument("--record", nargs="+", metavar="SIGNAL",
                     help="record only these signals (Block.signal; a vector name such as IMU.acc is allowed); "
                          "'all' records and writes every output (by default a scenario's files may leave out signals "
                          "that follow from others, listed in metrics.json)")
    run.add_argument("--format", default="npz", metavar="npz,mat,csv",
                     help="result files to write, comma-separated: npz (NumPy, the default), mat (MATLAB), csv")
    run.add_argument("--figures", choices=("png", "svg", "pdf"), default="png",
                     help="format of the report's figures: png (120 dpi, the default), svg or pdf (vector, for a "
                          "report or a thesis)")
    run.add_argument("--compress", action="store_true",
                     help="compress the npz and mat files (about a third smaller, many times slower to write)")
    run.add_argument("--stream", action="store_true",
                     help="write the record to OUT/results.stream/ in chunks as the run goes: memory stays flat "
                          "however long the run (read it with Result.load(OUT))")
    run.set_defaults(func=command)


def _settings(args) -> list[str]:
    """The ``--set`` pairs, with ``--estimator`` as the option it stands for."""
    settings = list(args.set)
    if getattr(args, "estimator", None):
        from quadcosim import scenarios

        if "estimator" not in scenarios.get(args.scenario).options:
            raise ValueError(f"--estimator: scenario {args.scenario} has no estimator; "
                             f"{scenarios._with_estimator()}")
        if ":" not in args.estimator:
            raise ValueError(f"--estimator {args.estimator!r}: write module:Class or file.py:Class")
        settings.append(f"estimator={args.estimator}")
    return settings


_FAULT_FORM = ("write TARGET:KIND:START:STOP[:VALUE], e.g. IMU.omega_x:offset:0.5:1:0.05 (a gyro offset of "
               "0.05 rad/s from 0.5 s to 1 s, on the true rate into the IMU)")


def _parse_fault(text: str):
    from quadcosim.orchestrator import Fault

    parts = text.split(":")
    if len(parts) not in (4, 5):
        raise ValueError(f"--fault {text!r}: {_FAULT_FORM}")
    fields = {"START": (parts[2], "s"), "STOP": (parts[3], "s; inf for no end")}
    if len(parts) == 5:
        fields["VALUE"] = (parts[4], "in the unit of the target, a factor for scale")
    numbers = {}
    for field, (given, unit) in fields.items():
        try:
            numbers[field] = float(given)
        except ValueError:
            raise ValueError(f"--fault {text!r}: {field} {given!r} is not a number ({unit}); {_FAULT_FORM}") from None
    if math.isnan(numbers["START"]) or math.isnan(numbers["STOP"]) or math.isinf(numbers["START"]):
        raise ValueError(f"--fault {text!r}: START must be a finite time (s) and STOP a time or inf; {_FAULT_FORM}")
    return Fault(parts[0], parts[1], numbers["START"], numbers["STOP"], numbers.get("VALUE"))


def _fmus(given) -> dict:
    """``--fmu NAME=PATH`` pairs as a dict, block name to FMU file."""
    fmus = {}
    for text in given or []:
        name, eq, path = text.partition("=")
        if not eq or not name.strip() or not path.strip():
            raise ValueError(f"--fmu {text!r}: write BLOCK=PATH, e.g. MotorMagnetics=my_motor.fmu")
        if not Path(path.strip()).is_file():
            raise ValueError(f"--fmu {text}: no file {path.strip()} (from {Path.cwd()})")
        fmus[name.strip()] = path.strip()
    return fmus


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive integer")
    return value


def command(args) -> int:
    """Run the scenario, print its metrics and where its files are; raises what ended it (a
    refusal, a failure or an interruption, each naming what was kept and where).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed ``run`` arguments.
    """
    from quadcosim.infra.interrupts import first_only
    from quadcosim.infra.progress import reporting

    # the first signal stops the run; later ones wait until its record is safe, then (when this
    # is the process's command line) are ignored while the process ends with the first one's code
    with first_only(final=getattr(args, "final", False)), reporting(True):
        return _run_reporting(args)


def _isolation(args):
    """``--watchdog`` and ``--fmu-in-process`` as the settings :mod:`quadcosim.orchestrator.isolated` reads
    (environment variables: a sweep's worker processes inherit them)."""
    import os

    if args.watchdog is not None:
        if not 0 < args.watchdog < float("inf"):
            raise ValueError(f"--watchdog {args.watchdog}: give the wall seconds an FMU step may take, a positive "
                             "number (e.g. 5)")
        os.environ["QUADCOSIM_FMU_WATCHDOG"] = repr(args.watchdog)
    if args.fmu_in_process:
        os.environ["QUADCOSIM_FMU_IN_PROCESS"] = "1"


def _run_reporting(args) -> int:
    from quadcosim.infra.progress import status

    status(f"quadcosim run {args.scenario}: loading the packages")
    from quadcosim import scenarios
    from quadcosim.orchestrator import RunInterrupted, SimulationError
    from quadcosim.orchestrator.fmu_checks import FMURefused
    from quadcosim.scenarios.output_options import default_folder

    out = Path(args.out) if args.out else default_folder(f"run {args.scenario}", args.scenario, args.overwrite)
    formats = [f.strip() for f in args.format.split(",") if f.strip()]
    from quadcosim.scenarios.plant import figure_format

    try:
        with refusals():  # a value or name refused: exit 2; the output folder failing under the run: exit 1
            _isolation(args)
            faults = [_parse_fault(f) for f in args.fault or []]
            with figure_format(args.figures):
                _, metrics = scenarios.run(args.scenario, _settings(args), out, progress=True, faults=faults,
                                           decimation=args.decimation, record=args.record, formats=formats,
                                           overwrite=args.overwrite, compress=args.compress, stream=args.stream,
                                           fmus=_fmus(args.fmu))
    except RunInterrupted as error:
        error.add_note(f"what was recorded ({len(error.result)} samples) and metrics.json are in {out}/")
        raise
    except SimulationError as error:
        if error.result is not None:
            error.add_note(f"what was recorded up to the failure ({len(error.result)} samples) is in {out}/")
        raise
    except FMURefused as error:
        if (out / "metrics.json").is_file():
            error.add_note(f"metrics.json (status refused, no sample) is in {out}/")
        raise
    warnings = metrics.pop("fmu_warnings", {})
    shown = {k: v for k, v in metrics.items() if k not in ("options", "scenario", "units", "signals_not_saved")}
    from quadcosim.scenarios.shown import shown as text

    for key, value in shown.items():
        print(f"  {key}: {text(value)}")
    _print_warnings(warnings)
    figures = [name for name in metrics.get("figures") or [] if isinstance(name, str)]
    drawn = [p.name for p in sorted(out.glob("diagram.*"))] + figures
    record = "the record streamed (results.stream/)" if args.stream else f"results ({', '.join(formats)})"
    print(f"{record}, metrics.json" + (f" and {', '.join(drawn)}" if drawn else "")
          + f" in {out}/" + (" (no report figures: see report above)" if "report" in metrics else ""))
    if metrics.get("status") == "diverged":  # warned above, naming the settings
        raise RunError(f"the run diverged (metrics.json: status diverged); its record and figures are in {out}/")
    return 0


def _print_warnings(warnings: dict, shown: int = 3):
    """The FMUs' warnings (counted in metrics.json): the count per block and the first few."""
    if not warnings:
        return
    print("  FMU warnings: " + ", ".join(f"{block} {w['count']}" for block, w in warnings.items()), file=sys.stderr)
    for block, w in warnings.items():
        for line in w["first"][:shown]:
            print(f"    {block}: {line}", file=sys.stderr)
