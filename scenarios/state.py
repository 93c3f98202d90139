"""A run's state, typed: the options as parsed (read-only), what the caller asks beside them, what
its ``metrics.json`` states whatever its end, and the system as built with the options as it uses them.

``--set Controller.kp_yaw=50`` is read once and checked against the scenario's declared blocks
before anything is built (:meth:`quadcosim.scenarios.Scenario.parse`, into :class:`Options`: the
gain as a number), set on the built block through the block contract
(:meth:`quadcosim.scenarios.Scenario.prepare`, into :class:`Prepared`), and written to
``metrics.json`` from :attr:`Prepared.used` (:class:`RunStated`); nothing on the way changes the
options in place.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypedDict

if TYPE_CHECKING:
    from pathlib import Path

    from quadcosim.orchestrator import Result, System


class Options(dict):
    """A scenario's options as parsed: option name (or ``Block.parameter``) to value, read-only.

    A mapping like any dict for reading (``o["k"]``, ``o | {...}``, ``dict(o)``, JSON); any
    change in place raises :class:`TypeError`: a step that uses other values makes a new
    mapping (``o | {"k": 2.0}``), so what was parsed stays what was asked.
    """

    def _refuse(self, *args, **kwargs):
        """Refused: the options are read-only once parsed (raises :class:`TypeError`)."""
        raise TypeError("a run's options are read-only once parsed: make a new mapping (options | {key: value})")

    __setitem__ = __delitem__ = __ior__ = _refuse
    clear = pop = popitem = setdefault = update = _refuse

    def __reduce__(self):
        return Options, (dict(self),)


@dataclass(frozen=True)
class RunRequest:
    """What a caller of :func:`quadcosim.scenarios.run` asks beside the options.

    Parameters
    ----------
    faults : tuple of quadcosim.orchestrator.Fault
        Injected on their connections.
    estimator : Block or class, optional
        A block of the user's in the place of ``Quaternion_estim``.
    record : list of str, optional
        Signals to keep (``["all"]``: every output).
    stream : bool
        Write the record in chunks as the run goes.
    blocks : dict, optional
        Blocks of the user's in the place of the scenario's, by name.
    fmus : dict, optional
        Block name to an FMU file of the user's put in that block's place.
    decimation : int
        Keep every N-th macro step.
    """

    faults: tuple = ()
    estimator: Any = None
    record: list | None = None
    stream: bool = False
    blocks: dict | None = None
    fmus: dict | None = None
    decimation: int = 1


@dataclass
class RunStated:
    """What a run of :func:`quadcosim.scenarios.run` states in ``metrics.json`` (and its result
    files' meta) whatever its end, filled in as the run learns it.

    Parameters
    ----------
    scenario : str
        The scenario's name.
    options : dict
        The settings as given, then the options as parsed, then as used (no default markers).
    injected_faults : list of dict
        The faults (:func:`quadcosim.scenarios.fault_record`).
    decimation : int
        Every N-th macro step kept.
    replaced_blocks : dict, optional
        Block name to the FMU of the user's that took its place and what it did not take over.
    duration_s : float, optional
        The simulated time (s), once the system is built.
    signals_not_saved : list of str, optional
        The signals recorded for the report but left out of the result files.
    """

    scenario: str
    options: dict
    injected_faults: list
    decimation: int
    replaced_blocks: dict | None = None
    duration_s: float | None = None
    signals_not_saved: list | None = None

    def metrics(self) -> dict:
        """The entries of ``metrics.json`` it stands for, in this order, each optional one once known."""
        stated = {"scenario": self.scenario, "options": self.options, "injected_faults": self.injected_faults,
                  "decimation": self.decimation}
        optional = {"replaced_blocks": self.replaced_blocks, "duration_s": self.duration_s,
                    "signals_not_saved": self.signals_not_saved}
        return stated | {key: value for key, value in optional.items() if value is not None}


@dataclass(frozen=True)
class Prepared:
    """A scenario's system built from its options, block parameters set.

    Parameters
    ----------
    system : quadcosim.orchestrator.System
    options : Options
        The options as the run reads them: as parsed, with the user's estimator named
        (``module:Class``) and each ``Block.parameter`` as set (a number, or a list for a vector).
    used : dict
        ``options`` with every default marker replaced by the value it stands for
        (:meth:`quadcosim.scenarios.Scenario.used`): what ``metrics.json`` states.
    """

    system: System
    options: Options
    used: dict = field(default_factory=dict)


#: ``build(options, estimator=None) -> System``: a scenario's system from its options.
Build = Callable[..., "System"]
#: ``report(result, options, out) -> dict``: a scenario's metrics (and figures into ``out``, a folder or None).
Report = Callable[["Result", Mapping, "Path | None"], dict]
#: ``duration(options) -> float``: the simulated time (s) when no ``duration`` option says it.
Duration = Callable[[Mapping], float]
#: ``resolve(options) -> dict``: the options with every default marker replaced by its value.
Resolve = Callable[[Mapping], dict]


class Extra(TypedDict, total=False):
    """What a scenario declares beside its options and hooks (:attr:`quadcosim.scenarios.Scenario.extra`), each
    key optional."""

    diagram: bool  # its wiring diagram drawn with each run's results
    title: Callable[[Mapping], str]  # the diagram's title from the options
    derived: dict[str, str]  # "Block.parameter" -> the option that sets it (--set refuses the parameter)
    # every block the system may hold, by name: an FMU model's name or a Block class; --set Block.parameter
    # is checked against them before anything is built (tests/test_scenarios.py checks them against builds)
    blocks: dict[str, Any]
    record: list[str]  # the signals recorded (default: every output)
    unrecorded: list[str]  # recorded for the report, left out of the result files
    components: dict[str, tuple[str, ...]]  # a list metric's components, named (roll, pitch, yaw)
    divergence: Any  # quadcosim.scenarios.divergence.Bounds: the flight's bounds, a run beyond them diverged
    units: dict[str, str]  # units of metrics whose names carry none
