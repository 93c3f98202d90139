within QuadCoSim;
model IMU "Accelerometer and gyrometer at sample_rate, magnetometer at mag_sample_rate; exposes the true rotation R_reel"
  // White noise and the bias random walk live in the FMU only: a seeded counter-based
  // generator has no equation-based form. With noise_enabled = false and zero bias walks
  // the FMU and this twin compute the same samples.
  input Real q0 = 1 "true attitude quaternion";
  input Real q1 = 0 "true attitude quaternion";
  input Real q2 = 0 "true attitude quaternion";
  input Real q3 = 0 "true attitude quaternion";
  input Real omega_x(unit = "rad/s") = 0 "true body rate";
  input Real omega_y(unit = "rad/s") = 0 "true body rate";
  input Real omega_z(unit = "rad/s") = 0 "true body rate";
  input Real f_x(unit = "m/s2") = 0 "true specific force";
  input Real f_y(unit = "m/s2") = 0 "true specific force";
  input Real f_z(unit = "m/s2") = -9.81 "true specific force";
  input Real b_d_x(unit = "T") = 0 "field of the motor currents";
  input Real b_d_y(unit = "T") = 0 "field of the motor currents";
  input Real b_d_z(unit = "T") = 0 "field of the motor currents";
  input Real omega_r1(unit = "rad/s") = 0 "speed of rotor 1 (CCW seen from above)";
  input Real omega_r2(unit = "rad/s") = 0 "speed of rotor 2 (CCW)";
  input Real omega_r3(unit = "rad/s") = 0 "speed of rotor 3 (CW)";
  input Real omega_r4(unit = "rad/s") = 0 "speed of rotor 4 (CW)";
  parameter Real sample_rate(unit = "Hz") = 1000 "sampling rate of accelerometer and gyrometer";
  parameter Real mag_sample_rate(unit = "Hz") = 100 "sampling rate of the magnetometer";
  parameter Real vibration_amplitude(unit = "m/s2") = 0 "rotor-imbalance acceleration of one rotor at vibration_speed";
  parameter Real vibration_speed(unit = "rad/s") = 495.22722057657535 "rotor speed of vibration_amplitude";
  parameter Boolean noise_enabled = true "white noise; drawn by the FMU only, no effect here";
  parameter Boolean bias_enabled = false "accelerometer and gyrometer biases on";
  parameter Real b_g_x(unit = "rad/s") = 0.02 "gyro bias";
  parameter Real b_g_y(unit = "rad/s") = -0.01 "gyro bias";
  parameter Real b_g_z(unit = "rad/s") = 0.015 "gyro bias";
  parameter Real b_a_x(unit = "m/s2") = 0 "accelerometer bias";
  parameter Real b_a_y(unit = "m/s2") = 0 "accelerometer bias";
  parameter Real b_a_z(unit = "m/s2") = 0 "accelerometer bias";
  parameter Real A_11 = 1 "soft-iron matrix";
  parameter Real A_12 = 0 "soft-iron matrix";
  parameter Real A_13 = 0 "soft-iron matrix";
  parameter Real A_21 = 0 "soft-iron matrix";
  parameter Real A_22 = 1 "soft-iron matrix";
  parameter Real A_23 = 0 "soft-iron matrix";
  parameter Real A_31 = 0 "soft-iron matrix";
  parameter Real A_32 = 0 "soft-iron matrix";
  parameter Real A_33 = 1 "soft-iron matrix";
  parameter Real b_s_x(unit = "T") = 0 "hard-iron bias";
  parameter Real b_s_y(unit = "T") = 0 "hard-iron bias";
  parameter Real b_s_z(unit = "T") = 0 "hard-iron bias";
  parameter Real m_I_x(unit = "T") = 4.7e-5*cos(65*3.141592653589793/180) "Earth field, north";
  parameter Real m_I_y(unit = "T") = 0 "Earth field, east";
  parameter Real m_I_z(unit = "T") = 4.7e-5*sin(65*3.141592653589793/180) "Earth field, down";
  discrete output Real acc_x(start = 0, fixed = true);
  discrete output Real acc_y(start = 0, fixed = true);
  discrete output Real acc_z(start = 0, fixed = true);
  discrete output Real gyro_x(start = 0, fixed = true);
  discrete output Real gyro_y(start = 0, fixed = true);
  discrete output Real gyro_z(start = 0, fixed = true);
  discrete output Real magneto_x(start = 0, fixed = true);
  discrete output Real magneto_y(start = 0, fixed = true);
  discrete output Real magneto_z(start = 0, fixed = true);
  discrete output Real R_reel_11(start = 0, fixed = true);
  discrete output Real R_reel_12(start = 0, fixed = true);
  discrete output Real R_reel_13(start = 0, fixed = true);
  discrete output Real R_reel_21(start = 0, fixed = true);
  discrete output Real R_reel_22(start = 0, fixed = true);
  discrete output Real R_reel_23(start = 0, fixed = true);
  discrete output Real R_reel_31(start = 0, fixed = true);
  discrete output Real R_reel_32(start = 0, fixed = true);
  discrete output Real R_reel_33(start = 0, fixed = true);
  discrete output Real gyro_bias_x(start = 0, fixed = true);
  discrete output Real gyro_bias_y(start = 0, fixed = true);
  discrete output Real gyro_bias_z(start = 0, fixed = true);
  discrete output Real acc_bias_x(start = 0, fixed = true);
  discrete output Real acc_bias_y(start = 0, fixed = true);
  discrete output Real acc_bias_z(start = 0, fixed = true);
