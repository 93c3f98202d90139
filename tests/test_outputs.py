"""Result files, metrics.json and the default output folder of `quadcosim run`."""

from __future__ import annotations

import json

import numpy as np
import pytest
from quadcosim.estimators import LAB_GAINS
from quadcosim.orchestrator import Result
from quadcosim.orchestrator.signals import matrix_shape, vector_groups
from scipy.io import loadmat

from quadcosim.main import main as cli


def test_vectors_are_grouped_by_name():
    names = ["IMU.acc_x", "IMU.acc_y", "IMU.acc_z", "Quadrotor.q0", "Quadrotor.q1", "Quadrotor.q2", "Quadrotor.q3",
             "MotorMagnetics.u_batt", "Quadrotor.i_max", *[f"IMU.R_reel_{i}{j}" for i in "123" for j in "123"],
             "A.c1", "A.c", "A.c2"]
    groups = vector_groups(names)
    assert groups == {"IMU.acc": ["IMU.acc_x", "IMU.acc_y", "IMU.acc_z"],
                      "Quadrotor.q": ["Quadrotor.q0", "Quadrotor.q1", "Quadrotor.q2", "Quadrotor.q3"],
                      "IMU.R_reel": [f"IMU.R_reel_{i}{j}" for i in "123" for j in "123"]}  # A.c is a signal itself
    assert matrix_shape(groups["IMU.R_reel"]) == (3, 3) and matrix_shape(groups["Quadrotor.q"]) == (4,)


def test_result_files_hold_vectors_units_and_options_and_no_tie_offs(tmp_path):
    out = tmp_path / "run"
    assert cli(["run", "open-loop", "--set", "duration=0.2", "--out", str(out), "--format", "npz,mat"]) == 0
    saved = Result.from_npz(out / "results.npz")
    assert not [n for n in saved.names if n.startswith("Const_")]  # the tie-offs of the wind are no signals
    assert saved.meta["constant_inputs"]["Quadrotor.wind_x"] == 0.0  # but their values are kept
    assert saved.units["IMU.acc_x"] == "m/s2" and saved.units["Quadrotor.omega_x"] == "rad/s"
    assert saved.options["duration"] == 0.2
    with np.load(out / "results.npz") as archive:  # the vector as one N x 3 array, R_reel N x 3 x 3
        assert archive["IMU.acc"].shape == (201, 3) and archive["IMU.R_reel"].shape == (201, 3, 3)
        assert np.array_equal(archive["IMU.acc"][:, 1], saved["IMU.acc_y"])
        assert np.array_equal(archive["IMU.R_reel"][:, 0, 2], saved["IMU.R_reel_13"])
        assert "IMU.acc_x" not in archive.files  # stored once
    mat = loadmat(out / "results.mat", squeeze_me=True)
    imu = mat["IMU"]
    assert imu["acc"].item().shape == (201, 3) and imu["R_reel"].item().shape == (201, 3, 3)
    assert np.array_equal(imu["R_reel"].item()[:, 1, 0], saved["IMU.R_reel_21"])
    assert np.array_equal(imu["acc_z"].item(), saved["IMU.acc_z"])
    assert mat["units"]["IMU"].item()["acc_x"].item() == "m/s2" and mat["units"]["time"].item() == "s"
    assert mat["options"]["duration"].item() == 0.2
    assert not [k for k in mat if k.startswith("Const_")]


