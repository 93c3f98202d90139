"""The one save path of the project: files written whole or not at all, disks that fill, output folders.

Every file the project writes (results, metrics, figures, calibration and parameter files,
recordings, tables) is first written under a temporary name in its own folder, flushed to disk
(``fsync``), then renamed over the final name: an interrupt, a crash or a full disk while
saving leaves the earlier file (or none), never a truncated one.

- :func:`atomic_path` is that writer; :func:`write_text`, :func:`write_json` and
  :func:`save_figure` use it. A full disk raises :class:`DiskFull`, naming the folder, the
  file, the bytes it needed and the bytes free; the partial file is removed.
- What it writes to is checked first (:func:`output_file`): a symbolic link is *followed*
  (the file it points to is replaced, the link is kept, as ``open(path, "w")`` would do); a
  folder, a FIFO, a device or a socket, a read-only file and a folder that does not exist are
  refused with :class:`OutputRefused`, before anything is written.
- Every file the project *reads* is checked by :func:`quadcosim.infra.inputs.regular_file` first.
- :func:`tracking` lists the files written into a folder while active: a run's ``metrics.json`` names them.
- :func:`prepare_out_dir` checks an output folder before a run and, with ``overwrite``,
  removes every file an earlier run left there; :func:`folder_lock` holds it for one process
  (a second one is refused with :class:`FolderBusy`, naming the first).
- :class:`Reserve` keeps room for a folder's ``metrics.json`` on a disk that may fill.
"""

from __future__ import annotations

import contextlib
import contextvars
import errno
import json
import math
import os
import shutil
import stat
import tempfile
import time
from pathlib import Path

from quadcosim.infra.errors import RunError, UsageError

#: Files a run leaves in its output folder (figures aside): an existing folder holding any of
#: them holds earlier results.
RESULT_FILES = ("results.npz", "results.mat", "results.csv", "metrics.json", "results.stream")

#: Suffixes of the figures a run draws; ``--overwrite`` removes them with the results.
FIGURE_SUFFIXES = (".png", ".svg", ".pdf")

# errors of a write that found no room: no space on the device, or over a disk quota
_NO_ROOM = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)

_UMASK = os.umask(0)
os.umask(_UMASK)

_written: contextvars.ContextVar[tuple[Path, list[str]] | None] = contextvars.ContextVar("written", default=None)


class DiskFull(RunError, OSError):
    """A file did not fit on its disk; nothing was left under its final name.

    Parameters
    ----------
    path : pathlib.Path
        The file that was being written.
    needed : int or None
        Bytes the file needs, when known before it is written.
    free : int or None
        Bytes free in its folder after the partial file was removed.
    reached : int
        Bytes written when the disk filled.
    """

    def __init__(self, path: Path, needed: int | None, free: int | None, reached: int = 0):
        self.path, self.needed, self.free, self.reached = Path(path), needed, free, reached
        if needed and needed > reached:
            need = f"about {megabytes(needed)}"
        else:
            need = f"more than the {megabytes(reached)} written when the disk filled"
        room = f"{megabytes(free)} free" if free is not None else "free space unknown"
        self.message = (f"no space left in {self.path.parent}/ to write {self.path.name}: it needs {need} ({room}). "
                        "Free space there or choose another --out folder")
        super().__init__(errno.ENOSPC, self.message)

    def __str__(self):
        return self.message


def printable(text) -> str:
    """``text`` (a file name read from the disk) with the bytes that are not UTF-8 shown as
    U+FFFD: what a figure title or a JSON file can hold (a name is bytes on Linux; Python keeps
    the undecodable ones as lone surrogates, which no text encoder takes)."""
    return str(text).encode("utf-8", "surrogateescape").decode("utf-8", "replace")


