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

import bisect
import itertools
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

_RANGE = re.compile(r"^\s*([^:]+):([^:]+)(?::(log|lin)(\d+))?\s*$")


def _number(text: str, where: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"{where}: {text!r} is not a number") from None


#: The most members a plan may have unless asked for more (``max_members``, ``--max-members``).
MAX_MEMBERS = 1_000_000


def count_of(spec: str, where: str = "--grid") -> int:
    """How many values the grid specification ``spec`` stands for, found without making them (a
    range of 10^8 values is counted, not built); ``where`` names it in error messages."""
    match = _RANGE.match(spec)
    if match is None or "," in spec:
        return len(spec.split(","))
    start, stop = _number(match[1], where), _number(match[2], where)
    if match[3] is None:
        if not (math.isfinite(start) and math.isfinite(stop)) or start != int(start) or stop != int(stop) \
                or stop < start:
            return 1  # refused, with its reason, by values_of
        return int(stop) - int(start) + 1
    return int(match[4])


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


class GridMembers(Sequence):
    """The members of a grid, made when asked for, never all held: member ``i`` is the
    ``i``-th combination of the dimensions, the last varying fastest, over the options
    ``base`` (every option typed, as the scenario parses them). A plan of a million members
    takes the memory of its dimensions.

    Parameters
    ----------
    base : dict
        The options every member shares (defaults and ``--set``).
    dimensions : dict of str to list
        Each varied option's typed values, slowest first.
    """

    def __init__(self, base: dict, dimensions: dict[str, list]):
        self.base, self.dimensions = base, dimensions
        self._sizes = [len(values) for values in dimensions.values()]
        self._count = math.prod(self._sizes)

    def __len__(self) -> int:
        return self._count

    def __getitem__(self, index):
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(self._count))]
        if index < 0:
            index += self._count
        if not 0 <= index < self._count:
            raise IndexError(f"member {index} of a plan of {self._count}")
        picked, rest = [], index
        for size in reversed(self._sizes):
            rest, position = divmod(rest, size)
            picked.append(position)
        values = {name: values[k] for (name, values), k in zip(self.dimensions.items(), reversed(picked), strict=True)}
        return Member(index, self.base | values, " ".join(f"{k}={v}" for k, v in values.items()))


class ChainedMembers(Sequence):
    """Several grids' members one after the other, numbered on: the distinct members of a grid in
    which an option acts on nothing for some members (:func:`distinct_members`).

    Parameters
    ----------
    parts : list of GridMembers
        The grids, in order.
    """

    def __init__(self, parts: list[GridMembers]):
        self.parts = parts
        self.starts = list(itertools.accumulate([0] + [len(part) for part in parts]))

    def __len__(self) -> int:
        return self.starts[-1]

    def __getitem__(self, index):
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        if index < 0:
            index += len(self)
        if not 0 <= index < len(self):
            raise IndexError(f"member {index} of a plan of {len(self)}")
        part = bisect.bisect_right(self.starts, index) - 1
        member = self.parts[part][index - self.starts[part]]
        return Member(index, member.options, member.label)


@dataclass
class Plan:
    """What a sweep runs: a scenario and its members, with the command-line description kept;
    ``varied`` are the options the grid varies, ``name`` a named sweep's name (else None).
    ``members`` is a list, or a :class:`GridMembers` for a grid (made as they are read)."""

    scenario: str
    members: Sequence
    varied: list[str] = field(default_factory=list)
    description: dict = field(default_factory=dict)
    name: str | None = None  # a named sweep's name

    def to_json(self) -> dict:
        """The plan as stored in ``sweep.json``: a grid by its shared options and dimensions,
        named cases one by one (:func:`stored_members` reads either back)."""
        stored = {"scenario": self.scenario, "name": self.name, "varied": self.varied,
                  "description": self.description, "count": len(self.members)}
        if isinstance(self.members, GridMembers):
            return stored | {"base": self.members.base, "dimensions": self.members.dimensions}
        if isinstance(self.members, ChainedMembers):
            return stored | {"parts": [{"base": p.base, "dimensions": p.dimensions} for p in self.members.parts]}
        return stored | {"members": [{"label": m.label, "options": m.options} for m in self.members]}


def stored_members(stored: dict) -> Sequence:
    """The members of a plan as :meth:`Plan.to_json` stored it (``sweep.json``, read back)."""
    if "members" in stored:
        return [Member(i, m["options"], m["label"]) for i, m in enumerate(stored["members"])]
    if "parts" in stored:
        return ChainedMembers([GridMembers(p["base"], p["dimensions"]) for p in stored["parts"]])
    return GridMembers(stored["base"], stored["dimensions"])


def _typed(scenario, name: str, values: list) -> list:
    """``values`` of option ``name`` typed and checked as :meth:`quadcosim.scenarios.Scenario.parse` does it
    (a block parameter, ``Block.name``, is kept as text and checked when a system is built)."""
    if "." in name:
        return [_text(v) for v in values]
    if name not in scenario.options:
        scenario.parse({name: _text(values[0])})  # refuses the unknown name, naming the nearest
    option = scenario.options[name]
    return [option.parse(name, _text(v)) for v in values]


