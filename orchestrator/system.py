"""A system of blocks and connections, and the fixed-step co-simulation master that runs it.

Signals live in one float64 vector, the bus. Each block's outputs occupy a contiguous
slice of it. Before a run everything is resolved once: value references, the slices each
FMU reads its inputs from (one ``fmi2SetReal`` per contiguous run, straight from the bus,
no copy), the views each Python block reads and writes, faults, recording. The loop then
makes only the FMI calls and the block steps, with no name look-up and no allocation per
step. It runs in C for whole chunks of steps (:mod:`quadcosim.orchestrator.chunks`: FMI calls, compiled
block steps, tables, recording, checks), returning to Python per chunk, for blocks without a
compiled form and for faults; ``run(..., master="step")`` runs it from Python one step at a
time, with bit-identical results.

Per macro step ``n`` (time ``t_n``), in dependency order:
1. every block due at ``n`` produces its outputs at ``t_n`` (FMU: set inputs, get outputs;
   Python block: ``step``);
2. the bus is recorded (every ``decimation`` steps) and checked for NaN and Inf;
3. every FMU due at ``n`` takes its inputs from blocks later in the order (a non-feedthrough
   input, so the loop is not algebraic) and steps to ``t_n + period * dt``.
"""

from __future__ import annotations

import math
import os

import numpy as np
from quadcosim.orchestrator.blocks import Block, Constant, FMUBlock
from quadcosim.orchestrator.errors import AlgebraicLoopError, SimulationError  # noqa: F401 (public here too)
from quadcosim.orchestrator.faults import Fault
from quadcosim.orchestrator.fmu import nearest
from quadcosim.orchestrator.plan import Plan
from quadcosim.orchestrator.result import Result
from quadcosim.orchestrator.signals import expand


