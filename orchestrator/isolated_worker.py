"""The worker process of an isolated FMU (:mod:`quadcosim.orchestrator.isolated`): it hosts the FMU's
instance and runs the C calls of its programs on the master's requests.

Run as ``python -m quadcosim.orchestrator.isolated_worker CONTROL REQUEST REPLY MEMFD`` by
:class:`quadcosim.orchestrator.isolated.IsolatedInstance`, with the descriptors it passes.
"""

from __future__ import annotations

import ctypes
import mmap
import os
import signal
import sys
from multiprocessing.connection import Connection
from pathlib import Path

from quadcosim.orchestrator.fmi_types import CEntry
from quadcosim.orchestrator.fmu import FMUError, FMUInstance, FMULog
from quadcosim.orchestrator.isolated import CALL_CODES, MAX_PROGRAMS, OP_PYTHON, library


class _Call(ctypes.Structure):
    """One C call of the hosted instance, in the worker (``Call`` in ``isolated.c``)."""

    _fields_ = [("function", ctypes.c_void_p), ("component", ctypes.c_void_p), ("vr", ctypes.c_void_p),
                ("n", ctypes.c_size_t), ("values", ctypes.c_void_p), ("kind", ctypes.c_int),
                ("program", ctypes.c_int)]


def _describe(error: BaseException) -> tuple:
    fields = {}
    if isinstance(error, FMUError):
        fields = {"function": error.function, "status": error.status, "time": error.time, "log": list(error.log)}
    return type(error).__name__, str(error), fields


class _Hosted:
    """The worker's instance and the C calls of its programs."""

    def __init__(self, instance, slots: int):
        self.instance, self.slots = instance, slots
        self.calls: list[tuple[int, int, CEntry]] = []  # (program, kind, entry)
        self.programs = 0
        self.table = (_Call * 0)()
        self.failed_call = None  # the shared mapping's "call": set by serve

    def add(self, direction: str, names: list, slots: list) -> tuple[int, str]:
        """A new program: the instance's calls for ``names`` at their slots; its number and label."""
        if self.programs >= MAX_PROGRAMS:
            raise ValueError(f"more than {MAX_PROGRAMS} call groups for one FMU")
        instance = self.instance
        if direction == "Step":
            entries = [instance.stepper()]
        else:
            addresses = [self.slots + 8 * k for k in slots]
            entries = (instance.setter if direction == "Set" else instance.getter)(names, addresses)
        program = self.programs
        self.programs += 1
        self.calls += [(program, CALL_CODES[direction], e) for e in entries]
        self.table = (_Call * len(self.calls))(*[_Call(e.function, e.component, e.vr or None, e.n, e.values or None,
                                                       kind, p) for p, kind, e in self.calls])
        return program, ", ".join(dict.fromkeys(e.label for e in entries))

    def failed(self, call: int) -> str | None:
        """The FMI function the call ``call`` of the table failed in."""
        if not 0 <= call < len(self.calls):
            return None
        entry = self.calls[call][2]
        failed = getattr(entry.keep, "failed_function", None)
        return failed() if failed is not None else entry.label


def _answer(message: tuple, hosted: _Hosted | None, slots: int, shared):
    """The worker's hosted instance after a control message, and its answer."""
    from quadcosim.orchestrator import fmu as module
    from quadcosim.orchestrator.fmu_checks import refused_at_start

    kind = message[0]
    instance = hosted.instance if hosted is not None else None
    if kind == "open":
        _, path, directory, overrides, name, start_time = message
        module._extracted[(path, Path(path).stat().st_mtime)] = directory  # the master's copy
        try:
            return _Hosted(FMUInstance(path, overrides, name=name, start_time=start_time), slots), None
        except Exception as error:
            refusal = refused_at_start(error, name, Path(path))
            raise refusal if refusal is not None else error from None
    if kind == "reset":
        _, overrides, name, start_time = message
        instance.reset(overrides, name=name, start_time=start_time)
        return hosted, None
    if kind == "program":
        return hosted, hosted.add(*message[1:])
    if kind == "call":
        _, method, arguments = message
        return hosted, getattr(instance, method)(*arguments)
    if kind == "failed":
        return hosted, hosted.failed(library().shared_failed_call(shared))
    if kind in ("log", "close"):
        log = instance.log if instance is not None else FMULog()
        if kind == "close" and instance is not None:
            instance.close()
        return hosted, (list(log), log.warnings, list(log.first_warnings))
    raise ValueError(f"unknown request {kind!r}")


def _worker(control_fd: int, request_fd: int, reply_fd: int, memfd: int):
    """Serve one FMU instance for the master at the other end of the descriptors."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the master decides; it kills this process
    try:  # and this process ends with the master, whatever ends it
        ctypes.CDLL(None).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (AttributeError, OSError):
        pass
    if os.getppid() == 1:
        os._exit(0)
    control = Connection(control_fd)
    control.send(("ok", None))  # started: the watchdog counts the FMU's time from here
    shared = mmap.mmap(memfd, 0)
    view = ctypes.c_char.from_buffer(shared)
    lib = library()
    hosted = None
    address_ = ctypes.addressof(view)
    slots = address_ + lib.slots_offset()
    while True:
        table = hosted.table if hosted is not None else None
        code = lib.serve(address_, request_fd, reply_fd, ctypes.addressof(table) if table else None,
                         len(table) if table else 0)
        if code != OP_PYTHON:
            break
        try:
            message = control.recv()
        except EOFError:
            break
        kind = message[0]
        try:
            hosted, answer = _answer(message, hosted, slots, address_)
            control.send(("ok", answer))
        except Exception as error:
            control.send(("error", _describe(error)))
            if kind == "open":
                break
        if kind == "close":
            break
    control.close()
    os._exit(0)  # no exit handlers: the extracted folder is the master's to remove


if __name__ == "__main__":
    _worker(*(int(a) for a in sys.argv[1:5]))
