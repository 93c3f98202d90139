"""An FMU in a worker process of its own: a crash, an exit or a hang of the FMU ends the run
with a message, not the master.

An FMU this project did not build (:func:`is_own`) runs isolated by default. The worker hosts
the same instance a block uses in process (:class:`quadcosim.orchestrator.fmu.FMUInstance`, or
:class:`quadcosim.orchestrator.fmu.FMU3Instance` for FMI 3.0: every variable type): the same set-up,
parameters and log. It asks the instance for the C calls of the loop
(:class:`quadcosim.orchestrator.fmi_types.Stepping`: ``setter``, ``getter``, ``stepper``) with addresses
in a shared memory mapping (``memfd``: nothing is left in ``/dev/shm`` whatever ends the
process), and runs them on request. The master sees an :class:`IsolatedInstance`, whose
``setter``, ``getter`` and ``stepper`` return C calls of its own (``orchestrator/c/isolated.c``)
with the signatures of ``fmi2SetReal``, ``fmi2GetReal`` and ``fmi2DoStep``, so that the call
runner and the chunk runner call them as they call an FMU in process. Each request is one byte
on a pipe and its reply one byte back, so a macro step costs one round trip between the
processes, no pickles. Set-up, reset and the end go through a pickled message on a socket, once
per run.

Settings, read when a block instantiates its FMU:

``QUADCOSIM_FMU_WATCHDOG``
    Wall seconds one request to the worker (a step, a read, or its set-up) may take; beyond
    them the worker is stopped and the run fails, naming the block and the FMU. Unset: no limit
    (Ctrl-C and SIGTERM stop a hanging FMU all the same).
``QUADCOSIM_FMU_IN_PROCESS``
    ``1``: run foreign FMUs in process too (a trusted FMU, for speed).

``quadcosim run`` sets both from ``--watchdog`` and ``--fmu-in-process``.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import mmap
import os
import signal
import socket
import subprocess
import sys
from multiprocessing.connection import Connection
from pathlib import Path

from quadcosim.orchestrator.fmi_types import CEntry, address, signals
from quadcosim.orchestrator.fmu import FMUError, FMUInstance, FMULog, fmu_file, model_description

SOURCE = Path(__file__).resolve().parent / "c" / "isolated.c"
LIBRARY_NAME = "libquadcosim_isolated.so"
OP_PYTHON = 4
FAILURE_NONE, FAILURE_ENDED, FAILURE_WATCHDOG, FAILURE_INTERRUPTED = range(4)
#: The code of each kind of call a program holds, as isolated.c numbers them.
CALL_CODES = {"Set": 0, "Get": 1, "Step": 2}
MAX_PROGRAMS = 256  # as in isolated.c
START_SECONDS = 60.0  # the worker's own start (Python, numpy, fmpy), before any FMU code runs
CLOSE_SECONDS = 5.0  # fmi2Terminate and fmi2FreeInstance at the end: a worker slower than this is killed


class _Proxy(ctypes.Structure):
    """The master's side of one worker, laid out as ``Proxy`` in ``isolated.c``."""

    _fields_ = [("shared", ctypes.c_void_p), ("request_fd", ctypes.c_int), ("reply_fd", ctypes.c_int),
                ("watchdog_ms", ctypes.c_int), ("failure", ctypes.c_int), ("program", ctypes.c_int),
                ("wake_fd", ctypes.c_int), ("spin_skip", ctypes.c_long), ("spin_backoff", ctypes.c_long)]


class _Entry(ctypes.Structure):
    """One C call of the master: a program of the worker, the bus addresses and slots of its
    values (``Entry`` in ``isolated.c``)."""

    _fields_ = [("proxy", ctypes.c_void_p), ("program", ctypes.c_int), ("n", ctypes.c_long),
                ("slots", ctypes.c_void_p), ("where", ctypes.c_void_p)]


_wake: list[int] = []  # the read end of the signal wake-up pipe this module set, once per process


