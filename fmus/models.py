"""The plant's models, the sensor FMUs: each one folder, registered by one line.

A sensor FMU ``<Model>`` is a package folder registered in the entry-point group
``quadcosim.sensors`` (:mod:`quadcosim.infra.members`), by this package or a third party's::

    [project.entry-points."quadcosim.sensors"]
    IMU = "quadcosim.fmus.IMU"

The folder holds everything of the model, and nothing else names it:

- ``model.c``: its equations (the four functions ``fmus/c/shell.h`` declares);
- ``variables.py``: its variable table ``TABLE`` (named ``<Model>``), and its ``ALIASES`` and
  ``SWITCHED`` if it declares them;
- ``<Model>.mo``: its Modelica twin, a class of the package ``QuadCoSim`` (optional);
- ``__init__.py``: what the checks drive it with, the names of :data:`CHECKS`.

The build, the orchestrator's parameter look-up, the twins, the tests and the documentation's
tables read :data:`MODELS` (the registered names, this package's first) and each member's folder.
"""

from __future__ import annotations

import functools
import importlib.util
from dataclasses import dataclass, field
from pathlib import Path

from quadcosim.infra.errors import UsageError
from quadcosim.infra.members import GROUPS, load, registered

GROUP = GROUPS["sensors"]
#: What a member's ``__init__.py`` may declare for the checks, with its default when it does not.
CHECKS = {
    # inputs held (by name, in the table's units) while its variable table is checked
    "HELD_INPUTS": {},
    # parameters of those runs
    "HELD_PARAMETERS": {},
    # (parameters of a fresh run, of an earlier run) for the reset check, off their defaults
    "RESET_PARAMETERS": ({}, {}),
    # [(parameter, value, words of the refusal)]: values its model_initialize refuses
    "REFUSED_PARAMETERS": [],
    # label -> TwinCase: the twin and the FMU agree under these inputs (needs <Model>.mo)
    "TWIN_CASES": {},
    # parameters the twin does not model (the noise: a counter-based generator has no equation)
    "TWIN_OMITS": ("seed", "sub_step"),
    # [(input expressions of time, parameters, outputs)]: manoeuvres its sub-step must converge on
    "SUBSTEP_CASES": [],
    # a vector the build must keep whole (its first rows), for the check that splits one
    "SPLIT_VECTOR": None,
    # the row of the documentation's table of FMUs: {"states": ..., "integrator": ...}
    "SUMMARY": {"states": "", "integrator": ""},
}


class SensorError(UsageError, ValueError):
    """A registered sensor FMU is not one: its folder lacks a file, or its table has another name."""


@dataclass(frozen=True)
class TwinCase:
    """Inputs under which a model's Modelica twin and its FMU must agree (noise off).

    Parameters
    ----------
    inputs : dict of str to str
        Input name to an expression of ``time`` (s) valid in Modelica and Python.
    parameters : dict
        Parameter values by name, SI (bool for Boolean parameters).
    step : float
        Communication step (s) of the FMU; it holds each input over a step.
    every : int
        Compare at every N-th communication point.
    tolerance : float
        Largest difference of an output, over its peak (1).
    """

    inputs: dict
    parameters: dict = field(default_factory=dict)
    step: float = 1e-3
    every: int = 1
    tolerance: float = 1e-6


@dataclass(frozen=True)
class Sensor:
    """One registered sensor FMU.

    Parameters
    ----------
    name : str
        Its model name: the FMU's, its table's and its twin's.
    module : str
        The package of its folder (the entry point's value).
    distribution : str
        The installed distribution registering it.
    """

    name: str
    module: str
    distribution: str

    @functools.cached_property
    def folder(self) -> Path:
        """The member's folder (found without importing it)."""
        spec = importlib.util.find_spec(self.module)
        if spec is None or not spec.submodule_search_locations:
            raise SensorError(f"sensor {self.name!r}: {self.module!r} (registered by {self.distribution}) is not an "
                              "importable package; a sensor FMU is a folder with __init__.py, model.c and variables.py")
        folder = Path(list(spec.submodule_search_locations)[0])
        missing = [name for name in ("model.c", "variables.py") if not (folder / name).is_file()]
        if missing:
            raise SensorError(f"sensor {self.name!r}: its folder {folder} has no {' nor '.join(missing)}; a sensor FMU "
                              "is a folder with its model.c and its variables.py (its TABLE)")
        return folder

    @property
    def twin(self) -> Path | None:
        """Its Modelica twin, ``<folder>/<name>.mo``, or None."""
        path = self.folder / f"{self.name}.mo"
        return path if path.is_file() else None

    def variables(self):
        """Its ``variables`` module (``TABLE``, ``ALIASES``, ``SWITCHED``)."""
        module = load(f"{self.module}.variables")
        name = getattr(getattr(module, "TABLE", None), "model", None)
        if name != self.name:
            raise SensorError(f"sensor {self.name!r}: {self.module}.variables' TABLE is named {name!r}; name it "
                              f"{self.name!r}, as its registration (entry point) does")
        return module

    def check(self, name: str):
        """What the member declares for the check ``name`` (one of :data:`CHECKS`), or its default."""
        return getattr(load(self.module), name, CHECKS[name])


@functools.cache
def _sensors(registry: tuple) -> dict[str, Sensor]:
    return {name: Sensor(name, value, owner) for name, (value, owner) in registry}


def sensors() -> dict[str, Sensor]:
    """The registered sensor FMUs by name, this package's first."""
    return _sensors(tuple(registered(GROUP).items()))


def sensor(model: str) -> Sensor:
    """The registered sensor FMU ``model``.

    Raises
    ------
    KeyError
        ``model`` is not registered; the message names those that are.
    """
    found = sensors().get(model)
    if found is None:
        raise KeyError(f"unknown model {model!r}; models: {', '.join(sensors())} (a sensor FMU is registered in "
                       f"the entry-point group {GROUP})")
    return found


def __getattr__(name: str):
    if name == "MODELS":  # read from the registry at each look-up: a package installed later is seen
        return tuple(sensors())
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def model_variables(model: str):
    """The variable table module of a registered model (``<folder>/variables.py``: its ``TABLE``,
    and its ``ALIASES`` and ``SWITCHED`` if it declares them).

    Raises
    ------
    KeyError
        ``model`` is not one of :data:`MODELS`.
    """
    return sensor(model).variables()


def model_folder(model: str) -> Path:
    """The folder of a registered model (its ``model.c``, ``variables.py`` and twin)."""
    return sensor(model).folder


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
    folder = model_folder(name)
    own = [folder / "model.c", folder / "variables.py"]
    return [path for path in [*sorted((here / "c").glob("*")), *shared, *own] if path.is_file()]
