"""Item 21: what a log reader would block on or read for hours is refused before it opens it, in
seconds: a FIFO, a device, a folder, a sparse file far beyond any log's size, a file beyond the
largest log read."""

import os
import signal
import time

import pytest

from quadcosim import flightlogs
from quadcosim.main import main as cli


@pytest.fixture
def deadline():
    """Fail a test that blocks for more than 20 s instead of hanging the suite."""
    def expired(number, frame):
        raise TimeoutError("a log command blocked for 20 s")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.alarm(20)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def _sparse(path, head: bytes, size: int):
    with open(path, "wb") as file:
        file.write(head)
        file.truncate(size)
    return path


@pytest.mark.parametrize("command", [["log", "info"], ["log", "replay"], ["calibrate", "--out", "cal"]])
def test_files_no_reader_can_finish_are_refused_at_once(tmp_path, capsys, deadline, command, monkeypatch):
    monkeypatch.chdir(tmp_path)
    fifo = tmp_path / "live.bin"
    os.mkfifo(fifo)
    folder = tmp_path / "flight.ulg"
    folder.mkdir()
    cases = {fifo: "a FIFO (named pipe), not a regular file",
             _sparse(tmp_path / "sparse.ulg", b"ULog\x01\x12\x35" + bytes(100), 10_000_000_000):
                 "10.0 GB, more than the 1 GB quadcosim reads",
             _sparse(tmp_path / "holes.bin", b"\xa3\x95\x80" + bytes(100), 500_000_000):
                 "a sparse file (500 MB long, 0.0 MB stored)",
             folder: "a folder, not a regular file"}
    if os.path.exists("/dev/zero"):
        cases["/dev/zero"] = "a character device, not a regular file"
    for path, said in cases.items():
        started = time.monotonic()
        argv = [*command[:2], str(path), *command[2:]] if command[0] == "log" else [command[0], str(path),
                                                                                    *command[1:]]
        assert cli(argv) == 2, argv
        assert said in capsys.readouterr().err
        assert time.monotonic() - started < 5.0
    assert not (tmp_path / "cal").exists()


def test_the_size_limit_is_one_gigabyte():
    assert flightlogs.MAX_LOG_BYTES == 1_000_000_000
