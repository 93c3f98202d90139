"""The run plan: everything the master resolves once before a run, and the loop that runs it.

The bus
    One float64 vector holds every signal: each block's outputs in a contiguous run of slots,
    blocks in dependency order, then one slot per fault for the faulted copy of its signal.

Building a plan (:class:`Plan`), in order:

1. :meth:`Plan._lay_out_bus`: a slot per block output, then a slot per fault (several faults
   on one input form a chain, each reading the slot of the one before: they compose in the
   order they were injected);
2. :meth:`Plan._plan_recording`: the recorded signals, as
   :class:`~quadcosim.orchestrator.program.Copy` slices from the bus into a row of a preallocated array;
3. :meth:`Plan._wire_blocks`, block by block in dependency order:

   - an FMU block (:meth:`Plan._wire_fmu`) is instantiated and its first outputs read. Its
     calls are split in two phases: phase A sets the inputs whose sources ran earlier in this
     macro step and gets the outputs; phase B sets the inputs whose sources run later (non
     feedthrough: a unit delay, not an algebraic loop) and steps. Inputs fed from
     consecutive slots share one :class:`~quadcosim.orchestrator.calls.SetInputs` call that reads straight
     from the bus;
   - a Python block (:meth:`Plan._wire_python`) gets a view of its output slots, and its
     inputs as a view of the bus when their slots are consecutive, or as
     :class:`~quadcosim.orchestrator.program.Copy` slices;
   - consecutive FMU blocks with one period and no fault share one batch: one call into the C
     runner (:func:`quadcosim.orchestrator.calls.batch`) per group per step.

Running (:meth:`Plan.run`), per macro step ``n`` at ``t_n``: the
:class:`~quadcosim.orchestrator.program.Phase` entries of phase A, due at ``n``, in order; the bus
is recorded (every ``decimation`` steps) and checked for NaN and Inf; the phase B entries due at
``n``. The same plan, read from :attr:`Plan.program`, is run either by the chunk runner
(:class:`quadcosim.orchestrator.chunks.ChunkRunner`, compiled, the default) or one step at a time
by :meth:`Plan._run_steps`.
"""

from __future__ import annotations

import math
import sysconfig
import time
import traceback
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np
from quadcosim.orchestrator.blocks import Block, FMUBlock
from quadcosim.orchestrator.calls import DoStep, FMICall, GetOutputs, SetInputs, batch
from quadcosim.orchestrator.errors import RunInterrupted, SimulationError
from quadcosim.orchestrator.faults import FaultTap, apply_faults, describe, suspects
from quadcosim.orchestrator.fmu import FMUError
from quadcosim.orchestrator.program import RECORD, Entry, Phase, copies
from quadcosim.orchestrator.result import Result, check_record_fits
from quadcosim.orchestrator.signals import signal_dtypes, signal_units

from quadcosim.infra.interrupts import signal_name, signal_number
from quadcosim.infra.progress import Progress

#: This package's folder and the Python's libraries: frames there are not a block's own code.
_NOT_A_BLOCK = (str(Path(__file__).resolve().parent), sysconfig.get_paths()["stdlib"],
                sysconfig.get_paths()["purelib"])


class _BatchPart(NamedTuple):
    period: int
    calls: list[FMICall]
    taps: list[FaultTap]


class _Failure(Exception):
    """A check in the loop failed (a non-finite signal)."""


#: A record this large (bytes) is touched once before the loop. A smaller one is served by the
#: allocator from memory it recycles (glibc maps fresh pages only above its mmap threshold,
#: which rises to 32 MB as large blocks are freed), so touching it would cost a run, such as a
#: sweep member, more than the page faults it saves.
PRE_TOUCH_BYTES = 32 * 2**20


