"""Silent wrong results: a rig whose clamp is released (``Quadrotor.clamped=false``) once
completed with the vehicle 284 m below the ground. The clamped scenarios declare the bounds of
a vehicle that does not move (:data:`quadcosim.scenarios.divergence.CLAMPED`): such a run ends
``diverged``, exit 1; metge, which fixes the clamp, says so in words."""

import json

import pytest
from quadcosim.scenarios import get
from quadcosim.scenarios.divergence import CLAMPED

from quadcosim.main import main as cli

RIG = ["run", "rig", "--set", "sweep=1", "free=1"]


def test_a_rig_released_from_its_clamp_ends_diverged(tmp_path, capsys):
    assert cli([*RIG, "Quadrotor.clamped=false", "--out", str(tmp_path / "free")]) == 1
    metrics = json.loads((tmp_path / "free" / "metrics.json").read_text())
    assert metrics["status"] == "diverged"
    assert metrics["diverged"]["what"].startswith("a speed of") and metrics["diverged"]["at_s"] < 1.0
    assert "Quadrotor.clamped=False" in metrics["diverged"]["settings"]
    assert "rig diverged at t = " in capsys.readouterr().err


def test_the_clamped_rig_completes_within_its_bounds(tmp_path):
    assert cli([*RIG, "--out", str(tmp_path / "rig")]) == 0
    metrics = json.loads((tmp_path / "rig" / "metrics.json").read_text())
    assert metrics["status"] == "completed" and "divergence_unchecked" not in metrics


@pytest.mark.parametrize("name", ["rig", "metge"])
def test_the_clamped_scenarios_declare_the_clamped_bounds(name):
    assert get(name).extra["divergence"] is CLAMPED


def test_metge_names_the_clamp_as_fixed(tmp_path, capsys):
    assert cli(["run", "metge", "--set", "Quadrotor.clamped=false", "--out", str(tmp_path / "m")]) == 2
    err = capsys.readouterr().err
    assert "Quadrotor.clamped is fixed by scenario metge (the rig): leave Quadrotor.clamped out of --set" in err
    assert "use --set (the rig)" not in err
