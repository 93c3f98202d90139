"""The estimators the project can name: the members of the entry-point group
``quadcosim.estimators`` (:mod:`quadcosim.infra.members`), one line each in a ``pyproject.toml``,
``name = "module:KIND"``, naming the member's :class:`Kind`.

:data:`KINDS` (read from the registry, never written here) is what a scenario's ``estimator``
option offers, what the comparisons run, what the replays of recordings run, and how tables
label them. A member is one module, which holds its :class:`Kind` with everything else of it: a
filter of this package's compiled core (:mod:`quadcosim.estimators.linear`,
:mod:`quadcosim.estimators.explicit`, :mod:`quadcosim.estimators.passive`) its gains with their
units, its corrections and its compiled step; a published filter
(:mod:`quadcosim.estimators.reference`) its package's gains; an estimator written as a block of
its own (the contract of :mod:`quadcosim.estimators.contract`) names that block, ``"module:Class"``,
in :attr:`Kind.block`, and is placed as a user's block would be.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

from quadcosim.infra import members
from quadcosim.infra.errors import UsageError

#: The entry-point group of the estimators.
GROUP = members.GROUPS["estimators"]


class Gain(NamedTuple):
    """One gain of a filter.

    Attributes
    ----------
    default : float
        Its value on recordings (:func:`quadcosim.estimators.estimate`'s default).
    unit : str
        ``"1/s"``, ``"1"``, ...
    meaning : str
        What it weighs, as ``quadcosim list --parameters`` prints it.
    lab : float or None
        The lab report's value, as ``tp`` runs the filter; None: the default.
    """

    default: float
    unit: str
    meaning: str
    lab: float | None = None


@dataclass(frozen=True)
class Kind:
    """One estimator.

    Attributes
    ----------
    name : str
        As options, metrics and file names spell it (``"passive"``); its registry line's name.
    label : str
        As tables and figures name it (``"VQF"``).
    lab : bool
        One of the lab's filters: its gains are the options ``k1``, ``k2``, ``kP``, ``kI``
        (1, 1, 1/s, 1/s^2) of ``tp``, defaulting to its gains' lab values.
    bias : bool
        Estimates a gyro bias, with the gain ``kI`` (1/s^2).
    streaming : bool
        Runs as a block in a closed loop (a scenario's ``estimator`` choice).
    batch : bool
        Runs on recorded arrays (:func:`quadcosim.estimators.estimate`): replays of flight logs.
    compared : dict or None
        The settings the comparisons of estimators (the lab matrix, Metge's yaw study, flight-log
        replays) run it with; None leaves it out of them.
    block : str or None
        ``"module:Class"`` of the block that implements it (an estimator of its own file); None
        for the filters :class:`quadcosim.estimators.QuaternionEstim` builds by name.
    rank : float
        Where tables and comparisons list it, lowest first (then by name).
    gains : dict
        Its gains by name, each a :class:`Gain` (value, unit, meaning).
    code : int or None
        Its branch of the compiled update (:func:`quadcosim.estimators.core.update`); None for
        the filters that run elsewhere.
    corrections : dict or None
        The disturbance-aware corrections (:mod:`quadcosim.estimators.corrections`) it runs by
        default, with their values; None: it has none.
    time_constants : dict
        Time constants (s) that may be given instead of its gains, at their defaults.
    from_time_constants : callable or None
        ``f(**time_constants) -> gains``: the gains of the time constants.
    reads_reel : bool
        With ``ry="reel"`` it reads the true rotation ``R_reel`` (the lab's passive filter).
    ned_only : bool
        It works in a NED frame only (gravity along +z).
    """

    name: str
    label: str
    lab: bool = False
    bias: bool = False
    streaming: bool = True
    batch: bool = True
    compared: dict | None = field(default_factory=dict)
    block: str | None = None
    rank: float = 100.0
    gains: dict = field(default_factory=dict)
    code: int | None = None
    corrections: dict | None = None
    time_constants: dict = field(default_factory=dict)
    from_time_constants: Callable | None = None
    reads_reel: bool = False
    ned_only: bool = False

    def defaults(self) -> dict:
        """Its gains' values on recordings, by name."""
        return {name: gain.default for name, gain in self.gains.items()}

    def lab_gains(self) -> dict:
        """Its gains' lab values (the defaults where the lab gave none), by name."""
        return {name: gain.default if gain.lab is None else gain.lab for name, gain in self.gains.items()}

    def meanings(self) -> dict:
        """Unit and meaning of each gain, by name."""
        return {name: (gain.unit, gain.meaning) for name, gain in self.gains.items()}


class EstimatorRegistrationError(UsageError, ValueError):
    """A registry line of ``quadcosim.estimators`` names something that is not the :class:`Kind` of its name."""


_loaded: dict = {}  # the registered lines read last -> the kinds they name


def registry() -> dict[str, Kind]:
    """The registered estimators, name -> :class:`Kind`, by rank (then name); each member's module
    is imported on the first call after the registry changed (:func:`quadcosim.infra.members.forget`).

    Raises
    ------
    EstimatorRegistrationError
        A line names no :class:`Kind`, or a Kind of another name.
    """
    lines = members.registered(GROUP)
    if _loaded.get("lines") is not lines:
        found = members.loaded(GROUP, Kind, EstimatorRegistrationError)
        _loaded["kinds"] = dict(sorted(found.items(), key=lambda item: (item[1].rank, item[0])))
        _loaded["lines"] = lines
    return _loaded["kinds"]


def __getattr__(name: str):
    if name == "KINDS":  # read from the registry when asked for, so that a member's module may import this one
        return registry()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def get(name: str) -> Kind | None:
    """The registered estimator ``name``, or None."""
    return registry().get(name)


def streaming() -> tuple[str, ...]:
    """The estimators a closed loop can run (a scenario's ``estimator`` choices)."""
    return tuple(name for name, kind in registry().items() if kind.streaming)


def compared(batch: bool = False) -> dict[str, dict]:
    """The estimators the comparisons run, each with its settings; ``batch``: those that run
    on recorded arrays only (a replay)."""
    return {name: dict(kind.compared) for name, kind in registry().items()
            if kind.compared is not None and (kind.batch or not batch)}


def with_bias() -> tuple[str, ...]:
    """The estimators with a gyro-bias estimate (gain ``kI``)."""
    return tuple(name for name, kind in registry().items() if kind.bias)
