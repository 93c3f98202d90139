"""The units of a sweep's columns: an option's declared unit, a block parameter's (an FMU's
variable table, a Python block's ``parameter_units``), a metric's from the end of its name."""

from __future__ import annotations


def of_options(scenario_name: str, names) -> dict[str, str]:
    """The unit of each option and block parameter (``Controller.kp``) among ``names`` that has one.

    Parameters
    ----------
    scenario_name : str
        A registered scenario.
    names : iterable of str
        Option names and ``Block.parameter`` names.

    Returns
    -------
    dict
        Name to unit (``{"k": "1/s", "Controller.kp": "1/s^2"}``); names without a unit are left out.
    """
    from quadcosim import scenarios

    scenario = scenarios.get(scenario_name)
    units = {name: option.unit for name, option in scenario.options.items() if option.unit}
    wanted = [name for name in names if "." in name]
    if wanted:
        from quadcosim.orchestrator.blocks import FMUBlock
        from quadcosim.orchestrator.parameters import fmu_parameters

        try:
            blocks = scenario.system(scenario.parse({})).blocks
        except (KeyError, ValueError, OSError):  # an FMU not built: the axes go without units
            blocks = {}
        for name in wanted:
            block, _, parameter = name.partition(".")
            found = blocks.get(block)
            if isinstance(found, FMUBlock):
                variable = fmu_parameters(found.model).get(parameter)
                unit = getattr(variable, "unit", None) or getattr(getattr(variable, "declaredType", None), "unit",
                                                                  None)
            else:
                unit = getattr(found, "parameter_units", {}).get(parameter)
            if unit:
                units[name] = unit
    return {name: unit for name, unit in units.items() if name in set(names)}


def of_columns(names, option_units: dict) -> dict[str, str]:
    """The unit of each column of ``names``: an option's from ``option_units``, a metric's from
    the end of its name (:func:`quadcosim.studies.sweep.figure.metric_unit`)."""
    from quadcosim.studies.sweep.figure import metric_unit

    found = {}
    for name in names:
        unit = option_units.get(name) or metric_unit(name)
        if unit:
            found[name] = unit
    return found
