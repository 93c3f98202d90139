"""The IMU FMU: accelerometer, gyrometer and magnetometer, sampled, with noise, biases and iron.

Its equations are ``model.c``, its variables ``variables.py``, its Modelica twin ``IMU.mo``;
below, what the checks drive it with (the names of :data:`quadcosim.fmus.models.CHECKS`).
"""

import math

from quadcosim.fmus.models import TwinCase

SUMMARY = {"states": "biases, rotor angles; accelerometer and gyro sampled at `sample_rate` (1 kHz), magnetometer "
                     "at `mag_sample_rate` (100 Hz), each held", "integrator": "none"}
HELD_INPUTS = {"q0": 0.9, "q1": 0.3, "q2": -0.2, "q3": math.sqrt(0.06), "omega_x": 0.3, "omega_y": -0.2,
               "omega_z": 0.1, "f_x": 1.0, "f_y": -0.5, "f_z": -9.7, "b_d_x": 1e-6, "b_d_y": -2e-6, "b_d_z": 3e-6}
HELD_PARAMETERS = {"noise_enabled": True, "bias_enabled": True}
RESET_PARAMETERS = ({"noise_enabled": True, "bias_enabled": True, "seed": 7}, {"noise_enabled": True, "seed": 3})
SPLIT_VECTOR = "magneto"
REFUSED_PARAMETERS = [
    ("sample_rate", -5.0, "sample_rate = -5 Hz must be positive"),
    ("mag_sample_rate", 0.0, "mag_sample_rate = 0 Hz must be positive"),
    ("vibration_amplitude", -0.1, "vibration_amplitude = -0.1 m/s2 must be non-negative"),
]
# The white noise and the bias random walk are drawn by a counter-based generator inside the
# FMU, which has no equation-based form: the twin leaves them out (tests/test_imu.py covers them).
TWIN_OMITS = ("seed", "sub_step", "gyro_noise_density", "acc_noise_density", "mag_noise_density", "gyro_bias_walk",
              "acc_bias_walk")
TWIN_CASES = {
    # at the instants of both sample clocks; measured 4.0e-7 of the peak
    "IMU": TwinCase({
        "q0": "cos(0.3*sin(time))", "q1": "sin(0.3*sin(time))*0.6", "q2": "sin(0.3*sin(time))*0.8",
        "q3": "0", "omega_x": "0.2*cos(3*time)", "omega_y": "-0.1 + 0.05*time", "omega_z": "0.3",
        "f_x": "0.5*sin(time)", "f_y": "-0.2", "f_z": "-9.81 + 0.3*cos(2*time)",
        "b_d_x": "2e-6*sin(5*time)", "b_d_y": "1e-6", "b_d_z": "-3e-6*cos(time)",
        "omega_r1": "500", "omega_r2": "520", "omega_r3": "480", "omega_r4": "450",
    }, {"noise_enabled": False, "bias_enabled": True, "sample_rate": 100.0, "mag_sample_rate": 50.0,
        "vibration_amplitude": 0.3, "b_a_x": 0.05, "A_11": 1.05, "A_12": 0.02, "A_23": -0.03, "b_s_x": 2e-6,
        "b_s_z": -1e-6}, step=1e-3, every=20, tolerance=1e-6),
}
