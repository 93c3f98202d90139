"""A system of blocks and connections, and the fixed-step co-simulation master that runs it.

Signals live in one float64 vector, the bus. Each block's outputs occupy a contiguous
slice of it. Before a run everything is resolved once: value references, the slices each
FMU reads its inputs from (one ``fmi2SetReal`` per contiguous run, straight from the bus,
no copy), the views each Python block reads and writes, faults, recording. The loop then
makes only the FMI calls and the Python block steps, with no name look-up and no
allocation per step.

Per macro step ``n`` (time ``t_n``), in dependency order:
1. every block due at ``n`` produces its outputs at ``t_n`` (FMU: set inputs, get outputs;
   Python block: ``step``);
2. the bus is recorded (every ``decimation`` steps) and checked for NaN and Inf;
3. every FMU due at ``n`` takes its inputs from blocks later in the order (a non-feedthrough
   input, so the loop is not algebraic) and steps to ``t_n + period * dt``.
"""

from __future__ import annotations

import ctypes
import math
import time
from dataclasses import dataclass, field

import numpy as np

from orchestrator.blocks import Block, Constant, FMUBlock
from orchestrator.calls import run_calls
from orchestrator.fmu import FMUError, nearest
from orchestrator.result import Result, expand


class SimulationError(RuntimeError):
    """A run failed. ``result`` holds what was recorded up to the failure."""

    def __init__(self, message: str, result: Result | None = None):
        super().__init__(message)
        self.result = result


class AlgebraicLoopError(ValueError):
    """Blocks with direct feedthrough form a cycle."""

    def __init__(self, cycle: list[str]):
        self.cycle = cycle
        super().__init__(
            "algebraic loop: " + " -> ".join(cycle + cycle[:1]) + ". Every block in it passes its inputs "
            "straight to its outputs. Break it with a block without direct feedthrough (a delay, a "
            "filter state) or connect one of these signals from elsewhere."
        )


FAULT_KINDS = ("offset", "scale", "stuck", "noise", "dropout")


