"""The default internal sub-step of each integrating FMU is the largest that converges.

On 2 s manoeuvres with 20 ms communication steps (inputs held over each), halving the
default sub-step changes no output by more than 1e-6 of its peak, and doubling it does on at
least one of them. The MotorMagnetics manoeuvres drive the motor currents onto both bounds of the
ESC (zero, where free-wheeling stops them, and the current limit), so the located mode switches
are part of what converges. The IMU has no continuous state and no integrator: its sub-step
question does not arise. The manoeuvres are each model's (``SUBSTEP_CASES`` in its folder's
``__init__.py``), gathered by fmus/agreement.py; `python -m quadcosim.fmus.agreement
--substeps` prints the changes.
"""

import pytest
from quadcosim.fmus.agreement import change_when_halved, default_sub_step, substep_cases

BOUND = 1e-6  # of each output's peak


@pytest.mark.parametrize("model", list(substep_cases()))
def test_default_sub_step_is_the_largest_that_converges(model, capsys):
    default = default_sub_step(model)
    at_default, at_double = change_when_halved(model, default), change_when_halved(model, 2 * default)
    with capsys.disabled():
        print(f"\n{model}: halving sub_step {default:g} s changes outputs by {at_default:.2g}; "
              f"halving {2 * default:g} s by {at_double:.2g}")
    assert at_default < BOUND
    assert at_double > BOUND
