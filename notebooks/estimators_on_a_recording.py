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
# # Estimators on a recording
#
# A recording is a file of gyro, accelerometer and magnetometer samples at a rate, with, when
# known, a reference attitude and the samples to score (`quadcosim.estimators.recording`: `.npz`,
# `.mat` or `.csv`). Set `QUADCOSIM_RECORDING` to a file of your own (a real flight log, say);
# without one, the notebook records 10 s of a simulated non-stationary flight, with noise and a
# gyro bias, and uses it as the recording.

# %%
import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from quadcosim.estimators import recording
from quadcosim.scenarios import replay

from quadcosim import scenarios

RECORDING = os.environ.get("QUADCOSIM_RECORDING", "")
if not RECORDING:
    folder = Path(tempfile.mkdtemp())
    scenarios.run("tp", {"flight": "nonstationary", "noise": True, "bias": True, "duration": 10.0}, folder / "run")
    RECORDING = str(replay.from_tp(folder / "run", folder / "recording.npz"))
data = recording.load(RECORDING)
samples = len(data["gyro"])
print(f"{Path(RECORDING).name}: {samples} samples at {data['rate']:g} Hz ({samples / data['rate']:g} s); "
      f"reference attitude: {'yes' if data['quat'] is not None else 'no'}")

# %% [markdown]
# ## What does the filter see?
#
# The three sensors against time: the gyro (body rates), the accelerometer (specific force,
# gravity minus acceleration) and the magnetometer.

# %%
t = np.arange(samples) / data["rate"]
fig, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 6), layout="constrained")
mag_norm = np.median(np.linalg.norm(data["mag"], axis=1)) or 1.0  # a recording's mag is in any unit
for ax, (key, unit, scale) in zip(axes, (("gyro", "deg/s", np.degrees(1.0)), ("acc", "m/s²", 1.0),
                                         ("mag", "1, over its median norm", 1.0 / mag_norm)), strict=True):
    for k, axis in enumerate("xyz"):
        ax.plot(t, data[key][:, k] * scale, lw=0.8, label=axis)
    ax.set(ylabel=f"{key} ({unit})")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1), fontsize=8)
axes[-1].set_xlabel("time (s)")
plt.show()

# %% [markdown]
# What to see: in non-stationary flight the accelerometer is far from gravity alone (its
# components swing by several m/s²), so a filter that trusts it as a tilt sensor is misled; the
# gyro's bias is too small to see by eye, but integrated over seconds it tilts an estimate.
#
# ## Which estimator scores best on these samples?
#
# Each estimator on the same samples, scored by the quaternion-error RMSE (total, inclination,
# heading; degrees): Mahony's explicit filter with the package's default gains (its
# disturbance-aware corrections on), and the published VQF and Madgwick filters run as the
# same block. `python -m quadcosim.scenarios.replay FILE --estimator NAME` does the same from a shell.

# %%
scores = {name: replay.replay(data, estimator=name)["errors"] for name in ("explicit", "vqf", "madgwick")}
kinds = [key for key in next(iter(scores.values())) if key.endswith("_deg")]
print(f"{'estimator':10s}", *(f"{key.removesuffix('_deg'):>14s}" for key in kinds), "  (RMSE, deg)")
for name, errors in scores.items():
    print(f"{name:10s}", *(f"{errors[key]:14.3f}" for key in kinds))

fig, ax = plt.subplots(figsize=(7, 3), layout="constrained")
width = 0.8 / len(kinds)
for i, key in enumerate(kinds):
    ax.bar(np.arange(len(scores)) + (i - (len(kinds) - 1) / 2) * width, [scores[n][key] for n in scores], width,
           label=key.removesuffix("_deg"))
ax.set_xticks(np.arange(len(scores)), list(scores))
ax.set(ylabel="RMSE (deg)", title=Path(RECORDING).name)
ax.legend()
plt.show()

# %% [markdown]
# What to see: the bars split each filter's error into inclination (roll and pitch, what the
# accelerometer corrects) and heading (what the magnetometer corrects): a filter can win one and
# lose the other, as it weighs its two references. On the simulated flight, with its gyro bias
# and fast swings, the published filters' inclination error is below the explicit filter's with
# the package's default gains; `notebooks/attitude_lab.py` and the estimators guide show how
# its gains change that.
