"""Interrupts that end a run cleanly.

Ctrl-C raises ``KeyboardInterrupt``; :func:`terminate_as_interrupt` makes SIGTERM raise
:class:`Terminated`, a ``KeyboardInterrupt`` too. The master catches both between two steps,
keeps what was recorded and frees the FMUs, so that a run stopped either way leaves its
partial results and no extracted FMU behind.

While a record is being made safe (saved, and its ``metrics.json`` written), :func:`held`
holds both signals back: the save finishes, and the first signal held is raised when the
block ends. A second Ctrl-C, pressed because the first seemed slow, cannot cut the save short.

Python drops an exception raised inside a finaliser or a weakref callback (matplotlib's
figures run many as they are freed) after printing it; the finaliser of a file object clears
an exception of its ``close`` without a word (fmpy's zip members are closed so while a model
description is read); and an extension module whose making is interrupted can be left broken
(pybind11 turns the interrupt into an ImportError). A signal whose interrupt would be dropped,
that lands in a file's ``close`` or that arrives during an import, is signalled again once that
is over (:func:`_dropped`, :func:`_handle`): it is raised late, never lost.
"""

from __future__ import annotations

import _thread
import contextlib
import io
import signal
import sys
import threading
import time


class Terminated(KeyboardInterrupt):
    """SIGTERM was received."""

    signal_number = signal.SIGTERM


def signal_number(interrupt: BaseException) -> int:
    """The signal behind an interrupt: SIGTERM for :class:`Terminated`, else SIGINT."""
    return int(getattr(interrupt, "signal_number", signal.SIGINT))


def signal_name(number: int) -> str:
    """The name of a signal.

    Parameters
    ----------
    number : int
        Signal number.

    Returns
    -------
    str
        ``"SIGINT"`` for 2, and so on; ``"signal N"`` for a number with no name.
    """
    try:
        return signal.Signals(number).name
    except ValueError:
        return f"signal {number}"


def exit_code(interrupt: BaseException) -> int:
    """The shell's exit code for a process ended by the interrupt's signal: 130 or 143."""
    return 128 + signal_number(interrupt)


def leave(code: int, at_once: bool = False):
    """End the process with exit code ``code``, even after an interrupt.

    CPython marks a KeyboardInterrupt raised inside code it runs from a string (``exec``, as
    dataclasses and numba do) as unhandled even when the program handles it, and under
    ``python -m`` then ends the process by SIGINT instead of with the exit code. An interrupted
    command (130, 143) therefore leaves through ``os._exit``, once the exit handlers have run
    and the streams are flushed; any other code through ``sys.exit``.

    Parameters
    ----------
    code : int
        The process's exit code.
    at_once : bool
        Leave through ``os._exit`` whatever the code (the exit handlers run and the streams are
        flushed first): the interpreter's finalisation, which restores SIGINT's and SIGTERM's
        default actions and takes a while with numba and matplotlib loaded, is skipped, so a
        signal as the process ends meets the program's handler, never the default (exit -15).
    """
    import os

    if at_once or code in (128 + signal.SIGINT, 128 + signal.SIGTERM):
        import atexit

        atexit._run_exitfuncs()
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


def _raise_terminated(number, frame):
    raise Terminated()


@contextlib.contextmanager
def terminate_as_interrupt():
    """Within the block, SIGTERM raises :class:`Terminated` instead of killing the process."""
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


_HELD = (signal.SIGINT, signal.SIGTERM)


class _State:
    """Who handles SIGINT and SIGTERM: the handlers replaced, the depth of :func:`held` blocks,
    the signal already raised by a :func:`first_only` region and the signals noted."""

    def __init__(self):
        self.previous: dict | None = None
        self.unraisable = None  # the unraisable-exception hook replaced
        self.dropping = False  # _dropped is running
        self.deferred: list[int] = []  # signals to raise once an import or a dropped interrupt is over
        self.regions = 0
        self.depth = 0
        self.raised: int | None = None
        self.noted: list[int] = []


_state = _State()


def interrupt_for(number: int) -> KeyboardInterrupt:
    """The exception a signal raises.

    Parameters
    ----------
    number : int
        Signal number.

    Returns
    -------
    KeyboardInterrupt
        :class:`Terminated` for SIGTERM, else ``KeyboardInterrupt``.
    """
    return Terminated() if number == signal.SIGTERM else KeyboardInterrupt()


def _handle(number, frame):
    if _state.depth or _state.raised is not None:
        _state.noted.append(number)  # a save is under way, or the run is already stopping
        return
    if _busy(frame):  # raised here, it would be dropped, or break a module
        _defer(number)
        return
    if _state.deferred:  # the first signal deferred is the one that stops the run
        number, later = _state.deferred[0], _state.deferred[1:]
        _state.deferred = []
        _state.noted.extend(later)
    _state.raised = number
    raise interrupt_for(number)


