"""A sweep's values checked before its cluster starts, as ``quadcosim run`` checks one run's.

Each option value of a plan was parsed when the plan was made (type, choices, minimum). What
only the scenario or an FMU can refuse (a build that rejects a combination, a block parameter
out of its FMU's range, a value an FMU refuses at initialization) is checked here, on the
client, by building the system and initializing its FMUs for probe members: the first member,
then each value of each dimension in turn, the other dimensions at their first value. A
dimension of more than :data:`PROBED_VALUES` values is probed at its first and last values and
at its extremes, where range checks refuse. A refused member stops the sweep before it starts,
naming the member and what refused it.
"""

from __future__ import annotations

import math

from quadcosim.studies.sweep.grid import ChainedMembers, GridMembers, Plan

from quadcosim.infra.errors import UsageError

#: Dimensions with up to this many values are probed value by value.
PROBED_VALUES = 32


class MemberRefused(UsageError, ValueError):
    """A member of a plan would fail: its label and the reason."""


def _extremes(values: list) -> set[int]:
    """Positions of the first, last, smallest and largest of ``values`` (numbers compared as such)."""
    picked = {0, len(values) - 1}
    numbers = [(v, k) for k, v in enumerate(values) if isinstance(v, int | float) and not isinstance(v, bool)]
    if numbers:
        picked |= {min(numbers)[1], max(numbers)[1]}
    return picked


def probes(plan: Plan) -> list[int]:
    """Indices of the members of ``plan`` to check (see the module documentation), the first
    member first: every member of a list of cases, probes of a grid, and of each part of a
    chain of grids."""
    members = plan.members
    if isinstance(members, ChainedMembers):
        return [start + k for start, part in zip(members.starts, members.parts, strict=False) for k in _grid(part)]
    if isinstance(members, GridMembers):
        return _grid(members)
    return list(range(len(members)))


def _grid(members: GridMembers) -> list[int]:
    """Probe indices of one grid: its first member, then each dimension's values in turn."""
    sizes = [len(values) for values in members.dimensions.values()]
    picked = [0]
    for d, values in enumerate(members.dimensions.values()):
        stride = math.prod(sizes[d + 1:])
        positions = range(len(values)) if len(values) <= PROBED_VALUES else sorted(_extremes(values))
        picked += [k * stride for k in positions if k]
    return picked


def check(plan: Plan) -> int:
    """Build the system of each probe member and initialize its FMUs; returns how many were checked.

    Parameters
    ----------
    plan : Plan
        The sweep's plan.

    Raises
    ------
    MemberRefused
        A member's system cannot be built or an FMU refused its parameters: the message names
        the member, the reason, and that the sweep did not start.
    """
    from quadcosim.fmus import FMUNotFoundError
    from quadcosim.orchestrator.blocks import FMUBlock
    from quadcosim.orchestrator.fmu import FMUError

    from quadcosim import scenarios

    scenario = scenarios.get(plan.scenario)
    indices = probes(plan)
    for index in indices:
        member = plan.members[index]
        try:
            system = scenario.system(dict(member.options))
            for block in system.blocks.values():
                if isinstance(block, FMUBlock):
                    block.instantiate(0.0)
                    block.close()
        except (KeyError, ValueError, FMUError, FMUNotFoundError) as error:
            reason = error.args[0] if isinstance(error, KeyError) and error.args else str(error)
            raise MemberRefused(f"member {member.index} ({member.label or 'the fixed options'}) would fail: "
                                f"{reason}\nNo member was run: fix that value in --grid or --set.") from None
    return len(indices)
