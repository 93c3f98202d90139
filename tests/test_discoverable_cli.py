"""A command line a student discovers: block parameters with units, a run's signals, degrees,
vector figures, help on every argument in plain text, one representation of a default, and no
traceback when the reader of the output leaves."""

import argparse
import json
import subprocess
import sys

import matplotlib
import numpy as np
import pytest
from quadcosim.estimators import DEFAULT_GAINS, LAB_GAINS
from quadcosim.flight import GAINS
from quadcosim.scenarios import get
from scipy.io import loadmat

from quadcosim.main import main, parser


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    """A 1 s tp run with the explicit filter (its .mat too), in a folder of its own."""
    out = tmp_path_factory.mktemp("runs") / "explicit"
    assert main(["run", "tp", "--set", "duration=1", "estimator=explicit", "--format", "npz,mat", "--out",
                 str(out)]) == 0
    return out


def test_list_shows_the_controller_gains_and_each_estimator_s_with_units_and_defaults(capsys):
    assert main(["list", "--parameters", "Controller"]) == 0
    listed = capsys.readouterr().out
    lines = {line.split()[0]: line for line in listed.splitlines()[1:]}
    assert list(lines) == list(GAINS)
    assert "= 64 " in lines["kp_yaw"] and "[1/s^2]" in lines["kp_yaw"] and "yaw, proportional" in lines["kp_yaw"]
    assert "[1/s^3]" in lines["ki_xy"]
    assert "--set Controller.NAME=VALUE" in listed
    assert main(["list", "--parameters", "Quaternion_estim"]) == 0
    listed = capsys.readouterr().out
    explicit = listed.split("  explicit:")[1].split("  passive:")[0]
    ki = next(line for line in explicit.splitlines() if line.split()[:1] == ["kI"])
    assert f"tp {LAB_GAINS['explicit']['kI']:g} " in ki and "[1/s^2]" in ki
    assert f"recordings {DEFAULT_GAINS['explicit']['kI']:.12g} " in ki
    assert "beta" in listed and "[rad/s]" in listed
    assert main(["list", "--parameters", "Controler"]) == 2
    assert "Python blocks: Controller, Quaternion_estim" in capsys.readouterr().err


def test_the_default_bias_gain_is_one_word_everywhere(finished_run, tmp_path, capsys):
    """kI's default is the word ``lab`` in the listing, the options and a sweep's table; a run of a
    filter with a bias gain records the value it used (0 for the explicit filter), in metrics.json
    and the .mat alike; a number is still taken, a negative one refused."""
    assert get("tp").options["kI"].default == "lab"
    assert main(["list"]) == 0
    assert any(line.split()[:3] == ["kI", "=", "lab"] for line in capsys.readouterr().out.splitlines())
    metrics = json.loads((finished_run / "metrics.json").read_text())
    mat = loadmat(finished_run / "results.mat")
    assert metrics["options"]["kI"] == LAB_GAINS["explicit"]["kI"] == mat["options"]["kI"][0, 0][0, 0]
    linear = tmp_path / "linear"
    assert main(["run", "tp", "--set", "duration=0.2", "--format", "npz,mat", "--out", str(linear)]) == 0
    metrics = json.loads((linear / "metrics.json").read_text())
    assert metrics["options"]["kI"] == "lab" == loadmat(linear / "results.mat")["options"]["kI"][0, 0][0]
    from quadcosim.studies.sweep import table

    table.write([table.row({"member": 0, "options": get("tp").parse(None)})], tmp_path)
    csv = (tmp_path / "sweep.csv").read_text().splitlines()
    assert csv[1].split(",")[csv[0].split(",").index("kI")] == "lab"
    assert get("tp").parse(["kI=0.3"])["kI"] == 0.3
    with pytest.raises(ValueError, match=r"kI=-1.0 must be at least 0"):
        get("tp").parse(["kI=-1"])
    with pytest.raises(ValueError, match=r"not a valid float \(or lab\)"):
        get("tp").parse(["kI=default"])


def test_plot_without_a_signal_lists_the_run_s_signals_with_units(finished_run, capsys):
    assert main(["plot", str(finished_run)]) == 0
    listed = capsys.readouterr().out.splitlines()
    assert "signals" in listed[0] and "samples over 1 s" in listed[0]
    assert "  IMU.gyro [x, y, z] (rad/s)" in listed
    assert "  Quaternion_estim.theta_est [1, 2, 3] (rad)" in listed
    assert "  MotorMagnetics.u_batt (V)" in listed


