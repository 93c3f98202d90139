"""The one check of every file the project reads: :func:`regular_file`.

A FIFO would block its reader until something writes into it, a device such as ``/dev/zero``
never ends (a reader fills the memory, and ignores SIGTERM while it does), a folder cannot be
read: recordings, results, calibration, parameter and profile files, logs and a user's module
are each checked before they are opened, and refused with a message naming the path, what it is
and the fix. :func:`read_small_text` adds a size limit for the small JSON files of a run.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

#: What :func:`regular_file` calls each kind of path that is not a regular file.
_NOT_REGULAR = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def regular_file(path, what: str, fix: str, error: type[Exception] = ValueError, label=None) -> os.stat_result:
    """Check that ``path`` is a regular file before it is read: the one check of every file the
    project reads (recordings, results, calibration, parameter and profile files, logs, a user's
    module).

    A symbolic link is followed. A FIFO would block the reader until something writes into it,
    a device such as ``/dev/zero`` never ends (a reader would fill the memory), a folder cannot
    be read: each is refused before it is opened.

    Parameters
    ----------
    path : str or pathlib.Path
        The file as the user gave it.
    what : str
        What the file should be, for the message (``"a calibration file"``).
    fix : str
        What to give instead, for the message.
    error : type
        The exception raised (a subclass of ``Exception`` taking one message).
    label : str, optional
        How the message names the path (default: the path itself, ``flight=FILE`` for a
        scenario's option).

    Returns
    -------
    os.stat_result
        The file's status (its ``st_size``, for the caller's own limit on its size).

    Raises
    ------
    error
        The path does not exist, cannot be reached, or is not a regular file; the message names
        the path, what it is and ``fix``.
    """
    path = Path(path)
    shown = label or str(path)
    if path.is_symlink():
        shown += f" (a link to {os.path.realpath(path)})"
    try:
        status = os.stat(path)
    except FileNotFoundError:
        raise error(f"{shown}: no such file; {fix}") from None
    except OSError as problem:  # a link that loops, a folder that cannot be searched
        raise error(f"{shown}: cannot read {what} ({problem.strerror}); {fix}") from None
    if not stat.S_ISREG(status.st_mode):
        kind = next((name for test, name in _NOT_REGULAR if test(status.st_mode)), "a special file")
        raise error(f"{shown}: {kind}, not a regular file; {fix}")
    return status


def read_small_text(path, what: str, fix: str, limit: int = 16_000_000, error: type[Exception] = ValueError) -> str:
    """The UTF-8 text of the small file at ``path`` (a ``metrics.json``, a ``meta.json``), read
    after :func:`regular_file` and a check of its size.

    Parameters
    ----------
    path : str or pathlib.Path
        The file.
    what : str
        What the file is, for the message (``"a run's metrics"``).
    fix : str
        What to do instead, for the message.
    limit : int
        Largest size read (bytes).
    error : type
        The exception raised.

    Raises
    ------
    error
        Not a regular file, larger than ``limit``, not readable or not UTF-8; the message names
        the file, the problem and ``fix``.
    """
    size = regular_file(path, what, fix, error).st_size
    if size > limit:
        raise error(f"{path}: {size / 1e6:.0f} MB, larger than {what} can be ({limit / 1e6:.0f} MB at most); {fix}")
    try:
        return Path(path).read_text(encoding="utf-8")
    except OSError as problem:
        raise error(f"{path}: cannot read {what} ({problem.strerror}); {fix}") from None
    except UnicodeDecodeError as problem:
        raise error(f"{path}: {what} is not UTF-8 text (byte {problem.start}); {fix}") from None
