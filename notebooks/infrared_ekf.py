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
# # The infrared horizon sensor: calibration in flight, and its faults
#
# A fixed-wing's infrared sensor reads `IR = a r + b + noise` with `a` and `b` drifting; the
# GPS turn rate arrives 1 s late. Three estimators of `a`, `b` and the present turn rate: the
# slides' EKF (with innovation gating and fault declaration), their regression, and
# Paparazzi's RLS. The turn-rate error is compared without faults, then with the slides' two
# faults (the IR +1200 counts from 60 s, the GPS +1.5 rad/s from 280 s).

# %%
import scenarios


def errors_of(options: dict) -> list[float]:
    """Turn-rate error std (deg/s) of the Kalman filter, the regression and the RLS."""
    _, m = scenarios.run("ir-calibration", options)
    return [m["turn_rate_error_deg_s"][name]["std"] for name in ("kalman", "regression", "rls")]


print("drift (default), Kalman / regression / RLS:", *(f"{e:.2f}" for e in errors_of({})))

# %% [markdown]
# With the slides' faults the gated filter declares each on the right sensor and keeps `a` and
# `b` through it; without gating, `b` absorbs the IR fault and the turn rate follows the GPS
# one.

# %%
for label, options in {"faults=both": {"faults": "both"},
                       "faults=both, gating off": {"faults": "both", "gating": False}}.items():
    print(f"{label:24s}", *(f"{e:8.2f}" for e in errors_of(options)))