def test_deg_draws_angles_in_degrees_and_format_writes_vector_figures(finished_run, tmp_path, capsys):
    from quadcosim.orchestrator import Result
    from quadcosim.scenarios.run_plots import plot

    result = Result.load(finished_run)
    path = plot(finished_run, ["Quadrotor.theta2", "MotorMagnetics.u_batt"], out=tmp_path / "deg.svg", deg=True)
    matplotlib.use("Agg")
    # the figure's numbers: read back from the SVG's axis labels would be fragile; redraw instead
    import matplotlib.pyplot as plt
    from quadcosim.scenarios.run_plots import _draw

    fig, (angle, volts) = plt.subplots(2)
    _draw(angle, result, "Quadrotor.theta2", deg=True)
    _draw(volts, result, "MotorMagnetics.u_batt", deg=True)
    assert np.allclose(angle.lines[0].get_ydata().max(), np.degrees(result["Quadrotor.theta2"]).max(), rtol=1e-9)
    assert angle.get_ylabel() == "deg" and volts.get_ylabel() == "V"  # a voltage stays a voltage
    assert volts.lines[0].get_ydata().max() == pytest.approx(result["MotorMagnetics.u_batt"].max())
    plt.close(fig)
    assert path.read_text().lstrip().startswith("<?xml") and "<svg" in path.read_text()[:2000]
    assert main(["plot", str(finished_run), "IMU.gyro", "--deg", "--format", "pdf"]) == 0
    written = finished_run / "plot-IMU.gyro.pdf"
    assert capsys.readouterr().out.strip().endswith("plot-IMU.gyro.pdf") and written.read_bytes()[:5] == b"%PDF-"
    assert main(["compare", str(finished_run), str(finished_run), "Quaternion_estim.theta_est", "--deg",
                 "--out", str(tmp_path / "c"), "--format", "pdf"]) == 0
    assert (tmp_path / "c.pdf").read_bytes()[:5] == b"%PDF-"
    assert main(["plot", str(finished_run), "IMU.gyro", "--out", str(tmp_path / "x.png"), "--format", "pdf"]) == 2
    assert "disagree" in capsys.readouterr().err


