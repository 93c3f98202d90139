"""Items 1 to 3: a signal while the record is written, while the figures are drawn, and two
signals in a row: the save finishes, metrics.json says what was kept, the exit code is the
signal's."""

import signal

import numpy as np
import pytest
import quadcosim.orchestrator.result
from conftest import SHORT_TP, assert_whole, metrics_of, send_self
from quadcosim.orchestrator import Result

from quadcosim.main import main as cli


@pytest.mark.parametrize("sent, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_while_the_record_is_written_lets_the_save_finish(tmp_path, monkeypatch, sent, code, capsys):
    write = quadcosim.orchestrator.result._write_array
    calls = []

    def interrupted(archive, name, values):  # two signals in the middle of the archive: both held
        calls.append(name)
        if len(calls) in (2, 3):
            send_self(sent)
        write(archive, name, values)

    monkeypatch.setattr(quadcosim.orchestrator.result, "_write_array", interrupted)
    out = tmp_path / "run"
    assert cli([*SHORT_TP, "--out", str(out)]) == code
    metrics = assert_whole(out)
    assert metrics["status"] == "interrupted" and metrics["interrupted_by"] == sent.name
    assert metrics["stopped_during"] == "saving the record" and metrics["record_complete"] is True
    assert metrics["samples"] == 501 and metrics["files"] == ["diagram.png", "results.npz"]
    assert len(calls) > 3  # every array was written after the signals
    assert f"interrupted by {sent.name} while saving the record" in capsys.readouterr().err


def test_a_signal_while_the_figures_are_drawn_keeps_metrics_and_overwrite_removes_every_figure(
        tmp_path, monkeypatch):
    import matplotlib.figure

    savefig = matplotlib.figure.Figure.savefig

    def interrupted(figure, path, *args, **kwargs):
        if "yaw" in str(path):
            with open(path, "wb") as half:  # a figure half-written under its temporary name
                half.write(b"\x89PNG half")
            send_self()
        return savefig(figure, path, *args, **kwargs)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", interrupted)
    out = tmp_path / "run"
    assert cli([*SHORT_TP, "--out", str(out)]) == 130
    metrics = assert_whole(out)
    assert metrics["stopped_during"] == "reporting (metrics and figures)" and metrics["record_complete"]
    assert metrics["files"] == ["diagram.png", "results.npz", "roll_pitch.png"]
    assert not (out / "yaw.png").exists()
    monkeypatch.undo()
    (out / "stale.png").write_bytes(b"a figure of an older run")  # not listed: removed all the same
    assert cli([*SHORT_TP, "--set", "flight=hover", "--out", str(out), "--overwrite"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["diagram.png", "metrics.json", "results.npz",
                                                     "roll_pitch.png", "yaw.png"]
    assert metrics_of(out)["options"]["flight"] == "hover"


def test_overwrite_removes_every_file_of_the_earlier_run(tmp_path):
    out = tmp_path / "run"
    assert cli([*SHORT_TP, "--out", str(out), "--format", "npz,mat,csv"]) == 0
    (out / ".results.x1.part.npz").write_bytes(b"left by a killed save")
    (out / "notes.txt").write_text("the user's own file")
    assert cli(["run", "open-loop", "--set", "duration=0.2", "--out", str(out), "--overwrite"]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == ["imu.png", "metrics.json", "notes.txt", "open_loop.png", "results.npz"], names


def test_a_second_signal_while_a_partial_record_is_saved_is_held(tmp_path, monkeypatch):
    """Item 3 in one process: the run is interrupted in its loop; a second signal arrives while
    its partial record is written, and a third while metrics.json is."""
    import quadcosim.scenarios.outputs

    save, write_json = Result.save, quadcosim.scenarios.outputs.write_json

    def save_interrupted(self, *args, **kwargs):
        send_self()
        return save(self, *args, **kwargs)

    def metrics_interrupted(path, data):
        send_self(signal.SIGTERM)
        return write_json(path, data)

    from quadcosim.orchestrator.chunks import CHUNK_STEPS, ChunkRunner

    chunk_end, ends = ChunkRunner._chunk_end, []

    def chunk_end_interrupted(runner):  # the first signal between the loop's first chunks
        ends.append(1)
        if len(ends) == 2:
            send_self()
        return chunk_end(runner)

    monkeypatch.setattr(ChunkRunner, "_chunk_end", chunk_end_interrupted)
    monkeypatch.setattr(Result, "save", save_interrupted)
    monkeypatch.setattr(quadcosim.scenarios.outputs, "write_json", metrics_interrupted)
    out = tmp_path / "run"
    assert cli(["run", "tp", "--set", "duration=10", "--out", str(out)]) == 130
    metrics = assert_whole(out)
    assert metrics["status"] == "interrupted" and metrics["stopped_during"] == "running"
    assert metrics["record_complete"] is False and metrics["interrupted_by"] == "SIGINT"
    assert metrics["samples"] == CHUNK_STEPS  # what the loop's first chunk recorded (steps 0 to 4095)
    assert np.isfinite(Result.load(out).data).all()
