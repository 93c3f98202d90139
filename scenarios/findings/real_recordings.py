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

COMMAND = "python -m benchmarks.real_recordings DATA"
CHOOSE = "python -m benchmarks.real_recordings DATA --choose"
LARGE = "mahony"  # the filter whose failures on single recordings the documentation counts
FILTERS = {"explicit": "explicit", "passive": "passive", "vqf": "VQF", "madgwick": "Madgwick", "mahony": "Mahony"}
METRICS = {"total_rmse_deg": "total", "heading_rmse_deg": "heading", "inclination_rmse_deg": "inclination"}
TOLERANCE_DEG = 0.005  # deg: the figures are deterministic; printed to 2 decimals
DIGITS = 2


def _entry(name, value, unit, digits=DIGITS, tolerance=TOLERANCE_DEG) -> dict:
    return {"name": f"real_recordings.{name}", "value": float(value), "unit": unit, "command": COMMAND,
            "tolerance": tolerance, "digits": digits}


def findings(results: dict) -> list[dict]:
    """The findings of :func:`benchmarks.real_recordings.evaluate`'s ``results``: per dataset, its
    number of recordings, every filter's mean total, heading and inclination RMSE (deg), and our
    best filter's mean total RMSE over VQF's."""
    out = []
    for dataset, found in results.items():
        out.append(_entry(f"{dataset}.recordings", found["recordings"], "1", 0, 0.0))
        for kind in FILTERS:
            for metric in METRICS:
                value = found["means"][kind][metric]
                if not math.isnan(value):  # a filter not run on the dataset: no finding
                    out.append(_entry(f"{dataset}.{kind}.{metric}", value, "deg"))
        best = min(found["means"][k]["total_rmse_deg"] for k in ("explicit", "passive"))
        out.append(_entry(f"{dataset}.best_over_vqf", best / found["means"]["vqf"]["total_rmse_deg"], "1"))
    return out + notes(results)


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
    if "broad" in results:
        large = large_errors(results["broad"], LARGE)
        out += [_entry(f"notes.broad.{LARGE}_large_errors", len(large), "1", 0, 0.0),
                _entry(f"notes.broad.{LARGE}_largest_error_deg", large[0] if large else 0.0, "deg", 1, 0.05)]
    return out


def left_out_ratios(choice: dict) -> list[dict]:
    """The cross-validation ``choice`` of :func:`benchmarks.real_recordings.choose`: for each filter and each
    choosing dataset, its error over VQF's there at the gains chosen without it."""
    return [{**_entry(f"choice.{kind}.without_{dataset}_over_vqf", fold["ratio_to_vqf"], "1"), "command": CHOOSE}
            for kind, chosen in choice.items() for dataset, fold in chosen["left_out"].items()]


def compute(quick: bool = False) -> list[dict]:
    """The group's findings, from the data folder named by ``QUADCOSIM_REAL_DATA``; ``quick`` leaves
    out the cross-validation over the gain grid (the published filters' results come from
    ``QUADCOSIM_REAL_CACHE`` when kept there).
    Raises ``FileNotFoundError`` when the data are absent."""
    folder = os.environ.get("QUADCOSIM_REAL_DATA")
    if not folder or not Path(folder).is_dir():
        raise FileNotFoundError("the real recordings are not on this machine: set QUADCOSIM_REAL_DATA to their "
                                "folder (see benchmarks/datasets.py); the recorded values are kept")
    from benchmarks import real_recordings

    cache = os.environ.get("QUADCOSIM_REAL_CACHE")
    found = findings(real_recordings.evaluate(folder, cache=cache))
    if quick:
        return found
    grids = real_recordings.evaluate(folder, real_recordings.CHOOSING, cache, grids=True)
    return found + left_out_ratios(real_recordings.choose(grids))


def _deg(value) -> str:
    return "—" if math.isnan(value) else f"{value:.2f}"


def readme_tables(results: dict) -> str:
    """The README's two tables (mean total RMSE and best over VQF; heading and inclination) from
    :func:`benchmarks.real_recordings.evaluate`'s ``results``."""
    from benchmarks.real_recordings import HELD_OUT

    head = "| dataset (recordings) | role | " + " | ".join(FILTERS.values()) + " | best / VQF |"
    lines = [head, "|---" * (len(FILTERS) + 3) + "|"]
    detail = ["| dataset | " + " | ".join(f"{label} heading / incl." for label in FILTERS.values()) + " |",
              "|---" * (len(FILTERS) + 1) + "|"]
    for dataset, found in results.items():
        m = found["means"]
        role = "held out" if dataset in HELD_OUT else "chose the defaults"
        best = min(m["explicit"]["total_rmse_deg"], m["passive"]["total_rmse_deg"]) / m["vqf"]["total_rmse_deg"]
        lines.append(f"| {dataset} ({found['recordings']}) | {role} | " +
                     " | ".join(_deg(m[k]["total_rmse_deg"]) for k in FILTERS) + f" | {best:.2f} |")
        detail.append(f"| {dataset} | " + " | ".join(
            f"{_deg(m[k]['heading_rmse_deg'])} / {_deg(m[k]['inclination_rmse_deg'])}" for k in FILTERS) + " |")
    return "\n".join(lines) + "\n\n" + "\n".join(detail)
