"""Acceptance 2 and item 3: a signal at any phase of a 120 s ``tp`` run (loading, building,
drawing, the loop, saving, reporting, each figure), alone or followed by a second one 50 to
300 ms later, leaves a valid ``metrics.json`` and a loadable record, with exit 130 or 143.

Each point is a phase's status line on standard error and a delay after it; the runs go two
at a time in child processes. Five points run by default, all twenty with the slow tests. (A
progress line on a pipe shows after the loop's first chunk, then at each quarter.)"""

import os
import re
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import pytest
from conftest import ROOT, assert_whole

# (status line that starts the phase, delay after it (s), signal, second SIGINT after (s) or None)
POINTS = [
    ("tp: loading the scenario", 0.0, signal.SIGINT, None),
    ("tp: building the system", 0.0, signal.SIGTERM, None),
    ("tp: building the system", 0.1, signal.SIGINT, 0.05),
    ("tp: wiring diagram", 0.0, signal.SIGINT, None),
    ("tp: wiring diagram", 0.15, signal.SIGTERM, 0.3),
    ("tp: starting", 0.0, signal.SIGINT, None),
    ("run: ", 0.0, signal.SIGINT, 0.05),
    ("run:  25 %", 0.0, signal.SIGTERM, None),
    ("run:  50 %", 0.0, signal.SIGINT, 0.15),
    ("run:  75 %", 0.0, signal.SIGINT, 0.3),
    ("run: 100 %", 0.0, signal.SIGTERM, None),
    ("tp: writing results.npz", 0.0, signal.SIGINT, None),
    ("tp: writing results.npz", 0.02, signal.SIGINT, 0.05),
    ("tp: writing results.npz", 0.05, signal.SIGTERM, 0.1),
    ("tp: report", 0.0, signal.SIGINT, None),
    ("tp: report", 0.1, signal.SIGTERM, 0.05),
    ("figure roll_pitch.png", 0.0, signal.SIGINT, None),
    ("figure roll_pitch.png", 0.1, signal.SIGINT, 0.2),
    ("figure yaw.png", 0.0, signal.SIGTERM, None),
    ("figure yaw.png", 0.05, signal.SIGINT, 0.3),
]

#: The points of the default run: one in each kind of phase.
DEFAULT = (2, 6, 13, 15, 19)


def shown(marker: str, err: str) -> bool:
    """Whether ``marker`` is on the standard error ``err``. The run's progress prints a line per
    quarter reached, but one chunk of the loop may cross several quarters and print only the
    last: ``run:  25 %`` is shown once any line reports 25 % or more."""
    wanted = re.fullmatch(r"run: +(\d+) %", marker)
    if wanted is None:
        return marker in err
    return any(int(reached) >= int(wanted.group(1)) for reached in re.findall(r"^run: +(\d+) %", err, re.M))


def interrupt_at(out, marker: str, delay: float, sent: int, second: float | None) -> tuple[int, str]:
    """Run ``tp`` (120 s) into ``out``, send ``sent`` ``delay`` s after ``marker`` shows on its
    standard error (and a SIGINT ``second`` s later); its exit code and standard error."""
    errors = out.with_suffix(".err")
    command = [sys.executable, "-m", "quadcosim.main", "run", "tp", "--set", "duration=120", "--out", str(out)]
    # an empty diagram cache: the wiring is drawn, so that a signal can reach the drawing phase
    env = os.environ | {"QUADCOSIM_DIAGRAM_CACHE": str(out.with_suffix(".diagrams"))}
    with errors.open("w") as stderr:
        process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=stderr, cwd=ROOT, env=env)
        try:
            deadline = time.monotonic() + 300
            while not shown(marker, errors.read_text()) and process.poll() is None and time.monotonic() < deadline:
                time.sleep(0.005)
            time.sleep(delay)
            process.send_signal(sent)
            if second is not None:
                time.sleep(second)
                process.send_signal(signal.SIGINT)
            code = process.wait(timeout=300)
        finally:
            if process.poll() is None:
                process.kill()
    return code, errors.read_text()


def _check(tmp_path, indices):
    outs = [tmp_path / f"point{k:02d}" for k in indices]
    with ThreadPoolExecutor(2) as pool:
        runs = list(pool.map(lambda k, out: interrupt_at(out, *POINTS[k]), indices, outs))
    phases = set()
    for k, out, (code, err) in zip(indices, outs, runs, strict=True):
        marker, delay, sent, second = POINTS[k]
        assert shown(marker, err), (k, err[-1500:])
        if code == 0:  # the signal came after the last save: the run had ended whole
            assert marker == "figure yaw.png", (k, err[-1500:])
            continue
        assert code == 128 + sent, (k, code, err[-2000:])
        metrics = assert_whole(out)
        assert metrics["status"] == "interrupted" and metrics["interrupted_by"] == signal.Signals(sent).name, k
        assert "Traceback" not in err, (k, err[-2000:])
        phases.add(metrics["stopped_during"])
    return phases


def test_a_signal_in_each_kind_of_phase_leaves_metrics_and_a_loadable_record(tmp_path):
    phases = _check(tmp_path, DEFAULT)
    assert len(phases) >= 4, phases  # loading or building, the loop, saving, reporting


@pytest.mark.slow
def test_a_signal_at_twenty_points_of_a_120_s_run_leaves_metrics_and_a_loadable_record(tmp_path):
    phases = _check(tmp_path, [k for k in range(len(POINTS)) if k not in DEFAULT])
    assert len(phases) >= 4, phases
