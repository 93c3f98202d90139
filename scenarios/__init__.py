"""Named scenarios: one command runs one and leaves results, figures and metrics behind.

A scenario declares its options (each with a default, a unit or choices, and a help text),
builds a :class:`orchestrator.System` from them, and reports on the result: it writes its
figures and returns its metrics. :func:`run` does the rest: results (``results.npz``,
``results.mat``), ``metrics.json``, and on a failure what was recorded up to it.
"""

from __future__ import annotations

import importlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from orchestrator.fmu import nearest

_MODULES = ("open_loop", "rig", "tp", "gain_study")


@dataclass
class Option:
    default: object
    help: str
    choices: tuple | None = None
    minimum: float | None = None

    def parse(self, name: str, text):
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
        if self.choices and value not in self.choices:
            raise ValueError(f"option {name}={text!r} must be one of {', '.join(map(str, self.choices))}")
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

    def parse(self, settings: dict | list | None) -> dict:
        """Options with defaults, from ``{"k": v}`` or ``["k=v", ...]``; refuses unknown keys."""
        values = {k: o.default for k, o in self.options.items()}
        pairs = settings.items() if isinstance(settings, dict) else [_split(s) for s in settings or []]
        for key, text in pairs:
            if key not in self.options:
                raise ValueError(f"unknown option {key!r} for scenario {self.name}.{nearest(key, self.options)} "
                                 f"Options: {', '.join(self.options)} (see `quadcosim list`).")
            values[key] = self.options[key].parse(key, text)
        return values


def _split(text: str) -> tuple[str, str]:
    key, eq, value = text.partition("=")
    if not eq:
        raise ValueError(f"--set {text!r}: write key=value")
    return key.strip(), value.strip()


def registry() -> dict[str, Scenario]:
    """Every scenario, by name. A module listed here that is missing is an error, not a gap."""
    scenarios = {}
    for module in _MODULES:
        scenario = importlib.import_module(f"scenarios.{module}").SCENARIO
        scenarios[scenario.name] = scenario
    return scenarios


def get(name: str) -> Scenario:
    scenarios = registry()
    if name not in scenarios:
        raise KeyError(f"unknown scenario {name!r}.{nearest(name, scenarios)} Scenarios: {', '.join(scenarios)}.")
    return scenarios[name]


def run(name: str, settings=None, out_dir=None, progress: bool = False, faults=()):
    """Run scenario ``name``; write results, metrics and figures into ``out_dir`` if given.

    Returns ``(result, metrics)``. On a failure, what was recorded is saved all the same and
    :class:`orchestrator.SimulationError` is raised.
    """
    from orchestrator import SimulationError

    scenario = get(name)
    options = scenario.parse(settings)
    system = scenario.build(options)
    for fault in faults:
        system.inject(fault)
    duration = scenario.duration(options) if scenario.duration else options["duration"]
    out = Path(out_dir) if out_dir else None
    try:
        result = system.run(duration, progress=progress, record=scenario.extra.get("record"))
    except SimulationError as error:
        if out is not None and error.result is not None:
            error.result.meta["scenario"] = {"name": name, "options": options}
            error.result.save(out)
            _write_metrics(out, {"scenario": name, "options": options, "error": str(error),
                                 "recorded_until_s": float(error.result.time[-1]) if len(error.result) else None})
        raise
    result.meta["scenario"] = {"name": name, "options": options}
    metrics = {"scenario": name, "options": options}
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        result.save(out)
    metrics |= scenario.report(result, options, out)
    if out is not None:
        _write_metrics(out, metrics)
    return result, metrics


def _write_metrics(out: Path, metrics: dict):
    out.mkdir(parents=True, exist_ok=True)
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2, default=float) + "\n")