def megabytes(count: int | None, against: int | None = None) -> str:
    """``count`` bytes as text: ``"12.3 MB"`` (``"0.004 MB"`` for a small file).

    With ``against``, another count of bytes printed beside it, enough digits are given for the
    two texts to differ when the counts do (``"2.0312 MB"`` beside ``"2.0305 MB"``).
    """
    if count is None:
        return "an unknown size"
    digits = 3
    while against is not None and against != count and digits < 12 and \
            f"{count / 1e6:.{digits}g}" == f"{against / 1e6:.{digits}g}":
        digits += 1
    return f"{count / 1e6:.{digits}g} MB"


def free_bytes(folder) -> int | None:
    """Bytes free to an unprivileged writer in ``folder`` (None where that is not known)."""
    try:
        return shutil.disk_usage(folder).free
    except OSError:
        return None


class OutputRefused(UsageError, ValueError):
    """A path that cannot take a file: a folder, a FIFO or device, a read-only file, or a file in
    a folder that does not exist. Nothing was written; the message names the path and the fix."""


_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def output_file(path) -> Path:
    """The regular file a writer replaces for ``path``, checked before anything is written.

    A symbolic link is followed, to the end of its chain: the file it points to is the one
    written (and created if it does not exist), and the link itself is kept. Everything else
    that is not a regular file is refused.

    Parameters
    ----------
    path : str or pathlib.Path
        The output path as the user gave it.

    Returns
    -------
    pathlib.Path
        ``path``, or the target of the link it is.

    Raises
    ------
    OutputRefused
        ``path`` (or its target) is a folder, a FIFO, a device or a socket, a read-only file,
        a link that loops, or lies in a folder that does not exist.
    """
    path = Path(path)
    target = Path(os.path.realpath(path)) if path.is_symlink() else path
    shown = path if target == path else f"{path} (a link to {target})"
    try:
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        mode = None
    except OSError as error:  # a link that loops, a folder that cannot be searched
        raise OutputRefused(f"{shown}: cannot write there ({error.strerror}); give another file name") from None
    if mode is not None:
        if stat.S_ISDIR(mode):
            raise OutputRefused(f"{shown}: a folder, not a file; give a file name (a folder/name)")
        for test, kind in _KINDS:
            if test(mode):
                raise OutputRefused(f"{shown}: {kind}, not a regular file; quadcosim writes its outputs to files "
                                    "(written whole, then renamed), never into a stream; give a file name")
        if not os.access(target, os.W_OK):
            raise OutputRefused(f"{shown}: the file is read-only; make it writable or give another file name")
    folder = target.parent
    if not folder.is_dir():
        what = "is not a folder" if folder.exists() else "does not exist"
        raise OutputRefused(f"{shown}: the folder {folder}/ {what}; create it or give another path")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputRefused(f"{shown}: the folder {folder}/ is not writable; give another path")
    return target


@contextlib.contextmanager
def atomic_path(path, size: int | None = None):
    """Yield a temporary path beside ``path``; on success it is renamed to ``path``.

    The temporary file keeps the suffix of ``path`` (writers such as ``numpy.savez`` and
    ``matplotlib`` choose their format by it). It is flushed to disk before the rename. On any
    exception, KeyboardInterrupt included, it is removed and ``path`` is left as it was; a
    full disk is raised as :class:`DiskFull`. ``path`` is checked first (:func:`output_file`):
    a symbolic link is followed (its target is replaced, the link kept); a folder, a FIFO, a
    device, a read-only file or a missing folder is refused with :class:`OutputRefused`. A
    file replaced keeps its permissions; a hard link to it keeps the earlier content.

    Parameters
    ----------
    path : str or pathlib.Path
        The final file.
    size : int, optional
        Bytes the file is expected to take, named in the message of a full disk.
    """
    from quadcosim.infra.interrupts import held

    asked = Path(path)
    path = output_file(asked)
    try:
        mode = stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        mode = 0o666 & ~_UMASK  # mkstemp makes it private; a result file is not
    temporary = None
    try:
        # a signal between the file's creation and its name being known would leave it behind:
        # held there, it is raised once the name is known, and the file is removed below
        with held():
            try:
                handle, name = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".part{path.suffix}",
                                                dir=path.parent)
            except OSError as error:
                problem = _no_room(error, path, 0, size)
                if problem is error:  # not a full disk: a folder that takes no file (/proc, a read-only mount)
                    raise OutputRefused(f"{asked}: cannot create a file in {path.parent}/ ({error.strerror}); give "
                                        "another path") from None
                raise problem from None
            temporary = Path(name)
            os.close(handle)
        yield temporary
        with open(temporary, "rb+") as written:
            os.fsync(written.fileno())
        os.chmod(temporary, mode)
        os.replace(temporary, path)
    except BaseException as error:
        if temporary is None:
            raise
        reached = temporary.stat().st_size if temporary.exists() else 0
        temporary.unlink(missing_ok=True)
        if isinstance(error, OSError) and not isinstance(error, DiskFull):
            raise _no_room(error, path, reached, size) from None
        raise
    _sync_folder(path.parent)
    _note_written(asked)


