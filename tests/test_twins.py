"""The Modelica twins in fmus/QuadCoSim match their FMUs, simulated under the same inputs.

Each twin is simulated by the PyPI package ``modelica`` (pinned) with its inputs bound to
functions of time in a wrapper model; the FMU is stepped with the same functions (see
fmus/twins.py). Noise is off. Tolerance: 1e-6 of each signal's peak over 2 s, except MotorMagnetics at 2e-5:
the FMU holds each input over a communication step while the twin sees it continuously, and
the stiff motor current follows the command within L/R = 0.4 ms, so the hold shows there (the
commands that swing ten times faster, onto the current bounds, are stepped at 20 us for it).

What the toolchain cannot check: the IMU's white noise and bias random walk are drawn by a
counter-based generator inside the FMU, which has no equation-based Modelica form; they are
covered by tests/test_imu.py instead.
"""

import numpy as np
import pytest

pytest.importorskip("modelica")

from fmus.build import table  # noqa: E402
from fmus.twins import simulate_fmu, simulate_twin  # noqa: E402

TOLERANCE = 1e-6  # of the peak of each signal
STOP = 2.0


def compare(model, inputs, parameters, fmu_step, every, tolerance=TOLERANCE, report=print):
    outputs = [v.name for v in table(model).of("output")]
    times, fmu = simulate_fmu(model, inputs, parameters, STOP, fmu_step, outputs)
    grid = times[::every]
    # a little beyond the last instant: the toolchain may leave an event at the stop time unhandled
    twin = simulate_twin(model, inputs, parameters, STOP + fmu_step, grid)
    worst = {}
    for name in outputs:
        reference = fmu[name][::every]
        scale = max(np.abs(reference).max(), 1e-300)
        worst[name] = np.abs(twin[name] - reference).max() / scale
    bad = {k: v for k, v in worst.items() if not v <= tolerance}
    name = max(worst, key=worst.get)
    report(f"\n{model} twin against FMU over {STOP:g} s: largest difference {worst[name]:.2g} of the peak ({name})")
    assert not bad, bad
    return twin


def test_quadrotor_twin():
    inputs = {f"omega_r{n}": f"495 + {15 * n}*sin({3 * n}*time) + 20*cos(5*time)" for n in range(1, 5)}
    inputs |= {f"domega_r{n}": f"{45 * n * n}*cos({3 * n}*time) - 100*sin(5*time)" for n in range(1, 5)}
    inputs |= {"wind_x": "3 + sin(2*time)", "wind_y": "-1.5*cos(time)", "wind_z": "0.5"}
    params = {"theta1_0": 0.1, "theta2_0": -0.2, "theta3_0": 0.4, "omega_x0": 0.3, "omega_y0": -0.5,
              "v_x0": 1.0, "v_y0": -2.0, "c_Dx": 0.01, "c_Dy": 0.02, "c_Dz": 0.03, "drag": 0.1}
    compare("Quadrotor", inputs, params, 1e-4, 100)


def test_quadrotor_twin_clamped():
    inputs = {f"omega_r{n}": f"400 + {30 * n}*sin({n}*time)" for n in range(1, 5)}
    compare("Quadrotor", inputs, {"clamped": True, "theta1_0": 0.2, "theta2_0": 0.1}, 1e-3, 10)


def test_motor_magnetics_twin():
    inputs = {f"c{n}": f"0.45 + 0.25*sin({n}*time)" for n in range(1, 5)}
    compare("MotorMagnetics", inputs, {}, 5e-5, 200, tolerance=2e-5)


@pytest.mark.parametrize("regenerative", [False, True], ids=["free-wheeling", "regenerative"])
def test_motor_magnetics_twin_on_the_current_bounds(regenerative):
    """Commands that swing fast enough to stop the currents at zero (or reverse them) and to
    drive them onto the limit: the FMU's located mode switches against the twin's state events."""
    inputs = {f"c{n}": f"0.5 + 0.45*sin({6 * n}*time)" for n in range(1, 5)}
    compare("MotorMagnetics", inputs, {"regenerative": regenerative}, 2e-5, 500, tolerance=2e-5)


def test_imu_twin_at_sample_instants():
    inputs = {
        "q0": "cos(0.3*sin(time))", "q1": "sin(0.3*sin(time))*0.6", "q2": "sin(0.3*sin(time))*0.8",
        "q3": "0", "omega_x": "0.2*cos(3*time)", "omega_y": "-0.1 + 0.05*time", "omega_z": "0.3",
        "f_x": "0.5*sin(time)", "f_y": "-0.2", "f_z": "-9.81 + 0.3*cos(2*time)",
        "b_d_x": "2e-6*sin(5*time)", "b_d_y": "1e-6", "b_d_z": "-3e-6*cos(time)",
        "omega_r1": "500", "omega_r2": "520", "omega_r3": "480", "omega_r4": "450",
    }
    params = {"noise_enabled": False, "bias_enabled": True, "sample_rate": 100.0, "mag_sample_rate": 50.0,
              "vibration_amplitude": 0.3, "b_a_x": 0.05,
              "A_11": 1.05, "A_12": 0.02, "A_23": -0.03, "b_s_x": 2e-6, "b_s_z": -1e-6}
    compare("IMU", inputs, params, 1e-3, 20)  # at the instants of both clocks


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
