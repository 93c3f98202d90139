"""The members of a sweep: grids and lists over a scenario's options, fixed options, seeds.

A grid value is written on the command line as ``NAME=SPEC``:

- ``a,b,c``: a list (``estimator=linear,explicit``, ``noise=on,off``);
- ``start:stop:logN``: ``N`` values spaced evenly in log between ``start`` and ``stop``;
- ``start:stop:linN``: ``N`` values spaced evenly between ``start`` and ``stop``;
- ``start:stop``: the integers from ``start`` to ``stop`` inclusive (seeds).

Every value is parsed by the scenario's own option (type, choices, minimum), so that a bad
member is refused before any run.
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass, field

import numpy as np

_RANGE = re.compile(r"^\s*([^:]+):([^:]+)(?::(log|lin)(\d+))?\s*$")


def _number(text: str, where: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"{where}: {text!r} is not a number") from None


def values_of(spec: str, where: str = "--grid") -> list:
    """The raw values (numbers or strings, not yet typed) of one grid specification ``spec``
    (``a,b,c`` or a range); ``where`` names it in error messages."""
    match = _RANGE.match(spec)
    if match is None or "," in spec:
        items = [item.strip() for item in spec.split(",")]
        if not spec.strip() or any(not item for item in items):
            raise ValueError(f"{where}: empty value in {spec!r}; write a,b,c or start:stop:logN")
        return items
    start, stop = _number(match[1], where), _number(match[2], where)
    if match[3] is None:
        if start != int(start) or stop != int(stop) or stop < start:
            raise ValueError(f"{where}: {spec!r} is an integer range start:stop with start <= stop; "
                             "for real values write start:stop:logN or start:stop:linN")
        return list(range(int(start), int(stop) + 1))
    count = int(match[4])
    if count < 1:
        raise ValueError(f"{where}: {spec!r} asks for no value")
    if match[3] == "log":
        if start <= 0 or stop <= 0:
            raise ValueError(f"{where}: {spec!r}: a log grid needs positive bounds")
        points = np.geomspace(start, stop, count)
    else:
        points = np.linspace(start, stop, count)
    # 12 significant digits: 0.1 rather than 0.10000000000000002 in tables and folder names.
    return [float(f"{p:.12g}") for p in points]


def _text(value) -> str:
    """A grid value as the option parser reads it: 2.0 as "2", so that integer options take it."""
    return str(int(value)) if isinstance(value, float) and value.is_integer() else str(value)


def split_assignment(text: str, flag: str) -> tuple[str, str]:
    """``text`` ``"k=0.1,1"`` as ``("k", "0.1,1")``; a clear error naming ``flag`` otherwise."""
    name, eq, spec = text.partition("=")
    if not eq or not name.strip():
        raise ValueError(f"{flag} {text!r}: write NAME=VALUES, e.g. k=0.01:10:log12 or estimator=linear,explicit")
    return name.strip(), spec.strip()


@dataclass
class Member:
    """One run of a sweep: its index, a label, and the scenario's options, complete and typed."""

    index: int
    options: dict
    label: str = ""


@dataclass
class Plan:
    """What a sweep runs: a scenario and its members, with the command-line description kept;
    ``varied`` are the options the grid varies, ``name`` a named sweep's name (else None)."""

    scenario: str
    members: list[Member]
    varied: list[str] = field(default_factory=list)
    description: dict = field(default_factory=dict)
    name: str | None = None  # a named sweep's name

    def to_json(self) -> dict:
        """The plan as stored in ``sweep.json`` (every member's options)."""
        return {"scenario": self.scenario, "name": self.name, "varied": self.varied,
                "description": self.description,
                "members": [{"label": m.label, "options": m.options} for m in self.members]}


