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
# # Magnetometer calibration: static, Metge et al.'s, dynamics-aware
#
# 1. Static: soft and hard iron from a hand-held rotation sweep, motors off
#    (`calibration.fit_static`).
# 2. Dynamic (Metge et al.): the field the motor currents make, from the clamped rig's sweeps
#    of each motor at two battery states (`calibration.fit_dynamic`, eqs. 5 to 8), compensated
#    by eq. 9.
# 3. Dynamics-aware: the same compensation with the commands passed through the motors'
#    identified dynamics (`calibration.fit_motor_dynamics`).
#
# The rig is shortened here (6 command levels, a 6 s free set) so that the notebook runs in
# under a minute; `quadcosim run metge` is the full one.

# %%

import scenarios

_, static = scenarios.run("static-cal", {"duration": 20.0})
print("soft iron A, largest error:", f"{static['A_error_max']:.2e}")
print("hard iron b_s, largest error (uT):", f"{static['b_s_error_max_uT']:.3f}")
print("heading error on a level turn (deg), uncorrected / corrected:",
      f"{static['heading_error_uncorrected_max_deg']:.1f} / {static['heading_error_max_deg']:.3f}")

# %%
_, metge = scenarios.run("metge", {"levels": 6, "free": 6.0})
table = metge["table1_deg"]
print("mean angular error of the field (deg)     set 1   set 2   free set")
for row in ("none", "calibration1", "calibration2"):
    print(f"{row:40s}", *(f"{table[row][c]:7.2f}" for c in ("set1", "set2", "free")))
print(f"{'dynamics-aware, calibration 1':40s}", " " * 15, f"{metge['free_set_dynamic_deg']:7.2f}")

# %% [markdown]
# Either calibration brings the sets' error down to the magnetometer's noise; on the free set,
# where the commands move fast, eq. 9 leaves an error that the dynamics-aware compensation
# removes.

# %%
dynamics = metge["motor_dynamics"]["calibration1"]
print({key: value for key, value in dynamics.items() if not isinstance(value, list)})
