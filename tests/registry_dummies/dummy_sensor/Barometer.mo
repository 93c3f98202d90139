within QuadCoSim;
model Barometer "Static pressure of the standard atmosphere at the altitude h0 - p_z, through a lag"
  input Real p_z(unit = "m") = 0 "position along z of NED {I} (down)";
  parameter Real h0(unit = "m") = 0 "altitude of the NED origin above mean sea level";
  parameter Real sea_level_pressure(unit = "N/m2") = 101325 "static pressure at mean sea level";
  parameter Real sea_level_temperature(unit = "K") = 288.15 "temperature at mean sea level";
  parameter Real lapse_rate(unit = "K/m") = 0.0065 "temperature lapse rate of the troposphere";
  parameter Real tau(unit = "s") = 0.02 "time constant of the sensor's port";
  parameter Real n = 9.80665*0.0289644/(8.3144598*lapse_rate) "exponent g M / (R L)";
  output Real altitude(unit = "m") "true altitude above mean sea level";
  output Real pressure(unit = "N/m2", start = sea_level_pressure*(1 - lapse_rate*h0/sea_level_temperature)^n,
    fixed = true)
    "measured static pressure, settled at the altitude h0 at the start";
equation
  altitude = h0 - p_z;
  tau*der(pressure) = sea_level_pressure*(1 - lapse_rate*altitude/sea_level_temperature)^n - pressure;
end Barometer;
