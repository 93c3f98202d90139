"""Simulate the Modelica twins and their FMUs under the same input functions of time.

The twins are simulated with the pure-Python Modelica toolchain published on PyPI as
``modelica`` (pinned in pyproject.toml). Two of its limits shape this module:
- it reads one program, not a package directory, and ignores ``within``: the package is
  assembled from ``package.mo`` and each registered model's twin (:mod:`quadcosim.fmus.modelica`);
- it leaves top-level inputs unset: each check wraps the model in a small model that binds
  every input to an expression of ``time``.
Input expressions use only ``time``, numbers, ``+ - * /`` and ``sin``, ``cos``, ``exp``, so
the same text is valid Modelica and valid Python.
"""

from __future__ import annotations

import math
import shutil

import numpy as np
from quadcosim.fmus import fmu_path
from quadcosim.fmus.modelica import package_source

_FUNCTIONS = {"sin": np.sin, "cos": np.cos, "exp": np.exp, "pi": math.pi}


def _modelica_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(float(value))


def simulate_twin(model: str, inputs: dict[str, str], parameters: dict, stop: float,
                  times: np.ndarray, tolerance: float = 1e-10) -> dict[str, np.ndarray]:
    """Simulate ``QuadCoSim.<model>`` with its inputs bound to expressions of time.

    Parameters
    ----------
    model : str
        Class name in the QuadCoSim package (the FMU's name).
    inputs : dict of str to str
        Input name to an expression of ``time`` (s) valid in Modelica and Python.
    parameters : dict
        Parameter bindings by name, in SI units (bool for Boolean parameters).
    stop : float
        End time (s).
    times : ndarray
        Times (s) at which to return the variables.
    tolerance : float
        Relative tolerance of the variable-step solver.

    Returns
    -------
    dict of str to ndarray
        Every variable of the model at ``times`` (values after any event at that time).
    """
    from modelica.lang import parse
    from modelica.sim import causalize, flatten, simulate

    bindings = [f"{name} = {expr}" for name, expr in inputs.items()]
    bindings += [f"{name} = {_modelica_value(v)}" for name, v in parameters.items()]
    wrapper = f"model Check\n  QuadCoSim.{model} plant({', '.join(bindings)});\nend Check;\n"
    source = package_source()
    end = source.rindex("end QuadCoSim;")
    source = source[:end] + wrapper + source[end:]
    system = causalize(flatten([parse(source)], "QuadCoSim.Check"))
    result = simulate(system, stop=stop, times=times, tolerance=tolerance)
    # The result holds the solver's steps besides the requested times; at an event time the
    # last row is the value after the event.
    index = np.searchsorted(result.time, np.asarray(times), side="right") - 1
    out = {}
    for name in result.names if hasattr(result, "names") else ():
        if name.startswith("plant."):
            out[name[len("plant."):]] = np.asarray(result[name])[index]
    return out


def input_values(inputs: dict[str, str], t: np.ndarray) -> dict[str, np.ndarray]:
    """Evaluate the input expressions at the times ``t``, in Python.

    Parameters
    ----------
    inputs : dict of str to str
        Input name to an expression of ``time`` (s).
    t : array_like
        Times (s).

    Returns
    -------
    dict of str to ndarray
        Each input at ``t``, shaped like ``t``.
    """
    t = np.asarray(t, dtype=float)
    return {name: np.broadcast_to(eval(expr, {"__builtins__": {}}, {**_FUNCTIONS, "time": t}), t.shape)
            for name, expr in inputs.items()}


def simulate_fmu(model: str, inputs: dict[str, str], parameters: dict, stop: float,
                 step: float, outputs: list[str]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Step the built FMU ``model`` with the inputs evaluated at each communication point.

    Outputs are read with the inputs set to their value at the communication point; the step
    is then taken with the inputs at mid-step, which the FMU holds constant over the step, so
    that a continuous input is integrated to second order in ``step``. The FMU is driven
    through fmpy directly, so that the plant needs no co-simulation master to be checked.

    Parameters
    ----------
    model : str
        Name of a built FMU (found by :func:`quadcosim.fmus.fmu_path`).
    inputs : dict of str to str
        Input name to expression of ``time`` (s), as for :func:`simulate_twin`.
    parameters : dict
        Parameter overrides by variable name, in the FMU's units (SI).
    stop : float
        End time (s).
    step : float
        Communication step (s).
    outputs : list of str
        Output names to return.

    Returns
    -------
    times : ndarray
        Communication times (s), ``0, step, ..., stop``.
    values : dict of str to ndarray
        Each output at ``times``, in the FMU's units.
    """
    slave, variables, unzipped = _start(model, parameters)
    try:
        n = int(round(stop / step))
        times = np.arange(n + 1) * step
        names = list(inputs)
        input_refs = [variables[name].valueReference for name in names]
        output_refs = [variables[name].valueReference for name in outputs]
        at = input_values(inputs, times)
        mid = input_values(inputs, times + 0.5 * step)
        u = np.column_stack([at[name] for name in names]) if names else None
        u_mid = np.column_stack([mid[name] for name in names]) if names else None
        values = np.empty((n + 1, len(outputs)))
        for k, t in enumerate(times):
            if names:
                slave.setReal(input_refs, list(u[k]))
            values[k] = slave.getReal(output_refs)
            if k < n:
                if names:
                    slave.setReal(input_refs, list(u_mid[k]))
                slave.doStep(float(t), step)
        return times, {name: values[:, j] for j, name in enumerate(outputs)}
    finally:
        slave.terminate()
        slave.freeInstance()
        shutil.rmtree(unzipped, ignore_errors=True)


def _start(model: str, parameters: dict):
    """Instantiate and initialise the built FMU ``model`` with fmpy, parameters set.

    Returns the fmpy slave, its variables by name and the folder it was extracted into.
    """
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    path = str(fmu_path(model))
    description = read_model_description(path)
    variables = {v.name: v for v in description.modelVariables}
    unzipped = extract(path)
    slave = FMU2Slave(guid=description.guid, unzipDirectory=unzipped,
                      modelIdentifier=description.coSimulation.modelIdentifier, instanceName=model)
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    for name, value in parameters.items():
        variable = variables[name]
        setter, kind = {"Real": (slave.setReal, float), "Integer": (slave.setInteger, int),
                        "Boolean": (slave.setBoolean, bool)}[variable.type]
        setter([variable.valueReference], [kind(value)])
    slave.exitInitializationMode()
    return slave, variables, unzipped