def wake_fd() -> int:
    """A pipe Python writes a byte into when a signal arrives (:func:`signal.set_wakeup_fd`), so
    that a master waiting on a worker wakes at Ctrl-C; -1 outside the main thread, or when
    another library (an asyncio loop) holds the wake-up descriptor."""
    import threading

    if _wake:
        return _wake[0] if signal.set_wakeup_fd(-1) == _wake[1] and signal.set_wakeup_fd(_wake[1]) == -1 else -1
    if threading.current_thread() is not threading.main_thread():
        return -1
    read, write = os.pipe2(os.O_NONBLOCK | os.O_CLOEXEC)
    previous = signal.set_wakeup_fd(write, warn_on_full_buffer=False)
    if previous != -1:  # someone else's: theirs stays
        signal.set_wakeup_fd(previous)
        os.close(read)
        os.close(write)
        return -1
    _wake.extend((read, write))
    return read


@functools.cache
def library() -> ctypes.CDLL:
    """``orchestrator/c/isolated.c`` compiled (next to the call runner, on first use), loaded once."""
    from quadcosim.orchestrator.calls import compile_shared, runner_dir

    path = runner_dir() / LIBRARY_NAME
    if not path.is_file() or path.stat().st_mtime < SOURCE.stat().st_mtime:
        compile_shared(SOURCE, path)
    lib = ctypes.CDLL(str(path))
    lib.shared_size.restype = lib.proxy_size.restype = lib.slots_offset.restype = ctypes.c_long
    lib.shared_size.argtypes = [ctypes.c_long]
    lib.shared_init.argtypes = [ctypes.c_void_p, ctypes.c_long]
    lib.shared_failed_call.argtypes = [ctypes.c_void_p]
    lib.shared_failed_call.restype = ctypes.c_long
    lib.proxy_request.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int]
    lib.proxy_post.argtypes = [ctypes.c_void_p, ctypes.c_int]
    lib.serve.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int, ctypes.c_void_p, ctypes.c_long]
    for name in ("proxy_request", "proxy_post", "serve", "proxy_set", "proxy_get", "proxy_step"):
        getattr(lib, name).restype = ctypes.c_int
    return lib


# ---------------------------------------------------------------------- which FMUs are own
@functools.lru_cache(maxsize=64)
def _digest(path: str, mtime_ns: int, size: int) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def digest(path) -> str:
    """SHA-256 of a file, computed once per version of it (path, modification time, size)."""
    stat = Path(path).stat()
    return _digest(str(path), stat.st_mtime_ns, stat.st_size)


def is_own(path) -> bool:
    """Whether the FMU file ``path`` is one this project built: byte for byte one of the plant
    models in the build folder (:func:`quadcosim.fmus.default_fmu_dir`), whatever its name or place.

    Parameters
    ----------
    path : str or pathlib.Path
        An ``.fmu`` file.

    Returns
    -------
    bool
        True for the project's own FMUs, which run in process; False for any other.
    """
    from quadcosim.fmus import MODELS, default_fmu_dir

    path = Path(path).absolute()
    folder = default_fmu_dir()
    built = [f for name in MODELS for f in (folder / f"{name}.fmu", folder / "fmi3" / f"{name}.fmu") if f.is_file()]
    if path in built:
        return True
    size = path.stat().st_size
    return any(f.stat().st_size == size and digest(f) == digest(path) for f in built)


def watchdog_seconds() -> float | None:
    """The watchdog's wall seconds per request (``$QUADCOSIM_FMU_WATCHDOG``), or None."""
    text = os.environ.get("QUADCOSIM_FMU_WATCHDOG", "").strip()
    if not text:
        return None
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value > 0 or value == float("inf"):
        raise ValueError(f"QUADCOSIM_FMU_WATCHDOG={text!r}: give the wall seconds an FMU step may take, a positive "
                         "number (e.g. 5)")
    return value


