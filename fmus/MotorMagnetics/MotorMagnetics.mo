within QuadCoSim;
model MotorMagnetics "Four DC-approximated brushless motors, ESCs with a current limit, LiPo battery, field of the supply currents"
  // The ESC's averaged model: it applies c_n u_batt to its motor and draws i_s,n = c_n i_n from
  // the battery. Free-wheeling (regenerative = false): a motor current that falls to zero while
  // the back-EMF exceeds c_n u_batt stays there, the rotor coasts. Regenerative braking: the
  // current reverses, down to -i_max. The limit holds |i_n| <= i_max. The FMU locates each of
  // these switches exactly; here they are the solver's state events.
  input Real c1 = 0 "ESC command of motor 1, saturated to [0, 1]";
  input Real c2 = 0 "ESC command of motor 2";
  input Real c3 = 0 "ESC command of motor 3";
  input Real c4 = 0 "ESC command of motor 4";

  parameter Boolean regenerative = false "ESC brakes regeneratively (false: free-wheeling)";
  parameter Real i_max(unit = "A") = 18.0 "limit of the motor current";
  parameter Real R_m(unit = "Ohm") = 0.10 "winding resistance";
  parameter Real L_m(unit = "H") = 4.0e-5 "winding inductance";
  parameter Real k_e(unit = "V.s/rad") = 60/(2*3.141592653589793*920) "back-EMF constant (920 KV)";
  parameter Real J_r(unit = "kg.m2") = 3.0e-5 "rotor and propeller inertia";
  parameter Real k_m(unit = "N.m.s2") = 1.6e-7 "propeller drag torque coefficient";
  parameter Real n_cells = 3 "LiPo cells in series";
  parameter Real capacity(unit = "A.s") = 7920 "battery capacity (2200 mAh)";
  parameter Real R_b(unit = "Ohm") = 0.02 "battery internal resistance";
  parameter Real soc0 = 0.9 "initial state of charge";
  parameter Real ocv0(unit = "V") = 3.27 "cell open-circuit voltage, constant term";
  parameter Real ocv1(unit = "V") = 1.53 "cell open-circuit voltage, soc term";
  parameter Real ocv2(unit = "V") = -2.03 "cell open-circuit voltage, soc^2 term";
  parameter Real ocv3(unit = "V") = 1.43 "cell open-circuit voltage, soc^3 term";
  parameter Real kappa1(unit = "T/A") = 2.78e-6 "field per ampere of supply current of ESC 1";
  parameter Real kappa2(unit = "T/A") = 2.40e-6 "field per ampere of supply current of ESC 2";
  parameter Real kappa3(unit = "T/A") = 3.15e-6 "field per ampere of supply current of ESC 3";
  parameter Real kappa4(unit = "T/A") = 2.63e-6 "field per ampere of supply current of ESC 4";
  parameter Real v1_x = 0.30;
  parameter Real v1_y = 0.80;
  parameter Real v1_z = -0.52;
  parameter Real v2_x = -0.55;
  parameter Real v2_y = -0.35;
  parameter Real v2_z = 0.76;
  parameter Real v3_x = 0.70;
  parameter Real v3_y = -0.50;
  parameter Real v3_z = 0.51;
  parameter Real v4_x = -0.40;
  parameter Real v4_y = 0.75;
  parameter Real v4_z = 0.53;
  parameter Real omega0(unit = "rad/s") = 0 "initial speed of every rotor, at its steady current";

  output Real omega_r1(unit = "rad/s", start = omega0, fixed = true);
  output Real omega_r2(unit = "rad/s", start = omega0, fixed = true);
  output Real omega_r3(unit = "rad/s", start = omega0, fixed = true);
  output Real omega_r4(unit = "rad/s", start = omega0, fixed = true);
  output Real domega_r1(unit = "rad/s2") "angular acceleration of rotor 1";
  output Real domega_r2(unit = "rad/s2") "angular acceleration of rotor 2";
  output Real domega_r3(unit = "rad/s2") "angular acceleration of rotor 3";
  output Real domega_r4(unit = "rad/s2") "angular acceleration of rotor 4";
  output Real b_d_x(unit = "T");
  output Real b_d_y(unit = "T");
  output Real b_d_z(unit = "T");
  output Real u_batt(unit = "V") "battery terminal voltage";
  output Real i1(unit = "A", start = k_m*omega0*abs(omega0)/k_e, fixed = true);
  output Real i2(unit = "A", start = k_m*omega0*abs(omega0)/k_e, fixed = true);
  output Real i3(unit = "A", start = k_m*omega0*abs(omega0)/k_e, fixed = true);
  output Real i4(unit = "A", start = k_m*omega0*abs(omega0)/k_e, fixed = true);
  output Real i_s1(unit = "A") "supply current of ESC 1";
  output Real i_s2(unit = "A") "supply current of ESC 2";
  output Real i_s3(unit = "A") "supply current of ESC 3";
  output Real i_s4(unit = "A") "supply current of ESC 4";
  output Real i_batt(unit = "A") "battery current, the sum of the supply currents";
  output Real soc(start = soc0, fixed = true) "state of charge";
  output Real b_d1_x, b_d1_y, b_d1_z, b_d2_x, b_d2_y, b_d2_z;
  output Real b_d3_x, b_d3_y, b_d3_z, b_d4_x, b_d4_y, b_d4_z;
