"""Named scenarios: one command runs one and leaves results, figures and metrics behind.

A scenario declares its options (each with a default, a unit or choices, and a help text),
builds a :class:`quadcosim.orchestrator.System` from them, and reports on the result: it writes its
figures and returns its metrics. :func:`run` does the rest: results (``results.npz``,
``results.mat``), ``metrics.json``, and on a failure what was recorded up to it.
"""

from __future__ import annotations

import contextlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from quadcosim.scenarios.catalogue import get, names, registry
from quadcosim.scenarios.option import Option, settings_pairs
from quadcosim.scenarios.state import Build, Duration, Extra, Options, Prepared, Report, Resolve, RunRequest, RunStated


@dataclass
class Scenario:
    name: str
    description: str
    options: dict[str, Option]
    build: Build  # (options, estimator=None) -> System
    report: Report  # (result, options, out_dir) -> metrics dict
    duration: Duration | None = None  # (options) -> seconds, when no option "duration" says it
    extra: Extra = field(default_factory=dict)
    resolve: Resolve | None = None  # (options) -> the options as used: a marker (kI = "lab") replaced by its value

    def used(self, options: dict) -> dict:
        """``options`` as the run uses them: every default marker replaced by the value it stands for."""
        return self.resolve(options) if self.resolve else dict(options)

    def inert(self, options: dict) -> list[str]:
        """The options that act on nothing in a run with ``options`` (their ``applies`` condition
        is not met: ``k`` with ``estimator=explicit``, ``seed`` with ``noise=off``).

        Parameters
        ----------
        options : dict
            Parsed options (:meth:`parse`).

        Returns
        -------
        list of str
            Option names, in declaration order.
        """
        inert = []
        for key, option in self.options.items():
            if option.applies:
                other, _, values = option.applies.partition("=")
                accepted = [self.options[other].parse(other, v) for v in values.split(",")]
                if options[other] not in accepted:
                    inert.append(key)
        return inert

    def title(self, options: dict) -> str:
        """The scenario's name and its options off their defaults, as a figure title names a run.

        Parameters
        ----------
        options : dict
            Parsed options (:meth:`parse`).

        Returns
        -------
        str
            ``"tp: feedback=estimate, k=0.1"``; a scenario may state it in words instead
            (``extra["title"]``, a function of the options).
        """
        if "title" in self.extra:
            return self.extra["title"](options)
        changed = [f"{key}={value}" for key, value in options.items()
                   if key not in self.options or value != self.options[key].default]  # or Block.parameter
        return f"{self.name}: " + (", ".join(changed) if changed else "default options")

    def parse(self, settings: dict | list | None, fmus: dict | None = None) -> Options:
        """Options with defaults, from ``settings`` ``{"k": v}`` or ``["k=v", ...]`` (None: all
        defaults), each read once and checked before anything is built. The options returned
        are read-only (:class:`Options`).

        A key ``Block.parameter`` sets a block parameter (``IMU.gyro_noise_density``). Where the
        scenario declares its blocks (``extra["blocks"]``), it is checked against the block's
        declared parameters (an FMU's variable table, a block class's
        :attr:`~quadcosim.orchestrator.Block.parameter_units`) and kept as the value it stands
        for (a number, a bool, or a list for a vector); a parameter the scenario sets from one of
        its options is refused, naming the option. A block whose parameters are known once it is
        built keeps its text, checked when :meth:`prepare` builds the system.

        Parameters
        ----------
        settings : dict, list of str or None
            Option values and block parameters.
        fmus : dict, optional
            Block name to an FMU file of the user's that will take that block's place: its
            parameters are that file's.

        Raises
        ------
        KeyError
            An unknown block or block parameter (the nearest names given).
        ValueError
            An unknown option (the nearest names given), or a value it does not take.
        """
        values = {k: o.default for k, o in self.options.items()}
        parameters = {}
        for key, text in settings_pairs(settings):
            if "." in key:
                values[key] = parameters[key] = text
                continue
            if key not in self.options:
                from quadcosim.orchestrator.fmu import nearest

                raise ValueError(f"unknown option {key!r} for scenario {self.name}.{nearest(key, self.options)} "
                                 f"Options: {', '.join(self.options)} (see `quadcosim list`).")
            values[key] = self.options[key].parse(key, text)
        values |= self._checked_parameters(parameters, fmus)
        return Options(values)

    def _checked_parameters(self, settings: dict, fmus: dict | None) -> dict:
        """``Block.parameter`` settings checked against the declared blocks (:meth:`parse`)."""
        declared = self.extra.get("blocks")
        if not settings or declared is None:
            return settings
        from quadcosim.orchestrator.parameters import check_declared

        resolved, deferred = check_declared(dict(declared) | dict(fmus or {}), settings)
        for target, values in resolved.items():
            self._refuse_derived(target, values)
        for target in deferred:
            self._refuse_derived(target, [target.partition(".")[2]])
        return {target: list(values.values()) if len(values) > 1 else next(iter(values.values()))
                for target, values in resolved.items()}

    def _refuse_derived(self, target: str, names):
        """Refuse ``target`` if any parameter it sets (``names``, within its block) is one the
        scenario sets from an option (``extra["derived"]``), naming that option."""
        derived = self.extra.get("derived", {})
        block = target.partition(".")[0]
        for name in names:
            option = derived.get(f"{block}.{name}")
            if option is not None and option.startswith("("):  # fixed by the scenario, no option
                raise ValueError(f"{block}.{name} is fixed by scenario {self.name} {option}: leave {target} "
                                 "out of --set")
            if option is not None:
                raise ValueError(f"{block}.{name} is set by scenario {self.name}'s option {option}: "
                                 f"use --set {option}=... instead of {target}")


    def system(self, options: Mapping, estimator=None, fmus: dict | None = None):
        """The system of these options (:meth:`prepare`'s, its block parameters set).

        Parameters
        ----------
        options : mapping
            From :meth:`parse`.
        estimator : Block or class, optional
            A block of the user's in the place of ``Quaternion_estim``.
        fmus : dict, optional
            Block name to an FMU file of the user's put in that block's place.

        Returns
        -------
        quadcosim.orchestrator.System
        """
        return self.prepare(options, estimator, fmus).system

    def prepare(self, options: Mapping, estimator=None, fmus: dict | None = None) -> Prepared:
        """The system of these options: built, its FMU blocks replaced by ``fmus``, then its
        block parameters resolved once and set; and the options as the run uses them.

        Parameters
        ----------
        options : mapping
            From :meth:`parse` (left as it is). Its ``Block.parameter`` entries are checked
            against the built system (the FMU's variable table, or the Python block) and set.
        estimator : Block or class, optional
            A block of the user's in the place of ``Quaternion_estim`` (see
            :mod:`quadcosim.estimators.contract`), for a scenario with an ``estimator`` option; the
            options name it (``module:Class``).
        fmus : dict, optional
            Block name to an FMU file of the user's with the same interface, put in that
            block's place (:func:`quadcosim.orchestrator.replace.replace_fmu` checks it); the system's
            ``replaced`` says which, with what the new FMU did not take over (also warned).

        Returns
        -------
        Prepared
            The system, the options as read by the run (:attr:`Prepared.options`: each
            ``Block.parameter`` as set) and as stated in ``metrics.json`` (:attr:`Prepared.used`).

        Raises
        ------
        KeyError, ValueError
            An unknown block or parameter, a bad value, or a parameter the scenario sets from
            one of its options (the message names that option).
        """
        from quadcosim.orchestrator.parameters import resolve_all, set_all

        if estimator is not None:
            if "estimator" not in self.options:
                raise ValueError(f"scenario {self.name} has no estimator to replace; {_with_estimator()}")
            from quadcosim.estimators import contract

            options = Options(options | {"estimator": contract.label(estimator)})
            system = self.build(options, estimator=estimator)
        else:
            system = self.build(options)
        system.replaced = {}
        for block, path in (fmus or {}).items():
            import warnings

            from quadcosim.orchestrator.replace import replace_fmu

            new, notes = replace_fmu(system, block, path)
            system.replaced[block] = {"fmu": str(new.path), "notes": notes}
            for note in notes:
                warnings.warn(note, stacklevel=2)
        derived = self.extra.get("derived", {})
        resolved = resolve_all(system, {k: v for k, v in options.items() if "." in k})
        for key, values in resolved.items():
            self._refuse_derived(key, values)
        options = Options(options | set_all(system, resolved, derived))
        return Prepared(system, options, self.used(options))


