"""Every trajectory equal to the last bit to those of the code before the FMUs' lean step path,
the reuse of FMU instances and the sweep changes: a SHA-256 (first 16 hex digits) of every
recorded signal of six short runs, stored in tests/data/trajectories.json from that code. A
change of physics or numerics changes them, and must come with new digests."""

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

import scenarios
from orchestrator import pool

STORED = json.loads((Path(__file__).resolve().parent / "data" / "trajectories.json").read_text())
RUNS = {
    "tp-linear": ("tp", {"duration": 2.0}),
    "tp-explicit-noise-bias-nonstationary-estimate": ("tp", {"duration": 2.0, "estimator": "explicit", "noise": True,
                                                              "bias": True, "flight": "nonstationary",
                                                              "feedback": "estimate", "seed": 3}),
    "tp-passive-triad-magnetic": ("tp", {"duration": 2.0, "estimator": "passive", "ry": "triad", "bias": True,
                                         "magnetic": True, "noise": True}),
    "open-loop-noise": ("open-loop", {"duration": 1.0, "noise": True, "bias": True}),
    "rig": ("rig", {"reference": 0.2, "sweep": 0.2, "noise": True}),
    "ir-calibration": ("ir-calibration", {"duration": 20.0}),
}


def digest(values) -> str:
    return hashlib.sha256(np.ascontiguousarray(values).tobytes()).hexdigest()[:16]


def digests(name: str, options: dict) -> dict:
    result, _ = scenarios.run(name, dict(options))
    return {signal: digest(result[signal]) for signal in result.names} | {"time": digest(result.time)}


@pytest.mark.parametrize("label", RUNS)
def test_every_recorded_signal_is_unchanged_to_the_bit(label):
    now = digests(*RUNS[label])
    changed = sorted(k for k in STORED[label] if now.get(k) != STORED[label][k])
    assert set(now) == set(STORED[label])
    assert not changed, f"{label}: {len(changed)} signals changed, e.g. {changed[:5]}"


def test_runs_on_reused_fmu_instances_are_unchanged_to_the_bit():
    previous = pool.reuse(True)
    try:
        for label in ("ir-calibration", "tp-passive-triad-magnetic", "tp-explicit-noise-bias-nonstationary-estimate"):
            assert digests(*RUNS[label]) == STORED[label], label
    finally:
        pool.reuse(previous)
