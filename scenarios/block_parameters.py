"""The parameters of the Python blocks, as ``quadcosim list --parameters MODEL`` shows them.

An FMU's parameters come from its variable table; a Python block's from the tables its module
declares: the controller's gains (:data:`quadcosim.flight.GAINS`) and each registered estimator's
gains (:attr:`quadcosim.estimators.kinds.Kind.gains`: unit, meaning, the lab's value as ``tp`` runs
it and the default of :func:`quadcosim.estimators.estimate`).
"""

from __future__ import annotations

#: Python blocks with a parameter table, by the name they take in a system.
PYTHON_BLOCKS = ("Controller", "Quaternion_estim")


def parameter_lines(model: str) -> list[str]:
    """The lines ``quadcosim list --parameters MODEL`` prints for a Python block.

    Parameters
    ----------
    model : str
        A name of :data:`PYTHON_BLOCKS`.

    Returns
    -------
    list of str
        A heading that says how to set them, then one line per parameter: name, default, unit
        in brackets, meaning.
    """
    from quadcosim.scenarios.shown import PARAMETER_DIGITS, shown

    if model == "Controller":
        from quadcosim.flight import GAINS

        lines = ["Controller gains (set one in tp with --set Controller.NAME=VALUE; in Python, "
                 "Controller(gains={NAME: VALUE})):"]
        for name, (default, unit, meaning) in GAINS.items():
            lines.append(f"  {name:10s} = {shown(default, PARAMETER_DIGITS):10}{'[' + unit + ']':10s} {meaning}")
        return lines
    from quadcosim.estimators import kinds

    lines = ["Quaternion_estim gains, by estimator: tp's default (the lab's values; tp sets them with its options "
             "k, k1, k2, kP, kI) and the default of quadcosim.estimators.estimate (recordings); in Python, "
             "QuaternionEstim(KIND, gains={NAME: VALUE}):"]
    for kind in kinds.registry().values():
        if kind.block:
            lines.append(f"  {kind.name}: its own block ({kind.block}), its parameters its own")
            continue
        lines.append(f"  {kind.name}:" if kind.gains else f"  {kind.name}: its package's own parameters (see its "
                     "documentation)")
        lab, recordings = kind.lab_gains(), kind.defaults()
        for name, (unit, meaning) in kind.meanings().items():
            in_tp = shown(lab[name], PARAMETER_DIGITS) if kind.streaming else "-"  # not a closed-loop choice
            lines.append(f"    {name:4s} tp {in_tp:8} recordings "
                         f"{shown(recordings[name], PARAMETER_DIGITS):12}{'[' + unit + ']':9s} {meaning}")
    return lines


def scenario_lines(model: str) -> list[str]:
    """The lines ``quadcosim list --parameters MODEL`` adds under an FMU's own defaults: the
    parameters each scenario sets from one of its options (tp runs with ``IMU.noise_enabled``
    from its option ``noise``, off by default), which ``--set MODEL.NAME`` cannot change.

    Parameters
    ----------
    model : str
        An FMU's name (``"IMU"``).

    Returns
    -------
    list of str
        A heading, then one line per scenario that sets any: ``parameter <- option (default)``;
        empty when none does.
    """
    from quadcosim import scenarios

    lines = []
    for name, scenario in scenarios.registry().items():
        derived = {k.partition(".")[2]: v for k, v in scenario.extra.get("derived", {}).items()
                   if k.startswith(model + ".")}
        said = [f"{parameter} <- {option}" if option.startswith("(") else
                f"{parameter} <- option {option} (default {scenario.options[option].default})"
                for parameter, option in derived.items() if option.startswith("(") or option in scenario.options]
        if said:
            lines.append(f"  {name}: {'; '.join(said)}")
    if lines:
        lines.insert(0, f"{model} parameters the scenarios set from their options (change the option, "
                        "--set OPTION=VALUE; the defaults above apply where no scenario sets them):")
    return lines
