"""A block of a declared system replaced by another, its wiring kept."""

from __future__ import annotations

from quadcosim.orchestrator.fmu import nearest


def replace(system, name: str, block):
    """Put ``block`` in the place of the block called ``name``, keeping its connections.

    ``block`` takes the name ``name``. Connections into inputs the new block does not have are
    dropped; inputs it adds are left for :meth:`quadcosim.orchestrator.System.connect` (a run refuses
    unconnected inputs). Every output of the old block that feeds another block must exist on
    the new one.

    Parameters
    ----------
    system : quadcosim.orchestrator.System
    name : str
        The block replaced.
    block : quadcosim.orchestrator.Block or quadcosim.orchestrator.FMUBlock
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


def replace_fmu(system, name: str, model) -> tuple:
    """Put the FMU file ``model`` in the place of the FMU block ``name``, after checking that it
    has the same interface: every input the system feeds and every output another block reads,
    by variable name and unit.

    The replaced block's parameter values carry over to the new FMU where it has a parameter of
    the same name; the others are returned, for the caller to say they were dropped.

    Parameters
    ----------
    system : quadcosim.orchestrator.System
    name : str
        An FMU block of ``system`` (``MotorMagnetics``).
    model : str or pathlib.Path
        An FMI 2.0 or 3.0 Co-Simulation FMU file.

    Returns
    -------
    block : quadcosim.orchestrator.FMUBlock
        The new block, in the system.
    notes : list of str
        What the new block does not take over: parameters it lacks, units it does not declare.

    Raises
    ------
    KeyError
        No block ``name``.
    ValueError
        ``name`` is not an FMU block, or the new FMU's interface differs; the message lists
        every mismatch (a missing variable, another unit).
    """
    from quadcosim.orchestrator.blocks import FMUBlock
    from quadcosim.orchestrator.fmu_checks import FMURefused

    if name not in system.blocks:
        raise KeyError(f"--fmu {name}: unknown block {name!r}.{nearest(name, system.blocks)} "
                       f"Blocks: {', '.join(system.blocks)}.")
    old = system.blocks[name]
    if not isinstance(old, FMUBlock):
        fmus = [n for n, b in system.blocks.items() if isinstance(b, FMUBlock)]
        raise ValueError(f"--fmu {name}: {name} is a Python block ({type(old).__name__}); an FMU replaces an FMU "
                         f"block: {', '.join(fmus)}")
    try:
        new = FMUBlock(name, model=model, period=old.period)
    except FMURefused as error:  # refused from the file alone: named with the block it was to replace
        raise FMURefused(f"{name}: {error}") from None
    fed = sorted({d.split(".", 1)[1] for d in system.connections if d.split(".", 1)[0] == name},
                 key=old.inputs.index)
    read = sorted({s.split(".", 1)[1] for s in system.connections.values() if s.split(".", 1)[0] == name},
                  key=old.outputs.index)
    mismatches, notes = [], []
    for kind, names, old_units, new_names, new_units in (("input", fed, old.input_units, new.inputs, new.input_units),
                                                         ("output", read, old.units, new.outputs, new.units)):
        for variable in names:
            if variable not in new_names:
                mismatches.append(f"no {kind} {variable} ({old_units.get(variable) or 'no unit'}), which the system "
                                  f"{'feeds' if kind == 'input' else 'reads'}{nearest(variable, new_names)}")
            elif not new_units.get(variable):
                notes.append(f"{name}.{variable}: the FMU declares no unit; taken as {old_units.get(variable)}")
            elif old_units.get(variable) and new_units[variable] != old_units[variable]:
                mismatches.append(f"{kind} {variable} in {new_units[variable]}, where {name} has "
                                  f"{old_units[variable]}")
    if mismatches:
        raise ValueError(f"--fmu {name}={model}: the FMU's interface differs from {name}'s ({len(mismatches)} "
                         "mismatch" + "es" * (len(mismatches) > 1) + "):\n  " + "\n  ".join(mismatches))
    new.parameters = {k: v for k, v in old.parameters.items() if k in new.parameter_names}
    dropped = sorted(set(old.parameters) - set(new.parameters))
    if dropped:
        notes.append(f"{name}: the FMU has no parameter {', '.join(dropped)}, which the scenario set; not set")
    replace(system, name, new)
    return new, notes
