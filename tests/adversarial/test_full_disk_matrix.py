"""Acceptance 3, CI's share: three of ``full_disk_matrix.py``'s 36 runs, as processes on a real
tmpfs (skipped where mounting is not permitted). A run whose disk fills while it saves its record,
a streamed run whose disk fills while it runs, and a replay with no room for its JSON: each leaves
``metrics.json`` (or its JSON) or nothing, no temporary, and no empty or partial file under a final
name. The disk sizes sit inside the phases the full matrix measured (a run writes about 620 kB,
a streamed one about 730 kB); whichever side of a phase's edge another machine falls on, the rule
is the same."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import full_disk_matrix as matrix  # noqa: E402

CASES = [("run", 470_000, "saving the record"), ("run --stream", 624_000, "running"), ("log replay", 0, None)]


@pytest.fixture(scope="module")
def log(tmp_path_factory):
    return matrix.synthetic_log(tmp_path_factory.mktemp("log"))


@pytest.mark.parametrize(("name", "budget", "phase"), CASES)
def test_a_disk_that_fills_leaves_metrics_json_or_nothing(tmp_path, log, name, budget, phase):
    if os.geteuid() != 0 or subprocess.run(["mount", "--version"], capture_output=True).returncode != 0:
        pytest.skip("mounting a tmpfs is not permitted here")
    found = matrix.one(name, log, tmp_path, budget)
    assert found["problems"] == [], found
    assert found["exit"] in (1, 2), found  # never 0 on a disk too small
    if found["left"] == "nothing":  # refused before it began (exit 2), or no room for even metrics.json
        assert found["exit"] == 2 or "no space left" in found["said"], found
    elif name != "log replay":
        assert found["left"].startswith("metrics.json (failed"), found
        assert phase in found["left"] or "reporting" in found["left"], found
    else:
        pytest.fail(f"a replay wrote its JSON on a full disk: {found}")
