within QuadCoSim;
model Quadrotor "Rigid-body dynamics of a quad-X multirotor with rotor drag, wind and rotor inertia, NED/FRD"
  input Real omega_r1(unit = "rad/s") = 0 "speed of rotor 1 (front-right, CCW)";
  input Real omega_r2(unit = "rad/s") = 0 "speed of rotor 2 (rear-left, CCW)";
  input Real omega_r3(unit = "rad/s") = 0 "speed of rotor 3 (front-left, CW)";
  input Real omega_r4(unit = "rad/s") = 0 "speed of rotor 4 (rear-right, CW)";
  input Real domega_r1(unit = "rad/s2") = 0 "angular acceleration of rotor 1";
  input Real domega_r2(unit = "rad/s2") = 0 "angular acceleration of rotor 2";
  input Real domega_r3(unit = "rad/s2") = 0 "angular acceleration of rotor 3";
  input Real domega_r4(unit = "rad/s2") = 0 "angular acceleration of rotor 4";
  input Real wind_x(unit = "m/s") = 0 "wind velocity, north";
  input Real wind_y(unit = "m/s") = 0 "wind velocity, east";
  input Real wind_z(unit = "m/s") = 0 "wind velocity, down";

  parameter Real m(unit = "kg") = 1.0 "mass";
  parameter Real Jxx(unit = "kg.m2") = 0.010 "inertia about x_B";
  parameter Real Jyy(unit = "kg.m2") = 0.010 "inertia about y_B";
  parameter Real Jzz(unit = "kg.m2") = 0.018 "inertia about z_B";
  parameter Real arm(unit = "m") = 0.225 "distance from the centre to a rotor axis";
  parameter Real k_f(unit = "N.s2") = 1.0e-5 "thrust coefficient";
  parameter Real k_m(unit = "N.m.s2") = 1.6e-7 "drag torque coefficient";
  parameter Real k_d(unit = "kg/rad") = 1.19e-4 "rotor drag (H-force) coefficient";
  parameter Real c_Dx(unit = "N.s2/m2") = 0 "parasitic drag along x_B";
  parameter Real c_Dy(unit = "N.s2/m2") = 0 "parasitic drag along y_B";
  parameter Real c_Dz(unit = "N.s2/m2") = 0 "parasitic drag along z_B";
  parameter Real drag(unit = "N.s/m") = 0 "optional linear drag on the airspeed";
  parameter Real J_r(unit = "kg.m2") = 3.0e-5 "inertia of one rotor and propeller";
  parameter Real g(unit = "m/s2") = 9.81 "gravity along +z of the NED frame";
  parameter Real k_norm(unit = "1/s") = 1.0 "quaternion norm-keeping gain";
  parameter Boolean clamped = false "body held at its initial pose";
  parameter Real p_x0(unit = "m") = 0 "initial north position";
  parameter Real p_y0(unit = "m") = 0 "initial east position";
  parameter Real p_z0(unit = "m") = 0 "initial down position";
  parameter Real v_x0(unit = "m/s") = 0 "initial north velocity";
  parameter Real v_y0(unit = "m/s") = 0 "initial east velocity";
  parameter Real v_z0(unit = "m/s") = 0 "initial down velocity";
  parameter Real theta1_0(unit = "rad") = 0 "initial roll";
  parameter Real theta2_0(unit = "rad") = 0 "initial pitch";
  parameter Real theta3_0(unit = "rad") = 0 "initial yaw";
  parameter Real omega_x0(unit = "rad/s") = 0 "initial body rate about x_B";
  parameter Real omega_y0(unit = "rad/s") = 0 "initial body rate about y_B";
  parameter Real omega_z0(unit = "rad/s") = 0 "initial body rate about z_B";

  output Real q0(start = cos(theta3_0/2)*cos(theta2_0/2)*cos(theta1_0/2) + sin(theta3_0/2)*sin(theta2_0/2)*sin(theta1_0/2), fixed = true);
  output Real q1(start = cos(theta3_0/2)*cos(theta2_0/2)*sin(theta1_0/2) - sin(theta3_0/2)*sin(theta2_0/2)*cos(theta1_0/2), fixed = true);
  output Real q2(start = cos(theta3_0/2)*sin(theta2_0/2)*cos(theta1_0/2) + sin(theta3_0/2)*cos(theta2_0/2)*sin(theta1_0/2), fixed = true);
  output Real q3(start = sin(theta3_0/2)*cos(theta2_0/2)*cos(theta1_0/2) - cos(theta3_0/2)*sin(theta2_0/2)*sin(theta1_0/2), fixed = true);
  output Real omega_x(unit = "rad/s", start = if clamped then 0 else omega_x0, fixed = true);
  output Real omega_y(unit = "rad/s", start = if clamped then 0 else omega_y0, fixed = true);
  output Real omega_z(unit = "rad/s", start = if clamped then 0 else omega_z0, fixed = true);
  output Real f_x(unit = "m/s2") "specific force along x_B";
  output Real f_y(unit = "m/s2") "specific force along y_B";
  output Real f_z(unit = "m/s2") "specific force along z_B";
  output Real p_x(unit = "m", start = p_x0, fixed = true);
  output Real p_y(unit = "m", start = p_y0, fixed = true);
  output Real p_z(unit = "m", start = p_z0, fixed = true);
  output Real v_x(unit = "m/s", start = if clamped then 0 else v_x0, fixed = true);
  output Real v_y(unit = "m/s", start = if clamped then 0 else v_y0, fixed = true);
  output Real v_z(unit = "m/s", start = if clamped then 0 else v_z0, fixed = true);
  output Real theta1(unit = "rad") "roll";
  output Real theta2(unit = "rad") "pitch";
  output Real theta3(unit = "rad") "yaw";
  output Real R11;
  output Real R12;
  output Real R13;
  output Real R21;
  output Real R22;
  output Real R23;
  output Real R31;
  output Real R32;
  output Real R33;
  output Real thrust(unit = "N") "total rotor thrust";
  output Real tau_x(unit = "N.m");
  output Real tau_y(unit = "N.m");
  output Real tau_z(unit = "N.m") "drag torque and spin-up reaction of the rotors";
  output Real drag_x(unit = "N") "aerodynamic drag along x_B";
  output Real drag_y(unit = "N") "aerodynamic drag along y_B";
  output Real drag_z(unit = "N") "aerodynamic drag along z_B";
