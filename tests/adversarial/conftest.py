"""Helpers of the adversarial tests: a small run, its files, and checks that nothing on disk is
truncated or half-written."""

import contextlib
import json
import os
import signal
import subprocess
from pathlib import Path

import numpy as np
import pytest
from quadcosim.orchestrator import Result

ROOT = Path(__file__).resolve().parents[2]

#: A run of tp short enough for a test: 0.5 s of flight, figures and diagram included.
SHORT_TP = ["run", "tp", "--set", "duration=0.5"]


def metrics_of(out: Path) -> dict:
    return json.loads((out / "metrics.json").read_text())


def assert_whole(out: Path) -> dict:
    """Every file in ``out`` is complete: no temporary left, ``metrics.json`` valid strict JSON
    listing files that exist, the record loadable with ``samples`` rows, every figure a whole
    PNG. Returns the metrics."""
    names = sorted(p.name for p in out.iterdir())
    assert not [n for n in names if n.startswith(".") or ".part" in n], names
    text = (out / "metrics.json").read_text()
    metrics = json.loads(text, parse_constant=lambda c: pytest.fail(f"metrics.json holds {c}"))
    for name in metrics["files"]:
        assert (out / name).exists(), (name, names)
    record = Result.load(out)
    assert len(record) == metrics["samples"]
    assert np.isfinite(np.asarray(record.time)).all()
    for name in names:
        if name.endswith(".png"):
            data = (out / name).read_bytes()
            assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[-8:-4] == b"IEND", name
    return metrics


@contextlib.contextmanager
def mounted(folder: Path, size: str):
    """A tmpfs of ``size`` (``"2m"``, ``"256k"``) mounted at ``folder`` (made) while the block runs;
    the test is skipped where mounting is not permitted (the injected full-disk tests cover the
    same paths)."""
    folder.mkdir()
    mounted = os.geteuid() == 0 and subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs",
                                                    str(folder)], capture_output=True).returncode == 0
    if not mounted:
        pytest.skip(f"mounting a {size} tmpfs is not permitted here")
    try:
        yield folder
    finally:
        subprocess.run(["umount", str(folder)], check=True)


def send_self(number: int = signal.SIGINT):
    """Deliver ``number`` to this process, as a user's Ctrl-C or a kill would."""
    os.kill(os.getpid(), number)
