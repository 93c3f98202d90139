"""The plant as FMI 2.0 and 3.0 Co-Simulation FMUs written in C, with their Modelica twins.

- :mod:`quadcosim.fmus.vehicle`: the physical constants of the default vehicle, with units;
- :mod:`quadcosim.fmus.airframe`: motor numbering and spin directions;
- :mod:`quadcosim.fmus.models`: the registered models (:data:`MODELS`, the entry-point group
  ``quadcosim.sensors``), each a folder ``fmus/<Model>/``: its equations ``model.c``, its variable
  table ``variables.py``, its Modelica twin ``<Model>.mo`` and the data its checks use;
  ``fmus/c/``: the FMI shell they share;
- :mod:`quadcosim.fmus.twins`: the twins gathered into the Modelica package ``QuadCoSim``
  (``fmus/QuadCoSim/package.mo`` and each model's class), simulated against the FMUs;
- :mod:`quadcosim.fmus.build`: builds ``<build root>/fmus/<Model>.fmu`` (FMI 2.0, what a run loads) and
  ``<build root>/fmus/fmi3/<Model>.fmu`` (FMI 3.0), each for Linux and, with mingw-w64, Windows
  (``quadcosim build``, or on first use).

The build root (:func:`build_root`) is ``build/`` in a source checkout and a per-user cache
folder for an installed package, so that an installation never writes into ``site-packages``.
"""

from __future__ import annotations

import os
from pathlib import Path

from quadcosim.fmus import models as _models
from quadcosim.fmus.models import fmu_sources, model_variables  # noqa: F401  (the package's names)

from quadcosim.infra.errors import UsageError
from quadcosim.infra.folders import (  # noqa: F401  (the package's names)
    BuildFolderRefused,
    build_root,
    compiler_command,
    make_folder,
)


def __getattr__(name: str):
    if name == "MODELS":  # the registered models' names, read at each look-up (quadcosim.fmus.models)
        return _models.MODELS
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class FMUNotFoundError(UsageError, FileNotFoundError):
    """A built FMU is missing."""


def default_fmu_dir() -> Path:
    """Where built FMUs live.

    Returns
    -------
    pathlib.Path
        ``$QUADCOSIM_FMU_DIR`` if set, else ``fmus/`` under :func:`build_root`.
    """
    env = os.environ.get("QUADCOSIM_FMU_DIR")
    return Path(env) if env else build_root() / "fmus"


_checked: set[Path] = set()  # FMUs found up to date by this process: checked once, not at every look-up


def stale(path: Path, name: str) -> bool:
    """Whether the FMU file ``path`` of model ``name`` is missing or older than one of its
    sources (:func:`fmu_sources`): to be built."""
    if not path.is_file():
        return True
    built = path.stat().st_mtime
    return any(source.stat().st_mtime > built for source in fmu_sources(name))


def _build_on_first_use(name: str, path: Path, fmi_version: int) -> None:
    """Build FMU ``name`` into its default folder, one process at a time (a lock file), said on
    standard error: the first run after an installation or an edit of its sources compiles it."""
    import fcntl
    import sys

    from quadcosim.fmus.build import build_fmu

    make_folder(path.parent, "the FMUs")
    with open(path.parent / ".build.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if stale(path, name):  # another process may have built it meanwhile
            print(f"quadcosim: building the FMU {name} into {path.parent} (its sources are newer, or it is "
                  "not built yet)", file=sys.stderr, flush=True)
            build_fmu(name, default_fmu_dir(), fmi_version=fmi_version)


def fmu_path(name: str, fmi_version: int = 2) -> Path:
    """Path of the built FMU called ``name``.

    Parameters
    ----------
    name : str
        Model name (one of :data:`MODELS`).
    fmi_version : int
        2 (what a run loads) or 3.

    Returns
    -------
    pathlib.Path
        ``<default_fmu_dir()>/<name>.fmu``, or ``<default_fmu_dir()>/fmi3/<name>.fmu`` for FMI 3.0.
        In the default folder a plant model is built on
        first use, and rebuilt when one of its sources (:func:`fmu_sources`) is newer; in a
        folder named by ``$QUADCOSIM_FMU_DIR`` it is used as found.

    Raises
    ------
    FMUNotFoundError
        The FMU is not built (and is not a plant model, or ``$QUADCOSIM_FMU_DIR`` names the
        folder); the message says how to build it.
    """
    if fmi_version not in (2, 3):
        raise ValueError(f"FMI version {fmi_version!r}: the plant's FMUs are built in FMI 2 and 3")
    path = default_fmu_dir() / ("" if fmi_version == 2 else "fmi3") / f"{name}.fmu"
    models = _models.MODELS
    if name in models and "QUADCOSIM_FMU_DIR" not in os.environ and path not in _checked:
        if stale(path, name):
            _build_on_first_use(name, path, fmi_version)
        _checked.add(path)
    if not path.is_file():
        known = ", ".join(models)
        hint = "" if name in models else f" ({name!r} is not one of the plant models: {known})"
        raise FMUNotFoundError(
            f"FMU {name!r} not found at {path}{hint}. Build the FMUs with `quadcosim build` "
            "(or `make fmus`)."
        )
    return path
