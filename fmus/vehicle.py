"""The default vehicle: every physical constant of the plant, in one place, with its unit.

The FMU variable tables take their start values from here, the controller and the mixer
read the same numbers, and the README quotes them.

Sources
-------
- Airframe: a 450 mm quad-X of about 1 kg on 10x4.5 inch propellers and 2212-class
  920 KV motors (the DJI F450 class). Inertia and thrust/drag coefficients are of the order
  of published identifications of this class (Bouabdallah, "Design and control of
  quadrotors with application to autonomous flying", EPFL thesis, 2007, for the order of J;
  k_f and k_m from static thrust-stand data of 10-inch propellers).
- Rotor drag and parasitic drag: see the constants below (RotorPy; Luukkonen).
- Motor: 920 rpm/V gives k_e = 60 / (2 pi 920) V s/rad. Winding resistance and inductance
  are representative of 2212-class outrunners (0.1 ohm, 40 uH); rotor plus propeller
  inertia is that of a 10-inch propeller and bell (3e-5 kg m^2).
- Battery: 3S 2200 mAh LiPo, internal resistance 5 mohm per cell plus wiring.
- Magnetic perturbation: kappa and directions chosen so that, drone clamped and one motor
  swept over its range, the uncompensated mean angular error of the measured field is of
  the order of Table 1 of Metge, Mégret, Giremus, Berthoumieu, Mazel, "Compensation dynamique
  des perturbations magnétiques pour l'estimation d'attitude d'un micro-drone" (10.6 to 11.1
  degrees).
"""

from __future__ import annotations

import math

from quadcosim.fmus.airframe import MOTORS

GRAVITY = 9.81  # m/s^2, along +z of the NED frame {I}

# Earth magnetic field in Paris, as in the lab's attitude-estimation report, NED frame.
EARTH_FIELD_NORM = 4.7e-5  # T
EARTH_FIELD_INCLINATION = math.radians(65.0)  # rad, below the horizon
EARTH_FIELD = (
    EARTH_FIELD_NORM * math.cos(EARTH_FIELD_INCLINATION),  # T, north
    0.0,  # T, east
    EARTH_FIELD_NORM * math.sin(EARTH_FIELD_INCLINATION),  # T, down
)

# Rigid body
MASS = 1.0  # kg
MOTOR_COUNT = len(MOTORS)  # rotors, each carrying an equal share in hover
INERTIA = (0.010, 0.010, 0.018)  # kg m^2, diagonal in {B} (Jxx, Jyy, Jzz)
ARM = 0.225  # m, centre to rotor axis
THRUST_COEFF = 1.0e-5  # N/(rad/s)^2, k_f: thrust of one rotor = k_f omega^2
DRAG_TORQUE_COEFF = 1.6e-7  # N m/(rad/s)^2, k_m: reaction torque of one rotor = k_m omega^2
# Rotor drag: the H-force of blade flapping and induced drag, F_B = -k_d (sum |omega_n|) (v_a,x, v_a,y, 0)
# with v_a the airspeed in {B}. RotorPy's value for the AscTec Hummingbird (Folk, Paulos, Kumar,
# "RotorPy: a Python-based multirotor simulator with aerodynamics for education and research", 2023).
# At hover it lumps to 4 k_d omega_h = 0.24 kg/s, the 0.25 kg/s Luukkonen identifies for a 0.5 kg
# quad ("Modelling and control of quadcopter", Aalto University, 2011): drag time constant m / 0.24 = 4.2 s.
ROTOR_DRAG_COEFF = 1.19e-4  # kg/rad, k_d (N per rad/s of rotor speed per m/s of airspeed)
# Parasitic (frame) drag, F_B,i = -c_D,i |v_a| v_a,i, optional, off by default. RotorPy's Hummingbird
# uses (0.5e-2, 0.5e-2, 1e-2) N/(m/s)^2.
PARASITIC_DRAG = (0.0, 0.0, 0.0)  # N/(m/s)^2, (c_Dx, c_Dy, c_Dz) in {B}
LINEAR_DRAG = 0.0  # N s/m, optional isotropic linear drag on the airspeed, F = -D v_a (off by default)
QUATERNION_NORM_GAIN = 1.0  # 1/s, gain of the norm-keeping term of dq

# Motors and ESCs (DC-motor approximation of a brushless motor)
MOTOR_KV = 920.0  # rpm/V
MOTOR_KE = 60.0 / (2.0 * math.pi * MOTOR_KV)  # V s/rad (= N m/A)
MOTOR_RESISTANCE = 0.10  # ohm
MOTOR_INDUCTANCE = 4.0e-5  # H
ROTOR_INERTIA = 3.0e-5  # kg m^2, rotor bell plus propeller
# ESC. Free-wheeling by default: with non-complementary PWM the motor current decays through
# the free-wheeling diodes and cannot reverse, so no current returns to the battery. The
# alternative, complementary PWM (BLHeli's "damped light"), shorts the motor while the PWM is off
# and brakes regeneratively (BLHeli SiLabs manual, rev. 14; O. Duffy, "BLHeli 14.8 damped
# light and active freewheeling", 2016).
ESC_REGENERATIVE = False  # 1 (Boolean): False free-wheeling, True regenerative braking
# Motor current limit: the 18 A rating of the DJI opto ESC of the F450 class (E. Boldt,
# "DJI ESC and brushless motor", robotic-controls.com, 2013); BLHeli_S's current protection
# limits the current fast enough to act during accelerations (Turnigy Multistar BLHeli_S manual).
ESC_CURRENT_LIMIT = 18.0  # A

