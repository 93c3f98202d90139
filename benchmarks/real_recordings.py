"""The estimators on public real recordings with optical ground truth, against VQF, Madgwick and Mahony.

    python -m benchmarks.real_recordings DATA [--datasets broad,smartphones,...] [--choose]
        [--cache DIR] [--json OUT]

DATA holds one sub-folder per dataset, as :mod:`benchmarks.datasets` describes (where each comes
from, by title, and how it is read and aligned); the data stay outside the repository. Every
recording is scored by the quaternion-error RMSE (total, heading, inclination; the BROAD
benchmark's decomposition, :func:`estimators.score`) over its scored samples, after the
alignment its dataset needs, and the mean over a dataset's recordings is reported for our
``explicit`` and ``passive`` (TRIAD) filters at their defaults (``estimators.DEFAULT_GAINS``,
corrections on) and for VQF, Madgwick and Mahony at their packages' defaults. Every filter
starts from the TRIAD attitude of the first sample (VQF from its own first samples); the
field's dip and norm are taken from the first second.

``--choose`` runs the cross-validation that chose the defaults: over the grid :data:`GRID`, on
the datasets of :data:`CHOOSING` only (never on :data:`HELD_OUT`), each gain set is scored by
the mean over those datasets of its mean total RMSE divided by VQF's on the same dataset (so
that each dataset counts alike, whatever its number of recordings); leaving each dataset out in
turn, the set chosen on the others is scored on it (the cross-validated ratio), and the set
chosen on all of them is the default.

The published filters' results do not depend on our gains: ``--cache DIR`` keeps them.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from benchmarks import datasets
from estimators import DEFAULT_GAINS, estimate, gain_grid
from orchestrator.files import write_text
from scenarios.replay import field_from_data, references

CHOOSING = ("broad", "smartphones", "diodem")  # the datasets the defaults were chosen on
HELD_OUT = ("repoimu",)  # kept aside until the defaults were frozen
PUBLISHED = ("vqf", "madgwick", "mahony")
OURS = ("explicit", "passive")
METRICS = ("total_rmse_deg", "heading_rmse_deg", "inclination_rmse_deg")
LARGE_ERROR_DEG = 50.0  # deg, a recording's total RMSE reported as a failure of the filter (notes)
FIELD_SECONDS = 1.0  # s, start of each recording the field references are taken from
GRID = {
    "explicit": {"kP": [0.25, 0.5, 1.0, 2.0], "kI": [0.0003, 0.001, 0.003, 0.01], "k2": [0.1, 0.3, 1.0],
                 "rest_gain": [0.03, 0.1, 0.3, 1.0]},
    "passive": {"kP": [0.25, 0.5, 1.0, 2.0], "kI": [0.0003, 0.001, 0.003, 0.01], "k2": [0.01, 0.03, 0.1],
                "rest_gain": [0.03, 0.1, 0.3, 1.0]},
}


def _options(kind: str, data: dict) -> dict:
    field = field_from_data(data["acc"], data["mag"], max(1, int(FIELD_SECONDS * data["rate"])))
    options = {"gyro": data["gyro"], "acc": data["acc"], "mag": data["mag"], "dt": 1.0 / data["rate"],
               "initial": "triad", "outputs": (), "reference": data["quat"], "scored": data["scored"],
               "align_heading": data["meta"]["align"], **references("enu", field["dip"], field["norm"])}
    if kind in OURS:
        options |= {"corrections": True, "ry": "triad"}
    return options


def errors(kind: str, data: dict, gains: dict | None = None) -> dict:
    """Total, heading and inclination RMSE (deg; (G,) arrays over the gain sets ``gains``) of the
    filter ``kind`` on the recording ``data`` (as :mod:`benchmarks.datasets` loads it)."""
    found = estimate(kind, gains=gains, **_options(kind, data))["errors"]
    return {metric: np.asarray(found[metric]) for metric in METRICS}


def _published(name: str, recordings: list, cache: Path | None) -> dict:
    path = None if cache is None else cache / f"{name}.json"
    if path is not None and path.exists():
        return json.loads(path.read_text())
    table = {}
    for label, data in recordings:
        table[label] = {kind: {m: float(v[0]) for m, v in errors(kind, data).items()} for kind in PUBLISHED}
        print(name, label, {k: round(v["total_rmse_deg"], 2) for k, v in table[label].items()}, file=sys.stderr)
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text(path, json.dumps(table, indent=1) + "\n")
    return table


def evaluate(folder, names=CHOOSING + HELD_OUT, cache=None, grids: bool = False) -> dict:
    """Per dataset, the mean total, heading and inclination RMSE (deg) of every filter at its
    defaults; with ``grids``, also each gain set of :data:`GRID` (mean total RMSE per set).

    Parameters
    ----------
    folder : str or pathlib.Path
        The data folder (one sub-folder per dataset, see :mod:`benchmarks.datasets`).
    names : sequence of str
        Datasets to score; those absent from ``folder`` are skipped.
    cache : str or pathlib.Path, optional
        Folder keeping the published filters' results.
    grids : bool
        Also score the grid of :data:`GRID` (for :func:`choose`).

    Returns
    -------
    dict
        Dataset name -> ``{"recordings": count, "left_out": [names of the recordings not used],
        "means": {filter: {metric: deg}}, "per_recording": {name: {filter: {metric: deg}}}, "grid":
        {kind: (G,) mean total RMSE}}``.
    """
    out = {}
    for name in names:
        left_out = []
        recordings = datasets.load(folder, name, left_out)
        if not recordings:
            continue
        published = _published(name, recordings, None if cache is None else Path(cache))
        rows = {label: dict(published[label]) for label, _ in recordings}
        grid_totals = {kind: [] for kind in OURS}
        for label, data in recordings:
            for kind in OURS:
                rows[label][kind] = {m: float(v[0]) for m, v in errors(kind, data).items()}
                if grids:
                    grid_totals[kind].append(errors(kind, data, gain_grid(**GRID[kind]))["total_rmse_deg"])
        means = {kind: {m: float(np.mean([rows[label][kind][m] for label in rows])) for m in METRICS}
                 for kind in OURS + PUBLISHED}
        out[name] = {"recordings": len(recordings), "left_out": left_out, "means": means, "per_recording": rows}
        if grids:
            out[name]["grid"] = {kind: np.mean(grid_totals[kind], axis=0).tolist() for kind in OURS}
        print(name, {k: round(v["total_rmse_deg"], 2) for k, v in means.items()}, file=sys.stderr)
    return out


def choose(results: dict) -> dict:
    """The cross-validation of the module docstring on :func:`evaluate`'s ``results`` (with
    grids): per filter, the gain set chosen on all the choosing datasets and, per left-out
    dataset, the set chosen without it and its ratio to VQF there."""
    names = [n for n in CHOOSING if n in results]
    choice = {}
    for kind in OURS:
        axes = gain_grid(**GRID[kind])
        ratios = {n: np.asarray(results[n]["grid"][kind]) / results[n]["means"]["vqf"]["total_rmse_deg"]
                  for n in names}
        best = int(np.argmin(np.mean([ratios[n] for n in names], axis=0)))
        folds = {}
        for left in names:
            inner = int(np.argmin(np.mean([ratios[n] for n in names if n != left], axis=0)))
            folds[left] = {"gains": {a: float(v[inner]) for a, v in axes.items()},
                           "ratio_to_vqf": float(ratios[left][inner])}
        choice[kind] = {"gains": {a: float(v[best]) for a, v in axes.items()},
                        "ratios_to_vqf": {n: float(ratios[n][best]) for n in names}, "left_out": folds}
    return choice


def large_errors(found: dict, kind: str, above: float = LARGE_ERROR_DEG) -> list[float]:
    """The total RMSE (deg) of filter ``kind`` on the recordings of one dataset (``found``, an entry
    of :func:`evaluate`'s results) where it exceeds ``above`` (deg), largest first."""
    return sorted((row[kind]["total_rmse_deg"] for row in found["per_recording"].values()
                   if row[kind]["total_rmse_deg"] > above), reverse=True)


def notes(results: dict) -> str:
    """What the table's means hide, per dataset of ``results`` (:func:`evaluate`'s): the
    recordings left out (:func:`datasets.usable`) and those on which a filter's error exceeds
    :data:`LARGE_ERROR_DEG`."""
    lines = []
    for name, found in results.items():
        used, left = found["recordings"], len(found.get("left_out", []))
        lines.append(f"{name}: {used} of {used + left} recordings used, {left} left out (gyro and reference "
                     f"rates differ by more than {datasets.MISMATCH_LIMIT:.0%})")
        for kind in OURS + PUBLISHED:
            large = large_errors(found, kind)
            if large:
                lines.append(f"  {kind}: total RMSE above {LARGE_ERROR_DEG:g} deg on {len(large)} recordings, "
                             f"at most {large[0]:.1f} deg")
    return "\n".join(lines)


def table(results: dict) -> str:
    """The summary tables of :func:`evaluate`'s ``results``: per dataset (its role), mean total RMSE
    (deg) of every filter and our best filter's ratio to VQF; then every filter's mean heading and
    inclination RMSE (deg)."""
    lines = ["| dataset (recordings) | role | explicit | passive | VQF | Madgwick | Mahony | best / VQF |",
             "|---|---|---|---|---|---|---|---|"]
    detail = ["| dataset | " + " | ".join(f"{k} heading / incl." for k in OURS + PUBLISHED) + " |",
              "|---" * (len(OURS + PUBLISHED) + 1) + "|"]
    for name, found in results.items():
        m = {k: v["total_rmse_deg"] for k, v in found["means"].items()}
        role = "held out" if name in HELD_OUT else "chose the defaults"
        ratio = min(m["explicit"], m["passive"]) / m["vqf"]
        lines.append(f"| {name} ({found['recordings']}) | {role} | {m['explicit']:.2f} | {m['passive']:.2f} | "
                     f"{m['vqf']:.2f} | {m['madgwick']:.2f} | {m['mahony']:.2f} | {ratio:.2f} |")
        detail.append(f"| {name} | " + " | ".join(
            f"{found['means'][k]['heading_rmse_deg']:.2f} / {found['means'][k]['inclination_rmse_deg']:.2f}"
            for k in OURS + PUBLISHED) + " |")
    return "\n".join(lines) + "\n\n" + "\n".join(detail)


def main(argv=None) -> int:
    """Command line (see the module docstring); prints the table, returns 0 (2 for a bad folder).
    ``argv``: the arguments (default ``sys.argv[1:]``)."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.real_recordings", description=__doc__.splitlines()[0])
    parser.add_argument("folder")
    parser.add_argument("--datasets", default=",".join(CHOOSING + HELD_OUT), help="comma-separated dataset names")
    parser.add_argument("--choose", action="store_true", help="cross-validate the defaults on the choosing datasets")
    parser.add_argument("--cache", help="folder keeping the published filters' results")
    parser.add_argument("--json", help="write the figures here")
    args = parser.parse_args(argv)
    names = tuple(n.strip() for n in args.datasets.split(","))
    unknown = [n for n in names if n not in datasets.LOADERS]
    if unknown or not Path(args.folder).is_dir():
        print(f"real_recordings: {args.folder} is not a folder, or unknown dataset {unknown}; datasets are "
              f"{', '.join(datasets.LOADERS)}", file=sys.stderr)
        return 2
    if args.choose:
        names = tuple(n for n in names if n in CHOOSING)  # the held-out dataset never enters the choice
    results = evaluate(args.folder, names, args.cache, grids=args.choose)
    print(table(results))
    print(notes(results))
    report = {"results": results, "defaults": {k: DEFAULT_GAINS[k] for k in OURS}}
    if args.choose:
        report["choice"] = choose(results)
        print(json.dumps(report["choice"], indent=1))
    if args.json:
        write_text(args.json, json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
