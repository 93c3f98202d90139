"""Variable table of the IMU FMU: accelerometer, gyrometer, magnetometer, and R_reel.

The defaults (noise densities, rates, the lab's gyro bias) and their sources are in
:mod:`quadcosim.fmus.vehicle`.
"""

from quadcosim.fmus import vehicle as V
from quadcosim.fmus.variables import Boolean, Integer, Real, Table

_Q = ("q0", "q1", "q2", "q3")
_W = ("omega_x", "omega_y", "omega_z")
_F = ("f_x", "f_y", "f_z")
_B = ("b_d_x", "b_d_y", "b_d_z")
_ROTORS = ("omega_r1", "omega_r2", "omega_r3", "omega_r4")
_AXES = "xyz"

GYRO_NOISE_DENSITY = V.GYRO_NOISE_DENSITY  # rad/s/sqrt(Hz)
ACC_NOISE_DENSITY = V.ACC_NOISE_DENSITY  # m/s^2/sqrt(Hz)
MAG_NOISE_DENSITY = V.MAG_NOISE_DENSITY  # T/sqrt(Hz)
LAB_GYRO_BIAS = V.LAB_GYRO_BIAS  # rad/s

TABLE = Table(
    "IMU",
    "Accelerometer and gyrometer sampled at 1 kHz, magnetometer at its own rate, with seeded white "
    "noise, biases, soft and hard iron, the field of the supply currents and optional rotor "
    "vibration; exposes the true rotation R_reel",
    variables=[
        Real("q0", "input", 1.0, "1", "true attitude quaternion, scalar part"),
        Real("q1", "input", 0.0, "1", "true attitude quaternion, x"),
        Real("q2", "input", 0.0, "1", "true attitude quaternion, y"),
        Real("q3", "input", 0.0, "1", "true attitude quaternion, z"),
        *[Real(f"omega_{a}", "input", 0.0, "rad/s", f"true body rate about {a}_B") for a in _AXES],
        Real("f_x", "input", 0.0, "m/s2", "true specific force along x_B"),
        Real("f_y", "input", 0.0, "m/s2", "true specific force along y_B"),
        Real("f_z", "input", -V.GRAVITY, "m/s2", "true specific force along z_B"),
        *[Real(f"b_d_{a}", "input", 0.0, "T", f"field of the supply currents, {a}_B") for a in _AXES],
        *[Real(f"omega_r{n}", "input", 0.0, "rad/s", f"speed of rotor {n} (for the vibration)") for n in range(1, 5)],
        # parameters
        Real("sample_rate", "parameter", V.IMU_RATE, "Hz", "sampling rate of accelerometer and gyrometer"),
        Real("mag_sample_rate", "parameter", V.MAG_RATE, "Hz", "sampling rate of the magnetometer"),
        Real("vibration_amplitude", "parameter", 0.0, "m/s2",
             "rotor-imbalance acceleration of one rotor at vibration_speed (0: off)"),
        Real("vibration_speed", "parameter", V.hover_rotor_speed(), "rad/s",
             "rotor speed at which vibration_amplitude is given; it grows as the speed squared"),
        Boolean("noise_enabled", "parameter", True, "white measurement noise on"),
        Boolean("bias_enabled", "parameter", False, "accelerometer and gyrometer biases on"),
        Integer("seed", "parameter", 1, "seed of the noise generator"),
        Real("gyro_noise_density", "parameter", GYRO_NOISE_DENSITY, "rad/s/Hz0.5", "gyro white noise density"),
        Real("acc_noise_density", "parameter", ACC_NOISE_DENSITY, "m/s2/Hz0.5", "accelerometer noise density"),
        Real("mag_noise_density", "parameter", MAG_NOISE_DENSITY, "T/Hz0.5", "magnetometer noise density"),
        Real("gyro_bias_walk", "parameter", 0.0, "rad/s2/Hz0.5", "gyro bias random walk density"),
        Real("acc_bias_walk", "parameter", 0.0, "m/s3/Hz0.5", "accelerometer bias random walk density"),
        *[Real(f"b_g_{a}", "parameter", LAB_GYRO_BIAS[k], "rad/s", f"initial gyro bias, {a}_B")
          for k, a in enumerate(_AXES)],
        *[Real(f"b_a_{a}", "parameter", 0.0, "m/s2", f"initial accelerometer bias, {a}_B") for a in _AXES],
        *[Real(f"A_{i}{j}", "parameter", 1.0 if i == j else 0.0, "1", f"soft-iron matrix, row {i} column {j}")
          for i in range(1, 4) for j in range(1, 4)],
        *[Real(f"b_s_{a}", "parameter", 0.0, "T", f"hard-iron bias, {a}_B") for a in _AXES],
        *[Real(f"m_I_{a}", "parameter", V.EARTH_FIELD[k], "T", f"Earth field in NED, {'NED'[k]}")
          for k, a in enumerate(_AXES)],
        # outputs
        *[Real(f"acc_{a}", "output", unit="m/s2", description=f"accelerometer, {a}_B", depends=_F + _ROTORS)
          for a in _AXES],
        *[Real(f"gyro_{a}", "output", unit="rad/s", description=f"gyrometer, {a}_B", depends=_W) for a in _AXES],
        *[Real(f"magneto_{a}", "output", unit="T", description=f"magnetometer, {a}_B", depends=_Q + _B)
          for a in _AXES],
        *[Real(f"R_reel_{i}{j}", "output", unit="1", description=f"true rotation body to NED, ({i},{j})",
               depends=_Q)
          for i in range(1, 4) for j in range(1, 4)],
        *[Real(f"gyro_bias_{a}", "output", unit="rad/s", description=f"true gyro bias, {a}_B") for a in _AXES],
        *[Real(f"acc_bias_{a}", "output", unit="m/s2", description=f"true accelerometer bias, {a}_B")
          for a in _AXES],
    ],
    # the sensors' outputs as arrays in FMI 3.0 (IMU.acc), as the master connects them
    arrays={"acc": "accelerometer (x, y, z)_B", "gyro": "gyrometer (x, y, z)_B",
            "magneto": "magnetometer (x, y, z)_B"},
)

# Other names a user may give a parameter vector (``--set IMU.gyro_bias=0.01,0,0``): the outputs
# ``gyro_bias_x..z`` are the true bias as it walks, the parameters ``b_g_x..z`` its initial value
ALIASES = {"gyro_bias": "b_g", "acc_bias": "b_a"}
# Parameters that act only while a Boolean switch is true (setting one while it is off is refused)
SWITCHED = {
    "noise_enabled": ("gyro_noise_density", "acc_noise_density", "mag_noise_density"),
    "bias_enabled": ("b_g", "b_a", "gyro_bias_walk", "acc_bias_walk"),
}