def _with_estimator() -> str:
    names = [s.name for s in registry().values() if "estimator" in s.options]
    return f"the scenarios with one: {', '.join(names)}"


def run(name: str, settings=None, out_dir=None, progress: bool = False, faults=(), decimation: int = 1,
        record=None, formats=("npz",), overwrite: bool = False, estimator=None, compress: bool = False,
        stream: bool = False, blocks=None, fmus: dict | None = None):
    """Run scenario ``name``; write results, metrics and figures into ``out_dir`` if given.

    Parameters
    ----------
    name : str
        A scenario of :func:`registry`.
    settings : dict or list of str, optional
        Option values, ``{"duration": 5}`` or ``["duration=5"]``, and block parameters
        (``{"IMU.gyro_noise_density": 1e-3}``).
    out_dir : str or pathlib.Path, optional
        Folder of the results, ``metrics.json`` and figures; checked before the run: a folder
        holding earlier results is refused unless ``overwrite``.
    progress : bool
        Progress and status lines on standard error.
    faults : sequence of quadcosim.orchestrator.Fault
        Faults injected; recorded in ``metrics.json``.
    decimation : int
        Keep every N-th macro step; at most the run's number of steps.
    record : list of str, optional
        Signals to keep; ``["all"]`` keeps every output; default: the scenario's choice
        (``extra["record"]``, or every output but ``extra["unrecorded"]``), else all.
    formats : sequence of str
        Result files written (``npz``, ``mat``, ``csv``); the ``.npz`` alone by default.
    overwrite : bool
        Replace the results already in ``out_dir``: every file of the earlier run is removed.
    estimator : quadcosim.orchestrator.Block or class, optional
        A block of the user's (an instance or a class, see :mod:`quadcosim.estimators.contract`) in the
        place of ``Quaternion_estim``.
    compress : bool
        Compress the ``.npz`` and ``.mat`` files (smaller, several times slower to write).
    stream : bool
        Write the record to ``results.stream/`` in chunks as the run goes, so that its memory
        stays flat however long the run (:mod:`quadcosim.orchestrator.stream`); needs ``out_dir`` and
        the ``npz`` format alone.
    blocks : dict, optional
        Blocks of the user's in the place of the scenario's, by name (``{"Controller":
        MyController()}``), each wired as the block it replaces (:meth:`quadcosim.orchestrator.System.replace`).
    fmus : dict, optional
        Block name to the path of an FMU of the user's with the same interface, in that block's
        place (``{"MotorMagnetics": "my_motor.fmu"}``; :meth:`Scenario.system`); recorded in
        ``metrics["replaced_blocks"]``.

    Returns
    -------
    (quadcosim.orchestrator.Result, dict)
        The result and the metrics. ``metrics["options"]`` holds every option's value as
        used (no default markers), ``metrics["units"]`` the units of the metrics and options,
        ``metrics["injected_faults"]`` the faults (:func:`fault_record`).

    Raises
    ------
    ValueError, KeyError
        A refused option, parameter or output folder, before the run starts; nothing is left
        in ``out_dir``, but for an FMU refused before the loop
        (:class:`quadcosim.orchestrator.fmu_checks.FMURefused`): then ``out_dir`` holds a ``metrics.json``
        with ``status: refused``, the message, the options and ``samples: 0``.
    quadcosim.orchestrator.SimulationError
        The run failed (:class:`quadcosim.orchestrator.RunInterrupted`: it was interrupted, in any
        phase); what was recorded is saved all the same, with a ``metrics.json`` saying where
        the run stopped and which files were kept.
    """
    from quadcosim.scenarios.outputs import RunFiles, remove_if_empty

    from quadcosim.infra.files import prepare_out_dir
    from quadcosim.infra.interrupts import first_only, held
    from quadcosim.infra.progress import status

    status(f"{name}: loading the scenario")
    if isinstance(record, str):  # one signal named alone, not its characters
        record = [record]
    files = None
    with first_only(), contextlib.ExitStack() as lock:  # the folder is this run's until it ends
        try:
            with held():  # a signal while the folder is made is raised once the run can record it
                _check_formats(formats, stream, out_dir)
                if name not in names():
                    get(name)  # refused (the nearest names given) before any folder is made
                given = dict(settings_pairs(settings))  # read once; a text with no "=" refused here
                made = out_dir is not None and not Path(out_dir).exists()
                out = prepare_out_dir(out_dir, overwrite, lock) if out_dir else None
                stated = RunStated(name, dict(given), [fault_record(f) for f in faults], decimation)
                try:
                    files = RunFiles(out, formats, stated, {}, compress) if out is not None else None
                except ValueError:  # no room for even metrics.json: refused, the folder left as it was
                    if made:
                        remove_if_empty(out)
                    raise
            with (files.tracking() if files else contextlib.nullcontext()):
                request = RunRequest(tuple(faults), estimator, record, stream, blocks, fmus, decimation)
                return _run_tracked(name, given, files, stated, made, request, progress)
        except KeyboardInterrupt as interrupt:  # as the folder was being made
            if files is None:
                raise
            with files.tracking():
                raise files.interrupted(interrupt) from None


