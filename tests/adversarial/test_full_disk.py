"""Items 4 and 5: a disk that fills while a figure or the record is written leaves nothing
truncated under a final name, names the folder and the bytes needed, and keeps metrics.json."""

import errno

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402
import quadcosim.orchestrator.result  # noqa: E402
import quadcosim.scenarios.outputs  # noqa: E402
from conftest import SHORT_TP, metrics_of  # noqa: E402
from quadcosim.orchestrator import Result  # noqa: E402
from quadcosim.orchestrator.diagram import draw  # noqa: E402
from quadcosim.scenarios import get  # noqa: E402
from quadcosim.scenarios.plant import save_figure  # noqa: E402

from quadcosim.infra.files import DiskFull  # noqa: E402
from quadcosim.main import main as cli  # noqa: E402


def _filling(written: int):
    """A ``savefig`` that writes ``written`` bytes of its file, then finds the disk full."""
    def savefig(figure, path, *args, **kwargs):
        with open(path, "wb") as handle:
            handle.write(b"\x89PNG" + bytes(written))
        raise OSError(errno.ENOSPC, "No space left on device")
    return savefig


def test_figures_are_never_left_truncated_when_the_disk_fills(tmp_path, monkeypatch):
    import matplotlib.figure

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", _filling(5000))
    scenario = get("tp")
    system = scenario.system(scenario.parse(["duration=0.1"]))
    open_before = plt.get_fignums()  # another test's figures are not this one's to judge
    with pytest.raises(DiskFull, match=r"no space left in .* to write diagram.png: it needs more than the 0.005 MB"):
        draw(system, tmp_path / "diagram.png", "tp")
    figure = plt.figure()
    with pytest.raises(DiskFull, match="to write yaw.png"):
        save_figure(figure, tmp_path, "yaw.png")
    assert list(tmp_path.iterdir()) == []  # neither the figures nor their temporaries
    assert plt.get_fignums() == open_before  # and both figures were closed


def test_a_full_disk_while_the_record_is_written_names_the_folder_and_keeps_metrics(tmp_path, monkeypatch, capsys):
    write = quadcosim.orchestrator.result._write_array

    def filling(archive, name, values):
        if name == "IMU.acc":  # some arrays written, then the disk is full
            raise OSError(errno.ENOSPC, "No space left on device")
        write(archive, name, values)

    monkeypatch.setattr(quadcosim.orchestrator.result, "_write_array", filling)
    out = tmp_path / "run"
    assert cli([*SHORT_TP, "--out", str(out), "--format", "npz,csv"]) == 1
    err = capsys.readouterr().err
    assert f"no space left in {out}/ to write results.npz: it needs about 0.35" in err
    names = sorted(p.name for p in out.iterdir())
    assert names == ["diagram.png", "metrics.json", "results.csv"], names  # no npz, no temporary
    metrics = metrics_of(out)
    assert metrics["status"] == "failed" and metrics["stopped_during"] == "saving the record"
    assert metrics["files"] == ["diagram.png", "results.csv"]
    assert "no space left" in metrics["files_not_written"]["results.npz"]


def test_a_record_too_large_for_the_disk_is_refused_before_the_run(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(quadcosim.scenarios.outputs, "free_bytes", lambda folder: 300_000)
    out = tmp_path / "run"
    assert cli([*SHORT_TP, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"the record's files need about 0.357 MB in {out}/, where 0.3 MB are free" in err
    assert "--decimation N, now 1" in err
    assert not out.exists()


def test_a_full_disk_for_metrics_json_itself_is_a_clear_failure(tmp_path, monkeypatch, capsys):
    def no_room(path, data):
        raise DiskFull(path, 3000, 0)

    monkeypatch.setattr(quadcosim.scenarios.outputs, "write_json", no_room)
    out = tmp_path / "run"
    assert cli([*SHORT_TP, "--out", str(out)]) == 1
    assert f"no space left in {out}/ to write metrics.json: it needs about 0.003 MB" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["diagram.png", "results.npz", "roll_pitch.png", "yaw.png"]
    assert len(Result.load(out)) == 501  # the record written before the disk filled is whole
