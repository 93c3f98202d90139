"""A block of a declared system replaced by another, its wiring kept."""

from __future__ import annotations

from orchestrator.fmu import nearest


def replace(system, name: str, block):
    """Put ``block`` in the place of the block called ``name``, keeping its connections.

    ``block`` takes the name ``name``. Connections into inputs the new block does not have are
    dropped; inputs it adds are left for :meth:`orchestrator.System.connect` (a run refuses
    unconnected inputs). Every output of the old block that feeds another block must exist on
    the new one.

    Parameters
    ----------
    system : orchestrator.System
    name : str
        The block replaced.
    block : orchestrator.Block or orchestrator.FMUBlock
        The new block.

    Returns
    -------
    The new block.

    Raises
    ------
    KeyError
        No block ``name``, or the new block lacks an output that is connected or an input
        where a fault is injected.
    """
    if name not in system.blocks:
        raise KeyError(f"unknown block {name!r}.{nearest(name, system.blocks)} Blocks: {', '.join(system.blocks)}.")
    used = sorted({s.split(".", 1)[1] for s in system.connections.values() if s.split(".", 1)[0] == name})
    missing = [y for y in used if y not in block.outputs]
    if missing:
        raise KeyError(f"the block replacing {name} lacks the output{'s' * (len(missing) > 1)} "
                       f"{', '.join(missing)}, which other blocks read")
    lost = [f.target for f in system.faults if f.target.split(".", 1)[0] == name
            and f.target.split(".", 1)[1] not in block.inputs]
    if lost:
        raise KeyError(f"the block replacing {name} lacks the input{'s' * (len(lost) > 1)} {', '.join(lost)}, "
                       "where a fault is injected")
    block.name = name
    for destination in [d for d in system.connections if d.split(".", 1)[0] == name]:
        if destination.split(".", 1)[1] not in block.inputs:
            del system.connections[destination]
    system.blocks[name] = block
    return block
