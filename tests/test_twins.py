"""The Modelica twins (fmus/<Model>/<Model>.mo) match their FMUs, simulated under the same inputs.

Each twin is simulated by the PyPI package ``modelica`` (pinned) with its inputs bound to
functions of time in a wrapper model; the FMU is stepped with the same functions (see
fmus/twins.py); the cases are each model's (``TWIN_CASES`` in its folder's ``__init__.py``),
gathered by fmus/agreement.py, whose `python -m quadcosim.fmus.agreement` prints the differences.
Noise is off. Tolerance, of each signal's peak over 2 s: 1e-6 for the
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

from quadcosim.fmus.agreement import twin_cases, twin_difference  # noqa: E402
from quadcosim.fmus.build import table  # noqa: E402
from quadcosim.fmus.models import sensors  # noqa: E402
from quadcosim.fmus.twins import simulate_twin  # noqa: E402


@pytest.mark.parametrize("label", list(twin_cases()))
def test_twin_agrees_with_its_fmu(label):
    """Each case of each model's ``TWIN_CASES`` (quadcosim.fmus.agreement.twin_cases) within its
    tolerance, of the peak of each signal, near what the case measures
    (``python -m quadcosim.fmus.agreement --twins``)."""
    _, case = twin_cases()[label]
    difference, name = twin_difference(label)
    print(f"\n{label} twin against FMU: largest difference {difference:.2g} of the peak ({name})")
    assert difference <= case.tolerance, name


@pytest.mark.parametrize("model", [name for name, member in sensors().items() if member.twin is not None])
def test_twin_parameters_equal_fmu_start_values(model):
    """Every parameter of the table but those the model's twin omits (``TWIN_OMITS``: the noise)
    has the FMU's start value in the twin."""
    omitted = sensors()[model].check("TWIN_OMITS")
    tab = table(model)
    parameters = [v for v in tab.of("parameter") if v.name not in omitted]
    inputs = {v.name: repr(float(v.start)) for v in tab.of("input")}
    twin = simulate_twin(model, inputs, {}, 0.01, np.array([0.0, 0.01]))
    for v in parameters:
        assert twin[v.name][0] == pytest.approx(float(v.start), rel=1e-12, abs=0), v.name
