"""The Quadrotor FMU: the rigid body of a quad-X with rotor drag, wind and rotor inertia.

Its equations are ``model.c``, its variables ``variables.py``, its Modelica twin ``Quadrotor.mo``;
below, what the checks drive it with (the names of :data:`quadcosim.fmus.models.CHECKS`).
"""

from quadcosim.fmus.models import TwinCase

SUMMARY = {"states": "p, v, q, ω (13)", "integrator": "RK4"}
HELD_INPUTS = {"omega_r1": 480.0, "omega_r2": 500.0, "omega_r3": 490.0, "omega_r4": 505.0}
RESET_PARAMETERS = ({"m": 1.3, "omega_x0": 0.2}, {"m": 0.9})
SPLIT_VECTOR = "q"
REFUSED_PARAMETERS = [
    ("m", -1.0, "m = -1 must be positive"),
    ("Jxx", 0.0, "Jxx = 0 must be positive"),
    ("k_d", -1e-4, "k_d = -0.0001 must be non-negative"),
    ("c_Dx", -0.01, "c_Dx = -0.01 must be non-negative"),
    ("drag", -0.2, "drag = -0.2 must be non-negative"),
    ("J_r", -3e-5, "J_r = -3e-05 must be non-negative"),
]

_SPEEDS = {f"omega_r{n}": f"495 + {15 * n}*sin({3 * n}*time) + 20*cos(5*time)" for n in range(1, 5)}
_ACCELERATIONS = {f"domega_r{n}": f"{45 * n * n}*cos({3 * n}*time) - 100*sin(5*time)" for n in range(1, 5)}
TWIN_CASES = {
    # measured 9.2e-8 of the peak (python -m quadcosim.fmus.agreement --twins)
    "Quadrotor": TwinCase(_SPEEDS | _ACCELERATIONS | {"wind_x": "3 + sin(2*time)", "wind_y": "-1.5*cos(time)",
                                                      "wind_z": "0.5"},
                          {"theta1_0": 0.1, "theta2_0": -0.2, "theta3_0": 0.4, "omega_x0": 0.3, "omega_y0": -0.5,
                           "v_x0": 1.0, "v_y0": -2.0, "c_Dx": 0.01, "c_Dy": 0.02, "c_Dz": 0.03, "drag": 0.1},
                          step=1e-4, every=100, tolerance=3e-7),
    # measured 1.4e-15: the clamped body's outputs are algebraic in its inputs, equal to rounding
    "Quadrotor clamped": TwinCase({f"omega_r{n}": f"400 + {30 * n}*sin({n}*time)" for n in range(1, 5)},
                                  {"clamped": True, "theta1_0": 0.2, "theta2_0": 0.1}, step=1e-3, every=10,
                                  tolerance=1e-12),
}
SUBSTEP_CASES = [(
    _SPEEDS | _ACCELERATIONS | {"wind_x": "2 + sin(time)", "wind_y": "-1", "wind_z": "0"},
    {"c_Dx": 0.01, "c_Dy": 0.01, "c_Dz": 0.02, "v_x0": 2.0, "omega_y0": 0.5},
    ["q0", "q1", "q2", "q3", "omega_x", "omega_y", "omega_z", "p_x", "p_y", "p_z", "v_x", "v_z", "f_x", "f_z"],
)]
