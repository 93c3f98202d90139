"""Findings on public real recordings: our filters at their defaults against VQF, Madgwick and Mahony.

The numbers need the datasets, which are not shipped (:mod:`benchmarks.datasets` says where each
comes from): set ``QUADCOSIM_REAL_DATA`` to the data folder (and optionally
``QUADCOSIM_REAL_CACHE`` to a folder keeping the published filters' results, which take tens of
minutes). Without the data, :func:`compute` raises ``FileNotFoundError``: the group is skipped and
its recorded values stay as they were, not reproducible on a machine without the data (CI).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from estimators import kinds

COMMAND = "python -m benchmarks.real_recordings DATA"
CHOOSE = "python -m benchmarks.tuning DATA"
LARGE = "mahony"  # the filter whose failures on single recordings the documentation counts
FILTERS = {name: kinds.KINDS[name].label for name in ("explicit", "passive", "vqf", "madgwick", "mahony")}
METRICS = {"total_rmse_deg": "total", "heading_rmse_deg": "heading", "inclination_rmse_deg": "inclination"}
TOLERANCE_DEG = 0.005  # deg: the figures are deterministic; printed to 2 decimals
DIGITS = 2


def _entry(name, value, unit, digits=DIGITS, tolerance=TOLERANCE_DEG, command=COMMAND) -> dict:
    return {"name": f"real_recordings.{name}", "value": float(value), "unit": unit, "command": command,
            "tolerance": tolerance, "digits": digits}


def findings(results: dict) -> list[dict]:
    """The findings of :func:`benchmarks.real_recordings.evaluate`'s ``results``: per dataset, its
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


def tuning(records: dict) -> list[dict]:
    """The search records of :mod:`benchmarks.tuning` (filter -> record): the values chosen, the score
    there (the worst development dataset's ratio to VQF) and the number of gain sets scored."""
    out = []
    for kind, record in records.items():
        for name, value in record["chosen"].items():
            digits = 0 if float(value).is_integer() else 3
            out.append(_entry(f"tuning.{kind}.{name}", value, "1", digits, 0.0, f"{CHOOSE} --filter {kind}"))
        out.append(_entry(f"tuning.{kind}.score", record["score"], "1", 2, 0.005, f"{CHOOSE} --filter {kind}"))
    return out


def notes(results: dict) -> list[dict]:
    """What the means of ``results`` (:func:`benchmarks.real_recordings.evaluate`'s) hide
    (:func:`benchmarks.real_recordings.notes`): per dataset that left
    recordings out, how many of how many; on ``broad``, the recordings where Mahony's total RMSE
    exceeds :data:`benchmarks.real_recordings.LARGE_ERROR_DEG`, how many and the largest (deg)."""
    from benchmarks.real_recordings import large_errors

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
    is not re-run here: ``python -m benchmarks.tuning DATA`` re-runs it). ``QUADCOSIM_REAL_PUBLISHED``
    names the published filters to run (comma-separated; default all).
    Raises ``FileNotFoundError`` when the data are absent."""
    folder = os.environ.get("QUADCOSIM_REAL_DATA")
    if not folder or not Path(folder).is_dir():
        raise FileNotFoundError("the real recordings are not on this machine: set QUADCOSIM_REAL_DATA to their "
                                "folder (see benchmarks/datasets.py); the recorded values are kept")
    import json

    from benchmarks import real_recordings

    cache = os.environ.get("QUADCOSIM_REAL_CACHE")
    published = tuple(k for k in os.environ.get("QUADCOSIM_REAL_PUBLISHED", "vqf,madgwick,mahony").split(",") if k)
    records = {path.stem.removeprefix("tuning_"): json.loads(path.read_text())
               for path in sorted(real_recordings.TUNING_RECORDS.glob("tuning_*.json"))}
    return findings(real_recordings.evaluate(folder, cache=cache, published=published)) + tuning(records)


def _deg(value) -> str:
    return "—" if math.isnan(value) else f"{value:.2f}"
