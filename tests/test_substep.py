"""The default internal sub-step of each integrating FMU is the largest that converges.

On 2 s manoeuvres with 20 ms communication steps (inputs held over each), halving the
default sub-step changes no output by more than 1e-6 of its peak, and doubling it does on at
least one of them. The MotorMagnetics manoeuvres drive the motor currents onto both bounds of the
ESC (zero, where free-wheeling stops them, and the current limit), so the located mode switches
are part of what converges. The IMU has no continuous state and no integrator: its sub-step
question does not arise.
"""

import numpy as np
import pytest

from fmus.build import table
from fmus.twins import simulate_fmu

_MOTOR_OUTPUTS = ["omega_r1", "omega_r2", "omega_r3", "omega_r4", "i1", "i2", "i3", "i4", "u_batt", "b_d_x",
                  "b_d_y", "b_d_z", "soc"]
CASES = {
    "Quadrotor": [(
        {**{f"omega_r{n}": f"495 + {15 * n}*sin({3 * n}*time) + 20*cos(5*time)" for n in range(1, 5)},
         **{f"domega_r{n}": f"{45 * n * n}*cos({3 * n}*time) - 100*sin(5*time)" for n in range(1, 5)},
         "wind_x": "2 + sin(time)", "wind_y": "-1", "wind_z": "0"},
        {"c_Dx": 0.01, "c_Dy": 0.01, "c_Dz": 0.02, "v_x0": 2.0, "omega_y0": 0.5},
        ["q0", "q1", "q2", "q3", "omega_x", "omega_y", "omega_z", "p_x", "p_y", "p_z", "v_x", "v_z", "f_x", "f_z"],
    )],
    "MotorMagnetics": [
        ({f"c{n}": f"0.45 + 0.25*sin({4 * n}*time)" for n in range(1, 5)}, {}, _MOTOR_OUTPUTS),
        ({f"c{n}": f"0.5 + 0.45*sin({6 * n}*time)" for n in range(1, 5)}, {}, _MOTOR_OUTPUTS),
    ],
}


def change_when_halved(model, sub_step):
    """Largest change of an output (relative to its peak) over the model's manoeuvres."""
    worst = 0.0
    for inputs, params, outputs in CASES[model]:
        runs = []
        for s in (sub_step, sub_step / 2):
            _, out = simulate_fmu(model, inputs, {**params, "sub_step": s}, 2.0, 0.02, outputs)
            runs.append(np.column_stack([out[k] for k in outputs]))
        scale = np.abs(runs[1]).max(axis=0)
        worst = max(worst, (np.abs(runs[0] - runs[1]).max(axis=0) / scale).max())
    return worst


@pytest.mark.parametrize("model", list(CASES))
def test_default_sub_step_is_the_largest_that_converges(model, capsys):
    default = next(v.start for v in table(model).of("parameter") if v.name == "sub_step")
    at_default, at_double = change_when_halved(model, default), change_when_halved(model, 2 * default)
    with capsys.disabled():
        print(f"\n{model}: halving sub_step {default:g} s changes outputs by {at_default:.2g}; "
              f"halving {2 * default:g} s by {at_double:.2g}")
    assert at_default < 1e-6
    assert at_double > 1e-6
