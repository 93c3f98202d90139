"""Variable table of the MotorMagnetics FMU (motors, ESCs, battery, field of the supply currents)."""

from quadcosim.fmus import vehicle as V
from quadcosim.fmus.variables import Boolean, Real, Table

_N = range(1, 5)

TABLE = Table(
    "MotorMagnetics",
    "Four DC-approximated brushless motors with free-wheeling or regenerative ESCs, a current limit "
    "and a LiPo battery; magnetic field of the ESCs' supply currents at the magnetometer",
    states=9,
    # each motor's field direction and field contribution, read as 4 x 3 arrays by the C model
    extra_vectors={"v": tuple(f"v{n}_{a}" for n in _N for a in "xyz"),
                   "b_d_motor": tuple(f"b_d{n}_{a}" for n in _N for a in "xyz")},
    variables=[
        *[Real(f"c{n}", "input", 0.0, "1", f"ESC command of motor {n}, saturated to [0, 1]") for n in _N],
        Boolean("regenerative", "parameter", V.ESC_REGENERATIVE,
                "ESC brakes regeneratively when the back-EMF exceeds its output (false: free-wheeling, "
                "the motor current cannot go negative)"),
        Real("i_max", "parameter", V.ESC_CURRENT_LIMIT, "A", "limit of the motor current, |i_n| <= i_max"),
        Real("R_m", "parameter", V.MOTOR_RESISTANCE, "Ohm", "winding resistance"),
        Real("L_m", "parameter", V.MOTOR_INDUCTANCE, "H", "winding inductance"),
        Real("k_e", "parameter", V.MOTOR_KE, "V.s/rad", "back-EMF and torque constant"),
        Real("J_r", "parameter", V.ROTOR_INERTIA, "kg.m2", "rotor and propeller inertia"),
        Real("k_m", "parameter", V.DRAG_TORQUE_COEFF, "N.m.s2", "propeller drag torque coefficient"),
        Real("n_cells", "parameter", float(V.BATTERY_CELLS), "1", "LiPo cells in series"),
        Real("capacity", "parameter", V.BATTERY_CAPACITY, "A.s", "battery capacity"),
        Real("R_b", "parameter", V.BATTERY_RESISTANCE, "Ohm", "battery internal resistance"),
        Real("soc0", "parameter", V.BATTERY_SOC0, "1", "initial state of charge"),
        *[Real(f"ocv{k}", "parameter", c, "V", f"cell open-circuit voltage, coefficient of soc^{k}")
          for k, c in enumerate(V.CELL_OCV_COEFFS)],
        *[Real(f"kappa{n}", "parameter", V.MOTOR_FIELD_GAIN[n - 1], "T/A", f"field per ampere of supply current of ESC {n}")
          for n in _N],
        *[Real(f"v{n}_{a}", "parameter", V.MOTOR_FIELD_DIRECTION[n - 1][k], "1",
               f"direction of the field of ESC {n}'s supply cable, {a} component (normalised)")
          for n in _N for k, a in enumerate("xyz")],
        Real("omega0", "parameter", 0.0, "rad/s", "initial speed of every rotor, at its steady current"),
        Real("sub_step", "parameter", 2.5e-4, "s", "largest internal step of the exponential integrator"),
        # outputs
        *[Real(f"omega_r{n}", "output", unit="rad/s", description=f"speed of rotor {n}") for n in _N],
        *[Real(f"domega_r{n}", "output", unit="rad/s2", description=f"angular acceleration of rotor {n}")
          for n in _N],
        *[Real(f"b_d_{a}", "output", unit="T", description=f"field of the supply currents at the magnetometer, {a}_B")
          for a in "xyz"],
        Real("u_batt", "output", unit="V", description="battery terminal voltage"),
        *[Real(f"i{n}", "output", unit="A", description=f"current of motor {n}") for n in _N],
        *[Real(f"i_s{n}", "output", unit="A", description=f"supply (input) current of ESC {n}, c{n} i{n}") for n in _N],
        Real("i_batt", "output", unit="A", description="battery current, the sum of the supply currents"),
        Real("soc", "output", unit="1", description="battery state of charge"),
        *[Real(f"b_d{n}_{a}", "output", unit="T", description=f"field of ESC {n}'s supply current alone, {a}_B")
          for n in _N for a in "xyz"],
    ],
)
