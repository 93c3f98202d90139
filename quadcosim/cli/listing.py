"""``quadcosim list``: the scenarios and their options, or one block's parameters."""

from __future__ import annotations

from quadcosim.infra.errors import UsageError


def add(sub) -> None:
    """Add the ``list`` verb to the sub-parsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``quadcosim`` parser's sub-parsers.
    """
    listing = sub.add_parser("list", help="the scenarios and their options")
    listing.add_argument("--parameters", metavar="MODEL",
                         help="list the parameters of a block instead, with units and defaults: an FMU (IMU, "
                              "Quadrotor, MotorMagnetics, ...) or a Python block (Controller, Quaternion_estim)")
    listing.set_defaults(func=command)


def command(args) -> int:
    """Print the scenarios and their options, or (``--parameters``) one block's parameters.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed ``list`` arguments.
    """
    if args.parameters:
        return _parameters(args.parameters)
    from quadcosim import scenarios

    for name, scenario in scenarios.registry().items():
        print(f"{name}: {scenario.description}")
        for key, option in scenario.options.items():
            choices = f" ({'|'.join(map(str, option.choices))})" if option.choices else ""
            print(f"    {key:16s} = {option.default!s:10s}{choices}  {option.help}")
    return 0


def _parameters(model: str) -> int:
    """Print the parameters of ``model``, an FMU or a Python block, with units and defaults."""
    from quadcosim.fmus import MODELS
    from quadcosim.fmus.build import table
    from quadcosim.scenarios.block_parameters import PYTHON_BLOCKS, parameter_lines, scenario_lines

    if model in PYTHON_BLOCKS:
        print("\n".join(parameter_lines(model)))
        return 0
    if model not in MODELS:
        raise UsageError(f"unknown model {model!r}; FMUs: {', '.join(MODELS)}; Python blocks: "
                         f"{', '.join(PYTHON_BLOCKS)}")
    from quadcosim.orchestrator.parameters import model_notes

    print(f"{model} parameters (set one in any scenario with --set {model}.NAME=VALUE; a vector as x,y,z):")
    from quadcosim.scenarios.shown import PARAMETER_DIGITS, shown

    for v in table(model).of("parameter"):
        unit = f" [{v.unit}]" if v.unit else ""
        print(f"  {v.name:22s} = {shown(v.start, PARAMETER_DIGITS):24}{unit:14s} {v.description}")
    aliases, switched = model_notes(model)
    for alias, name in aliases.items():
        print(f"  {alias} stands for the vector {name}")
    for switch, governed in switched.items():
        print(f"  {', '.join(governed)} act only while {switch} is true")
    print("\n".join(scenario_lines(model)))
    return 0
