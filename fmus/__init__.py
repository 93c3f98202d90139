"""The plant as FMI 2.0 Co-Simulation FMUs written in C, with their Modelica twins.

- :mod:`fmus.vehicle`: the physical constants of the default vehicle, with units;
- :mod:`fmus.airframe`: motor numbering and spin directions;
- ``fmus/<Model>/variables.py``: each model's variable table; ``fmus/<Model>/model.c``: its
  equations; ``fmus/c/``: the FMI shell they share;
- ``fmus/QuadCoSim/``: the Modelica twins;
- :mod:`fmus.build`: builds ``build/fmus/<Model>.fmu`` (``quadcosim build``).
"""

from __future__ import annotations

import os
from pathlib import Path

MODELS = ("Quadrotor", "MotorMagnetics", "IMU", "InfraredSensor")


_BUILD = Path(__file__).resolve().parent.parent / "build" / "fmus"  # resolved once: runs look FMUs up often


class FMUNotFoundError(FileNotFoundError):
    """A built FMU is missing."""


def default_fmu_dir() -> Path:
    """Where built FMUs live.

    Returns
    -------
    pathlib.Path
        ``$QUADCOSIM_FMU_DIR`` if set, else ``build/fmus`` beside the package.
    """
    env = os.environ.get("QUADCOSIM_FMU_DIR")
    return Path(env) if env else _BUILD


def fmu_path(name: str) -> Path:
    """Path of the built FMU called ``name``.

    Parameters
    ----------
    name : str
        Model name (one of :data:`MODELS`).

    Returns
    -------
    pathlib.Path
        ``<default_fmu_dir()>/<name>.fmu``.

    Raises
    ------
    FMUNotFoundError
        The FMU is not built; the message says how to build it.
    """
    path = default_fmu_dir() / f"{name}.fmu"
    if not path.is_file():
        known = ", ".join(MODELS)
        hint = "" if name in MODELS else f" ({name!r} is not one of the plant models: {known})"
        raise FMUNotFoundError(
            f"FMU {name!r} not found at {path}{hint}. Build the FMUs with `quadcosim build` "
            "(or `make fmus`)."
        )
    return path
