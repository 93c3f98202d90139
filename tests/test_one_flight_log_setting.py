"""One setting for the real-log folder: ``$QUADCOSIM_FLIGHT_LOGS`` names it for the real-log
tests as for the findings (the tests once looked only in ``../shared/data/flightlogs``)."""

import os
import subprocess
import sys

from findings.flightlogs import FOLDER_VARIABLE
from tests import flightlog_data

ROOT = flightlog_data.ROOT


def test_the_tests_read_the_folder_the_findings_read(tmp_path):
    assert FOLDER_VARIABLE == "QUADCOSIM_FLIGHT_LOGS"
    (tmp_path / flightlog_data.ERLE).write_bytes(b"")  # a file of that name: the folder is read, the log is not
    done = subprocess.run([sys.executable, "-c", "from tests import flightlog_data as d; print(d.FOLDER); "
                           f"print(d.path({flightlog_data.ERLE!r}))"], cwd=ROOT, capture_output=True, text=True,
                          env=os.environ | {FOLDER_VARIABLE: str(tmp_path)}, timeout=120)
    assert done.stdout.split() == [str(tmp_path), str(tmp_path / flightlog_data.ERLE)], done.stderr[-1500:]


def test_without_the_setting_the_folder_beside_the_repository_is_read():
    env = {k: v for k, v in os.environ.items() if k != FOLDER_VARIABLE}
    done = subprocess.run([sys.executable, "-c", "from tests import flightlog_data as d; print(d.FOLDER)"], cwd=ROOT,
                          capture_output=True, text=True, env=env, timeout=120)
    assert done.stdout.strip() == str(ROOT.parent / "shared" / "data" / "flightlogs")
