"""The parameters of the Python blocks, as ``quadcosim list --parameters MODEL`` shows them.

An FMU's parameters come from its variable table; a Python block's from the tables its module
declares: the controller's gains (:data:`quadcosim.flight.GAINS`) and each attitude filter's
gains (:data:`quadcosim.estimators.GAIN_MEANINGS`, defaults :data:`quadcosim.estimators.LAB_GAINS` as ``tp`` runs
them and :data:`quadcosim.estimators.DEFAULT_GAINS` as :func:`quadcosim.estimators.estimate` runs them).
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
    from quadcosim.estimators import DEFAULT_GAINS, GAIN_MEANINGS, LAB_GAINS
    from quadcosim.estimators.reference import DEFAULT_GAINS as REFERENCE_GAINS

    lines = ["Quaternion_estim gains, by estimator: tp's default (the lab's values; tp sets them with its options "
             "k, k1, k2, kP, kI) and the default of quadcosim.estimators.estimate (recordings); in Python, "
             "QuaternionEstim(KIND, gains={NAME: VALUE}):"]
    for kind, meanings in GAIN_MEANINGS.items():
        lines.append(f"  {kind}:")
        for name, (unit, meaning) in meanings.items():
            lab, recordings = shown(LAB_GAINS[kind][name], PARAMETER_DIGITS), shown(DEFAULT_GAINS[kind][name],
                                                                                    PARAMETER_DIGITS)
            lines.append(f"    {name:4s} tp {lab:8} recordings {recordings:12}{'[' + unit + ']':9s} {meaning}")
    lines.append("  madgwick:")
    lines.append(f"    beta tp {shown(REFERENCE_GAINS['madgwick']['beta'], PARAMETER_DIGITS):8} "
                 f"recordings {shown(REFERENCE_GAINS['madgwick']['beta'], PARAMETER_DIGITS):12}{'[rad/s]':9s} "
                 "gradient step (the ahrs package's default)")
    lines.append("  vqf: the vqf package's own parameters (tauAcc, tauMag, ...; see its documentation)")
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
