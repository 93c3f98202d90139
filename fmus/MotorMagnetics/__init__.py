"""The MotorMagnetics FMU: four motors, their ESCs and battery, and the field of the supply currents.

Its equations are ``model.c``, its variables ``variables.py``, its Modelica twin
``MotorMagnetics.mo``; below, what the checks drive it with (the names of
:data:`quadcosim.fmus.models.CHECKS`).
"""

from quadcosim.fmus.models import TwinCase

SUMMARY = {"states": "ω_r, i (per motor), state of charge (9)",
           "integrator": "exponential RK4 (Cox–Matthews) on the stiff electro-mechanical part, cut at each ESC mode "
                         "switch"}
HELD_INPUTS = {"c1": 0.35, "c2": 0.5, "c3": 0.62, "c4": 0.8}
RESET_PARAMETERS = ({"soc0": 0.8}, {"soc0": 0.6, "sub_step": 1e-4})
SPLIT_VECTOR = "omega_r"
REFUSED_PARAMETERS = [
    ("L_m", 0.0, "L_m = 0 must be positive"),
    ("i_max", 0.0, "i_max = 0 must be positive"),
    ("i_max", -5.0, "i_max = -5 must be positive"),
    ("omega0", 2000.0, "omega0 = 2000 rad/s needs a motor current of 61.7 A, beyond i_max = 18 A"),
]

_SLOW_COMMANDS = {f"c{n}": f"0.45 + 0.25*sin({n}*time)" for n in range(1, 5)}
# commands that swing fast enough to stop the currents at zero (or reverse them) and drive them onto the limit
_BOUNDS_COMMANDS = {f"c{n}": f"0.5 + 0.45*sin({6 * n}*time)" for n in range(1, 5)}
# The FMU holds each input over a step while the twin sees it continuously, and the stiff current
# follows the command within L/R = 0.4 ms: stepped finely, within 2e-5 (measured 6.0e-6 to 8.5e-6).
TWIN_CASES = {
    "MotorMagnetics": TwinCase(_SLOW_COMMANDS, {}, step=5e-5, every=200, tolerance=2e-5),
    "MotorMagnetics on the current bounds, free-wheeling": TwinCase(_BOUNDS_COMMANDS, {"regenerative": False},
                                                                    step=2e-5, every=500, tolerance=2e-5),
    "MotorMagnetics on the current bounds, regenerative": TwinCase(_BOUNDS_COMMANDS, {"regenerative": True},
                                                                   step=2e-5, every=500, tolerance=2e-5),
}
_OUTPUTS = ["omega_r1", "omega_r2", "omega_r3", "omega_r4", "i1", "i2", "i3", "i4", "u_batt", "b_d_x", "b_d_y",
            "b_d_z", "soc"]
SUBSTEP_CASES = [
    ({f"c{n}": f"0.45 + 0.25*sin({4 * n}*time)" for n in range(1, 5)}, {}, _OUTPUTS),
    (_BOUNDS_COMMANDS, {}, _OUTPUTS),
]