protected
  parameter Real c45 = sqrt(0.5) "arms at 45 degrees";
  Real T1, T2, T3, T4 "rotor thrusts";
  Real a_x, a_y, a_z "acceleration in NED";
  Real norm_error "k_norm (1 - |q|^2)";
  Real va_x, va_y, va_z "airspeed in the body frame";
  Real airspeed;
  Real h_r "sum of s_n omega_n; the rotors' angular momentum is -J_r h_r e3";
  Real F_x, F_y, F_z "drag force in the body frame";
equation
  T1 = k_f*omega_r1^2;
  T2 = k_f*omega_r2^2;
  T3 = k_f*omega_r3^2;
  T4 = k_f*omega_r4^2;
  thrust = T1 + T2 + T3 + T4;
  tau_x = arm*c45*(-T1 + T2 + T3 - T4);
  tau_y = arm*c45*(T1 - T2 + T3 - T4);
  // rotors 1, 2 counter-clockwise (s = +1), 3, 4 clockwise (s = -1), seen from above
  tau_z = k_m*(omega_r1^2 + omega_r2^2 - omega_r3^2 - omega_r4^2)
    + J_r*(domega_r1 + domega_r2 - domega_r3 - domega_r4);
  h_r = omega_r1 + omega_r2 - omega_r3 - omega_r4;

  R11 = 1 - 2*(q2^2 + q3^2);
  R12 = 2*(q1*q2 - q0*q3);
  R13 = 2*(q1*q3 + q0*q2);
  R21 = 2*(q1*q2 + q0*q3);
  R22 = 1 - 2*(q1^2 + q3^2);
  R23 = 2*(q2*q3 - q0*q1);
  R31 = 2*(q1*q3 - q0*q2);
  R32 = 2*(q2*q3 + q0*q1);
  R33 = 1 - 2*(q1^2 + q2^2);

  // airspeed in {B}: R^T (v - wind)
  va_x = R11*(v_x - wind_x) + R21*(v_y - wind_y) + R31*(v_z - wind_z);
  va_y = R12*(v_x - wind_x) + R22*(v_y - wind_y) + R32*(v_z - wind_z);
  va_z = R13*(v_x - wind_x) + R23*(v_y - wind_y) + R33*(v_z - wind_z);
  // skipped when unused: the toolchain differentiates sqrt, infinite at zero airspeed
  airspeed = if clamped or c_Dx + c_Dy + c_Dz <= 0 then 0 else sqrt(va_x^2 + va_y^2 + va_z^2);
  F_x = -k_d*(abs(omega_r1) + abs(omega_r2) + abs(omega_r3) + abs(omega_r4))*va_x - c_Dx*airspeed*va_x - drag*va_x;
  F_y = -k_d*(abs(omega_r1) + abs(omega_r2) + abs(omega_r3) + abs(omega_r4))*va_y - c_Dy*airspeed*va_y - drag*va_y;
  F_z = -c_Dz*airspeed*va_z - drag*va_z;
  drag_x = if clamped then 0 else F_x;
  drag_y = if clamped then 0 else F_y;
  drag_z = if clamped then 0 else F_z;
  a_x = if clamped then 0 else (R11*F_x + R12*F_y + R13*(F_z - thrust))/m;
  a_y = if clamped then 0 else (R21*F_x + R22*F_y + R23*(F_z - thrust))/m;
  a_z = if clamped then 0 else g + (R31*F_x + R32*F_y + R33*(F_z - thrust))/m;
  der(p_x) = if clamped then 0 else v_x;
  der(p_y) = if clamped then 0 else v_y;
  der(p_z) = if clamped then 0 else v_z;
  der(v_x) = a_x;
  der(v_y) = a_y;
  der(v_z) = a_z;

  norm_error = k_norm*(1 - (q0^2 + q1^2 + q2^2 + q3^2));
  der(q0) = if clamped then 0 else 0.5*(-q1*omega_x - q2*omega_y - q3*omega_z) + norm_error*q0;
  der(q1) = if clamped then 0 else 0.5*(q0*omega_x + q2*omega_z - q3*omega_y) + norm_error*q1;
  der(q2) = if clamped then 0 else 0.5*(q0*omega_y + q3*omega_x - q1*omega_z) + norm_error*q2;
  der(q3) = if clamped then 0 else 0.5*(q0*omega_z + q1*omega_y - q2*omega_x) + norm_error*q3;
  // gyroscopic moment of the rotors: -omega x (-J_r h_r e3) = J_r h_r (omega_y, -omega_x, 0)
  der(omega_x) = if clamped then 0 else (tau_x + J_r*h_r*omega_y - (Jzz - Jyy)*omega_y*omega_z)/Jxx;
  der(omega_y) = if clamped then 0 else (tau_y - J_r*h_r*omega_x - (Jxx - Jzz)*omega_z*omega_x)/Jyy;
  der(omega_z) = if clamped then 0 else (tau_z - (Jyy - Jxx)*omega_x*omega_y)/Jzz;

  // specific force f_B = R^T (dv - g e3)
  f_x = R11*a_x + R21*a_y + R31*(a_z - g);
  f_y = R12*a_x + R22*a_y + R32*(a_z - g);
  f_z = R13*a_x + R23*a_y + R33*(a_z - g);

  theta1 = atan2(R32, R33);
  theta2 = -asin(R31);
  theta3 = atan2(R21, R11);
end Quadrotor;