def plan(scenario_name: str, grids=(), settings=(), seeds: str | None = None,
         max_members: int = MAX_MEMBERS) -> Plan:
    """Expand ``--grid`` and ``--set`` strings (and ``--seeds``) into typed members.

    The members are counted from the specifications before any value is made, and a plan of
    more than ``max_members`` is refused with its count; the members themselves are made
    when read (:class:`GridMembers`).

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
    max_members : int
        The most members accepted.

    Raises
    ------
    ValueError
        A bad specification or value (the message names it), or too many members.
    """
    from quadcosim import scenarios

    scenario = scenarios.get(scenario_name)
    fixed = dict(split_assignment(s, "--set") for s in settings)
    specs: dict[str, tuple[str, str]] = {}
    for text in grids:
        name, spec = split_assignment(text, "--grid")
        if name in specs:
            raise ValueError(f"--grid {name} is given twice; put all its values in one --grid")
        specs[name] = (spec, f"--grid {name}")
    if seeds is not None:
        if "seed" not in scenario.options:
            raise ValueError(f"scenario {scenario_name} has no seed option; --seeds does not apply to it")
        if "seed" in specs or "seed" in fixed:
            raise ValueError("--seeds and a seed in --grid or --set: give the seeds once")
        try:
            specs["seed"] = (seeds if ":" in str(seeds) else f"1:{int(seeds)}", "--seeds")
        except ValueError:
            raise ValueError(f"--seeds {seeds!r}: give a count N or a range A:B") from None
    for name in specs:
        if name in fixed:
            raise ValueError(f"option {name} is both varied (--grid) and fixed (--set); keep one")
    counts = {name: count_of(spec, where) for name, (spec, where) in specs.items()}
    total = math.prod(counts.values())
    if total > max_members:
        sizes = f" ({' x '.join(f'{counts[name]:,} {name}' for name in counts)})" if counts else ""
        raise ValueError(f"the plan has {total:,} member{'s' * (total != 1)}{sizes}, more than the {max_members:,} "
                         "allowed: narrow the grid, or raise the limit (--max-members)")
    # Type and check every value once, through the scenario's own options.
    base = scenario.parse(fixed)
    typed = {name: _typed(scenario, name, values_of(spec, where)) for name, (spec, where) in specs.items()}
    for name, values in typed.items():
        if len(set(map(repr, values))) != len(values):
            raise ValueError(f"--grid {name}: repeated values {values}")
    return Plan(scenario_name, distinct_members(scenario, base, typed, seeds is not None), list(typed),
                {"grid": list(grids), "set": list(settings), "seeds": seeds})


def _shown(value) -> str:
    """An option value as a user writes it: on/off for a switch."""
    return ("on" if value else "off") if isinstance(value, bool) else str(value)


def distinct_members(scenario, base: dict, typed: dict, seeds_given: bool = False) -> Sequence:
    """The grid's members, each distinct run once.

    A varied option that acts on nothing in some members (``k`` with ``estimator=explicit``,
    ``seed`` with ``noise=off``: the options' ``applies``) would make duplicates of them: there
    it keeps its first value only, and a warning says which option, for which members, and how
    many runs that saves. The grid is split by the values of the options such conditions name
    (a few), each part a lazy :class:`GridMembers`, so a large plan is never held.

    Parameters
    ----------
    scenario : quadcosim.scenarios.Scenario
    base : dict
        The options every member shares, typed.
    typed : dict of str to list
        The varied options' typed values, slowest first.
    seeds_given : bool
        The ``seed`` dimension came from ``--seeds`` (named so in the warning).

    Returns
    -------
    GridMembers or ChainedMembers
        The plain grid when every option acts in every member.
    """
    import warnings

    rules = {name: scenario.options[name].applies for name in typed
             if name in scenario.options and scenario.options[name].applies}
    controllers = [name for name in typed if name in {rule.partition("=")[0] for rule in rules.values()}]
    parts, dropped = [], {}
    for combination in itertools.product(*(typed[name] for name in controllers)):
        chosen = dict(zip(controllers, combination, strict=True))
        inert = [name for name in scenario.inert(base | chosen) if name in rules and name not in controllers]
        dimensions = {name: [chosen[name]] if name in chosen else values
                      for name, values in typed.items() if name not in inert}
        part = GridMembers(base | {name: typed[name][0] for name in inert}, dimensions)
        saved = len(part) * math.prod(len(typed[name]) for name in inert) - len(part)
        for name in inert:
            other = rules[name].partition("=")[0]
            values, count = dropped.get(name, (set(), 0))
            dropped[name] = (values | {_shown((base | chosen)[other])}, count + saved)
        parts.append(part)
    if not dropped:
        return GridMembers(base, typed)
    total = math.prod(len(values) for values in typed.values())
    for name, (values, count) in dropped.items():
        condition = rules[name]
        flag = "--seeds" if name == "seed" and seeds_given else f"--grid {name}"
        warnings.warn(f"{flag}: {name} acts only when {condition}; with {condition.partition('=')[0]}="
                      f"{'/'.join(sorted(values))} it varies nothing, so those members run once, at "
                      f"{name}={typed[name][0]} ({count} duplicate members of {total} dropped)", stacklevel=3)
    return ChainedMembers(parts)


def plan_of_cases(scenario_name: str, cases: dict[str, dict], name: str | None = None) -> Plan:
    """A plan of the scenario ``scenario_name`` from named ``cases`` (label -> options), as a named
    sweep (its ``name``) declares them."""
    from quadcosim import scenarios

    scenario = scenarios.get(scenario_name)
    members = [Member(i, scenario.parse(options), label) for i, (label, options) in enumerate(cases.items())]
    varied = sorted({k for options in cases.values() for k in options}, key=list(scenario.options).index)
    return Plan(scenario_name, members, varied, {"cases": list(cases)}, name=name)
