"""Recorded files and the replay command: a tp run written to a file and replayed gives tp's error."""

import json

import numpy as np
import pytest
from quadcosim.estimators import DEFAULT_GAINS, recording, score
from quadcosim.orchestrator.result import Result
from quadcosim.scenarios import replay

from quadcosim import scenarios


@pytest.mark.parametrize("kind, options", [("explicit", {"kI": 0.05, "corrections": "on"}),
                                           ("passive", {"ry": "triad"}), ("vqf", {})])
def test_replay_of_a_tp_recording_reproduces_its_error(tmp_path, kind, options):
    run, metrics = scenarios.run("tp", {"estimator": kind, "flight": "nonstationary", "feedback": "estimate",
                                        "noise": True, "bias": True, "duration": 3.0, **options}, tmp_path / "run")
    path = replay.from_tp(tmp_path / "run", tmp_path / "recording.npz")
    result = replay.replay(recording.load(path))
    reported = score(run["Quaternion_estim.q_est"], run["Quadrotor.q"], run.time >= metrics["settle_s"])
    print(kind, "tp", reported["total_rmse_deg"], "replay", result["errors"]["total_rmse_deg"])
    for key in ("total_rmse_deg", "inclination_rmse_deg", "heading_rmse_deg"):
        assert abs(result["errors"][key] - reported[key]) < 1e-9


@pytest.mark.parametrize("suffix", [".npz", ".mat", ".csv"])
def test_recordings_round_trip_in_every_format(tmp_path, suffix):
    rng = np.random.default_rng(1)
    data = {"gyro": rng.standard_normal((50, 3)), "acc": rng.standard_normal((50, 3)) + [0, 0, -9.81],
            "mag": rng.standard_normal((50, 3)), "quat": rng.standard_normal((50, 4))}
    scored = np.arange(50) > 10
    path = recording.save(tmp_path / f"r{suffix}", rate=200.0, scored=scored, meta={"frame": "enu"}, **data)
    back = recording.load(path)
    for key, value in data.items():
        assert np.array_equal(back[key], value)
    assert back["rate"] == pytest.approx(200.0, rel=1e-12)
    assert np.array_equal(back["scored"], scored)
    if suffix != ".csv":
        assert back["meta"] == {"frame": "enu"}


def test_a_recording_without_rate_or_sensor_is_refused_by_name(tmp_path):
    np.savez(tmp_path / "a.npz", gyro=np.zeros((5, 3)), acc=np.zeros((5, 3)), mag=np.zeros((5, 3)))
    with pytest.raises(ValueError, match="gives no sampling rate"):
        recording.load(tmp_path / "a.npz")
    np.savez(tmp_path / "b.npz", gyro=np.zeros((5, 3)), mag=np.zeros((5, 3)), rate=100.0)
    with pytest.raises(ValueError, match="has no acc array"):
        recording.load(tmp_path / "b.npz")
    np.savez(tmp_path / "c.npz", gyro=np.ones((5, 3)), acc=np.ones((5, 3)), rate=100.0)
    assert not recording.load(tmp_path / "c.npz")["mag"].any()  # a 6-axis recording: zeros, the filters warn