def _run_tracked(name: str, given: dict, files, stated: RunStated, made: bool, request: RunRequest,
                 progress: bool):
    """The run of :func:`run` once its folder is made: load, parse ``given`` (the settings, as
    pairs) and check it before anything is built, then :func:`_run_phases`; an interrupt in any
    phase becomes :class:`quadcosim.orchestrator.RunInterrupted`, a refusal leaves the folder as it was."""
    try:
        scenario = get(name)
        options = scenario.parse(given, fmus=request.fmus)
        stated.options = dict(options)
        if files:
            files.units = {f"options.{k}": o.unit for k, o in scenario.options.items() if o.unit}
        return _run_phases(scenario, options, stated, files, request, progress)
    except KeyboardInterrupt as interrupt:  # outside the loop: loading, building, drawing, saving, reporting
        if files is None:
            raise
        raise files.interrupted(interrupt) from None
    except (KeyError, ValueError) as error:  # refused before the run: the folder is left as it was
        if files is not None and files.result is None:  # but for metrics.json naming an FMU refused
            from quadcosim.orchestrator.fmu_checks import FMURefused

            files.refused(remove_folder=made, fmu_refusal=error if isinstance(error, FMURefused) else None)
        raise
    except OSError as error:  # the disk filled, or the folder failed, outside the loop and the save
        if files is None:
            raise
        raise files.broke(error) from None


