"""The estimators the project can name, one line each in :data:`KINDS`: what a scenario's
``estimator`` option offers, what the comparisons run, and how tables label them.

Adding an estimator is one file and one line here. A filter of this package's compiled core
(:mod:`quadcosim.estimators.core`) or of the published packages (:mod:`quadcosim.estimators.reference`) is built as
:class:`quadcosim.estimators.QuaternionEstim` of its name; an estimator written as a block of its own
(the contract of :mod:`quadcosim.estimators.contract`) names that block, ``"module:Class"``, in
:attr:`Kind.block`, and is placed as a user's block would be.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Kind:
    """One estimator.

    Attributes
    ----------
    name : str
        As options, metrics and file names spell it (``"passive"``).
    label : str
        As tables and figures name it (``"VQF"``).
    lab : bool
        One of the lab's filters: its gains are the options ``k1``, ``k2``, ``kP``, ``kI``
        (1, 1, 1/s, 1/s^2), defaulting to :data:`quadcosim.estimators.LAB_GAINS`.
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
    """

    name: str
    label: str
    lab: bool = False
    bias: bool = False
    streaming: bool = True
    batch: bool = True
    compared: dict | None = field(default_factory=dict)
    block: str | None = None


KINDS = {kind.name: kind for kind in (
    Kind("linear", "linear", lab=True),
    Kind("explicit", "explicit", lab=True, bias=True),
    Kind("passive", "passive", lab=True, bias=True, compared={"ry": "triad"}),
    Kind("vqf", "VQF"),
    Kind("madgwick", "Madgwick"),
    Kind("mahony", "Mahony", streaming=False, compared=None),
)}


def streaming() -> tuple[str, ...]:
    """The estimators a closed loop can run (a scenario's ``estimator`` choices)."""
    return tuple(name for name, kind in KINDS.items() if kind.streaming)


def compared(batch: bool = False) -> dict[str, dict]:
    """The estimators the comparisons run, each with its settings; ``batch``: those that run
    on recorded arrays only (a replay)."""
    return {name: dict(kind.compared) for name, kind in KINDS.items()
            if kind.compared is not None and (kind.batch or not batch)}


def with_bias() -> tuple[str, ...]:
    """The estimators with a gyro-bias estimate (gain ``kI``)."""
    return tuple(name for name, kind in KINDS.items() if kind.bias)
