"""The Modelica twins in fmus/QuadCoSim match their FMUs, simulated under the same inputs.

Each twin is simulated by the PyPI package ``modelica`` (pinned) with its inputs bound to
functions of time in a wrapper model; the FMU is stepped with the same functions (see
fmus/twins.py); the cases are fmus/agreement.py's, whose `python -m quadcosim.fmus.agreement`
prints the differences. Noise is off. Tolerance, of each signal's peak over 2 s: 1e-6 for the
IMU; 3e-7 for the Quadrotor; 1e-12 for the clamped Quadrotor, whose outputs are algebraic in its
inputs, so the two agree to rounding; 2e-5 for MotorMagnetics: the FMU holds each input over a
communication step while the twin sees it continuously, and the stiff motor current follows the
command within L/R = 0.4 ms, so the hold shows there (the commands that swing ten times faster,
onto the current bounds, are stepped at 20 us for it).

What the toolchain cannot check: the IMU's white noise and bias random walk are drawn by a
counter-based generator inside the FMU, which has no equation-based Modelica form; they are
covered by tests/test_imu.py instead.
"""

import numpy as np
import pytest

pytest.importorskip("modelica")

from quadcosim.fmus.agreement import TWIN_CASES, twin_difference  # noqa: E402
from quadcosim.fmus.build import table  # noqa: E402
from quadcosim.fmus.twins import simulate_twin  # noqa: E402

# of the peak of each signal, near what each case measures (python -m quadcosim.fmus.agreement --twins)
TOLERANCE = {"IMU": 1e-6,  # measured 4.0e-7
             "Quadrotor": 3e-7,  # measured 9.2e-8
             "Quadrotor clamped": 1e-12,  # measured 1.4e-15: algebraic outputs, equal to rounding
             "MotorMagnetics": 2e-5}  # measured 6.0e-6 to 8.5e-6: the FMU's held command seen by L/R


def check(label, report=print):
    """The case ``label`` of quadcosim.fmus.agreement.TWIN_CASES within its tolerance."""
    difference, name = twin_difference(label)
    report(f"\n{label} twin against FMU: largest difference {difference:.2g} of the peak ({name})")
    assert difference <= TOLERANCE.get(label, TOLERANCE[TWIN_CASES[label][0]]), name


def test_quadrotor_twin():
    check("Quadrotor")


def test_quadrotor_twin_clamped():
    check("Quadrotor clamped")


def test_motor_magnetics_twin():
    check("MotorMagnetics")


@pytest.mark.parametrize("regenerative", ["free-wheeling", "regenerative"])
def test_motor_magnetics_twin_on_the_current_bounds(regenerative):
    """Commands that swing fast enough to stop the currents at zero (or reverse them) and to
    drive them onto the limit: the FMU's located mode switches against the twin's state events."""
    check(f"MotorMagnetics on the current bounds, {regenerative}")


def test_imu_twin_at_sample_instants():
    check("IMU")


@pytest.mark.parametrize("model", ["Quadrotor", "MotorMagnetics", "IMU"])
def test_twin_parameters_equal_fmu_start_values(model):
    tab = table(model)
    parameters = [v for v in tab.of("parameter") if v.name not in ("sub_step", "seed")]
    if model == "IMU":
        parameters = [v for v in parameters if "noise" not in v.name and "walk" not in v.name]
    inputs = {v.name: repr(float(v.start)) for v in tab.of("input")}
    twin = simulate_twin(model, inputs, {}, 0.01, np.array([0.0, 0.01]))
    for v in parameters:
        assert twin[v.name][0] == pytest.approx(float(v.start), rel=1e-12, abs=0), v.name
