"""Cost of a short test written with the pytest plugin (``quadcosim bench pytest``).

Writes a test file of ``tests`` tests, each running the lab's closed loop (``tp``, default
options) for ``duration`` simulated seconds through the ``run_scenario`` fixture and checking its
attitude error, runs it with pytest in a fresh process (one session, as a user's ``pytest``
runs), and prints:

- the wall time of each test (set-up, call and tear-down, as pytest measures them): the first,
  which pays for loading the FMUs and the compiled code, and the median of the others;
- beside it, the stepping alone (the master's loop over the run's macro steps,
  ``result.meta["loop_seconds"]``), and what the rest of a test costs (building the system,
  resetting the pooled FMU instances, the metrics);
- the whole session's wall time, pytest's start-up included.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TESTS = 20
DURATION = 2.0  # s of simulated time per test
TARGET_S = 0.1  # wall time per test after the first

TEST_FILE = '''
import json, os
import pytest

LOOPS = {{}}


@pytest.mark.parametrize("index", range({tests}))
def test_tp_short(run_scenario, index):
    result = run_scenario("tp", duration={duration})
    LOOPS[index] = result.meta["loop_seconds"]
    assert_attitude_error(result, below_deg=1.0, after_s=1.0)


def teardown_module():
    with open(os.environ["QUADCOSIM_BENCH_OUT"], "w") as file:
        json.dump(LOOPS, file)
'''

CONFTEST = '''
import json, os

DURATIONS = {}


def pytest_runtest_logreport(report):
    DURATIONS.setdefault(report.nodeid, 0.0)
    DURATIONS[report.nodeid] += report.duration


def pytest_sessionfinish(session):
    with open(os.environ["QUADCOSIM_BENCH_OUT"] + ".tests", "w") as file:
        json.dump(DURATIONS, file)
'''


def measure(tests: int = TESTS, duration: float = DURATION) -> dict:
    """Run the test file in a fresh pytest process and gather its timings.

    Parameters
    ----------
    tests : int
        Tests in the session, each a ``tp`` run.
    duration : float
        Simulated time of each run (s).

    Returns
    -------
    dict
        ``first_test_s`` and ``per_test_s`` (the median of the others), wall time (s);
        ``stepping_s`` (the median stepping loop of those), ``overhead_s`` (their difference),
        ``session_s`` (the pytest process, start to end), ``passed``, and the inputs.
    """
    import os

    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        test_file = folder / "test_short_horizons.py"
        test_file.write_text("from quadcosim.scenarios.testing.assertions import assert_attitude_error\n"
                             + TEST_FILE.format(tests=tests, duration=duration))
        (folder / "conftest.py").write_text(CONFTEST)
        out = folder / "loops.json"
        environment = os.environ | {"QUADCOSIM_BENCH_OUT": str(out)}
        started = time.perf_counter()
        done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
                               str(test_file)], cwd=folder, env=environment, capture_output=True, text=True)
        session = time.perf_counter() - started
        if done.returncode != 0:
            raise RuntimeError(f"the benchmark's tests failed:\n{done.stdout[-3000:]}\n{done.stderr[-2000:]}")
        loops = json.loads(out.read_text())
        walls = list(json.loads(Path(str(out) + ".tests").read_text()).values())
    steady_walls, steady_loops = walls[1:], [loops[str(i)] for i in range(1, tests)]
    per_test, stepping = statistics.median(steady_walls), statistics.median(steady_loops)
    return {"tests": tests, "simulated_s_per_test": duration, "first_test_s": walls[0], "per_test_s": per_test,
            "per_test_max_s": max(steady_walls), "stepping_s": stepping, "overhead_s": per_test - stepping,
            "first_stepping_s": loops["0"], "session_s": session, "target_s": TARGET_S,
            "passed": per_test <= TARGET_S}


def report(figures: dict) -> str:
    """The figures as text."""
    return "\n".join([
        f"{figures['tests']} tests, each tp for {figures['simulated_s_per_test']:g} s of simulated time, "
        "in one pytest session (fixture run_scenario, FMU instances pooled)",
        f"first test:           {figures['first_test_s']:.3f} s wall (stepping {figures['first_stepping_s']:.3f} s)",
        f"each test after it:   {figures['per_test_s']:.3f} s wall, median "
        f"(largest {figures['per_test_max_s']:.3f} s); "
        f"target <= {figures['target_s']:g} s: {'met' if figures['passed'] else 'NOT met'}",
        f"  stepping alone:     {figures['stepping_s']:.3f} s",
        f"  the rest:           {figures['overhead_s']:.3f} s (building, FMU reset, metrics, pytest)",
        f"whole session:        {figures['session_s']:.2f} s wall, pytest's start-up included",
    ])


def main(argv=None) -> int:
    """``quadcosim bench pytest [--json]``: measure and print; returns 0.
    ``argv``: the arguments (default ``sys.argv[1:]``)."""
    import argparse

    parser = argparse.ArgumentParser(prog="quadcosim bench pytest", description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--tests", type=int, default=TESTS, help="tests in the session")
    parser.add_argument("--duration", type=float, default=DURATION, help="simulated seconds per test")
    args = parser.parse_args(argv)
    figures = measure(args.tests, args.duration)
    print(json.dumps(figures) if args.json else report(figures))
    return 0


if __name__ == "__main__":  # the same as quadcosim bench pytest
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench pytest").run, main)
