"""The estimators on public real recordings with optical ground truth, against VQF, Madgwick and Mahony.

    python -m quadcosim.benchmarks.real_recordings DATA [--datasets broad,smartphones,...] [--cache DIR]
        [--json OUT]

DATA holds one sub-folder per dataset, as :mod:`quadcosim.benchmarks.datasets` describes (where each comes
from, by title, and how it is read and aligned); the data stay outside the repository. Every
recording is scored by the quaternion-error RMSE (total, heading, inclination; the BROAD
benchmark's decomposition, :func:`quadcosim.estimators.score`) over its scored samples, after the
alignment its dataset needs, and the mean over a dataset's recordings is reported for the
recommended ``explicit`` filter and the ``passive`` (TRIAD) filter at their defaults
(``quadcosim.estimators.DEFAULT_GAINS``, corrections on), for the explicit filter with each of its parts
for real recordings taken away in turn (:data:`ABLATIONS`), and for VQF, Madgwick and Mahony at
their packages' defaults and VQF at the time constants chosen for it by the same procedure as
ours (:data:`TUNED`, ``python -m quadcosim.benchmarks.tuning DATA --filter vqf``). Every filter starts from
the TRIAD attitude of the first sample (VQF from its own first samples); the field's dip and norm
are taken from the first second.

The defaults were chosen on :data:`DEVELOPMENT`, each in turn held out of the search (``python -m
quadcosim.benchmarks.tuning
DATA``, ``--score-folds``).

The published filters' results do not depend on our gains: ``--cache DIR`` keeps them.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np
from quadcosim.benchmarks import datasets
from quadcosim.estimators import DEFAULT_GAINS, estimate
from quadcosim.estimators.explicit import DEFAULT_TIME_CONSTANTS
from quadcosim.estimators.filters import DEFAULT_CORRECTIONS
from quadcosim.scenarios.replay import field_from_data, references

from quadcosim.infra.files import write_text

# the datasets the defaults are chosen on, each in turn held out of the search (quadcosim.benchmarks.tuning)
DEVELOPMENT = ("broad", "smartphones", "repoimu", "iphones")
# datasets measured in an earlier round whose recordings cannot be reached now: their committed rows are kept, marked
UNREACHABLE = ("diodem",)
PUBLISHED = ("vqf", "madgwick", "mahony")
OURS = ("explicit", "passive")
METRICS = ("total_rmse_deg", "heading_rmse_deg", "inclination_rmse_deg")
LARGE_ERROR_DEG = 50.0  # deg, a recording's total RMSE reported as a failure of the filter (notes)
FIELD_SECONDS = 1.0  # s, start of each recording the field references are taken from
# The recommended filter with one of its parts for real recordings taken away: settings over its defaults
ABLATIONS = {
    "no_motion_bias": {"tau_bias": math.inf},  # the bias learnt at rest only
    "no_rest_deviation": {"rest_deviation": 0.0},  # rest: the low-passes tested, not the deviations
    "no_recovery": {"mag_rejection_time": 0.0},  # a disturbance rejected for as long as it lasts
    "no_rejection": {"mag_norm_tolerance": 0.0, "mag_dip_tolerance": 0.0, "mag_rejection_time": 0.0},  # every
    # field used
    "fixed_reference": {"mag_reference_time": 0.0},  # the field of the first second the reference for ever
    "no_separation": {"heading_level": 0.0, "heading_only": 0.0},  # the magnetometer's correction tilts too
    "previous_attitude": {"correct_at_sample": 0.0},  # corrections against the previous sample's attitude
    "first_second_reference": {"mag_first_time": 0.0},  # the first reference the first second's field
    "new_field_at_reference_time": {"mag_new_time": 0.0},  # a new field adopted after mag_reference_time
    "sine_heading": {"heading_angle": 0.0},  # the heading corrected by the sine of its error
    "no_scale_change": {"mag_scale_time": 0.0},  # a field that only changed its norm waits mag_new_time too
}
TUNING_RECORDS = Path(__file__).parent / "data"  # the search records of quadcosim.benchmarks.tuning


def tuned(kind: str) -> dict | None:
    """The gains chosen for the published filter ``kind`` by :mod:`quadcosim.benchmarks.tuning` (its committed
    record ``benchmarks/data/tuning_KIND.json``), or None when it was not tuned."""
    path = TUNING_RECORDS / f"tuning_{kind}.json"
    return json.loads(path.read_text())["chosen"] if path.exists() else None


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
    filter ``kind`` on the recording ``data`` (as :mod:`quadcosim.benchmarks.datasets` loads it)."""
    found = estimate(kind, gains=gains, **_options(kind, data))["errors"]
    return {metric: np.asarray(found[metric]) for metric in METRICS}


