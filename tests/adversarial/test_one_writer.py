"""Items 1, 2 and 12: every file is written by one writer, whole or not at all; a symbolic link is
followed (its target replaced, the link kept); a FIFO, a device, a folder or a missing folder is
refused before anything is written, by the writer and by the commands that write."""

import errno
import json
import os
import stat

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402
from quadcosim.calibration.flight import autopilot  # noqa: E402
from quadcosim.flightlogs.autopilots import registry  # noqa: E402

import quadcosim.infra.files  # noqa: E402
from quadcosim.infra.files import DiskFull, save_figure, write_json, write_text  # noqa: E402

PARAMETERS = {"COMPASS_OFS_X": 12.5, "COMPASS_MOTCT": 2}


@pytest.mark.parametrize("writer", [member.write for member in registry().values()])
def test_parameter_files_are_never_left_empty_by_a_full_disk(tmp_path, monkeypatch, writer):
    path = tmp_path / "compass.params"
    path.write_text("earlier\n")
    real_replace = os.replace

    def full(source, target):  # the data written, then no room for the rename's metadata
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(quadcosim.infra.files.os, "replace", full)
    with pytest.raises(DiskFull, match=f"no space left in {tmp_path}/ to write compass.params"):
        writer(PARAMETERS, path)
    monkeypatch.setattr(quadcosim.infra.files.os, "replace", real_replace)
    assert path.read_text() == "earlier\n"  # the earlier file, whole
    assert sorted(p.name for p in tmp_path.iterdir()) == ["compass.params"]  # no temporary left
    writer(PARAMETERS, path)
    assert autopilot.read_parameters(path) == PARAMETERS


def test_a_symbolic_link_is_followed_and_kept(tmp_path):
    target = tmp_path / "kept" / "result.json"
    target.parent.mkdir()
    target.write_text("{}")
    link = tmp_path / "latest.json"
    link.symlink_to(target)
    write_json(link, {"value": 1})
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert json.loads(target.read_text()) == {"value": 1}
    dangling = tmp_path / "new.json"
    dangling.symlink_to(tmp_path / "kept" / "made.json")
    write_text(dangling, "made\n")  # a link to a file not yet there: the file is made
    assert (tmp_path / "kept" / "made.json").read_text() == "made\n" and dangling.is_symlink()


def test_a_fifo_is_refused_and_its_reader_is_not_fed_a_replacement(tmp_path):
    from quadcosim.infra.files import OutputRefused

    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    with pytest.raises(OutputRefused, match="a FIFO"):
        write_json(fifo, {"value": 1})
    assert fifo.is_fifo()  # still the FIFO, not a regular file renamed over it
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe.json"]


def test_a_device_a_folder_and_a_missing_folder_are_refused(tmp_path):
    from quadcosim.infra.files import OutputRefused

    if os.geteuid() == 0:  # a device node of its own (the null device's numbers), never /dev/null itself
        device = tmp_path / "null"
        os.mknod(device, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
        with pytest.raises(OutputRefused, match="a character device"):
            write_text(device, "x")
        assert device.is_char_device()
        device.unlink()
    with pytest.raises(OutputRefused, match="a folder, not a file"):
        write_text(tmp_path, "x")
    with pytest.raises(OutputRefused, match="the folder .*absent/ does not exist; create it"):
        write_text(tmp_path / "absent" / "file.txt", "x")
    figure = plt.figure()
    try:
        with pytest.raises(OutputRefused, match=r"\.xyz is not a figure format matplotlib writes; end it with .png"):
            save_figure(figure, tmp_path / "figure.xyz")
    finally:
        plt.close(figure)
    assert list(tmp_path.iterdir()) == []
