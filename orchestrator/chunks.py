"""The chunk runner: the master's loop in compiled code, for whole chunks of macro steps.

A :class:`~quadcosim.orchestrator.plan.Plan` is turned into a program of operations per step, run by
``run_chunk`` of ``orchestrator/c/calls.c``:

- each FMI call of a batch (``fmi2SetReal`` straight from the bus, ``fmi2GetReal`` into it,
  ``fmi2DoStep``);
- each block with a compiled step (:meth:`quadcosim.orchestrator.blocks.Block.compiled`): its inputs
  gathered from the bus, its C-callable step called with its outputs' slots of the bus;
- each :class:`~quadcosim.orchestrator.blocks.Table` and :class:`~quadcosim.orchestrator.blocks.Constant`: a row
  copied onto the bus (a callable table is evaluated by Python a chunk of rows at a time, the
  same chunks as the per-step master evaluates);
- the recording (every ``decimation`` steps) and the non-finite check of the whole bus.

The runner returns to Python at the end of each chunk (progress, table rows, Ctrl-C), at once
on a failure with the step and the operation, and at each operation only Python can run: a
block without a compiled form, and the faults. Faults are applied by the same Python code as
in the per-step master, at the same point of the step, so that they stay exact: a system with
faults costs one return to Python per faulted phase and step. Everything else gives the same
numbers as the per-step master, bit for bit (the same compiled functions on the same values
in the same order).
"""

from __future__ import annotations

import ctypes

import numpy as np
from quadcosim.orchestrator.blocks import Block, Constant, Table
from quadcosim.orchestrator.calls import _pack, runner_library
from quadcosim.orchestrator.faults import apply_faults
from quadcosim.orchestrator.fmu import FMUError
from quadcosim.orchestrator.program import RECORD

from quadcosim.infra.progress import status

OP_BLOCK, OP_TABLE, OP_RECORD, OP_PYTHON = 3, 4, 5, 6
CHUNK_DONE, PYTHON, FINISHED, NON_FINITE, FMI_FAILED, BLOCK_FAILED = range(6)
CHUNK_STEPS = 4096  # macro steps per call into C: a few ms to tens of ms of wall time


class _Gather(ctypes.Structure):
    _fields_ = [("into", ctypes.c_long), ("source", ctypes.c_long), ("n", ctypes.c_long)]


class _Op(ctypes.Structure):
    """One operation, laid out as ``Op`` in ``orchestrator/c/calls.c``."""

    _fields_ = [("kind", ctypes.c_int), ("period", ctypes.c_int), ("function", ctypes.c_void_p),
                ("component", ctypes.c_void_p), ("vr", ctypes.c_void_p), ("n", ctypes.c_size_t),
                ("values", ctypes.c_void_p), ("h", ctypes.c_double), ("step", ctypes.c_void_p),
                ("u", ctypes.c_void_p), ("y", ctypes.c_void_p), ("data", ctypes.c_void_p),
                ("gather", ctypes.c_void_p), ("gathers", ctypes.c_long), ("table", ctypes.c_void_p),
                ("first_row", ctypes.c_long), ("rows", ctypes.c_long), ("width", ctypes.c_long)]


class _Program(ctypes.Structure):
    """The program and its resumable position, laid out as ``Program`` in ``calls.c``."""

    _fields_ = [("ops", ctypes.c_void_p), ("count", ctypes.c_long), ("bus", ctypes.c_void_p),
                ("bus_size", ctypes.c_long), ("record", ctypes.c_void_p), ("record_width", ctypes.c_long),
                ("record_gather", ctypes.c_void_p), ("record_gathers", ctypes.c_long),
                ("decimation", ctypes.c_long), ("t0", ctypes.c_double), ("dt", ctypes.c_double),
                ("last", ctypes.c_long), ("n", ctypes.c_long), ("op", ctypes.c_long), ("recorded", ctypes.c_long),
                ("status", ctypes.c_int), ("record_first", ctypes.c_long)]


def _gathers(pairs: list[tuple[int, int, int]]):
    """A ctypes array of (into, source, n) copies."""
    return (_Gather * max(1, len(pairs)))(*[_Gather(*p) for p in pairs])


def _runs(slots: list[int]) -> list[tuple[int, int, int]]:
    """Copies gathering bus ``slots`` into a vector, one per run of consecutive slots."""
    from quadcosim.orchestrator.program import consecutive

    return [(i, slots[i], j - i) for i, j in consecutive(slots)]


class _Item:
    """One operation being built: its C form, what it describes, and what keeps it alive."""

    def __init__(self, op: _Op, owner=None, python=None, table=None, keep=()):
        self.op, self.owner, self.python, self.table, self.keep = op, owner, python, table, keep