protected
  // sample instants k / rate from integer counts, not by adding 1 / rate: no drift against the
  // FMU's instants
  discrete Real t_next(start = 0, fixed = true) "next sample instant of accelerometer and gyrometer";
  discrete Real t_next_mag(start = 0, fixed = true) "next sample instant of the magnetometer";
  discrete Real n_next(start = 0, fixed = true) "count of accelerometer and gyrometer samples";
  discrete Real n_next_mag(start = 0, fixed = true) "count of magnetometer samples";
  Real phi1(start = 0, fixed = true), phi2(start = 0, fixed = true) "rotor angles";
  Real phi3(start = 0, fixed = true), phi4(start = 0, fixed = true) "rotor angles";
  parameter Real vib = vibration_amplitude/vibration_speed^2;
  Real R11, R12, R13, R21, R22, R23, R31, R32, R33 "R(q), body to NED";
  Real mb_x, mb_y, mb_z "Earth field in the body frame, R^T m_I";
equation
  R11 = 1 - 2*(q2^2 + q3^2);
  R12 = 2*(q1*q2 - q0*q3);
  R13 = 2*(q1*q3 + q0*q2);
  R21 = 2*(q1*q2 + q0*q3);
  R22 = 1 - 2*(q1^2 + q3^2);
  R23 = 2*(q2*q3 - q0*q1);
  R31 = 2*(q1*q3 - q0*q2);
  R32 = 2*(q2*q3 + q0*q1);
  R33 = 1 - 2*(q1^2 + q2^2);
  mb_x = R11*m_I_x + R21*m_I_y + R31*m_I_z;
  mb_y = R12*m_I_x + R22*m_I_y + R32*m_I_z;
  mb_z = R13*m_I_x + R23*m_I_y + R33*m_I_z;
  der(phi1) = omega_r1;
  der(phi2) = omega_r2;
  der(phi3) = omega_r3;
  der(phi4) = omega_r4;
  when time >= t_next then
    n_next = pre(n_next) + 1;
    t_next = n_next/sample_rate;
    // each rotor's imbalance turns with it: (cos phi, -s sin phi), s = +1, +1, -1, -1
    acc_x = f_x + (if bias_enabled then b_a_x else 0) + vib*(omega_r1^2*cos(phi1)
      + omega_r2^2*cos(phi2) + omega_r3^2*cos(phi3) + omega_r4^2*cos(phi4));
    acc_y = f_y + (if bias_enabled then b_a_y else 0) + vib*(-omega_r1^2*sin(phi1)
      - omega_r2^2*sin(phi2) + omega_r3^2*sin(phi3) + omega_r4^2*sin(phi4));
    acc_z = f_z + (if bias_enabled then b_a_z else 0);
    gyro_x = omega_x + (if bias_enabled then b_g_x else 0);
    gyro_y = omega_y + (if bias_enabled then b_g_y else 0);
    gyro_z = omega_z + (if bias_enabled then b_g_z else 0);
    R_reel_11 = R11;
    R_reel_12 = R12;
    R_reel_13 = R13;
    R_reel_21 = R21;
    R_reel_22 = R22;
    R_reel_23 = R23;
    R_reel_31 = R31;
    R_reel_32 = R32;
    R_reel_33 = R33;
    gyro_bias_x = if bias_enabled then b_g_x else 0;
    gyro_bias_y = if bias_enabled then b_g_y else 0;
    gyro_bias_z = if bias_enabled then b_g_z else 0;
    acc_bias_x = if bias_enabled then b_a_x else 0;
    acc_bias_y = if bias_enabled then b_a_y else 0;
    acc_bias_z = if bias_enabled then b_a_z else 0;
  end when;
  when time >= t_next_mag then
    n_next_mag = pre(n_next_mag) + 1;
    t_next_mag = n_next_mag/mag_sample_rate;
    magneto_x = A_11*mb_x + A_12*mb_y + A_13*mb_z + b_s_x + b_d_x;
    magneto_y = A_21*mb_x + A_22*mb_y + A_23*mb_z + b_s_y + b_d_y;
    magneto_z = A_31*mb_x + A_32*mb_y + A_33*mb_z + b_s_z + b_d_z;
  end when;
end IMU;