def test_replay_command_line(tmp_path, capsys):
    scenarios.run("tp", {"estimator": "madgwick", "duration": 1.0}, tmp_path / "run")
    assert replay.main(["--from-tp", str(tmp_path / "run"), "--write", str(tmp_path / "r.csv")]) == 0
    assert replay.main([str(tmp_path / "r.csv"), "--estimator", "explicit", "--set", "kP=0.5",
                        "--json", str(tmp_path / "out.json")]) == 0
    result = json.loads((tmp_path / "out.json").read_text())
    assert result["estimator"] == "explicit" and result["gains"] == {"kP": 0.5}
    assert result["gains_in_force"]["kP"] == 0.5 and result["gains_in_force"]["kI"] == DEFAULT_GAINS["explicit"]["kI"]
    # the results folder of the run itself, with no flag: its own estimator again, its own error
    assert replay.main([str(tmp_path / "run"), "--json", str(tmp_path / "same.json")]) == 0
    same = json.loads((tmp_path / "same.json").read_text())
    run = Result.from_npz(tmp_path / "run" / "results.npz")
    settle = json.loads((tmp_path / "run" / "metrics.json").read_text())["settle_s"]
    reported = score(run["Quaternion_estim.q_est"], run["Quadrotor.q"], run.time >= min(settle, 0.5))
    assert same["estimator"] == "madgwick" and same["gains_in_force"] == {"beta": 0.041}
    capsys.readouterr()
    assert replay.main([str(tmp_path / "run")]) == 0  # without --json: a few lines, the same numbers
    shown = capsys.readouterr().out.splitlines()
    errors = same["errors"]
    assert shown[:3] == [f"madgwick on {tmp_path / 'run'} (frame ned)", "  gains in force: beta=0.041",
                         f"  quaternion error RMS (deg): total {errors['total_rmse_deg']:.2f}, inclination "
                         f"{errors['inclination_rmse_deg']:.2f}, heading {errors['heading_rmse_deg']:.2f}"]
    # the same arithmetic but for the kernels' rounding: under 1e-9 deg with this CPU's OpenBLAS kernels,
    # 6.9e-9 with OPENBLAS_CORETYPE=Prescott NUMBA_CPU_NAME=generic
    assert abs(same["errors"]["total_rmse_deg"] - reported["total_rmse_deg"]) < 2e-8
    # every estimator option by name, ry included
    assert replay.main([str(tmp_path / "run" / "results.npz"), "--estimator", "passive", "--ry", "triad", "--set",
                        "k2=0.1", "--corrections", "heading_only", "--discretisation", "euler", "--b0", "0,0,0.01",
                        "--json", str(tmp_path / "passive.json")]) == 0
    passive = json.loads((tmp_path / "passive.json").read_text())
    assert passive["ry"] == "triad" and passive["discretisation"] == "euler" and passive["b0"] == [0, 0, 0.01]
    assert passive["gains_in_force"]["k2"] == 0.1 and passive["gains_in_force"]["heading_only"] == 1.0
    assert passive["gains_in_force"]["acc_tolerance"] == 0.0  # the corrections not named are off
    assert result["errors"]["total_rmse_deg"] < 2.5  # 1.94 deg measured: a 1 s run, the start of convergence
    assert replay.main([str(tmp_path / "missing.npz")]) == 2
    assert "no recording at" in capsys.readouterr().err


def test_replay_figure_draws_the_errors_it_reports(tmp_path, capsys, monkeypatch):
    """``quadcosim replay --figure``: inclination and heading errors sample by sample, whose RMS over the scored
    samples is the reported one; a recording without a reference, or a figure suffix matplotlib
    does not write, is refused naming the fix."""
    from quadcosim.infra import files
    from quadcosim.main import main as quadcosim

    drawn = []

    def keep(fig, path, **options):
        drawn.append([(ax.lines[0].get_ydata(), ax.get_title(loc="left")) for ax in fig.axes])
        return saved(fig, path, **options)

    saved = files.save_figure
    monkeypatch.setattr(files, "save_figure", keep)
    run, metrics = scenarios.run("tp", {"estimator": "explicit", "flight": "nonstationary", "noise": True,
                                        "duration": 3.0}, tmp_path / "run")
    drawn.clear()  # the run's own report figures
    assert quadcosim(["replay", str(tmp_path / "run"), "--figure", str(tmp_path / "errors.png"), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert (tmp_path / "errors.png").stat().st_size > 10_000 and "q" not in result
    scored = run.time >= min(metrics["settle_s"], 1.5)
    assert len(drawn) == 1
    for (values, title), name in zip(drawn[0], ("inclination", "heading"), strict=True):
        rms = float(np.sqrt(np.mean(np.asarray(values)[scored] ** 2)))
        assert rms == pytest.approx(result["errors"][f"{name}_rmse_deg"], rel=1e-9, abs=1e-12)
        assert title.startswith(f"{name} error of explicit: RMS")
    assert replay.main([str(tmp_path / "run"), "--figure", str(tmp_path / "errors.xyz")]) == 2
    assert "errors.xyz" in capsys.readouterr().err
    np.savez(tmp_path / "plain.npz", gyro=np.zeros((50, 3)), acc=np.tile([0.0, 0.0, -9.81], (50, 1)),
             mag=np.tile([0.2, 0.0, 0.4], (50, 1)), rate=100.0)
    assert replay.main([str(tmp_path / "plain.npz"), "--figure", str(tmp_path / "none.png")]) == 2
    assert "has none" in capsys.readouterr().err and not (tmp_path / "none.png").exists()
    with pytest.raises(SystemExit):
        quadcosim(["replay"])
    assert "quadcosim replay: error: give a RECORDING" in capsys.readouterr().err
