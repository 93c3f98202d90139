"""``calibrate --score F`` once misread some parameter files without a word: a UTF-8 byte-order
mark dropped the first parameter, a duplicated key took the last value, a file with no parameter
for the scored compass scored as the log, and ``COMPASS_MOT_X,3e38`` printed a share of -8e78 %.
Each is now read right or refused naming the line and the fix."""

import json

import pytest
from quadcosim.calibration.flight.autopilot import read_parameters

from quadcosim.main import main
from tests.flightlog_synthetic import write_log


def test_a_byte_order_mark_keeps_the_first_parameter(tmp_path):
    path = tmp_path / "excel.parm"
    path.write_bytes("\ufeffCOMPASS_OFS_X,12.5\nCOMPASS_MOTCT,2\n".encode())
    assert read_parameters(path) == {"COMPASS_OFS_X": 12.5, "COMPASS_MOTCT": 2}


def test_a_duplicated_key_is_refused_naming_its_line(tmp_path):
    path = tmp_path / "twice.parm"
    path.write_text("COMPASS_OFS_X,12.5\nCOMPASS_MOTCT,2\nCOMPASS_OFS_X,-40\n")
    with pytest.raises(ValueError, match="twice.parm, line 3: COMPASS_OFS_X is given a second time"):
        read_parameters(path)


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    folder = tmp_path_factory.mktemp("score")
    write_log(folder / "flight.log", gps=True)
    return folder


@pytest.mark.parametrize(("content", "said"), [
    ("COMPASS_OFS2_X,100\nCOMPASS_DIA3_X,1.1\n",
     "none of its 2 parameters (COMPASS_OFS2_X, COMPASS_DIA3_X) acts on the compass scored (compass 0)"),
    ("COMPASS_MOTCT,2\nCOMPASS_MOT_X,3e38\n", "its largest value: COMPASS_MOT_X = 3e+38"),
], ids=["another_compass", "absurd_value"])
def test_a_file_that_would_score_as_something_else_is_refused(flight, tmp_path, capsys, content, said):
    (tmp_path / "given.parm").write_text(content)
    assert main(["calibrate", str(flight / "flight.log"), "--score", str(tmp_path / "given.parm"), "--out",
                 str(tmp_path / "scored")]) == 2
    err = capsys.readouterr().err
    assert said in err and "Traceback" not in err, err[-1500:]


def test_a_file_acting_on_the_compass_is_scored(flight, tmp_path):
    (tmp_path / "given.parm").write_text("\ufeffCOMPASS_MOTCT,2\nCOMPASS_MOT_X,-3\n")
    assert main(["calibrate", str(flight / "flight.log"), "--score", str(tmp_path / "given.parm"), "--out",
                 str(tmp_path / "scored")]) == 0
    score = json.loads((tmp_path / "scored" / "metrics.json").read_text())["score"]
    assert score["parameters"] == 2 and -1 < score["explained"] < 1
