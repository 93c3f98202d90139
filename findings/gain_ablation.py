"""Findings of the gain study's ablations: its estimate-fed runs with an accelerometer that sees
gravity alone, and without rotor drag (two ``quadcosim run gain-study`` runs, minutes each)."""

from __future__ import annotations

from findings import finding

PERCENT = 100.0
GRAVITY = {"closed_accelerometer": "gravity"}
NO_DRAG = {"closed_drag": False}


def _command(settings: dict) -> str:
    key, value = next(iter(settings.items()))
    return f"quadcosim run gain-study --set {key}={'off' if value is False else value}"


def compute(quick: bool = False) -> list[dict]:
    """The closed loop's relative difference from the prediction: its range over every gain and
    at the largest with gravity alone; at the largest without drag (a ratio). ``quick``: none."""
    if quick:
        return []
    from quadcosim import (
        scenarios,
        studies,  # noqa: F401  (registers gain-study)
    )

    gravity = scenarios.run("gain-study", GRAVITY)[1]["closed_loop_relative_difference"]
    no_drag = scenarios.run("gain-study", NO_DRAG)[1]["closed_loop_relative_difference"]
    return [finding("gain_ablation.gravity.min_pct", PERCENT * min(gravity), "%", _command(GRAVITY), 0.5, 0),
            finding("gain_ablation.gravity.max_pct", PERCENT * max(gravity), "%", _command(GRAVITY), 0.5, 0),
            finding("gain_ablation.gravity.largest_gain_pct", PERCENT * gravity[-1], "%", _command(GRAVITY), 0.5, 0),
            finding("gain_ablation.no_drag.largest_gain_ratio", 1.0 + no_drag[-1], "1", _command(NO_DRAG), 0.5, 0)]