def plan(scenario_name: str, grids=(), settings=(), seeds: str | None = None) -> Plan:
    """Expand ``--grid`` and ``--set`` strings (and ``--seeds``) into typed members.

    Parameters
    ----------
    scenario_name : str
        A registered scenario (``quadcosim list``).
    grids : list of str
        ``NAME=SPEC`` strings (see the module documentation); the first varies slowest.
    settings : list of str
        ``NAME=VALUE`` fixed options.
    seeds : str, optional
        ``N`` (seeds 1 to N) or ``start:stop``: the scenario's ``seed`` option as the last,
        fastest-varying dimension (Monte Carlo).
    """
    import scenarios

    scenario = scenarios.get(scenario_name)
    fixed = dict(split_assignment(s, "--set") for s in settings)
    dimensions: dict[str, list] = {}
    for text in grids:
        name, spec = split_assignment(text, "--grid")
        if name in dimensions:
            raise ValueError(f"--grid {name} is given twice; put all its values in one --grid")
        dimensions[name] = values_of(spec, f"--grid {name}")
    if seeds is not None:
        if "seed" not in scenario.options:
            raise ValueError(f"scenario {scenario_name} has no seed option; --seeds does not apply to it")
        if "seed" in dimensions or "seed" in fixed:
            raise ValueError("--seeds and a seed in --grid or --set: give the seeds once")
        spec = seeds if ":" in str(seeds) else f"1:{int(seeds)}"
        dimensions["seed"] = values_of(spec, "--seeds")
    for name in dimensions:
        if name in fixed:
            raise ValueError(f"option {name} is both varied (--grid) and fixed (--set); keep one")
    # Type and check every value once, through the scenario's own options.
    scenario.parse(fixed)
    typed = {name: [scenario.parse({name: _text(v)})[name] for v in values] for name, values in dimensions.items()}
    for name, values in typed.items():
        if len(set(map(repr, values))) != len(values):
            raise ValueError(f"--grid {name}: repeated values {values}")
    members = _distinct_members(scenario, fixed, typed, seeds is not None)
    return Plan(scenario_name, members, list(typed),
                {"grid": list(grids), "set": list(settings), "seeds": seeds})


def _shown(value) -> str:
    """An option value as a user writes it: on/off for a switch."""
    return ("on" if value else "off") if isinstance(value, bool) else str(value)


def _distinct_members(scenario, fixed: dict, typed: dict, seeds_given: bool) -> list[Member]:
    """The grid's members, each distinct run once: a varied option that acts on nothing in a
    member (``k`` with ``estimator=explicit``, ``seed`` with ``noise=off``; the options'
    ``applies``) makes duplicates of that member: the first is kept, the others dropped, and a
    warning says which option, for which members, and how many runs it saved."""
    import warnings

    members, seen, dropped = [], {}, {}
    for combination in itertools.product(*typed.values()):
        chosen = dict(zip(typed, combination, strict=True))
        options = scenario.parse(fixed | chosen)
        inert = [name for name in scenario.inert(options) if name in typed]
        key = repr(sorted((k, "inert" if k in inert else v) for k, v in options.items()))
        if key in seen:
            for name in inert:
                other = scenario.options[name].applies.partition("=")[0]
                values, count, kept = dropped.get(name, (set(), 0, seen[key][name]))
                dropped[name] = (values | {_shown(options[other])}, count + 1, kept)
            continue
        seen[key] = options
        label = " ".join(f"{k}={v}" for k, v in chosen.items() if k not in inert)
        members.append(Member(len(members), options, label))
    total = int(np.prod([len(v) for v in typed.values()])) if typed else 1
    for name, (values, count, kept) in dropped.items():
        condition = scenario.options[name].applies
        flag = "--seeds" if name == "seed" and seeds_given else f"--grid {name}"
        warnings.warn(f"{flag}: {name} acts only when {condition}; with {condition.partition('=')[0]}="
                      f"{'/'.join(sorted(values))} it varies nothing, so those members run once, at {name}={kept} "
                      f"({count} duplicate members of {total} dropped)",
                      stacklevel=3)
    return members


def plan_of_cases(scenario_name: str, cases: dict[str, dict], name: str | None = None) -> Plan:
    """A plan of the scenario ``scenario_name`` from named ``cases`` (label -> options), as a named
    sweep (its ``name``) declares them."""
    import scenarios

    scenario = scenarios.get(scenario_name)
    members = [Member(i, scenario.parse(options), label) for i, (label, options) in enumerate(cases.items())]
    varied = sorted({k for options in cases.values() for k in options}, key=list(scenario.options).index)
    return Plan(scenario_name, members, varied, {"cases": list(cases)}, name=name)