def _published(name: str, recordings: list, cache: Path | None, kinds=PUBLISHED) -> dict:
    """Label -> {kind: {metric: deg}} of the published filters ``kinds`` at their defaults on the
    dataset ``name``, kept per filter in ``cache`` (``NAME.KIND.json``) when given."""
    table = {label: {} for label, _ in recordings}
    for kind in kinds:
        path = None if cache is None else cache / f"{name}.{kind}.json"
        if path is not None and path.exists():
            found = json.loads(path.read_text())
        else:
            found = {label: {m: float(v[0]) for m, v in errors(kind, data).items()} for label, data in recordings}
            if path is not None:
                path.parent.mkdir(parents=True, exist_ok=True)
                write_text(path, json.dumps(found, indent=1) + "\n")
        for label in table:
            table[label][kind] = found[label]
    return table


def _ablations(data: dict) -> dict:
    """Variant -> {metric: deg} of the explicit filter on ``data`` with each entry of :data:`ABLATIONS`
    (all in one batch call)."""
    variants = list(ABLATIONS)
    names = sorted({k for v in ABLATIONS.values() for k in v})
    defaults = {"tau_bias": DEFAULT_TIME_CONSTANTS["tau_bias"]} | DEFAULT_CORRECTIONS["explicit"]
    gains = {name: np.array([ABLATIONS[v].get(name, defaults[name]) for v in variants]) for name in names}
    found = errors("explicit", data, gains)
    return {v: {m: float(found[m][k]) for m in METRICS} for k, v in enumerate(variants)}


def _tuned_published(recordings: list, kinds=PUBLISHED) -> dict:
    """Label -> {"KIND_tuned": {metric: deg}} of the published filters ``kinds`` at their tuned gains
    (:func:`tuned`)."""
    rows = {label: {} for label, _ in recordings}
    for kind in kinds:
        gains = tuned(kind)
        if gains is None:
            continue
        for label, data in recordings:
            rows[label][f"{kind}_tuned"] = {m: float(v[0]) for m, v in errors(kind, data, gains).items()}
    return rows


def evaluate(folder, names=DEVELOPMENT + UNREACHABLE, cache=None, published=PUBLISHED) -> dict:
    """Per dataset, the mean total, heading and inclination RMSE (deg) of every filter at its
    defaults, of the explicit filter's ablations (:data:`ABLATIONS`) and of the published filters
    tuned by :mod:`quadcosim.benchmarks.tuning` (``vqf_tuned``, ...).

    Parameters
    ----------
    folder : str or pathlib.Path
        The data folder (one sub-folder per dataset, see :mod:`quadcosim.benchmarks.datasets`).
    names : sequence of str
        Datasets to score; those absent from ``folder`` are skipped.
    cache : str or pathlib.Path, optional
        Folder keeping the published filters' results at their defaults.
    published : sequence of str
        The published filters to score (the ``ahrs`` package's take about a millisecond a sample).

    Returns
    -------
    dict
        Dataset name -> ``{"recordings": count, "left_out": [names of the recordings not used],
        "means": {filter or variant: {metric: deg}}, "per_recording": {name: {filter: {metric: deg}}}}``.
    """
    out = {}
    for name in names:
        left_out = []
        recordings = datasets.load(folder, name, left_out)
        if not recordings:
            continue
        found = _published(name, recordings, None if cache is None else Path(cache), published)
        rows = {label: dict(found[label]) for label, _ in recordings}
        for label, extra in _tuned_published(recordings, published).items():
            rows[label] |= extra
        for label, data in recordings:
            for kind in OURS:
                rows[label][kind] = {m: float(v[0]) for m, v in errors(kind, data).items()}
            rows[label] |= {f"explicit_{v}": found for v, found in _ablations(data).items()}
        kinds = list(next(iter(rows.values())))
        means = {kind: {m: float(np.mean([rows[label][kind][m] for label in rows])) for m in METRICS}
                 for kind in kinds}
        out[name] = {"recordings": len(recordings), "left_out": left_out, "means": means, "per_recording": rows}
        print(name, {k: round(v["total_rmse_deg"], 2) for k, v in means.items()}, file=sys.stderr)
    return out


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
        for kind in (k for k in OURS + PUBLISHED if k in found["means"]):
            large = large_errors(found, kind)
            if large:
                lines.append(f"  {kind}: total RMSE above {LARGE_ERROR_DEG:g} deg on {len(large)} recordings, "
                             f"at most {large[0]:.1f} deg")
    return "\n".join(lines)