class ChunkRunner:
    """The program of a plan, and the loop that runs it a chunk at a time.

    Parameters
    ----------
    plan : quadcosim.orchestrator.plan.Plan
        A plan, wired (FMUs instantiated, Python blocks started).
    """

    def __init__(self, plan):
        self.plan = plan
        self.items: list[_Item] = []
        for entry in plan.program:
            self._add_entry(entry)
        self.ops = (_Op * len(self.items))(*[item.op for item in self.items])
        self.record_gather = _gathers([(c.into.start, c.source.start, c.into.stop - c.into.start)
                                       for c in plan.record_copies])
        bus, record = plan.bus, plan.record
        self.program = _Program(ctypes.addressof(self.ops), len(self.items), bus.ctypes.data, len(bus),
                                record.ctypes.data, record.shape[1], ctypes.addressof(self.record_gather),
                                len(plan.record_copies), plan.decimation, plan.t0, plan.dt, plan.steps, 0, 0, 0, 0, 0)
        self.tables = [k for k, item in enumerate(self.items) if item.table is not None
                       and item.table.function is not None]

    # ------------------------------------------------------------------ building
    def _add_entry(self, entry):
        plan = self.plan
        if entry is RECORD:
            self.items.append(_Item(_Op(kind=OP_RECORD, period=1)))
            return
        period = entry.phase.period
        if entry.calls:
            if entry.taps:
                self._python(period, _faults(list(entry.taps), plan.bus), entry.calls[0].block)
            for call in entry.calls:
                packed = _pack(call, plan.bus)
                op = _Op(kind=packed.kind, period=period, function=packed.function, component=packed.component,
                         vr=packed.vr, n=packed.n, values=packed.values, h=packed.h)
                self.items.append(_Item(op, owner=call, keep=(call,)))
            return
        self._add_block(entry, period)

    def _add_block(self, entry, period: int):
        plan, block = self.plan, entry.block
        first, outputs = plan._outputs(block)
        y = plan.bus.ctypes.data + 8 * first
        if type(block) in (Table, Constant):  # exactly these: a subclass may step otherwise
            rows = block.values.reshape(1, -1) if isinstance(block, Constant) else block.segment(0)[1]
            rows = np.ascontiguousarray(rows, dtype=float)
            op = _Op(kind=OP_TABLE, period=period, y=y, table=rows.ctypes.data, first_row=0, rows=len(rows),
                     width=len(block.outputs))
            self.items.append(_Item(op, owner=block, table=block if type(block) is Table else None,
                                    keep=[rows]))
            return
        if type(block).compiled is not Block.compiled:
            status(f"{block.name}: loading its compiled step")  # a compile, when one happens, is announced
        compiled = block.compiled()
        if compiled is None:
            self._python(period, entry.phase.run, block)
            return
        if entry.taps:
            self._python(period, _faults(list(entry.taps), plan.bus), block)
        slots = [plan._source(block.name, u)[0] for u in block.inputs]
        if len(compiled.inputs) < len(slots) or compiled.inputs.dtype != np.float64:
            raise ValueError(f"{block.name}: its compiled step's input buffer holds {len(compiled.inputs)} "
                             f"values for {len(slots)} inputs")
        runs = _runs(slots)
        gather = _gathers(runs)
        op = _Op(kind=OP_BLOCK, period=period, step=compiled.address, u=compiled.inputs.ctypes.data, y=y,
                 data=compiled.data.ctypes.data, gather=ctypes.addressof(gather), gathers=len(runs))
        self.items.append(_Item(op, owner=block, keep=(compiled, gather)))

    def _python(self, period: int, run, owner):
        self.items.append(_Item(_Op(kind=OP_PYTHON, period=period), owner=owner, python=run))

    # ------------------------------------------------------------------ running
    def run(self, bar=None):
        """Run the plan to its last step, updating ``plan.n`` and ``plan.recorded``.

        Parameters
        ----------
        bar : quadcosim.infra.progress.Progress, optional
            Updated at the end of each chunk.

        Raises
        ------
        quadcosim.orchestrator.fmu.FMUError
            An FMI call failed.
        Exception
            What :meth:`quadcosim.orchestrator.plan.Plan.non_finite` returns, or what a Python block raised.
        """
        plan, program, items = self.plan, self.program, self.items
        run_chunk = runner_library().run_chunk
        pointer = ctypes.addressof(program)
        dt, t0 = plan.dt, plan.t0
        while True:
            end = self._chunk_end()
            try:
                code = run_chunk(pointer, end)
            finally:  # a signal raised as the call returns leaves the record's length known too
                plan.n, plan.recorded = program.n, program.recorded
            if plan.stream is not None and plan.recorded - plan.record_first == len(plan.record):
                plan.flush()  # the window is full: to disk, and the next rows start at record[0]
                program.record_first = plan.record_first
            if code == CHUNK_DONE:
                if bar is not None:
                    bar.update(program.n * dt - bar.n)
                continue
            if code == PYTHON:
                items[program.op].python(t0 + program.n * dt)
                program.op += 1
                continue
            if code == FINISHED:
                return
            self._fail(code)

    def _chunk_end(self) -> int:
        """The step the next chunk stops before: a chunk ahead, and no further than the rows of
        the callable tables at hand (refilled here when the present step needs the next ones)."""
        program, plan = self.program, self.plan
        end = min(program.n + CHUNK_STEPS, plan.steps + 1)
        if plan.stream is not None:  # no further than the last step whose row fits in the window
            end = min(end, (plan.record_first + len(plan.record) - 1) * plan.decimation + 1)
        for k in self.tables:
            op, table = self.ops[k], self.items[k].table
            row = -(-program.n // op.period)  # the table's next row due
            if row >= op.first_row + op.rows:
                first, rows = table.segment(row)
                self.items[k].keep = [rows]
                op.table, op.first_row, op.rows = rows.ctypes.data, first, len(rows)
            end = min(end, (op.first_row + op.rows) * op.period)
        return end

    def _fail(self, code: int):
        plan, program = self.plan, self.program
        item = self.items[program.op]
        t = plan.t0 + program.n * plan.dt
        if code == NON_FINITE:
            raise plan.non_finite(t)
        if code == FMI_FAILED:
            call = item.owner
            raise FMUError(call.block.name, call.function, program.status, t, list(call.block.instance.log))
        raise RuntimeError(f"{item.owner.name}: its compiled step returned {program.status} at t = {t:.6g} s")


def _faults(taps: list, bus: np.ndarray):
    """The faults of ``taps`` as a Python operation of time ``t`` (s)."""
    def run(t):
        apply_faults(taps, bus, t)
    return run