def _check_formats(formats, stream: bool, out_dir):
    from quadcosim.orchestrator.result import FORMATS

    unknown = [f for f in formats if f not in FORMATS]
    if unknown or not formats:
        raise ValueError(f"--format {','.join(formats)}: choose among {', '.join(FORMATS)}")
    if stream and (out_dir is None or list(formats) != ["npz"]):
        raise ValueError("--stream writes the record as it goes into OUT/results.stream/: give --out and no "
                         "--format (other formats can be written afterwards: Result.load(folder).save(...))")


def _run_phases(scenario: Scenario, options: Options, stated: RunStated, files, request: RunRequest,
                progress: bool):
    """Build, draw, run, save and report, each phase named in ``files`` for ``metrics.json``;
    ``request`` holds the faults, the user's estimator, blocks and FMUs, the signals to record
    and ``stream``."""
    from quadcosim.orchestrator import SimulationError
    from quadcosim.scenarios.metrics import FAULT_UNITS, metric_units

    from quadcosim.infra.progress import status

    name = scenario.name
    prepared, duration, kept, saved = _build(scenario, options, stated, files, request)
    system, options = prepared.system, prepared.options
    if files:
        files.phase, files.stream = "running", _open_stream(files, request.stream)
    from quadcosim.orchestrator.diagram import blocks_text

    status(f"{name}: starting {duration:g} s of simulated time ({blocks_text(system)})")
    try:
        result = system.run(duration, decimation=request.decimation, progress=progress, record=kept,
                            stream=files.stream if files else None)
    except SimulationError as error:
        if files is not None:
            files.stopped(error)
        raise
    except (KeyError, ValueError):  # refused as the run was set up (a value an FMU refused, memory)
        if files is not None:
            files.refused()
        raise
    result.meta |= {"scenario": {"name": name, "options": stated.options}, "faults": stated.injected_faults}
    if stated.signals_not_saved:  # named in the files, so that asking for one says how to keep it
        result.meta["left_out"] = stated.signals_not_saved
    metrics = stated.metrics() | {"status": "completed", "samples": len(result), "signals_recorded": len(result.names),
                      "fmu_warnings": _warning_counts(result)}
    metrics |= _divergence(scenario, result, options)
    if files is not None:
        files.phase = "saving the record"
        status(f"{name}: writing {', '.join(f'results.{f}' for f in files.formats)} "
               f"({_signals_text(saved, result.names)}, {len(result)} samples)")
        files.keep_record(result)
        if files.not_written:  # a full disk, or no memory left for a writer: metrics.json says which
            raise files.failed("; ".join(f"{file} not written: {why}" for file, why in files.not_written.items()))
        metrics |= files.record_megabytes()
        files.phase = "reporting (metrics and figures)"
    status(f"{name}: report" + (" (metrics and figures)" if files else " (metrics)"))
    metrics |= _report(scenario, result, options, files, request.record)
    declared = scenario.extra.get("units", {}) | (metrics.get("units") or {})  # for names that carry none
    option_units = {f"options.{k}": o.unit for k, o in scenario.options.items() if o.unit}
    metrics["units"] = metric_units(metrics, declared) | option_units | {"injected_faults": FAULT_UNITS}
    if files is not None:
        metrics["save_cpu_s"] = files.save_cpu_seconds
        files.finish(metrics)
    if metrics["status"] == "diverged":
        import warnings

        from quadcosim.scenarios.divergence import message

        warnings.warn(message(name, metrics["diverged"], _settings_given(scenario, options)), stacklevel=2)
    return result, metrics


