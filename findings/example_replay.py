"""Findings of the estimators replayed on the example logs (``quadcosim log example``): every
estimator's heading difference from the log's attitude without and with the compensation, and
an ablation of the linear filter's heading on flight a's internal compass.

The example logs are written by the package (:mod:`quadcosim.scenarios.flightlog.example`), so the group
always runs; their attitude is the simulated truth, and their Earth field the World Magnetic
Model's, whose declination the replay's Earth field carries. The ablation takes flight a as
:func:`quadcosim.scenarios.flightlog.replay.replay_log` replays it and changes one thing at a time: the
compensation paired with the log's offsets (which already hold the motors' mean field) instead of
those fitted with its model; for the linear filter, the reference turned to magnetic north by the
replay's Earth field's declination, the gyro's body rates turned into Euler-angle rates (at the
log's roll and pitch), both, and both with the filter started from the log's attitude.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from findings import finding

COMMAND = "python -m findings example_replay"  # the group prints them; the logs are written on the way
FLIGHTS = ("a", "b", "c")
COMPASS = 1  # the internal compass, the one the battery current moves
TOLERANCE_DEG = 0.05  # deg: seeded synthetic logs, the same numbers on every run but for float noise
ABLATIONS = ("magnetic_north", "euler_rates", "both", "both_started")


def _euler_rates(gyro, reference) -> np.ndarray:
    """Body rates ``gyro`` (N, 3, rad/s) as Z-Y-X Euler-angle rates (rad/s) at the roll and pitch
    of ``reference`` (N, 4, body to NED, scalar first)."""
    from scipy.spatial.transform import Rotation

    _, pitch, roll = Rotation.from_quat(reference, scalar_first=True).as_euler("ZYX").T
    p, q, r = gyro.T
    turn = q * np.sin(roll) + r * np.cos(roll)
    return np.column_stack([p + np.tan(pitch) * turn, q * np.cos(roll) - r * np.sin(roll), turn / np.cos(pitch)])


def linear_ablation(path) -> dict:
    """The linear filter's heading RMS difference (deg) from the log's attitude on the log at
    ``path`` (compass :data:`COMPASS`), without and with the compensation, under each of
    :data:`ABLATIONS`; ``log_offsets``: every estimator's heading with the compensation paired
    with the log's offsets; ``declination``: of the replay's Earth field (deg, east of north) and
    of the World Magnetic Model's (``wmm``); ``bias``: the norm of the mean difference (µT) between
    the field replayed and the one the example was made with."""
    from quadcosim.estimators import estimate
    from quadcosim.flightlogs import read_log
    from quadcosim.scenarios.flightlog import replay
    from quadcosim.scenarios.flightlog.example import earth_field
    from scipy.spatial.transform import Rotation

    log = read_log(path)
    time, dt, gyro, acc, reference = replay._uniform(log, COMPASS)
    without, with_model, _ = replay._fields(log, COMPASS, time)
    _, with_log_offsets, _ = replay._fields(log, COMPASS, time, model_offsets=False)
    half = time[0] + 0.5 * (time[-1] - time[0])
    scored, first = time >= max(half, time[0] + 5.0), time < half
    rates = _euler_rates(gyro, reference)
    found = {"log_offsets": {}, "declination": {}, "bias": {}}
    R = Rotation.from_quat(reference, scalar_first=True).as_matrix()
    truth = np.einsum("tji,j->ti", R, earth_field())  # the field the example was made with, in the body
    found["declination"]["wmm"] = float(np.degrees(np.arctan2(earth_field()[1], earth_field()[0])))
    for label, mag in (("without", without), ("with", with_model), ("log_offsets", with_log_offsets)):
        earth = np.einsum("tij,tj->i", R[first], mag[first]) / first.sum()
        found["declination"][label] = float(np.degrees(np.arctan2(earth[1], earth[0])))
        found["bias"][label] = float(np.linalg.norm(np.mean(mag - truth, axis=0)) * 1e6)
        turned = (Rotation.from_euler("z", -np.arctan2(earth[1], earth[0]))
                  * Rotation.from_quat(reference, scalar_first=True)).as_quat(scalar_first=True)
        common = {"acc": acc, "mag": mag, "dt": dt, "earth_field": earth, "outputs": (), "scored": scored}
        if label == "log_offsets":
            for kind, settings in replay.ESTIMATORS.items():
                errors = estimate(kind, gyro=gyro, initial="triad", reference=reference, **common, **settings)
                found[label][kind] = float(errors["errors"]["heading_rmse_deg"][0])
            continue
        variants = {"magnetic_north": (gyro, turned, {"initial": "triad"}),
                    "euler_rates": (rates, reference, {"initial": "triad"}),
                    "both": (rates, turned, {"initial": "triad"}),
                    "both_started": (rates, turned, {"q0": turned[0]})}
        for name, (g, ref, start) in variants.items():
            errors = estimate("linear", gyro=g, reference=ref, **common, **start)["errors"]
            found.setdefault(name, {})[label] = float(errors["heading_rmse_deg"][0])
    return found


def compute(quick: bool = False) -> list[dict]:
    """The group's findings (see the module docstring; the same with ``quick``: about a minute)."""
    from quadcosim.scenarios.flightlog.example import write_examples
    from quadcosim.scenarios.flightlog.replay import replay_log

    found = []
    with tempfile.TemporaryDirectory() as folder:
        paths = dict(zip(FLIGHTS, write_examples(Path(folder)), strict=True))
        for key, path in paths.items():
            result = replay_log(path, COMPASS)
            for kind, r in result["estimators"].items():
                for label in ("without", "with"):
                    found.append(finding(f"example_replay.{key}.{kind}.{label}", r[label]["heading_rms_deg"], "deg",
                                         COMMAND, TOLERANCE_DEG, 2))
        ablation = linear_ablation(paths["a"])
    for kind, value in ablation.pop("log_offsets").items():
        found.append(finding(f"example_replay.log_offsets.{kind}", value, "deg", COMMAND, TOLERANCE_DEG, 2))
    for label, value in ablation.pop("declination").items():
        found.append(finding(f"example_replay.declination.{label}", value, "deg", COMMAND, TOLERANCE_DEG, 1))
    for label, value in ablation.pop("bias").items():
        found.append(finding(f"example_replay.bias_ut.{label}", value, "uT", COMMAND, 0.01, 2))
    for name, values in ablation.items():
        for label, value in values.items():
            found.append(finding(f"example_replay.linear.{name}.{label}", value, "deg", COMMAND, TOLERANCE_DEG, 2))
    return found
