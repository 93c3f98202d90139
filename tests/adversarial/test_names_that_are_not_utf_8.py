"""Item 10: a log whose file name is not UTF-8 (a name is bytes on Linux) is drawn and calibrated:
figure titles and messages show the bytes that do not decode as U+FFFD, never a traceback."""

import json
import os

from quadcosim.main import main as cli
from tests.flightlog_synthetic import write_log


def test_a_log_name_that_is_not_utf_8(tmp_path, capsys):
    log = tmp_path / os.fsdecode(b"vol-\xe9t\xe9.log")  # Latin-1 bytes: lone surrogates in Python
    write_log(log, duration=20.0)
    figure = tmp_path / "overview.png"
    assert cli(["log", "plot", str(log), "--out", str(figure)]) == 0
    assert figure.stat().st_size > 20_000
    out = tmp_path / "cal"
    assert cli(["calibrate", str(log), "--out", str(out), "--models", "current"]) == 0
    capsys.readouterr()
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "completed" and {"residual.png", "heading.png"} <= set(metrics["files"])
    assert cli(["log", "info", str(log), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["file"] == str(log)
