"""The plant's models: one line each in :data:`MODELS`, a folder each under ``fmus/`` (its
``model.c`` and ``variables.py``), read by the build, the orchestrator and the twins."""

import importlib

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
    return importlib.import_module(f"fmus.{model}.variables")