def _sync_folder(folder: Path):
    """Flush the folder's entry of a renamed file, so that a crash after the rename keeps it."""
    try:
        descriptor = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return
    try:
        os.fsync(descriptor)
    except OSError:  # some filesystems do not sync a folder: the rename stands all the same
        pass
    finally:
        os.close(descriptor)


def _no_room(error: OSError, path: Path, reached: int, size: int | None) -> OSError:
    """``error`` as :class:`DiskFull` when it says the disk is full, else unchanged (NumPy's
    ``tofile`` reports a short write without an error number: "N requested and M written")."""
    code = getattr(error, "errno", None)
    short_write = code is None and "requested and" in str(error) and "written" in str(error)
    if code not in _NO_ROOM and not short_write:
        return error
    return DiskFull(path, size, free_bytes(path.parent), reached)


def _note_written(path: Path):
    tracked = _written.get()
    if tracked is not None and path.parent.resolve() == tracked[0] and path.name not in tracked[1]:
        tracked[1].append(path.name)


@contextlib.contextmanager
def tracking(folder):
    """Within the block, list the files written into ``folder`` by this save path.

    Parameters
    ----------
    folder : str or pathlib.Path
        The output folder.

    Yields
    ------
    list of str
        The names written so far, in order, updated as files are written.
    """
    names: list[str] = []
    token = _written.set((Path(folder).resolve(), names))
    try:
        yield names
    finally:
        _written.reset(token)


def note_written(path):
    """Count ``path`` among the files of :func:`tracking` (a folder written by other means)."""
    _note_written(Path(path))


