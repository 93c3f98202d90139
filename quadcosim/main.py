"""quadcosim: run the quadrotor co-simulation scenarios, build the FMUs, benchmark the master.

  quadcosim build [--force]                build the plant FMUs (those not up to date) and the master's call runner
  quadcosim list [--parameters MODEL]      scenarios and their options (or an FMU's parameters)
  quadcosim run SCENARIO [--set k=v k2=v2 ...] [--estimator module:Class] [--out DIR] [--fault ...]
                                           (--set IMU.gyro_noise_density=0.001: an FMU parameter)
  quadcosim diagram SCENARIO [--out FILE]  picture of the wiring
  quadcosim plot RUN SIGNAL...             signals of a finished run (its folder) against time
  quadcosim compare RUN RUN... SIGNAL      one signal of several finished runs on one figure
  quadcosim bench [--json]                 speed of the master
  quadcosim bench infrared [--json]        IR calibration: operations per iteration, us per update
  quadcosim bench sweep [--json]           sweep engine: 40 closed-loop runs on 1 and 2 Dask workers
  quadcosim bench pytest [--json]          cost of a short test written with the pytest plugin
  quadcosim bench isolation [--json]       cost of an FMU run in a worker process of its own
  quadcosim sweep SCENARIO [--grid k=a:b:logN]... [--set k=v]... [--seeds N] [--workers N | --scheduler ADDR]
                  [--out DIR] [--resume]  the scenario over a grid, on Dask (see `quadcosim sweep -h`)
  quadcosim sweep-plot DIR METRIC --x OPTION [--by OPTION]   a metric of a sweep against an option
  quadcosim tune SCENARIO --minimize METRIC --over NAME=LOW:HIGH[:log]... [--seeds N] [--budget N]
                  [--workers N | --scheduler ADDR] [--out DIR] [--resume]   the options that minimise it
  quadcosim replay RECORDING [--estimator KIND] [--figure FILE]   an estimator on a recorded file, scored
  quadcosim log info|plot FILE             a PX4 or ArduPilot flight log: what it holds, an overview figure
  quadcosim calibrate FILE... --compass N --out DIR   the magnetometer and its motor interference from flights
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import warnings
from pathlib import Path


def _build(args) -> int:
    from quadcosim.fmus import BuildFolderRefused, default_fmu_dir
    from quadcosim.fmus.build import BuildError, build_all
    from quadcosim.orchestrator.calls import LIBRARY_NAME, SOURCE, RunnerBuildError, build_runner, runner_dir

    try:
        build_all(Path(args.out or default_fmu_dir()), force=args.force)
        library = runner_dir() / LIBRARY_NAME
        if args.force or not library.is_file() or library.stat().st_mtime < SOURCE.stat().st_mtime:
            print(f"built {build_runner()}")
        else:
            print(f"up to date {library}")
        from quadcosim.orchestrator.fmi_types import typed_path

        print(f"ready {typed_path(build=args.force)}")
        from quadcosim.benchmarks import build_references

        for library in build_references():
            print(f"built {library}")
        from quadcosim.scenarios import compiled

        seconds = compiled.compile_all()
        print(f"{'compiled' if compiled.compiled_any() else 'loaded'} the numba steps in {seconds:.1f} s")
    except (BuildError, RunnerBuildError, BuildFolderRefused) as error:
        print(error, file=sys.stderr)
        return 1
    return 0


def _list(args) -> int:
    if args.parameters:
        from quadcosim.fmus import MODELS
        from quadcosim.fmus.build import table
        from quadcosim.scenarios.block_parameters import PYTHON_BLOCKS, parameter_lines, scenario_lines

        if args.parameters in PYTHON_BLOCKS:
            print("\n".join(parameter_lines(args.parameters)))
            return 0
        if args.parameters not in MODELS:
            print(f"unknown model {args.parameters!r}; FMUs: {', '.join(MODELS)}; Python blocks: "
                  f"{', '.join(PYTHON_BLOCKS)}", file=sys.stderr)
            return 2
        from quadcosim.orchestrator.parameters import model_notes

        print(f"{args.parameters} parameters (set one in any scenario with --set {args.parameters}.NAME=VALUE; "
              "a vector as x,y,z):")
        from quadcosim.scenarios.shown import PARAMETER_DIGITS, shown

        for v in table(args.parameters).of("parameter"):
            unit = f" [{v.unit}]" if v.unit else ""
            print(f"  {v.name:22s} = {shown(v.start, PARAMETER_DIGITS):24}{unit:14s} {v.description}")
        aliases, switched = model_notes(args.parameters)
        for alias, name in aliases.items():
            print(f"  {alias} stands for the vector {name}")
        for switch, governed in switched.items():
            print(f"  {', '.join(governed)} act only while {switch} is true")
        print("\n".join(scenario_lines(args.parameters)))
        return 0
    from quadcosim import scenarios

    for name, scenario in scenarios.registry().items():
        print(f"{name}: {scenario.description}")
        for key, option in scenario.options.items():
            choices = f" ({'|'.join(map(str, option.choices))})" if option.choices else ""
            print(f"    {key:16s} = {option.default!s:10s}{choices}  {option.help}")
    return 0


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


def _run(args) -> int:
    from quadcosim.infra.interrupts import exit_code, first_only
    from quadcosim.infra.progress import reporting

    # the first signal stops the run; later ones wait until its record is safe, then (when this
    # is the process's command line) are ignored while the process ends with the first one's code
    with first_only(final=getattr(args, "final", False)), reporting(True):
        try:
            return _run_reporting(args)
        except KeyboardInterrupt as interrupt:  # before the run began: nothing was written
            print("quadcosim: interrupted", file=sys.stderr)
            return exit_code(interrupt)


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

    out = Path(args.out) if args.out else _default_out(args.scenario, args.overwrite)
    formats = [f.strip() for f in args.format.split(",") if f.strip()]
    from quadcosim.scenarios.plant import figure_format

    try:
        _isolation(args)
        faults = [_parse_fault(f) for f in args.fault or []]
        with figure_format(args.figures):
            _, metrics = scenarios.run(args.scenario, _settings(args), out, progress=True, faults=faults,
                                       decimation=args.decimation, record=args.record, formats=formats,
                                       overwrite=args.overwrite, compress=args.compress, stream=args.stream,
                                       fmus=_fmus(args.fmu))
    except RunInterrupted as error:
        print(f"quadcosim run {args.scenario}: {error}", file=sys.stderr)
        print(f"what was recorded ({len(error.result)} samples) and metrics.json are in {out}/", file=sys.stderr)
        return 128 + error.signal_number
    except SimulationError as error:
        print(f"quadcosim run {args.scenario}: failed: {error}", file=sys.stderr)
        if error.result is not None:
            print(f"what was recorded up to the failure ({len(error.result)} samples) is in {out}/", file=sys.stderr)
        return 1
    except (KeyError, ValueError) as error:
        print(f"quadcosim run {args.scenario}: {_said(error)}", file=sys.stderr)
        from quadcosim.orchestrator.fmu_checks import FMURefused

        if isinstance(error, FMURefused) and (out / "metrics.json").is_file():
            print(f"metrics.json (status refused, no sample) is in {out}/", file=sys.stderr)
        return 2
    except OSError as error:  # the output folder failed under the run (removed, read-only, a disk error)
        print(f"quadcosim run {args.scenario}: failed: {error}", file=sys.stderr)
        return 1
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
        print(f"quadcosim run {args.scenario}: the run diverged (metrics.json: status diverged); its record and "
              f"figures are in {out}/", file=sys.stderr)
        return 1
    return 0


def _said(error: Exception) -> str:
    """The message of a refusal: its text (a KeyError's own, without the quotes its str adds)."""
    if isinstance(error, KeyError) and error.args and isinstance(error.args[0], str):
        return error.args[0]
    return str(error)


def _default_out(scenario: str, overwrite: bool) -> Path:
    """``results/SCENARIO``, or with earlier results there (and no --overwrite) the next free
    ``results/SCENARIO-N``, said on standard error: a run never replaces results unasked."""
    from quadcosim.infra.files import free_folder, holds_results

    base = Path("results") / scenario
    if overwrite:
        return base
    out = free_folder(base)
    if out != base:
        print(f"quadcosim run {scenario}: {base}/ holds earlier results ({', '.join(holds_results(base))}); "
              f"writing to {out}/ (--out DIR chooses the folder, --overwrite replaces {base}/)", file=sys.stderr)
    return out


def _print_warnings(warnings: dict, shown: int = 3):
    """The FMUs' warnings (counted in metrics.json): the count per block and the first few."""
    if not warnings:
        return
    print("  FMU warnings: " + ", ".join(f"{block} {w['count']}" for block, w in warnings.items()), file=sys.stderr)
    for block, w in warnings.items():
        for line in w["first"][:shown]:
            print(f"    {block}: {line}", file=sys.stderr)


def _diagram(args) -> int:
    from quadcosim.infra.progress import reporting, status

    with reporting(True):
        status(f"quadcosim diagram {args.scenario}: loading the packages")
        from quadcosim import scenarios
        from quadcosim.orchestrator.diagram import draw

        try:
            scenario = scenarios.get(args.scenario)
            options = scenario.parse(_settings(args))
            status(f"{args.scenario}: building the system (its FMUs loaded)")
            system = scenario.system(options)
        except (KeyError, ValueError) as error:
            print(error.args[0] if error.args else error, file=sys.stderr)
            return 2
        from quadcosim.infra.files import figure_file
        from quadcosim.orchestrator.diagram import blocks_text

        status(f"{args.scenario}: drawing the wiring ({blocks_text(system)})")
        try:
            out = figure_file(args.out, "diagram.png", Path("results") / args.scenario)
            path = draw(system, out, scenario.title(options))
        except ValueError as error:  # an output path refused (OutputRefused), before anything is written
            print(f"quadcosim diagram: {error}", file=sys.stderr)
            return 2
        except OSError as error:  # a full disk: named, nothing left under the figure's name
            print(f"quadcosim diagram: failed: {error}", file=sys.stderr)
            return 1
    print(path)
    return 0


def _bench(args) -> int:
    if args.out and args.suite != "master":
        print(f"quadcosim bench {args.suite}: --out draws the master suite's figures only; drop --out, or run "
              "quadcosim bench --out FILE", file=sys.stderr)
        return 2
    if args.suite == "infrared":
        from quadcosim.benchmarks import infrared

        return infrared.main(["--json"] if args.json else [])
    if args.suite == "sweep":
        from quadcosim.benchmarks import sweep

        return sweep.main(["--json"] if args.json else [])
    if args.suite == "isolation":
        from quadcosim.benchmarks import isolation

        return isolation.main(["--json"] if args.json else [])
    if args.suite == "pytest":
        from quadcosim.benchmarks import pytest_cost

        return pytest_cost.main(["--json"] if args.json else [])
    from quadcosim.benchmarks import master as bench

    return bench.main((["--json"] if args.json else []) + ["--seconds", str(args.seconds)]
                      + (["--out", args.out] if args.out else []))


def _version() -> str:
    """The installed package's version (pyproject.toml's), or ``unknown`` outside an installation."""
    from importlib import metadata

    try:
        return metadata.version("quadcosim")
    except metadata.PackageNotFoundError:
        return "unknown (not installed: pip install -e .)"


def parser() -> argparse.ArgumentParser:
    """The ``quadcosim`` argument parser, one sub-command per action."""
    from quadcosim.scenarios.shown import PlainHelp

    p = argparse.ArgumentParser(prog="quadcosim", description=__doc__, formatter_class=PlainHelp)
    p.add_argument("--version", action="version", version=f"quadcosim {_version()}")
    sub = p.add_subparsers(dest="command", required=True)
    build = sub.add_parser("build", help="build the plant FMUs, the master's C runner and the benchmark's C "
                           "references (into build/ in a source checkout, a per-user cache when installed; a run "
                           "builds what it needs on first use)")
    build.add_argument("--out", default=None, help="output folder of the FMUs (default: fmus/ in the build folder)")
    build.add_argument("--force", action="store_true", help="rebuild the FMUs that are up to date too")
    build.set_defaults(func=_build)
    listing = sub.add_parser("list", help="the scenarios and their options")
    listing.add_argument("--parameters", metavar="MODEL",
                         help="list the parameters of a block instead, with units and defaults: an FMU (IMU, "
                              "Quadrotor, MotorMagnetics, ...) or a Python block (Controller, Quaternion_estim)")
    listing.set_defaults(func=_list)
    _add_run(sub)
    diagram = sub.add_parser("diagram", help="draw the wiring of a scenario")
    diagram.add_argument("scenario", help="a scenario name (quadcosim list shows them)")
    diagram.add_argument("--set", action="extend", nargs="+", default=[], metavar="KEY=VALUE",
                         help="scenario options or block parameters, as for run (the wiring may depend on them: "
                              "magnetic=on adds the motors' field)")
    diagram.add_argument("--estimator", metavar="MODULE:CLASS", help="your own estimator block (as for run)")
    diagram.add_argument("--out", help="PNG or SVG file (default results/SCENARIO/diagram.png; a folder takes "
                         "diagram.png)")
    diagram.set_defaults(func=_diagram)
    bench = sub.add_parser("bench", help="benchmarks: co-simulation master, IR calibration cost, sweep engine, "
                                         "pytest plugin, an FMU in a worker process")
    bench.add_argument("suite", nargs="?", default="master",
                       choices=("master", "infrared", "sweep", "pytest", "isolation"),
                       help="what to time: master (the co-simulation loop, the default), infrared (the IR "
                            "calibration's cost per update), sweep (40 closed-loop runs on Dask), pytest (the "
                            "pytest plugin's fixtures) or isolation (an FMU in a worker process against in process)")
    bench.add_argument("--json", action="store_true",
                       help="print the measurements as one JSON object on standard output instead of a table")
    bench.add_argument("--seconds", type=float, default=5.0, metavar="S",
                       help="simulated time of each timed run of the master suite (s, default 5)")
    bench.add_argument("--out", metavar="FILE",
                       help="the master suite: also draw its figures (PNG, SVG or PDF file, or a folder: bench.png)")
    bench.set_defaults(func=_bench)
    replay = sub.add_parser("replay", add_help=False,
                            help="any estimator on a recorded IMU file or a tp run's folder, scored against its "
                                 "reference attitude (quadcosim replay --help)")
    replay.add_argument("rest", nargs=argparse.REMAINDER)  # main() hands them to quadcosim.scenarios.replay
    from quadcosim.scenarios import run_plots

    run_plots.add_arguments(sub)
    _add_studies(sub)
    _add_flight_logs(sub)
    return p


def _add_run(sub):
    """The ``run`` sub-command, added to the sub-parsers ``sub``."""
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
    run.set_defaults(func=_run)


def _add_studies(sub):
    """The ``sweep``, ``sweep-plot`` and ``tune`` verbs (:mod:`quadcosim.studies.sweep`,
    :mod:`quadcosim.studies.tune`)."""
    from quadcosim.studies.sweep import command as sweep

    sweep.add_arguments(sub.add_parser("sweep", help="run a scenario over a grid of options and seeds, on Dask"))\
        .set_defaults(func=sweep.sweep)
    sweep.add_plot_arguments(sub.add_parser("sweep-plot", help="a metric of a sweep table against an option"))\
        .set_defaults(func=sweep.sweep_plot)
    from quadcosim.studies import tune

    tune.add_arguments(sub.add_parser("tune", help="the options that minimise a metric (scipy.optimize), on Dask"))\
        .set_defaults(func=tune.command)


def _add_flight_logs(sub):
    """The ``log`` and ``calibrate`` verbs (:mod:`quadcosim.scenarios.flightlog`) on the sub-parsers ``sub``."""
    from quadcosim.scenarios.flightlog import calibrate
    from quadcosim.scenarios.flightlog import command as flightlog

    flightlog.add_arguments(sub.add_parser("log", help="read a PX4 ULog or ArduPilot DataFlash flight log"))
    calibrate.add_arguments(sub.add_parser("calibrate", help="calibrate a magnetometer and its motor interference "
                                           "from real flights; ArduPilot and PX4 parameters"))


def _show_warning(message, category, filename, lineno, file=None, line=None):
    from quadcosim.infra.progress import say

    say(f"quadcosim: warning: {message}", sys.stderr)  # above a progress bar, never inside it


def main(argv=None) -> int:
    """Run ``quadcosim`` with ``argv`` (the process arguments if None); returns the exit code."""
    from quadcosim.infra.interrupts import exit_code, terminate_as_interrupt

    for stream in (sys.stdout, sys.stderr):  # a file name that is not UTF-8 is printed escaped, never a traceback
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    try:
        with terminate_as_interrupt(), warnings.catch_warnings():  # SIGTERM ends it as Ctrl-C does: cleanly
            warnings.simplefilter("default")
            warnings.showwarning = _show_warning
            final = argv is None  # the process's own command line, not a call from Python
            argv = sys.argv[1:] if argv is None else list(argv)
            if argv[:1] == ["replay"]:  # the replay's parser, shared with python -m quadcosim.scenarios.replay
                from quadcosim.scenarios.replay import main as replay

                return replay(argv[1:], prog="quadcosim replay")
            args = parser().parse_args(argv)
            args.final = final
            if args.command in ("run", "sweep", "tune", "bench", "build"):
                from quadcosim.scenarios.compiled import announce_compiles

                announce_compiles()
            return args.func(args)
    except KeyboardInterrupt as interrupt:  # before or after a run: nothing half-written is left
        print("quadcosim: interrupted", file=sys.stderr)
        return exit_code(interrupt)


def entry() -> None:
    """The ``quadcosim`` program: :func:`main`, then exit with its code
    (:func:`quadcosim.infra.interrupts.leave`)."""
    # Before numpy loads: numpy and scipy each bring an OpenBLAS that starts a thread per core and
    # spins it at load, CPU a command spends for nothing on its small matrices. A user's setting
    # wins; a program that imports this module is left as it is.
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    import signal

    from quadcosim.infra.interrupts import exit_code, leave

    # SIGTERM's handler outside main's own: main restores it when it returns, and a signal then
    # (the command's work done) ends the process at once with 143, never by SIGTERM's default
    signal.signal(signal.SIGTERM, _ended_while_leaving)
    global _leaving_code
    try:
        code = _leaving_code = main()
        signal.signal(signal.SIGINT, _ended_while_leaving)
        sys.stdout.flush()  # here, not at exit: a reader gone (| head) is then seen below
    except BrokenPipeError:  # the reader of our output left (quadcosim list | head -1): no traceback
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # nothing more to flush at exit
        code = 128 + signal.SIGPIPE  # as a program that the pipe's signal ended
    except KeyboardInterrupt as interrupt:  # Ctrl-C as main returned: its work is done or was refused
        code = exit_code(interrupt)
    _leaving_code = code
    signal.signal(signal.SIGINT, _ended_while_leaving)
    leave(code, at_once=True)


#: The command's exit code once :func:`main` returned (None before).
_leaving_code = None


def _ended_while_leaving(number, frame):
    """A signal after the command finished, while the process exits: leave at once with the
    command's own code (its work is done; 128 + the signal if main had not yet returned), rather
    than die by it (SIGTERM's default) or print a KeyboardInterrupt traceback from an exit handler
    (SIGINT's)."""
    sys.stderr.flush()
    os._exit(_leaving_code if _leaving_code is not None else 128 + number)


if __name__ == "__main__":
    entry()
