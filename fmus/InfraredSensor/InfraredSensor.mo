within QuadCoSim;
model InfraredSensor "Fixed-wing in coordinated turns, infrared horizon sensor with drifting a and b, late GPS turn rate"
  // Measurement noise (infrared count noise, GPS course noise) lives in the FMU only: a seeded
  // counter-based generator has no equation-based form. With noise_enabled = false the FMU and
  // this twin compute the same samples.
  // The GPS heading history is a register of 41 samples written out in scalar form: this twin
  // covers sample_rate = 20 Hz, gps_delay = 1 s and gps_window = 1 s (20 samples each), the
  // defaults; the FMU takes any whole number of samples.
  input Real phi(unit = "rad") = 0 "bank angle, |phi| < pi/2";
  parameter Real sample_rate(unit = "Hz") = 20 "sampling rate of the infrared and GPS outputs";
  parameter Real airspeed(unit = "m/s") = 12 "true airspeed V";
  parameter Real gravity(unit = "m/s2") = 9.81 "gravity g";
  parameter Real psi0(unit = "rad") = 0 "initial heading";
  parameter Real ir_gain(unit = "s/rad") = -410 "a at t = 0";
  parameter Real ir_offset = 933 "b at t = 0 (count)";
  parameter Boolean drift_enabled = true "a and b drift with time of day, temperature and cloud";
  parameter Real gain_day_rate(unit = "1/s") = -0.25/3600 "time of day: relative change of a per second";
  parameter Real offset_day_rate(unit = "1/s") = 500/3600 "time of day: change of b per second (count/s)";
  parameter Real gain_temperature = 0.02 "temperature: relative amplitude on a";
  parameter Real offset_temperature = 10 "temperature: amplitude on b";
  parameter Real temperature_period(unit = "s") = 600 "temperature: period";
  parameter Real cloud_start(unit = "s") = 170 "cloud: entry time";
  parameter Real cloud_duration(unit = "s") = 70 "cloud: time under full cover";
  parameter Real cloud_ramp(unit = "s") = 15 "cloud: time to enter or leave full cover";
  parameter Real gain_cloud = -0.08 "cloud: relative change of a under full cover";
  parameter Real offset_cloud = 70 "cloud: change of b under full cover";
  parameter Real gps_window(unit = "s") = 1 "GPS turn rate: heading difference over this time";
  parameter Real gps_delay(unit = "s") = 1 "GPS turn rate: delivered this late";
  parameter Boolean noise_enabled = true "measurement noise; drawn by the FMU only, no effect here";
  output Real r(unit = "rad/s") "true turn rate g tan(phi) / V";
  output Real psi(unit = "rad", start = psi0, fixed = true) "true heading";
  output Real a(unit = "s/rad") "true infrared gain";
  output Real b "true infrared offset (count)";
  discrete output Real ir(start = 0, fixed = true) "infrared reading, sampled (count)";
  discrete output Real gps_turn_rate(unit = "rad/s", start = 0, fixed = true) "GPS turn rate, sampled";
  discrete output Real gps_valid(start = 0, fixed = true) "1 once the heading history covers the window";
protected
  discrete Real t_next(start = 0, fixed = true) "next sample instant";
  discrete Real n(start = 0, fixed = true) "samples taken";
  discrete Real h0(start = 0, fixed = true), h1(start = 0, fixed = true), h2(start = 0, fixed = true), h3(start = 0, fixed = true), h4(start = 0, fixed = true), h5(start = 0, fixed = true);
  discrete Real h6(start = 0, fixed = true), h7(start = 0, fixed = true), h8(start = 0, fixed = true), h9(start = 0, fixed = true), h10(start = 0, fixed = true), h11(start = 0, fixed = true);
  discrete Real h12(start = 0, fixed = true), h13(start = 0, fixed = true), h14(start = 0, fixed = true), h15(start = 0, fixed = true), h16(start = 0, fixed = true), h17(start = 0, fixed = true);
  discrete Real h18(start = 0, fixed = true), h19(start = 0, fixed = true), h20(start = 0, fixed = true), h21(start = 0, fixed = true), h22(start = 0, fixed = true), h23(start = 0, fixed = true);
  discrete Real h24(start = 0, fixed = true), h25(start = 0, fixed = true), h26(start = 0, fixed = true), h27(start = 0, fixed = true), h28(start = 0, fixed = true), h29(start = 0, fixed = true);
  discrete Real h30(start = 0, fixed = true), h31(start = 0, fixed = true), h32(start = 0, fixed = true), h33(start = 0, fixed = true), h34(start = 0, fixed = true), h35(start = 0, fixed = true);
  discrete Real h36(start = 0, fixed = true), h37(start = 0, fixed = true), h38(start = 0, fixed = true), h39(start = 0, fixed = true), h40(start = 0, fixed = true) "heading h_j, j samples ago";
  Real cloud "cloud cover in [0, 1]";
  Real wave "temperature oscillation";
equation
  r = gravity*tan(phi)/airspeed;
  der(psi) = r;
  wave = sin(2*3.141592653589793*time/temperature_period);
  cloud = if time <= cloud_start or time >= cloud_start + 2*cloud_ramp + cloud_duration then 0
    elseif time < cloud_start + cloud_ramp then sin(0.5*3.141592653589793*(time - cloud_start)/cloud_ramp)^2
    elseif time <= cloud_start + cloud_ramp + cloud_duration then 1
    else cos(0.5*3.141592653589793*(time - cloud_start - cloud_ramp - cloud_duration)/cloud_ramp)^2;
  a = if drift_enabled then ir_gain*(1 + gain_day_rate*time + gain_temperature*wave + gain_cloud*cloud) else ir_gain;
  b = if drift_enabled then ir_offset + offset_day_rate*time + offset_temperature*wave + offset_cloud*cloud else ir_offset;
  when time >= t_next then
    n = pre(n) + 1;
    t_next = (pre(n) + 1)/sample_rate "from the count: a running sum of 1/sample_rate drifts off the sample instants";
    ir = a*r + b;
    h0 = psi;
    h1 = pre(h0);
    h2 = pre(h1);
    h3 = pre(h2);
    h4 = pre(h3);
    h5 = pre(h4);
    h6 = pre(h5);
    h7 = pre(h6);
    h8 = pre(h7);
    h9 = pre(h8);
    h10 = pre(h9);
    h11 = pre(h10);
    h12 = pre(h11);
    h13 = pre(h12);
    h14 = pre(h13);
    h15 = pre(h14);
    h16 = pre(h15);
    h17 = pre(h16);
    h18 = pre(h17);
    h19 = pre(h18);
    h20 = pre(h19);
    h21 = pre(h20);
    h22 = pre(h21);
    h23 = pre(h22);
    h24 = pre(h23);
    h25 = pre(h24);
    h26 = pre(h25);
    h27 = pre(h26);
    h28 = pre(h27);
    h29 = pre(h28);
    h30 = pre(h29);
    h31 = pre(h30);
    h32 = pre(h31);
    h33 = pre(h32);
    h34 = pre(h33);
    h35 = pre(h34);
    h36 = pre(h35);
    h37 = pre(h36);
    h38 = pre(h37);
    h39 = pre(h38);
    h40 = pre(h39);
    // written with pre() so that no equation of this clause reads another's new value:
    // pre(n) = k, pre(h19) = h20 = psi 20 samples ago, pre(h39) = h40 = psi 40 samples ago
    gps_turn_rate = if pre(n) >= 40 then (pre(h19) - pre(h39))/gps_window else 0;
    gps_valid = if pre(n) >= 40 then 1 else 0;
  end when;
end InfraredSensor;
