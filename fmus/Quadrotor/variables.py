"""Variable table of the Quadrotor FMU: rigid body of a quad-X with rotor drag, wind and rotor inertia."""

from quadcosim.fmus import vehicle as V
from quadcosim.fmus.variables import Boolean, Real, Table

_W = ("omega_r1", "omega_r2", "omega_r3", "omega_r4")
_DW = ("domega_r1", "domega_r2", "domega_r3", "domega_r4")
_WIND = ("wind_x", "wind_y", "wind_z")
_F = _W + _WIND

TABLE = Table(
    "Quadrotor",
    "Rigid-body dynamics of a quad-X multirotor with rotor drag, wind and rotor inertia; NED/FRD, quaternion attitude",
    states=13,
    variables=[
        # inputs
        *[Real(f"omega_r{n}", "input", 0.0, "rad/s", f"speed of rotor {n}") for n in range(1, 5)],
        *[Real(f"domega_r{n}", "input", 0.0, "rad/s2", f"angular acceleration of rotor {n}") for n in range(1, 5)],
        *[Real(f"wind_{a}", "input", 0.0, "m/s", f"wind velocity, {d} (NED)")
          for a, d in zip("xyz", ("north", "east", "down"), strict=True)],
        # parameters
        Real("m", "parameter", V.MASS, "kg", "mass"),
        Real("Jxx", "parameter", V.INERTIA[0], "kg.m2", "inertia about x_B"),
        Real("Jyy", "parameter", V.INERTIA[1], "kg.m2", "inertia about y_B"),
        Real("Jzz", "parameter", V.INERTIA[2], "kg.m2", "inertia about z_B"),
        Real("arm", "parameter", V.ARM, "m", "distance from the centre to a rotor axis"),
        Real("k_f", "parameter", V.THRUST_COEFF, "N.s2", "thrust coefficient, T_n = k_f omega_n^2"),
        Real("k_m", "parameter", V.DRAG_TORQUE_COEFF, "N.m.s2", "drag torque coefficient"),
        Real("k_d", "parameter", V.ROTOR_DRAG_COEFF, "kg/rad",
             "rotor drag (H-force): F_B = -k_d sum|omega_n| (v_a,x, v_a,y, 0)"),
        *[Real(f"c_D{a}", "parameter", V.PARASITIC_DRAG[k], "N.s2/m2", f"parasitic drag along {a}_B, -c |v_a| v_a")
          for k, a in enumerate("xyz")],
        Real("drag", "parameter", V.LINEAR_DRAG, "N.s/m", "optional linear drag on the airspeed, -drag v_a"),
        Real("J_r", "parameter", V.ROTOR_INERTIA, "kg.m2", "inertia of one rotor and propeller about its axis"),
        Real("g", "parameter", V.GRAVITY, "m/s2", "gravity along +z of {I}"),
        Real("k_norm", "parameter", V.QUATERNION_NORM_GAIN, "1/s", "quaternion norm-keeping gain"),
        Real("sub_step", "parameter", 1e-2, "s", "largest internal RK4 step"),
        Boolean("clamped", "parameter", False, "body held at its initial pose (rig on the ground)"),
        Real("p_x0", "parameter", 0.0, "m", "initial north position"),
        Real("p_y0", "parameter", 0.0, "m", "initial east position"),
        Real("p_z0", "parameter", 0.0, "m", "initial down position"),
        Real("v_x0", "parameter", 0.0, "m/s", "initial north velocity"),
        Real("v_y0", "parameter", 0.0, "m/s", "initial east velocity"),
        Real("v_z0", "parameter", 0.0, "m/s", "initial down velocity"),
        Real("theta1_0", "parameter", 0.0, "rad", "initial roll"),
        Real("theta2_0", "parameter", 0.0, "rad", "initial pitch"),
        Real("theta3_0", "parameter", 0.0, "rad", "initial yaw"),
        Real("omega_x0", "parameter", 0.0, "rad/s", "initial body rate about x_B"),
        Real("omega_y0", "parameter", 0.0, "rad/s", "initial body rate about y_B"),
        Real("omega_z0", "parameter", 0.0, "rad/s", "initial body rate about z_B"),
        # outputs; q, omega and f are contiguous, in the order the IMU takes them
        Real("q0", "output", unit="1", description="attitude quaternion, scalar part"),
        Real("q1", "output", unit="1", description="attitude quaternion, x"),
        Real("q2", "output", unit="1", description="attitude quaternion, y"),
        Real("q3", "output", unit="1", description="attitude quaternion, z"),
        Real("omega_x", "output", unit="rad/s", description="body rate about x_B"),
        Real("omega_y", "output", unit="rad/s", description="body rate about y_B"),
        Real("omega_z", "output", unit="rad/s", description="body rate about z_B"),
        Real("f_x", "output", unit="m/s2", description="specific force along x_B", depends=_F),
        Real("f_y", "output", unit="m/s2", description="specific force along y_B", depends=_F),
        Real("f_z", "output", unit="m/s2", description="specific force along z_B", depends=_F),
        Real("p_x", "output", unit="m", description="north position"),
        Real("p_y", "output", unit="m", description="east position"),
        Real("p_z", "output", unit="m", description="down position"),
        Real("v_x", "output", unit="m/s", description="north velocity"),
        Real("v_y", "output", unit="m/s", description="east velocity"),
        Real("v_z", "output", unit="m/s", description="down velocity"),
        Real("theta1", "output", unit="rad", description="roll (Z-Y-X Euler)"),
        Real("theta2", "output", unit="rad", description="pitch (Z-Y-X Euler)"),
        Real("theta3", "output", unit="rad", description="yaw (Z-Y-X Euler)"),
        *[
            Real(f"R{i}{j}", "output", unit="1", description=f"rotation body to NED, row {i} column {j}")
            for i in range(1, 4)
            for j in range(1, 4)
        ],
        Real("thrust", "output", unit="N", description="total rotor thrust", depends=_W),
        Real("tau_x", "output", unit="N.m", description="rotor torque about x_B", depends=_W),
        Real("tau_y", "output", unit="N.m", description="rotor torque about y_B", depends=_W),
        Real("tau_z", "output", unit="N.m", description="rotor torque about z_B, drag and spin-up reaction",
             depends=_W + _DW),
        *[Real(f"drag_{a}", "output", unit="N", description=f"aerodynamic drag force along {a}_B", depends=_F)
          for a in "xyz"],
    ],
)
