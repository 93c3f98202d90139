"""How closely the FMUs agree with their Modelica twins, and with themselves at half the sub-step.

``python -m quadcosim.fmus.agreement`` prints, for each case, the largest difference of an output over
its peak, in parts per million (ppm):

- each Modelica twin (``fmus/QuadCoSim/``) simulated by the pure-Python ``modelica`` toolchain
  against its FMU under the same input functions of time (:data:`TWIN_CASES`, noise off);
- each integrating FMU at its default internal sub-step against the same FMU at half of it, and
  at twice the default against the default, on the manoeuvres of :data:`SUBSTEP_CASES` (inputs
  held over 20 ms communication steps for 2 s).

``tests/test_twins.py`` and ``tests/test_substep.py`` run the same cases and bound the figures.
"""

from __future__ import annotations

import argparse

import numpy as np
from quadcosim.fmus.build import table
from quadcosim.fmus.twins import simulate_fmu, simulate_twin

STOP_S = 2.0  # s simulated by every case
SUBSTEP_COMMUNICATION_S = 0.02  # s, communication step of the sub-step manoeuvres
PPM = 1e-6  # 1, a part per million: the unit the differences are printed in
SMALLEST_SCALE = 1e-300  # floor of a signal's peak, so that an all-zero signal is not divided by zero

_QUADROTOR_SPEEDS = {f"omega_r{n}": f"495 + {15 * n}*sin({3 * n}*time) + 20*cos(5*time)" for n in range(1, 5)}
_QUADROTOR_ACCELERATIONS = {f"domega_r{n}": f"{45 * n * n}*cos({3 * n}*time) - 100*sin(5*time)" for n in range(1, 5)}
_SLOW_COMMANDS = {f"c{n}": f"0.45 + 0.25*sin({n}*time)" for n in range(1, 5)}
# commands that swing fast enough to stop the currents at zero (or reverse them) and drive them onto the limit
_BOUNDS_COMMANDS = {f"c{n}": f"0.5 + 0.45*sin({6 * n}*time)" for n in range(1, 5)}
_IMU_INPUTS = {
    "q0": "cos(0.3*sin(time))", "q1": "sin(0.3*sin(time))*0.6", "q2": "sin(0.3*sin(time))*0.8",
    "q3": "0", "omega_x": "0.2*cos(3*time)", "omega_y": "-0.1 + 0.05*time", "omega_z": "0.3",
    "f_x": "0.5*sin(time)", "f_y": "-0.2", "f_z": "-9.81 + 0.3*cos(2*time)",
    "b_d_x": "2e-6*sin(5*time)", "b_d_y": "1e-6", "b_d_z": "-3e-6*cos(time)",
    "omega_r1": "500", "omega_r2": "520", "omega_r3": "480", "omega_r4": "450",
}
_IMU_PARAMETERS = {"noise_enabled": False, "bias_enabled": True, "sample_rate": 100.0, "mag_sample_rate": 50.0,
                   "vibration_amplitude": 0.3, "b_a_x": 0.05,
                   "A_11": 1.05, "A_12": 0.02, "A_23": -0.03, "b_s_x": 2e-6, "b_s_z": -1e-6}

#: Twin checks: label -> (model, input expressions of time, parameters, FMU communication step in
#: s, compare every N-th communication point). The motor cases step the FMU finely: it holds each
#: input over a step, while the twin sees it continuously and the current follows within L/R.
TWIN_CASES = {
    "Quadrotor": ("Quadrotor", _QUADROTOR_SPEEDS | _QUADROTOR_ACCELERATIONS | {
        "wind_x": "3 + sin(2*time)", "wind_y": "-1.5*cos(time)", "wind_z": "0.5"}, {
        "theta1_0": 0.1, "theta2_0": -0.2, "theta3_0": 0.4, "omega_x0": 0.3, "omega_y0": -0.5,
        "v_x0": 1.0, "v_y0": -2.0, "c_Dx": 0.01, "c_Dy": 0.02, "c_Dz": 0.03, "drag": 0.1}, 1e-4, 100),
    "Quadrotor clamped": ("Quadrotor", {f"omega_r{n}": f"400 + {30 * n}*sin({n}*time)" for n in range(1, 5)},
                          {"clamped": True, "theta1_0": 0.2, "theta2_0": 0.1}, 1e-3, 10),
    "MotorMagnetics": ("MotorMagnetics", _SLOW_COMMANDS, {}, 5e-5, 200),
    "MotorMagnetics on the current bounds, free-wheeling": ("MotorMagnetics", _BOUNDS_COMMANDS,
                                                            {"regenerative": False}, 2e-5, 500),
    "MotorMagnetics on the current bounds, regenerative": ("MotorMagnetics", _BOUNDS_COMMANDS,
                                                           {"regenerative": True}, 2e-5, 500),
    "IMU": ("IMU", _IMU_INPUTS, _IMU_PARAMETERS, 1e-3, 20),  # at the instants of both sample clocks
}

_MOTOR_OUTPUTS = ["omega_r1", "omega_r2", "omega_r3", "omega_r4", "i1", "i2", "i3", "i4", "u_batt", "b_d_x",
                  "b_d_y", "b_d_z", "soc"]
#: Sub-step manoeuvres: model -> [(input expressions of time, parameters, outputs compared)].
SUBSTEP_CASES = {
    "Quadrotor": [(
        _QUADROTOR_SPEEDS | _QUADROTOR_ACCELERATIONS | {"wind_x": "2 + sin(time)", "wind_y": "-1", "wind_z": "0"},
        {"c_Dx": 0.01, "c_Dy": 0.01, "c_Dz": 0.02, "v_x0": 2.0, "omega_y0": 0.5},
        ["q0", "q1", "q2", "q3", "omega_x", "omega_y", "omega_z", "p_x", "p_y", "p_z", "v_x", "v_z", "f_x", "f_z"],
    )],
    "MotorMagnetics": [
        ({f"c{n}": f"0.45 + 0.25*sin({4 * n}*time)" for n in range(1, 5)}, {}, _MOTOR_OUTPUTS),
        (_BOUNDS_COMMANDS, {}, _MOTOR_OUTPUTS),
    ],
}


def twin_difference(label: str) -> tuple[float, str]:
    """Largest difference between twin and FMU over the peak of the signal, over the outputs of
    the case ``label`` of :data:`TWIN_CASES`.

    Returns
    -------
    (float, str)
        The difference (1) and the output it occurs on.
    """
    model, inputs, parameters, fmu_step, every = TWIN_CASES[label]
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
    ``sub_step`` (s) to half of it, over the manoeuvres of :data:`SUBSTEP_CASES`."""
    changes = []
    for inputs, parameters, outputs in SUBSTEP_CASES[model]:
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
        for model in SUBSTEP_CASES:
            step = default_sub_step(model)
            print(f"{model}: halving the default sub-step {step:g} s changes the outputs by "
                  f"{change_when_halved(model, step) / PPM:.3f} ppm of their peak; halving {2 * step:g} s by "
                  f"{change_when_halved(model, 2 * step) / PPM:.3f} ppm", flush=True)
    if args.twins or both:
        for label in TWIN_CASES:
            difference, name = twin_difference(label)
            print(f"{label} twin against its FMU over {STOP_S:g} s: largest difference {difference / PPM:.3f} "
                  f"ppm of the peak ({name})", flush=True)
    return 0


if __name__ == "__main__":  # the same as quadcosim study agreement
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim study agreement").run, main)
