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
#    (`quadcosim.calibration.fit_static`): the magnetometer reads $m = A\,h + b_s$, and the fit
#    recovers $A$ and $b_s$ from the sweep's ellipsoid.
# 2. Dynamic (Metge et al.): the field the motor currents make, from the clamped rig's sweeps
#    of each motor at two battery states (`quadcosim.calibration.fit_dynamic`, eqs. 5 to 8), compensated
#    by eq. 9.
# 3. Dynamics-aware: the same compensation with the commands passed through the motors'
#    identified dynamics (`quadcosim.calibration.fit_motor_dynamics`).
#
# The runs are shortened (a 20 s sweep; the rig at 6 command levels with a 6 s free set) so
# that the notebook runs in under a minute; `quadcosim run metge` is the full rig.

# %%
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
from IPython.display import Image, display

from quadcosim import scenarios

folder = Path(tempfile.mkdtemp())

# %% [markdown]
# ## How well does a 20 s sweep recover the soft and hard iron?

# %%
_, static = scenarios.run("static-cal", {"duration": 20.0}, folder / "static")
print("static calibration, 20 s sweep:")
print(f"  soft iron A, largest element error:   {static['A_error_max']:.2e} (dimensionless)")
print(f"  hard iron b_s, largest element error: {static['b_s_error_max_uT']:.3f} uT")
print(f"  heading error on a level turn:        {static['heading_error_uncorrected_max_deg']:.1f} deg uncorrected, "
      f"{static['heading_error_max_deg']:.3f} deg corrected")
display(Image(filename=folder / "static" / "static_calibration.png"))

# %% [markdown]
# What to see: the raw samples lie on an ellipsoid off the origin (soft iron stretches the
# sphere, hard iron moves it); the corrected ones on the sphere of the Earth's field. The
# heading error of a level turn falls from tens of degrees to a fraction of one.
#
# ## What do the motors' currents do to the field, and how much does each calibration remove?

# %%
_, metge = scenarios.run("metge", {"levels": 6, "free": 6.0}, folder / "metge")
table = metge["table1_deg"]
print("mean angular error of the field (deg)     set 1   set 2   free set")
for row in ("none", "calibration1", "calibration2"):
    print(f"{row:40s}", *(f"{table[row][c]:7.2f}" for c in ("set1", "set2", "free")))
print(f"{'dynamics-aware, calibration 1':40s}", " " * 15, f"{metge['free_set_dynamic_deg']:7.2f}")

labels = ["none", "calibration 1", "calibration 2", "dynamics-aware"]
free = [table["none"]["free"], table["calibration1"]["free"], table["calibration2"]["free"],
        metge["free_set_dynamic_deg"]]
fig, ax = plt.subplots(figsize=(6, 3), layout="constrained")
ax.bar(labels, free, color=["grey", "C0", "C1", "C2"])
ax.set(ylabel="mean angular error (deg)", title="the free set: fast commands", yscale="log")
plt.show()

# %% [markdown]
# What to see: either calibration brings the sets' error down to the magnetometer's noise; on
# the free set, where the commands move fast, eq. 9 leaves an error that the dynamics-aware
# compensation removes. The run's own figure shows it against time:

# %%
display(Image(filename=folder / "metge" / "figure3_free_set.png"))
dynamics = metge["motor_dynamics"]["calibration1"]
print("identified motor dynamics (calibration 1):")
print(f"  rate {dynamics['rate']:.1f} 1/s, drag {dynamics['drag']:.3f} 1/(V s), "
      f"winding-voltage limit {dynamics['limit']:.2f} V, free-wheeling ESC: {dynamics['freewheel']}")
print("  field gain per motor (uT/V):", ", ".join(f"{1e6 * g:.1f}" for g in dynamics["gain"]))

# %% [markdown]
# What to see: one first-order lag for the four motors (rate, drag, the ESC's limit) and one
# field gain per motor: the field its current makes at the magnetometer, per volt of its
# winding.
