"""Variable table of the Barometer FMU: the static pressure of the standard atmosphere at the
body's altitude, through the lag of the sensor's port.

The atmosphere is the troposphere of the International Standard Atmosphere (ISO 2533:1975):
sea-level pressure 101325 Pa and temperature 288.15 K, lapse rate 6.5 K/km.
"""

from quadcosim.fmus.variables import Real, Table

TABLE = Table(
    "Barometer",
    "Static-pressure sensor: the International Standard Atmosphere's troposphere at the altitude h0 - p_z, "
    "seen through a first-order lag of the sensor's port",
    states=1,
    variables=[
        Real("p_z", "input", 0.0, "m", "position along z of NED {I} (down)"),
        Real("h0", "parameter", 0.0, "m", "altitude of the NED origin above mean sea level"),
        Real("sea_level_pressure", "parameter", 101325.0, "N/m2", "static pressure at mean sea level"),
        Real("sea_level_temperature", "parameter", 288.15, "K", "temperature at mean sea level"),
        Real("lapse_rate", "parameter", 0.0065, "K/m", "temperature lapse rate of the troposphere"),
        Real("tau", "parameter", 0.02, "s", "time constant of the sensor's port"),
        Real("altitude", "output", unit="m", description="true altitude above mean sea level, h0 - p_z",
             depends=("p_z",)),
        Real("pressure", "output", unit="N/m2", description="measured static pressure (through the lag)"),
    ],
)
