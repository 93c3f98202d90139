"""``calibrate --score PARAMS`` reads another tool's parameter file: a file that is no parameter
file, a line that holds no value and a value no autopilot stores are refused naming the file,
the line and the fix, never met by a library's message ("Residuals are not finite") or an
overflow warning; ``--firmware`` is refused before the flights are read."""

import os

import pytest
from quadcosim.calibration.flight.autopilot import read_parameters

from quadcosim.main import main as cli


@pytest.mark.parametrize(("content", "named"), [
    (b"COMPASS_OFS_X,nan\n", "line 1: COMPASS_OFS_X = nan is not a value an autopilot stores"),
    (b"# offsets\nCOMPASS_OFS_X,1e300\n", "line 2: COMPASS_OFS_X = 1e300 is not a value an autopilot stores"),
    (b"1\t1\tCAL_MAG0_XOFF\tinf\t9\n", "line 1: CAL_MAG0_XOFF = inf is not a value an autopilot stores"),
    (b"COMPASS_OFS_X\n", "line 1: 'COMPASS_OFS_X' is not NAME,VALUE (ArduPilot)"),
    (b"COMPASS_OFS_X,abc\n", "line 1: 'COMPASS_OFS_X,abc' is not NAME,VALUE"),
    ("COMPASS_OFS_X,1\n# \u00e9\n".encode("latin-1"), "not a text parameter file (byte 18 is not UTF-8)"),
    (b"", "no parameters in the file"),
])
def test_a_broken_parameter_file_is_refused_naming_the_line(tmp_path, content, named):
    path = tmp_path / "given.parm"
    path.write_bytes(content)
    with pytest.raises(ValueError, match=f"{path}.*{named}".replace("(", r"\(").replace(")", r"\)")):
        read_parameters(path)


def test_a_fifo_or_a_folder_is_refused_without_blocking(tmp_path):
    os.mkfifo(tmp_path / "pipe.parm")  # opened for reading, it would block until a writer came
    with pytest.raises(ValueError, match=r"pipe.parm: a FIFO \(named pipe\), not a regular file"):
        read_parameters(tmp_path / "pipe.parm")
    with pytest.raises(ValueError, match="not a regular file"):
        read_parameters(tmp_path)
    assert read_parameters(_written(tmp_path)) == {"COMPASS_OFS_X": 12.5, "COMPASS_MOTCT": 2}


def _written(folder):
    path = folder / "fine.parm"
    path.write_text("COMPASS_OFS_X,12.5\nCOMPASS_MOTCT,2\n")
    return path


def test_an_unknown_firmware_is_refused_before_the_flights_are_read(tmp_path, capsys):
    absent = tmp_path / "never_read.log"  # refused first: the log is not opened
    assert cli(["calibrate", str(absent), "--firmware", "9.x", "--out", str(tmp_path / "cal")]) == 2
    assert "--firmware '9.x' is not a Copter version such as 3.4 or 4.5" in capsys.readouterr().err
    assert not (tmp_path / "cal").exists()
