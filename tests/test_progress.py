"""What a run shows while it works: a bar on a terminal, a few plain lines to a pipe, status
lines around the run."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

from quadcosim.infra.progress import PIPE_LINES, Progress, reporting, status

ROOT = Path(__file__).resolve().parent.parent


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_on_a_terminal_the_bar_ends_at_100_percent_on_its_own_line():
    screen = Terminal()
    bar = Progress(20.0, "run", stream=screen)
    for _ in range(199):  # the run loop's chunks stop short of the end
        bar.update(0.1)
    bar.complete()
    bar.close()
    text = screen.getvalue()
    last = text.split("\r")[-1]
    assert "100%" in last and "20.0/20.0 s" in last and text.endswith("\n")
    assert "99%" not in last


def test_to_a_pipe_a_few_plain_lines_and_after_a_failure_no_100_percent():
    pipe = io.StringIO()
    bar = Progress(120.0, "run", stream=pipe)
    for _ in range(1000):
        bar.update(0.12)
    bar.complete()
    bar.close()
    lines = pipe.getvalue().splitlines()
    assert len(lines) == 1 + PIPE_LINES and "\r" not in pipe.getvalue()
    assert lines[0].startswith("run:   0 % (0.1/120 s simulated")  # the loop runs
    assert lines[-1].startswith("run: 100 % (120.0/120 s simulated")
    stopped = io.StringIO()
    bar = Progress(120.0, "run", stream=stopped)
    bar.update(70.0)
    bar.close()
    assert stopped.getvalue().splitlines()[0].startswith("run:  58 % (70.0/120 s simulated")


def _percent_and_seconds(line: str) -> tuple[int, float, float]:
    percent = int(line.split("%")[0].split(":")[1])
    done, total = line.split("(")[1].split(" s simulated")[0].split("/")
    return percent, float(done), float(total)


def test_each_line_s_percentage_is_the_simulated_time_it_shows():
    """A chunk that crosses a quarter, or several, prints the time reached, not the quarter:
    never "25 % (8.2/17 s)"."""
    pipe = io.StringIO()
    bar = Progress(17.0, "run", stream=pipe)
    for _ in range(4):
        bar.update(4.096)  # the chunk runner's 4096 steps of 1 ms
    bar.complete()
    lines = pipe.getvalue().splitlines()
    shown = [_percent_and_seconds(line) for line in lines]
    assert [p for p, _, _ in shown] == [24, 48, 72, 96, 100]
    assert all(p == int(100 * done / total) for p, done, total in shown)


def test_status_lines_only_while_reporting():
    quiet, told = io.StringIO(), io.StringIO()
    with reporting(False, stream=quiet):
        status("nothing")
    with reporting(True, stream=told):
        status("tp: building the system")
    status("after")
    assert quiet.getvalue() == "" and told.getvalue().endswith("] tp: building the system\n")


def test_a_120_s_run_writes_at_most_15_lines_to_a_pipe(tmp_path):
    """Acceptance 5, on the open loop (the cheapest 120 s run): every line of standard error, status
    lines included, and no carriage return. Left free for 120 s the vehicle falls (10 m/s at 3.3 s): the run
    ends diverged, exit 1, its warning one of the lines."""
    process = subprocess.run([sys.executable, "-m", "quadcosim.main", "run", "open-loop", "--set", "duration=120",
                              "--out", str(tmp_path / "run")], capture_output=True, text=True, cwd=ROOT,
                             env=os.environ | {"COLUMNS": "80"}, timeout=600)
    assert process.returncode == 1 and "open-loop diverged at t = " in process.stderr, process.stderr
    lines = process.stderr.splitlines()
    assert len(lines) <= 15, process.stderr
    assert "\r" not in process.stderr
    progress = [line for line in lines if line.startswith("run: ")]
    first = int(progress[0].split("%")[0].split(":")[1])  # the first chunk ran: the loop runs
    assert 0 <= first < 25 and "/120 s simulated" in progress[0]
    shown = [_percent_and_seconds(line) for line in progress]
    assert all(p == int(100 * done / total) for p, done, total in shown)  # the percentage is the time shown
    assert len(progress) == 1 + PIPE_LINES and shown[-1][0] == 100
    assert any("open-loop: building the system" in line for line in lines)
    assert any("open-loop: report" in line for line in lines)
    print(f"{len(lines)} lines on standard error:\n{process.stderr}")
