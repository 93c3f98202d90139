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
once, by :func:`exit_code_of`.
"""

from __future__ import annotations


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
