"""The estimators on real recordings with optical ground truth, against VQF and Madgwick.

    python -m benchmarks.real_recordings FOLDER [--frame enu] [--json OUT]

FOLDER holds recordings that :mod:`estimators.recording` reads (the ``.mat`` files of the
BROAD benchmark, Laidig et al., "BROAD: a benchmark for robust inertial orientation
estimation", Data, 2021, read as they are; ENU frame). Each is scored by the quaternion-error
RMSE over its scored samples (BROAD: the movement phases), and the mean over the recordings
is reported for:
- ``explicit`` and ``passive`` (TRIAD) at their defaults (``estimators.DEFAULT_GAINS``,
  corrections on) and at the gain set of a grid with the least mean error ("tuned", one set
  for all recordings), with and without the disturbance-aware corrections; the tuning is
  done on every other recording (the first, third, ...) and the means are given over all
  recordings and over the held-out others (``held_out_mean_total_rmse_deg``), so that a
  gain set fitted to the recordings shows itself;
- ``vqf`` and ``madgwick`` at their packages' defaults.
The filters start from the TRIAD attitude of the first sample; the field's dip and norm are
taken from the first second. The data stay outside the repository.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from estimators import DEFAULT_GAINS, estimate, gain_grid, recording
from scenarios.replay import field_from_data, references

GRID = {"kP": [0.3, 0.5, 1.0, 2.0, 3.0], "kI": [0.0, 0.001, 0.003, 0.01, 0.03]}
FIELD_SECONDS = 1.0  # s, start of each recording the field references are taken from


def _errors(kind, data, refs, gains=None, corrections=None):
    options = {"corrections": corrections, "ry": "triad"} if kind in ("explicit", "passive") else {}
    return estimate(kind, gyro=data["gyro"], acc=data["acc"], mag=data["mag"], dt=1.0 / data["rate"],
                    gains=gains, initial="triad", outputs=(), reference=data["quat"], scored=data["scored"],
                    **options, **refs)["errors"]["total_rmse_deg"]


def evaluate(folder, frame: str = "enu", published: bool = True) -> dict:
    """Total RMSE (deg) per recording and filter variant, and the tuned gain sets.

    Parameters
    ----------
    folder : str or pathlib.Path
        Folder of the recordings (``.mat``, ``.npz``, ``.csv``).
    frame : {"enu", "ned"}
        Navigation frame of the recordings' reference attitudes.
    published : bool
        Also run the published filters (VQF, Madgwick) at their packages' defaults.

    Returns
    -------
    dict
        ``recordings`` (name -> variant -> total RMSE, deg), ``mean_total_rmse_deg``,
        ``tuned_gains`` (variant -> gain set) and the ``defaults``.
    """
    paths = sorted(p for p in Path(folder).iterdir() if p.suffix.lower() in (".mat", ".npz", ".csv"))
    if not paths:
        raise ValueError(f"no recordings (.mat, .npz, .csv) in {folder}")
    grid = gain_grid(**GRID)
    rows, grids = {}, {}
    for path in paths:
        data = recording.load(path)
        field = field_from_data(data["acc"], data["mag"], int(FIELD_SECONDS * data["rate"]))
        refs = references(frame, field["dip"], field["norm"])
        row = {}
        for kind in ("explicit", "passive"):
            row[f"{kind} default"] = float(_errors(kind, data, refs, corrections=True)[0])
            for corrections in (False, True):
                grids[(path.name, kind, corrections)] = _errors(kind, data, refs, grid, corrections)
        if published:
            for kind in ("vqf", "madgwick"):
                row[kind] = float(_errors(kind, data, refs)[0])
        rows[path.stem] = row
        print(path.stem, {k: round(v, 2) for k, v in row.items()}, file=sys.stderr)
    tuned = {}
    for kind in ("explicit", "passive"):
        for corrections in (False, True):
            mean = np.mean([grids[(p.name, kind, corrections)] for p in paths[0::2]], axis=0)
            best = int(np.argmin(mean))
            label = f"{kind} tuned, corrections {'on' if corrections else 'off'}"
            tuned[label] = {name: float(values[best]) for name, values in grid.items()}
            for p in paths:
                rows[p.stem][label] = float(grids[(p.name, kind, corrections)][best])
    labels = next(iter(rows.values()))
    means = {label: float(np.mean([r[label] for r in rows.values()])) for label in labels}
    held_out = {label: float(np.mean([rows[p.stem][label] for p in paths[1::2]])) for label in labels}
    return {"recordings": rows, "mean_total_rmse_deg": means, "held_out_mean_total_rmse_deg": held_out,
            "tuning_recordings": [p.stem for p in paths[0::2]], "tuned_gains": tuned,
            "defaults": {k: DEFAULT_GAINS[k] for k in ("explicit", "passive")}}


def main(argv=None) -> int:
    """Command line (see the module docstring); prints the mean errors, returns 0.
    ``argv``: the arguments (default ``sys.argv[1:]``)."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.real_recordings", description=__doc__.splitlines()[0])
    parser.add_argument("folder")
    parser.add_argument("--frame", default="enu", choices=("ned", "enu"))
    parser.add_argument("--json", help="write the figures here")
    args = parser.parse_args(argv)
    result = evaluate(args.folder, args.frame)
    vqf = result["mean_total_rmse_deg"].get("vqf")
    vqf_held = result["held_out_mean_total_rmse_deg"].get("vqf")
    print(f"{'mean total RMSE (deg)':40s} {'all':>6s} {'x VQF':>6s} {'held-out':>9s} {'x VQF':>6s}")
    for label, mean in result["mean_total_rmse_deg"].items():
        held = result["held_out_mean_total_rmse_deg"][label]
        ratios = (f"{mean / vqf:6.2f}", f"{held / vqf_held:6.2f}") if vqf else ("", "")
        print(f"{label:40s} {mean:6.2f} {ratios[0]} {held:9.2f} {ratios[1]}")
    print("tuned gain sets:", json.dumps(result["tuned_gains"]))
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
