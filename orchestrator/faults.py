"""Faults injected on connections: offset, scale, stuck-at, noise burst, dropout.

A fault sits on the connection into one block input. While it is active, the master gives
that input a faulted copy of its source signal, held in a bus slot of its own, so that the
source signal itself (and every other block reading it) stays intact.

Several faults on one input compose in the order they are injected, each acting on the output
of the one before: an offset of +10 then an offset of +100 add 110; an offset of +1 then a
scale of 2 give ``2 (x + 1)``, the reverse order ``2 x + 1``. A fault's value must be finite,
and a fault whose window no step of the run falls in is reported with a warning.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

FAULT_KINDS = ("offset", "scale", "stuck", "noise", "dropout")


@dataclass
class Fault:
    """A fault on the connection into ``target`` (``"Block.input"``), active for
    ``start <= t < stop``.

    Parameters
    ----------
    target : str
        The faulted input, ``"Block.input"``.
    kind : str
        - ``offset``: adds ``value`` (the signal's unit);
        - ``scale``: multiplies by ``value`` (dimensionless);
        - ``stuck``: holds ``value``, or the value at ``start`` when ``value`` is None;
        - ``noise``: adds white Gaussian noise of standard deviation ``value`` (the signal's
          unit), drawn once per macro step from a generator seeded by ``seed``;
        - ``dropout``: the signal is lost and reads 0.
    start, stop : float
        Active window (s).
    value : float, optional
        See ``kind``.
    seed : int
        Seed of the noise generator.
    """

    target: str
    kind: str
    start: float
    stop: float
    value: float | None = None
    seed: int = 0
    _held: float | None = field(default=None, repr=False)

    def __post_init__(self):
        if self.kind not in FAULT_KINDS:
            raise ValueError(f"unknown fault kind {self.kind!r}; use one of {', '.join(FAULT_KINDS)}")
        if not self.stop > self.start:
            raise ValueError(f"fault on {self.target}: stop ({self.stop}) must come after start ({self.start})")
        if self.kind in ("offset", "scale", "noise") and self.value is None:
            raise ValueError(f"a {self.kind} fault needs a value")
        for name in ("start", "stop"):
            if math.isnan(getattr(self, name)):
                raise ValueError(f"fault on {self.target}: {name} is NaN; give a time in seconds")
        if self.value is not None and not math.isfinite(self.value):
            raise ValueError(f"{self.kind} fault on {self.target}: value {self.value} is not a finite number")
        if self.kind == "noise" and self.value < 0:
            raise ValueError(f"noise fault on {self.target}: standard deviation {self.value} is negative")

    def reset(self) -> None:
        """Forget the held value and reseed the noise generator, before a run."""
        self._held = None
        self._rng = np.random.default_rng(self.seed)

    def apply(self, t: float, x: float) -> float:
        """The faulted value of signal value ``x`` at time ``t`` (s); ``x`` outside the window."""
        if not self.start <= t < self.stop:
            self._held = None
            return x
        kind = self.kind
        if kind == "offset":
            return x + self.value
        if kind == "scale":
            return x * self.value
        if kind == "stuck":
            if self._held is None:
                self._held = x if self.value is None else self.value
            return self._held
        if kind == "noise":
            return x + self.value * self._rng.standard_normal()
        return 0.0


@dataclass(frozen=True)
class FaultTap:
    """Where one fault reads its source signal and writes the faulted copy.

    Parameters
    ----------
    fault : Fault
        The fault.
    source : int
        Bus slot of the source signal.
    slot : int
        Bus slot of the faulted copy, which the faulted input reads.
    """

    fault: Fault
    source: int
    slot: int


def apply_faults(taps: list[FaultTap], bus: np.ndarray, t: float) -> None:
    """Write each tap's faulted copy of its source into its own bus slot.

    Parameters
    ----------
    taps : list of FaultTap
        The faults and their slots.
    bus : ndarray
        The bus.
    t : float
        Present time (s).
    """
    for tap in taps:
        bus[tap.slot] = tap.fault.apply(t, bus[tap.source])


def suspects(faults: list[Fault], connections: dict[str, str], block: str,
             t: float) -> list[tuple[Fault, list[str]]]:
    """The faults that may have made ``block`` fail at time ``t``: those started by then on an
    input of ``block`` or of a block that feeds it, directly or through others.

    Parameters
    ----------
    faults : list of Fault
        The injected faults (targets resolved, ``"Block.input"``).
    connections : dict
        Destination ``"B.u"`` to source ``"A.y"``, as :class:`quadcosim.orchestrator.System` holds them.
    block : str
        The block whose output failed.
    t : float
        Time of the failure (s).

    Returns
    -------
    list of (Fault, list of str)
        Each suspect and the path of blocks from its target to ``block``.
    """
    feeders: dict[str, set[str]] = {}
    for destination, source in connections.items():
        feeders.setdefault(destination.split(".", 1)[0], set()).add(source.split(".", 1)[0])
    paths, frontier = {block: [block]}, [block]
    while frontier:  # breadth first, upstream: the shortest path from each block to ``block``
        following = []
        for name in frontier:
            for feeder in sorted(feeders.get(name, ())):
                if feeder not in paths:
                    paths[feeder] = [feeder] + paths[name]
                    following.append(feeder)
        frontier = following
    found = []
    for fault in faults:
        target = fault.target.split(".", 1)[0]
        if fault.start <= t and target in paths:
            found.append((fault, paths[target]))
    return found


def describe(fault: Fault) -> str:
    """``"the offset fault on IMU.omega_x (value 0.05, from 0.5 s to 1 s)"``."""
    value = "" if fault.value is None else f"value {fault.value:g}, "
    return f"the {fault.kind} fault on {fault.target} ({value}from {fault.start:g} s to {fault.stop:g} s)"
