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
# `quadcosim.estimators.analysis`. Short horizons (a few seconds of flight each), so that the notebook runs
# in well under a minute.
#
# ## Does the vehicle follow its attitude setpoint?
#
# `quadcosim run tp --set flight=nonstationary noise=on duration=6` from Python; then
# `quadcosim plot RUN Setpoint.theta_d Quadrotor.theta --tracking --deg`, the setpoint against
# the response, from Python too.

# %%
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from IPython.display import Image, display
from quadcosim.scenarios.run_plots import plot

from quadcosim import scenarios

folder = Path(tempfile.mkdtemp())
result, metrics = scenarios.run("tp", {"flight": "nonstationary", "duration": 6.0, "noise": True}, folder / "run")
roll, pitch, yaw = metrics["rms_error_deg"]
print(f"estimation error, RMS after 2 s: roll {roll:.3f} deg, pitch {pitch:.3f} deg, yaw {yaw:.3f} deg")
display(Image(filename=plot(folder / "run", ["Setpoint.theta_d", "Quadrotor.theta"], tracking=True, deg=True)))

# %% [markdown]
# What to see: the response (solid) follows the setpoint (dashed) with its amplitude kept and
# a small lag, set by the attitude loop's bandwidth.
#
# ## How close is the estimate to the truth?
#
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
# What to see: the lab's default filter (the linear one) follows the truth at first, then
# falls behind when the vehicle also turns in yaw: it integrates body rates as Euler rates.
#
# ## Which filter is accurate in which flight?
#
# The same questions as the lab report's, each a set of options (`quadcosim run tp --set ...`
# on the command line).

# %%
flights, estimators = ("quasi", "nonstationary"), ("linear", "explicit", "passive")
rms = {}
for flight in flights:
    for estimator in estimators:
        _, m = scenarios.run("tp", {"estimator": estimator, "flight": flight, "duration": 4.0, "noise": True})
        rms[flight, estimator] = m["rms_error_deg"]
print(f"{'flight':14s} {'estimator':9s} {'roll':>7s} {'pitch':>7s} {'yaw':>7s}   (RMS error after 2 s, deg)")
for (flight, estimator), (r, p, y) in rms.items():
    print(f"{flight:14s} {estimator:9s} {r:7.3f} {p:7.3f} {y:7.3f}")

fig, axes = plt.subplots(1, 2, sharey=True, figsize=(8, 3), layout="constrained")
for ax, flight in zip(axes, flights, strict=True):
    for i, estimator in enumerate(estimators):
        ax.bar(np.arange(3) + (i - 1) * 0.27, rms[flight, estimator], 0.27, label=estimator)
    ax.set_xticks(range(3), ["roll", "pitch", "yaw"])
    ax.set(title=f"flight={flight}", yscale="log")
axes[0].set_ylabel("RMS error after 2 s (deg)")
axes[1].legend()
plt.show()

# %% [markdown]
# What to see (log scale): every filter is accurate in quasi-stationary flight. In
# non-stationary flight the linear filter's yaw error is the largest of all, as it integrates
# body rates as Euler rates; the passive complementary filter on SO(3) stays the most accurate
# in both flights.
#
# ## The linear filter's gain, predicted
#
# `quadcosim.estimators.analysis` predicts the linear filter's error variance against its gain $k$ from
# the sensor noise per sample (python-control): the sum of the gyro's and the
# accelerometer-derived angle's noise variances, each through the filter's discrete transfer
# function from that noise to the error, by its $H_2$ norm:
#
# $$\sigma^2(k) = \sigma^2_{\text{gyro}}\,\lVert H_{\text{gyro}}(k)\rVert_2^2
#   + \sigma^2_{\text{angle}}\,\lVert H_{\text{angle}}(k)\rVert_2^2 .$$
#
# A small gain trusts the gyro and lets its noise integrate, a large one passes the
# accelerometer's noise; `quadcosim run gain-study` sets the prediction against simulation.

# %%
from quadcosim.estimators import analysis

dt = 1e-3  # s, the IMU's sample time
sigma_gyro, sigma_angle = analysis.imu_noise_per_sample(1.0 / dt)
gains = np.geomspace(0.05, 5.0, 30)
predicted = np.degrees(np.sqrt(analysis.linear_error_variance(gains, dt, sigma_gyro, sigma_angle)))
best = analysis.linear_optimal_gain(dt, sigma_gyro, sigma_angle)
print(f"optimal gain {best:.2f} 1/s, predicted RMS error there {np.interp(best, gains, predicted):.3f} deg")
fig, ax = plt.subplots(figsize=(6, 3.5), layout="constrained")
ax.loglog(gains, predicted)
ax.axvline(best, color="k", ls=":", label=f"optimal gain {best:.2f} 1/s")
ax.set(xlabel="gain k (1/s)", ylabel="predicted RMS error (deg)")
ax.legend()
plt.show()

# %% [markdown]
# What to see: the error falls with the gain on the left (less integrated gyro noise), rises on
# the right (more accelerometer noise), and the optimum sits between.
