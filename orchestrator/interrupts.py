"""Interrupts that end a run cleanly.

Ctrl-C raises ``KeyboardInterrupt``; :func:`terminate_as_interrupt` makes SIGTERM raise
:class:`Terminated`, a ``KeyboardInterrupt`` too. The master catches both between two steps,
keeps what was recorded and frees the FMUs, so that a run stopped either way leaves its
partial results and no extracted FMU behind.
"""

from __future__ import annotations

import contextlib
import signal


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