def runs_isolated(path, isolated: bool | None = None) -> bool:
    """Whether the FMU at ``path`` runs in a worker process: ``isolated`` if given, else a
    foreign FMU does unless ``$QUADCOSIM_FMU_IN_PROCESS`` is ``1``."""
    if isolated is not None:
        return bool(isolated)
    if os.environ.get("QUADCOSIM_FMU_IN_PROCESS", "").strip() in ("1", "true", "yes"):
        return False
    return not is_own(path)


# ---------------------------------------------------------------------- the master's side
class _Program:
    """What a C call of the master keeps alive, and the FMI function it failed in."""

    def __init__(self, instance: IsolatedInstance, program: int, label: str, keep: tuple):
        self.instance, self.program, self.label, self.keep = instance, program, label, keep

    def failed_function(self) -> str:
        """The FMI function of the failed call (``"fmi3SetUInt16"``)."""
        return self.instance.failed_function(self.program, self.label)


class WorkerFailed(FMUError):
    """The worker of an isolated FMU crashed, exited, or outlasted the watchdog: an
    :class:`quadcosim.orchestrator.fmu.FMUError` whose log holds what happened.

    Parameters
    ----------
    block : str
        Block (instance) name.
    function : str
        The FMI function, or the set-up request, under way.
    status : int
        4 (Fatal).
    time : float or None
        Communication time of the call (s).
    log : list of str
        What happened to the worker.
    """


