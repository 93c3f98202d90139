"""Items 14, 16, 22 and 23: what the log readers print is captured and said in one warning, by every
command (a corrupt tail of zeros, a damaged ULog, a cut text log), standard output stays the
command's own (``--json`` parses), and a signal while pymavlink indexes ends the command as a
signal does (130, 143), not as a corrupt log."""

import json
import random
import signal
import time

import pytest
from conftest import send_self

from quadcosim.main import main as cli
from tests.flightlog_data import ERLE, path
from tests.flightlog_synthetic import write_log
from tests.flightlog_ulog_synthetic import write_ulog


def test_a_tail_of_zeros_is_one_warning_not_a_line_a_byte(tmp_path, capfd):
    log = tmp_path / "padded.bin"
    log.write_bytes(path(ERLE).read_bytes()[:300_000] + bytes(1_000_000))
    assert cli(["log", "info", str(log)]) == 0
    out, err = capfd.readouterr()
    assert len(err) < 2000 and len(out) < 5000, err[:2000]  # 999,457 lines of "bad header" on stderr before
    for shown in (out, err):  # the summary's list, and the warnings on standard error
        assert "the last 1 MB are zeros (a log padded, or cut when the vehicle lost power)" in shown
        assert "corrupt stretches skipped: pymavlink reported 999457 problems while reading (999457 bad header" \
            in shown


def test_a_damaged_ulog_keeps_standard_output_for_the_json(tmp_path, capfd):
    log = tmp_path / "damaged.ulg"
    write_ulog(log, duration=20.0)
    data = bytearray(log.read_bytes())
    shuffle = random.Random(3)
    for _ in range(30):
        data[shuffle.randrange(3000, len(data))] ^= 0xFF
    log.write_bytes(bytes(data))
    assert cli(["log", "info", str(log), "--json"]) == 0
    out, err = capfd.readouterr()
    info = json.loads(out)  # pyulog's "Warning: no subscription found" lines went to standard output before
    assert info["warnings"][0].startswith("corrupt stretches skipped: pyulog reported 3 problems while reading "
                                          "(3 message without its subscription)")
    assert "no subscription found" in err  # the warning, once, on standard error


def test_a_cut_text_log_is_reported_by_every_command(tmp_path, capsys):
    whole = tmp_path / "whole.log"
    write_log(whole, duration=20.0)
    cut = tmp_path / "cut.log"
    text = whole.read_bytes()
    cut.write_bytes(text[: text.rindex(b"\n") - 10])  # the last line loses its end
    warning = f"warning: {cut}: truncated: the last line is cut (61 bytes without their end of line)"
    assert cli(["log", "info", str(cut)]) == 0
    assert "quadcosim log info: " + warning in capsys.readouterr().err
    assert cli(["log", "replay", str(cut), "--json", str(tmp_path / "replay.json")]) == 0
    assert "quadcosim log replay: " + warning in capsys.readouterr().err  # replay read it silently before
    assert json.loads((tmp_path / "replay.json").read_text())["estimators"]


@pytest.mark.parametrize("number", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_while_pymavlink_indexes_ends_the_command_as_a_signal(tmp_path, monkeypatch, number, capsys):
    from pymavlink import dfindexer

    def interrupted(*args, **kwargs):  # the compiled indexer turns an interrupt into a MemoryError
        try:
            send_self(number)
            time.sleep(5)
        except KeyboardInterrupt:
            raise MemoryError() from None
        pytest.fail("the signal was not delivered")

    monkeypatch.setattr(dfindexer, "build_offsets", interrupted)
    log = tmp_path / "flight.bin"
    log.write_bytes(path(ERLE).read_bytes()[:300_000])
    assert cli(["log", "info", str(log)]) == 128 + number
    err = capsys.readouterr().err
    assert "interrupted" in err and "not a readable DataFlash log" not in err