def _signals_text(saved, recorded) -> str:
    """The signals written, counted as ``metrics.json`` counts them (``signals_recorded``)."""
    if not saved or len(saved) == len(recorded):
        return f"{len(recorded)} signals"
    return (f"{len(saved)} of the {len(recorded)} signals recorded; the others follow from them "
            "(metrics.json: signals_not_saved)")


def _divergence(scenario, result, options) -> dict:
    """``status`` ``diverged`` and the first bound crossed (``diverged``) when the scenario bounds its
    flight (``extra["divergence"]``) and the run crossed a bound; the signals a bound reads that
    were not recorded (``divergence_unchecked``)."""
    bounds = scenario.extra.get("divergence")
    if bounds is None or not len(result):
        return {}
    from quadcosim.scenarios.divergence import first_crossing, unchecked

    found = {}
    missing = unchecked(result, bounds)
    if missing:
        found["divergence_unchecked"] = missing
    crossing = first_crossing(result, bounds)
    if crossing is not None:
        found |= {"status": "diverged", "diverged": crossing | {"settings": _settings_given(scenario, options)}}
    return found


def _settings_given(scenario, options) -> list[str]:
    """The options off their defaults and the block parameters set, as ``key=value``."""
    return [f"{key}={value}" for key, value in options.items()
            if key not in scenario.options or value != scenario.options[key].default]


def _recorded_names(system, kept) -> list[str]:
    """The signals a run records: ``kept`` resolved (vector names expanded), or every output."""
    from quadcosim.scenarios.metrics import recorded_outputs

    if kept is None:
        return recorded_outputs(system)
    return list(dict.fromkeys(name for signal in kept for name in system._resolve(signal, "output")))


def _open_stream(files, stream: bool):
    """The writer of ``results.stream/`` when the record is streamed, else None."""
    if not stream:
        return None
    from quadcosim.orchestrator.result import FOLDER
    from quadcosim.orchestrator.stream import StreamWriter

    return StreamWriter(files.out / FOLDER)


def _build(scenario: Scenario, options: Options, stated: RunStated, files, request: RunRequest):
    """The prepared system (:meth:`Scenario.prepare`), its duration (s), the signals recorded and
    those written (``stated`` takes the options as used, the duration, the FMUs replaced and the
    signals left out of the files). A refusal removes what this run wrote."""
    from quadcosim.infra.progress import status

    if files:
        files.phase = "building the system"
    status(f"{scenario.name}: building the system")
    try:
        prepared = scenario.prepare(options, estimator=request.estimator, fmus=request.fmus)
        system = prepared.system
        stated.replaced_blocks = system.replaced or None
        for block_name, block in (request.blocks or {}).items():
            system.replace(block_name, block)
        for fault in request.faults:
            system.inject(fault)
        duration = scenario.duration(prepared.options) if scenario.duration else prepared.options["duration"]
        _check_decimation(request.decimation, duration, system.dt)
        stated.options, stated.duration_s = prepared.used, duration
        kept, saved, stated.signals_not_saved = _signals_kept(scenario, system, request.record)
        if files:
            files.saved = saved
            recorded = _recorded_names(system, kept)
            rows = int(round(duration / system.dt)) // request.decimation + 1
            files.check_room(rows, recorded, saved or recorded, request.decimation, request.stream)
            _draw(scenario, system, prepared.options, files)
    except (KeyError, ValueError):
        if files:
            files.refused()
        raise
    return prepared, duration, kept, saved