class IsolatedInstance(FMUInstance):
    """An FMU instance run by a worker process: the instance protocol of the master
    (:class:`quadcosim.orchestrator.fmi_types.Stepping`), for an FMI 2.0 or 3.0 FMU of any variable type.

    Parameters
    ----------
    model : str or pathlib.Path
        Path of an ``.fmu`` file (or a built model's name).
    parameters : dict, optional
        Overrides of parameter start values, by variable name.
    name : str, optional
        Instance (block) name used in messages.
    start_time : float
        Start time (s).
    watchdog : float, optional
        Wall seconds one request may take; :func:`watchdog_seconds` by default.

    Raises
    ------
    quadcosim.orchestrator.fmu_checks.FMURefused
        The FMU refused to start (a ``ValueError``: the command line exits 2).
    WorkerFailed
        The worker crashed, exited or hung during the set-up.
    """

    def __init__(self, model, parameters: dict | None = None, name: str | None = None, start_time: float = 0.0,
                 watchdog: float | None = None):
        from quadcosim.orchestrator.fmi_types import is_fmi3, is_parameter
        from quadcosim.orchestrator.fmu import _unzip

        self.closed, self.process = True, None
        path = fmu_file(model)
        self.path, self.name, self.time = path, name or path.stem, start_time
        self._log = FMULog()
        self.description = description = model_description(path)
        self.fmi3 = is_fmi3(description)
        self.variables = {v.name: v for v in description.modelVariables}
        self.parameters = [v.name for v in description.modelVariables if is_parameter(v)]
        found = [s for causality in ("input", "output") for s in signals(description, causality)]
        self.signal = {s.name: s for s in found}
        self.inputs = [s.name for s in signals(description, "input")]
        self.outputs = [s.name for s in signals(description, "output")]
        self._slot = {s.name: k for k, s in enumerate(found)}  # each signal's float64 in the shared mapping
        self._labels: dict[int, str] = {}  # the worker's programs: the FMI functions each calls
        self.overrides = overrides = self._check_parameters(parameters or {})
        self.watchdog = watchdog_seconds() if watchdog is None else watchdog
        self.failure_text = None
        lib = library()
        capacity = max(1, len(found))
        self._memfd = os.memfd_create("quadcosim-fmu", os.MFD_CLOEXEC)
        size = lib.shared_size(capacity)
        os.ftruncate(self._memfd, size)
        self._map = mmap.mmap(self._memfd, size)
        self._view = ctypes.c_char.from_buffer(self._map)
        lib.shared_init(ctypes.addressof(self._view), capacity)
        request_r, request_w = os.pipe2(os.O_CLOEXEC)
        reply_r, reply_w = os.pipe2(os.O_CLOEXEC)
        ours, theirs = socket.socketpair()
        self._fds = [request_w, reply_r]
        self._control = Connection(ours.detach())
        child = theirs.detach()
        directory = _unzip(path)  # here: the master's exit removes it, however the worker ends
        try:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "quadcosim.orchestrator.isolated_worker", str(child), str(request_r),
                 str(reply_w),
                 str(self._memfd)],
                pass_fds=(child, request_r, reply_w, self._memfd), stdin=subprocess.DEVNULL,
                start_new_session=True)  # the terminal's Ctrl-C reaches the master alone
        finally:
            for fd in (child, request_r, reply_w):
                os.close(fd)
        self._proxy = _Proxy(ctypes.addressof(self._view), request_w, reply_r,
                             int(round(self.watchdog * 1000)) if self.watchdog else 0, 0, -1, wake_fd())
        self.closed = False
        try:
            self._ask(("ready",), "its start", limit=START_SECONDS)  # Python and fmpy loaded: no FMU code yet
            self._ask(("open", str(path), directory, overrides, self.name, start_time), "its set-up")
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------ the loop's calls
    def setter(self, names, addresses) -> list[CEntry]:
        """The C call that sets inputs ``names`` from the float64 values at ``addresses``: kept
        in the shared mapping, applied by the worker with the next request.

        Parameters
        ----------
        names : sequence of str
            Signal names (an FMI 3.0 array: all its elements).
        addresses : sequence of int
            Address of each one's float64 value (on the bus).

        Returns
        -------
        list of quadcosim.orchestrator.fmi_types.CEntry
            One call, of the signature of ``fmi2SetReal``, or none for no names.
        """
        return self._program("Set", names, addresses)

    def getter(self, names, addresses) -> list[CEntry]:
        """The C call that writes outputs ``names`` to the float64 values at ``addresses`` (as
        :meth:`setter`; after each step the worker reads them ahead)."""
        return self._program("Get", names, addresses)

    def stepper(self) -> CEntry:
        """The C call of one communication step in the worker, of the signature of ``fmi2DoStep``."""
        return self._program("Step", [], [])[0]

    def _program(self, direction: str, names, addresses) -> list[CEntry]:
        names, addresses = list(names), list(addresses)
        if direction != "Step" and not names:
            return []
        if len(names) != len(addresses):
            raise ValueError(f"{self.name}: {len(names)} signals and {len(addresses)} addresses")
        self._signals(names)  # unknown names refused here, as in process
        slots = [self._slot[n] for n in names]
        program, label = self._ask(("program", direction, names, slots), "its set-up")
        self._labels[program] = label
        lib = library()
        slots_array = (ctypes.c_long * len(slots))(*slots)
        where = (ctypes.c_void_p * len(addresses))(*addresses)
        entry = _Entry(ctypes.addressof(self._proxy), program, len(names), ctypes.addressof(slots_array),
                       ctypes.addressof(where))
        function = {"Set": lib.proxy_set, "Get": lib.proxy_get, "Step": lib.proxy_step}[direction]
        return [CEntry(address(function), ctypes.addressof(entry), 0, 0, 0, label,
                       _Program(self, program, label, (entry, slots_array, where, function)))]

    def failed_function(self, program: int, label: str) -> str:
        """The FMI function a call of ``program`` failed in (the worker's own account, which
        names the typed call of the group), or ``label``."""
        if self.closed or self._proxy.failure:
            return label
        try:
            return self._ask(("failed",), "its log") or label
        except (FMUError, ValueError, OSError):
            return label

    # ------------------------------------------------------------------ set-up and tests, by name
    def set(self, names, values):
        """Set inputs by signal name (:meth:`quadcosim.orchestrator.fmu.FMUInstance.set`), in the worker.

        Parameters
        ----------
        names : sequence of str
            Signal names.
        values : array_like
            Their values (SI), as float64.
        """
        import numpy as np

        self._call("set", list(names), np.asarray(values, dtype=np.float64).reshape(-1))

    def get(self, names):
        """Signals by name, as float64 (:meth:`quadcosim.orchestrator.fmu.FMUInstance.get`), from the worker.

        Parameters
        ----------
        names : sequence of str
            Signal names.

        Returns
        -------
        ndarray
            Their present values.
        """
        return self._call("get", list(names))

    def step(self, t: float, h: float):
        """One communication step from ``t`` by ``h`` (s), in the worker."""
        self._call("step", t, h)
        self.time = t + h

    def texts(self) -> dict[str, str]:
        """The FMU's String and Binary values (:meth:`quadcosim.orchestrator.fmu.FMUInstance.texts`)."""
        return self._call("texts")

    def terminated(self) -> bool:
        """Whether the FMU asked to end the simulation in its last step."""
        if self.closed or self._proxy.failure:
            return False
        return self._call("terminated")

    def _call(self, method: str, *arguments):
        return self._ask(("call", method, arguments), method)

    @property
    def log(self) -> FMULog:
        """The FMU's log, brought over from the worker while it lives."""
        if not self.closed and not self._proxy.failure and self.process is not None and self.process.poll() is None:
            try:
                self.fetch_log()
            except (FMUError, ValueError, OSError):
                pass
        return self._log

    # ------------------------------------------------------------------ control messages
    def _ask(self, message: tuple, doing: str, limit: float | None = None):
        """Send a control message and return the worker's answer; an error it reports is raised
        here as the master's own, a worker that ends or hangs as a refusal (:class:`FMURefused`:
        these requests come before the loop)."""
        from quadcosim.orchestrator.fmu_checks import FMURefused

        try:
            return self._control_request(message, doing, limit)
        except WorkerFailed as error:
            raise FMURefused(f"{self.name}: {error.log[0]}") from None

    def _control_request(self, message: tuple, doing: str, limit: float | None):
        if self._proxy.failure:
            raise self._failed(doing, None)
        if message[0] != "ready":
            if library().proxy_post(ctypes.byref(self._proxy), OP_PYTHON) < 0:
                self._proxy.failure = FAILURE_ENDED
                raise self._failed(doing, None)
            self._control.send(message)
        limit = self.watchdog if limit is None else limit
        try:
            if not self._control.poll(None if limit in (None, float("inf")) else limit):
                self._proxy.failure = FAILURE_WATCHDOG
                raise self._failed(doing, None)
            answer = self._control.recv()
        except (EOFError, OSError):
            self._proxy.failure = FAILURE_ENDED
            raise self._failed(doing, None) from None
        except KeyboardInterrupt:  # the worker is busy with the request: it is killed, not asked again
            self._proxy.failure = FAILURE_INTERRUPTED
            raise
        if answer[0] == "error":
            raise _rebuild(answer[1], self)
        return answer[1]

    def _failed(self, doing: str, t: float | None) -> WorkerFailed:
        """The failure of the worker, its text kept for :meth:`explain`."""
        return WorkerFailed(self.name, doing, 4, t, [self.what_happened(doing)])

    def what_happened(self, doing: str) -> str:
        """What became of the worker while it was ``doing`` a call: crashed (by which signal),
        exited (with which code), outlasted the watchdog, or was interrupted."""
        if self.failure_text is not None:
            return self.failure_text
        failure = self._proxy.failure
        fmu = self.path.name
        if failure == FAILURE_WATCHDOG:
            self._kill()
            text = (f"{fmu} did not return from {doing} within the watchdog's {self.watchdog:g} s "
                    "(QUADCOSIM_FMU_WATCHDOG, --watchdog); its process was stopped")
        elif failure == FAILURE_INTERRUPTED:
            self._kill()
            text = f"{fmu} was stopped in {doing} by an interrupt"
        else:
            code = self._reap()
            if code is None:
                text = f"{fmu}'s process stopped answering in {doing}"
            elif code < 0:
                name = signal.Signals(-code).name if -code in signal.Signals._value2member_map_ else f"signal {-code}"
                cause = {"SIGSEGV": " (a segmentation fault: the FMU read or wrote memory it does not own)",
                         "SIGABRT": " (the FMU called abort)", "SIGBUS": " (a bus error)",
                         "SIGFPE": " (an arithmetic fault)", "SIGKILL": " (killed from outside)"}.get(name, "")
                text = f"{fmu} crashed in {doing}: its process was killed by {name}{cause}"
            else:
                text = f"{fmu} ended its process in {doing} with exit code {code} (the FMU called exit)"
        kept = " The record is kept up to the last good step;" if doing in self._labels.values() else ""
        self.failure_text = text + f".{kept} Run the FMU in fmpy (fmpy simulate) or ask its exporter for a fixed one."
        return self.failure_text

    def explain(self, error: FMUError) -> str | None:
        """The message of a run this instance's worker ended: the block, the FMU and what
        happened; None when the worker did not fail (the FMU returned an error status)."""
        if not self._proxy.failure:
            return None
        doing = self._labels.get(self._proxy.program, error.function)
        when = "" if error.time is None else f" at t = {error.time:.6g} s"
        return f"{self.name} ({self.path}, run in its own process){when}: {self.what_happened(doing)}"

    @property
    def interrupted(self) -> bool:
        """Whether a signal ended the last request (the master raises it)."""
        return self._proxy.failure == FAILURE_INTERRUPTED

    def _reap(self) -> int | None:
        try:
            return self.process.wait(timeout=2.0)
        except subprocess.TimeoutExpired:
            self._kill()
            return None

    def _kill(self):
        if self.process is not None and self.process.poll() is None:
            self.process.kill()
            self.process.wait()

    # ------------------------------------------------------------------ FMUInstance's life cycle
    def reset(self, parameters: dict | None = None, name: str | None = None, start_time: float = 0.0):
        """As :meth:`quadcosim.orchestrator.fmu.FMUInstance.reset`, in the worker.

        Parameters
        ----------
        parameters : dict, optional
            Overrides of parameter start values, by variable name.
        name : str, optional
            Instance (block) name used in messages.
        start_time : float
            Start time (s).
        """
        self.overrides = overrides = self._check_parameters(parameters or {})
        self.name, self.time = name or self.path.stem, start_time
        self._log.clear()
        self._log.warnings, self._log.first_warnings = 0, []
        try:
            self._ask(("reset", overrides, self.name, start_time), f"fmi{3 if self.fmi3 else 2}Reset")
        except BaseException:
            self.close()
            raise

    def fetch_log(self):
        """Copy the worker's log (messages, warnings) into :attr:`log`."""
        if self.closed or self._proxy.failure:
            return
        messages, warnings, first = self._ask(("log",), "its log")
        self._log.clear()
        self._log.extend(messages)
        self._log.warnings, self._log.first_warnings = warnings, first

    def close(self):
        """End the worker: terminate and free the FMU there (a worker that failed is killed),
        then release the pipes and the shared memory."""
        if self.closed:
            return
        self.closed = True
        try:
            if self.process is not None and self.process.poll() is None and not self._proxy.failure:
                self.watchdog = min(self.watchdog or CLOSE_SECONDS, CLOSE_SECONDS)
                try:
                    messages, warnings, first = self._ask(("close",), f"fmi{3 if self.fmi3 else 2}Terminate")
                    self._log.clear()
                    self._log.extend(messages)
                    self._log.warnings, self._log.first_warnings = warnings, first
                    self.process.wait(timeout=5.0)
                except (FMUError, ValueError, subprocess.TimeoutExpired, OSError):
                    pass
        finally:
            self._kill()
            self._control.close()
            for fd in self._fds:
                os.close(fd)
            self._fds = []
            del self._view
            self._map.close()
            os.close(self._memfd)

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass


