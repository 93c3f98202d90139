"""Files written whole or not at all, and output folders checked before a run.

Every result, metrics or figure file is first written under a temporary name in its own
folder, flushed to disk, then renamed over the final name: an interrupt or a crash while
saving leaves the earlier file (or none), never a truncated one.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path

#: Files a run leaves in its output folder (figures aside): an existing folder holding any of
#: them holds earlier results.
RESULT_FILES = ("results.npz", "results.mat", "results.csv", "metrics.json")


_UMASK = os.umask(0)
os.umask(_UMASK)


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; on success it is renamed to ``path``.

    The temporary file keeps the suffix of ``path`` (writers such as ``numpy.savez`` and
    ``matplotlib`` choose their format by it). On any exception, KeyboardInterrupt included,
    it is removed and ``path`` is left as it was.
    """
    path = Path(path)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".part{path.suffix}",
                                         dir=path.parent)
    os.close(handle)
    temporary = Path(temporary)
    try:
        yield temporary
        with open(temporary, "rb+") as written:
            os.fsync(written.fileno())
        os.chmod(temporary, 0o666 & ~_UMASK)  # mkstemp makes it private; a result file is not
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically."""
    with atomic_path(path) as temporary:
        temporary.write_text(text)
    return Path(path)


def write_json(path, data) -> Path:
    """Write ``data`` as indented JSON to ``path`` atomically (numbers of any NumPy type)."""
    return write_text(path, json.dumps(data, indent=2, default=_plain) + "\n")


def save_figure(figure, path, **options) -> Path:
    """``figure.savefig(path)``, atomically."""
    path = Path(path)
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format=path.suffix.lstrip(".") or None, **options)
    return path


def _plain(value):
    try:
        return value.item()  # NumPy scalars
    except AttributeError:
        return float(value)


def prepare_out_dir(out, overwrite: bool = False) -> Path:
    """Check that ``out`` can hold a run's results before the run starts, and create it.

    Refuses an existing file, a folder that cannot be written, and a folder that already
    holds results unless ``overwrite`` (then the earlier result files are removed, so that
    none is left stale beside the new ones).
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
        for name in {*earlier, *_listed_files(out)}:
            (out / name).unlink(missing_ok=True)
    return out


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
    return [name for name in listed if isinstance(name, str) and Path(name).name == name]