def write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically."""
    with atomic_path(path, size=len(text.encode())) as temporary:
        temporary.write_text(text)
    return Path(path)


def write_json(path, data) -> Path:
    """Write ``data`` as indented JSON to ``path`` atomically.

    NumPy numbers become plain numbers, and a non-finite number becomes ``null`` (JSON has no
    ``Infinity`` nor ``NaN``): the file is valid JSON for any reader.
    """
    return write_text(path, json_text(data))


def json_text(data, indent: int | None = 2) -> str:
    """``data`` as strict JSON text (see :func:`write_json`), newline-terminated when indented."""
    text = json.dumps(finite(data), indent=indent, default=_plain, allow_nan=False)
    return text + "\n" if indent else text


def finite(data):
    """``data`` with every non-finite float (``inf``, ``nan``) replaced by None, recursively."""
    if isinstance(data, float):
        return data if math.isfinite(data) else None
    if isinstance(data, dict):
        return {key: finite(value) for key, value in data.items()}
    if isinstance(data, list | tuple):
        return [finite(value) for value in data]
    if hasattr(data, "item") and getattr(data, "ndim", 1) == 0:  # a NumPy scalar
        return finite(data.item())
    return data


def figure_format(path, figure=None) -> str:
    """The format matplotlib writes ``path`` in, from its suffix (``figure``: the figure to write,
    whose canvas may write more formats than the default one); :class:`OutputRefused` for a
    suffix it does not write (or none), naming those it does."""
    from matplotlib.backend_bases import FigureCanvasBase

    path = Path(path)
    kinds = (figure.canvas if figure is not None else FigureCanvasBase).get_supported_filetypes()
    kind = path.suffix.lstrip(".").lower()
    if kind not in kinds:
        said = f".{kind} is not a figure format matplotlib writes" if kind else "the name has no suffix to choose " \
            "the figure's format"
        raise OutputRefused(f"{path}: {said}; end it with "
                            f"{', '.join('.' + k for k in ('png', 'svg', 'pdf') if k in kinds)} "
                            f"(or {', '.join('.' + k for k in sorted(kinds) if k not in ('png', 'svg', 'pdf'))})")
    return kind


def figure_file(given, name: str, folder) -> Path:
    """The figure file a command writes, checked before anything is drawn or read.

    Parameters
    ----------
    given : str or pathlib.Path or None
        The user's ``--out``: a file, or an existing folder (which takes ``name``).
    name : str
        The figure's default name.
    folder : str or pathlib.Path
        Its default folder, made when ``given`` is None.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    OutputRefused
        A suffix matplotlib does not write (:func:`figure_format`), or a path that cannot take
        a file (:func:`output_file`).
    """
    if given:
        path = Path(given)
        path = path / name if path.is_dir() else path
    else:
        Path(folder).mkdir(parents=True, exist_ok=True)
        path = Path(folder) / name
    figure_format(path)
    output_file(path)
    return path


#: Backends that draw without a window: kept as they are by :func:`headless_backend`.
_WINDOWLESS = ("agg", "pdf", "svg", "ps", "pgf", "cairo", "template")


def headless_backend() -> None:
    """Make matplotlib draw without a window (Agg) unless it already does: a figure written to a
    file must not open one, nor need a display. A notebook's inline backend (and any other
    windowless one) is kept, so that the notebook's own figures still show after a run drew its
    report."""
    import matplotlib

    backend = matplotlib.get_backend().lower()
    if "inline" in backend or backend in _WINDOWLESS or backend.startswith("module://"):
        return
    matplotlib.use("Agg")


def save_figure(figure, path, **options) -> Path:
    """``figure.savefig(path)``, atomically; a suffix matplotlib does not write is refused
    (:func:`figure_format`) before anything is written."""
    path = Path(path)
    kind = figure_format(path, figure)
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format=kind, **options)
    return path


def _plain(value):
    try:
        return finite(value.item())  # NumPy scalars
    except AttributeError:
        pass
    if hasattr(value, "tolist"):
        return finite(value.tolist())
    try:
        return finite(float(value))
    except (TypeError, ValueError):
        return str(value)


#: The lock file of an output folder held by a process (:func:`folder_lock`).
LOCK_NAME = ".quadcosim.lock"


class FolderBusy(UsageError, ValueError):
    """Another process is writing into the output folder; the message names it (pid, command)."""


def _holder(text: str) -> dict:
    try:
        holder = json.loads(text)
        return holder if isinstance(holder, dict) else {}
    except ValueError:
        return {}


def _alive(pid) -> bool:
    try:
        os.kill(int(pid), 0)
    except (OSError, ValueError, TypeError) as error:
        return isinstance(error, PermissionError)  # another user's process: alive
    return True


def busy_message(folder: Path, holder: dict) -> str:
    """The refusal of a folder held by another process.

    Parameters
    ----------
    folder : pathlib.Path
        The output folder.
    holder : dict
        What its lock file says: ``pid``, ``command``, ``since`` (s since the epoch).

    Returns
    -------
    str
        The folder, the holder's pid and command, since when, and the fix.
    """
    pid, command = holder.get("pid", "?"), holder.get("command") or "quadcosim"
    since = holder.get("since")
    started = f", since {time.strftime('%Y-%m-%d %H:%M:%S', time.localtime(since))}" if since else ""
    child = "" if _alive(holder.get("pid")) else " (that process has ended; one it started still holds the folder)"
    return (f"{folder}/ is being written by another process: pid {pid}, `{command}`{started}{child}. Wait for it "
            "to end, or choose another folder (two runs in one folder would mix their files)")


def _try_lock(descriptor: int) -> bool:
    """Take the lock on the open lock file; False when another process holds it."""
    import fcntl

    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    except OSError:  # a filesystem without locks: the pid written in the file decides
        holder = _holder(os.pread(descriptor, 4096, 0).decode(errors="replace"))
        return not holder or holder.get("pid") == os.getpid() or not _alive(holder.get("pid"))
    return True


def held_by(folder) -> dict | None:
    """The process holding ``folder`` (``pid``, ``command``, ``since``), or None when it is free."""
    lock = Path(folder) / LOCK_NAME
    try:
        descriptor = os.open(lock, os.O_RDWR)
    except OSError:
        return None
    try:
        if _try_lock(descriptor):
            return None
        return _holder(os.pread(descriptor, 4096, 0).decode(errors="replace"))
    finally:
        os.close(descriptor)  # closing releases a lock taken just above


@contextlib.contextmanager
def folder_lock(folder, command: str | None = None):
    """Hold the output folder ``folder`` for this process while the block runs.

    The lock is ``folder/.quadcosim.lock``, locked with ``flock`` and holding this process's
    pid and command line. A second process asking for the folder is refused; a lock left by a
    process that died (killed outright) is free, and taken over. The file is removed when the
    block ends.

    Parameters
    ----------
    folder : str or pathlib.Path
        An existing folder.
    command : str, optional
        What this process is doing, named to a process refused (default: its command line).

    Raises
    ------
    FolderBusy
        Another live process holds the folder; the message names its pid and command.
    """
    import sys

    folder = Path(folder)
    lock = folder / LOCK_NAME
    while True:
        try:
            descriptor = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as error:
            raise OutputRefused(f"{folder}/: cannot take the folder ({error.strerror}); choose another "
                                "place") from None
        if not _try_lock(descriptor):
            holder = _holder(os.pread(descriptor, 4096, 0).decode(errors="replace"))
            os.close(descriptor)
            raise FolderBusy(busy_message(folder, holder))
        try:  # the file locked must still be the one named: a holder ending removes it
            same = os.stat(lock).st_ino == os.fstat(descriptor).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(descriptor)
    holder = {"pid": os.getpid(), "command": command or " ".join(["quadcosim", *sys.argv[1:]]),
              "since": time.time()}
    try:
        os.ftruncate(descriptor, 0)
        os.pwrite(descriptor, (json.dumps(holder) + "\n").encode(), 0)
    except OSError:  # a full disk: the lock holds without its note
        pass
    try:
        yield holder
    finally:
        try:
            if os.stat(lock).st_ino == os.fstat(descriptor).st_ino:
                lock.unlink()
        except OSError:
            pass
        os.close(descriptor)


class Reserve:
    """Room kept on the disk of a folder for one small file written last (``metrics.json``).

    A file of ``size`` bytes is written at once; :meth:`release` removes it just before that
    last file is written, so that a disk that filled in between still takes it.

    Parameters
    ----------
    folder : pathlib.Path
        The output folder.
    size : int
        Bytes kept.

    Raises
    ------
    DiskFull
        Not even ``size`` bytes are free: nothing was left.
    """

    #: Name of the file that keeps the room (a temporary name: ``--overwrite`` removes one a
    #: killed process left).
    NAME = ".metrics.reserve.part"

    def __init__(self, folder: Path, size: int = 64 * 1024):
        self.path = Path(folder) / self.NAME
        try:
            with open(self.path, "wb") as file:
                file.write(bytes(size))
                file.flush()
                os.fsync(file.fileno())
        except OSError as error:
            self.path.unlink(missing_ok=True)
            raise _no_room(error, Path(folder) / "metrics.json", 0, size) from None

    @property
    def held(self) -> bool:
        """Whether the room is still kept."""
        return self.path.exists()

    def release(self):
        """Give the room back (idempotent)."""
        self.path.unlink(missing_ok=True)


def prepare_out_dir(out, overwrite: bool = False, lock: contextlib.ExitStack | None = None) -> Path:
    """Check that ``out`` can hold a run's results before the run starts, and create it.

    Refuses an existing file, a folder that cannot be written, a folder another process is
    writing (with ``lock``), and a folder that already holds results unless ``overwrite``:
    then every file an earlier run left is removed (its result files, those its
    ``metrics.json`` lists, its figures and any temporary file of a save cut short), so that
    none is left stale beside the new ones.

    Parameters
    ----------
    out : str or pathlib.Path
        The output folder.
    overwrite : bool
        Replace the results already there.
    lock : contextlib.ExitStack, optional
        Hold the folder (:func:`folder_lock`) until this stack closes; taken before the
        folder's results are checked or removed.

    Raises
    ------
    ValueError
        The folder is refused (:class:`FolderBusy` when another process holds it).
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out}: a file of that name exists; give a folder name")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise ValueError(f"--out {out}: cannot create the folder ({error.strerror}); choose another place") from None
    if not os.access(out, os.W_OK | os.X_OK):
        raise ValueError(f"--out {out}: the folder is not writable; choose another place")
    if lock is not None:
        try:
            lock.enter_context(folder_lock(out))
        except FolderBusy as error:
            raise FolderBusy(f"--out {error}") from None
    earlier = holds_results(out)
    if earlier:
        if not overwrite:
            raise ValueError(f"--out {out} already holds results ({', '.join(earlier)}); give another folder "
                             "or add --overwrite to replace them")
        for name in earlier_files(out):
            _remove(out / name)
    return out


