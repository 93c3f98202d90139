"""The InfraredSensor FMU: a fixed-wing in coordinated turns, its infrared horizon sensor and its GPS turn rate.

Its equations are ``model.c``, its variables ``variables.py``, its Modelica twin
``InfraredSensor.mo`` (checked against the FMU by ``tests/test_infrared_sensor.py``); below,
what the checks drive it with (the names of :data:`quadcosim.fmus.models.CHECKS`).
"""

SUMMARY = {"states": "heading; IR and GPS sampled at 20 Hz, 2 s of GPS heading history",
           "integrator": "exact (bank held over a step)"}
HELD_INPUTS = {"phi": 0.3}
RESET_PARAMETERS = ({"noise_enabled": True, "seed": 5}, {"seed": 9, "gps_delay": 0.5})
# the noise lives in the FMU only: a seeded counter-based generator has no equation-based form
TWIN_OMITS = ("seed", "ir_noise", "gps_heading_noise")