# Battery
BATTERY_CELLS = 3  # in series
BATTERY_CAPACITY = 2.2 * 3600.0  # A s (2200 mAh)
BATTERY_RESISTANCE = 0.02  # ohm, internal plus wiring
HOVER_SAG_ITERATIONS = 30  # fixed-point iterations of the hover command under the battery's sag
BATTERY_SOC0 = 0.9  # 1, initial state of charge
# Open-circuit voltage of one cell against state of charge s in [0, 1]:
# E_cell(s) = c0 + c1 s + c2 s^2 + c3 s^3, monotone, 4.20 V full, 3.71 V at half, 3.27 V empty.
CELL_OCV_COEFFS = (3.27, 1.53, -2.03, 1.43)  # V, V, V, V

# Magnetic field of the ESC supply cables at the magnetometer, sensor frame {B}: kappa_n times the
# supply current c_n i_n along v_n (v_n normalised by the FMU). Chosen for the rig's one-motor
# error (see Sources above): 10.5 degrees, with the free set at 17.5 degrees.
MOTOR_FIELD_GAIN = (2.78e-6, 2.40e-6, 3.15e-6, 2.63e-6)  # T/A, field per ampere of supply current
MOTOR_FIELD_DIRECTION = (
    (0.30, 0.80, -0.52),  # 1, unit-less
    (-0.55, -0.35, 0.76),  # 2, unit-less
    (0.70, -0.50, 0.51),  # 3, unit-less
    (-0.40, 0.75, 0.53),  # 4, unit-less
)


def cell_voltage(soc: float) -> float:
    """Open-circuit voltage of one cell (V) at state of charge ``soc`` (1)."""
    c0, c1, c2, c3 = CELL_OCV_COEFFS
    return c0 + soc * (c1 + soc * (c2 + soc * c3))


def hover_rotor_speed(mass: float = MASS, thrust_coeff: float = THRUST_COEFF) -> float:
    """Rotor speed (rad/s) at which four rotors carry ``mass`` (kg) with thrust coefficient ``thrust_coeff`` (N s^2)."""
    return math.sqrt(mass * GRAVITY / (MOTOR_COUNT * thrust_coeff))


def steady_current(omega: float, drag_torque_coeff: float = DRAG_TORQUE_COEFF, ke: float = MOTOR_KE) -> float:
    """Motor current (A) that holds rotor speed ``omega`` (rad/s) against propeller drag, with
    drag torque coefficient ``drag_torque_coeff`` (N m s^2) and motor constant ``ke`` (V s/rad).
    """
    return drag_torque_coeff * omega * abs(omega) / ke


def steady_command(omega, u_batt, resistance: float = MOTOR_RESISTANCE, ke: float = MOTOR_KE,
                   drag_torque_coeff: float = DRAG_TORQUE_COEFF):
    """ESC command (1) that holds rotor speed ``omega`` (rad/s) at battery voltage ``u_batt`` (V).

    The steady-state map of the DC-motor model, c u = R i + k_e omega with i = k_m omega^2 / k_e
    (``resistance`` R in ohm, ``ke`` in V s/rad, ``drag_torque_coeff`` k_m in N m s^2); it
    ignores the electrical and mechanical transients, as a command-based model does.
    """
    current = drag_torque_coeff * omega * abs(omega) / ke
    return (resistance * current + ke * omega) / u_batt


def hover_command(soc: float = BATTERY_SOC0) -> float:
    """ESC command (1) that holds hover speed at state of charge ``soc``, under hover load.

    The load sags the battery voltage, which raises the command: solved as a fixed point.
    """
    w = hover_rotor_speed()
    open_circuit = BATTERY_CELLS * cell_voltage(soc)
    u = open_circuit
    for _ in range(HOVER_SAG_ITERATIONS):
        c = steady_command(w, u)
        u = open_circuit - BATTERY_RESISTANCE * MOTOR_COUNT * c * steady_current(w)
    return c


# IMU
# Noise densities from datasheets: InvenSense MPU-9250 product specification (PS-MPU-9250A-01
# rev. 1.1) for the gyrometer (0.01 deg/s/sqrt(Hz)) and the accelerometer (300 ug/sqrt(Hz));
# ST LIS3MDL datasheet (DocID024204 rev. 5) for the magnetometer, RMS noise 3.2 mgauss at 80 Hz
# in ultra-high-performance mode, 0.32 uT / sqrt(80 Hz).
GYRO_NOISE_DENSITY = math.radians(0.01)  # rad/s/sqrt(Hz), MPU-9250
ACC_NOISE_DENSITY = 300e-6 * 9.80665  # m/s^2/sqrt(Hz), MPU-9250
MAG_NOISE_DENSITY = 0.32e-6 / math.sqrt(80.0)  # T/sqrt(Hz), LIS3MDL
LAB_GYRO_BIAS = (0.02, -0.01, 0.015)  # rad/s, the lab's gyro bias case (Bao and Yuan, lab report, 2024)
IMU_RATE = 1000.0  # Hz, accelerometer and gyrometer sampling (MPU-9250 output data rate 1 kHz)
# Magnetometers of this class run far slower: AK8963 at 100 Hz in continuous mode 2 (AK8963
# datasheet, MS1356-E-02), LIS3MDL up to 80 Hz in its low-noise modes, HMC5883L at 75 Hz.
MAG_RATE = 100.0  # Hz, magnetometer sampling, AK8963 continuous mode 2
