"""A student's first week, each wrong turn a newcomer took: ``quadcosim --version``, the docs of
``result.save``, a streamed run's message and its replay, the hint for ``IMU.R_reel`` that tp
leaves out of its files, and a filter of one's own fed the true rotation through
``AttitudeEstimator.update``."""

import re
from pathlib import Path

import numpy as np
import pytest
from quadcosim.estimators.contract import AttitudeEstimator
from quadcosim.orchestrator import Result
from scipy.spatial.transform import Rotation

from quadcosim import scenarios
from quadcosim.main import main

ROOT = Path(__file__).resolve().parents[1]


def test_version_is_the_packages(capsys):
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    version = re.search(r'^version = "(.+)"$', (ROOT / "pyproject.toml").read_text(), re.M).group(1)
    assert capsys.readouterr().out.strip() == f"quadcosim {version}"


def test_result_save_writes_what_the_docs_say(tmp_path):
    result, _ = scenarios.run("open-loop", {"duration": 0.05})
    written = sorted(p.name for p in result.save(tmp_path / "a"))
    assert written == ["results.npz"]
    assert sorted(p.name for p in result.save(tmp_path / "b", formats=("npz", "mat"))) == ["results.mat",
                                                                                            "results.npz"]
    for page in ("README.md", "docs/getting-started.md"):
        text = " ".join((ROOT / page).read_text().split())
        assert "`result.save(folder)` writes `.npz` (`formats=(\"npz\", \"mat\")` adds MATLAB `.mat`" in text, page


def test_a_streamed_run_says_where_its_record_is_and_replays(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["run", "tp", "--set", "duration=0.5", "--stream", "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert "the record streamed (results.stream/), metrics.json" in said and "results (npz)" not in said
    assert not (out / "results.npz").exists()
    assert main(["replay", str(out)]) == 0
    assert "quaternion error RMS (deg): total" in capsys.readouterr().out


def test_the_signal_tp_leaves_out_says_how_to_keep_it(tmp_path):
    scenarios.run("tp", {"duration": 0.1}, out_dir=tmp_path / "r")
    result = Result.load(tmp_path / "r")
    with pytest.raises(KeyError, match=r"'IMU.R_reel': the scenario left it out of its result files .*run it with "
                                       r"--record all"):
        result["IMU.R_reel"]
    with pytest.raises(KeyError, match="Did you mean"):
        result["IMU.nope"]


class TrueRotation(AttitudeEstimator):
    """The estimate is the true rotation itself, read from R_reel: an estimator of zero error."""

    def update(self, acc, gyro, mag, R_reel):
        x, y, z, w = Rotation.from_matrix(R_reel).as_quat()
        self.q = np.array([w, x, y, z])


def test_an_attitude_estimator_can_read_the_true_rotation():
    result, metrics = scenarios.run("tp", {"duration": 1.0, "flight": "hover", "noise": True}, estimator=TrueRotation)
    assert metrics["status"] == "completed"
    error = np.asarray(result["Quaternion_estim.theta_est"]) - np.asarray(result["Quadrotor.theta"])
    assert np.abs(error[1:]).max() < 1e-9  # the first sample precedes the first IMU reading


def test_list_parameters_shows_what_each_scenario_sets(capsys):
    """tp runs the IMU with noise off (its option noise), which the FMU's own default (on) hides."""
    assert main(["list", "--parameters", "IMU"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"noise_enabled +  = True", out)  # the FMU's default, as before
    assert "IMU parameters the scenarios set from their options" in out
    assert "  tp: noise_enabled <- option noise (default False); bias_enabled <- option bias (default False)" in out
    assert main(["list", "--parameters", "Quadrotor"]) == 0
    assert "  metge: clamped <- (the rig)" in capsys.readouterr().out


def test_the_testing_guide_says_when_parallel_workers_pay():
    """-n 2 was recommended flat; on two cores the guide's own example ran slower with it."""
    text = " ".join((ROOT / "docs" / "guides" / "testing.md").read_text().split())
    assert "When it pays: only when the suite runs much longer in series than a worker takes to start" in text
    assert "slower with `-n 2` than without on a two-core machine" in text


def test_the_docs_pages_keep_no_empty_section_navigation():
    """Every page is a child of the index alone: the primary sidebar would be an empty column
    (430 px of a 1280 px window); long commands and table cells wrap."""
    namespace = {"__file__": str(ROOT / "docs" / "conf.py")}
    source = (ROOT / "docs" / "conf.py").read_text()
    exec(compile(source.split("# equations as MathML")[0], "conf.py", "exec"), namespace)
    sidebars = namespace["html_sidebars"]
    assert sidebars["*"] == sidebars["guides/*"] == sidebars["_generated/*"] == []
    nested = sorted(p.stem for p in (ROOT / "docs").glob("*.md") if "toctree" in p.read_text() and p.stem != "index")
    assert nested == ["notebooks"]  # the one section of pages of its own: its pages keep their navigation
    assert sidebars["notebooks"] == sidebars["_generated/notebooks/*"] == ["sidebar-nav-bs"]
    css = (ROOT / "docs" / "_static" / "layout.css").read_text()
    assert "white-space: pre-wrap" in css and "overflow-wrap: anywhere" in css