def test_a_20_s_tp_run_writes_its_record_uncompressed_and_matlab_reads_units_and_options(tmp_path):
    """tp's default run of 20 s, every file it writes; its results as MATLAB reads them. The
    record is stored uncompressed (fast to write): 8 bytes a value; ``compress`` makes it smaller."""
    out = tmp_path / "tp"
    assert cli(["run", "tp", "--set", "duration=20", "--set", "noise=on", "--set", "bias=on",
                "--set", "estimator=explicit", "--out", str(out)]) == 0
    written = {p.name: p.stat().st_size for p in out.iterdir()}
    assert "results.mat" not in written and "results.npz" in written
    total = sum(written.values())
    saved = Result.from_npz(out / "results.npz")
    metrics = json.loads((out / "metrics.json").read_text())
    values = 8 * len(saved) * (len(saved.names) + 1)
    assert values < written["results.npz"] < values + 100e3, written  # the arrays, their headers and _meta
    assert metrics["results_npz_mb"] == written["results.npz"] / 1e6  # the size the run prints
    assert metrics["units"]["results_npz_mb"] == "MB"
    assert total < 15e6, written  # measured 14.6 MB, figures included
    saved.to_npz(tmp_path / "compressed.npz", compress=True)
    assert (tmp_path / "compressed.npz").stat().st_size < 0.65 * values  # measured 0.60 of the values
    assert sorted(metrics["signals_not_saved"])[:2] == ["IMU.R_reel_11", "IMU.R_reel_12"]
    saved.to_mat(tmp_path / "results.mat")
    mat = loadmat(tmp_path / "results.mat")
    assert mat["Quadrotor"]["q"][0, 0].shape == (20001, 4)
    assert mat["units"]["Quadrotor"][0, 0]["omega_x"][0, 0][0] == "rad/s"
    options = mat["options"][0, 0]
    assert options["estimator"][0] == "explicit" and options["noise"][0, 0]
    assert options["kI"][0, 0] == LAB_GAINS["explicit"]["kI"]  # the gain used, not the word lab
    print(f"20 s tp: {total / 1e6:.2f} MB written: {written}")


def test_metrics_state_options_as_used_units_tolerances_faults_and_steady_error(tmp_path):
    out = tmp_path / "tp"
    assert cli(["run", "tp", "--set", "duration=2", "--set", "estimator=passive", "--set", "bias=on",
                "--fault", "IMU.omega_x:offset:0.5:1:0.05", "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["options"]["kI"] == LAB_GAINS["passive"]["kI"]
    assert metrics["injected_faults"] == [{"target": "IMU.omega_x", "kind": "offset", "start": 0.5, "stop": 1.0,
                                           "value": 0.05, "seed": 0}]
    assert metrics["units"]["injected_faults"].startswith("start, stop: s")
    assert metrics["bias_convergence_tolerance_rad_s"] == 1e-3
    units = metrics["units"]
    assert units["rms_error_deg"] == "deg" and units["bias_error_final"] == "rad/s"
    assert units["options.kI"] == "1/s^2" and units["options.duration"] == "s" and units["options.imu_rate"] == "Hz"
    assert len(metrics["steady_error_deg"]) == 3 and metrics["steady_window_s"] == [1.5, 2.0]
    with np.load(out / "results.npz") as archive:
        meta = json.loads(str(archive["_meta"]))
    assert meta["faults"] == metrics["injected_faults"] and meta["options"]["kI"] == metrics["options"]["kI"]


def test_the_default_out_never_replaces_earlier_results(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    run = ["run", "open-loop", "--set", "duration=0.05"]
    assert cli(run) == 0
    first = (tmp_path / "results" / "open-loop" / "results.npz").read_bytes()
    assert cli(run) == 0
    assert "results/open-loop/ holds earlier results (results.npz, metrics.json); writing to results/open-loop-2/ " \
           "(--out DIR chooses the folder, --overwrite replaces results/open-loop/)" in capsys.readouterr().err
    assert (tmp_path / "results" / "open-loop" / "results.npz").read_bytes() == first
    assert (tmp_path / "results" / "open-loop-2" / "results.npz").is_file()
    assert cli([*run, "--set", "duration=0.1", "--overwrite"]) == 0
    assert len(Result.from_npz(tmp_path / "results" / "open-loop" / "results.npz")) == 101
    assert not (tmp_path / "results" / "open-loop-3").exists()


@pytest.mark.parametrize("text, unit", [("macro step (s)", "s"), ("bias gain (1/s^2); lab: the lab's value, "
                                         "0 (explicit)", "1/s^2"), ("weight (1; Mahony's Kp = kP k1)", "1"),
                                        ("gravity alone (an ablation)", None), ("bias (0.02, -0.01) rad/s", None),
                                        ("profile (flight/profiles.py)", None)])
def test_option_units_come_from_their_help(text, unit):
    from quadcosim.scenarios.metrics import option_unit

    assert option_unit(text) == unit
