"""Findings on public real recordings: our filters at their defaults against VQF, Madgwick and Mahony.

The numbers need the datasets, which are not shipped (:mod:`quadcosim.benchmarks.datasets` says where each
comes from): set ``QUADCOSIM_REAL_DATA`` to the data folder (and optionally
``QUADCOSIM_REAL_CACHE`` to a folder keeping the published filters' results, which take tens of
minutes). Without the data, :func:`compute` raises ``FileNotFoundError``: the group is skipped and
its recorded values stay as they were, not reproducible on a machine without the data (CI).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from quadcosim.estimators import kinds

COMMAND = "python -m quadcosim.benchmarks.real_recordings DATA"
CHOOSE = "python -m quadcosim.benchmarks.tuning DATA"
FOLDS = "python -m quadcosim.benchmarks.tuning DATA --score-folds"
LARGE = "mahony"  # the filter whose failures on single recordings the documentation counts
FILTERS = {name: kinds.get(name).label for name in ("explicit", "passive", "vqf", "madgwick", "mahony")}
METRICS = {"total_rmse_deg": "total", "heading_rmse_deg": "heading", "inclination_rmse_deg": "inclination"}
TOLERANCE_DEG = 0.005  # deg: the figures are deterministic; printed to 2 decimals
DIGITS = 2


def _entry(name, value, unit, digits=DIGITS, tolerance=TOLERANCE_DEG, command=COMMAND) -> dict:
    return {"name": f"real_recordings.{name}", "value": float(value), "unit": unit, "command": command,
            "tolerance": tolerance, "digits": digits}


def findings(results: dict) -> list[dict]:
    """The findings of :func:`quadcosim.benchmarks.real_recordings.evaluate`'s ``results``: per dataset, its
    number of recordings, the mean total, heading and inclination RMSE (deg) of every filter, of
    the published filters tuned the same way as ours and of the recommended filter's ablations,
    and the recommended filter's mean total RMSE over VQF's (at VQF's defaults, and tuned)."""
    out = []
    for dataset, found in results.items():
        out.append(_entry(f"{dataset}.recordings", found["recordings"], "1", 0, 0.0))
        for kind, means in found["means"].items():
            for metric in METRICS:
                value = means[metric]
                if not math.isnan(value):  # a filter not run on the dataset: no finding
                    out.append(_entry(f"{dataset}.{kind}.{metric}", value, "deg"))
        total = {k: v["total_rmse_deg"] for k, v in found["means"].items()}
        out.append(_entry(f"{dataset}.explicit_over_vqf", total["explicit"] / total["vqf"], "1"))
        for kind in ("vqf", "madgwick", "mahony"):
            if f"{kind}_tuned" in total:
                out.append(_entry(f"{dataset}.explicit_over_{kind}_tuned", total["explicit"] / total[f"{kind}_tuned"],
                                  "1"))
    return out + notes(results)


def _value(name, value, command) -> dict:
    """A chosen value (a grid point), printed with the decimals it has (at most 3)."""
    digits = next((d for d in range(3) if round(float(value), d) == float(value)), 3)
    return _entry(name, value, "1", digits, 0.0, command)


def tuning(records: dict) -> list[dict]:
    """The search records of :mod:`quadcosim.benchmarks.tuning` (filter -> record): the values chosen on all the
    datasets, the score there, and the values each leave-one-dataset-out fold chose without its dataset."""
    out = []
    for kind, record in records.items():
        command = f"{CHOOSE} --filter {kind}"
        for name, value in record["chosen"].items():
            out.append(_value(f"tuning.{kind}.{name}", value, command))
        out.append(_entry(f"tuning.{kind}.score", record["score"], "1", 2, 0.005, command))
        for held, fold in record.get("folds", {}).items():
            out += [_value(f"tuning.{kind}.without_{held}.{name}", value, command)
                    for name, value in fold["values"].items()]
    return out


def folds(scores: dict) -> list[dict]:
    """The leave-one-dataset-out table (:func:`quadcosim.benchmarks.tuning.score_folds`' ``scores``): per
    dataset, while it was held out of the search, the mean total RMSE (deg) of the explicit filter
    at its fold's values, of VQF at its defaults and of VQF tuned by the same fold, and the ratios."""
    out = []
    for held, found in scores.items():
        for kind in ("explicit", "vqf", "vqf_tuned"):
            out.append(_entry(f"folds.{held}.{kind}", found[kind]["total_rmse_deg"], "deg", command=FOLDS))
        for ratio in ("explicit_over_vqf", "explicit_over_vqf_tuned", "vqf_tuned_over_vqf"):
            out.append(_entry(f"folds.{held}.{ratio}", found[ratio], "1", command=FOLDS))
    ratios = [found["explicit_over_vqf"] for found in scores.values()]
    if ratios:
        out.append(_entry("folds.worst_explicit_over_vqf", max(ratios), "1", command=FOLDS))
    return out


def swaps(found: dict, held: str) -> list[dict]:
    """The findings of :func:`quadcosim.benchmarks.tuning.swaps` on the held-out dataset ``held``: the fold's and
    the defaults' ratio to VQF there, and each differing parameter swapped in either direction."""
    out = [_entry(f"swaps.{held}.{k}", found[k], "1", command=FOLDS) for k in ("fold", "defaults")]
    for name, ratios in found["swapped"].items():
        out += [_entry(f"swaps.{held}.{name}.{k}", v, "1", command=FOLDS) for k, v in ratios.items()]
    return out


def unreachable() -> list[dict]:
    """The rows of the datasets that cannot be reached now
    (:data:`quadcosim.benchmarks.real_recordings.UNREACHABLE`), as measured in an earlier round and kept in
    their committed records (``benchmarks/data/unreachable_NAME.json``), named
    ``real_recordings.unreachable.NAME.*``: not re-measured, at the defaults of that round."""
    import json

    from quadcosim.benchmarks import real_recordings

    out = []
    for name in real_recordings.UNREACHABLE:
        record = json.loads((real_recordings.TUNING_RECORDS / f"unreachable_{name}.json").read_text())
        for key, value in record["values"].items():
            unit = "1" if key == "recordings" or "_over_" in key else "deg"
            digits, tolerance = (0, 0.0) if key == "recordings" else (DIGITS, 0.0)
            out.append(_entry(f"unreachable.{name}.{key}", value, unit, digits, tolerance,
                              f"{COMMAND} --datasets {name}"))
    return out


def notes(results: dict) -> list[dict]:
    """What the means of ``results`` (:func:`quadcosim.benchmarks.real_recordings.evaluate`'s) hide
    (:func:`quadcosim.benchmarks.real_recordings.notes`): per dataset that left
    recordings out, how many of how many; on ``broad``, the recordings where Mahony's total RMSE
    exceeds :data:`quadcosim.benchmarks.real_recordings.LARGE_ERROR_DEG`, how many and the largest (deg)."""
    from quadcosim.benchmarks.real_recordings import large_errors

    out = []
    for dataset, found in results.items():
        left = len(found.get("left_out", []))
        if left:
            out += [_entry(f"notes.{dataset}.left_out", left, "1", 0, 0.0),
                    _entry(f"notes.{dataset}.available", found["recordings"] + left, "1", 0, 0.0)]
    if "broad" in results and LARGE in results["broad"]["means"]:
        large = large_errors(results["broad"], LARGE)
        out += [_entry(f"notes.broad.{LARGE}_large_errors", len(large), "1", 0, 0.0),
                _entry(f"notes.broad.{LARGE}_largest_error_deg", large[0] if large else 0.0, "deg", 1, 0.05)]
    return out


def compute(quick: bool = False) -> list[dict]:
    """The group's findings, from the data folder named by ``QUADCOSIM_REAL_DATA`` (the published
    filters' results at their defaults come from ``QUADCOSIM_REAL_CACHE`` when kept there), and the
    tuning's committed records (``benchmarks/data/tuning_*.json``; ``quick`` or not, the search itself
    is not re-run here: ``python -m quadcosim.benchmarks.tuning DATA`` re-runs it). ``QUADCOSIM_REAL_PUBLISHED``
    names the published filters to run (comma-separated; default all).
    Raises ``FileNotFoundError`` when the data are absent."""
    folder = os.environ.get("QUADCOSIM_REAL_DATA")
    if not folder or not Path(folder).is_dir():
        raise FileNotFoundError("the real recordings are not on this machine: set QUADCOSIM_REAL_DATA to their "
                                "folder (see benchmarks/datasets.py); the recorded values are kept")
    import json

    from quadcosim.benchmarks import real_recordings

    cache = os.environ.get("QUADCOSIM_REAL_CACHE")
    published = tuple(k for k in os.environ.get("QUADCOSIM_REAL_PUBLISHED", "vqf,madgwick,mahony").split(",") if k)
    from quadcosim.benchmarks import tuning as search

    records = {path.stem.removeprefix("tuning_"): json.loads(path.read_text())
               for path in sorted(real_recordings.TUNING_RECORDS.glob("tuning_*.json"))}
    results = real_recordings.evaluate(folder, names=real_recordings.DEVELOPMENT, cache=cache, published=published)
    scores = search.score_folds(folder, log=lambda text: None)
    worst = search.worst_fold(scores)  # the fold whose loss is taken apart
    return (findings(results) + tuning(records) + folds(scores) + swaps(search.swaps(folder, worst), worst)
            + unreachable())


def _deg(value) -> str:
    return "—" if math.isnan(value) else f"{value:.2f}"
