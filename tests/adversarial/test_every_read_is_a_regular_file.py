"""Hangs and memory: every file the project reads goes through one check
(:func:`quadcosim.infra.files.regular_file`) before it is opened. ``/dev/zero`` as a calibration
file once filled 16 GB of memory and ignored SIGTERM; a FIFO blocked its reader until killed.
Each is now refused at once, exit 2, naming what the path is."""

import os
import subprocess
import sys
import time

import pytest
from conftest import ROOT
from quadcosim.calibration import Calibration
from quadcosim.calibration.static import CalibrationError

from quadcosim.infra.inputs import regular_file

#: Seconds a refusal may take: the process starts, imports and reads the options; never a hang.
LIMIT_S = 120


def _quadcosim(argv, cwd):
    started = time.monotonic()
    try:
        done = subprocess.run([sys.executable, "-m", "quadcosim.main", *map(str, argv)], capture_output=True,
                              text=True, timeout=LIMIT_S, cwd=cwd, env=os.environ | {"MPLBACKEND": "Agg"})
    except subprocess.TimeoutExpired:
        pytest.fail(f"quadcosim {' '.join(map(str, argv))} hung (killed after {LIMIT_S} s)")
    return done.returncode, done.stderr, time.monotonic() - started


@pytest.fixture
def inputs(tmp_path):
    os.mkfifo(tmp_path / "fifo.json")
    os.mkfifo(tmp_path / "fifo.csv")
    os.mkfifo(tmp_path / "fifo.npz")
    (tmp_path / "zero.npz").symlink_to("/dev/zero")
    return tmp_path


@pytest.mark.parametrize(("argv", "said"), [
    (["run", "tp", "--set", "duration=0.5", "compensation=static", "calibration=/dev/zero"],
     "/dev/zero: a character device, not a regular file"),
    (["run", "tp", "--set", "duration=0.5", "compensation=static", "calibration={tmp}/fifo.json"],
     "fifo.json: a FIFO (named pipe), not a regular file"),
    (["run", "metge", "--set", "static={tmp}/fifo.json"], "fifo.json: a FIFO (named pipe), not a regular file"),
    (["replay", "{tmp}/fifo.csv"], "fifo.csv: a FIFO (named pipe), not a regular file"),
    (["replay", "{tmp}/fifo.npz"], "fifo.npz: a FIFO (named pipe), not a regular file"),
    (["replay", "{tmp}/zero.npz"], "zero.npz (a link to /dev/zero): a character device, not a regular file"),
    (["plot", "{tmp}/fifo.npz", "IMU.acc"], "fifo.npz: a FIFO (named pipe), not a regular file"),
], ids=["calibration_dev_zero", "calibration_fifo", "metge_static_fifo", "replay_fifo_csv", "replay_fifo_npz",
        "replay_link_to_dev_zero", "plot_fifo_npz"])
def test_a_device_or_fifo_read_as_input_is_refused_at_once(inputs, argv, said):
    argv = [a.format(tmp=inputs) for a in argv]
    if argv[0] == "run":
        argv += ["--out", inputs / "run"]
    code, err, seconds = _quadcosim(argv, inputs)
    assert code == 2, err[-2000:]
    assert said in err and "Traceback" not in err, err[-2000:]
    assert seconds < LIMIT_S
    assert not (inputs / "run" / "results.npz").exists()


def test_regular_file_names_every_kind_and_follows_links(tmp_path):
    os.mkfifo(tmp_path / "pipe")
    (tmp_path / "folder").mkdir()
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    (tmp_path / "fine").write_text("{}")
    (tmp_path / "link").symlink_to(tmp_path / "fine")
    for name, said in (("pipe", "a FIFO (named pipe), not a regular file; FIX"),
                       ("folder", "a folder, not a regular file; FIX"),
                       ("absent", "no such file; FIX"),
                       ("loop", "cannot read the thing (Too many levels of symbolic links); FIX")):
        with pytest.raises(ValueError, match=f"{name}.*{said}".replace("(", r"\(").replace(")", r"\)")):
            regular_file(tmp_path / name, "the thing", "FIX")
    assert regular_file(tmp_path / "link", "the thing", "FIX").st_size == 2


def test_a_calibration_file_beyond_its_size_is_refused_unread(tmp_path):
    path = tmp_path / "huge.json"
    with open(path, "wb") as file:  # sparse: 20 MB long, nothing stored
        file.truncate(20_000_000)
    with pytest.raises(CalibrationError, match="huge.json: 20 MB, not a calibration file"):
        Calibration.load(path)


def test_every_reader_of_the_project_checks_its_file_first():
    """The readers of files a user names: each calls the one check before it opens the file."""
    readers = {"calibration/file.py": "regular_file(", "estimators/recording.py": "regular_file(",
               "orchestrator/result.py": "regular_file(", "flight/profile_file.py": "regular_file(",
               "calibration/flight/autopilot.py": "regular_file(", "flightlogs/__init__.py": "regular_file(",
               "estimators/contract.py": "regular_file(", "scenarios/replay.py": "read_small_text(",
               "scenarios/run_plots.py": "read_small_text("}
    for module, call in readers.items():
        assert call in (ROOT / module).read_text(), module
