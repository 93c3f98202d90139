"""Named scenarios: one command runs one and leaves results, figures and metrics behind.

A scenario declares its options (each with a default, a unit or choices, and a help text),
builds a :class:`orchestrator.System` from them, and reports on the result: it writes its
figures and returns its metrics. :func:`run` does the rest: results (``results.npz``,
``results.mat``), ``metrics.json``, and on a failure what was recorded up to it.
"""

from __future__ import annotations

import importlib
import math
from dataclasses import dataclass, field
from pathlib import Path

# scenario name -> module of scenarios declaring it: a look-up imports that module alone
_MODULES = {"open-loop": "open_loop", "rig": "rig", "tp": "tp", "gain-study": "gain_study",
            "static-cal": "static_cal", "metge": "metge", "ir-calibration": "ir_calibration"}


@dataclass
class Option:
    default: object
    help: str
    choices: tuple | None = None
    minimum: float | None = None
    classes: bool = False  # beside the choices, a block class of the user's, "module:Class"

    def parse(self, name: str, text):
        """The option's value from text, checked against its type, choices and minimum.

        Parameters
        ----------
        name : str
            Option name, for messages.
        text : str or value
            ``"0.5"``, ``"true"``, ...

        Returns
        -------
        object
            The value, of the default's type.

        Raises
        ------
        ValueError
            Not a valid value; the message says what is expected.
        """
        default = self.default
        try:
            if isinstance(default, bool):
                if str(text).lower() in ("1", "true", "on", "yes"):
                    value = True
                elif str(text).lower() in ("0", "false", "off", "no"):
                    value = False
                else:
                    raise ValueError(text)
            elif isinstance(default, int):
                value = int(text)
            elif isinstance(default, float):
                value = float(text)
                if not math.isfinite(value):
                    raise ValueError(text)
            else:
                value = str(text)
        except ValueError:
            raise ValueError(f"option {name}={text!r} is not a valid {type(default).__name__}") from None
        if self.choices and value not in self.choices and not (self.classes and ":" in value):
            other = " or module:Class (a block of your own)" if self.classes else ""
            raise ValueError(f"option {name}={text!r} must be one of {', '.join(map(str, self.choices))}{other}")
        if self.minimum is not None and value < self.minimum:
            raise ValueError(f"option {name}={value} must be at least {self.minimum}")
        return value


@dataclass
class Scenario:
    name: str
    description: str
    options: dict[str, Option]
    build: object  # (options) -> System
    report: object  # (result, options, out_dir) -> metrics dict
    duration: object = None  # (options) -> seconds
    extra: dict = field(default_factory=dict)

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

    def parse(self, settings: dict | list | None) -> dict:
        """Options with defaults, from ``settings`` ``{"k": v}`` or ``["k=v", ...]`` (None: all
        defaults); refuses unknown keys.

        A key ``Block.parameter`` sets a block parameter (``IMU.gyro_noise_density``); it is
        kept as given and checked against the block when :meth:`system` builds the system.
        """
        values = {k: o.default for k, o in self.options.items()}
        pairs = settings.items() if isinstance(settings, dict) else [_split(s) for s in settings or []]
        for key, text in pairs:
            if "." in key:
                values[key] = text
                continue
            if key not in self.options:
                from orchestrator.fmu import nearest

                raise ValueError(f"unknown option {key!r} for scenario {self.name}.{nearest(key, self.options)} "
                                 f"Options: {', '.join(self.options)} (see `quadcosim list`).")
            values[key] = self.options[key].parse(key, text)
        return values


    def system(self, options: dict, estimator=None):
        """The system of these options: built, then its block parameters set.

        Parameters
        ----------
        options : dict
            From :meth:`parse`. Its ``Block.parameter`` entries are set on the built system
            (checked against the FMU's variable table) and replaced by the values used.
        estimator : Block or class, optional
            A block of the user's in the place of ``Quaternion_estim`` (see
            :mod:`estimators.contract`), for a scenario with an ``estimator`` option.

        Raises
        ------
        KeyError, ValueError
            An unknown block or parameter, a bad value, or a parameter the scenario sets from
            one of its options (the message names that option).
        """
        from orchestrator.parameters import apply, resolve

        if estimator is not None:
            if "estimator" not in self.options:
                raise ValueError(f"scenario {self.name} has no estimator to replace; {_with_estimator()}")
            system = self.build(options, estimator=estimator)
        else:
            system = self.build(options)
        settings = {k: v for k, v in options.items() if "." in k}
        derived = self.extra.get("derived", {})
        for key in settings:
            block = key.partition(".")[0]
            for name in resolve(system, key, settings[key]):
                option = derived.get(f"{block}.{name}")
                if option is not None:
                    raise ValueError(f"{block}.{name} is set by scenario {self.name}'s option {option}: "
                                     f"use --set {option}=... instead of {key}")
        options.update(apply(system, settings, derived))
        return system


def _with_estimator() -> str:
    names = [s.name for s in registry().values() if "estimator" in s.options]
    return f"the scenarios with one: {', '.join(names)}"


def _split(text: str) -> tuple[str, str]:
    key, eq, value = text.partition("=")
    if not eq:
        raise ValueError(f"--set {text!r}: write key=value")
    return key.strip(), value.strip()


def names() -> tuple[str, ...]:
    """The scenarios' names, without importing any scenario module."""
    return tuple(_MODULES)


def registry() -> dict[str, Scenario]:
    """Every scenario, by name (imports every scenario module; :func:`get` imports one)."""
    return {name: get(name) for name in _MODULES}


