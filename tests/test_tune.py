"""quadcosim tune on a real Dask cluster: a diverged evaluation is a penalty and never the best,
tune.json holds the history, --resume runs nothing already run, bad arguments are refused."""

import json

import pytest
from quadcosim.studies import tune

from quadcosim.main import main as cli


@pytest.mark.slow
def test_a_tune_never_takes_a_diverged_point_and_resumes_without_running_again(tmp_path, capsys):
    out = tmp_path / "kp"
    # pitch tracking over the attitude gain kp: at 3032 1/s^2 (the scan's third point) the quadrotor crashes by t = 4 s
    arguments = ["tune", "tp", "--minimize", "tracking_rms_deg[1]", "--over", "Controller.kp=100:6000:log",
                 "--set", "duration=4", "--budget", "5", "--workers", "2", "--out", str(out), "--quiet"]
    assert cli(arguments) == 0
    data = json.loads((out / "tune.json").read_text())
    history = data["history"]
    assert len(history) == data["evaluations"] == 5
    crashed = [e for e in history if e["status"] == "diverged"]
    assert crashed and all(e["value"] is None for e in crashed)
    kept = [e for e in history if e["value"] is not None]
    assert data["value"] == min(e["value"] for e in kept) and data["best"] == min(kept, key=lambda e: e["value"])[
        "options"]
    assert max(e["options"]["Controller.kp"] for e in crashed) > data["best"]["Controller.kp"]
    assert (out / "convergence.png").stat().st_size > 10_000
    capsys.readouterr()
    # --resume replays the optimiser through the recorded evaluations: nothing runs again
    assert cli([*arguments, "--resume"]) == 0
    again = json.loads((out / "tune.json").read_text())
    assert again["members_run_now"] == 0 and again["best"] == data["best"] and again["history"] == history
    assert cli([*arguments[:-3], "--set", "duration=3", "--out", str(out), "--resume", "--quiet"]) == 2
    assert "holds a tune with other set, base" in capsys.readouterr().err


@pytest.mark.parametrize("arguments, message", [
    (["--over", "k=1:0.1"], "give finite bounds LOW < HIGH"),
    (["--over", "k=-1:1:log"], "a log scale needs LOW > 0"),
    (["--over", "kk=0.1:1"], "kk"),
    (["--over", "k=0.1:1", "--budget", "1"], "--budget 1: give at least 2"),
    (["--over", "k=0.1:1", "--set", "k=0.2"], "both tuned (--over) and fixed (--set)"),
    (["--over", "k=0.1:1", "--minimize", "rms error"], "give a metric column"),
])
def test_bad_tune_arguments_are_refused_before_any_run(arguments, message, capsys, tmp_path):
    base = ["tune", "tp", "--minimize", "rms_error_deg[0]", "--out", str(tmp_path / "t"), "--quiet"]
    if "--minimize" in arguments:
        base = base[:2] + base[4:]
    assert cli([*base, *arguments]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "t").exists()


def test_the_prediction_applies_to_the_linear_filters_gain_against_noise():
    predicted = tune.prediction(tune.plan("tp", "rms_error_deg[0]", ["k=0.005:20:log"], ["noise=on"]))
    assert 0.1 < predicted["k"] < 5.0 and predicted["rms_error_deg"] > 0
    assert tune.prediction(tune.plan("tp", "rms_error_deg[0]", ["k=0.005:20:log"])) is None  # no noise
    assert tune.prediction(tune.plan("tp", "rms_error_deg[2]", ["k=0.005:20:log"], ["noise=on"])) is None


def test_loop_margins_of_a_tune_of_the_attitude_gains():
    import math

    plan = tune.plan("tp", "step_iae_total_deg_times_s", ["Controller.kp=30:600:log", "Controller.kd=5:60:log"],
                     ["flight=step"])
    margins = tune.loop_margins(plan, {"Controller.kp": 144.0, "Controller.kd": 19.2})
    w = margins["roll_pitch_crossover_rad_s"]
    # L(jw) = (kp + j kd w) / (-w^2): unit gain at the crossover, phase margin atan(kd w / kp)
    assert math.hypot(144.0, 19.2 * w) / w**2 == pytest.approx(1.0, rel=1e-6)
    assert margins["roll_pitch_phase_margin_deg"] == pytest.approx(math.degrees(math.atan2(19.2 * w, 144.0)), abs=1e-6)
    # yaw at its defaults 64 and 12.8: the same damping 0.8, the same margin
    assert margins["yaw_phase_margin_deg"] == pytest.approx(margins["roll_pitch_phase_margin_deg"], abs=1e-6)
    assert tune.loop_margins(tune.plan("tp", "rms_error_deg[0]", ["k=0.1:1"]), {"k": 0.5}) is None
