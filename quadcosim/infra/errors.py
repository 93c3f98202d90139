"""The root of the package's errors, and its two branches.

Every error the package raises on purpose derives from :class:`QuadcosimError` through one of:

- :class:`UsageError`: what was asked cannot be done as asked (an option, a file, an FMU, a log
  refused); nothing ran, and the message names the problem and the fix. The command line ends
  with exit code 2.
- :class:`RunError`: a run or a computation that started did not finish (a simulation that
  diverged, an FMU that failed, a fit that found nothing); what was recorded is kept. The
  command line ends with exit code 1.

Each class keeps the built-in exception it has always been as a second base (``ValueError``,
``RuntimeError``, ``OSError``), so code that caught that still does. The exit codes are mapped
once, by :func:`exit_code_of`; :func:`report` prints an error as a command ends with it, and
:func:`refusals` raises the built-in errors a command's work may end with as the package's.
"""

from __future__ import annotations

import contextlib
import sys


class QuadcosimError(Exception):
    """The root of the errors the package raises on purpose."""

    #: The command line's exit code for an error of this class.
    exit_code = 1


class UsageError(QuadcosimError):
    """A request refused before anything ran: the message names the problem and the fix."""

    exit_code = 2


class RunError(QuadcosimError):
    """A run or computation that started and did not finish; what it recorded is kept."""

    exit_code = 1


def exit_code_of(error: BaseException) -> int | None:
    """The command line's exit code for ``error``: 2 for a :class:`UsageError`, 1 for a
    :class:`RunError`, None for an error that is not the package's (a fault: its traceback is
    shown).

    Parameters
    ----------
    error : BaseException
        The error that ended a command.

    Returns
    -------
    int or None
        The exit code, or None.
    """
    return error.exit_code if isinstance(error, QuadcosimError) else None


@contextlib.contextmanager
def refusals(usage: tuple = (KeyError, ValueError), failures: tuple = (OSError,)):
    """Raise the built-in errors a verb's work may end with as the package's: ``usage`` ones (a
    name, a value or a file refused) as :class:`UsageError`, ``failures`` (a disk that filled, a
    folder removed under the run) as :class:`RunError`, each with its message and the original as
    its cause. The package's own errors pass as they are.

    Parameters
    ----------
    usage : tuple of type
        The built-in exceptions that mean a refused request.
    failures : tuple of type
        The built-in exceptions that mean a failed run.
    """
    try:
        yield
    except QuadcosimError:
        raise
    except usage as error:
        raise UsageError(said(error)) from error
    except failures as error:
        raise RunError(said(error)) from error


def said(error: BaseException) -> str:
    """The message of an error: its text (a KeyError's own, without the quotes its str adds)."""
    if isinstance(error, KeyError) and error.args and isinstance(error.args[0], str):
        return error.args[0]
    return str(error)


def report(error: QuadcosimError, prog: str) -> int:
    """Print ``error`` as the command ``prog`` ended (its message, ``failed:`` before a run's, and
    its notes: what was kept, where), and return its exit code. The one place the command line
    turns an error into an exit code.

    Parameters
    ----------
    error : QuadcosimError
        The error that ended the verb.
    prog : str
        The command, as its messages start (``quadcosim run tp``).

    Returns
    -------
    int
        The exit code: 2 for a refusal, 1 for a failure, 128 + the signal for an interrupted run.
    """
    code = exit_code_of(error)
    failed = "failed: " if code == 1 else ""
    print(f"{prog}: {failed}{said(error)}", file=sys.stderr)
    for note in getattr(error, "__notes__", ()):
        print(note, file=sys.stderr)
    return code
