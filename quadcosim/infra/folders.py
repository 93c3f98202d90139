"""Where compiled artefacts go, and the C compiler that makes them: one folder check naming the
environment setting that chose a folder, and ``$CC`` split as a shell splits it."""

from __future__ import annotations

import functools
import os
from pathlib import Path

from quadcosim.infra.errors import RunError


class BuildFolderRefused(RunError, ValueError):
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


def _checkout() -> Path | None:
    """The source checkout this package is imported from (the folder holding quadcosim's
    ``pyproject.toml`` beside the packages), or None for an installed package."""
    root = Path(__file__).resolve().parents[2]
    project = root / "pyproject.toml"
    if project.is_file() and 'name = "quadcosim"' in project.read_text():
        return root
    return None


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("quadcosim")
    except PackageNotFoundError:
        return "unversioned"


def build_root() -> Path:
    """Where compiled artefacts (FMUs, the master's C runner, benchmark references) live.

    Returns
    -------
    pathlib.Path
        ``$QUADCOSIM_BUILD_DIR`` if set; else ``build/`` in the source checkout the package is
        imported from; else, for an installed package, the per-user cache
        ``$XDG_CACHE_HOME/quadcosim/<version>`` (``~/.cache/quadcosim/<version>``).
    """
    return _build_root(os.environ.get("QUADCOSIM_BUILD_DIR"), os.environ.get("XDG_CACHE_HOME"))


@functools.lru_cache(maxsize=8)  # resolved once per setting: runs look FMUs up often
def _build_root(env: str | None, cache: str | None) -> Path:
    if env:
        return Path(env)
    checkout = _checkout()
    if checkout is not None:
        return checkout / "build"
    return Path(cache or Path.home() / ".cache") / "quadcosim" / _version()