def test_a_run_writes_its_report_figures_as_pdf(tmp_path):
    out = tmp_path / "ol"
    assert main(["run", "open-loop", "--set", "duration=0.3", "--figures", "pdf", "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["figures"] == ["open_loop.pdf", "imu.pdf"]
    assert all((out / name).read_bytes()[:5] == b"%PDF-" for name in metrics["figures"])
    assert not list(out.glob("open_loop.png"))


def _arguments(p: argparse.ArgumentParser, path=()):
    for action in p._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _arguments(sub, path + (name,))
        elif not isinstance(action, argparse._HelpAction):
            yield path, action


def test_every_argument_has_help():
    missing = [" ".join(path + (a.dest,)) for path, a in _arguments(parser())
               if not a.help and a.dest != "rest"]  # findings' arguments: its own parser, below
    assert missing == []
    from findings.__main__ import parser as findings

    assert [a.dest for _, a in _arguments(findings()) if not a.help] == []


def test_help_is_plain_text(capsys):
    from findings.__main__ import main as findings

    with pytest.raises(SystemExit):
        findings(["--help"])
    text = capsys.readouterr().out
    assert "python -m findings" in text and "findings.GROUPS" in text
    assert "``" not in text and ":data:" not in text and ":mod:" not in text
    with pytest.raises(SystemExit):
        main(["--help"])
    assert "``" not in capsys.readouterr().out


def test_a_reader_that_leaves_early_gets_no_traceback():
    """``quadcosim list --parameters IMU | head -1``: the first line, and no BrokenPipeError."""
    command = f"'{sys.executable}' -m quadcosim.main list --parameters IMU | head -1"
    done = subprocess.run(["bash", "-o", "pipefail", "-c", command], capture_output=True, text=True, timeout=120)
    assert done.stdout.startswith("IMU parameters") and done.stdout.count("\n") == 1
    assert "Traceback" not in done.stderr and "BrokenPipe" not in done.stderr, done.stderr
    assert done.returncode == 128 + 13  # SIGPIPE's code, as a program the pipe's signal ends


def test_labels_fit_their_axes(finished_run, tmp_path):
    """compare's y labels are the unit alone (the name is the axes' title): the label, drawn,
    is shorter than its axes (it overlapped its neighbours when it carried the long name)."""
    import matplotlib.pyplot as plt
    from quadcosim.orchestrator import Result
    from quadcosim.scenarios.run_plots import AXES_SIZE, _draw

    result = Result.load(finished_run)
    fig, axes = plt.subplots(3, 1, figsize=(AXES_SIZE[0], 3 * AXES_SIZE[1]), layout="constrained")
    for ax, component in zip(axes, result.columns("Quaternion_estim.theta_est"), strict=True):
        _draw(ax, result, component, deg=False, label_prefix="explicit: ")
    fig.canvas.draw()
    for ax in axes:
        label, box = ax.yaxis.label.get_window_extent(), ax.get_window_extent()
        assert label.height < box.height, (ax.get_ylabel(), label.height, box.height)
        assert ax.get_title(loc="left").startswith("Quaternion_estim.theta_est")
    plt.close(fig)


class _Terminal:
    """A stream that says it is a terminal (tqdm then draws its bar in place), keeping all."""

    def __init__(self):
        self.text = ""

    def write(self, text):
        self.text += text
        return len(text)

    def flush(self):
        pass

    def isatty(self):
        return True


def test_a_status_line_during_a_progress_bar_is_written_on_a_line_of_its_own(monkeypatch):
    from quadcosim.infra import progress

    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    with progress.reporting(True):
        bar = progress.Progress(200.0, "run tp")
        bar.update(80.0)
        progress.status("Quaternion_estim: a line in the middle of the run")
        progress.say("quadcosim: warning: another one")
        bar.update(120.0)
        bar.close()
    lines = [part for chunk in terminal.text.split("\n") for part in chunk.split("\r")]
    said = [part for part in lines if "a line in the middle" in part or "another one" in part]
    assert len(said) == 2 and all("%|" not in part for part in said), said  # not inside the bar's line
    assert said[0].lstrip().startswith("[") and said[1].startswith("quadcosim: warning")
    assert "100%|" in terminal.text.rsplit("another one", 1)[1]  # the bar drawn again below, to the end


def test_the_run_names_the_figures_it_wrote_and_counts_as_metrics_json_counts(tmp_path, capsys):
    """--record with --decimation: the report needs signals not recorded and is skipped; the last
    line names diagram.png alone, not "figures". The status lines count the blocks as the
    diagram does and the signals as metrics.json does."""
    out = tmp_path / "tp"
    assert main(["run", "tp", "--set", "duration=0.5", "--record", "Quadrotor.theta", "--decimation", "10",
                 "--out", str(out)]) == 0
    captured = capsys.readouterr()
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["report"].startswith("report skipped")
    last = captured.out.strip().splitlines()[-1]
    assert last == f"results (npz), metrics.json and diagram.png in {out}/ (no report figures: see report above)"
    assert "and figures in" not in captured.out
    assert "(6 blocks and 4 constants tying off inputs)" in captured.err  # the diagram's heading counts alike
    assert "loading its compiled step (numba" not in captured.err  # a compile is announced when it happens
    full = tmp_path / "full"
    assert main(["run", "tp", "--set", "duration=0.2", "--out", str(full)]) == 0
    captured = capsys.readouterr()
    metrics = json.loads((full / "metrics.json").read_text())
    recorded, left_out = metrics["signals_recorded"], len(metrics["signals_not_saved"])
    assert f"({recorded - left_out} of the {recorded} signals recorded;" in captured.err
    assert "and diagram.png, roll_pitch.png, yaw.png in" in captured.out.strip().splitlines()[-1]


def test_tracking_draws_setpoint_and_response_on_one_axes_in_degrees(finished_run, tmp_path, capsys, monkeypatch):
    """``plot RUN Setpoint.theta_d Quadrotor.theta --tracking --deg``: roll, pitch and yaw each on
    one axes, the setpoint (dashed) and the response, in degrees, the unit on the y axis."""
    from quadcosim.orchestrator import Result
    from quadcosim.scenarios import run_plots

    drawn = {}
    real_save = run_plots.save_figure

    def keep(fig, path, **kw):
        drawn["axes"] = [(ax.get_ylabel(), [(line.get_label(), line.get_linestyle(), line.get_ydata())
                                              for line in ax.lines]) for ax in fig.axes if ax.lines]
        return real_save(fig, path, **kw)

    monkeypatch.setattr(run_plots, "save_figure", keep)
    assert main(["plot", str(finished_run), "Setpoint.theta_d", "Quadrotor.theta", "--tracking", "--deg",
                 "--out", str(tmp_path / "tracking.png")]) == 0
    assert (tmp_path / "tracking.png").read_bytes()[:4] == b"\x89PNG"
    result = Result.load(finished_run)
    assert len(drawn["axes"]) == 3
    for k, (unit, lines) in enumerate(drawn["axes"], start=1):
        assert unit == "deg"
        assert [(label, style) for label, style, _ in lines] == [(f"Setpoint.theta_d{k}", "--"),
                                                                 (f"Quadrotor.theta{k}", "-")]
        for (_, _, y), name in zip(lines, (f"Setpoint.theta_d{k}", f"Quadrotor.theta{k}"), strict=True):
            assert np.max(np.abs(y)) == pytest.approx(np.degrees(np.max(np.abs(result[name]))), rel=1e-9)
    capsys.readouterr()
    assert main(["plot", str(finished_run), "Setpoint.theta_d", "IMU.acc", "--tracking"]) == 2
    assert "units differ (Setpoint.theta_d (rad), IMU.acc (m/s2))" in capsys.readouterr().err
    assert main(["plot", str(finished_run), "Setpoint.theta_d", "Quadrotor.theta2", "--tracking"]) == 2
    assert "differ in size" in capsys.readouterr().err
    assert main(["plot", str(finished_run), "Quadrotor.theta", "--tracking"]) == 2
    assert "at least two" in capsys.readouterr().err


def test_compare_writes_under_results_never_replacing_and_names_the_runs_alone(finished_run, tmp_path, capsys,
                                                                               monkeypatch):
    """``compare`` without ``--out``: ``results/compare-SIGNAL.png``, then the next free name
    (said), ``--overwrite`` replaces; each legend entry names a run, not the component again
    (the component is the axes' title)."""
    import quadcosim.scenarios.run_plots as run_plots

    legends = []

    def keep_legends(fig, path, **options):
        legends.append([[t.get_text() for t in ax.get_legend().get_texts()] for ax in fig.axes])
        return save_figure(fig, path, **options)

    save_figure = run_plots.save_figure
    monkeypatch.setattr(run_plots, "save_figure", keep_legends)
    monkeypatch.chdir(tmp_path)
    other = tmp_path / "other" / finished_run.name  # a second run of the same folder name
    other.parent.mkdir()
    other.symlink_to(finished_run)
    signal = "Quaternion_estim.theta_est"
    assert main(["compare", str(finished_run), str(other), signal]) == 0
    first = tmp_path / "results" / f"compare-{signal}.png"
    assert capsys.readouterr().out.strip() == str(first.relative_to(tmp_path)) and first.stat().st_size > 10_000
    assert legends[0] == [[str(finished_run), str(other)]] * 3
    assert main(["compare", str(finished_run), str(other), signal]) == 0
    told = capsys.readouterr()
    assert told.out.strip().endswith(f"compare-{signal}-2.png") and "--overwrite" in told.err
    stamp = first.stat().st_mtime_ns
    assert main(["compare", "--overwrite", str(finished_run), str(finished_run.parent / "x"), signal]) == 2
    assert main(["compare", "--overwrite", str(finished_run), str(other), signal]) == 0
    assert capsys.readouterr().out.strip() == str(first.relative_to(tmp_path)) and first.stat().st_mtime_ns > stamp
    assert {p.name for p in first.parent.iterdir()} == {first.name, f"compare-{signal}-2.png"}


def test_plot_and_log_plot_defaults_never_replace_an_earlier_figure(finished_run, tmp_path, capsys, monkeypatch):
    """``plot RUN SIGNAL`` and ``log plot FILE`` without ``--out``: a second figure of the same
    name takes the next free ``-2`` name (said); ``--overwrite`` replaces the first."""
    monkeypatch.chdir(tmp_path)
    first = finished_run / "plot-Quadrotor.theta2.png"
    first.unlink(missing_ok=True)
    for name in ("plot-Quadrotor.theta2-2.png", "plot-Quadrotor.theta2-3.png"):
        (finished_run / name).unlink(missing_ok=True)
    assert main(["plot", str(finished_run), "Quadrotor.theta2"]) == 0
    assert capsys.readouterr().out.strip() == str(first)
    assert main(["plot", str(finished_run), "Quadrotor.theta2", "--deg"]) == 0
    told = capsys.readouterr()
    assert told.out.strip() == str(finished_run / "plot-Quadrotor.theta2-2.png") and "--overwrite" in told.err
    assert main(["plot", str(finished_run), "Quadrotor.theta2", "--overwrite"]) == 0
    assert capsys.readouterr().out.strip() == str(first)
    assert main(["log", "example", "logs"]) == 0
    overview = tmp_path / "results" / "logs" / "example-a-overview.png"
    assert main(["log", "plot", "logs/example-a.log"]) == 0
    assert main(["log", "plot", "logs/example-a.log"]) == 0
    assert overview.is_file() and overview.with_name("example-a-overview-2.png").is_file()
    stamp = overview.stat().st_mtime_ns
    assert main(["log", "plot", "logs/example-a.log", "--overwrite"]) == 0
    assert overview.stat().st_mtime_ns > stamp and not overview.with_name("example-a-overview-3.png").exists()