def worker_failure(blocks, error: FMUError) -> tuple[str | None, int | None]:
    """The message of a run that ``error`` ended, when a worker failed under it.

    Parameters
    ----------
    blocks : list of quadcosim.orchestrator.FMUBlock
        The run's FMU blocks, their instances live.
    error : quadcosim.orchestrator.fmu.FMUError
        What the runner raised.

    Returns
    -------
    message : str or None
        The block, the FMU and what happened to its worker, or the FMU's error with its file
        named for an FMU given by path; None otherwise (the error's own message stands).
    interrupted : int or None
        The signal that ended the request (the run was interrupted, not failed), else None.
    """
    from quadcosim.infra.interrupts import stopping

    for block in blocks:
        instance = getattr(block, "instance", None)
        if isinstance(instance, IsolatedInstance) and block.name == error.block and instance._proxy.failure:
            if instance.interrupted:
                instance.what_happened(error.function)
                return None, stopping() or int(signal.SIGINT)
            return instance.explain(error), None
        if block.name == error.block and str(block.model).lower().endswith(".fmu"):  # a user's FMU: named
            text = str(error)
            return f"{block.name} ({Path(block.model).name}):{text[len(block.name) + 1:]}", None
    return None, None


def _rebuild(error: tuple, instance: IsolatedInstance) -> Exception:
    """The master's exception for an error the worker reported as ``(kind, message, fields)``."""
    from quadcosim.orchestrator.fmu import ParameterRefused
    from quadcosim.orchestrator.fmu_checks import FMURefused

    kind, message, fields = error
    if kind == "FMUError":
        return FMUError(instance.name, fields["function"], fields["status"], fields["time"], fields["log"])
    if kind == "ParameterRefused":
        inner = FMUError(instance.name, fields["function"], fields["status"], fields["time"], fields["log"])
        return ParameterRefused(inner, instance.overrides, instance.path.stem)
    if kind == "FMURefused":
        return FMURefused(message)
    if kind in ("KeyError", "TypeError", "ValueError"):
        return {"KeyError": KeyError, "TypeError": TypeError, "ValueError": ValueError}[kind](message)
    return RuntimeError(f"{instance.name} ({instance.path.name}, in its worker process): {kind}: {message}")


