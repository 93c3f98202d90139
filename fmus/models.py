"""The plant's models: one line each in :data:`MODELS`, a folder each under ``fmus/`` (its
``model.c`` and ``variables.py``), read by the build, the orchestrator and the twins."""

import importlib
from pathlib import Path

MODELS = ("Quadrotor", "MotorMagnetics", "IMU", "InfraredSensor")


def model_variables(model: str):
    """The variable table module of one of :data:`MODELS` (``fmus/<model>/variables.py``: its
    ``TABLE``, and its ``ALIASES`` and ``SWITCHED`` if it declares them).

    Raises
    ------
    KeyError
        ``model`` is not one of :data:`MODELS`.
    """
    if model not in MODELS:
        raise KeyError(f"unknown model {model!r}; models: {', '.join(MODELS)}")
    return importlib.import_module(f"quadcosim.fmus.{model}.variables")


def fmu_sources(name: str) -> list[Path]:
    """The files an FMU is built from: its equations and variable table, the shared shell and
    headers, and the modules that generate its description and constants.

    Parameters
    ----------
    name : str
        Model name (one of :data:`MODELS`).

    Returns
    -------
    list of pathlib.Path
        Existing files only.
    """
    here = Path(__file__).resolve().parent
    shared = [here / f"{module}.py" for module in ("build", "variables", "airframe", "vehicle")]
    own = [here / name / "model.c", here / name / "variables.py"]
    return [path for path in [*sorted((here / "c").glob("*")), *shared, *own] if path.is_file()]
