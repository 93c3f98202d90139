"""How a command ends: the one place an error or an interrupt becomes an exit code.

A command's work raises; :class:`Command` runs it, and turns a
:class:`~quadcosim.infra.errors.QuadcosimError` into its message and exit code (usage 2, run 1,
an interrupted run 128 + its signal, :func:`~quadcosim.infra.errors.report`) and an interrupt
into its own code (130 for Ctrl-C, 143 for SIGTERM). An error that is not the package's is a
fault: its traceback is shown. :func:`program` is a process's whole life around it: the
``quadcosim`` command line (:func:`quadcosim.cli.entry`) and a module's ``python -m`` double
that calls the same code as its verb.
"""

from __future__ import annotations

import os
import signal
import sys
import warnings

from quadcosim.infra.errors import QuadcosimError, report


class Command:
    """A command's name as its messages start (``quadcosim run tp``), known once its arguments are
    read, and the running of its work.

    Parameters
    ----------
    prog : str
        The command's name until its work names it better.
    """

    def __init__(self, prog: str):
        self.prog = prog

    def run(self, work, *args) -> int:
        """``work(*args)``'s exit code (0 when it returns None), or the code of what it raised.

        SIGTERM ends it as Ctrl-C does (cleanly); warnings are printed on one line each, above a
        progress bar; a file name that is not UTF-8 is printed escaped, never a traceback.

        Parameters
        ----------
        work : callable
            The command's work; it may set :attr:`prog`.
        *args
            Its arguments.

        Returns
        -------
        int
            The exit code.
        """
        from quadcosim.infra.interrupts import exit_code, terminate_as_interrupt

        for stream in (sys.stdout, sys.stderr):
            if hasattr(stream, "reconfigure"):
                stream.reconfigure(errors="backslashreplace")
        try:
            with terminate_as_interrupt(), warnings.catch_warnings():
                warnings.simplefilter("default")
                warnings.showwarning = _show_warning
                return work(*args) or 0
        except QuadcosimError as error:
            return report(error, self.prog)
        except KeyboardInterrupt as interrupt:  # before or after a run: nothing half-written is left
            print(f"{self.prog}: interrupted", file=sys.stderr)
            return exit_code(interrupt)


def _show_warning(message, category, filename, lineno, file=None, line=None):
    from quadcosim.infra.progress import say

    say(f"quadcosim: warning: {message}", sys.stderr)  # above a progress bar, never inside it


def program(main, *args) -> None:
    """A process that runs ``main(*args)`` and exits with its code
    (:func:`quadcosim.infra.interrupts.leave`): a signal after the work is done ends it at once
    with the work's code, a reader of its output gone (``| head``) with 141, never a traceback.

    Parameters
    ----------
    main : callable
        Returns the exit code (:meth:`Command.run`'s).
    *args
        Its arguments.
    """
    # Before numpy loads: numpy and scipy each bring an OpenBLAS that starts a thread per core and
    # spins it at load, CPU a command spends for nothing on its small matrices. A user's setting
    # wins; a program that imports this module is left as it is.
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    from quadcosim.infra.interrupts import exit_code, leave

    # SIGTERM's handler outside main's own: main restores it when it returns, and a signal then
    # (the command's work done) ends the process at once with 143, never by SIGTERM's default
    signal.signal(signal.SIGTERM, _ended_while_leaving)
    global _leaving_code
    try:
        code = _leaving_code = main(*args)
        signal.signal(signal.SIGINT, _ended_while_leaving)
        sys.stdout.flush()  # here, not at exit: a reader gone (| head) is then seen below
    except BrokenPipeError:  # the reader of our output left (quadcosim list | head -1): no traceback
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # nothing more to flush at exit
        code = 128 + signal.SIGPIPE  # as a program that the pipe's signal ended
    except KeyboardInterrupt as interrupt:  # Ctrl-C as main returned: its work is done or was refused
        code = exit_code(interrupt)
    _leaving_code = code
    signal.signal(signal.SIGINT, _ended_while_leaving)
    leave(code, at_once=True)


#: The command's exit code once its work returned (None before).
_leaving_code = None


def _ended_while_leaving(number, frame):
    """A signal after the command finished, while the process exits: leave at once with the
    command's own code (its work is done; 128 + the signal if main had not yet returned), rather
    than die by it (SIGTERM's default) or print a KeyboardInterrupt traceback from an exit handler
    (SIGINT's)."""
    sys.stderr.flush()
    os._exit(_leaving_code if _leaving_code is not None else 128 + number)
