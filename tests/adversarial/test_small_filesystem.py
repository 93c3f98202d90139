"""Acceptance 3: on a 2 MB filesystem (a tmpfs, where mounting one is permitted) every command
that writes leaves no truncated file under a final name: each is refused before it starts,
or fails with the folder and the bytes named, or completes; what is on the disk is whole."""

import json
import os

import pytest
from conftest import mounted
from quadcosim.orchestrator import Result
from scipy.io import loadmat

from quadcosim.main import main as cli


@pytest.fixture
def small_disk(tmp_path):
    """A 2 MB tmpfs mounted at ``tmp_path / "disk"`` (skipped where mounting is not permitted)."""
    with mounted(tmp_path / "disk", "2m") as disk:
        yield disk


def _whole(path):
    """Raise unless ``path`` is a complete file of its kind."""
    data = path.read_bytes()
    if path.suffix == ".png":
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[-8:-4] == b"IEND", path
    elif path.suffix == ".json":
        json.loads(data)
    elif path.suffix == ".npz":
        Result.from_npz(path)
    elif path.suffix == ".mat":
        loadmat(path)
    elif path.suffix == ".csv":
        assert data.endswith(b"\n"), path


def _check_disk(disk) -> list[str]:
    """Every file on the disk is whole and no temporary is left; the files, relative."""
    found = []
    for folder, _, names in os.walk(disk):
        for name in names:
            path = os.path.join(folder, name)
            assert not name.startswith(".") and ".part" not in name, path
            _whole(type(disk)(path))
            found.append(os.path.relpath(path, disk))
    for run in {p.parent for p in disk.rglob("metrics.json")}:
        if (run / "results.stream").is_dir() or (run / "results.npz").exists():
            metrics = json.loads((run / "metrics.json").read_text())
            assert len(Result.load(run)) == metrics["samples"], run
    return sorted(found)


COMMANDS = [  # (arguments, exit codes allowed): the disk fills as they go
    (["run", "tp", "--out", "{disk}/tp20"], {2}),  # 14 MB: refused before it starts
    (["run", "tp", "--set", "duration=1", "--out", "{disk}/tp1"], {0}),
    (["run", "tp", "--set", "duration=1", "--format", "npz,mat,csv", "--out", "{disk}/tp1-all"], {2}),
    (["run", "open-loop", "--set", "duration=0.5", "--out", "{disk}/open-loop"], {0, 1}),
    (["run", "tp", "--set", "duration=1", "--out", "{disk}/tp1-b"], {0, 1, 2}),
    (["run", "tp", "--set", "duration=0.3", "--stream", "--out", "{disk}/stream"], {0, 1, 2}),
    (["run", "tp", "--set", "duration=0.3", "--out", "{disk}/tp03"], {0, 1, 2}),
    (["run", "tp", "--set", "duration=0.3", "--out", "{disk}/tp03-b"], {0, 1, 2}),
    (["diagram", "tp", "--out", "{disk}/wiring.png"], {0, 1}),
    (["run", "tp", "--set", "duration=0.2", "--out", "{disk}/tp1", "--overwrite"], {0, 1, 2}),
]


def test_every_command_on_a_2_MB_filesystem_leaves_no_truncated_file(small_disk, capsys):
    codes = []
    for arguments, allowed in COMMANDS:
        arguments = [a.format(disk=small_disk) for a in arguments]
        try:
            code = cli(arguments)
        except OSError as error:  # a command outside `run` may fail on the full disk: never half a file
            assert error.errno == 28 and "no space left" in str(error), error
            code = 1
        err = capsys.readouterr().err
        assert code in allowed, (arguments, code, err[-2000:])
        assert "Traceback" not in err, err[-2000:]
        if code == 1 and arguments[0] == "run":
            assert "no space left in " in err and " MB" in err, err[-2000:]
            out = type(small_disk)(arguments[arguments.index("--out") + 1])
            assert json.loads((out / "metrics.json").read_text())["status"] == "failed"  # at least metrics.json
        codes.append(code)
        _check_disk(small_disk)
    assert 1 in codes and 2 in codes and 0 in codes, codes  # the disk filled, and runs fit before it did
    print(f"exit codes on the 2 MB disk: {codes}; files left: {_check_disk(small_disk)}")
