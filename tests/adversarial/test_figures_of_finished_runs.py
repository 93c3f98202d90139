"""Items 11, 12, 18, 19 and 25: ``plot``, ``compare``, ``log plot`` and ``log replay --json`` name a
damaged record, a streamed record whose chunks are gone and an output path that cannot take
the file, before they draw; a folder given as ``--out`` takes the figure's default name; the
messages say what they mean (two sizes that differ print differently, one run group in the
usage)."""

import re
import shutil

import pytest
import quadcosim.scenarios.outputs
from conftest import SHORT_TP

from quadcosim.main import main as cli
from quadcosim.main import parser
from tests.flightlog_synthetic import write_log

SIGNAL = "Quadrotor.theta1"


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """A finished run and a streamed one (0.5 s of tp each)."""
    base = tmp_path_factory.mktemp("runs")
    assert cli([*SHORT_TP, "--out", str(base / "run")]) == 0
    assert cli([*SHORT_TP, "--stream", "--out", str(base / "stream")]) == 0
    return base


@pytest.mark.parametrize("damage", ["truncated", "garbage"])
def test_a_damaged_record_is_named_not_a_library_error(runs, tmp_path, capsys, damage):
    run = tmp_path / "run"
    shutil.copytree(runs / "run", run)
    data = (run / "results.npz").read_bytes()
    (run / "results.npz").write_bytes(data[: len(data) // 2] if damage == "truncated" else bytes(1000) + data[1000:])
    for command in (["plot", str(run), SIGNAL], ["compare", str(run), str(runs / "run"), SIGNAL]):
        assert cli(command) == 2
        err = capsys.readouterr().err
        assert f"{run}: the run's record is damaged and cannot be read (" in err and "run the scenario again" in err
    assert not list(run.glob("plot-*"))


def test_a_streamed_record_whose_chunks_are_gone_is_named(runs, tmp_path, capsys):
    run = tmp_path / "stream"
    shutil.copytree(runs / "stream", run)
    for chunk in (run / "results.stream").glob("chunk-*.npy"):
        chunk.unlink()
    assert cli(["plot", str(run), SIGNAL]) == 2
    err = capsys.readouterr().err
    assert "the streamed record is damaged: its meta.json lists 1 chunks (501 samples), 0 are there " \
           "(chunk-000000.npy is missing)" in err
    assert not list(run.glob("plot-*"))  # no figure of empty axes


def test_output_paths_that_cannot_take_the_figure_are_refused_first(runs, tmp_path, capsys):
    missing = tmp_path / "absent" / "figure.png"
    for command in (["plot", str(runs / "run"), SIGNAL, "--out", str(missing)],
                    ["compare", str(runs / "run"), str(runs / "stream"), SIGNAL, "--out", str(missing)],
                    ["plot", str(runs / "run"), SIGNAL, "--out", str(tmp_path / "figure.xyz")]):
        assert cli(command) == 2, command
        assert re.search(r"does not exist; create it|\.xyz is not a figure format", capsys.readouterr().err)
    assert cli(["plot", str(runs / "run"), SIGNAL, "--out", str(tmp_path)]) == 0  # a folder takes the default name
    assert capsys.readouterr().out.strip() == str(tmp_path / f"plot-{SIGNAL}.png")
    assert (tmp_path / f"plot-{SIGNAL}.png").stat().st_size > 10_000


def test_log_plot_and_replay_outputs(tmp_path, capsys):
    log = tmp_path / "flight.log"
    write_log(log, duration=20.0)
    assert cli(["log", "plot", str(log), "--out", str(tmp_path / "x.xyz")]) == 2
    assert "x.xyz: .xyz is not a figure format" in capsys.readouterr().err
    folder = tmp_path / "figures"
    folder.mkdir()
    assert cli(["log", "plot", str(log), "--out", str(folder)]) == 0
    assert capsys.readouterr().out.strip() == str(folder / "flight-overview.png")  # not figures.png
    assert (folder / "flight-overview.png").exists() and not (tmp_path / "figures.png").exists()
    assert cli(["log", "replay", str(log), "--json", str(tmp_path / "absent" / "replay.json")]) == 2
    assert "does not exist; create it or give another path" in capsys.readouterr().err


def test_sizes_that_differ_are_printed_differently(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(quadcosim.scenarios.outputs.RunFiles, "disk_need",
                        lambda self, rows, signals, members: 2_031_200)
    monkeypatch.setattr(quadcosim.scenarios.outputs, "free_bytes", lambda folder: 2_030_500)
    assert cli([*SHORT_TP, "--out", str(tmp_path / "run")]) == 2
    assert "need about 2.031 MB in " in capsys.readouterr().err  # where 2.03 MB are free: not 2.03 twice


def test_compare_usage_names_one_group_of_runs(capsys):
    with pytest.raises(SystemExit):
        parser().parse_args(["compare", "--help"])
    usage = capsys.readouterr().out.split("\n\n")[0]
    assert "RUN RUN [RUN...] SIGNAL" in usage and "[RUN... SIGNAL ...]" not in usage, usage
