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
# known, a reference attitude and the samples to score (`estimators.recording`: `.npz`,
# `.mat` or `.csv`). Set `RECORDING` to a file of your own (a real flight log, say); without
# one, the notebook records a simulated non-stationary flight with noise and a gyro bias and
# uses it as the recording.

# %%
import os
import tempfile
from pathlib import Path

import numpy as np

import scenarios
from estimators import recording
from scenarios import replay

RECORDING = os.environ.get("QUADCOSIM_RECORDING", "")
if not RECORDING:
    folder = Path(tempfile.mkdtemp())
    scenarios.run("tp", {"flight": "nonstationary", "noise": True, "bias": True, "duration": 10.0}, folder / "run")
    RECORDING = str(replay.from_tp(folder / "run", folder / "recording.npz"))
data = recording.load(RECORDING)
print(RECORDING, {key: np.shape(value) for key, value in data.items() if hasattr(value, "shape")})

# %% [markdown]
# Each estimator on the same samples, scored by the quaternion-error RMSE (total, inclination,
# heading; degrees): Mahony's explicit filter with the package's default gains (its
# disturbance-aware corrections on), and the published VQF and Madgwick filters run as the
# same block. `python -m scenarios.replay FILE --estimator NAME` does the same from a shell.

# %%
for estimator in ("explicit", "vqf", "madgwick"):
    out = replay.replay(data, estimator=estimator)
    errors = out["errors"]
    print(f"{estimator:9s}", {key: round(float(np.ravel(value)[0]), 3) for key, value in errors.items()
                              if key.endswith("_deg")})