def get(name: str) -> Scenario:
    """The scenario called ``name``, importing its module only.

    Parameters
    ----------
    name : str
        Scenario name, e.g. ``"tp"`` (see :func:`names`).

    Returns
    -------
    Scenario
        The scenario's declaration.

    Raises
    ------
    KeyError
        Unknown name; the message names the nearest. A listed module that is missing, or
        that declares another name, is an error, not a gap.
    """
    if name not in _MODULES:
        from orchestrator.fmu import nearest

        raise KeyError(f"unknown scenario {name!r}.{nearest(name, _MODULES)} Scenarios: {', '.join(_MODULES)}.")
    scenario = importlib.import_module(f"scenarios.{_MODULES[name]}").SCENARIO
    if scenario.name != name:
        raise RuntimeError(f"scenarios.{_MODULES[name]} declares {scenario.name!r}, registered as {name!r}")
    return scenario


def run(name: str, settings=None, out_dir=None, progress: bool = False, faults=(), decimation: int = 1,
        record=None, formats=("npz", "mat"), overwrite: bool = False, estimator=None):
    """Run scenario ``name`` with the options ``settings`` (as :meth:`Scenario.parse` takes them);
    write results, metrics and figures into ``out_dir`` if given. ``progress`` shows a progress
    bar on long runs; ``faults`` are :class:`orchestrator.Fault` injected into the run.

    ``decimation`` keeps every N-th macro step; ``record`` lists the signals to keep (default:
    the scenario's choice, else all); ``formats`` are the result files written (``npz``,
    ``mat``, ``csv``). ``out_dir`` is checked before the run: a folder holding earlier results
    is refused unless ``overwrite``. ``settings`` may set block parameters
    (``{"IMU.gyro_noise_density": 1e-3}``); ``estimator`` puts a block of the user's (an
    instance or a class, see :mod:`estimators.contract`) in the place of ``Quaternion_estim``.

    Returns ``(result, metrics)``. On a failure or an interrupt, what was recorded is saved all
    the same, with a ``metrics.json`` saying where the run stopped, and
    :class:`orchestrator.SimulationError` (:class:`orchestrator.RunInterrupted`) is raised.
    """
    from orchestrator import RunInterrupted, SimulationError
    from orchestrator.files import prepare_out_dir
    from orchestrator.interrupts import signal_name
    from orchestrator.result import FORMATS

    scenario = get(name)
    options = scenario.parse(settings)
    unknown = [f for f in formats if f not in FORMATS]
    if unknown or not formats:
        raise ValueError(f"--format {','.join(formats)}: choose among {', '.join(FORMATS)}")
    out = prepare_out_dir(out_dir, overwrite) if out_dir else None
    system = scenario.system(options, estimator=estimator)
    for fault in faults:
        system.inject(fault)
    if out is not None and scenario.extra.get("diagram"):  # the wiring of this run, drawn before it runs
        from orchestrator.diagram import draw

        draw(system, out / "diagram.png", scenario.title(options))
    duration = scenario.duration(options) if scenario.duration else options["duration"]
    base = {"scenario": name, "options": options, "duration_s": duration, "decimation": decimation}
    try:
        result = system.run(duration, decimation=decimation, progress=progress,
                            record=record if record else scenario.extra.get("record"))
    except SimulationError as error:
        partial = error.result
        if out is not None and partial is not None:
            partial.meta["scenario"] = {"name": name, "options": options}
            partial.meta["faults"] = [fault_record(f) for f in faults]
            written = partial.save(out, formats=formats)
            stopped = {"status": "interrupted" if isinstance(error, RunInterrupted) else "failed",
                       "error": str(error),
                       "recorded_until_s": float(partial.time[-1]) if len(partial) else None,
                       "samples": len(partial),
                       "fmu_warnings": _warning_counts(partial)}
            if isinstance(error, RunInterrupted):
                stopped["interrupted_by"] = signal_name(error.signal_number)
            _write_metrics(out, base | stopped | {"files": sorted(p.name for p in written)})
        raise
    result.meta["scenario"] = {"name": name, "options": options}
    result.meta["faults"] = [fault_record(f) for f in faults]
    metrics = base | {"status": "completed", "samples": len(result), "fmu_warnings": _warning_counts(result)}
    written = result.save(out, formats=formats) if out is not None else []
    try:
        metrics |= scenario.report(result, options, out)
    except KeyError as error:
        if not record:
            raise
        # the report needs a signal the user chose not to record: the results stand alone
        metrics["report"] = f"report skipped: {error.args[0]} (add it to --record for the report)"
    if out is not None:
        figures = sorted(p.name for p in out.iterdir() if p.suffix in (".png", ".svg", ".pdf"))
        _write_metrics(out, metrics | {"files": sorted([p.name for p in written] + figures)})
    return result, metrics


def fault_record(fault) -> dict:
    """A fault as recorded with a run: target, kind, start and stop (s), value (the signal's unit).

    Parameters
    ----------
    fault : orchestrator.Fault

    Returns
    -------
    dict
    """
    return {"target": fault.target, "kind": fault.kind, "start": fault.start, "stop": fault.stop,
            "value": fault.value}


def _warning_counts(result) -> dict:
    """Per FMU block that warned: ``{"count": n, "first": [the first few messages]}``."""
    return dict(result.meta.get("fmu_warnings", {}))


def _write_metrics(out: Path, metrics: dict):
    from orchestrator.files import write_json

    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "metrics.json", metrics)