protected
  Real c1s, c2s, c3s, c4s "saturated commands";
  Real drive1, drive2, drive3, drive4 "c_n u_batt - k_e omega_n";
  parameter Real low = if regenerative then -i_max else 0 "lower bound of the motor currents";
  parameter Real n1 = sqrt(v1_x^2 + v1_y^2 + v1_z^2);
  parameter Real n2 = sqrt(v2_x^2 + v2_y^2 + v2_z^2);
  parameter Real n3 = sqrt(v3_x^2 + v3_y^2 + v3_z^2);
  parameter Real n4 = sqrt(v4_x^2 + v4_y^2 + v4_z^2);
equation
  c1s = min(max(c1, 0), 1);
  c2s = min(max(c2, 0), 1);
  c3s = min(max(c3, 0), 1);
  c4s = min(max(c4, 0), 1);
  i_s1 = c1s*i1;
  i_s2 = c2s*i2;
  i_s3 = c3s*i3;
  i_s4 = c4s*i4;
  i_batt = i_s1 + i_s2 + i_s3 + i_s4;
  u_batt = n_cells*(ocv0 + soc*(ocv1 + soc*(ocv2 + soc*ocv3))) - R_b*i_batt;
  der(soc) = -i_batt/capacity;

  drive1 = c1s*u_batt - k_e*omega_r1;
  drive2 = c2s*u_batt - k_e*omega_r2;
  drive3 = c3s*u_batt - k_e*omega_r3;
  drive4 = c4s*u_batt - k_e*omega_r4;
  der(i1) = if (i1 <= low and drive1 - R_m*low <= 0) or (i1 >= i_max and drive1 - R_m*i_max >= 0)
    then 0 else (drive1 - R_m*i1)/L_m;
  der(i2) = if (i2 <= low and drive2 - R_m*low <= 0) or (i2 >= i_max and drive2 - R_m*i_max >= 0)
    then 0 else (drive2 - R_m*i2)/L_m;
  der(i3) = if (i3 <= low and drive3 - R_m*low <= 0) or (i3 >= i_max and drive3 - R_m*i_max >= 0)
    then 0 else (drive3 - R_m*i3)/L_m;
  der(i4) = if (i4 <= low and drive4 - R_m*low <= 0) or (i4 >= i_max and drive4 - R_m*i_max >= 0)
    then 0 else (drive4 - R_m*i4)/L_m;
  J_r*domega_r1 = k_e*i1 - k_m*omega_r1*abs(omega_r1);
  J_r*domega_r2 = k_e*i2 - k_m*omega_r2*abs(omega_r2);
  J_r*domega_r3 = k_e*i3 - k_m*omega_r3*abs(omega_r3);
  J_r*domega_r4 = k_e*i4 - k_m*omega_r4*abs(omega_r4);
  der(omega_r1) = domega_r1;
  der(omega_r2) = domega_r2;
  der(omega_r3) = domega_r3;
  der(omega_r4) = domega_r4;

  b_d1_x = kappa1*i_s1*v1_x/n1;
  b_d1_y = kappa1*i_s1*v1_y/n1;
  b_d1_z = kappa1*i_s1*v1_z/n1;
  b_d2_x = kappa2*i_s2*v2_x/n2;
  b_d2_y = kappa2*i_s2*v2_y/n2;
  b_d2_z = kappa2*i_s2*v2_z/n2;
  b_d3_x = kappa3*i_s3*v3_x/n3;
  b_d3_y = kappa3*i_s3*v3_y/n3;
  b_d3_z = kappa3*i_s3*v3_z/n3;
  b_d4_x = kappa4*i_s4*v4_x/n4;
  b_d4_y = kappa4*i_s4*v4_y/n4;
  b_d4_z = kappa4*i_s4*v4_z/n4;
  b_d_x = b_d1_x + b_d2_x + b_d3_x + b_d4_x;
  b_d_y = b_d1_y + b_d2_y + b_d3_y + b_d4_y;
  b_d_z = b_d1_z + b_d2_z + b_d3_z + b_d4_z;
end MotorMagnetics;