def open_instance(model, parameters: dict | None = None, name: str | None = None, start_time: float = 0.0,
                  isolated: bool | None = None) -> FMUInstance:
    """An initialized instance of ``model``: in a worker process for a foreign FMU
    (:func:`runs_isolated`), else in process; its set-up refusals as
    :class:`quadcosim.orchestrator.fmu_checks.FMURefused`.

    Parameters
    ----------
    model : str or pathlib.Path
        A built model's name or an ``.fmu`` path.
    parameters, name, start_time
        As for :class:`quadcosim.orchestrator.fmu.FMUInstance`.
    isolated : bool, optional
        Force the choice; by default :func:`runs_isolated` decides.

    Returns
    -------
    quadcosim.orchestrator.fmu.FMUInstance
        Or its :class:`IsolatedInstance`.
    """
    from quadcosim.orchestrator.fmu_checks import probe, refused_at_start

    path = fmu_file(model)
    own = is_own(path)
    if isolated if isolated is not None else runs_isolated(path) if not own else False:
        instance = IsolatedInstance(path, parameters, name=name, start_time=start_time)
    else:
        try:
            instance = FMUInstance(model, parameters, name=name, start_time=start_time)
        except Exception as error:
            refusal = refused_at_start(error, name or path.stem, path)
            if refusal is None:
                raise
            raise refusal from None
    if not own:
        try:
            probe(instance, instance.inputs + instance.outputs)
        except BaseException:
            instance.close()
            raise
    return instance