def _check_decimation(decimation: int, duration: float, dt: float):
    steps = int(round(duration / dt))
    if decimation > steps:
        raise ValueError(f"--decimation {decimation} is more than the run's {steps} steps ({duration:g} s every "
                         f"{dt:g} s): it would record the first sample alone. Give at most --decimation {steps}, "
                         "or a longer run")


def _draw(scenario, system, options, files):
    from quadcosim.infra.progress import status

    if scenario.extra.get("diagram"):  # the wiring of this run, drawn before it runs
        from quadcosim.orchestrator.diagram import draw

        files.phase = "drawing the wiring diagram"
        status(f"{scenario.name}: wiring diagram")
        draw(system, files.out / "diagram.png", scenario.title(options), cache=diagram_cache())


def diagram_cache() -> Path:
    """Where runs keep the wiring diagrams they drew, by a digest of the wiring
    (:func:`quadcosim.orchestrator.diagram.wiring_key`): ``$QUADCOSIM_DIAGRAM_CACHE`` if set, else
    ``diagrams/`` beside the built FMUs."""
    import os

    from quadcosim.fmus import build_root

    return Path(os.environ.get("QUADCOSIM_DIAGRAM_CACHE") or build_root() / "diagrams")


def _report(scenario, result, options, files, record) -> dict:
    """The scenario's metrics (and figures); a report that fails keeps the saved record."""
    from quadcosim.scenarios.figures import closed_on_failure

    try:
        with closed_on_failure():
            return scenario.report(result, options, files.out if files else None)
    except KeyError as error:
        if not record:
            if files is None:
                raise
            raise files.failed(f"the report failed: KeyError: {error}") from error
        # the report needs a signal the user chose not to record: the results stand alone
        return {"report": f"report skipped: {error.args[0]} (add it to --record for the report)"}
    except Exception as error:
        from quadcosim.infra.interrupts import interrupt_for, stopping

        if stopping() is not None:  # a signal surfaced as another error inside a C extension (a figure's)
            raise interrupt_for(stopping()) from error
        if files is None:
            raise
        from quadcosim.infra.files import DiskFull

        what = str(error) if isinstance(error, DiskFull) else f"{type(error).__name__}: {error}"
        raise files.failed(f"the report failed: {what}") from error


def fault_record(fault) -> dict:
    """A fault as recorded with a run (``metrics.json``, the result files' meta, figure titles).

    Parameters
    ----------
    fault : quadcosim.orchestrator.Fault

    Returns
    -------
    dict
        ``target``, ``kind``, ``start`` and ``stop`` (s), ``value`` (the target's unit; a factor
        for ``scale``; None for a held value or a dropout), ``seed`` (of a noise fault).
    """
    return {"target": fault.target, "kind": fault.kind, "start": fault.start, "stop": fault.stop,
            "value": fault.value, "seed": fault.seed}


def _signals_kept(scenario, system, record) -> tuple[list[str] | None, list[str] | None, list[str] | None]:
    """The signals to record, those to write into the result files (None: all), and those
    recorded but left out of the files (None: none is).

    ``record`` chooses (``["all"]``: every output, recorded and written); else the scenario:
    ``extra["record"]`` lists what it records, ``extra["unrecorded"]`` what its files leave out
    (recorded all the same, for the report and for Python callers), the third list.
    """
    from quadcosim.scenarios.metrics import recorded_outputs

    if record == ["all"]:
        return None, None, None
    if record:
        return record, None, None
    if "unrecorded" in scenario.extra:
        every = recorded_outputs(system)
        saved = recorded_outputs(system, scenario.extra["unrecorded"])
        return None, saved, [n for n in every if n not in set(saved)]
    return scenario.extra.get("record"), None, None


def _warning_counts(result) -> dict:
    """Per FMU block that warned: ``{"count": n, "first": [the first few messages]}``."""
    return dict(result.meta.get("fmu_warnings", {}))