def _role(name: str) -> str:
    return "unreachable" if name in UNREACHABLE else "chose the defaults, held out in its fold"


def table(results: dict) -> str:
    """The summary tables of :func:`evaluate`'s ``results``: per dataset (its role), mean total RMSE
    (deg) of every filter at its defaults and the recommended filter's over VQF's; every filter's
    mean heading and inclination RMSE (deg); the recommended filter against the published filters
    tuned the same way; and the ablations (total, heading and inclination RMSE, deg)."""
    present = next(iter(results.values()))["means"] if results else {}
    filters = tuple(k for k in OURS + PUBLISHED if k in present)
    lines = ["| dataset (recordings) | role | " + " | ".join(filters) + " | explicit / VQF |",
             "|---" * (len(filters) + 3) + "|"]
    detail = ["| dataset | " + " | ".join(f"{k} heading / incl." for k in filters) + " |",
              "|---" * (len(filters) + 1) + "|"]
    tuned_kinds = [k for k in PUBLISHED if f"{k}_tuned" in present]
    versus = ["| dataset | explicit | " + " | ".join(f"{k} tuned" for k in tuned_kinds) + " | " +
              " | ".join(f"explicit / {k} tuned" for k in tuned_kinds) + " |",
              "|---" * (2 * len(tuned_kinds) + 2) + "|"]
    variants = ["explicit"] + [f"explicit_{v}" for v in ABLATIONS]
    ablation = ["| dataset | " + " | ".join(variants) + " |", "|---" * (len(variants) + 1) + "|"]
    for name, found in results.items():
        m = found["means"]
        total = {k: v["total_rmse_deg"] for k, v in m.items()}
        lines.append(f"| {name} ({found['recordings']}) | {_role(name)} | " +
                     " | ".join(f"{total[k]:.2f}" for k in filters) + f" | {total['explicit'] / total['vqf']:.2f} |")
        detail.append(f"| {name} | " + " | ".join(
            f"{m[k]['heading_rmse_deg']:.2f} / {m[k]['inclination_rmse_deg']:.2f}" for k in filters) + " |")
        versus.append(f"| {name} | {total['explicit']:.2f} | " +
                      " | ".join(f"{total[f'{k}_tuned']:.2f}" for k in tuned_kinds) + " | " +
                      " | ".join(f"{total['explicit'] / total[f'{k}_tuned']:.2f}" for k in tuned_kinds) + " |")
        ablation.append(f"| {name} | " + " | ".join(
            f"{m[v]['total_rmse_deg']:.2f} ({m[v]['heading_rmse_deg']:.2f} / {m[v]['inclination_rmse_deg']:.2f})"
            for v in variants) + " |")
    return "\n\n".join("\n".join(t) for t in (lines, detail, versus, ablation))


def main(argv=None) -> int:
    """Command line (see the module docstring); prints the tables, returns 0 (2 for a bad folder).
    ``argv``: the arguments (default ``sys.argv[1:]``)."""
    parser = argparse.ArgumentParser(prog="python -m quadcosim.benchmarks.real_recordings",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("folder")
    parser.add_argument("--datasets", default=",".join(DEVELOPMENT + UNREACHABLE), help="comma-separated dataset names")
    parser.add_argument("--cache", help="folder keeping the published filters' results")
    parser.add_argument("--published", default=",".join(PUBLISHED), help="comma-separated published filters to run")
    parser.add_argument("--json", help="write the figures here")
    args = parser.parse_args(argv)
    names = tuple(n.strip() for n in args.datasets.split(","))
    unknown = [n for n in names if n not in datasets.LOADERS]
    if unknown or not Path(args.folder).is_dir():
        from quadcosim.infra.errors import UsageError

        raise UsageError(f"{args.folder} is not a folder, or unknown dataset {unknown}; datasets are "
                         f"{', '.join(datasets.LOADERS)}")
    results = evaluate(args.folder, names, args.cache, tuple(k.strip() for k in args.published.split(",") if k))
    print(table(results))
    print(notes(results))
    report = {"results": results, "defaults": {k: DEFAULT_GAINS[k] for k in OURS},
              "time_constants": DEFAULT_TIME_CONSTANTS}
    if args.json:
        write_text(args.json, json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":  # the same as quadcosim bench real-recordings
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench real-recordings").run, main)
