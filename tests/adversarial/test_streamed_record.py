"""``--stream``: the record goes to disk in chunks as the run goes; read back it equals, bit for
bit, the record kept in memory, with either master; a run cut short keeps its whole chunks."""

import numpy as np
import pytest
import quadcosim.orchestrator.stream
from conftest import assert_whole
from quadcosim.orchestrator import Result
from quadcosim.orchestrator.stream import StreamWriter
from quadcosim.scenarios import get

from quadcosim.main import main as cli


@pytest.mark.parametrize("master", ["chunk", "step"])
def test_a_streamed_record_equals_the_record_in_memory_bit_for_bit(tmp_path, monkeypatch, master):
    monkeypatch.setattr(quadcosim.orchestrator.stream, "WINDOW_BYTES", 8 * 126 * 700)  # 700 rows: several chunks
    monkeypatch.setenv("QUADCOSIM_MASTER", master)
    scenario = get("tp")
    options = ["duration=2", "noise=on", "bias=on", "estimator=explicit"]
    kept = scenario.system(scenario.parse(options)).run(2.0, decimation=3)
    streamed = scenario.system(scenario.parse(options)).run(2.0, decimation=3, stream=StreamWriter(tmp_path / "s"))
    assert len(list((tmp_path / "s").glob("chunk-*.npy"))) == 1 + len(kept) // 700
    assert streamed.names == kept.names and len(streamed) == len(kept) == 667
    assert np.array_equal(streamed.time, kept.time)
    assert np.array_equal(streamed.data, kept.data)
    assert np.array_equal(streamed["IMU.acc"], kept["IMU.acc"])
    assert streamed.units == kept.units


def test_stream_on_the_command_line_writes_the_folder_and_result_load_reads_either(tmp_path):
    assert cli(["run", "tp", "--set", "duration=1", "--stream", "--out", str(tmp_path / "s")]) == 0
    assert cli(["run", "tp", "--set", "duration=1", "--out", str(tmp_path / "m")]) == 0
    metrics = assert_whole(tmp_path / "s")
    assert "results.stream" in metrics["files"] and not (tmp_path / "s" / "results.npz").exists()
    streamed, kept = Result.load(tmp_path / "s"), Result.load(tmp_path / "m" / "results.npz")
    assert np.array_equal(streamed["Quadrotor.q"], kept["Quadrotor.q"])
    assert metrics["rms_error_deg"] == assert_whole(tmp_path / "m")["rms_error_deg"]
    chunks = sum(f.stat().st_size for f in (tmp_path / "s" / "results.stream").iterdir())
    assert metrics["results_stream_mb"] == chunks / 1e6 and "results_npz_mb" not in metrics
    assert cli(["run", "tp", "--stream", "--format", "npz,mat", "--out", str(tmp_path / "x")]) == 2


def test_a_streamed_run_cut_short_keeps_its_whole_chunks(tmp_path, monkeypatch):
    monkeypatch.setattr(quadcosim.orchestrator.stream, "WINDOW_BYTES", 8 * 126 * 1000)
    writer = StreamWriter(tmp_path / "s")
    chunks = []
    write = writer.write

    def killed_after_two(time, rows):  # the process dies while its third chunk is written
        if len(chunks) == 2:
            raise SystemExit("killed")
        chunks.append(len(rows))
        write(time, rows)

    writer.write = killed_after_two
    scenario = get("tp")
    with pytest.raises(SystemExit):
        scenario.system(scenario.parse(["duration=4"])).run(4.0, stream=writer)
    kept = Result.load(tmp_path / "s")
    assert len(kept) == 2000 and kept.time[-1] == pytest.approx(1.999)
    assert np.isfinite(kept.data).all()


def test_the_report_of_a_streamed_record_taken_chunk_by_chunk_equals_the_whole_records(tmp_path, monkeypatch):
    """tp's statistics and envelopes read a streamed record one chunk at a time: the same
    bias convergence time and figure samples, the same errors to rounding."""
    from quadcosim.orchestrator.result import envelope

    from quadcosim import scenarios

    monkeypatch.setattr(quadcosim.orchestrator.stream, "WINDOW_BYTES", 8 * 126 * 1500)  # 1500 rows a chunk
    settings = {"duration": 6, "estimator": "passive", "bias": True, "flight": "hover", "kP": 10, "kI": 10}
    streamed, by_chunk = scenarios.run("tp", settings, tmp_path / "s", stream=True)
    kept, whole = scenarios.run("tp", settings, tmp_path / "m")
    assert len(streamed.chunk_files) == 5
    assert by_chunk["bias_convergence_s"] == whole["bias_convergence_s"] and 2 < whole["bias_convergence_s"] < 4
    assert by_chunk["bias_error_final"] == whole["bias_error_final"]
    assert by_chunk["steady_window_s"] == whole["steady_window_s"]
    for key in ("rms_error_deg", "max_error_deg", "tracking_rms_deg", "steady_error_deg"):
        assert by_chunk[key] == pytest.approx(whole[key], rel=1e-12, abs=1e-15), key
    for name in ("Quadrotor.theta1", "Quaternion_estim.b_est_x"):
        drawn = streamed.envelope(lambda w, name=name: w[name], points=700)
        expected = envelope(kept.time, kept[name], points=700)
        assert np.array_equal(drawn[0], expected[0]) and np.array_equal(drawn[1], expected[1])
    assert by_chunk["figures"] == whole["figures"] == ["roll_pitch.png", "yaw.png", "bias.png"]
    from quadcosim.scenarios.figures import angle_curve
    from quadcosim.scenarios.tp import _angle_curve

    drawn = _angle_curve(streamed, "Quadrotor.theta3")
    expected = angle_curve(kept.time, np.degrees(kept["Quadrotor.theta3"]))
    assert np.array_equal(drawn[0], expected[0], equal_nan=True)
    assert np.allclose(drawn[1], expected[1], rtol=0, atol=1e-12, equal_nan=True)
