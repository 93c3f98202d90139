"""A sensor FMU registered from outside the package: a barometer, the static pressure of the
standard atmosphere at the body's altitude through the lag of the sensor's port.

One folder, as a third party ships one: ``model.c``, ``variables.py``, its Modelica twin
``Barometer.mo`` and, here, what the checks drive it with (:data:`quadcosim.fmus.models.CHECKS`).
It is registered by one line in the entry-point group ``quadcosim.sensors``,
``Barometer = "dummy_sensor"`` (``tests/test_registries.py``).
"""

from quadcosim.fmus.models import TwinCase

SUMMARY = {"states": "the measured pressure (1)", "integrator": "exact (altitude held over a step)"}
HELD_INPUTS = {"p_z": -120.0}
RESET_PARAMETERS = ({"h0": 300.0, "tau": 0.05}, {"sea_level_pressure": 100000.0, "tau": 0.01})
REFUSED_PARAMETERS = [
    ("tau", 0.0, "tau = 0 s must be positive"),
    ("lapse_rate", -0.0065, "lapse_rate = -0.0065 K/m must be positive"),
    ("h0", 50000.0, "altitude h0 - p_z = 50000 m is at or above 44330.8 m, where the troposphere ends"),
]
TWIN_CASES = {
    "Barometer": TwinCase({"p_z": "-30*sin(time) - 10*time"}, {"h0": 500.0, "tau": 0.05}, step=1e-3, every=10,
                          tolerance=1e-6),
}
