"""Where compiled artefacts go, and the C compiler that makes them: one folder check naming the
environment setting that chose a folder, and ``$CC`` split as a shell splits it."""

from __future__ import annotations

import os
from pathlib import Path


class BuildFolderRefused(ValueError):
    """A folder compiled artefacts go to cannot be made or written; the message names the
    environment setting that chose it, when one did."""


#: The settings that choose where compiled artefacts go, the most specific first.
FOLDER_SETTINGS = ("QUADCOSIM_RUNNER_DIR", "QUADCOSIM_FMU_DIR", "QUADCOSIM_BUILD_DIR", "XDG_CACHE_HOME")


def compiler_command(given: str | None = None) -> list[str]:
    """The C compiler as a command line: ``given``, else ``$CC``, else ``cc``, split as a shell
    splits it (``CC="gcc -m64"`` is the compiler ``gcc`` with the flag ``-m64``)."""
    import shlex

    command = shlex.split(given or os.environ.get("CC") or "cc")
    return command or ["cc"]


def make_folder(folder, what: str) -> Path:
    """Make ``folder`` (and its parents) for ``what`` (``"the FMUs"``), or refuse it naming the
    setting that chose it (``$QUADCOSIM_BUILD_DIR``...) and the fix.

    Raises
    ------
    BuildFolderRefused
        The folder cannot be made, or is not writable.
    """
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        problem = None if os.access(folder, os.W_OK | os.X_OK) else "not writable"
    except OSError as error:
        problem = error.strerror
    if problem is None:
        return folder
    chosen = next((v for v in FOLDER_SETTINGS if os.environ.get(v) and
                   (folder == Path(os.environ[v]) or Path(os.environ[v]) in folder.parents)), None)
    fix = (f"it comes from ${chosen}={os.environ[chosen]}: set ${chosen} to a writable folder, or unset it"
           if chosen else "make it writable, or set $QUADCOSIM_BUILD_DIR to a writable folder")
    raise BuildFolderRefused(f"{folder}/: cannot write {what} there ({problem}); {fix}")
