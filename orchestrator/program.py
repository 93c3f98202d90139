"""The program a run plan is compiled into, as both runners read it: the slice copies between
the bus and the blocks, the phases run per macro step, and the entries of the chunk runner.

:class:`quadcosim.orchestrator.plan.Plan` builds it; :class:`quadcosim.orchestrator.chunks.ChunkRunner` and the
plan's own step loop run it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

from quadcosim.orchestrator.blocks import Block


class Copy(NamedTuple):
    """One slice copy ``vector[into] = bus[source]`` (a named tuple: unpacked in the loop)."""

    into: slice
    source: slice


class Phase(NamedTuple):
    """A function of time (s) run every ``period`` macro steps."""

    period: int
    run: Callable[[float], None]


class Entry(NamedTuple):
    """One phase as the chunk runner reads it: the FMI ``calls`` of a batch or a Python
    ``block`` (its inputs and outputs found in the plan), the faults applied first, and the
    per-step form ``phase``. The entry :data:`RECORD` stands for the recording and the check."""

    phase: Phase | None
    calls: tuple
    taps: tuple
    block: Block | None


RECORD = Entry(None, (), (), None)


def consecutive(slots: list[int]) -> list[tuple[int, int]]:
    """Index ranges ``[i, j)`` of ``slots`` over which each slot is the previous one plus one."""
    ranges, i = [], 0
    while i < len(slots):
        j = i + 1
        while j < len(slots) and slots[j] == slots[j - 1] + 1:
            j += 1
        ranges.append((i, j))
        i = j
    return ranges


def copies(slots: list[int]) -> tuple[Copy, ...]:
    """The slice copies that gather bus ``slots`` into a vector, in order."""
    return tuple(Copy(slice(i, j), slice(slots[i], slots[j - 1] + 1)) for i, j in consecutive(slots))