@dataclass
class Fault:
    """A fault on the connection into ``target`` (``"Block.input"``), active for
    ``start <= t < stop`` (s).

    kind:
    - ``offset``: adds ``value``;
    - ``scale``: multiplies by ``value``;
    - ``stuck``: holds ``value``, or the value at ``start`` when ``value`` is None;
    - ``noise``: adds white Gaussian noise of standard deviation ``value`` (seeded by ``seed``);
    - ``dropout``: the signal is lost and reads 0.
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
        if self.kind == "noise" and self.value < 0:
            raise ValueError(f"noise fault on {self.target}: standard deviation {self.value} is negative")

    def reset(self):
        self._held = None
        self._rng = np.random.default_rng(self.seed)

    def apply(self, t: float, x: float) -> float:
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
        """Connect output ``source`` to input ``destination`` (``"Block.signal"``; a vector
        name such as ``"IMU.acc"`` connects its components in order)."""
        sources = self._resolve(source, "output")
        destinations = self._resolve(destination, "input")
        if len(sources) != len(destinations):
            raise ValueError(f"{source} has {len(sources)} components and {destination} has {len(destinations)}")
        for s, d in zip(sources, destinations, strict=True):
            if d in self.connections:
                raise ValueError(f"{d} is already connected to {self.connections[d]}")
            self.connections[d] = s

    def set_input(self, destination: str, value: float):
        """Tie input ``destination`` (or each component of it) to a constant ``value``."""
        targets = self._resolve(destination, "input")
        name = "Const_" + destination.replace(".", "_")
        block = self.add(Constant(name, {t.split(".", 1)[1]: value for t in targets}))
        for target in targets:
            self.connections[target] = f"{block.name}.{target.split('.', 1)[1]}"

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
        return [f"{b.name}.{u}" for b in self.blocks.values() for u in b.inputs
                if f"{b.name}.{u}" not in self.connections]

    def order(self) -> list:
        """Blocks in dependency order; raises :class:`AlgebraicLoopError` on a cycle of
        direct-feedthrough connections."""
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

    def signals(self) -> list[str]:
        return [f"{b.name}.{y}" for b in self.blocks.values() for y in b.outputs]

    # ------------------------------------------------------------------ running
    def run(self, duration: float, decimation: int = 1, progress: bool = False, start_time: float = 0.0,
            record=None) -> Result:
        """Run for ``duration`` seconds and return the recorded :class:`Result`.

        ``record`` lists the signals to keep (vector names allowed); by default every output
        of every block. They are recorded every ``decimation`` macro steps. On a failure a
        :class:`SimulationError` is raised whose ``result`` holds what was recorded up to it.
        """
        if not (isinstance(duration, int | float) and math.isfinite(duration) and duration > 0):
            raise ValueError(f"duration = {duration!r} s must be a positive number of seconds")
        if int(decimation) != decimation or decimation < 1:
            raise ValueError(f"decimation = {decimation!r} must be a positive integer")
        missing = self.unconnected()
        if missing:
            raise ValueError(f"unconnected input{'s' * (len(missing) > 1)}: {', '.join(missing)}. Connect each "
                             "with system.connect(source, destination) or tie it with system.set_input(name, value).")
        plan = _Plan(self, duration, int(decimation), start_time, record)
        try:
            plan.run(progress)
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


class _Failure(Exception):
    def __init__(self, message: str):
        super().__init__(message)


class _Plan:
    """Everything resolved once for one run."""

    def __init__(self, system: System, duration: float, decimation: int, t0: float, record=None):
        self.system, self.dt, self.t0, self.decimation = system, system.dt, t0, decimation
        self.steps = int(round(duration / system.dt))
        if self.steps < 1:
            raise ValueError(f"duration {duration} s is shorter than one macro step ({system.dt} s)")
        self.order = system.order()
        self.position = {b.name: i for i, b in enumerate(self.order)}
        # bus layout: outputs block by block, then one slot per fault
        self.slot: dict[str, int] = {}
        for block in self.order:
            for y in block.outputs:
                self.slot[f"{block.name}.{y}"] = len(self.slot)
        self.fault_slot = {f.target: len(self.slot) + k for k, f in enumerate(system.faults)}
        self.bus = np.zeros(len(self.slot) + len(system.faults))
        if record is None:
            slots = list(range(len(self.slot)))
        else:
            slots = sorted({self.slot[name] for signal in record for name in system._resolve(signal, "output")})
        by_slot = {v: k for k, v in self.slot.items()}
        self.names = [by_slot[s] for s in slots]
        self.record_runs = _copies(slots)
        self.rows = self.steps // decimation + 1
        self.record = np.empty((self.rows, len(slots)))
        self.recorded = 0
        self.fmus = []
        for fault in system.faults:
            fault.reset()
        try:
            self._prepare()
        except BaseException:
            self.close()
            raise

    def _source(self, block_name: str, u: str) -> tuple[int, bool]:
        """Bus slot an input reads, and whether its source runs earlier in the order."""
        destination = f"{block_name}.{u}"
        source = self.system.connections[destination]
        early = self.position[source.split(".", 1)[0]] < self.position[block_name]
        return self.fault_slot.get(destination, self.slot[source]), early

    def _prepare(self):
        bus_address = self.bus.ctypes.data
        self.phase_a, self.phase_b = [], []
        pending: list = []  # FMU blocks of the phase-A batch being gathered
        late_calls: dict[int, list] = {}  # period -> phase-B calls
        for block in self.order:
            first = self.slot[f"{block.name}.{block.outputs[0]}"] if block.outputs else 0
            faults = [(f, self.slot[self.system.connections[f.target]], self.fault_slot[f.target])
                      for f in self.system.faults if f.target.startswith(block.name + ".")]
            if isinstance(block, FMUBlock):
                instance = block.instantiate(self.t0)
                self.fmus.append(block)
                early, late = [], []
                for u in block.inputs:
                    slot, is_early = self._source(block.name, u)
                    (early if is_early else late).append((instance.variables[u].valueReference, slot))
                self.bus[first:first + len(block.outputs)] = instance.get(block.outputs)
                out_vr = instance.vr(block.outputs)
                calls_a = [_call(_SET, block, instance, vrs, bus_address + 8 * slot) for vrs, slot in _runs(early)]
                calls_a.append(_call(_GET, block, instance, out_vr, bus_address + 8 * first))
                calls_b = [_call(_SET, block, instance, vrs, bus_address + 8 * slot) for vrs, slot in _runs(late)]
                calls_b.append(_call(_STEP, block, instance, None, 0, h=block.period * self.dt))
                if pending and (faults or pending[0][0] != block.period):
                    self.phase_a.append(self._batch(pending))
                    pending = []
                pending.append((block.period, calls_a, faults))
                late_calls.setdefault(block.period, []).extend(calls_b)
            else:
                if pending:
                    self.phase_a.append(self._batch(pending))
                    pending = []
                block.start(self.t0, block.period * self.dt)
                y = self.bus[first:first + len(block.outputs)]
                slots = [self._source(block.name, u)[0] for u in block.inputs]
                self.phase_a.append((block.period, _python_phase(block, slots, y, faults, self.bus)))
        if pending:
            self.phase_a.append(self._batch(pending))
        for period, calls in late_calls.items():
            self.phase_b.append(self._batch([(period, calls, [])]))

    def _batch(self, parts):
        """One phase entry running the FMI calls of ``parts`` in a single call into C."""
        period = parts[0][0]
        calls = [c for _, cs, _ in parts for c in cs]
        faults = [f for _, _, fs in parts for f in fs]
        return period, _batch_phase(calls, faults, self.bus)

    def run(self, progress: bool):
        bus, record, dt, t0, dec = self.bus, self.record, self.dt, self.t0, self.decimation
        phase_a, phase_b, runs = self.phase_a, self.phase_b, self.record_runs
        reduce, isfinite = np.add.reduce, math.isfinite
        bar = _progress(self.steps * dt) if progress else None
        chunk = max(1, self.steps // 200)
        n = 0
        started = time.perf_counter()
        try:
            for n in range(self.steps + 1):
                t = t0 + n * dt
                for period, fn in phase_a:
                    if period == 1 or n % period == 0:
                        fn(t)
                if n % dec == 0:
                    row = record[n // dec]
                    for a, b, c, d in runs:
                        row[a:b] = bus[c:d]
                    self.recorded = n // dec + 1
                    if not isfinite(reduce(bus)):
                        raise _Failure(self._non_finite(t))
                if n == self.steps:
                    break
                for period, fn in phase_b:
                    if period == 1 or n % period == 0:
                        fn(t)
                if bar is not None and n % chunk == 0 and n:
                    bar.n = n * dt
                    bar.refresh()
        except _Failure as failure:
            raise SimulationError(str(failure), self.result(error=str(failure))) from None
        except FMUError as error:
            message = str(error)
            if "not a finite number" in message:
                message = self._non_finite(t0 + n * dt) + "\n" + message
            raise SimulationError(message, self.result(error=message)) from None
        except Exception as error:  # a Python block failed: keep what was recorded
            message = f"at t = {t0 + n * dt:.6g} s: {type(error).__name__}: {error}"
            raise SimulationError(message, self.result(error=message)) from error
        finally:
            self.loop_seconds = time.perf_counter() - started
            if bar is not None:
                bar.close()

    def _non_finite(self, t: float) -> str:
        for block in self.order:  # the first in the order is where it appeared
            for y in block.outputs:
                name = f"{block.name}.{y}"
                value = self.bus[self.slot[name]]
                if not math.isfinite(value):
                    return (f"{name} became {value} at t = {t:.6g} s (the first non-finite signal in the block "
                            f"order). Check the block {block.name} and its inputs.")
        for fault in self.system.faults:
            value = self.bus[self.fault_slot[fault.target]]
            if not math.isfinite(value):
                return f"the {fault.kind} fault on {fault.target} made it {value} at t = {t:.6g} s"
        return f"a signal became non-finite at t = {t:.6g} s"

    def result(self, error: str | None = None) -> Result:
        rows = self.recorded
        time = self.t0 + np.arange(rows) * self.decimation * self.dt
        meta = {"dt": self.dt, "decimation": self.decimation, "loop_seconds": getattr(self, "loop_seconds", None),
                "order": [b.name for b in self.order],
                "connections": dict(self.system.connections)}
        return Result(time, self.names, self.record[:rows].copy(), meta, error)

    def close(self):
        for block in self.fmus:
            block.close()
        for block in self.system.blocks.values():
            if isinstance(block, Block):
                block.close()


def _consecutive(slots: list[int]) -> list[tuple[int, int]]:
    """Index ranges [i, j) of ``slots`` over which each slot is the previous one plus one."""
    ranges, i = [], 0
    while i < len(slots):
        j = i + 1
        while j < len(slots) and slots[j] == slots[j - 1] + 1:
            j += 1
        ranges.append((i, j))
        i = j
    return ranges


def _copies(slots: list[int]) -> tuple:
    """Slice copies gathering bus ``slots`` into a vector: (to from, to end, bus from, bus end)."""
    return tuple((i, j, slots[i], slots[j - 1] + 1) for i, j in _consecutive(slots))


def _runs(refs: list[tuple[int, int]]):
    """Split (value reference, bus slot) pairs into runs of consecutive slots: one
    fmi2SetReal each, reading straight from the bus. Yields (value references, first slot)."""
    refs = sorted(refs, key=lambda r: r[1])
    slots = [slot for _, slot in refs]
    return [(np.array([vr for vr, _ in refs[i:j]], dtype=np.uint32), slots[i]) for i, j in _consecutive(slots)]


class _Call(ctypes.Structure):
    """One FMI call, as orchestrator/c/calls.c reads it."""

    _fields_ = [("kind", ctypes.c_int), ("block", ctypes.c_int), ("function", ctypes.c_void_p),
                ("component", ctypes.c_void_p), ("vr", ctypes.c_void_p), ("n", ctypes.c_size_t),
                ("values", ctypes.c_void_p), ("h", ctypes.c_double)]


_SET, _GET, _STEP = 0, 1, 2
_FUNCTION_NAMES = ("fmi2SetReal", "fmi2GetReal", "fmi2DoStep")


def _call(kind, block, instance, vrs, address, h=0.0):
    function = (instance.raw_set_real, instance.raw_get_real, instance.raw_do_step)[kind]
    call = _Call(kind, 0, ctypes.cast(function, ctypes.c_void_p).value, instance.component,
                 None if vrs is None else vrs.ctypes.data, 0 if vrs is None else len(vrs), address, h)
    return call, block, vrs


def _batch_phase(calls, faults, bus):
    run = run_calls()
    array = (_Call * len(calls))(*[c for c, _, _ in calls])
    blocks = [b for _, b, _ in calls]
    keep = [v for _, _, v in calls]  # the value reference arrays the calls point into
    count, failed, now = ctypes.c_int(len(calls)), ctypes.c_int(-1), ctypes.c_double(0.0)
    failed_ref = ctypes.byref(failed)

    def phase(t, keep=keep):
        if faults:
            _apply_faults(faults, bus, t)
        now.value = t
        status = run(array, count, now, failed_ref)
        if status > 1:
            block = blocks[failed.value]
            raise FMUError(block.name, _FUNCTION_NAMES[array[failed.value].kind], status, t, list(block.instance.log))
    return phase


def _apply_faults(faults, bus, t):
    for fault, source, slot in faults:
        bus[slot] = fault.apply(t, bus[source])


def _python_phase(block, slots, y, faults, bus):
    step = block.step
    n = len(slots)
    if n and slots == list(range(slots[0], slots[0] + n)):
        u = bus[slots[0]:slots[0] + n]  # a view: no copy at all
        copies = ()
    else:
        u = np.zeros(n)
        copies = _copies(slots)

    if not copies and not faults:
        def phase(t):
            step(t, u, y)
        return phase

    def phase(t):
        if faults:
            _apply_faults(faults, bus, t)
        for a, b, c, d in copies:
            u[a:b] = bus[c:d]
        step(t, u, y)
    return phase


def _progress(total_seconds: float):
    from tqdm import tqdm

    # shown only when a run lasts more than a few seconds of wall time
    return tqdm(total=total_seconds, unit="s sim", delay=3.0,
                bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} s [{elapsed}<{remaining}]")

