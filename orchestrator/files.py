"""The one save path of a run: files written whole or not at all, disks that fill, output folders.

Every result, metrics, figure or calibration file is first written under a temporary name in
its own folder, flushed to disk (``fsync``), then renamed over the final name: an interrupt, a
crash or a full disk while saving leaves the earlier file (or none), never a truncated one.

- :func:`atomic_path` is that writer; :func:`write_text`, :func:`write_json` and
  :func:`save_figure` use it. A full disk raises :class:`DiskFull`, naming the folder, the
  file, the bytes it needed and the bytes free; the partial file is removed.
- :func:`tracking` lists the files written into a folder while it is active, so that a run's
  ``metrics.json`` names exactly the files it wrote (figures included).
- :func:`prepare_out_dir` checks an output folder before a run and, with ``overwrite``,
  removes every file an earlier run left there.
"""

from __future__ import annotations

import contextlib
import contextvars
import errno
import json
import math
import os
import shutil
import tempfile
from pathlib import Path

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


class DiskFull(OSError):
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


def megabytes(count: int | None) -> str:
    """``count`` bytes as text: ``"12.3 MB"`` (``"0.004 MB"`` for a small file)."""
    return "an unknown size" if count is None else f"{count / 1e6:.3g} MB"


def free_bytes(folder) -> int | None:
    """Bytes free to an unprivileged writer in ``folder`` (None where that is not known)."""
    try:
        return shutil.disk_usage(folder).free
    except OSError:
        return None


@contextlib.contextmanager
def atomic_path(path, size: int | None = None):
    """Yield a temporary path beside ``path``; on success it is renamed to ``path``.

    The temporary file keeps the suffix of ``path`` (writers such as ``numpy.savez`` and
    ``matplotlib`` choose their format by it). It is flushed to disk before the rename. On any
    exception, KeyboardInterrupt included, it is removed and ``path`` is left as it was; a
    full disk is raised as :class:`DiskFull`.

    Parameters
    ----------
    path : str or pathlib.Path
        The final file.
    size : int, optional
        Bytes the file is expected to take, named in the message of a full disk.
    """
    from orchestrator.interrupts import held

    path = Path(path)
    temporary = None
    try:
        # a signal between the file's creation and its name being known would leave it behind:
        # held there, it is raised once the name is known, and the file is removed below
        with held():
            try:
                handle, name = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".part{path.suffix}",
                                                dir=path.parent)
            except OSError as error:
                raise _no_room(error, path, 0, size) from None
            temporary = Path(name)
            os.close(handle)
        yield temporary
        with open(temporary, "rb+") as written:
            os.fsync(written.fileno())
        os.chmod(temporary, 0o666 & ~_UMASK)  # mkstemp makes it private; a result file is not
        os.replace(temporary, path)
    except BaseException as error:
        if temporary is None:
            raise
        reached = temporary.stat().st_size if temporary.exists() else 0
        temporary.unlink(missing_ok=True)
        if isinstance(error, OSError) and not isinstance(error, DiskFull):
            raise _no_room(error, path, reached, size) from None
        raise
    _note_written(path)


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


def save_figure(figure, path, **options) -> Path:
    """``figure.savefig(path)``, atomically."""
    path = Path(path)
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format=path.suffix.lstrip(".") or None, **options)
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


def prepare_out_dir(out, overwrite: bool = False) -> Path:
    """Check that ``out`` can hold a run's results before the run starts, and create it.

    Refuses an existing file, a folder that cannot be written, and a folder that already
    holds results unless ``overwrite``: then every file an earlier run left is removed (its
    result files, those its ``metrics.json`` lists, its figures and any temporary file of a
    save cut short), so that none is left stale beside the new ones.
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
    """The result files of an earlier run in folder ``out`` (empty if none, or no folder)."""
    out = Path(out)
    return [name for name in RESULT_FILES if (out / name).exists()] if out.is_dir() else []


def free_folder(base) -> Path:
    """``base`` if it holds no results, else the first of ``base-2``, ``base-3``, ... that
    holds none: a default output folder never replaces earlier results."""
    base = Path(base)
    candidate, number = base, 1
    while holds_results(candidate) or (candidate.exists() and not candidate.is_dir()):
        number += 1
        candidate = base.with_name(f"{base.name}-{number}")
    return candidate


def _listed_files(out: Path) -> list[str]:
    """The files an earlier run listed in its metrics.json (its figures among them)."""
    try:
        listed = json.loads((out / "metrics.json").read_text()).get("files", [])
    except (OSError, ValueError, AttributeError):
        return []
    return [name for name in listed
            if isinstance(name, str) and Path(name).name == name and name not in ("", ".", "..")]