def earlier_files(out: Path) -> list[str]:
    """Every file of an earlier run in ``out``: results, listed files, figures, temporaries."""
    names = {*holds_results(out), *_listed_files(out)}
    for path in out.iterdir():
        if path.suffix in FIGURE_SUFFIXES or (path.name.startswith(".") and ".part" in path.name):
            names.add(path.name)
    return sorted(names)


def _remove(path: Path):
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


def holds_results(out) -> list[str]:
    """The result files of an earlier run in ``out`` (none if no folder, or a refused run's metrics.json alone)."""
    out = Path(out)
    names = [name for name in RESULT_FILES if (out / name).exists()] if out.is_dir() else []
    return [] if names == ["metrics.json"] and _earlier_metrics(out).get("status") == "refused" else names


def first_free(path, taken, file: bool = False) -> Path:
    """``path`` (str or pathlib.Path) unless ``taken(path)`` (a callable of a pathlib.Path), else the
    first of ``NAME-2``, ``NAME-3``, ... that is not taken; a ``file`` keeps its suffix last
    (``STEM-2.SUFFIX``). Returns the pathlib.Path."""
    path = Path(path)
    candidate, number = path, 1
    while taken(candidate):
        number += 1
        candidate = path.with_name(f"{path.stem}-{number}{path.suffix}" if file else f"{path.name}-{number}")
    return candidate


def free_folder(base) -> Path:
    """``base`` if it holds no results, else the first of ``base-2``, ``base-3``, ... that
    holds none and that no other process is writing: a default output folder never replaces
    earlier results."""
    return first_free(base, lambda candidate: holds_results(candidate) or held_by(candidate)
                      or (candidate.exists() and not candidate.is_dir()))


def _earlier_metrics(out: Path) -> dict:
    """The metrics.json an earlier run left in ``out`` (empty if none, or unreadable)."""
    try:
        metrics = json.loads((out / "metrics.json").read_text())
    except (OSError, ValueError):
        return {}
    return metrics if isinstance(metrics, dict) else {}


def _listed_files(out: Path) -> list[str]:
    """The files an earlier run listed in its metrics.json (its figures among them)."""
    return [name for name in _earlier_metrics(out).get("files", [])
            if isinstance(name, str) and Path(name).name == name and name not in ("", ".", "..")]