class Plan:
    """Everything resolved once for one run of ``system``: bus, recording, calls, phases.

    Parameters
    ----------
    system : quadcosim.orchestrator.System
        The system, fully connected.
    duration : float
        Simulated time (s).
    decimation : int
        Record every ``decimation`` macro steps.
    t0 : float
        Start time (s).
    record : list of str, optional
        Signals to record (vector names allowed); every output by default.
    stream : quadcosim.orchestrator.stream.StreamWriter, optional
        Write the record to disk in chunks as the run goes: memory then holds a window of
        rows (:func:`quadcosim.orchestrator.stream.window_rows`), not the whole record.
    """

    def __init__(self, system, duration: float, decimation: int, t0: float, record=None, stream=None):
        self.system, self.dt, self.t0, self.decimation = system, system.dt, t0, decimation
        self.stream, self.record_first = stream, 0  # the row record[0] holds (streamed: a window)
        self.steps = int(round(duration / system.dt))
        if self.steps < 1:
            raise ValueError(f"duration {duration} s is shorter than one macro step ({system.dt} s)")
        self.order = system.order()
        self.position = {b.name: i for i, b in enumerate(self.order)}
        self._lay_out_bus()
        self._plan_recording(record)
        self.fmus: list[FMUBlock] = []
        self.logs = {}  # block name -> its FMU's log, kept after the FMU is freed
        self.texts = {}  # "Block.variable" -> an FMU's String or Binary value after initialization
        for fault in system.faults:
            fault.reset()
            _warn_if_idle(fault, t0, self.steps, self.dt)
        try:
            self._wire_blocks()
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------ building
    def _lay_out_bus(self):
        self.slot: dict[str, int] = {}
        for block in self.order:
            for y in block.outputs:
                self.slot[f"{block.name}.{y}"] = len(self.slot)
        # fault k writes slot len(slot) + k and reads its signal's slot, or the slot of the
        # fault before it on the same input; the input reads the last fault's slot
        self.fault_slot: dict[str, int] = {}  # input -> slot of its last fault
        self.fault_taps: list[FaultTap] = []
        for k, fault in enumerate(self.system.faults):
            source = self.fault_slot.get(fault.target, self.slot[self.system.connections[fault.target]])
            self.fault_slot[fault.target] = len(self.slot) + k
            self.fault_taps.append(FaultTap(fault, source, len(self.slot) + k))
        self.bus = np.zeros(len(self.slot) + len(self.system.faults))

    def _plan_recording(self, record):
        ties = {f"{b.name}.{y}": float(value) for b in self.system.blocks.values() if getattr(b, "ties", None)
                for y, value in zip(b.outputs, b.values, strict=True)}
        self.constant_inputs = {into: ties[source] for into, source in self.system.connections.items()
                                if source in ties}
        if record is None:  # every output but the tie-offs of System.set_input (in meta as constant_inputs)
            hidden = set(ties)
            slots = [s for name, s in self.slot.items() if name not in hidden]
        else:
            slots = sorted({self.slot[name] for signal in record for name in self.system._resolve(signal, "output")})
        by_slot = {v: k for k, v in self.slot.items()}
        self.names = [by_slot[s] for s in slots]
        self.units = signal_units(self.system.blocks, self.names)
        self.dtypes = signal_dtypes(self.system.blocks, self.names)
        self.record_copies = copies(slots)
        rows = self.steps // self.decimation + 1
        if self.stream is not None:
            from quadcosim.orchestrator.stream import window_rows

            rows = window_rows(len(slots), rows)
        check_record_fits(rows, len(slots), self.decimation)
        self.record = np.empty((rows, len(slots)))
        if self.record.nbytes >= PRE_TOUCH_BYTES:
            self.record.fill(0.0)  # touched once here: no first-touch page fault inside the loop
        self.recorded = 0
        if self.stream is not None:
            self.stream.start(self.names, self.units)

    def flush(self):
        """Write the rows of the window to the stream and empty the window."""
        first, rows = self.record_first, self.recorded - self.record_first
        times = np.arange(first, first + rows, dtype=np.float64)  # as result() computes them
        times *= self.decimation
        times *= self.dt
        times += self.t0
        self.stream.write(times, self.record[:rows])
        self.record_first = self.recorded

    def _source(self, block_name: str, u: str) -> tuple[int, bool]:
        """Bus slot input ``u`` reads, and whether its source runs earlier in the order."""
        destination = f"{block_name}.{u}"
        source = self.system.connections[destination]
        early = self.position[source.split(".", 1)[0]] < self.position[block_name]
        return self.fault_slot.get(destination, self.slot[source]), early

    def _outputs(self, block) -> tuple[int, np.ndarray]:
        """First bus slot of ``block``'s outputs, and the view of them."""
        first = self.slot[f"{block.name}.{block.outputs[0]}"] if block.outputs else 0
        return first, self.bus[first:first + len(block.outputs)]

    def _taps(self, block) -> list[FaultTap]:
        return [tap for tap in self.fault_taps if tap.fault.target.startswith(block.name + ".")]

    def _wire_blocks(self):
        self.phase_a: list[Phase] = []
        self.phase_b: list[Phase] = []
        self.program: list[Entry] = []  # what each phase runs, for the chunk runner: A, then B
        pending: list[_BatchPart] = []  # FMU blocks gathered into the next phase-A batch
        late: dict[int, list[FMICall]] = {}  # period -> phase-B calls
        for block in self.order:
            taps = self._taps(block)
            if isinstance(block, FMUBlock):
                calls_a, calls_b = self._wire_fmu(block)
                if pending and (taps or pending[0].period != block.period):
                    self._add_batch(self.phase_a, pending)
                    pending = []
                pending.append(_BatchPart(block.period, calls_a, taps))
                late.setdefault(block.period, []).extend(calls_b)
            else:
                if pending:
                    self._add_batch(self.phase_a, pending)
                    pending = []
                phase = Phase(block.period, self._wire_python(block, taps))
                self.phase_a.append(phase)
                self.program.append(Entry(phase, (), tuple(taps), block))
        if pending:
            self._add_batch(self.phase_a, pending)
        self.program.append(RECORD)
        for period, calls in late.items():
            self._add_batch(self.phase_b, [_BatchPart(period, calls, [])])

    def _wire_fmu(self, block: FMUBlock) -> tuple[list[FMICall], list[FMICall]]:
        """Instantiate ``block``, read its first outputs; its phase-A and phase-B calls."""
        instance = block.instantiate(self.t0)
        self.fmus.append(block)
        self.logs[block.name] = instance.log
        early, late = [], []
        for u in block.inputs:
            slot, is_early = self._source(block.name, u)
            (early if is_early else late).append((u, self.bus.ctypes.data + 8 * slot))
        first, outputs = self._outputs(block)
        outputs[:] = instance.get(block.outputs)
        self.texts.update({f"{block.name}.{k}": v for k, v in instance.texts().items()})
        addresses = [outputs.ctypes.data + 8 * k for k in range(len(block.outputs))]
        calls_a = [SetInputs(block, e) for e in instance.setter([u for u, _ in early], [a for _, a in early])]
        calls_a += [GetOutputs(block, e) for e in instance.getter(block.outputs, addresses)]
        calls_b = [SetInputs(block, e) for e in instance.setter([u for u, _ in late], [a for _, a in late])]
        calls_b.append(DoStep(block, instance.stepper(), block.period * self.dt))
        return calls_a, calls_b

    def _add_batch(self, phases: list[Phase], parts: list[_BatchPart]):
        calls = [c for part in parts for c in part.calls]
        taps = [t for part in parts for t in part.taps]
        phase = Phase(parts[0].period, batch(calls, taps, self.bus))
        phases.append(phase)
        self.program.append(Entry(phase, tuple(calls), tuple(taps), None))

    def _wire_python(self, block: Block, taps: list[FaultTap]) -> Callable[[float], None]:
        """``block.step`` with its inputs gathered from the bus and its outputs written there."""
        block.start(self.t0, block.period * self.dt)
        step, bus = block.step, self.bus
        _, y = self._outputs(block)
        slots = [self._source(block.name, u)[0] for u in block.inputs]
        n = len(slots)
        if n and slots == list(range(slots[0], slots[0] + n)):
            u, gather = bus[slots[0]:slots[0] + n], ()  # a view: no copy at all
        else:
            u, gather = np.zeros(n), copies(slots)
        if not gather and not taps:
            def phase(t):
                step(t, u, y)
            return phase

        def phase(t):
            if taps:
                apply_faults(taps, bus, t)
            for into, source in gather:
                u[into] = bus[source]
            step(t, u, y)
        return phase

    # ------------------------------------------------------------------ running
    def run(self, progress: bool = False, master: str = "chunk"):
        """Step from ``t0`` to ``t0 + steps * dt``.

        Parameters
        ----------
        progress : bool
            Show the run's progress on standard error (:class:`quadcosim.infra.progress.Progress`:
            a bar on a terminal, a few plain lines otherwise).
        master : {"chunk", "step"}
            ``"chunk"``: the compiled chunk runner (:mod:`quadcosim.orchestrator.chunks`) runs whole chunks
            of steps in C; ``"step"``: this loop, in Python, one step at a time. Both give
            bit-identical results.

        Raises
        ------
        quadcosim.orchestrator.SimulationError
            On any failure; its ``result`` holds what was recorded up to it.
        """
        from quadcosim.orchestrator.chunks import ChunkRunner

        # the bar first: on a terminal it shows while the compiled steps load (compiled at the first run after a change)
        bar = Progress(self.steps * self.dt, "run") if progress else None
        try:
            runner = ChunkRunner(self) if master == "chunk" else None  # compiled steps loaded here, not timed
        except BaseException:
            if bar is not None:
                bar.close()
            raise
        self.n = 0
        started, cpu = time.perf_counter(), time.thread_time()
        try:
            if runner is not None:
                runner.run(bar)
            else:
                self._run_steps(bar)
            if bar is not None:  # both return only when the run reached its end
                bar.complete()
        except _Failure as failure:
            raise SimulationError(str(failure), self.result(error=str(failure))) from None
        except FMUError as error:
            from quadcosim.orchestrator.isolated import worker_failure

            message, interrupted = worker_failure(self.fmus, error)
            if interrupted is not None:  # a signal ended a request to a worker: the run was interrupted
                message = f"interrupted by {signal_name(interrupted)} at t = {self.t0 + self.n * self.dt:.6g} s"
                raise RunInterrupted(message, self.result(error=message), interrupted) from None
            message = message or str(error)
            instance = getattr(self.system.blocks.get(error.block), "instance", None)
            if error.status == 2 and instance is not None and instance.terminated():
                message = f"{error.block}: the FMU asked to end the simulation ({error.function} returned Discard, " \
                          f"fmi2Terminated) at t = {error.time:.6g} s; the record holds the steps before"
            if "not a finite number" in message:
                message = self._non_finite(self.t0 + self.n * self.dt) + "\n" + message
            raise SimulationError(message, self.result(error=message)) from None
        except Exception as error:  # a Python block failed: keep what was recorded
            where = raised_at(error)
            message = f"at t = {self.t0 + self.n * self.dt:.6g} s: {type(error).__name__}: {error}{where}"
            failure = SimulationError(message, self.result(error=message))
            failure.traceback = "".join(traceback.format_exception(error))
            raise failure from error
        except KeyboardInterrupt as interrupt:  # Ctrl-C, or SIGTERM by way of Terminated
            number = signal_number(interrupt)
            message = f"interrupted by {signal_name(number)} at t = {self.t0 + self.n * self.dt:.6g} s"
            raise RunInterrupted(message, self.result(error=message), number) from None
        finally:
            self.loop_seconds = time.perf_counter() - started
            self.loop_cpu_seconds = time.thread_time() - cpu
            if bar is not None:
                bar.close()

    def _run_steps(self, bar):
        """The per-step loop; ``self.n`` is the step it stopped at."""
        bus, record, dt, t0, dec = self.bus, self.record, self.dt, self.t0, self.decimation
        phase_a, phase_b, gather = self.phase_a, self.phase_b, self.record_copies
        reduce, isfinite = np.add.reduce, math.isfinite
        chunk = max(1, self.steps // 200)
        n = 0
        try:
            for n in range(self.steps + 1):
                t = t0 + n * dt
                for period, fn in phase_a:
                    if period == 1 or n % period == 0:
                        fn(t)
                if n % dec == 0:
                    row = record[n // dec - self.record_first]
                    for into, source in gather:
                        row[into] = bus[source]
                    self.recorded = n // dec + 1
                    if self.stream is not None and self.recorded - self.record_first == len(record):
                        self.flush()
                    if not isfinite(reduce(bus)):
                        raise _Failure(self._non_finite(t))
                if n == self.steps:
                    break
                for period, fn in phase_b:
                    if period == 1 or n % period == 0:
                        fn(t)
                if bar is not None and n % chunk == 0 and n:
                    bar.update(n * dt - bar.n)
        finally:
            self.n = n

    def non_finite(self, t: float):
        """The failure to raise for a non-finite signal found at time ``t`` (s)."""
        return _Failure(self._non_finite(t))

    def _non_finite(self, t: float) -> str:
        bus = self.bus
        for tap in self.fault_taps:  # a fault that turned a finite signal non-finite is the cause
            if not math.isfinite(bus[tap.slot]) and math.isfinite(bus[tap.source]):
                fault = tap.fault
                return (f"the {fault.kind} fault on {fault.target} (value {fault.value}, from {fault.start} s "
                        f"to {fault.stop} s) made it {bus[tap.slot]} at t = {t:.6g} s")
        for block in self.order:  # the first in the order is where it appeared
            for y in block.outputs:
                name = f"{block.name}.{y}"
                value = bus[self.slot[name]]
                if not math.isfinite(value):
                    return (f"{name} became {value} at t = {t:.6g} s (the first non-finite signal in the block "
                            f"order). " + _cause(self.system, block.name, t))
        return f"a signal became non-finite at t = {t:.6g} s"

    def result(self, error: str | None = None) -> Result:
        """What was recorded so far.

        Parameters
        ----------
        error : str, optional
            The message of the failure that ended the run, kept in the result.

        Returns
        -------
        quadcosim.orchestrator.Result
            Time in s from ``t0``, one column per recorded signal; for a streamed record, read
            back from its folder (:class:`quadcosim.orchestrator.result.StreamedResult`).
        """
        if self.stream is not None:
            return self._streamed(error)
        rows = self.recorded
        times = np.arange(rows, dtype=np.float64)  # in place, one vector: the values of
        times *= self.decimation                   # t0 + arange(rows) * decimation * dt
        times *= self.dt
        times += self.t0
        return Result(times, self.names, self.record[:rows], self._meta(), error)

    def _meta(self) -> dict:
        """The run's meta data: step, decimation, loop time, order, wiring, warnings, units."""
        warnings = {name: {"count": log.warnings, "first": list(log.first_warnings)}
                    for name, log in self.logs.items() if log.warnings}
        return {"dt": self.dt, "decimation": self.decimation, "loop_seconds": getattr(self, "loop_seconds", None),
                "loop_cpu_seconds": getattr(self, "loop_cpu_seconds", None),
                "order": [b.name for b in self.order],
                "connections": dict(self.system.connections), "fmu_warnings": warnings, "units": self.units,
                "constant_inputs": self.constant_inputs, **({"dtypes": self.dtypes} if self.dtypes else {}),
                **({"texts": dict(self.texts)} if self.texts else {})}

    def _streamed(self, error: str | None) -> Result:
        from quadcosim.orchestrator.result import StreamedResult

        if self.recorded > self.record_first:
            self.flush()
        self.stream.close(self._meta(), error)
        return StreamedResult(self.stream.path)

    def close(self):
        """Free the FMU instances and close the Python blocks."""
        for block in self.fmus:
            block.close()
        for block in self.system.blocks.values():
            if isinstance(block, Block):
                block.close()


def _cause(system, block: str, t: float) -> str:
    """The injected fault most likely to have made ``block`` fail at ``t``: among those that feed
    it and had started, one active at ``t`` first, then the nearest, then the latest started.
    Without one, the block to check."""
    found = suspects(system.faults, system.connections, block, t)
    if not found:
        return f"Check the block {block} and its inputs."
    found.sort(key=lambda item: (not item[0].start <= t < item[0].stop, len(item[1]), -item[0].start))
    (fault, path), others = found[0], found[1:]
    where = f"on an input of {block}" if len(path) == 1 else f"feeding it through {' -> '.join(path)}"
    state = "active at that time" if fault.start <= t < fault.stop else "over by then"
    text = f"Likely cause: {describe(fault)}, {state}, {where}. Remove it or lower its value."
    if others:
        text += f" Other faults that had started and feed {block}: " + "; ".join(describe(f) for f, _ in others) + "."
    return text


def _warn_if_idle(fault, t0: float, steps: int, dt: float):
    """Warn when no macro step of the run, ``t0 + n dt`` for ``0 <= n <= steps``, falls in the
    fault's window: the fault would do nothing."""
    first = max(0, math.ceil((fault.start - t0) / dt - 1e-9))
    if first > steps or not t0 + first * dt < fault.stop:
        warnings.warn(f"the {fault.kind} fault on {fault.target} acts for {fault.start} s <= t < {fault.stop} s, "
                      f"when no step of the run ({t0:g} s to {t0 + steps * dt:g} s, every {dt:g} s) falls: "
                      "it has no effect", RuntimeWarning, stacklevel=4)


def raised_at(error: BaseException) -> str:
    """Where ``error`` was raised, the innermost frame outside this package (a user's block):
    ``" (raised at my_filter.py, line 12, in update)"``; empty when it was raised here."""
    frames = [f for f in traceback.extract_tb(error.__traceback__) if not f.filename.startswith(_NOT_A_BLOCK)]
    if not frames or getattr(error, "names_its_block", False):
        return ""
    last = frames[-1]
    return f" (raised at {last.filename}, line {last.lineno}, in {last.name})"