def _importing(frame) -> bool:
    """Whether the code at ``frame`` runs inside an import."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib"):
            return True
        frame = frame.f_back
    return False


def _closing(frame) -> bool:
    """Whether the code at ``frame`` runs inside the ``close`` of a file object, which its
    finaliser may be running: an exception raised there is then cleared, unreported."""
    while frame is not None:
        code = frame.f_code
        if code.co_name == "close" and code.co_argcount and isinstance(frame.f_locals.get(code.co_varnames[0]),
                                                                       io.IOBase):
            return True
        frame = frame.f_back
    return False


def _busy(frame) -> bool:
    """Whether a signal handled in the main thread at ``frame`` could not be raised there:
    :func:`_dropped` is running, the main thread is importing (an extension module stopped in
    its making can be left broken) or closing a file (its finaliser would clear the interrupt)."""
    return _state.dropping or _importing(frame) or _closing(frame)


def _dropped(unraisable):
    """``sys.unraisablehook`` while the signals are taken over: an interrupt that :func:`_handle`
    raised inside a finaliser or weakref callback, which Python drops, is signalled again once
    this hook has returned; any other exception is reported as before."""
    if (_state.raised is not None and isinstance(unraisable.exc_value, KeyboardInterrupt)
            and threading.current_thread() is threading.main_thread()):
        number, _state.raised = _state.raised, None
        _state.dropping = True
        _defer(number, first=True)
        _state.dropping = False  # the last statement: no signal can be handled between it and the return
        return
    (_state.unraisable or sys.__unraisablehook__)(unraisable)


def _defer(number: int, first: bool = False):
    """Keep signal ``number`` (last, or ``first``) and, from another thread, signal the first kept
    to the main thread once it is no longer :func:`_busy`."""

    def signal_again():
        while _busy(sys._current_frames().get(threading.main_thread().ident)):
            time.sleep(0.001)
        if _state.deferred:
            _thread.interrupt_main(_state.deferred[0])

    if first:
        _state.deferred.insert(0, number)
    else:
        _state.deferred.append(number)
    threading.Thread(target=signal_again, name="signal again", daemon=True).start()


def _install() -> bool:
    """Take over both signals (main thread only); False where signals cannot be handled."""
    if threading.current_thread() is not threading.main_thread():
        return False
    if _state.previous is None:
        _state.previous = {number: signal.signal(number, _handle) for number in _HELD}
        _state.unraisable, sys.unraisablehook = sys.unraisablehook, _dropped
    return True


def _uninstall():
    if _state.previous is not None and not _state.regions and not _state.depth:
        for number, handler in _state.previous.items():
            signal.signal(number, handler)
        if sys.unraisablehook is _dropped:
            sys.unraisablehook = _state.unraisable
        waiting = _state.deferred[0] if _state.deferred and _state.raised is None else None
        _state.previous, _state.raised, _state.noted, _state.unraisable = None, None, [], None
        _state.deferred = []
        if waiting is not None:  # kept, not yet raised: the handlers now in place act on it
            signal.raise_signal(waiting)


@contextlib.contextmanager
def first_only(final: bool = False):
    """Within the block, the first SIGINT or SIGTERM raises (as :func:`interrupt_for` makes
    it); every later one is noted and ignored: the run it stopped is being saved.

    Parameters
    ----------
    final : bool
        The process ends with the block: when a signal stopped it, both signals stay ignored
        after it, so that the exit code is the first signal's (a command line's last block).

    Outside the main thread the block changes nothing.
    """
    if not _install():
        yield
        return
    _state.regions += 1
    try:
        yield
    finally:
        _state.regions -= 1
        if final and _state.raised is not None and not _state.regions:
            _state.previous = dict.fromkeys(_HELD, signal.SIG_IGN)
        _uninstall()


@contextlib.contextmanager
def held():
    """Within the block, SIGINT and SIGTERM are noted, not raised: a save under way finishes.

    On leaving the block without an exception, the first signal noted is raised, unless an
    enclosing :func:`first_only` region has raised one already (the run is then stopping, and
    the later signals are ignored). Blocks nest. Outside the main thread (a worker of a sweep),
    where signals cannot be handled, the block holds nothing back.

    Yields
    ------
    list of int
        The signals noted so far.
    """
    if not _install():
        yield []
        return
    _state.depth += 1
    try:
        yield _state.noted
    finally:
        _state.depth -= 1
        waiting = _state.noted[0] if not _state.depth and _state.raised is None and _state.noted else None
        if waiting is not None:
            _state.raised = waiting
        _uninstall()
    if waiting is not None:
        raise interrupt_for(waiting)


def pending() -> list[int]:
    """The signals noted since the first :func:`held` block or :func:`first_only` region began."""
    return list(_state.noted)


def stopping() -> int | None:
    """The signal that a :func:`first_only` region has raised, if any (it is ending the run)."""
    return _state.raised


@contextlib.contextmanager
def surfaced():
    """Within the block, a signal is raised as its interrupt even when the library it lands in
    turns it into another exception.

    pymavlink's compiled indexer reports a Ctrl-C that lands in it as a ``MemoryError``, which a
    reader would then call a corrupt log. Here the first SIGINT or SIGTERM is noted as it is
    raised (:func:`first_only`), and any exception leaving the block after it, whatever its
    type, becomes that interrupt: the command ends with 130 or 143, not with a refusal.
    """
    with first_only():
        try:
            yield
        except Exception:
            number = stopping()
            if number is not None:
                raise interrupt_for(number) from None
            raise
