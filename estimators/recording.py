"""Recorded IMU files in and out: ``.npz``, ``.mat`` and ``.csv``.

A recording holds ``gyro`` (N, 3, rad/s), ``acc`` (N, 3, m/s^2, specific force), ``mag``
(N, 3, any unit), the sampling ``rate`` (Hz), and optionally a reference attitude ``quat``
(N, 4, body to inertial, scalar first), a boolean ``scored`` (N,) marking the samples that
count in the errors, and ``meta``, a JSON text (frame, estimator settings of the run that wrote
it).

Names accepted when reading (first found wins):
- ``gyro``: ``gyro``, ``gyr``, ``imu_gyr``; ``acc``: ``acc``, ``imu_acc``; ``mag``: ``mag``,
  ``magneto``, ``imu_mag``;
- ``quat``: ``quat``, ``q_ref``, ``opt_quat``; ``scored``: ``scored``, ``movement``;
- ``rate``: ``rate``, ``sampling_rate``, or ``1/dt``.
``.mat`` files of the BROAD benchmark (Laidig et al., "BROAD: a benchmark for robust inertial
orientation estimation", Data, 2021) read as they are. A ``.csv`` has a header row with the
columns ``gyro_x, gyro_y, gyro_z, acc_x, ..., mag_z``, optionally ``quat_0 .. quat_3`` and
``scored``, and ``time`` (s) from which the rate is taken.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

ALIASES = {
    "gyro": ("gyro", "gyr", "imu_gyr"),
    "acc": ("acc", "imu_acc"),
    "mag": ("mag", "magneto", "imu_mag"),
    "quat": ("quat", "q_ref", "opt_quat"),
    "scored": ("scored", "movement"),
    "rate": ("rate", "sampling_rate"),
}
AXES = ("x", "y", "z")


def _first(data: dict, key: str):
    for name in ALIASES[key]:
        if name in data:
            return data[name]
    return None


def _read_csv(path: Path) -> dict:
    table = np.genfromtxt(path, delimiter=",", names=True)
    names = table.dtype.names or ()
    data = {}
    for key in ("gyro", "acc", "mag"):
        columns = [f"{key}_{a}" for a in AXES]
        missing = [c for c in columns if c not in names]
        if missing:
            raise ValueError(f"{path}: the CSV header lacks {', '.join(missing)}; columns are {', '.join(names)}")
        data[key] = np.column_stack([table[c] for c in columns])
    if all(f"quat_{k}" in names for k in range(4)):
        data["quat"] = np.column_stack([table[f"quat_{k}"] for k in range(4)])
    if "scored" in names:
        data["scored"] = table["scored"]
    if "time" in names and len(table) > 1:
        data["rate"] = 1.0 / float(np.median(np.diff(table["time"])))
    return data


def load(path, rate: float | None = None) -> dict:
    """Read the recording at ``path`` (``.npz``, ``.mat`` or ``.csv``); ``rate`` (Hz) overrides or
    supplies the sampling rate.

    Returns
    -------
    dict
        ``gyro``, ``acc``, ``mag`` (N, 3), ``rate`` (Hz), ``quat`` (N, 4) or None,
        ``scored`` (N,) bool or None, ``meta`` (dict).
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no recording at {path}")
    suffix = path.suffix.lower()
    if suffix == ".npz":
        with np.load(path, allow_pickle=False) as f:
            raw = {k: f[k] for k in f.files}
    elif suffix == ".mat":
        from scipy.io import loadmat

        raw = {k: v for k, v in loadmat(path, squeeze_me=False).items() if not k.startswith("__")}
    elif suffix == ".csv":
        raw = _read_csv(path)
    else:
        raise ValueError(f"{path}: unknown recording format {suffix!r}; use .npz, .mat or .csv")
    out = {}
    for key in ("gyro", "acc", "mag"):
        value = _first(raw, key)
        if value is None:
            raise ValueError(f"{path} has no {key} array (looked for {', '.join(ALIASES[key])})")
        out[key] = np.ascontiguousarray(np.asarray(value, dtype=float).reshape(-1, 3))
    quat = _first(raw, "quat")
    out["quat"] = None if quat is None else np.ascontiguousarray(np.asarray(quat, dtype=float).reshape(-1, 4))
    scored = _first(raw, "scored")
    out["scored"] = None if scored is None else np.asarray(scored).reshape(-1).astype(bool)
    found = _first(raw, "rate")
    if rate is None and found is None and "dt" in raw:
        found = 1.0 / float(np.asarray(raw["dt"]).reshape(-1)[0])
    rate = rate if rate is not None else (None if found is None else float(np.asarray(found).reshape(-1)[0]))
    if rate is None or not np.isfinite(rate) or rate <= 0:
        raise ValueError(f"{path} gives no sampling rate: store 'rate' (Hz) or 'dt' (s), or pass rate=")
    out["rate"] = rate
    meta = raw.get("meta")
    out["meta"] = json.loads(str(np.asarray(meta).reshape(-1)[0])) if meta is not None else {}
    return out


def save(path, *, gyro, acc, mag, rate: float, quat=None, scored=None, meta: dict | None = None) -> Path:
    """Write a recording to ``path`` (format from the suffix: ``.npz``, ``.mat`` or ``.csv``).

    Parameters
    ----------
    gyro, acc, mag : (N, 3) arrays
        Gyro (rad/s), accelerometer (m/s^2, specific force) and magnetometer (any unit), body axes.
    rate : float
        Sampling rate (Hz).
    quat : (N, 4) array, optional
        Reference attitude, body to inertial, scalar first.
    scored : (N,) bool array, optional
        Samples to score.
    meta : dict, optional
        Anything else worth keeping (JSON-serialisable).
    """
    path = Path(path)
    data = {"gyro": np.asarray(gyro, float), "acc": np.asarray(acc, float), "mag": np.asarray(mag, float),
            "rate": np.array(float(rate))}
    if quat is not None:
        data["quat"] = np.asarray(quat, float)
    if scored is not None:
        data["scored"] = np.asarray(scored, bool)
    path.parent.mkdir(parents=True, exist_ok=True)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        np.savez(path, meta=np.array(json.dumps(meta or {})), **data)
    elif suffix == ".mat":
        from scipy.io import savemat

        savemat(path, data | {"meta": json.dumps(meta or {})})
    elif suffix == ".csv":
        n = len(data["gyro"])
        columns = {"time": np.arange(n) / rate}
        for key in ("gyro", "acc", "mag"):
            columns |= {f"{key}_{a}": data[key][:, k] for k, a in enumerate(AXES)}
        if quat is not None:
            columns |= {f"quat_{k}": data["quat"][:, k] for k in range(4)}
        if scored is not None:
            columns["scored"] = data["scored"].astype(float)
        np.savetxt(path, np.column_stack(list(columns.values())), delimiter=",", header=",".join(columns),
                   comments="", fmt="%.17g")
    else:
        raise ValueError(f"{path}: unknown recording format {suffix!r}; use .npz, .mat or .csv")
    return path
