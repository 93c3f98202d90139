"""Items 1 and 3: a disk that fills at any phase leaves ``metrics.json`` (or nothing), never a 0-byte
or partial file under a final name: while the wiring diagram is drawn, while a calibration's
parameter files and figures are written (a real 256 kB filesystem where mounting one is
permitted), and when not even ``metrics.json`` would fit."""

import errno
import json
import os

import matplotlib.figure
import pytest
from conftest import SHORT_TP, metrics_of, mounted

from quadcosim import scenarios
from quadcosim.main import main as cli
from tests.flightlog_synthetic import write_log

CALIBRATION = ["--models", "current"]


def test_a_full_disk_while_the_diagram_is_drawn_leaves_metrics_json(tmp_path, monkeypatch, capsys):
    savefig = matplotlib.figure.Figure.savefig

    def filling(figure, path, *args, **kwargs):
        if ".diagram." in str(path):  # the diagram's temporary file: half written, then no room
            with open(path, "wb") as handle:
                handle.write(b"\x89PNG" + bytes(3000))
            raise OSError(errno.ENOSPC, "No space left on device")
        return savefig(figure, path, *args, **kwargs)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", filling)
    monkeypatch.setattr(scenarios, "diagram_cache", lambda: tmp_path / "diagrams")  # empty: the wiring is drawn
    out = tmp_path / "run"
    assert cli([*SHORT_TP, "--out", str(out)]) == 1
    assert f"no space left in {out}/ to write diagram.png" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "results.npz"]  # no reserve, no temporary
    metrics = metrics_of(out)
    assert metrics["status"] == "failed" and metrics["stopped_during"] == "drawing the wiring diagram"
    assert metrics["samples"] == 0 and metrics["files"] == ["results.npz"]


@pytest.fixture
def small_disk(tmp_path):
    """A 256 kB tmpfs at ``tmp_path / "disk"`` (skipped where mounting is not permitted)."""
    with mounted(tmp_path / "disk", "256k") as disk:
        yield disk


def _fill(disk, leave: int):
    """Fill ``disk`` but ``leave`` bytes."""
    free = os.statvfs(disk).f_bavail * os.statvfs(disk).f_frsize
    (disk / "filler").write_bytes(bytes(max(0, free - leave)))


def _partial(disk) -> list[str]:
    """Temporary files, and empty files under a final name, left on ``disk``."""
    left = []
    for folder, _, names in os.walk(disk):
        for name in names:
            path = os.path.join(folder, name)
            if name != "filler" and (name.startswith(".") or ".part" in name or os.path.getsize(path) == 0):
                left.append(os.path.relpath(path, disk))
    return left


def test_a_calibration_on_a_filling_disk_keeps_its_metrics_json(small_disk, tmp_path, capsys):
    log = tmp_path / "flight.log"
    write_log(log, duration=20.0)
    _fill(small_disk, 100_000)  # the parameter files and calibration.json fit, not the figures
    out = small_disk / "cal"
    assert cli(["calibrate", str(log), "--out", str(out), *CALIBRATION]) == 1
    err = capsys.readouterr().err
    assert "residual.png not written: no space left in" in err and "Traceback" not in err
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "failed"
    assert metrics["files"] == ["metrics.json", "calibration.json", "ardupilot.parm"]  # the log's autopilot's
    assert set(metrics["files_not_written"]) == {"residual.png", "heading.png"}
    assert sorted(os.listdir(out)) == sorted(metrics["files"]) and _partial(small_disk) == []


def test_a_calibration_with_no_room_for_metrics_json_leaves_nothing(small_disk, tmp_path, capsys):
    log = tmp_path / "flight.log"
    write_log(log, duration=20.0)
    _fill(small_disk, 8_000)
    out = small_disk / "cal"
    assert cli(["calibrate", str(log), "--out", str(out), *CALIBRATION]) == 1
    assert f"no space left in {out}/ to write metrics.json" in capsys.readouterr().err
    assert not out.exists() and _partial(small_disk) == []
