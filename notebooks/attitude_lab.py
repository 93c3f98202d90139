# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # The attitude lab, end to end
#
# The lab's closed loop, `Setpoint -> Controller -> MotorMagnetics -> Quadrotor -> IMU ->
# Quaternion_estim`, run from Python: one run and its figures, then the three filters in the two
# flights of the lab, then the linear filter's gain against the analysis of
# `estimators.analysis`. Short horizons (a few seconds of flight each), so that the notebook runs
# in well under a minute.

# %%
import matplotlib.pyplot as plt
import numpy as np

import scenarios

result, metrics = scenarios.run("tp", {"duration": 5.0, "noise": True})
print("RMS error after 2 s (deg; roll, pitch, yaw):", np.round(metrics["rms_error_deg"], 4))

# %% [markdown]
# Every signal of the run is in `result`, by the block names of the lab's Simulink model; a
# vector name (`Quaternion_estim.theta_est`) stands for its components.

# %%
fig, ax = plt.subplots(figsize=(8, 3), layout="constrained")
ax.plot(result.time, np.degrees(result["Quadrotor.theta1"]), label="roll, truth")
ax.plot(result.time, np.degrees(result["Quaternion_estim.theta_est1"]), "--", label="roll, estimate")
ax.set(xlabel="time (s)", ylabel="roll (deg)")
ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1))
plt.show()

# %% [markdown]
# ## The three filters, quasi-stationary and non-stationary flight
#
# The same questions as the lab report's, each a set of options (`quadcosim run tp --set ...`
# on the command line).

# %%
rows = []
for flight in ("quasi", "nonstationary"):
    for estimator in ("linear", "explicit", "passive"):
        _, m = scenarios.run("tp", {"estimator": estimator, "flight": flight, "duration": 4.0, "noise": True})
        rows.append((flight, estimator, *np.round(m["rms_error_deg"], 3)))
print(f"{'flight':14s} {'estimator':9s}  roll   pitch  yaw (deg RMS)")
for flight, estimator, *rms in rows:
    print(f"{flight:14s} {estimator:9s} ", *rms)

# %% [markdown]
# The linear filter is accurate in quasi-stationary flight and degrades in non-stationary
# flight, where it integrates body rates as Euler rates; the complementary filters on SO(3) do
# not.
#
# ## The linear filter's gain, predicted
#
# `estimators.analysis` predicts the linear filter's error variance against its gain from the
# sensor noise densities (python-control); `quadcosim run gain-study` sets it against
# simulation.

# %%
from estimators import analysis

dt = 1e-3  # s, the IMU's sample time
sigma_gyro, sigma_angle = analysis.imu_noise_per_sample(1.0 / dt)
gains = np.geomspace(0.05, 5.0, 30)
predicted = np.degrees(np.sqrt(analysis.linear_error_variance(gains, dt, sigma_gyro, sigma_angle)))
best = analysis.linear_optimal_gain(dt, sigma_gyro, sigma_angle)
fig, ax = plt.subplots(figsize=(6, 3.5), layout="constrained")
ax.loglog(gains, predicted)
ax.axvline(best, color="k", ls=":", label=f"optimal gain {best:.2f} 1/s")
ax.set(xlabel="gain k (1/s)", ylabel="predicted RMS error (deg)")
ax.legend()
plt.show()
