"""``quadcosim bench`` on ordinary bad input: ``--seconds`` 0, -1, nan, 1e-9 or 1e308 once
traced back (a division by zero steps, an overflow); ``--out`` on a full disk traced back after
the timing. Refused with exit 2 before any timing; the full disk keeps the printed figures and
exits 1 naming the disk."""

import pytest
from conftest import mounted

from quadcosim.main import main as cli


@pytest.mark.parametrize("seconds", ["0", "-1", "nan", "1e-9", "1e308"])
def test_seconds_no_timing_can_take_are_refused_at_once(seconds, capsys):
    assert cli(["bench", f"--seconds={seconds}"]) == 2
    err = capsys.readouterr().err
    assert "give the simulated time of each timed run, from 0.01 s (10 macro steps) to 3600 s" in err


def test_a_full_disk_keeps_the_measurement_and_names_the_disk(tmp_path, capsys):
    with mounted(tmp_path / "full", "64k") as full:
        (full / "filler").write_bytes(bytes(60 * 1024))
        assert cli(["bench", "--seconds", "0.01", "--out", str(full / "bench.png")]) == 1
        out, err = capsys.readouterr()
        assert "closed_loop_us_per_step" in out  # the figures measured are printed
        assert "the figure was not written: no space left in" in err and "bench.png" in err
        assert not (full / "bench.png").exists()
