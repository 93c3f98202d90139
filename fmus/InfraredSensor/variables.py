"""Variable table of the InfraredSensor FMU: turn kinematics, infrared horizon sensor, GPS turn rate.

The numbers come from "Calibration d'un récepteur Infra-Rouge pour Micro Drone" (Paparazzi
project, 2004): a 1.4 kg, 1.4 m span aircraft; the infrared reading sampled every 50 ms; on a
real flight of 8000 samples the regression ``IR = -400 r + 990``, IR mean 965 and standard
deviation 101.6, turn rate mean 0.037 and standard deviation 0.24 rad/s; the GPS turn rate a
heading difference delivered 1 s late. The drift profile (time of day, temperature, cloud) and
the noise levels are chosen so that a flight of the ir-calibration scenario's bank profile has the
slides' turn-rate statistics exactly and IR statistics near theirs (``metrics.json`` of the
scenario prints them). The slides' three numbers are not consistent with one least-squares
line: 990 - 400 x 0.037 = 975, not 965.
"""

from quadcosim.fmus.variables import Boolean, Integer, Real, Table

GRAVITY = 9.81  # m/s^2
AIRSPEED = 12.0  # m/s: cruise of a 1.4 kg, 1.4 m span fixed-wing
IR_GAIN = -410.0  # IR count per rad/s at take-off: -400 on average over the flight
IR_OFFSET = 933.0  # IR count at take-off
IR_NOISE = 4.0  # IR count, standard deviation per sample
GPS_HEADING_NOISE = 0.01  # rad, standard deviation of each GPS course sample

TABLE = Table(
    "InfraredSensor",
    "Fixed-wing in coordinated turns (r = g tan(phi) / V) with an infrared horizon sensor "
    "IR = a r + b whose a and b drift, and a GPS turn rate from heading differences, delivered late",
    variables=[
        Real("phi", "input", 0.0, "rad", "bank angle, from a scripted profile; |phi| < pi/2"),
        # kinematics
        Real("sample_rate", "parameter", 20.0, "Hz", "sampling rate of the infrared and GPS outputs"),
        Real("airspeed", "parameter", AIRSPEED, "m/s", "true airspeed V, held constant"),
        Real("gravity", "parameter", GRAVITY, "m/s2", "gravity g"),
        Real("psi0", "parameter", 0.0, "rad", "initial heading"),
        # infrared sensor and its drift
        Real("ir_gain", "parameter", IR_GAIN, "s/rad", "a at t = 0: IR count per rad/s of turn rate"),
        Real("ir_offset", "parameter", IR_OFFSET, "1", "b at t = 0: IR count at zero turn rate"),
        Boolean("drift_enabled", "parameter", True, "a and b drift with time of day, temperature and cloud"),
        Real("gain_day_rate", "parameter", -0.25 / 3600, "1/s", "time of day: relative change of a per second (-25 % per hour)"),
        Real("offset_day_rate", "parameter", 500.0 / 3600, "1/s", "time of day: change of b per second (500 count per hour)"),
        Real("gain_temperature", "parameter", 0.02, "1", "temperature: relative amplitude on a"),
        Real("offset_temperature", "parameter", 10.0, "1", "temperature: amplitude on b (count)"),
        Real("temperature_period", "parameter", 600.0, "s", "temperature: period of the oscillation"),
        Real("cloud_start", "parameter", 170.0, "s", "cloud: time the aircraft enters it"),
        Real("cloud_duration", "parameter", 70.0, "s", "cloud: time under full cover"),
        Real("cloud_ramp", "parameter", 15.0, "s", "cloud: time to enter or leave full cover"),
        Real("gain_cloud", "parameter", -0.08, "1", "cloud: relative change of a under full cover"),
        Real("offset_cloud", "parameter", 70.0, "1", "cloud: change of b under full cover (count)"),
        # GPS
        Real("gps_window", "parameter", 1.0, "s", "GPS turn rate: heading difference over this time"),
        Real("gps_delay", "parameter", 1.0, "s", "GPS turn rate: delivered this late"),
        # noise
        Boolean("noise_enabled", "parameter", True, "white measurement noise on"),
        Integer("seed", "parameter", 1, "seed of the noise generator"),
        Real("ir_noise", "parameter", IR_NOISE, "1", "infrared noise, standard deviation per sample (count)"),
        Real("gps_heading_noise", "parameter", GPS_HEADING_NOISE, "rad", "GPS course noise per sample"),
        # outputs
        Real("r", "output", unit="rad/s", description="true turn rate g tan(phi) / V", depends=("phi",)),
        Real("psi", "output", unit="rad", description="true heading"),
        Real("a", "output", unit="s/rad", description="true infrared gain a"),
        Real("b", "output", unit="1", description="true infrared offset b (count)"),
        Real("ir", "output", unit="1", description="infrared reading a r + b + noise, sampled (count)",
             depends=("phi",)),
        Real("gps_turn_rate", "output", unit="rad/s",
             description="GPS turn rate: heading difference over gps_window, gps_delay late, sampled"),
        Real("gps_valid", "output", unit="1", description="1 once the GPS heading history covers the window"),
    ],
)