class System:
    """Blocks plus connections, declared by name, run by a fixed-step master.

    Parameters
    ----------
    dt : float
        Macro step (s), default 1 ms.

    Examples
    --------
    >>> sys = System(dt=1e-3)
    >>> sys.add(FMUBlock("MotorMagnetics"))
    >>> sys.add(Table("Setpoint", ["c1", "c2", "c3", "c4"], [[0.5] * 4]))
    >>> sys.connect("Setpoint.c", "MotorMagnetics.c")
    >>> result = sys.run(1.0)
    """

    def __init__(self, dt: float = 1e-3):
        if not (isinstance(dt, int | float) and math.isfinite(dt) and dt > 0):
            raise ValueError(f"macro step dt = {dt!r} s must be a positive number of seconds")
        self.dt = float(dt)
        self.blocks: dict[str, Block | FMUBlock] = {}
        self.connections: dict[str, str] = {}  # destination "B.u" -> source "A.y"
        self.faults: list[Fault] = []

    # ------------------------------------------------------------------ declaration
    def add(self, block):
        """Add ``block`` (a :class:`Block` or :class:`FMUBlock`) and return it.

        Raises
        ------
        ValueError
            The name is taken, or contains a dot.
        """
        if block.name in self.blocks:
            raise ValueError(f"a block named {block.name!r} is already in the system")
        if "." in block.name:
            raise ValueError(f"block name {block.name!r} must not contain a dot")
        self.blocks[block.name] = block
        return block

    def _resolve(self, signal: str, direction: str) -> list[str]:
        block_name, dot, name = signal.partition(".")
        if not dot:
            raise ValueError(f"signal {signal!r} must be written Block.signal")
        block = self.blocks.get(block_name)
        if block is None:
            raise KeyError(f"unknown block {block_name!r} in {signal!r}.{nearest(block_name, self.blocks)} "
                           f"Blocks: {', '.join(self.blocks)}.")
        names = block.outputs if direction == "output" else block.inputs
        members = expand(name, names)
        if not members:
            raise KeyError(f"{block_name} has no {direction} {name!r}.{nearest(name, names)} "
                           f"Its {direction}s: {', '.join(names)}.")
        return [f"{block_name}.{m}" for m in members]

    def connect(self, source: str, destination: str):
        """Connect an output to an input.

        Parameters
        ----------
        source : str
            ``"Block.output"``; a vector name such as ``"IMU.acc"`` stands for its components
            in order (``acc_x, acc_y, acc_z``).
        destination : str
            ``"Block.input"``, with as many components as ``source``.

        Raises
        ------
        KeyError
            Unknown block or signal (the message names the nearest valid names).
        ValueError
            Component counts differ, or an input is already connected.
        """
        sources = self._resolve(source, "output")
        destinations = self._resolve(destination, "input")
        if len(sources) != len(destinations):
            raise ValueError(f"{source} has {len(sources)} components and {destination} has {len(destinations)}")
        self._refuse_connected(destinations)
        for s, d in zip(sources, destinations, strict=True):
            self.connections[d] = s

    def set_input(self, destination: str, value):
        """Tie an input (or each component of a vector input) to a constant.

        Parameters
        ----------
        destination : str
            ``"Block.input"`` or a vector name (``"Quadrotor.wind"``, an FMI 3.0 array).
        value : float or sequence of float
            The constant, in the input's unit: one number (every component takes it), or one
            per component, in order.

        Raises
        ------
        ValueError
            An input is already connected (as :meth:`connect`), a value is not finite, or the
            values are not one per component.
        """
        targets = self._resolve(destination, "input")
        self._refuse_connected(targets)
        values = [value] if isinstance(value, int | float | str) else list(np.ravel(value))
        if len(values) == 1:
            values = values * len(targets)
        if len(values) != len(targets):
            raise ValueError(f"{destination} has {len(targets)} component{'s' * (len(targets) > 1)} "
                             f"({', '.join(t.split('.', 1)[1] for t in targets)}): give one value or "
                             f"{len(targets)}, not {len(values)}")
        for target, v in zip(targets, values, strict=True):
            if not math.isfinite(float(v)):
                raise ValueError(f"{target} = {v!r}: a constant input must be a finite number")
        name = "Const_" + destination.replace(".", "_")
        block = self.add(Constant(name, {t.split(".", 1)[1]: v for t, v in zip(targets, values, strict=True)},
                                  ties=destination))
        for target in targets:
            self.connections[target] = f"{block.name}.{target.split('.', 1)[1]}"

    def _refuse_connected(self, destinations: list[str]):
        for d in destinations:
            if d in self.connections:
                raise ValueError(f"{d} is already connected to {self.connections[d]}; an input has one source")

    def set_parameter(self, target: str, value):
        """Set a block parameter before the run; returns the value set.

        Parameters
        ----------
        target : str
            ``"Block.parameter"``: an FMU parameter, vector or alias, checked against the FMU's
            variable table, or a Python block's numeric attribute.
        value : number, bool, str or sequence
            In the parameter's unit (see :func:`quadcosim.orchestrator.parameters.resolve`).
        """
        from quadcosim.orchestrator.parameters import apply

        return apply(self, {target: value})[target]

    def replace(self, name: str, block):
        """Put ``block`` in the place of block ``name`` (it takes that name), keeping the wiring;
        see :func:`quadcosim.orchestrator.replace.replace`. Returns ``block``."""
        from quadcosim.orchestrator.replace import replace

        return replace(self, name, block)

    def inject(self, fault: Fault) -> Fault:
        """Add a fault on the connection into ``fault.target``."""
        targets = self._resolve(fault.target, "input")
        if len(targets) != 1:
            raise ValueError(f"a fault applies to one signal; {fault.target} has {len(targets)}")
        fault.target = targets[0]
        self.faults.append(fault)
        return fault

    # ------------------------------------------------------------------ structure
    def unconnected(self) -> list[str]:
        """Inputs with no source, as ``"Block.input"``."""
        return [f"{b.name}.{u}" for b in self.blocks.values() for u in b.inputs
                if f"{b.name}.{u}" not in self.connections]

    def order(self) -> list:
        """Blocks in dependency order (Gauss-Seidel): a block runs after the blocks that feed
        its direct-feedthrough inputs.

        Raises
        ------
        AlgebraicLoopError
            Direct-feedthrough connections form a cycle.
        """
        names = list(self.blocks)
        after: dict[str, set[str]] = {n: set() for n in names}  # n must run after these
        for dst, src in self.connections.items():
            dst_block, dst_input = dst.split(".", 1)
            src_block = src.split(".", 1)[0]
            if dst_input in self.blocks[dst_block].feedthrough_inputs and src_block != dst_block:
                after[dst_block].add(src_block)
            elif dst_input in self.blocks[dst_block].feedthrough_inputs:
                raise AlgebraicLoopError([dst_block])
        ordered, placed = [], set()
        while len(ordered) < len(names):
            ready = [n for n in names if n not in placed and after[n] <= placed]
            if not ready:
                raise AlgebraicLoopError(_cycle({n: after[n] - placed for n in names if n not in placed}))
            ordered.append(ready[0])
            placed.add(ready[0])
        return [self.blocks[n] for n in ordered]

    # ------------------------------------------------------------------ running
    def run(self, duration: float, decimation: int = 1, progress: bool = False, start_time: float = 0.0,
            record=None, master: str | None = None, stream=None) -> Result:
        """Run the system and return what was recorded.

        Parameters
        ----------
        duration : float
            Simulated time (s), at least one macro step.
        decimation : int
            Record every ``decimation`` macro steps.
        progress : bool
            Show a progress bar on long runs.
        start_time : float
            Time of the first step (s).
        record : list of str, optional
            Signals to keep (vector names such as ``"IMU.acc"`` allowed); every output of every
            block by default.
        master : {"chunk", "step"}, optional
            ``"chunk"`` (the default, or ``$QUADCOSIM_MASTER``): compiled code runs whole chunks
            of steps (:mod:`quadcosim.orchestrator.chunks`); ``"step"``: one step at a time from Python.
            Both give bit-identical results.
        stream : quadcosim.orchestrator.stream.StreamWriter, optional
            Write the record to its folder in chunks as the run goes (memory stays flat);
            the result is then read back from that folder.

        Returns
        -------
        quadcosim.orchestrator.Result
            The recorded signals, indexed by name.

        Raises
        ------
        ValueError
            Invalid duration or decimation, or an input left unconnected.
        quadcosim.orchestrator.SimulationError
            A failure during the run; its ``result`` holds what was recorded up to it.
        """
        if not (isinstance(duration, int | float) and math.isfinite(duration) and duration > 0):
            raise ValueError(f"duration = {duration!r} s must be a positive number of seconds")
        if int(decimation) != decimation or decimation < 1:
            raise ValueError(f"decimation = {decimation!r} must be a positive integer")
        master = master or os.environ.get("QUADCOSIM_MASTER") or "chunk"
        if master not in ("chunk", "step"):
            raise ValueError(f"master = {master!r} must be 'chunk' or 'step' (also in $QUADCOSIM_MASTER)")
        missing = self.unconnected()
        if missing:
            raise ValueError(f"unconnected input{'s' * (len(missing) > 1)}: {', '.join(missing)}. Connect each "
                             "with system.connect(source, destination) or tie it with system.set_input(name, value).")
        plan = Plan(self, duration, int(decimation), start_time, record, stream)
        try:
            plan.run(progress, master)
        finally:
            plan.close()
        return plan.result()


def _cycle(after: dict[str, set[str]]) -> list[str]:
    """One cycle in the 'runs after' graph restricted to blocks that could not be placed."""
    node = next(iter(after))
    seen: list[str] = []
    while node not in seen:
        seen.append(node)
        node = next(iter(after[node]))
    cycle = seen[seen.index(node):]
    return list(reversed(cycle))
