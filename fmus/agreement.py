"""How closely the FMUs agree with their Modelica twins, and with themselves at half the sub-step.

``python -m quadcosim.fmus.agreement`` prints, for each case, the largest difference of an output over
its peak, in parts per million (ppm):

- each Modelica twin (``fmus/<Model>/<Model>.mo``) simulated by the pure-Python ``modelica``
  toolchain against its FMU under the same input functions of time (:func:`twin_cases`, noise off);
- each integrating FMU at its default internal sub-step against the same FMU at half of it, and
  at twice the default against the default, on the manoeuvres of :func:`substep_cases` (inputs
  held over 20 ms communication steps for 2 s).

Each model declares its cases in its folder's ``__init__.py`` (``TWIN_CASES``, ``SUBSTEP_CASES``).

``tests/test_twins.py`` and ``tests/test_substep.py`` run the same cases and bound the figures.
"""

from __future__ import annotations

import argparse

import numpy as np
from quadcosim.fmus.build import table
from quadcosim.fmus.models import TwinCase, sensors
from quadcosim.fmus.twins import simulate_fmu, simulate_twin

STOP_S = 2.0  # s simulated by every case
SUBSTEP_COMMUNICATION_S = 0.02  # s, communication step of the sub-step manoeuvres
PPM = 1e-6  # 1, a part per million: the unit the differences are printed in
SMALLEST_SCALE = 1e-300  # floor of a signal's peak, so that an all-zero signal is not divided by zero


def twin_cases() -> dict[str, tuple[str, TwinCase]]:
    """The twin checks of every registered model: label -> (model, its :class:`TwinCase`), from
    each model's ``TWIN_CASES`` (:data:`quadcosim.fmus.models.CHECKS`)."""
    return {label: (model, case) for model, member in sensors().items()
            for label, case in member.check("TWIN_CASES").items()}


def substep_cases() -> dict[str, list]:
    """The sub-step manoeuvres of every registered model that declares some: model -> [(input
    expressions of time, parameters, outputs compared)], its ``SUBSTEP_CASES``."""
    return {model: cases for model, member in sensors().items() if (cases := member.check("SUBSTEP_CASES"))}


def twin_difference(label: str) -> tuple[float, str]:
    """Largest difference between twin and FMU over the peak of the signal, over the outputs of
    the case ``label`` of :func:`twin_cases`.

    Returns
    -------
    (float, str)
        The difference (1) and the output it occurs on.
    """
    model, case = twin_cases()[label]
    inputs, parameters, fmu_step, every = case.inputs, case.parameters, case.step, case.every
    outputs = [v.name for v in table(model).of("output")]
    times, fmu = simulate_fmu(model, inputs, parameters, STOP_S, fmu_step, outputs)
    # a little beyond the last instant: the toolchain may leave an event at the stop time unhandled
    twin = simulate_twin(model, inputs, parameters, STOP_S + fmu_step, times[::every])
    worst = {}
    for name in outputs:
        reference = fmu[name][::every]
        worst[name] = np.abs(twin[name] - reference).max() / max(np.abs(reference).max(), SMALLEST_SCALE)
    name = max(worst, key=lambda k: np.inf if np.isnan(worst[k]) else worst[k])  # a NaN is the worst
    return float(worst[name]), name


def default_sub_step(model: str) -> float:
    """The default internal sub-step (s) of ``model``, from its variable table."""
    return float(next(v.start for v in table(model).of("parameter") if v.name == "sub_step"))


def change_when_halved(model: str, sub_step: float) -> float:
    """Largest change of an output over its peak (1) when ``model``'s sub-step goes from
    ``sub_step`` (s) to half of it, over the manoeuvres of :func:`substep_cases`."""
    changes = []
    for inputs, parameters, outputs in substep_cases()[model]:
        runs = []
        for step in (sub_step, sub_step / 2):
            _, out = simulate_fmu(model, inputs, {**parameters, "sub_step": step}, STOP_S,
                                  SUBSTEP_COMMUNICATION_S, outputs)
            runs.append(np.column_stack([out[k] for k in outputs]))
        scale = np.maximum(np.abs(runs[1]).max(axis=0), SMALLEST_SCALE)
        changes.append((np.abs(runs[0] - runs[1]).max(axis=0) / scale).max())
    return float(np.max(changes))  # a NaN stays a NaN, and fails any bound


def main(argv=None) -> int:
    """Print every twin difference and sub-step change (see the module docstring).

    Parameters
    ----------
    argv : list of str, optional
        ``--twins`` or ``--substeps`` prints one half only.

    Returns
    -------
    int
        Exit status, 0.
    """
    parser = argparse.ArgumentParser(prog="python -m quadcosim.fmus.agreement", description=__doc__.splitlines()[0])
    parser.add_argument("--twins", action="store_true", help="the twin checks only")
    parser.add_argument("--substeps", action="store_true", help="the sub-step checks only")
    args = parser.parse_args(argv)
    both = not (args.twins or args.substeps)
    if args.substeps or both:
        for model in substep_cases():
            step = default_sub_step(model)
            print(f"{model}: halving the default sub-step {step:g} s changes the outputs by "
                  f"{change_when_halved(model, step) / PPM:.3f} ppm of their peak; halving {2 * step:g} s by "
                  f"{change_when_halved(model, 2 * step) / PPM:.3f} ppm", flush=True)
    if args.twins or both:
        for label in twin_cases():
            difference, name = twin_difference(label)
            print(f"{label} twin against its FMU over {STOP_S:g} s: largest difference {difference / PPM:.3f} "
                  f"ppm of the peak ({name})", flush=True)
    return 0


if __name__ == "__main__":  # the same as quadcosim study agreement
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim study agreement").run, main)
