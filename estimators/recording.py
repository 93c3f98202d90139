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
A recording without a magnetometer reads as zeros there (the filters then give a 6-axis
estimate, with a warning). Arrays hold one sample per row: one stored transposed (3 x N) is
refused, never reshaped.
``.mat`` files of the BROAD benchmark (Laidig et al., "BROAD: a benchmark for robust inertial
orientation estimation", Data, 2021) read as they are. A ``.csv`` has a header row with the
columns ``gyro_x, gyro_y, gyro_z, acc_x, ..., mag_z``, optionally ``quat_0 .. quat_3`` and
``scored``, and ``time`` (s) from which the rate is taken.
"""

from __future__ import annotations

import json
import warnings
import zipfile
from pathlib import Path

import numpy as np

# A small real recording shipped with the package: 24 s of BROAD's trial "01_undisturbed_slow_rotation_A"
# (Laidig, Caruso, Cereatti, Seel, "BROAD - A Benchmark for Robust Inertial Orientation Estimation",
# Data, 2021; CC BY 4.0, cut and stored in single precision, otherwise unchanged): 286 Hz, ENU, mag in uT,
# at rest, then slow rotations (`python -m quadcosim.estimators.recording` says how long each), with its optical
# reference and movement phases.
EXAMPLE = Path(__file__).parent / "data" / "broad_excerpt.npz"

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
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # numpy warns on an empty file; refused below with its name
        try:
            table = np.atleast_1d(np.genfromtxt(path, delimiter=",", names=True))
        except IndexError:  # numpy's answer to a file without a header row
            table = np.zeros(0)
        except UnicodeDecodeError as error:
            raise ValueError(f"{path}: not UTF-8 text (byte {error.object[error.start]:#04x} at byte {error.start}, "
                             "a Latin-1 or Windows character?); save the file as UTF-8") from None
        except ValueError as error:
            raise ValueError(f"{path} is not a readable CSV recording ({error}); write it with "
                             "quadcosim.estimators.recording.save") from None
    names = table.dtype.names or ()
    if not names or len(table) == 0:
        raise ValueError(f"{path} holds no samples: a header row (gyro_x, ..., mag_z) and one row per sample are "
                         "needed")
    data = {}
    for key in ("gyro", "acc", "mag"):
        columns = [f"{key}_{a}" for a in AXES]
        missing = [c for c in columns if c not in names]
        if missing and key == "mag":
            continue
        if missing:
            raise ValueError(f"{path}: the CSV header lacks {', '.join(missing)}; columns are {', '.join(names)}")
        data[key] = np.column_stack([table[c] for c in columns])
    if all(f"quat_{k}" in names for k in range(4)):
        data["quat"] = np.column_stack([table[f"quat_{k}"] for k in range(4)])
    if "scored" in names:
        data["scored"] = table["scored"]
    if "time" in names and len(table) > 1:
        data["rate"] = _rate_from_time(path, table["time"])
    return data


def _rate_from_time(path, time) -> float:
    """Sampling rate (Hz) from a time column (s), refusing one that does not increase."""
    steps = np.diff(np.asarray(time, dtype=float))
    bad = np.flatnonzero(~(steps > 0))
    if len(bad):
        k = int(bad[0]) + 1
        raise ValueError(f"{path}: time is not increasing at sample {k} ({time[k - 1]:g} s then {time[k]:g} s); "
                         "sort the samples by time and remove repeated ones")
    return 1.0 / float(np.median(steps))


def _read_raw(path: Path) -> dict:
    suffix = path.suffix.lower()
    if suffix == ".npz":
        try:
            with np.load(path, allow_pickle=False) as f:
                return {k: f[k] for k in f.files}
        except (OSError, ValueError, zipfile.BadZipFile, EOFError) as error:
            raise ValueError(f"{path} is not a readable .npz archive ({error}); write it with numpy.savez or "
                             "quadcosim.estimators.recording.save") from None
    if suffix == ".mat":
        from scipy.io import loadmat

        try:
            return {k: v for k, v in loadmat(path, squeeze_me=False).items() if not k.startswith("__")}
        except (OSError, ValueError, TypeError, NotImplementedError) as error:
            raise ValueError(f"{path} is not a readable MATLAB file ({error}); save it with MATLAB's save "
                             "(-v7 or older) or scipy.io.savemat") from None
    if suffix == ".csv":
        return _read_csv(path)
    raise ValueError(f"{path}: unknown recording format {suffix!r}; use .npz, .mat or .csv")


def _rows(path, key: str, value, width: int) -> np.ndarray:
    """The array ``key`` as (N, width) samples in rows; a transposed (width, N) one is refused, not reshaped."""
    try:
        if np.iscomplexobj(value):  # numpy would drop the imaginary part with a warning alone
            raise ValueError(f"{path}: {key} holds complex numbers; a recording holds real samples")
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        if "complex" in str(error):
            raise
        raise ValueError(f"{path}: {key} is not numeric") from None
    if array.ndim == 2 and array.shape[0] == width and array.shape[1] != width:
        raise ValueError(f"{path}: {key} is stored {array.shape[0]} x {array.shape[1]}, transposed; store it with "
                         f"one sample per row ({array.shape[1]} x {width})")
    if array.ndim != 2 or array.shape[1] != width:
        raise ValueError(f"{path}: {key} must be an (N, {width}) array, one sample per row, not shape {array.shape}")
    return np.ascontiguousarray(array)


def _scored(path, value) -> np.ndarray:
    """The ``scored`` flags: booleans, or numbers 0 and 1 (a CSV's); text is refused (any
    non-empty string would read as true)."""
    array = np.asarray(value).reshape(-1)
    if array.dtype.kind == "b":
        return array
    if array.dtype.kind not in "iuf" or not np.isin(array, (0, 1)).all():
        shown = array[0] if array.dtype.kind not in "iuf" else array[~np.isin(array, (0, 1))][0]
        raise ValueError(f"{path}: scored holds {shown!r}; it flags each sample with true/false or 1/0")
    return array.astype(bool)


def _meta(path, raw) -> dict:
    meta = raw.get("meta")
    if meta is None:
        return {}
    try:
        value = json.loads(str(np.asarray(meta).reshape(-1)[0]))
    except (ValueError, IndexError) as error:
        raise ValueError(f"{path}: meta is not a JSON text ({error}); rewrite it with json.dumps or remove "
                         "it") from None
    if not isinstance(value, dict):
        raise ValueError(f"{path}: meta must be a JSON object ({{...}}), not {type(value).__name__}")
    return value


def _rate(path, raw, rate):
    found = _first(raw, "rate")
    if rate is None and found is None and "dt" in raw:
        dt = np.asarray(raw["dt"], dtype=float).reshape(-1)
        found = 1.0 / float(dt[0]) if dt.size and dt[0] != 0 else float("nan")
    if rate is None and found is None and "time" in raw:
        found = _rate_from_time(path, np.asarray(raw["time"], dtype=float).reshape(-1))
    if rate is None and found is not None:
        values = np.asarray(found, dtype=float).reshape(-1)
        rate = float(values[0]) if values.size else None
    if rate is None or not np.isfinite(rate) or rate <= 0:
        raise ValueError(f"{path} gives no sampling rate: store 'rate' (Hz), 'dt' (s) or 'time' (s), or pass rate=")
    return float(rate)


def load(path, rate: float | None = None) -> dict:
    """Read the recording at ``path`` (``.npz``, ``.mat`` or ``.csv``); ``rate`` (Hz) overrides or
    supplies the sampling rate.

    Returns
    -------
    dict
        ``gyro``, ``acc``, ``mag`` (N, 3; zeros when the file has no magnetometer), ``rate``
        (Hz), ``quat`` (N, 4) or None, ``scored`` (N,) bool or None, ``meta`` (dict).

    Raises
    ------
    ValueError
        A file that is not a recording, an array stored transposed (3 x N) or of another
        shape, an empty CSV, a time column that does not increase, a ``meta`` that is not
        JSON, or no sampling rate: each names the problem and the fix.
    """
    from quadcosim.infra.inputs import regular_file

    path = Path(path)
    if not path.exists() and not path.is_symlink():
        raise FileNotFoundError(f"no recording at {path}")
    regular_file(path, "the recording", "give a .npz, .mat or .csv recording file")
    raw = _read_raw(path)
    out = {}
    for key in ("gyro", "acc", "mag"):
        value = _first(raw, key)
        if value is None and key == "mag" and out:
            out[key] = np.zeros_like(out["gyro"])  # a 6-axis recording: the filters warn and correct the tilt only
            continue
        if value is None:
            raise ValueError(f"{path} has no {key} array (looked for {', '.join(ALIASES[key])})")
        out[key] = _rows(path, key, value, 3)
    quat = _first(raw, "quat")
    out["quat"] = None if quat is None else _rows(path, "quat", quat, 4)
    scored = _first(raw, "scored")
    out["scored"] = None if scored is None else _scored(path, scored)
    out["rate"] = _rate(path, raw, rate)
    out["meta"] = _meta(path, raw)
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
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".mat", ".csv"):
        raise ValueError(f"{path}: unknown recording format {suffix!r}; use .npz, .mat or .csv")
    from quadcosim.infra.files import atomic_path

    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as temporary:
        _write(temporary, suffix, data, meta, rate, quat, scored)
    return path


def _write(path: Path, suffix: str, data: dict, meta, rate: float, quat, scored):
    """The recording ``data`` into ``path`` in the format of ``suffix`` (see :func:`save`)."""
    if suffix == ".npz":
        np.savez(path, meta=np.array(json.dumps(meta or {})), **data)
    elif suffix == ".mat":
        from scipy.io import savemat

        savemat(path, data | {"meta": json.dumps(meta or {})})
    else:
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


def describe(data: dict) -> dict:
    """What a loaded recording holds: its length, rate, and the time before its first scored sample.

    Parameters
    ----------
    data : dict
        A recording as :func:`load` gives it.

    Returns
    -------
    dict
        ``samples``, ``rate_hz`` (Hz), ``duration_s`` (s), ``scored_share`` (1, the share of
        scored samples; 1 when the recording marks none) and ``before_first_scored_s`` (s, the
        time before the first scored sample: the rest before the movement, in BROAD's phases).
    """
    samples, rate = len(data["gyro"]), float(data["rate"])
    scored = data.get("scored")
    scored = np.ones(samples, dtype=bool) if scored is None else np.asarray(scored, dtype=bool)
    first = int(np.argmax(scored)) if scored.any() else samples
    return {"samples": samples, "rate_hz": rate, "duration_s": samples / rate, "scored_share": float(scored.mean()),
            "before_first_scored_s": first / rate}


def main(argv=None) -> int:
    """``python -m quadcosim.estimators.recording [FILE]``: print :func:`describe` of ``FILE`` (default
    :data:`EXAMPLE`, the shipped excerpt).

    Parameters
    ----------
    argv : list of str, optional
        The arguments (the process's by default).

    Returns
    -------
    int
        Exit status, 0.
    """
    import argparse

    parser = argparse.ArgumentParser(prog="python -m quadcosim.estimators.recording",
                                     description=describe.__doc__.split("\n")[0])
    parser.add_argument("file", nargs="?", default=str(EXAMPLE), help="a recording (default: the shipped excerpt)")
    path = Path(parser.parse_args(argv).file)
    d = describe(load(path))
    print(f"{path.name}: {d['samples']} samples at {d['rate_hz']:.1f} Hz, {d['duration_s']:.1f} s; "
          f"{d['before_first_scored_s']:.2f} s before the first scored sample (at rest), "
          f"{d['scored_share']:.0%} of the samples scored")
    return 0


if __name__ == "__main__":  # the same as quadcosim study recording
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim study recording").run, main)
